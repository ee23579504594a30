//! The GPU solver: records batches of steps per submission and reads back only the control block
//! and the history rows the GPU wrote, plus the nodal state at snapshot times.

use std::sync::Arc;
use std::time::Instant;

use crate::contact::ContactSample;
use crate::element::plastic::PlasticState;
use crate::error::{Error, Result};
use crate::model::Model;
use crate::plan::{Plan, Stage};
use crate::step::cpu::CpuSolver;
use crate::step::{Counters, Event, Failure, Sample, Schedule, Snapshot, Solver};

use super::contact::{ContactCounters, ContactOptions, STATE_SEARCH_GROW};
use super::context::GpuContext;
use super::kernels::{Features, Kernels};
use super::layout::*;
use super::state::{GpuState, MAX_BATCH};

/// One 2-vector per node.
pub type NodalField = Vec<[f64; 2]>;

/// Fewest steps recorded per submission (the most: [`MAX_BATCH`]).
pub const MIN_BATCH: u32 = 32;

/// Explicit central-difference integration on the GPU (f32).
#[derive(Debug)]
pub struct GpuSolver {
    ctx: Arc<GpuContext>,
    kernels: Kernels,
    state: GpuState,
    schedule: Schedule,
    names: Names,
    readback: wgpu::Buffer,
    snap_readback: Option<wgpu::Buffer>,
    ctrl: Control,
    rows_read: u32,
    dt_estimate: f64,
    counters: Counters,
    finished: bool,
    /// Offset of the contact counters in `readback`.
    counters_at: u64,
    /// Staging buffer of the new history rows: `n` rows copied at a time, the main rows packed
    /// from 0 and the contact rows right after them ([`GpuSolver::row_bytes`]`(n)` in all), so
    /// that a readback maps only the prefix it needs. Sized for a full history ring (a batch
    /// that wrote more rows than were copied with it), which can be hundreds of MB with many
    /// bodies: mapping it whole at every readback cost 0.2 s a batch on the 10^4-disk pile.
    rows_readback: wgpu::Buffer,
    /// Rows from `rows_read` on copied with the last submission (most batches write one).
    spec_rows: u32,
}

/// History rows copied with each submission, so that the usual batch (one sample) needs one
/// round trip; more rows are read in a second one.
const SPEC_ROWS: u32 = 4;

/// What failure messages need of the model.
#[derive(Debug, Clone)]
struct Names {
    bodies: Vec<(String, std::ops::Range<usize>, std::ops::Range<usize>)>,
    nodes: usize,
    /// What sets the penalty springs' step, if any.
    penalty: Option<String>,
}

impl Names {
    fn element(&self, e: usize) -> String {
        match self.bodies.iter().find(|b| b.2.contains(&e)) {
            Some(b) => format!(
                "element {e} (body {:?}, local element {})",
                b.0,
                e - b.2.start
            ),
            None => format!("element {e}"),
        }
    }

    fn node(&self, i: usize) -> String {
        match self.bodies.iter().find(|b| b.1.contains(&i)) {
            Some(b) => format!("node {i} (body {:?}, local node {})", b.0, i - b.1.start),
            None => format!("node {i}"),
        }
    }
}

impl GpuSolver {
    /// Uploads `model` to the device of `ctx` and compiles the kernels its plan needs.
    ///
    /// # Errors
    /// [`Error::Gpu`] when the model does not fit.
    pub fn new(
        ctx: Arc<GpuContext>,
        model: &Model,
        plan: &Plan,
        schedule: Schedule,
    ) -> Result<Self> {
        Self::with_reductions(ctx, model, plan, schedule, None)
    }

    /// As [`GpuSolver::new`], choosing whether the control workgroup reduces directly (`Some(true)`)
    /// or after the first-level reduction kernels (`Some(false)`); `None` decides by adapter and size.
    ///
    /// # Errors
    /// [`Error::Gpu`] when the model does not fit.
    pub fn with_reductions(
        ctx: Arc<GpuContext>,
        model: &Model,
        plan: &Plan,
        schedule: Schedule,
        fused: Option<bool>,
    ) -> Result<Self> {
        Self::with_options(ctx, model, plan, schedule, fused, ContactOptions::default())
    }

