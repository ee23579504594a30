//! Pressure loads and mass damping on the GPU (`shaders/loads.wgsl`), compiled only for scenes
//! that have them: the pressure entries' forces before the node stage, and the work of the
//! pressure and damping impulses after the contact stage. The CPU reference is the Pressure and
//! MassDamping stages of [`crate::step::cpu::CpuSolver`]; the damped velocity update itself is the
//! `loads` variant of the node kernel.

use bytemuck::{Pod, Zeroable};
use wgpu::{ComputePipeline, Device};

use super::shader::{compute_pipeline, Features};
use crate::model::Model;

/// WGSL source.
pub const SOURCE: &str = concat!(
    include_str!("../../shaders/curve.wgsl"),
    include_str!("../../shaders/loads.wgsl")
);

/// Threads per workgroup.
pub const WORKGROUP: u32 = 64;

/// Mirror of WGSL `Entry`: one loaded node of one pressure load.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, Pod, Zeroable)]
pub struct GpuPressureEntry {
    /// Force per unit pressure on the node (N/Pa).
    pub f: [f32; 2],
    /// The load's pressure (Pa).
    pub value: f32,
    /// The load's ramp duration (s; 0 without a ramp; -1 - k for load curve k of the curve
    /// table, [`super::boundary::curve_table`]).
    pub ramp: f32,
}

const _: () = assert!(std::mem::size_of::<GpuPressureEntry>() == 16);

/// The pipeline of entry point `entry` (`pressure_force`, `load_work`).
pub(crate) fn pipeline(device: &Device, features: Features, entry: &str) -> ComputePipeline {
    compute_pipeline(device, entry, SOURCE, features, entry, Some(WORKGROUP))
}

/// The pressure entries in the CPU's order (loads in scene order, each load's nodes ascending),
/// with the node of each.
pub fn pressure_entries(model: &Model) -> Vec<(u32, GpuPressureEntry)> {
    let (_, curves) = super::boundary::curve_table(model);
    model
        .pressures
        .iter()
        .zip(curves)
        .flat_map(|(p, curve)| {
            // A load curve k is encoded as the ramp -1 - k (see loads.wgsl's Entry).
            let ramp = match curve {
                Some(k) => -1.0 - k as f32,
                None => p.ramp.unwrap_or(0.0) as f32,
            };
            p.nodes.iter().map(move |&(n, f)| {
                (
                    n,
                    GpuPressureEntry {
                        f: [f[0] as f32, f[1] as f32],
                        value: p.value as f32,
                        ramp,
                    },
                )
            })
        })
        .collect()
}
