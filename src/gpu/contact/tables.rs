//! The contact set's static tables on the device: `#[repr(C)]` mirrors of WGSL `Slot` and
//! `Segment` (`shaders/contact_common.wgsl`) and the per-node and per-interface words the contact
//! kernels read beside them, built from [`crate::contact::Tables`], their CPU form
//! (`src/contact/tables.rs`), once per scene.

use bytemuck::{Pod, Zeroable};

use crate::contact::{SegmentTable, SlotTable, Tables};
use crate::error::{Error, Result};

/// Mirror of WGSL `Slot`: one pass's slave node or one wall's node.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, Pod, Zeroable)]
pub struct GpuSlot {
    /// Interface index (bits 0-15) and the WGSL `SLOT_*` flags.
    pub info: u32,
    /// The slave node (local index).
    pub s: u32,
    /// The slave's neighbours along its own surface (passes).
    pub np: u32,
    /// See `np`.
    pub nn: u32,
    /// Walls: the unit normal.
    pub normal: [f32; 2],
    /// Walls: a point of the wall.
    pub point: [f32; 2],
    /// Walls: the node's penalty stiffness.
    pub k: f32,
    /// The pass index (walls: `u32::MAX`).
    pub pass: u32,
    /// The slave's body.
    pub body: u32,
    /// Coulomb coefficient of the slot's contact or wall (0: none).
    pub mu: f32,
    /// Penalty friction: the tangential spring over the normal one.
    pub kt: f32,
    /// Perturbed Lagrangian: the slots of the neighbours `np`, `nn` in the same pass (`NONE`:
    /// none), whose candidate segments give their gaps.
    pub ps: u32,
    /// See `ps`.
    pub ns: u32,
    /// Augmented Lagrangian: the multipliers' update rate (1/s; 0: another method).
    pub ar: f32,
}

/// Mirror of WGSL `Segment`: a master segment of a pass.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, Pod, Zeroable)]
pub struct GpuSegment {
    /// First end (local node).
    pub a: u32,
    /// Second end (local node; the body lies on the left of a -> b).
    pub b: u32,
    /// Penalty stiffness.
    pub k: f32,
    /// The segment's pass.
    pub pass: u32,
    /// The segment's body.
    pub body: u32,
    /// 1: a candidate edge of an eroding body that is not on its surface now (WGSL
    /// `SEGMENT_OFF`).
    pub off: u32,
    /// Bit 0: a lies on the axis of an axisymmetric body, bit 1: b does (WGSL `SEGMENT_AXIS_A`,
    /// `SEGMENT_AXIS_B`; [`crate::contact::rules::project`]).
    pub axis: u32,
    /// Padding to 32 bytes.
    pub _pad: u32,
}

const _: () = assert!(std::mem::size_of::<GpuSlot>() == 64);
const _: () = assert!(std::mem::size_of::<GpuSegment>() == 32);

impl From<&SlotTable> for GpuSlot {
    fn from(s: &SlotTable) -> Self {
        GpuSlot {
            info: s.interface
                | (u32::from(s.penalty) << 16)
                | (u32::from(s.wall) << 17)
                | (u32::from(s.second_is_slave) << 18)
                | (u32::from(s.group) << 19)
                | (u32::from(s.self_contact) << 20)
                | (u32::from(s.perturbed) << 21)
                | (u32::from(s.off) << 22),
            s: s.node,
            np: s.neighbours[0],
            nn: s.neighbours[1],
            normal: s.normal.map(|x| x as f32),
            point: s.point.map(|x| x as f32),
            k: s.stiffness as f32,
            pass: s.pass,
            body: s.body,
            mu: s.friction as f32,
            kt: s.friction_stiffness as f32,
            ps: s.neighbour_slots[0],
            ns: s.neighbour_slots[1],
            ar: s.augmentation as f32,
        }
    }
}

impl From<&SegmentTable> for GpuSegment {
    fn from(s: &SegmentTable) -> Self {
        GpuSegment {
            a: s.nodes[0],
            b: s.nodes[1],
            k: s.stiffness as f32,
            pass: s.pass,
            body: s.body,
            off: u32::from(s.off),
            axis: u32::from(s.axis[0]) | (u32::from(s.axis[1]) << 1),
            _pad: 0,
        }
    }
}

/// Per local node its reference position and inverse masses along x and y (WGSL `c_ref`).
pub(crate) fn reference(t: &Tables) -> Vec<[f32; 4]> {
    t.reference
        .iter()
        .zip(&t.inv_mass)
        .map(|(x, im)| [x[0] as f32, x[1] as f32, im[0] as f32, im[1] as f32])
        .collect()
}

/// Per local node its global index and the bits of its f32 mass (WGSL `c_nodes`).
pub(crate) fn node_words(t: &Tables) -> Vec<[u32; 2]> {
    t.nodes
        .iter()
        .zip(&t.mass)
        .map(|(&g, &m)| [g, (m as f32).to_bits()])
        .collect()
}

/// The first slot of each of the `ni` interfaces, then the slot count (WGSL `o_iface`): each
/// interface's slots are contiguous (passes, then walls, in interface order).
///
/// # Errors
/// [`Error::Gpu`] when there are more than 65 535 interfaces (the slot's 16 bits) or the slots
/// are not grouped by interface.
pub(crate) fn interface_starts(t: &Tables, ni: usize) -> Result<Vec<u32>> {
    if ni > 0xffff {
        return Err(Error::Gpu(format!(
            "the GPU backend supports at most 65535 contacts and walls (scene has {ni})"
        )));
    }
    let mut iface = vec![u32::MAX; ni + 1];
    for (k, s) in t.slots.iter().enumerate().rev() {
        iface[s.interface as usize] = k as u32;
    }
    iface[ni] = t.slots.len() as u32;
    for f in (0..ni).rev() {
        if iface[f] == u32::MAX {
            iface[f] = iface[f + 1];
        }
    }
    if t.slots.windows(2).any(|w| w[1].interface < w[0].interface) {
        return Err(Error::Gpu(
            "contact slots are not grouped by interface".into(),
        ));
    }
    Ok(iface)
}
