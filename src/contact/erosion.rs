//! Eroding contact on the CPU reference: when elements erode ([`crate::step::erosion`]), the
//! contact surfaces of their bodies follow ([`ContactSet::follow_erosion`]). The edges an eroded
//! element exposes join its body's surface and the edges it took away leave, in every pass it
//! takes part in (two bodies, a group such as `bodies = "all"`, self-contact) and in the rigid
//! walls; the nodes it leaves with no element stay as free slave nodes (neighbours: none), so
//! that they still hit surfaces and walls. The broad-phase search runs again in the step that
//! eroded them. A scene without failure never calls it.
//!
//! The form of the surface is that of a fixed candidate list under a mask
//! ([`crate::model::surface::EdgeCandidates`]): every edge of an erodible body's elements is a
//! potential segment, exposed when its element remains and the one across it has eroded (or
//! there is none), and every node of such a body has a local contact number from the first
//! build (`ContactSet::new`), so that erosion never renumbers. The CPU compacts the masked list
//! into the passes' slave and segment lists (with the same segment order, stiffness rule and
//! neighbours as a fresh build on the remaining mesh: `tests/core/erosion_contact.rs` checks it
//! against [`crate::model::surface::Surface::of_remaining`]), and recomputes the penalty step.
//!
//! The GPU twin ([`Masked`], used by `crate::gpu::contact`) keeps fixed slot and segment lists
//! that hold every candidate: every node of an erodible body is a slot of each pass and wall it
//! takes part in, every edge of its elements a segment. A mask marks those that are not on a
//! surface now. In the step that eroded an element the device stops before its contact stage;
//! the host follows the erosion on its copy of the set (this function, from the per-element
//! flags read back), writes the mask with the slaves' neighbours and stiffnesses of the new
//! surfaces into the fixed lists ([`Masked::tables`]) and resumes the step with a search, which
//! skips masked entries. No slot or segment is renumbered, so the constraints' warm starts and
//! the multipliers that slots carry stay where they are, and the update depends only on the
//! flags: the same bits every run.

use std::collections::HashMap;

use super::{ContactSet, Tables};
use crate::model::Model;

/// The GPU's fixed contact lists of an eroding scene: the tables of every candidate slot and
/// segment (`contact::build::every_candidate`), onto which [`Masked::tables`] lays the surfaces
/// of the moment, the rest masked off.
#[derive(Debug, Clone)]
pub struct Masked {
    /// Every candidate, each off.
    every: Tables,
    /// Slot of each (pass, interface, node) among `every`'s slots (walls: pass `u32::MAX`).
    slot_at: HashMap<(u32, u32, u32), u32>,
    /// Segment of each (pass, a, b) among `every`'s segments.
    segment_at: HashMap<(u32, u32, u32), u32>,
}

impl Masked {
    /// The candidate lists of `set` (built by [`ContactSet::new`] for `model`); `None` when a
    /// candidate needs a node outside the set's local nodes (a set not built for `model`).
    pub fn new(model: &Model, set: &ContactSet) -> Option<Masked> {
        let (passes, walls) = super::build::every_candidate(model, &set.nodes)?;
        let mut all = set.clone();
        all.passes = passes;
        all.walls = walls;
        let mut every = all.tables();
        for s in &mut every.slots {
            s.off = true;
            s.neighbours = [s.node; 2];
            s.neighbour_slots = [u32::MAX; 2];
        }
        for g in &mut every.segments {
            g.off = true;
        }
        let slot_at = every
            .slots
            .iter()
            .enumerate()
            .map(|(k, s)| ((s.pass, s.interface, s.node), k as u32))
            .collect();
        let segment_at = every
            .segments
            .iter()
            .enumerate()
            .map(|(k, g)| ((g.pass, g.nodes[0], g.nodes[1]), k as u32))
            .collect();
        Some(Masked {
            every,
            slot_at,
            segment_at,
        })
    }

    /// Slots and segments of the fixed lists.
    pub fn sizes(&self) -> (usize, usize) {
        (self.every.slots.len(), self.every.segments.len())
    }

    /// The tables of `set` (as it follows erosion) laid out on the fixed lists: each of its
    /// slots and segments at its candidate's place (the slots' neighbour slots renumbered), every
    /// other candidate off. `None` when one of them is not a candidate.
    pub fn tables(&self, set: &ContactSet) -> Option<Tables> {
        let now = set.tables();
        let at: Vec<u32> = now
            .slots
            .iter()
            .map(|s| self.slot_at.get(&(s.pass, s.interface, s.node)).copied())
            .collect::<Option<_>>()?;
        let mut out = self.every.clone();
        for (s, &k) in now.slots.iter().zip(&at) {
            let mut t = *s;
            t.neighbour_slots = s
                .neighbour_slots
                .map(|j| at.get(j as usize).copied().unwrap_or(u32::MAX));
            out.slots[k as usize] = t;
        }
        for g in &now.segments {
            let k = *self.segment_at.get(&(g.pass, g.nodes[0], g.nodes[1]))?;
            out.segments[k as usize] = *g;
        }
        out.margin = now.margin;
        Some(out)
    }
}

impl ContactSet {
    /// Follows erosion: the passes' slave nodes and master segments and the walls' nodes become
    /// those of the surfaces left where `eroded` (per global element) have eroded, with their
    /// free nodes, and the next step searches again. Constraints and warm starts of nodes that
    /// remain carry over. Leaves the set as it was (and returns `false`) in the one case it
    /// cannot follow: a surface node outside the first build's local nodes (a body that erodes
    /// but was built without failure).
    pub fn follow_erosion(&mut self, model: &Model, eroded: &[bool]) -> bool {
        let Some((passes, walls)) =
            super::build::rebuild(model, eroded, &self.nodes, &mut self.surfaces)
        else {
            return false;
        };
        for (old, new) in self.passes.iter_mut().zip(passes) {
            old.slaves = new.slaves;
            old.slave_body = new.slave_body;
            old.neighbours = new.neighbours;
            old.neighbour_slaves = new.neighbour_slaves;
            old.segments = new.segments;
            old.segment_body = new.segment_body;
            old.stiffness = new.stiffness;
            old.candidates.clear();
        }
        for (old, new) in self.walls.iter_mut().zip(walls) {
            old.nodes = new.nodes;
            old.body = new.body;
            old.neighbours = new.neighbours;
            old.stiffness = new.stiffness;
        }
        self.searched = false;
        self.penalty_step = self.compute_penalty_step();
        true
    }
}
