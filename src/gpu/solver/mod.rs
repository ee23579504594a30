//! The GPU solver ([`GpuSolver`], the [`Solver`] of the GPU backend; its CPU twin is
//! [`crate::step::cpu::CpuSolver`]): built from a model and its plan (the kernels its features
//! need, the device state), it records batches of steps per submission and reads back only the
//! control block and the history rows the GPU wrote, plus the nodal state at snapshot times.
//! By file: this one builds the solver and submits the batches; `readback.rs` reads each batch's
//! results back and decodes them, `snapshot.rs` the nodal state, `failure.rs` the messages of a
//! stopped run, `profile.rs` times stages and steps for the bench, `hooks.rs` reads the contact
//! search for tests; checkpoints are in `src/gpu/checkpoint.rs`.

mod failure;
mod hooks;
mod profile;
mod readback;
mod snapshot;
mod submit;

pub use hooks::LastColouring;
pub use profile::PROFILE_PARTS;
pub use submit::{record_ahead, AheadCounts};

use std::sync::Arc;
use std::time::Instant;

use crate::element::plastic::PlasticState;
use crate::error::{Error, Result};
use crate::model::Model;
use crate::plan::{Plan, Stage};
use crate::step::cpu::CpuSolver;
use crate::step::{Counters, Event, Schedule, Solver};

use super::contact::{ContactCounters, ContactOptions};
use super::context::{GpuContext, KernelKey};
use super::element::{ERODED_INVERTED, ERODED_SMALL_STEP};
use super::kernels::{Features, Kernels};
use super::layout::*;
use super::state::{GpuState, MAX_BATCH};
use failure::Names;
use submit::RecordedAhead;

/// One 2-vector per node.
pub type NodalField = Vec<[f64; 2]>;

/// Fewest steps recorded per submission (the most: [`MAX_BATCH`]).
pub const MIN_BATCH: u32 = 32;

/// Explicit central-difference integration on the GPU (f32).
#[derive(Debug)]
pub struct GpuSolver {
    ctx: Arc<GpuContext>,
    kernels: Arc<Kernels>,
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
    /// The step at which the last submission began.
    batch_start: u32,
    /// Per element whether it has eroded, as the host last read it (a scene with failure and
    /// contact; empty: not read yet, or a checkpoint restored since), brought up to date at each
    /// follow from the list of the elements eroded since the one before.
    eroded: Vec<bool>,
    /// The most steps a submission records while elements erode in a scene with contact: each
    /// erosion stops the submission, and the steps recorded after the stop still cost their
    /// (empty) dispatches, so the cap is twice the steps before the last stop, doubled after
    /// each submission without one, up to [`MAX_BATCH`].
    erosion_cap: u32,
    /// Whether the next batch is recorded while the device runs this one (`submit.rs`).
    record_ahead: bool,
    /// The batch recorded ahead, if any.
    prepared: Option<RecordedAhead>,
    /// How the batches recorded ahead were used.
    ahead: AheadCounts,
}

