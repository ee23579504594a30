//! Reading results back from the device: after each submission the control block, the contact
//! counters and the history rows the batch wrote (one round trip for the usual batch, a second
//! one for more rows), decoded into the run's events; and one-off copies of any buffers for
//! snapshots, checkpoints and test hooks. The CPU reference writes the same events directly
//! ([`crate::step::cpu::CpuSolver`]).

use crate::contact::ContactSample;
use crate::error::{Error, Result};
use crate::gpu::contact::{ContactCounters, STATE_ERODED, STATE_SEARCH_GROW};
use crate::gpu::layout::*;
use crate::gpu::state::MAX_BATCH;
use crate::step::{Event, Failure, Sample};

use super::GpuSolver;

impl GpuSolver {
    /// Maps and copies the whole of `buffer` (counted in the bytes read back).
    pub(super) fn map_read(&mut self, buffer: &wgpu::Buffer) -> Result<Vec<u8>> {
        self.map_prefix(buffer, buffer.size())
    }

    /// Maps and copies the first `len` bytes of `buffer` (counted in the bytes read back).
    pub(super) fn map_prefix(&mut self, buffer: &wgpu::Buffer, len: u64) -> Result<Vec<u8>> {
        self.counters.bytes_read_back += len;
        let slice = buffer.slice(..len);
        slice.map_async(wgpu::MapMode::Read, |_| {});
        self.ctx
            .device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| Error::Gpu(format!("device lost while waiting: {e}")))?;
        let bytes = slice
            .get_mapped_range()
            .map_err(|e| Error::Gpu(format!("cannot map readback buffer: {e:?}")))?
            .to_vec();
        buffer.unmap();
        Ok(bytes)
    }

    /// Reads back the control block and the new history rows.
    pub(super) fn read(&mut self, events: &mut Vec<Event>) -> Result<()> {
        let readback = self.readback.clone();
        let (bytes, spec) = self.map_with_rows(&readback)?;
        self.counters.readbacks += 1;
        let ctrl: Control = bytemuck::pod_read_unaligned(&bytes[..std::mem::size_of::<Control>()]);
        let mut switched = false;
        if let Some(c) = self.state.contact.as_mut() {
            let at = self.counters_at as usize;
            c.counters = bytemuck::pod_read_unaligned(
                &bytes[at..at + std::mem::size_of::<ContactCounters>()],
            );
            switched = c.switch_search(ctrl.step);
        }
        if switched {
            // The batch recorded ahead searches the other way.
            self.drop_recorded_ahead();
        }
        let stride = self.state.params.row_stride as usize;
        let cstride = self
            .state
            .contact
            .as_ref()
            .map_or(0, |c| c.params.hist_stride as usize);
        let new_rows = ctrl
            .rows
            .saturating_sub(self.rows_read)
            .min(self.state.params.row_capacity) as usize;
        let hist_len = 4 * stride * new_rows;
        let rows_bytes = if new_rows <= self.spec_rows as usize {
            spec
        } else {
            self.read_rows(new_rows)?
        };
        let hist: &[u8] = &rows_bytes[..hist_len];
        // The contact rows follow the main rows copied (the spec rows or the rows read).
        let copied = if new_rows <= self.spec_rows as usize {
            self.spec_rows as usize
        } else {
            new_rows
        };
        let at = 4 * stride * copied;
        let chist: &[u8] = &rows_bytes[at..at + 4 * cstride * new_rows];
        let mut row_events = Vec::new();
        for j in 0..ctrl.rows.saturating_sub(self.rows_read) as usize {
            let sample = self.sample(hist, chist, j);
            self.counters.eroded_elements = sample.eroded_elements;
            row_events.push(Event::Sample(sample));
        }
        self.rows_read = self.rows_read.max(ctrl.rows);
        if ctrl.dt_next > 0.0 {
            self.dt_estimate = ctrl.dt_next as f64;
        }
        self.ctrl = ctrl;
        if ctrl.state == STATE_SEARCH_GROW || ctrl.state == STATE_ERODED {
            if ctrl.state == STATE_ERODED {
                self.contact_follow_erosion()?;
            } else {
                self.contact_grow()?;
            }
            events.extend(row_events);
            return Ok(());
        }
        self.erosion_cap = (2 * self.erosion_cap).min(MAX_BATCH);
        let snapshot_done = ctrl.state == STATE_DONE && ctrl.flags & FLAG_SNAPSHOT != 0;
        if ctrl.state == STATE_PAUSED || snapshot_done {
            let (step, time) = if ctrl.state == STATE_PAUSED {
                (
                    ctrl.step as u64 - 1,
                    self.time_of(&ctrl) - ctrl.dt_prev as f64,
                )
            } else {
                (ctrl.step as u64, self.time_of(&ctrl))
            };
            let snap = self.read_snapshot(step, time)?;
            row_events.push(Event::Snapshot(snap));
            if ctrl.state == STATE_PAUSED {
                self.ctx.queue.write_buffer(
                    &self.state.ctrl,
                    CONTROL_STATE_OFFSET,
                    bytemuck::bytes_of(&STATE_RUNNING),
                );
            }
        }
        events.extend(row_events);
        match ctrl.state {
            STATE_DONE => {
                self.finished = true;
                events.push(Event::Done);
            }
            STATE_FAILED => {
                self.finished = true;
                let message = self.names.failure(&ctrl, &self.schedule);
                events.push(Event::Failed(Failure {
                    step: ctrl.step as u64,
                    time: self.time_of(&ctrl),
                    message,
                }));
            }
            _ => {}
        }
        Ok(())
    }

    /// History row `j` of the rows read back (`hist`: the main rows, `chist`: the contact rows)
    /// as a sample.
    fn sample(&self, hist: &[u8], chist: &[u8], j: usize) -> Sample {
        let nb = self.names.body_count();
        // The plastic work's word before the bodies' (plastic scenes), then the eroded count and
        // energy (scenes with failure).
        let pw = self.state.params.plastic as usize;
        let fw = 2 * self.state.params.failure as usize;
        let base = j * self.state.params.row_stride as usize;
        let w = |i: usize| -> f32 {
            bytemuck::pod_read_unaligned(&hist[4 * (base + i)..4 * (base + i) + 4])
        };
        let mut sample = Sample {
            time: seconds(w(0).to_bits(), w(1).to_bits(), self.schedule.end_time),
            step: w(2).to_bits() as u64,
            dt: w(3) as f64,
            kinetic: w(4) as f64,
            internal: w(5) as f64,
            hourglass: w(6) as f64,
            viscous: w(7) as f64,
            plastic: if pw > 0 { w(9) as f64 } else { 0.0 },
            eroded_elements: if fw > 0 { w(9 + pw) as u64 } else { 0 },
            eroded_energy: if fw > 0 { w(10 + pw) as f64 } else { 0.0 },
            external: w(8) as f64,
            contact: 0.0,
            friction: 0.0,
            contacts: Vec::new(),
            body_velocity: (0..nb)
                .map(|b| {
                    [
                        w(9 + pw + fw + 2 * b) as f64,
                        w(10 + pw + fw + 2 * b) as f64,
                    ]
                })
                .collect(),
        };
        if let Some(c) = &self.state.contact {
            let cs = c.params.hist_stride as usize;
            let cb = j * cs;
            let r = |i: usize| -> f64 {
                let x: f32 = bytemuck::pod_read_unaligned(&chist[4 * (cb + i)..4 * (cb + i) + 4]);
                x as f64
            };
            sample.contact = r(0);
            // With friction: its work in word 1, and 5 words per interface (ft last).
            let friction = c.params.friction != 0;
            let (base, per) = if friction { (2, 5) } else { (1, 4) };
            if friction {
                sample.friction = r(1);
            }
            sample.contacts = (0..c.names.len())
                .map(|f| ContactSample {
                    force: [r(base + per * f), r(base + 1 + per * f)],
                    max_penetration: r(base + 2 + per * f),
                    active_nodes: r(base + 3 + per * f) as u32,
                    ft: if friction { r(base + 4 + per * f) } else { 0.0 },
                })
                .collect();
        }
        sample
    }

    /// Records copies of the `n` history rows from `rows_read` on (the main rows packed from 0,
    /// then the contact rows packed right after them) into the rows staging buffer.
    pub(super) fn copy_rows(&self, enc: &mut wgpu::CommandEncoder, n: usize) {
        let cap = self.state.params.row_capacity as usize;
        let first = self.rows_read as usize % cap;
        let mut copy = |src: &wgpu::Buffer, words: usize, dst_at: u64| {
            let head = n.min(cap - first);
            if head > 0 {
                enc.copy_buffer_to_buffer(
                    src,
                    (4 * first * words) as u64,
                    &self.rows_readback,
                    dst_at,
                    (4 * head * words) as u64,
                );
            }
            if head < n {
                enc.copy_buffer_to_buffer(
                    src,
                    0,
                    &self.rows_readback,
                    dst_at + (4 * head * words) as u64,
                    (4 * (n - head) * words) as u64,
                );
            }
        };
        copy(
            &self.state.history,
            self.state.params.row_stride as usize,
            0,
        );
        if let Some(c) = &self.state.contact {
            copy(
                &c.history,
                c.params.hist_stride as usize,
                4 * (n * self.state.params.row_stride as usize) as u64,
            );
        }
    }

    /// Bytes of `n` main and contact history rows.
    fn row_bytes(&self, n: usize) -> u64 {
        let c = self
            .state
            .contact
            .as_ref()
            .map_or(0, |c| c.params.hist_stride as u64);
        4 * n as u64 * (self.state.params.row_stride as u64 + c)
    }

    /// Maps the control readback and the rows copied with the submission in one round trip.
    fn map_with_rows(&mut self, readback: &wgpu::Buffer) -> Result<(Vec<u8>, Vec<u8>)> {
        let rows = self.rows_readback.clone();
        let rows_len = self.row_bytes(self.spec_rows as usize);
        self.counters.bytes_read_back += readback.size() + rows_len;
        let a = readback.slice(..);
        // Only the rows copied with the submission (none: nothing to map).
        let b = (rows_len > 0).then(|| rows.slice(..rows_len));
        a.map_async(wgpu::MapMode::Read, |_| {});
        if let Some(b) = &b {
            b.map_async(wgpu::MapMode::Read, |_| {});
        }
        self.ctx
            .device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| Error::Gpu(format!("device lost while waiting: {e}")))?;
        let get = |s: wgpu::BufferSlice<'_>| -> Result<Vec<u8>> {
            Ok(s.get_mapped_range()
                .map_err(|e| Error::Gpu(format!("cannot map readback buffer: {e:?}")))?
                .to_vec())
        };
        let out = (get(a)?, b.map(get).transpose()?.unwrap_or_default());
        readback.unmap();
        if rows_len > 0 {
            rows.unmap();
        }
        Ok(out)
    }

    /// Reads the `n` history rows from `rows_read` on in a second round trip (a batch that
    /// wrote more rows than were copied with it).
    fn read_rows(&mut self, n: usize) -> Result<Vec<u8>> {
        let mut enc = self
            .ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("rows"),
            });
        self.copy_rows(&mut enc, n);
        self.ctx.queue.submit([enc.finish()]);
        let rb = self.rows_readback.clone();
        self.counters.readbacks += 1;
        self.map_prefix(&rb, self.row_bytes(n))
    }

    /// Copies each `(buffer, offset, bytes)` in turn into one fresh staging buffer, reads it back
    /// (one readback, counted) and returns the bytes, packed in that order. For test hooks and
    /// one-off reads; the per-batch readbacks keep their own buffers.
    pub(crate) fn read_copies(
        &mut self,
        label: &str,
        parts: &[(&wgpu::Buffer, u64, u64)],
    ) -> Result<Vec<u8>> {
        let total: u64 = parts.iter().map(|p| p.2).sum();
        let staging = self.ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: total.max(4),
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut enc = self
            .ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(label) });
        let mut at = 0;
        for &(src, offset, bytes) in parts {
            enc.copy_buffer_to_buffer(src, offset, &staging, at, bytes);
            at += bytes;
        }
        self.ctx.queue.submit([enc.finish()]);
        self.counters.readbacks += 1;
        let mut bytes = self.map_read(&staging)?;
        bytes.truncate(total as usize);
        Ok(bytes)
    }
}
