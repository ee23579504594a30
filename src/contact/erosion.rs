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

/// The place of each entry of a fixed list by its key: a group (a slot's pass and interface, a
/// segment's pass), a local node `a` and a second number `b` (a slot's node again, a segment's
/// second node). Per group, the entries of each `a` are contiguous (counted by `a`): a lookup is
/// a group among a few and a scan of the few entries of one node. [`Masked::changes`] took two
/// `HashMap`s of `(u32, u32, u32)` before (2026-11-28): their lookups, about 170 ns each in maps of
/// 10^4 slots and 4 x 10^4 segments, cost half its time a follow on the 10^4 striker with failure.
#[derive(Debug, Clone, Default)]
struct Index {
    /// Each group's key and its table.
    groups: Vec<((u32, u32), IndexGroup)>,
}

/// One group of an [`Index`]: the entries of node `a` are `items[start[a]..start[a + 1]]`.
#[derive(Debug, Clone, Default)]
struct IndexGroup {
    start: Vec<u32>,
    /// `(b, place)`, by `a` and then in list order.
    items: Vec<(u32, u32)>,
}

impl Index {
    /// The index of the list whose entry `k` has the key `keys[k]`: (group, a, b).
    fn new(keys: impl Iterator<Item = ((u32, u32), u32, u32)> + Clone) -> Index {
        let mut groups: Vec<((u32, u32), IndexGroup)> = Vec::new();
        let group_of = |groups: &mut Vec<((u32, u32), IndexGroup)>, key: (u32, u32)| match groups
            .iter()
            .position(|(g, _)| *g == key)
        {
            Some(i) => i,
            None => {
                groups.push((key, IndexGroup::default()));
                groups.len() - 1
            }
        };
        // Counts by node, then offsets, then the places.
        for (key, a, _) in keys.clone() {
            let i = group_of(&mut groups, key);
            let g = &mut groups[i].1;
            let a = a as usize;
            if g.start.len() < a + 2 {
                g.start.resize(a + 2, 0);
            }
            g.start[a + 1] += 1;
        }
        for (_, g) in &mut groups {
            for i in 1..g.start.len() {
                g.start[i] += g.start[i - 1];
            }
            g.items = vec![(0, 0); g.start.last().copied().unwrap_or(0) as usize];
        }
        let mut fill: Vec<Vec<u32>> = groups.iter().map(|(_, g)| g.start.clone()).collect();
        for (k, (key, a, b)) in keys.enumerate() {
            let i = group_of(&mut groups, key);
            let at = &mut fill[i][a as usize];
            groups[i].1.items[*at as usize] = (b, k as u32);
            *at += 1;
        }
        Index { groups }
    }

    /// The place of the entry (group, a, b), if any (the last such).
    fn get(&self, key: (u32, u32), a: u32, b: u32) -> Option<u32> {
        let (_, g) = self.groups.iter().find(|(k, _)| *k == key)?;
        let a = a as usize;
        let (lo, hi) = (*g.start.get(a)?, *g.start.get(a + 1)?);
        // The last of equal keys, as a map collected in list order would keep.
        g.items[lo as usize..hi as usize]
            .iter()
            .rev()
            .find(|e| e.0 == b)
            .map(|e| e.1)
    }
}