    /// As [`GpuSolver::with_reductions`], also choosing the contact stage's options (solve path,
    /// initial candidate capacity, one-workgroup size; see [`ContactOptions`]).
    ///
    /// # Errors
    /// [`Error::Gpu`] when the model does not fit, or `contact.group` is not a power of two
    /// from 8 to 256.
    pub fn with_options(
        ctx: Arc<GpuContext>,
        model: &Model,
        plan: &Plan,
        schedule: Schedule,
        fused: Option<bool>,
        contact: ContactOptions,
    ) -> Result<Self> {
        let cpu_adapter = ctx.info.device_type == wgpu::DeviceType::Cpu;
        let any = |f: &dyn Fn(&crate::model::BodyModel) -> bool| model.bodies.iter().any(f);
        use crate::scene::{ContactMethod, Formulation, HourglassForm, MaterialModel};
        let features = Features {
            dissipation: plan.has_dissipation(),
            fields: plan.has(Stage::Fields),
            loads: plan.has(Stage::Pressure)
                || plan.has(Stage::MassDamping)
                || plan.has(Stage::Gravity),
            plastic: model.has_plasticity(),
            axisymmetric: any(&|b| b.params.formulation == Formulation::Axisymmetric),
            linear_elastic: any(&|b| b.params.model == MaterialModel::LinearElastic),
            neo_hookean: any(&|b| b.params.model == MaterialModel::NeoHookean),
            plane_stress: any(&|b| b.params.formulation == Formulation::PlaneStress),
            hourglass_stiffness: any(&|b| b.params.hourglass == HourglassForm::Stiffness),
            contact_springs: model
                .contacts
                .iter()
                .any(|c| c.method != ContactMethod::Lagrange)
                || model
                    .walls
                    .iter()
                    .any(|w| w.method != ContactMethod::Lagrange),
            contact_friction: model.contacts.iter().any(|c| c.friction > 0.0)
                || model.walls.iter().any(|w| w.friction > 0.0),
            reduce_group: if cpu_adapter { 64 } else { 256 },
            contact_group: contact
                .group
                .unwrap_or_else(|| super::contact::one_group(ctx.info.device_type)),
        };
        if !(8..=256).contains(&features.contact_group) || !features.contact_group.is_power_of_two()
        {
            return Err(Error::Gpu(format!(
                "contact group of {} threads: a power of two from 8 to 256",
                features.contact_group
            )));
        }
        let device = &ctx.device;
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let kernels = Kernels::new(
            device,
            features,
            plan.has(Stage::VelocityBoundaries),
            plan.has(Stage::Contact),
            plan.has(Stage::Pressure),
        );
        let state = GpuState::new(
            device,
            &kernels,
            model,
            plan,
            &schedule,
            fused,
            ctx.info.device_type,
            contact,
        );
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(Error::Gpu(format!(
                "kernel or buffer setup rejected by {}: {e}",
                ctx.adapter_name()
            )));
        }
        let mut state = state?;
        let row_cap = state.params.row_capacity;
        let history_bytes = 4 * (row_cap as u64 * state.params.row_stride as u64);
        let contact_row_bytes = state
            .contact
            .as_ref()
            .map_or(0, |c| 4 * (row_cap as u64 * c.params.hist_stride as u64));
        let counters_at = 256;
        let rows_readback = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("rows_readback"),
            size: history_bytes + contact_row_bytes,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        state
            .allocated
            .push(("rows_readback", rows_readback.size()));
        let counters_bytes = if state.contact.is_some() {
            std::mem::size_of::<ContactCounters>() as u64
        } else {
            0
        };
        let readback = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size: counters_at + counters_bytes,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        state.allocated.push(("readback", readback.size()));
        let nn = model.node_count() as u64;
        let snap_readback = features.fields.then(|| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("snapshot_readback"),
                size: 8 * nn + 8 * nn + 16 * nn,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        });
        if let Some(b) = &snap_readback {
            state.allocated.push(("snapshot_readback", b.size()));
        }
        // First estimate of the step, for batch sizes only.
        let cpu = CpuSolver::new(model.clone(), plan.clone(), schedule);
        let dt_estimate = schedule
            .time_step
            .unwrap_or(schedule.time_step_scale * cpu.stable_step().0);
        let names = Names {
            bodies: model
                .bodies
                .iter()
                .map(|b| (b.name.clone(), b.nodes.clone(), b.elements.clone()))
                .collect(),
            nodes: model.node_count(),
            penalty: state
                .contact
                .as_ref()
                .and_then(|c| c.penalty_step())
                .map(|(_, w)| w.to_string()),
        };
        Ok(Self {
            ctx,
            kernels,
            state,
            schedule,
            names,
            readback,
            snap_readback,
            ctrl: Control::default(),
            rows_read: 0,
            dt_estimate,
            counters: Counters::default(),
            finished: false,
            counters_at,
            rows_readback,
            spec_rows: 0,
        })
    }

    /// The device-side state (buffers allocated for this scene).
    pub fn state(&self) -> &GpuState {
        &self.state
    }

    pub(crate) fn state_mut(&mut self) -> &mut GpuState {
        &mut self.state
    }

    /// The host's copy of the control block, rows read, step estimate, counters and whether the
    /// run ended (for checkpoints).
    pub(crate) fn host_state(&self) -> (Control, u32, f64, Counters, bool) {
        (
            self.ctrl,
            self.rows_read,
            self.dt_estimate,
            self.counters,
            self.finished,
        )
    }

    /// Sets what [`GpuSolver::host_state`] returns (restoring a checkpoint).
    pub(crate) fn set_host_state(
        &mut self,
        ctrl: Control,
        rows_read: u32,
        dt_estimate: f64,
        counters: Counters,
        finished: bool,
    ) {
        self.ctrl = ctrl;
        self.rows_read = rows_read;
        self.dt_estimate = dt_estimate;
        self.counters = counters;
        self.finished = finished;
    }

    /// Gives the contact candidate buffer room for `cap` candidates, if it has not (restoring a
    /// checkpoint of a run whose buffer grew).
    pub(crate) fn resize_contact_candidates(&mut self, cap: u32) -> Result<()> {
        let device = &self.ctx.device;
        if let (Some(c), Some(k)) = (self.state.contact.as_mut(), self.kernels.contact.as_ref()) {
            if c.params.cand_capacity != cap {
                c.resize_candidates(device, k, cap);
            }
        }
        Ok(())
    }

    /// The compiled kernels.
    pub fn kernels(&self) -> &Kernels {
        &self.kernels
    }

    /// The context.
    pub fn context(&self) -> &Arc<GpuContext> {
        &self.ctx
    }

    fn time_of(&self, c: &Control) -> f64 {
        seconds(c.t_lo, c.t_hi, self.schedule.end_time)
    }

    /// Steps to record in the next submission: up to the next sample, snapshot or end.
    fn batch(&self) -> u32 {
        let t = self.time_of(&self.ctrl);
        let s = &self.schedule;
        let mut next = s.end_time;
        let k = (t / s.history_interval).floor() + 1.0;
        next = next.min(k * s.history_interval);
        if let Some(fi) = s.field_interval {
            next = next.min(((t / fi).floor() + 1.0) * fi);
        }
        let steps = ((next - t) / self.dt_estimate).ceil() + 2.0;
        (steps.max(0.0) as u32).clamp(MIN_BATCH, MAX_BATCH)
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

    /// Records `steps` steps in one submission, with a copy of the control block and history
    /// into the readback buffer at the end.
    pub fn submit(&mut self, steps: u32) {
        let device = &self.ctx.device;
        let mut enc = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("steps"),
        });
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("steps"),
                timestamp_writes: None,
            });
            for _ in 0..steps {
                self.state.record_step(&self.kernels, &mut pass);
            }
        }
        self.finish_submission(enc, steps);
    }

    /// Ends a submission of `steps` steps recorded into `enc`: the copies of the control block,
    /// the history rows and the contact counters into the readback buffers, then submits.
    fn finish_submission(&mut self, mut enc: wgpu::CommandEncoder, steps: u32) {
        enc.copy_buffer_to_buffer(
            &self.state.ctrl,
            0,
            &self.readback,
            0,
            std::mem::size_of::<Control>() as u64,
        );
        self.spec_rows = self.expected_rows(steps);
        self.copy_rows(&mut enc, self.spec_rows as usize);
        if let Some(c) = &self.state.contact {
            enc.copy_buffer_to_buffer(
                &c.ctl,
                super::contact::PARAMS_SIZE,
                &self.readback,
                self.counters_at,
                std::mem::size_of::<ContactCounters>() as u64,
            );
        }
        self.ctx.queue.submit([enc.finish()]);
        self.counters.submissions += 1;
    }

    fn map_read(&mut self, buffer: &wgpu::Buffer) -> Result<Vec<u8>> {
        self.map_prefix(buffer, buffer.size())
    }

    /// Maps and copies the first `len` bytes of `buffer` (counted in the bytes read back).
    fn map_prefix(&mut self, buffer: &wgpu::Buffer, len: u64) -> Result<Vec<u8>> {
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
    fn read(&mut self, events: &mut Vec<Event>) -> Result<()> {
        let readback = self.readback.clone();
        let (bytes, spec) = self.map_with_rows(&readback)?;
        self.counters.readbacks += 1;
        let ctrl: Control = bytemuck::pod_read_unaligned(&bytes[..std::mem::size_of::<Control>()]);
        if let Some(c) = self.state.contact.as_mut() {
            let at = self.counters_at as usize;
            c.counters = bytemuck::pod_read_unaligned(
                &bytes[at..at + std::mem::size_of::<ContactCounters>()],
            );
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
        let nb = self.names.bodies.len();
        // The plastic work's word before the bodies' (plastic scenes).
        let pw = self.state.params.plastic as usize;
        let mut row_events = Vec::new();
        let first_row = self.rows_read;
        while self.rows_read < ctrl.rows {
            let j = (self.rows_read - first_row) as usize;
            let base = j * stride;
            let w = |i: usize| -> f32 {
                bytemuck::pod_read_unaligned(&hist[4 * (base + i)..4 * (base + i) + 4])
            };
            let sample = Sample {
                time: seconds(w(0).to_bits(), w(1).to_bits(), self.schedule.end_time),
                step: w(2).to_bits() as u64,
                dt: w(3) as f64,
                kinetic: w(4) as f64,
                internal: w(5) as f64,
                hourglass: w(6) as f64,
                viscous: w(7) as f64,
                plastic: if pw > 0 { w(9) as f64 } else { 0.0 },
                external: w(8) as f64,
                contact: 0.0,
                friction: 0.0,
                contacts: Vec::new(),
                body_velocity: (0..nb)
                    .map(|b| [w(9 + pw + 2 * b) as f64, w(10 + pw + 2 * b) as f64])
                    .collect(),
            };
            let mut sample = sample;
            if let Some(c) = &self.state.contact {
                let cs = c.params.hist_stride as usize;
                let cb = j * cs;
                let r = |i: usize| -> f64 {
                    let x: f32 =
                        bytemuck::pod_read_unaligned(&chist[4 * (cb + i)..4 * (cb + i) + 4]);
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
            row_events.push(Event::Sample(sample));
            self.rows_read += 1;
        }
        if ctrl.dt_next > 0.0 {
            self.dt_estimate = ctrl.dt_next as f64;
        }
        self.ctrl = ctrl;
        if ctrl.state == STATE_SEARCH_GROW {
            self.contact_grow()?;
            events.extend(row_events);
            return Ok(());
        }
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
                let i = ctrl.fail_index as usize;
                let message = match ctrl.fail_code {
                    1 => format!(
                        "{} inverted: a corner Jacobian is not positive; reduce time_step_scale, \
                         refine the mesh or raise the hourglass coefficient",
                        self.names.element(i)
                    ),
                    2 => format!(
                        "velocity of {} is not finite: the run went unstable",
                        if i < self.names.nodes { self.names.node(i) } else { format!("node {i}") }
                    ),
                    3 => format!(
                        "the fixed time_step {:e} exceeds the stable step {:e} of {}{}",
                        self.schedule.time_step.unwrap_or(0.0),
                        ctrl.fail_value,
                        self.names.element(i),
                        self.names.penalty.as_deref().map_or(String::new(), |w| format!(
                            " and the penalty springs of {w}"
                        ))
                    ),
                    4 => format!(
                        "the stable step collapsed to {:e} (first step {:e}) at {}",
                        ctrl.fail_value,
                        ctrl.dt_first,
                        self.names.element(i)
                    ),
                    _ => format!(
                        "stable step is {:e} at {}: the element is degenerate or its state is not finite",
                        ctrl.fail_value,
                        self.names.element(i)
                    ),
                };
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

    /// Records copies of the `n` history rows from `rows_read` on (the main rows packed from 0,
    /// then the contact rows packed right after them) into the rows staging buffer.
    fn copy_rows(&self, enc: &mut wgpu::CommandEncoder, n: usize) {
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

    /// A contact search stopped the step because a contact buffer is too small: grows it (from
    /// the counters just read back) and resumes the step from its contact stage.
    fn contact_grow(&mut self) -> Result<()> {
        let device = &self.ctx.device;
        let (Some(c), Some(k)) = (self.state.contact.as_mut(), self.kernels.contact.as_ref())
        else {
            return Err(Error::Gpu(
                "contact grow requested without contact buffers".into(),
            ));
        };
        c.grow(device, &self.ctx.queue, k)?;
        self.ctx.queue.write_buffer(
            &self.state.ctrl,
            CONTROL_STATE_OFFSET,
            bytemuck::bytes_of(&STATE_RUNNING),
        );
        let mut enc = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("resumed step"),
        });
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("resumed step"),
                timestamp_writes: None,
            });
            self.state.record_tail(&self.kernels, &mut pass);
        }
        self.ctx.queue.submit([enc.finish()]);
        self.counters.submissions += 1;
        Ok(())
    }

    fn read_snapshot(&mut self, step: u64, time: f64) -> Result<Snapshot> {
        let (Some(rb), Some(u_snap)) = (self.snap_readback.clone(), self.state.u_snap.clone())
        else {
            return Err(Error::Gpu(
                "snapshot requested without field buffers".into(),
            ));
        };
        let nn = self.names.nodes as u64;
        let mut enc = self
            .ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("snapshot"),
            });
        enc.copy_buffer_to_buffer(&u_snap, 0, &rb, 0, 8 * nn);
        enc.copy_buffer_to_buffer(&self.state.v_prev, 0, &rb, 8 * nn, 8 * nn);
        enc.copy_buffer_to_buffer(&self.state.nodes, 0, &rb, 16 * nn, 16 * nn);
        self.ctx.queue.submit([enc.finish()]);
        let bytes = self.map_read(&rb)?;
        self.counters.readbacks += 1;
        let f: &[f32] = bytemuck::cast_slice(&bytes);
        let n = nn as usize;
        let displacement = (0..n)
            .map(|i| [f[2 * i] as f64, f[2 * i + 1] as f64])
            .collect();
        let velocity = (0..n)
            .map(|i| {
                let vp = [f[2 * n + 2 * i], f[2 * n + 2 * i + 1]];
                let v = [f[4 * n + 4 * i + 2], f[4 * n + 4 * i + 3]];
                [0.5 * (vp[0] + v[0]) as f64, 0.5 * (vp[1] + v[1]) as f64]
            })
            .collect();
        let plastic = self.plastic_state()?;
        Ok(Snapshot {
            time,
            step,
            displacement,
            velocity,
            plastic,
        })
    }

    /// The plastic state of every element (empty without a plastic body): C_p^-1 = I + the
    /// stored deviation, and alpha.
    fn plastic_state(&mut self) -> Result<Vec<PlasticState>> {
        let Some(buf) = self.state.plastic.clone() else {
            return Ok(Vec::new());
        };
        let ne = self.state.params.n_elems as u64;
        let bytes = self.read_copies("plastic_readback", &[(&buf, 0, 32 * ne)])?;
        let f: &[f32] = bytemuck::cast_slice(&bytes);
        Ok((0..ne as usize)
            .map(|e| {
                let d = &f[8 * e..8 * e + 4];
                PlasticState {
                    cp_inv: [
                        1.0 + d[0] as f64,
                        1.0 + d[1] as f64,
                        d[2] as f64,
                        1.0 + d[3] as f64,
                    ],
                    alpha: f[8 * e + 4] as f64,
                }
            })
            .collect())
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

    /// Reads the current nodal displacements and half-step velocities (one extra readback).
    ///
    /// # Errors
    /// [`Error::Gpu`] when the device is lost.
    pub fn nodes(&mut self) -> Result<(NodalField, NodalField)> {
        let nn = self.names.nodes as u64;
        let nodes = self.state.nodes.clone();
        let bytes = self.read_copies("nodes_readback", &[(&nodes, 0, 16 * nn)])?;
        let f: &[f32] = bytemuck::cast_slice(&bytes);
        let n = nn as usize;
        Ok((
            (0..n)
                .map(|i| [f[4 * i] as f64, f[4 * i + 1] as f64])
                .collect(),
            (0..n)
                .map(|i| [f[4 * i + 2] as f64, f[4 * i + 3] as f64])
                .collect(),
        ))
    }

    /// Times a contact buffer grew (the candidates) or a colouring was enlarged during the run.
    pub fn contact_grows(&self) -> u32 {
        self.state.contact.as_ref().map_or(0, |c| c.grows)
    }

    /// Test hook: each slot's candidate segments from the last device search ([`crate::contact::Tables`]
    /// numbering), read back from the device (one extra readback).
    ///
    /// # Errors
    /// [`Error::Gpu`] when the scene has no contact or the device is lost.
    pub fn contact_candidates(&mut self) -> Result<Vec<Vec<u32>>> {
        let Some(c) = self.state.contact.as_ref() else {
            return Err(Error::Gpu("the scene has no contact".into()));
        };
        let p = c.params;
        let (Some(ws), Some(grow)) = (c.binding(13).cloned(), c.binding(14).cloned()) else {
            return Err(Error::Gpu("contact buffers missing".into()));
        };
        let n = p.n_slots as u64;
        let off_bytes = 4 * (n + 1);
        let cand_bytes = 4 * p.cand_capacity as u64;
        let bytes = self.read_copies(
            "candidates_readback",
            &[
                (&ws, 4 * p.o_coff as u64, off_bytes),
                (&grow, 0, cand_bytes),
            ],
        )?;
        let w: &[u32] = bytemuck::cast_slice(&bytes);
        let (off, cand) = w.split_at(n as usize + 1);
        Ok((0..n as usize)
            .map(|k| cand[off[k] as usize..off[k + 1] as usize].to_vec())
            .collect())
    }

    /// Test hook: the active slots of the last device search (those that can have a constraint
    /// until the next: a pass slot with candidates, a wall slot near its wall), in slot order
    /// ([`crate::contact::Tables`] numbering), read back from the device (one extra readback).
    ///
    /// # Errors
    /// [`Error::Gpu`] when the scene has no contact or the device is lost.
    pub fn contact_active_slots(&mut self) -> Result<Vec<u32>> {
        let Some(c) = self.state.contact.as_ref() else {
            return Err(Error::Gpu("the scene has no contact".into()));
        };
        let p = c.params;
        let Some(ws) = c.binding(13).cloned() else {
            return Err(Error::Gpu("contact buffers missing".into()));
        };
        let n = p.n_slots as u64;
        let bytes = self.read_copies(
            "active_readback",
            &[
                (&ws, 4 * (p.o_aoff as u64 + n), 4),
                (&ws, 4 * p.o_alist as u64, 4 * n.max(1)),
            ],
        )?;
        let w: &[u32] = bytemuck::cast_slice(&bytes);
        let count = (w[0] as usize).min(n as usize);
        Ok(w[1..1 + count].to_vec())
    }

    /// Kernel test hook: uploads displacements `u` and half-step velocities `v`, runs the element
    /// stage once, and returns each element's nodal forces and stable step.
    ///
    /// # Errors
    /// [`Error::Gpu`] when the device is lost.
    #[allow(clippy::type_complexity)]
    pub fn element_stage(
        &mut self,
        u: &[[f64; 2]],
        v: &[[f64; 2]],
    ) -> Result<(Vec<[[f64; 2]; 4]>, Vec<f64>)> {
        let data: Vec<[f32; 4]> = u
            .iter()
            .zip(v)
            .map(|(u, v)| [u[0] as f32, u[1] as f32, v[0] as f32, v[1] as f32])
            .collect();
        self.ctx
            .queue
            .write_buffer(&self.state.nodes, 0, bytemuck::cast_slice(&data));
        let ne = self.state.params.n_elems as u64;
        let mut enc = self
            .ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("element"),
            });
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("element"),
                timestamp_writes: None,
            });
            self.state.record_element(&self.kernels, &mut pass);
        }
        self.ctx.queue.submit([enc.finish()]);
        let (force, dt) = (self.state.elem_force.clone(), self.state.elem_dt.clone());
        let bytes = self.read_copies(
            "element_readback",
            &[(&force, 0, 32 * ne), (&dt, 0, 4 * ne)],
        )?;
        let f: &[f32] = bytemuck::cast_slice(&bytes);
        let n = ne as usize;
        let forces = (0..n)
            .map(|e| {
                std::array::from_fn(|a| [f[8 * e + 2 * a] as f64, f[8 * e + 2 * a + 1] as f64])
            })
            .collect();
        let dt = (0..n).map(|e| f[8 * n + e] as f64).collect();
        Ok((forces, dt))
    }

    /// Runs `steps` steps of one stage alone (`"element"`, `"node"`, `"control"`, or a part of
    /// the contact stage: `"prep"`, `"search"`, `"narrow"`, `"solve"`, `"report"`), of the bare
    /// loop (`"bare"`: the element and node stages only, at the last step size) or whole steps
    /// (`"step"`) in one submission, and returns the wall seconds, for the bench's per-stage
    /// shares and its full / bare ratio. Whole steps this way do not stop for contact searches:
    /// time contact scenes with [`GpuSolver::run_steps`].
    ///
    /// # Errors
    /// [`Error::Gpu`] when the device is lost.
    pub fn time_stage(&mut self, stage: &str, steps: u32) -> Result<f64> {
        let t0 = Instant::now();
        let mut enc = self
            .ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(stage) });
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some(stage),
                timestamp_writes: None,
            });
            for _ in 0..steps {
                match stage {
                    "element" => self.state.record_element(&self.kernels, &mut pass),
                    "node" => self.state.record_node(&self.kernels, &mut pass),
                    "control" => self.state.record_control(&self.kernels, &mut pass),
                    "bare" => {
                        self.state.record_element(&self.kernels, &mut pass);
                        self.state.record_node(&self.kernels, &mut pass);
                    }
                    "prep" | "search" | "narrow" | "solve" | "report" => {
                        if let (Some(k), Some(c)) = (&self.kernels.contact, &self.state.contact) {
                            c.record_parts(k, &mut pass, contact_part(stage));
                        }
                    }
                    _ => self.state.record_step(&self.kernels, &mut pass),
                }
            }
        }
        self.ctx.queue.submit([enc.finish()]);
        self.ctx
            .device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| Error::Gpu(format!("device lost while waiting: {e}")))?;
        Ok(t0.elapsed().as_secs_f64())
    }
}

