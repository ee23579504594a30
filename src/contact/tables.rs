//! The contact set as flat, static tables for the GPU kernels ([`Tables`]), and the pairs the
//! last step activated in their numbering ([`ContactSet::active_pairs`]), against which the
//! device search's candidates are checked in tests.

use super::ContactSet;
use crate::scene::ContactMethod;

/// A slot of the GPU contact kernel: one pass's slave node or one wall's node.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SlotTable {
    /// Interface (contact or wall) index.
    pub interface: u32,
    /// Penalty springs (penalty, perturbed or augmented Lagrangian; else Lagrange).
    pub penalty: bool,
    /// Augmented Lagrangian: the multipliers' update rate (1/s; 0: another method).
    pub augmentation: f64,
    /// Perturbed Lagrangian: the spring acts on the consistent penetration (see
    /// [`super::solve::consistent_penetration`]).
    pub perturbed: bool,
    /// The slots of the node's neighbours in the same pass (`u32::MAX`: none; walls: none).
    pub neighbour_slots: [u32; 2],
    /// A wall's node (else a pass's slave node).
    pub wall: bool,
    /// The slave body is the interface's second body (its impulse counts negative).
    pub second_is_slave: bool,
    /// Slave node (local index).
    pub node: u32,
    /// Neighbours along the slave's surface (passes).
    pub neighbours: [u32; 2],
    /// Wall normal and point.
    pub normal: [f64; 2],
    /// A point of the wall.
    pub point: [f64; 2],
    /// Wall penalty stiffness of the node.
    pub stiffness: f64,
    /// Coulomb friction coefficient of the slot's contact or wall.
    pub friction: f64,
    /// Penalty friction: the tangential spring over the normal one.
    pub friction_stiffness: f64,
    /// The slot's pass (index in pass order), `u32::MAX` for a wall.
    pub pass: u32,
    /// The slave node's body (for a wall, the node's body).
    pub body: u32,
    /// The pass is a group: the impulse's sign on the interface's first body follows the body
    /// order (+1 when this slot's body is below the segment's, -1 above, 0 equal).
    pub group: bool,
    /// The pass admits self-contact (see [`super::rules::admissible`]).
    pub self_contact: bool,
    /// A candidate node of an eroding body that is not a slave now (the GPU's masked tables,
    /// [`super::erosion::Masked`]); never in [`ContactSet::tables`].
    pub off: bool,
}

/// A master segment of the GPU contact kernel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SegmentTable {
    /// Local nodes a -> b (the body on the left).
    pub nodes: [u32; 2],
    /// Penalty stiffness.
    pub stiffness: f64,
    /// The segment's pass (index in pass order).
    pub pass: u32,
    /// The segment's body.
    pub body: u32,
    /// Whether a, b lie on the axis of an axisymmetric body (see
    /// [`super::rules::project`]).
    pub axis: [bool; 2],
    /// A candidate edge of an eroding body that is not on its surface now (the GPU's masked
    /// tables, [`super::erosion::Masked`]); never in [`ContactSet::tables`].
    pub off: bool,
}

/// The flat, static tables of a contact set, for the GPU kernel.
#[derive(Debug, Clone)]
pub struct Tables {
    /// Global index of each local contact node.
    pub nodes: Vec<u32>,
    /// Inverse mass per local node and direction (0 on a constrained direction).
    pub inv_mass: Vec<[f64; 2]>,
    /// Mass per local node.
    pub mass: Vec<f64>,
    /// Reference (undeformed) position of each local node (for [`super::rules::admissible`]).
    pub reference: Vec<[f64; 2]>,
    /// Slots: every pass's slave nodes in order, then every wall's nodes.
    pub slots: Vec<SlotTable>,
    /// Master segments of all passes, in pass order.
    pub segments: Vec<SegmentTable>,
    /// Search margin (half the shortest segment).
    pub margin: f64,
}

impl ContactSet {
    /// Slots of the GPU tables: every pass's slave nodes and every wall's nodes.
    pub fn slot_count(&self) -> usize {
        self.passes.iter().map(|p| p.slaves.len()).sum::<usize>()
            + self.walls.iter().map(|w| w.nodes.len()).sum::<usize>()
    }

    /// The static tables of the GPU kernels.
    pub fn tables(&self) -> Tables {
        let (slots, segments) = self.entries();
        Tables {
            nodes: self.nodes.clone(),
            inv_mass: self.inv_mass.clone(),
            mass: self.mass.clone(),
            reference: self.reference.clone(),
            slots,
            segments,
            margin: self.margin,
        }
    }

