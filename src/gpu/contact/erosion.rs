//! Eroding contact on the device (a scene with failure and contact): the contact state's fixed
//! slot and segment lists hold every candidate under a mask ([`crate::contact::erosion::Masked`]),
//! and after a step stopped with [`super::STATE_ERODED`] the host follows the erosion on its copy of the
//! contact set (the CPU reference's [`crate::contact::ContactSet::follow_erosion`]) and writes the
//! entries that changed among those on before or now ([`Masked::changes`]; the whole lists only
//! after a checkpoint's buffers were restored), in `ContactState::follow_erosion`; the search
//! skips masked entries (`shaders/contact_search.wgsl`).

use bytemuck::Pod;

use super::tables::{GpuSegment, GpuSlot};
use super::{ContactState, PARAMS_SIZE};
use crate::contact::erosion::{LaidOut, Masked};
use crate::contact::Tables;
use crate::error::{Error, Result};
use crate::model::Model;

/// What a [`ContactState`] of an eroding scene keeps to follow erosion.
#[derive(Debug)]
pub(super) struct Eroding {
    pub masked: Masked,
    pub model: Box<Model>,
    /// The device's slot and segment lists as last written (empty: not known, after a
    /// checkpoint's buffers were restored).
    pub slots: Vec<GpuSlot>,
    /// See `slots`.
    pub segments: Vec<GpuSegment>,
    /// The entries on in them.
    pub on: LaidOut,
}

/// Sets the entries `changes` of `was` (the device's list of `T`, records from offset 0 of
/// `buffer`) and writes those that differ, one write per run of them (runs fewer than 16 entries
/// apart merged): the work and the bytes are those of the entries that changed, not of the list.
fn write_entries<T: Pod + PartialEq>(
    queue: &wgpu::Queue,
    buffer: &wgpu::Buffer,
    was: &mut [T],
    changes: impl Iterator<Item = (usize, T)>,
) {
    let mut dirty: Vec<usize> = Vec::new();
    for (k, t) in changes {
        if was[k] != t {
            was[k] = t;
            dirty.push(k);
        }
    }
    let size = std::mem::size_of::<T>();
    let mut i = 0;
    while i < dirty.len() {
        let start = dirty[i];
        let mut end = start + 1;
        i += 1;
        while i < dirty.len() && dirty[i] < end + 16 {
            end = dirty[i] + 1;
            i += 1;
        }
        queue.write_buffer(
            buffer,
            (start * size) as u64,
            bytemuck::cast_slice(&was[start..end]),
        );
    }
}

/// The error of eroding contact tables that cannot be built or followed (`what` of them).
pub(super) fn unfollowed(what: &str) -> Error {
    Error::Gpu(format!(
        "cannot {what} the eroding contact's candidate lists: a surface node or edge is not a \
         candidate of its body"
    ))
}

impl ContactState {
    /// After a step stopped with [`super::STATE_ERODED`]: the surfaces follow the elements flagged in
    /// `eroded` (per global element) on the host's copy of the set, whose slots and segments
    /// are written into the fixed lists under their mask, and a search is marked due, so that
    /// the resumed step searches the new surfaces. Returns the penalty springs' step now.
    ///
    /// # Errors
    /// [`Error::Gpu`] when a surface node or edge is not among the candidates.
    pub(crate) fn follow_erosion(
        &mut self,
        queue: &wgpu::Queue,
        eroded: &[bool],
    ) -> Result<Option<f64>> {
        let Some(er) = self.eroding.as_mut() else {
            return Err(unfollowed("follow"));
        };
        // As on the CPU: a set that cannot follow (never with a set built for this model)
        // keeps its surfaces.
        self.set.follow_erosion(&er.model, eroded);
        let buffer = |binding: u32| {
            self.entries
                .iter()
                .find(|e| e.0 == binding)
                .map(|e| e.1.clone())
        };
        let (b_slots, b_segs) = (buffer(7), buffer(8));
        let known = er.slots.len() + er.segments.len() == {
            let (ns, ng) = er.masked.sizes();
            ns + ng
        };
        if known {
            // The entries on before or now, against what the device holds.
            let ch = er
                .masked
                .changes(&self.set, &mut er.on)
                .ok_or_else(|| unfollowed("lay out"))?;
            if let Some(b) = &b_slots {
                let it = ch
                    .slots
                    .iter()
                    .map(|(k, t)| (*k as usize, GpuSlot::from(t)));
                write_entries(queue, b, &mut er.slots, it);
            }
            if let Some(b) = &b_segs {
                let it = ch
                    .segments
                    .iter()
                    .map(|(k, g)| (*k as usize, GpuSegment::from(g)));
                write_entries(queue, b, &mut er.segments, it);
            }
        } else {
            // The device's lists are not known (a checkpoint restored): all of them.
            let t: Tables = er
                .masked
                .tables(&self.set)
                .ok_or_else(|| unfollowed("lay out"))?;
            er.on = er
                .masked
                .laid_out(&self.set)
                .ok_or_else(|| unfollowed("lay out"))?;
            er.slots = t.slots.iter().map(GpuSlot::from).collect();
            er.segments = t.segments.iter().map(GpuSegment::from).collect();
            if let (Some(b), false) = (&b_slots, er.slots.is_empty()) {
                queue.write_buffer(b, 0, bytemuck::cast_slice(&er.slots));
            }
            if let (Some(b), false) = (&b_segs, er.segments.is_empty()) {
                queue.write_buffer(b, 0, bytemuck::cast_slice(&er.segments));
            }
        }
        // Counters: due = 1 (offset 0).
        queue.write_buffer(&self.ctl, PARAMS_SIZE, bytemuck::bytes_of(&1u32));
        Ok(self.set.penalty_step().map(|(dt, _)| dt))
    }

    /// Forgets what [`ContactState::follow_erosion`] last wrote (after a checkpoint's buffers
    /// were restored): its next call writes the whole lists.
    pub(crate) fn forget_written(&mut self) {
        if let Some(er) = self.eroding.as_mut() {
            er.slots.clear();
            er.segments.clear();
        }
    }
}