impl GpuSolver {
    /// Takes about `steps` steps (the step a contact search interrupted counts once), in
    /// submissions of at most [`MAX_BATCH`] steps with the contact searches the kernels ask for,
    /// discarding outputs (for benchmarks), and returns the steps taken: fewer when the run ended
    /// or failed.
    ///
    /// # Errors
    /// [`Error::Gpu`] when the device is lost.
    pub fn run_steps(&mut self, steps: u64) -> Result<u64> {
        let start = self.ctrl.step as u64;
        let mut events = Vec::new();
        while !self.finished {
            let done = (self.ctrl.step as u64).saturating_sub(start);
            if done >= steps {
                break;
            }
            let n = (steps - done).min(MAX_BATCH as u64) as u32;
            self.submit(n);
            self.read(&mut events)?;
            events.clear();
        }
        Ok((self.ctrl.step as u64).saturating_sub(start))
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
        use super::contact::{PART_NARROW, PART_PREP, PART_REPORT, PART_SEARCH, PART_SOLVE};
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
        let start = self.ctrl.step as u64;
        let mut events = Vec::new();
        while !self.finished {
            let done = (self.ctrl.step as u64).saturating_sub(start);
            if done >= steps {
                break;
            }
            let n = (steps - done).min(PROFILE_BATCH as u64) as u32;
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
                    let contact = |mask: u32, pass: &mut wgpu::ComputePass<'_>| {
                        if let (Some(k), Some(c)) = (&self.kernels.contact, &self.state.contact) {
                            c.record_parts(k, pass, mask);
                        }
                    };
                    match p {
                        0 => self.state.record_forces(&self.kernels, &mut pass),
                        1 => self.state.record_update(&self.kernels, &mut pass),
                        2 => contact(PART_PREP, &mut pass),
                        3 => contact(PART_SEARCH, &mut pass),
                        4 => contact(PART_NARROW, &mut pass),
                        5 => contact(PART_SOLVE, &mut pass),
                        6 => contact(PART_REPORT, &mut pass),
                        _ => self.state.record_end(&self.kernels, &mut pass),
                    }
                }
            }
            let used = 2 * np as u32 * n;
            enc.resolve_query_set(&queries, 0..used, &resolve, 0);
            enc.copy_buffer_to_buffer(&resolve, 0, &staging, 0, 8 * used as u64);
            self.finish_submission(enc, n);
            self.read(&mut events)?;
            events.clear();
            let stamps: Vec<u64> =
                bytemuck::pod_collect_to_vec(&self.map_prefix(&staging, 8 * used as u64)?);
            // Timing data, not results: kept out of the bytes read back.
            self.counters.bytes_read_back -= 8 * used as u64;
            for i in 0..n as usize {
                for (p, t) in seconds.iter_mut().enumerate() {
                    let q = 2 * (i * np + p);
                    *t += stamps[q + 1].saturating_sub(stamps[q]) as f64 * period;
                }
            }
        }
        let taken = (self.ctrl.step as u64).saturating_sub(start);
        for t in &mut seconds {
            *t /= taken.max(1) as f64;
        }
        Ok(Some((taken, seconds)))
    }
}

