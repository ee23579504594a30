//! Timing the GPU step for the bench: one stage alone or whole steps by wall time
//! ([`GpuSolver::time_stage`]), and each part of real steps between GPU timestamps
//! ([`GpuSolver::profile_steps`], where the adapter has timestamp queries), or whole batches of
//! steps between two ([`GpuSolver::profile_whole_steps`]).

use std::time::Instant;

use crate::error::{Error, Result};
use crate::gpu::contact::{PART_NARROW, PART_PREP, PART_REPORT, PART_SEARCH, PART_SOLVE};
use crate::gpu::state::MAX_BATCH;

use super::GpuSolver;

impl GpuSolver {
    /// Runs `steps` steps of one stage alone (`"element"`, `"node"`, `"control"`, or a part of
    /// the contact stage: `"prep"`, `"search"`, `"narrow"`, `"solve"`, `"report"`), of the bare
    /// loop (`"bare"`: the element and node stages only, at the last step size) or whole steps
    /// (`"step"`) in one submission, and returns the wall seconds from the submission to the
    /// device's end (the host's recording before it is not timed: a run records each batch
    /// while the device runs the one before), for the bench's per-stage shares and the bare
    /// loop. Whole steps this way do not stop for contact searches: time runs with
    /// [`GpuSolver::run_steps`].
    ///
    /// # Errors
    /// [`Error::Gpu`] when the device is lost.
    pub fn time_stage(&mut self, stage: &str, steps: u32) -> Result<f64> {
        let (state, kernels) = (&self.state, &self.kernels);
        let enc = self.encode_pass(stage, |pass| {
            for _ in 0..steps {
                match stage {
                    "element" => state.record_element(kernels, pass),
                    "node" => state.record_node(kernels, pass),
                    "control" => state.record_control(kernels, pass),
                    "bare" => {
                        state.record_element(kernels, pass);
                        state.record_node(kernels, pass);
                    }
                    "prep" | "search" | "narrow" | "solve" | "report" => {
                        if let (Some(k), Some(c)) = (&kernels.contact, &state.contact) {
                            c.record_parts(k, pass, contact_part(stage));
                        }
                    }
                    _ => state.record_step(kernels, pass),
                }
            }
        });
        let commands = enc.finish();
        let t0 = Instant::now();
        self.ctx.queue.submit([commands]);
        self.ctx
            .device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| Error::Gpu(format!("device lost while waiting: {e}")))?;
        Ok(t0.elapsed().as_secs_f64())
    }
}

/// The parts of a step that [`GpuSolver::profile_steps`] times, in step order.
pub const PROFILE_PARTS: [&str; 8] = [
    "forces",
    "update",
    "contact prep",
    "contact search",
    "contact narrow",
    "contact solve",
    "contact report",
    "end",
];

/// Steps per [`GpuSolver::profile_steps`] submission (two timestamps per part and step within
/// wgpu's 4096 queries per set).
const PROFILE_BATCH: u32 = 4096 / (2 * PROFILE_PARTS.len() as u32);

