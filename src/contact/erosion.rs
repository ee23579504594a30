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
//! How the GPU twin should mirror it: keep the candidate edges and candidate nodes of every
//! erodible body in its static tables (segments and slots, each with its penalty stiffness
//! computed once by the same rule), with a mask per candidate edge and per candidate node
//! written from the per-element eroded flags by one deterministic kernel in the step that
//! eroded something (an edge: its element alive and the one across it eroded or none; a node:
//! on an exposed edge, or all its elements eroded; its two neighbours from the exposed edges
//! that end and start at it); the search and the narrow phase skip masked entries, and the
//! search is forced in that step. No compaction, no reallocation, and the same bits every run,
//! since the mask depends only on the flags.

use super::ContactSet;
use crate::model::Model;

impl ContactSet {
    /// Follows erosion: the passes' slave nodes and master segments and the walls' nodes become
    /// those of the surfaces left where `eroded` (per global element) have eroded, with their
    /// free nodes, and the next step searches again. Constraints and warm starts of nodes that
    /// remain carry over. Leaves the set as it was (and returns `false`) in the one case it
    /// cannot follow: a surface node outside the first build's local nodes (a body that erodes
    /// but was built without failure).
    pub fn follow_erosion(&mut self, model: &Model, eroded: &[bool]) -> bool {
        let Some((passes, walls)) = super::build::rebuild(model, eroded, &self.nodes) else {
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