/// History rows copied with each submission, so that the usual batch (one sample) needs one
/// round trip; more rows are read in a second one.
const SPEC_ROWS: u32 = 4;

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
        let contact_group = contact
            .group
            .unwrap_or_else(|| super::contact::one_group(ctx.info.device_type));
        let contact_cap = super::contact::local_constraints(
            ctx.device.limits().max_compute_workgroup_storage_size,
            contact_group,
        );
        let contact_cap = contact
            .compact_local
            .map_or(contact_cap, |c| c.min(contact_cap));
        let contact_parallel_colouring = contact
            .parallel_colouring
            .unwrap_or_else(|| super::contact::parallel_colouring(ctx.info.device_type));
        let contact_pair_blocks = contact
            .pair_blocks
            .unwrap_or_else(|| super::contact::pair_blocks(ctx.info.device_type));
        let contact_local_sweeps = contact
            .local_sweeps
            .unwrap_or_else(|| super::contact::local_sweeps(ctx.info.device_type));
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
            failure: plan.has(Stage::Failure),
            thermal: any(&|b| b.params.has_thermal()),
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
            control_group: if cpu_adapter { 8 } else { 256 },
            contact_group,
            contact_cap,
            contact_parallel_colouring,
            contact_pair_blocks,
            contact_local_sweeps,
        };
        let limits = ctx.device.limits();
        let most = limits
            .max_compute_invocations_per_workgroup
            .min(limits.max_compute_workgroup_size_x)
            .min(1024);
        if !(8..=most).contains(&features.contact_group)
            || !features.contact_group.is_power_of_two()
        {
            return Err(Error::Gpu(format!(
                "contact group of {} threads: a power of two from 8 to {most} (this adapter's \
                 largest workgroup, at most 1024)",
                features.contact_group
            )));
        }
        let device = &ctx.device;
        let key = KernelKey {
            features,
            boundaries: plan.has(Stage::VelocityBoundaries),
            contact: plan.has(Stage::Contact),
            pressure: plan.has(Stage::Pressure),
        };
        let mut rejected = None;
        let kernels = ctx.kernels.get_or_compile(key, || {
            let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
            let kernels = Kernels::new(device, features, key.boundaries, key.contact, key.pressure);
            match pollster::block_on(scope.pop()) {
                None => Some(kernels),
                Some(e) => {
                    rejected = Some(e);
                    None
                }
            }
        });
        let Some(kernels) = kernels else {
            return Err(Error::Gpu(format!(
                "kernels rejected by {}: {}",
                ctx.adapter_name(),
                rejected.map_or_else(|| "no reason given".to_string(), |e| e.to_string())
            )));
        };
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
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
                "buffer setup rejected by {}: {e}",
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
        let names = Names::new(
            model,
            state
                .contact
                .as_ref()
                .and_then(|c| c.penalty_step())
                .map(|(_, w)| w.to_string()),
        );
        let record_ahead = submit::record_ahead(ctx.info.device_type);
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
            batch_start: 0,
            eroded: Vec::new(),
            erosion_cap: MAX_BATCH,
            record_ahead,
            prepared: None,
            ahead: AheadCounts::default(),
        })
    }

    /// The device-side state (buffers allocated for this scene).
    pub fn state(&self) -> &GpuState {
        &self.state
    }

    pub(crate) fn state_mut(&mut self) -> &mut GpuState {
        self.drop_recorded_ahead();
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
        self.drop_recorded_ahead();
        self.ctrl = ctrl;
        self.rows_read = rows_read;
        self.dt_estimate = dt_estimate;
        self.counters = counters;
        self.finished = finished;
        // The device's erosion state was restored: read it whole at the next follow.
        self.eroded.clear();
    }

    /// Gives the contact candidate buffer room for `cap` candidates, if it has not (restoring a
    /// checkpoint of a run whose buffer grew).
    pub(crate) fn resize_contact_candidates(&mut self, cap: u32) -> Result<()> {
        self.drop_recorded_ahead();
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
        (steps.max(0.0) as u32)
            .clamp(MIN_BATCH, MAX_BATCH)
            .min(self.erosion_cap)
    }

    /// A contact search stopped the step because a contact buffer is too small: grows it (from
    /// the counters just read back) and resumes the step from its contact stage.
    fn contact_grow(&mut self) -> Result<()> {
        self.drop_recorded_ahead();
        let device = &self.ctx.device;
        let (Some(c), Some(k)) = (self.state.contact.as_mut(), self.kernels.contact.as_ref())
        else {
            return Err(Error::Gpu(
                "contact grow requested without contact buffers".into(),
            ));
        };
        c.grow(device, &self.ctx.queue, k)?;
        self.resume_step();
        Ok(())
    }

    /// Elements eroded in a scene with contact and the step stopped before its contact stage:
    /// reads the list of the elements eroded since the last follow (every element's flag the
    /// first time and after a restore), moves the contact surfaces onto the edges they expose (and the
    /// penalty springs' step with them), and resumes the step from its contact stage.
    fn contact_follow_erosion(&mut self) -> Result<()> {
        self.drop_recorded_ahead();
        let t0 = std::time::Instant::now();
        let (Some(buf), Some(list)) = (self.state.erosion.clone(), self.state.eroded_list.clone())
        else {
            return Err(Error::Gpu("erosion stop without erosion state".into()));
        };
        let ne = self.state.params.n_elems as usize;
        // The elements eroded since the last follow (`Control::eroded` of them) when the host
        // knows the flags before them; else every element's flag.
        let count = self.ctrl.eroded as usize;
        if self.eroded.len() == ne && count > 0 && 4 * count as u64 <= list.size() {
            let bytes =
                self.read_copies("eroded_list_readback", &[(&list, 0, 4 * count as u64)])?;
            let listed: &[u32] = bytemuck::cast_slice(&bytes);
            for &e in listed {
                if let Some(f) = self.eroded.get_mut(e as usize) {
                    *f = true;
                }
            }
        } else {
            let bytes = self.read_copies("erosion_readback", &[(&buf, 0, 16 * ne as u64)])?;
            let f: &[f32] = bytemuck::cast_slice(&bytes);
            self.eroded = (0..ne).map(|e| f[4 * e + 1] != 0.0).collect();
        }
        self.counters.eroded_elements = self.eroded.iter().filter(|&&e| e).count() as u64;
        let queue = &self.ctx.queue;
        let Some(c) = self.state.contact.as_mut() else {
            return Err(Error::Gpu("erosion stop without contact buffers".into()));
        };
        let penalty = c.follow_erosion(queue, &self.eroded)?.unwrap_or(0.0) as f32;
        if penalty != self.state.params.penalty_dt {
            self.state.params.penalty_dt = penalty;
            if let Some((_, b)) = self.state.buffers.iter().find(|(n, _)| *n == "params") {
                queue.write_buffer(
                    b,
                    std::mem::offset_of!(Params, penalty_dt) as u64,
                    bytemuck::bytes_of(&penalty),
                );
            }
        }
        queue.write_buffer(
            &self.state.ctrl,
            CONTROL_ERODED_OFFSET,
            bytemuck::bytes_of(&0u32),
        );
        self.counters.erosion_follows += 1;
        self.counters.erosion_follow_seconds += t0.elapsed().as_secs_f64();
        let ran = self.ctrl.step.saturating_sub(self.batch_start);
        self.erosion_cap = (2 * ran).clamp(2, MAX_BATCH);
        self.resume_step();
        Ok(())
    }

    /// Resumes a step that a contact stop interrupted, from its contact stage.
    fn resume_step(&mut self) {
        self.drop_recorded_ahead();
        self.ctx.queue.write_buffer(
            &self.state.ctrl,
            CONTROL_STATE_OFFSET,
            bytemuck::bytes_of(&STATE_RUNNING),
        );
        let enc = self.encode_pass("resumed step", |pass| {
            self.state.record_tail(&self.kernels, pass)
        });
        self.ctx.queue.submit([enc.finish()]);
        self.counters.submissions += 1;
    }

    /// Takes about `steps` steps (the step a contact search interrupted counts once), in
    /// submissions of at most [`MAX_BATCH`] steps with the contact searches the kernels ask for,
    /// discarding outputs (for benchmarks), and returns the steps taken: fewer when the run ended
    /// or failed.
    ///
    /// # Errors
    /// [`Error::Gpu`] when the device is lost.
    pub fn run_steps(&mut self, steps: u64) -> Result<u64> {
        self.take_steps(steps, MAX_BATCH, |solver, n| {
            solver.submit(n);
            Ok(())
        })
    }

    /// Takes about `steps` steps in submissions of at most `batch` steps, each recorded and
    /// submitted by `submit` (with its number of steps), its results read back and discarded;
    /// returns the steps taken: fewer when the run ended or failed.
    fn take_steps(
        &mut self,
        steps: u64,
        batch: u32,
        mut submit: impl FnMut(&mut Self, u32) -> Result<()>,
    ) -> Result<u64> {
        let start = self.ctrl.step as u64;
        let mut events = Vec::new();
        while !self.finished {
            let done = (self.ctrl.step as u64).saturating_sub(start);
            if done >= steps {
                break;
            }
            let n = (steps - done).min(batch.min(self.erosion_cap) as u64) as u32;
            submit(self, n)?;
            self.read(&mut events)?;
            events.clear();
        }
        Ok((self.ctrl.step as u64).saturating_sub(start))
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

    fn finished(&self) -> bool {
        self.finished
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

    fn eroded_inverted_now(&mut self) -> Result<u64> {
        self.eroded_apart(ERODED_INVERTED)
    }

    fn eroded_small_step_now(&mut self) -> Result<u64> {
        self.eroded_apart(ERODED_SMALL_STEP)
    }

    fn counters(&self) -> Counters {
        let mut out = self.counters;
        if let Some(c) = &self.state.contact {
            let k = c.counters;
            out.contact_searches = k.searches as u64;
            out.contact_sweeps_max = k.sweeps_max as u64;
            out.contact_unconverged = k.unconverged as u64;
            out.contact_residual_max = f64::from(f32::from_bits(k.residual_max))
                / f64::from(c.params.margin).max(f64::MIN_POSITIVE);
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