/// The GPU's fixed contact lists of an eroding scene: the tables of every candidate slot and
/// segment (`contact::build::every_candidate`), onto which [`Masked::tables`] lays the surfaces
/// of the moment, the rest masked off.
#[derive(Debug, Clone)]
pub struct Masked {
    /// Every candidate, each off.
    every: Tables,
    /// Slot of each (pass, interface, node) among `every`'s slots (walls: pass `u32::MAX`).
    slot_at: Index,
    /// Segment of each (pass, a, b) among `every`'s segments.
    segment_at: Index,
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
        let slot_at = Index::new(
            every
                .slots
                .iter()
                .map(|s| ((s.pass, s.interface), s.node, s.node)),
        );
        let segment_at = Index::new(
            every
                .segments
                .iter()
                .map(|g| ((g.pass, 0), g.nodes[0], g.nodes[1])),
        );
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
            .map(|s| self.slot_at.get((s.pass, s.interface), s.node, s.node))
            .collect::<Option<_>>()?;
        let seg_at: Vec<u32> = segments
            .iter()
            .map(|g| self.segment_at.get((g.pass, 0), g.nodes[0], g.nodes[1]))
            .collect::<Option<_>>()?;
        let new_slots: Vec<(u32, SlotTable)> = slots
            .iter()
            .zip(&at)
            .map(|(s, &k)| {
                let mut t = *s;
                t.neighbour_slots = s
                    .neighbour_slots
                    .map(|j| at.get(j as usize).copied().unwrap_or(u32::MAX));
                (k, t)
            })
            .collect();
        let new_segments: Vec<(u32, SegmentTable)> = segments
            .iter()
            .zip(&seg_at)
            .map(|(g, &k)| (k, *g))
            .collect();
        let slots = merged(&on.slots, |k| self.every.slots[k as usize], new_slots);
        let segments = merged(
            &on.segments,
            |k| self.every.segments[k as usize],
            new_segments,
        );
        let sorted = |mut v: Vec<u32>| {
            v.sort_unstable();
            v
        };
        on.slots = sorted(at);
        on.segments = sorted(seg_at);
        Some(Changes { slots, segments })
    }
}

/// The entries `before` (ascending, each with its masked content `off`) and `now` (each index
/// once), ascending by index, an entry of `now` in place of one `before` of the same index.
/// A merge of two sorted lists: [`Masked::changes`] took a `BTreeMap` of the tables before
/// (2026-11-28), whose inserts of 100-byte tables cost most of its 0.7 ms a follow on the 10^4
/// striker with failure.
fn merged<T: Copy>(
    before: &[u32],
    off: impl Fn(u32) -> T,
    mut now: Vec<(u32, T)>,
) -> Vec<(u32, T)> {
    now.sort_unstable_by_key(|e| e.0);
    let mut out = Vec::with_capacity(before.len() + now.len());
    let mut old = before.iter().copied().peekable();
    for (k, t) in now {
        while let Some(b) = old.next_if(|&b| b < k) {
            out.push((b, off(b)));
        }
        old.next_if_eq(&k);
        out.push((k, t));
    }
    out.extend(old.map(|b| (b, off(b))));
    out
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

#[cfg(test)]
mod tests {
    use super::{merged, Index};
    use std::collections::{BTreeMap, HashMap};

    /// The index finds what a map of the same keys finds (the last of equal keys), and nothing
    /// for a key it does not hold.
    #[test]
    fn index_finds_what_a_map_finds() {
        let keys: Vec<((u32, u32), u32, u32)> = (0..500u32)
            .map(|k| ((k % 3, u32::from(k % 7 == 0)), (k * 37) % 41, (k * 13) % 5))
            .collect();
        let index = Index::new(keys.iter().copied());
        let map: HashMap<((u32, u32), u32, u32), u32> = keys
            .iter()
            .enumerate()
            .map(|(k, &key)| (key, k as u32))
            .collect();
        for (key, a, b) in &keys {
            assert_eq!(index.get(*key, *a, *b), map.get(&(*key, *a, *b)).copied());
        }
        assert_eq!(index.get((0, 0), 1000, 0), None);
        assert_eq!(index.get((9, 9), 0, 0), None);
        assert_eq!(index.get((0, 0), 0, 99), None);
    }

    /// The merge gives what a map of the entries before, overwritten by those of now, gives.
    #[test]
    fn merged_gives_the_entries_of_a_map_overwritten_by_now() {
        let before: Vec<u32> = (0..200).filter(|k| k % 3 != 1).collect();
        let now: Vec<(u32, i64)> = (0..250u32)
            .filter(|k| k % 4 != 2)
            .map(|k| ((k * 7919) % 250, -i64::from(k)))
            .collect();
        let mut map: BTreeMap<u32, i64> = before.iter().map(|&k| (k, i64::from(k))).collect();
        map.extend(now.iter().copied());
        let want: Vec<(u32, i64)> = map.into_iter().collect();
        assert_eq!(merged(&before, i64::from, now), want);
    }
}