    /// The slots and segments of [`ContactSet::tables`] alone (what erosion changes).
    pub fn entries(&self) -> (Vec<SlotTable>, Vec<SegmentTable>) {
        let mut slots = Vec::new();
        let mut segments = Vec::new();
        for (pi, p) in self.passes.iter().enumerate() {
            let base = slots.len() as u32;
            for (si, &s) in p.slaves.iter().enumerate() {
                let neighbour_slots = p.neighbour_slaves.get(si).map_or([u32::MAX; 2], |n| {
                    n.map(|j| if j == u32::MAX { j } else { base + j })
                });
                slots.push(SlotTable {
                    neighbour_slots,
                    interface: p.interface as u32,
                    penalty: p.method.has_springs(),
                    perturbed: p.method == ContactMethod::PerturbedLagrange,
                    augmentation: p.law.augmentation,
                    wall: false,
                    second_is_slave: !p.group && !p.slave_is_first,
                    node: s,
                    neighbours: p.neighbours[si],
                    normal: [0.0; 2],
                    point: [0.0; 2],
                    stiffness: 0.0,
                    friction: p.law.friction,
                    friction_stiffness: p.law.friction_stiffness,
                    pass: pi as u32,
                    body: p.slave_body[si],
                    group: p.group,
                    self_contact: p.self_contact,
                    off: false,
                });
            }
            segments.extend(
                p.segments
                    .iter()
                    .zip(&p.stiffness)
                    .zip(&p.segment_body)
                    .map(|((&nodes, &stiffness), &body)| SegmentTable {
                        nodes,
                        stiffness,
                        pass: pi as u32,
                        body,
                        axis: self.on_axis(nodes),
                        off: false,
                    }),
            );
        }
        for w in &self.walls {
            for (idx, &l) in w.nodes.iter().enumerate() {
                slots.push(SlotTable {
                    interface: w.interface as u32,
                    penalty: w.method.has_springs(),
                    perturbed: w.method == ContactMethod::PerturbedLagrange,
                    augmentation: w.law.augmentation,
                    wall: true,
                    second_is_slave: false,
                    node: l,
                    neighbours: w.neighbours.get(idx).copied().unwrap_or([l, l]),
                    neighbour_slots: [u32::MAX; 2],
                    normal: w.normal,
                    point: w.point,
                    stiffness: w.stiffness[idx],
                    friction: w.law.friction,
                    friction_stiffness: w.law.friction_stiffness,
                    pass: u32::MAX,
                    body: w.body[idx],
                    group: false,
                    self_contact: false,
                    off: false,
                });
            }
        }
        (slots, segments)
    }
}

impl ContactSet {
    /// The (slot, segment) pairs, in [`Tables`] numbering, of the constraints of the last
    /// [`ContactSet::apply`] that carry an impulse (wall constraints excluded): the pairs the
    /// narrow phase activated, against which a device search's candidates are checked in tests.
    pub fn active_pairs(&self) -> Vec<(u32, u32)> {
        let mut slot_base = Vec::with_capacity(self.passes.len());
        let mut seg_base = Vec::with_capacity(self.passes.len());
        let (mut sb, mut gb) = (0u32, 0u32);
        for p in &self.passes {
            slot_base.push(sb);
            seg_base.push(gb);
            sb += p.slaves.len() as u32;
            gb += p.segments.len() as u32;
        }
        let mut out = Vec::new();
        for c in &self.cons {
            if c.a == u32::MAX || c.lambda <= 0.0 {
                continue;
            }
            for (pi, p) in self.passes.iter().enumerate() {
                if p.interface as u32 != c.interface {
                    continue;
                }
                let Some(si) = p.slaves.iter().position(|&s| s == c.s) else {
                    continue;
                };
                if let Some(j) = p.segments.iter().position(|&ab| ab == [c.a, c.b]) {
                    out.push((slot_base[pi] + si as u32, seg_base[pi] + j as u32));
                    break;
                }
            }
        }
        out.sort_unstable();
        out
    }

    /// The wall slots, in [`Tables`] numbering (after every pass's slaves), of the constraints of
    /// the last [`ContactSet::apply`] that carry an impulse: the wall contacts, against which a
    /// device search's active slots are checked in tests.
    pub fn active_wall_slots(&self) -> Vec<u32> {
        let mut base = self
            .passes
            .iter()
            .map(|p| p.slaves.len() as u32)
            .sum::<u32>();
        let mut out = Vec::new();
        for w in &self.walls {
            for c in &self.cons {
                if c.a != u32::MAX || c.lambda <= 0.0 || c.interface != w.interface as u32 {
                    continue;
                }
                if let Some(i) = w.nodes.iter().position(|&l| l == c.s) {
                    out.push(base + i as u32);
                }
            }
            base += w.nodes.len() as u32;
        }
        out.sort_unstable();
        out.dedup();
        out
    }
}