impl Solver for GpuSolver {
    fn save_state(&mut self) -> Result<Vec<u8>> {
        GpuSolver::save_state(self)
    }

    fn restore_state(&mut self, state: &[u8]) -> Result<()> {
        GpuSolver::restore_state(self, state)
    }

    fn advance(&mut self, events: &mut Vec<Event>) -> Result<()> {
        let start = events.len();
        let t0 = Instant::now();
        while !self.finished && events.len() == start {
            let steps = self.batch();
            self.submit(steps);
            self.read(events)?;
            if t0.elapsed().as_secs_f64() > crate::step::ADVANCE_SECONDS {
                break;
            }
        }
        Ok(())
    }

    fn steps(&self) -> u64 {
        self.ctrl.step as u64
    }

    fn time(&self) -> f64 {
        self.time_of(&self.ctrl)
    }

    fn dt_range(&self) -> (f64, f64) {
        (self.ctrl.dt_min as f64, self.ctrl.dt_max as f64)
    }

    fn backend(&self) -> &'static str {
        "gpu"
    }

    fn adapter(&self) -> String {
        self.ctx.adapter_name()
    }

    fn displacement_now(&mut self) -> Result<Vec<[f64; 2]>> {
        Ok(self.nodes()?.0)
    }

    fn plastic_now(&mut self) -> Result<Vec<PlasticState>> {
        self.plastic_state()
    }

    fn counters(&self) -> Counters {
        let mut out = self.counters;
        if let Some(c) = &self.state.contact {
            let k = c.counters;
            out.contact_searches = k.searches as u64;
            out.contact_sweeps_max = k.sweeps_max as u64;
            out.contact_unconverged = k.unconverged as u64;
            out.contact_penalty_bounded = k.bounded as u64;
            out.contact_sweeps_mean = if k.solve_steps > 0 {
                k.sweeps_total as f64 / k.solve_steps as f64
            } else {
                0.0
            };
        }
        out
    }
}

/// The contact-stage part mask of a [`GpuSolver::time_stage`] stage name.
fn contact_part(stage: &str) -> u32 {
    use super::contact::{PART_NARROW, PART_PREP, PART_REPORT, PART_SEARCH, PART_SOLVE};
    match stage {
        "prep" => PART_PREP,
        "search" => PART_SEARCH,
        "narrow" => PART_NARROW,
        "solve" => PART_SOLVE,
        _ => PART_REPORT,
    }
}
