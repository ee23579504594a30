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
//! the host follows the erosion on its copy of the set (this function, from the flags it keeps,
//! brought up to date by the list of the elements eroded since the last follow), writes the mask with the slaves' neighbours and stiffnesses of the new
//! surfaces into the fixed lists (the entries on before or now, [`Masked::changes`], whose result
//! is [`Masked::tables`]'s: work and bytes in the surfaces' size, not the candidates') and resumes
//! the step with a search, which skips masked entries. No slot or segment is renumbered, so the constraints' warm starts and
//! the multipliers that slots carry stay where they are, and the update depends only on the
//! flags: the same bits every run.

use std::collections::{BTreeMap, HashMap};

use super::tables::{SegmentTable, SlotTable};
use super::{ContactSet, Tables};
use crate::model::Model;

/// The entries of [`Masked`]'s fixed lists that are on (not masked) in a layout, ascending: what
/// [`Masked::changes`] compares the next layout with.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LaidOut {
    /// Slots on.
    pub slots: Vec<u32>,
    /// Segments on.
    pub segments: Vec<u32>,
}

/// The entries of [`Masked`]'s fixed lists that a new layout may change, each with its index and
/// its content in the new layout, ascending by index.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Changes {
    /// Slots.
    pub slots: Vec<(u32, SlotTable)>,
    /// Segments.
    pub segments: Vec<(u32, SegmentTable)>,
}

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
        let mut out = self.every.clone();
        let changes = self.changes(set, &mut LaidOut::default())?;
        for (k, t) in changes.slots {
            out.slots[k as usize] = t;
        }
        for (k, g) in changes.segments {
            out.segments[k as usize] = g;
        }
        out.margin = set.margin;
        Some(out)
    }

    /// The entries on in the layout of `set` ([`Masked::tables`]); `None` as there.
    pub fn laid_out(&self, set: &ContactSet) -> Option<LaidOut> {
        let mut on = LaidOut::default();
        self.changes(set, &mut on)?;
        Some(on)
    }

    /// What laying out `set`'s surfaces (as it follows erosion) changes in the fixed lists after
    /// the layout whose entries on were `on`: every entry on before or now, with its content in
    /// [`Masked::tables`]`(set)` (`set`'s slot or segment where it is on, the candidate's masked
    /// entry where it left); `on` becomes `set`'s. Work in the size of the surfaces, not of the
    /// candidates: applied to the lists of the layout before, it gives those of
    /// [`Masked::tables`]. `None` as there (and `on` unchanged).
    pub fn changes(&self, set: &ContactSet, on: &mut LaidOut) -> Option<Changes> {
        let (slots, segments) = set.entries();
        let at: Vec<u32> = slots
            .iter()
            .map(|s| self.slot_at.get(&(s.pass, s.interface, s.node)).copied())
            .collect::<Option<_>>()?;
        let seg_at: Vec<u32> = segments
            .iter()
            .map(|g| {
                self.segment_at
                    .get(&(g.pass, g.nodes[0], g.nodes[1]))
                    .copied()
            })
            .collect::<Option<_>>()?;
        let mut new_slots: BTreeMap<u32, SlotTable> = on
            .slots
            .iter()
            .map(|&k| (k, self.every.slots[k as usize]))
            .collect();
        for (s, &k) in slots.iter().zip(&at) {
            let mut t = *s;
            t.neighbour_slots = s
                .neighbour_slots
                .map(|j| at.get(j as usize).copied().unwrap_or(u32::MAX));
            new_slots.insert(k, t);
        }
        let mut new_segments: BTreeMap<u32, SegmentTable> = on
            .segments
            .iter()
            .map(|&k| (k, self.every.segments[k as usize]))
            .collect();
        for (g, &k) in segments.iter().zip(&seg_at) {
            new_segments.insert(k, *g);
        }
        let sorted = |mut v: Vec<u32>| {
            v.sort_unstable();
            v
        };
        on.slots = sorted(at);
        on.segments = sorted(seg_at);
        Some(Changes {
            slots: new_slots.into_iter().collect(),
            segments: new_segments.into_iter().collect(),
        })
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
