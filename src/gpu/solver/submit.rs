//! Submitting batches of steps. Recording a batch costs the host a few microseconds a step (on
//! the development machine about 0.8 us a dispatch, almost all of it in wgpu's `finish`: 20 us a
//! step for the striker's 26 dispatches, 4 us for the block's 7), and the device waits for it
//! when it is recorded after the batch before has been read back. So on GPUs ([`record_ahead`])
//! the solver records the next batch right after submitting one, while the device runs it
//! ("recording ahead"), and
//! submits it after the readback when the next batch has the same number of steps and nothing
//! has changed the buffers or bind groups since (a contact buffer grown, the surfaces moved
//! after an erosion, a checkpoint restored: [`GpuSolver::drop_recorded_ahead`]); otherwise it
//! records the batch anew. The commands are the same either way, so are the results (tested);
//! the control block, history and counter copies are recorded at each submission, since they
//! depend on what the readback found.

use std::time::Instant;

use crate::gpu::layout::Control;

use super::{GpuSolver, SPEC_ROWS};
use crate::gpu::contact::ContactCounters;

/// Whether a solver on an adapter of `device_type` records each batch while the device runs
/// the one before, by default: on GPUs. On a CPU adapter (lavapipe) the device's threads run on
/// the host's cores, so there is nothing to overlap, and the same-run figures on the 2-core
/// development machine went either way (BENCHMARKS.md, 2026-11-28); the tests of
/// `tests/gpu/general.rs` and `tests/gpu/erosion_contact.rs` turn it on there.
pub fn record_ahead(device_type: wgpu::DeviceType) -> bool {
    device_type != wgpu::DeviceType::Cpu
}

/// A batch of steps recorded ahead of its submission.
#[derive(Debug)]
pub(super) struct RecordedAhead {
    steps: u32,
    commands: wgpu::CommandBuffer,
}

/// How the batches recorded ahead were used, for tests and the bench.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct AheadCounts {
    /// Batches recorded ahead and submitted.
    pub used: u64,
    /// Batches recorded ahead and dropped (another step count, or the buffers changed).
    pub dropped: u64,
}

impl GpuSolver {
    /// Whether each batch is recorded while the device runs the one before (the default on
    /// GPUs, [`record_ahead`]), or after its readback; the same results either way. Turning it
    /// off drops a batch recorded ahead.
    pub fn set_record_ahead(&mut self, on: bool) {
        self.record_ahead = on;
        if !on {
            self.drop_recorded_ahead();
        }
    }

    /// How the batches recorded ahead were used so far.
    pub fn recorded_ahead(&self) -> AheadCounts {
        self.ahead
    }

    /// Times the contact search switched between its per-item kernels and one workgroup
    /// ([`crate::gpu::contact::SearchSwitch`]) so far; 0 without contact or a switch.
    pub fn search_switches(&self) -> u64 {
        self.state
            .contact
            .as_ref()
            .map_or(0, |c| c.search_switches())
    }

    /// Drops the batch recorded ahead, if any: called wherever the host changes a buffer or bind
    /// group that the recorded commands name, or the commands a step records.
    pub(super) fn drop_recorded_ahead(&mut self) {
        if self.prepared.take().is_some() {
            self.ahead.dropped += 1;
        }
    }

    /// History rows a batch of `steps` steps is expected to write (at most [`SPEC_ROWS`]): one
    /// per history time it may reach (with half the batch again of slack), the first step's and
    /// the end's.
    fn expected_rows(&self, steps: u32) -> u32 {
        let s = &self.schedule;
        let t = self.time_of(&self.ctrl);
        let reach = t + 1.5 * steps as f64 * self.dt_estimate;
        let mut n = ((reach / s.history_interval).floor() - (t / s.history_interval).floor())
            .clamp(0.0, SPEC_ROWS as f64) as u32;
        if self.ctrl.step == 0 {
            n += 1;
        }
        if reach >= s.end_time {
            n += 1;
        }
        n.min(steps).min(SPEC_ROWS)
    }

    /// `steps` steps recorded in one compute pass (the host's time in
    /// [`crate::step::Counters::record_seconds`]).
    fn record_steps(&mut self, steps: u32) -> wgpu::CommandBuffer {
        let t0 = Instant::now();
        let commands = self
            .encode_pass("steps", |pass| {
                for _ in 0..steps {
                    self.state.record_step(&self.kernels, pass);
                }
            })
            .finish();
        self.counters.record_seconds += t0.elapsed().as_secs_f64();
        commands
    }

    /// Submits `steps` steps (the batch recorded ahead where it has as many, else recorded now),
    /// with a copy of the control block and history into the readback buffer at the end; then,
    /// with recording ahead on and the run not over, records the next batch of as many steps.
    pub fn submit(&mut self, steps: u32) {
        self.batch_start = self.ctrl.step;
        let commands = match self.prepared.take() {
            Some(p) if p.steps == steps => {
                self.ahead.used += 1;
                p.commands
            }
            other => {
                if other.is_some() {
                    self.ahead.dropped += 1;
                }
                self.record_steps(steps)
            }
        };
        let mut copies = self
            .ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("readback copies"),
            });
        self.readback_copies(&mut copies, steps);
        self.ctx.queue.submit([commands, copies.finish()]);
        self.counters.submissions += 1;
        if self.record_ahead && !self.finished {
            let commands = self.record_steps(steps);
            self.prepared = Some(RecordedAhead { steps, commands });
        }
    }

    /// A command encoder with one compute pass labelled `label`, recorded by `record`.
    pub(super) fn encode_pass(
        &self,
        label: &str,
        record: impl FnOnce(&mut wgpu::ComputePass<'_>),
    ) -> wgpu::CommandEncoder {
        let mut enc = self
            .ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(label) });
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some(label),
                timestamp_writes: None,
            });
            record(&mut pass);
        }
        enc
    }

    /// The copies that end a submission of `steps` steps: the control block, the history rows
    /// and the contact counters into the readback buffers.
    fn readback_copies(&mut self, enc: &mut wgpu::CommandEncoder, steps: u32) {
        enc.copy_buffer_to_buffer(
            &self.state.ctrl,
            0,
            &self.readback,
            0,
            std::mem::size_of::<Control>() as u64,
        );
        self.spec_rows = self.expected_rows(steps);
        self.copy_rows(enc, self.spec_rows as usize);
        if let Some(c) = &self.state.contact {
            enc.copy_buffer_to_buffer(
                &c.ctl,
                crate::gpu::contact::PARAMS_SIZE,
                &self.readback,
                self.counters_at,
                std::mem::size_of::<ContactCounters>() as u64,
            );
        }
    }

    /// Ends a submission of `steps` steps recorded into `enc` (the bench's profile): the
    /// readback copies, then submits.
    pub(super) fn finish_submission(&mut self, mut enc: wgpu::CommandEncoder, steps: u32) {
        self.readback_copies(&mut enc, steps);
        self.ctx.queue.submit([enc.finish()]);
        self.counters.submissions += 1;
    }
}