impl GpuSolver {
    /// Takes about `steps` real steps (as [`GpuSolver::run_steps`], outputs discarded) with each
    /// part of a step ([`PROFILE_PARTS`]: element forces and stable step, node update, the
    /// contact stage's five parts, sums and control) in its own compute pass between GPU
    /// timestamps, and returns the steps taken and each part's device seconds per step. `None`
    /// when the adapter has no timestamp queries.
    ///
    /// # Errors
    /// [`Error::Gpu`] when the device is lost.
    pub fn profile_steps(&mut self, steps: u64) -> Result<Option<(u64, Vec<f64>)>> {
        if !self.ctx.timestamps {
            return Ok(None);
        }
        let np = PROFILE_PARTS.len();
        let device = self.ctx.device.clone();
        let queries = device.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some("profile"),
            ty: wgpu::QueryType::Timestamp,
            count: 2 * np as u32 * PROFILE_BATCH,
        });
        let bytes = 8 * 2 * (np as u64) * PROFILE_BATCH as u64;
        let resolve = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("profile_resolve"),
            size: bytes,
            usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let staging = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("profile_staging"),
            size: bytes,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let period = self.ctx.queue.get_timestamp_period() as f64 * 1e-9;
        let mut seconds = vec![0.0; np];
        let taken = self.take_steps(steps, PROFILE_BATCH, |solver, n| {
            let mut enc = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("profile"),
            });
            for i in 0..n {
                for (p, _) in PROFILE_PARTS.iter().enumerate() {
                    let q = 2 * (i * np as u32 + p as u32);
                    let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                        label: Some(PROFILE_PARTS[p]),
                        timestamp_writes: Some(wgpu::ComputePassTimestampWrites {
                            query_set: &queries,
                            beginning_of_pass_write_index: Some(q),
                            end_of_pass_write_index: Some(q + 1),
                        }),
                    });
                    let (state, kernels) = (&solver.state, &solver.kernels);
                    let contact = |mask: u32, pass: &mut wgpu::ComputePass<'_>| {
                        if let (Some(k), Some(c)) = (&kernels.contact, &state.contact) {
                            c.record_parts(k, pass, mask);
                        }
                    };
                    match p {
                        0 => state.record_forces(kernels, &mut pass),
                        1 => state.record_update(kernels, &mut pass),
                        2 => contact(PART_PREP, &mut pass),
                        3 => contact(PART_SEARCH, &mut pass),
                        4 => contact(PART_NARROW, &mut pass),
                        5 => contact(PART_SOLVE, &mut pass),
                        6 => contact(PART_REPORT, &mut pass),
                        _ => state.record_end(kernels, &mut pass),
                    }
                }
            }
            let used = 2 * np as u32 * n;
            enc.resolve_query_set(&queries, 0..used, &resolve, 0);
            enc.copy_buffer_to_buffer(&resolve, 0, &staging, 0, 8 * used as u64);
            solver.finish_submission(enc, n);
            let stamps: Vec<u64> =
                bytemuck::pod_collect_to_vec(&solver.map_prefix(&staging, 8 * used as u64)?);
            // Timing data, not results: kept out of the bytes read back.
            solver.counters.bytes_read_back -= 8 * used as u64;
            for i in 0..n as usize {
                for (p, t) in seconds.iter_mut().enumerate() {
                    let q = 2 * (i * np + p);
                    *t += stamps[q + 1].saturating_sub(stamps[q]) as f64 * period;
                }
            }
            Ok(())
        })?;
        for t in &mut seconds {
            *t /= taken.max(1) as f64;
        }
        Ok(Some((taken, seconds)))
    }
}

impl GpuSolver {
    /// Takes about `steps` real steps (as [`GpuSolver::run_steps`], outputs discarded), each
    /// batch in one compute pass between two GPU timestamps, and returns the steps taken and the
    /// device seconds per step: the whole step as the device runs it, without the passes that
    /// [`GpuSolver::profile_steps`] puts between its parts, and without the host's time between
    /// batches. `None` when the adapter has no timestamp queries.
    ///
    /// # Errors
    /// [`Error::Gpu`] when the device is lost.
    pub fn profile_whole_steps(&mut self, steps: u64) -> Result<Option<(u64, f64)>> {
        if !self.ctx.timestamps {
            return Ok(None);
        }
        let device = self.ctx.device.clone();
        let queries = device.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some("profile_whole"),
            ty: wgpu::QueryType::Timestamp,
            count: 2,
        });
        let buffer = |label: &str, usage: wgpu::BufferUsages| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: 16,
                usage,
                mapped_at_creation: false,
            })
        };
        let resolve = buffer(
            "profile_whole_resolve",
            wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
        );
        let staging = buffer(
            "profile_whole_staging",
            wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        );
        let period = self.ctx.queue.get_timestamp_period() as f64 * 1e-9;
        let mut seconds = 0.0;
        let taken = self.take_steps(steps, MAX_BATCH, |solver, n| {
            let mut enc = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("profile_whole"),
            });
            {
                let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("steps"),
                    timestamp_writes: Some(wgpu::ComputePassTimestampWrites {
                        query_set: &queries,
                        beginning_of_pass_write_index: Some(0),
                        end_of_pass_write_index: Some(1),
                    }),
                });
                for _ in 0..n {
                    solver.state.record_step(&solver.kernels, &mut pass);
                }
            }
            enc.resolve_query_set(&queries, 0..2, &resolve, 0);
            enc.copy_buffer_to_buffer(&resolve, 0, &staging, 0, 16);
            solver.finish_submission(enc, n);
            let stamps: Vec<u64> = bytemuck::pod_collect_to_vec(&solver.map_prefix(&staging, 16)?);
            // Timing data, not results: kept out of the bytes read back.
            solver.counters.bytes_read_back -= 16;
            seconds += stamps[1].saturating_sub(stamps[0]) as f64 * period;
            Ok(())
        })?;
        Ok(Some((taken, seconds / taken.max(1) as f64)))
    }
}

/// The contact-stage part mask of a [`GpuSolver::time_stage`] stage name.
fn contact_part(stage: &str) -> u32 {
    match stage {
        "prep" => PART_PREP,
        "search" => PART_SEARCH,
        "narrow" => PART_NARROW,
        "solve" => PART_SOLVE,
        _ => PART_REPORT,
    }
}
