//! Time stepping: the explicit central-difference step and what both backends share. The CPU
//! reference solver is [`cpu`], the GPU's [`crate::gpu::solver`].
//!
//! One step, as in the explicit flowchart (Belytschko, Box X.?):
//! 1. element stage: nodal forces f_n from u_n (and the lagged v^{n-1/2} for the viscous parts),
//!    the element stable steps, and on output steps the energies;
//! 2. dt^{n+1/2} = min over elements x `time_step_scale` (or the fixed step);
//! 3. node stage: v^{n+1/2} = v^{n-1/2} + dt_n M^-1 f_n with dt_n = (dt^{n-1/2} + dt^{n+1/2}) / 2
//!    (dt^{1/2} / 2 on the first step), then the velocity boundary conditions;
//! 4. output at t_n when due; stop when t_n >= end_time (a last step that would overshoot it by
//!    more than 1 % of the run is shortened: [`clip_to_end`]);
//! 5. u_{n+1} = u_n + dt^{n+1/2} v^{n+1/2}, t_{n+1} = t_n + dt^{n+1/2}.

pub mod cpu;
pub mod erosion;

use crate::element::plastic::PlasticState;
use crate::error::Result;

/// Longest a [`Solver::advance`] call runs without an event before it returns (seconds).
pub const ADVANCE_SECONDS: f64 = 0.25;

/// When samples, snapshots and the end fall, as both backends decide them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Schedule {
    /// Simulated end time.
    pub end_time: f64,
    /// Time between samples (history rows).
    pub history_interval: f64,
    /// Time between snapshots, if any.
    pub field_interval: Option<f64>,
    /// Safety factor on the stable step.
    pub time_step_scale: f64,
    /// Fixed step, if any.
    pub time_step: Option<f64>,
}

/// A time is due when t_n >= T - TIME_SLACK * dt^{n-1/2}: a small fraction of the last step, so
/// that t_n = T up to round-off (f64 on the CPU, f32 steps on the GPU) counts as due on both.
pub const TIME_SLACK: f64 = 0.01;

/// The step dt^{n+1/2}, shortened to `remaining` = T - t_n when it would carry the run past its end
/// time T by more than 1 % of T (a run of few steps, or a first step longer than the whole run):
/// such a run then ends on T. Otherwise the run ends at the first t_n >= T - [`TIME_SLACK`] dt,
/// less than one step past T, with every step as the stability limit gives it: shortening the last
/// steps of a long run would perturb its energy audit (the conserved kinetic energy
/// 1/2 v^{n-1/2} M v^{n+1/2} is exact for smoothly varying steps only; halving the last two
/// steps was measured to move the audit of a dissipative block by 7e-3) and, for a very short
/// last step, make the Lagrange contact corrections arbitrarily large. `at_end`: t_n is already
/// at the end (no step follows; `dt` is only reported).
///
/// The GPU's `control_dt` (`shaders/control.wgsl`) applies the same rule in f32.
pub fn clip_to_end(dt: f64, remaining: f64, end_time: f64, at_end: bool) -> f64 {
    if !at_end && remaining > 0.0 && remaining < dt && dt - remaining > 0.01 * end_time {
        remaining
    } else {
        dt
    }
}

/// Tracks the next due sample and snapshot.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Clock {
    /// Index k of the next sample time k * history_interval.
    pub next_sample: u64,
    /// Index k of the next snapshot time k * field_interval.
    pub next_snapshot: u64,
}

impl Clock {
    /// A clock at t = 0 with everything due.
    pub fn new() -> Self {
        Self {
            next_sample: 0,
            next_snapshot: 0,
        }
    }

    fn due(t: f64, dt_prev: f64, target: f64) -> bool {
        t + TIME_SLACK * dt_prev >= target
    }

    /// Whether t_n is at or past the end.
    pub fn at_end(s: &Schedule, t: f64, dt_prev: f64) -> bool {
        Self::due(t, dt_prev, s.end_time)
    }

    /// Whether a sample is due at `t` (always at the end).
    pub fn sample_due(&self, s: &Schedule, t: f64, dt_prev: f64) -> bool {
        Self::at_end(s, t, dt_prev)
            || Self::due(t, dt_prev, self.next_sample as f64 * s.history_interval)
    }

    /// Whether a snapshot is due at `t` (always at the end when snapshots are on).
    pub fn snapshot_due(&self, s: &Schedule, t: f64, dt_prev: f64) -> bool {
        match s.field_interval {
            Some(fi) => {
                Self::at_end(s, t, dt_prev) || Self::due(t, dt_prev, self.next_snapshot as f64 * fi)
            }
            None => false,
        }
    }

    /// The first index k >= `from` whose time k * `interval` is not due at `t`: what walking
    /// k += 1 from `from` finds (due-ness only falls as k grows), by an exponential search and a
    /// bisection instead. A walk passes dt / interval indices in one step, without bound where
    /// the step dwarfs the interval (a last step of 1e141 s past end_time = 2e-5 s with
    /// history_interval = 1e-6 s, from a density of 1e300, walked 1e147 indices: a hang).
    /// Saturates at `u64::MAX`.
    fn first_not_due(from: u64, t: f64, dt_prev: f64, interval: f64) -> u64 {
        let due = |k: u64| Self::due(t, dt_prev, k as f64 * interval);
        if !due(from) {
            return from;
        }
        // Invariant: `lo` is due; `hi` is not (or is u64::MAX).
        let (mut lo, mut hi, mut stride) = (from, from, 1u64);
        while hi < u64::MAX {
            hi = lo.saturating_add(stride);
            if !due(hi) {
                break;
            }
            lo = hi;
            stride = stride.saturating_mul(2);
        }
        if hi == u64::MAX && due(hi) {
            return u64::MAX;
        }
        while hi - lo > 1 {
            let mid = lo + (hi - lo) / 2;
            if due(mid) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        hi
    }

    /// Advances the sample index past every time due at `t`.
    pub fn took_sample(&mut self, s: &Schedule, t: f64, dt_prev: f64) {
        self.next_sample = Self::first_not_due(self.next_sample, t, dt_prev, s.history_interval);
    }

    /// Advances the snapshot index past every time due at `t`.
    pub fn took_snapshot(&mut self, s: &Schedule, t: f64, dt_prev: f64) {
        if let Some(fi) = s.field_interval {
            self.next_snapshot = Self::first_not_due(self.next_snapshot, t, dt_prev, fi);
        }
    }
}

impl Default for Clock {
    fn default() -> Self {
        Self::new()
    }
}

/// Energies and body velocities at t_n (one history row before the error column).
#[derive(Debug, Clone, PartialEq)]
pub struct Sample {
    /// t_n.
    pub time: f64,
    /// n.
    pub step: u64,
    /// dt^{n+1/2}.
    pub dt: f64,
    /// Kinetic energy in the conserved form 1/2 v^{n-1/2} M v^{n+1/2}.
    pub kinetic: f64,
    /// Strain energy.
    pub internal: f64,
    /// Hourglass energy: stored (stiffness form) plus dissipated (viscous form).
    pub hourglass: f64,
    /// Work dissipated by the bulk viscosity.
    pub viscous: f64,
    /// Work dissipated by plastic flow (0 without a J2 plastic material).
    pub plastic: f64,
    /// Elements eroded so far (0 without failure).
    pub eroded_elements: u64,
    /// Strain and stored hourglass energy the eroded elements held when they eroded (0 without
    /// failure); their kinetic energy stays with their nodes.
    pub eroded_energy: f64,
    /// Work done on the model by prescribed velocities.
    pub external: f64,
    /// Contact energy: penalty energy stored plus the work the contact corrections removed
    /// (minus the work the contact impulses did on the model).
    pub contact: f64,
    /// Work dissipated by friction (>= 0; 0 without friction).
    pub friction: f64,
    /// Per contact and rigid wall (in the scene's order, contacts first).
    pub contacts: Vec<crate::contact::ContactSample>,
    /// Per body: momentum / mass at t_n.
    pub body_velocity: Vec<[f64; 2]>,
}

/// Nodal state at t_n for field output.
#[derive(Debug, Clone, PartialEq)]
pub struct Snapshot {
    /// t_n.
    pub time: f64,
    /// n.
    pub step: u64,
    /// Displacements u_n.
    pub displacement: Vec<[f64; 2]>,
    /// Velocities at t_n, (v^{n-1/2} + v^{n+1/2}) / 2.
    pub velocity: Vec<[f64; 2]>,
    /// Plastic state of every element at t_n (empty for a model without a J2 plastic material).
    pub plastic: Vec<PlasticState>,
    /// Per element, whether it eroded (empty for a model without failure).
    pub eroded: Vec<bool>,
    /// Johnson-Cook damage of every element (empty without Johnson-Cook damage).
    pub damage: Vec<f64>,
}

/// Why a run stopped early.
#[derive(Debug, Clone, PartialEq)]
pub struct Failure {
    /// Step at which it was detected.
    pub step: u64,
    /// Time at which it was detected.
    pub time: f64,
    /// What went wrong, naming the element or node.
    pub message: String,
}

/// What a solver reports while it advances.
#[derive(Debug, Clone, PartialEq)]
pub enum Event {
    /// A history sample.
    Sample(Sample),
    /// A field snapshot.
    Snapshot(Snapshot),
    /// The run reached its end time.
    Done,
    /// The run went unstable.
    Failed(Failure),
}

/// Counters a backend reports in the summary.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Counters {
    /// Command-buffer submissions (GPU).
    pub submissions: u64,
    /// Readbacks from the device (GPU).
    pub readbacks: u64,
    /// Contact broad-phase searches (0 without contact).
    pub contact_searches: u64,
    /// Bytes copied from the device to the host so far (GPU; 0 on the CPU).
    pub bytes_read_back: u64,
    /// Lagrange contact: projected Gauss-Seidel sweeps per step with Lagrange constraints, mean
    /// and largest (0 without).
    pub contact_sweeps_mean: f64,
    /// See `contact_sweeps_mean`.
    pub contact_sweeps_max: u64,
    /// Lagrange contact: steps whose residual stayed above the tolerance (their sweeps
    /// stopped at the sweep limit).
    pub contact_unconverged: u64,
    /// Lagrange contact: the largest residual of a step (the largest change of a gap in its
    /// last sweep over the search margin; 0 without).
    #[serde(default)]
    pub contact_residual_max: f64,
    /// Penalty contact: impulses bounded by the perfectly plastic impulse (constraint-steps with
    /// a spring too stiff for the step; the energy they keep is lost).
    pub contact_penalty_bounded: u64,
    /// Elements eroded so far (0 without failure): it grows in a batch where elements erode.
    #[serde(default)]
    pub eroded_elements: u64,
    /// Times the contact surfaces followed erosion (steps in which elements eroded, in a scene
    /// with failure and contact or walls; 0 otherwise).
    #[serde(default)]
    pub erosion_follows: u64,
    /// Host wall seconds those follows took: on the GPU the eroded elements read back, the host's
    /// follow of its copy of the contact set and the writes of the entries that changed (the
    /// forced search and the resumed step run on the device, not counted); on the CPU the
    /// follow ([`crate::contact::ContactSet::follow_erosion`]).
    #[serde(default)]
    pub erosion_follow_seconds: f64,
    /// GPU: host wall seconds spent recording batches of steps into command buffers (wgpu's
    /// encoding and `finish`), whether recorded ahead while the device ran the batch before or
    /// at the submission ([`crate::gpu::GpuSolver::set_record_ahead`]); 0 on the CPU.
    #[serde(default)]
    pub record_seconds: f64,
}

/// A time integrator of a model: the CPU reference or the GPU backend.
pub trait Solver {
    /// The nodal displacement at the solver's current time (read back from the device on the
    /// GPU), for post-processing such as element stresses after a run.
    ///
    /// # Errors
    /// A failed device readback.
    fn displacement_now(&mut self) -> Result<Vec<[f64; 2]>>;

    /// The plastic state of every element now (empty without a J2 plastic material).
    ///
    /// # Errors
    /// A failed device readback.
    fn plastic_now(&mut self) -> Result<Vec<PlasticState>> {
        Ok(Vec::new())
    }

    /// Elements eroded so far because they were about to invert (`run.erosion.inverted`; 0
    /// without): a part of [`Counters::eroded_elements`].
    ///
    /// # Errors
    /// A failed device readback.
    fn eroded_inverted_now(&mut self) -> Result<u64> {
        Ok(0)
    }

    /// Elements eroded so far because their stable step fell below
    /// `run.erosion.min_time_step` (0 without): a part of [`Counters::eroded_elements`].
    ///
    /// # Errors
    /// A failed device readback.
    fn eroded_small_step_now(&mut self) -> Result<u64> {
        Ok(0)
    }

    /// Advances at least one step, until one or more events happened (or, without one, for about
    /// [`ADVANCE_SECONDS`]), and appends them.
    ///
    /// # Errors
    /// Only for backend failures (a lost device); instability is an [`Event::Failed`].
    fn advance(&mut self, events: &mut Vec<Event>) -> Result<()>;
    /// Whether the solver has ended (its [`Event::Done`] or [`Event::Failed`] given): it takes no
    /// more steps.
    fn finished(&self) -> bool;
    /// Steps taken so far.
    fn steps(&self) -> u64;
    /// Current simulated time.
    fn time(&self) -> f64;
    /// Backend name ("cpu" or "gpu").
    fn backend(&self) -> &'static str;
    /// Adapter or processor description.
    fn adapter(&self) -> String;
    /// Smallest and largest step taken so far.
    fn dt_range(&self) -> (f64, f64);
    /// Submission and readback counters.
    fn counters(&self) -> Counters {
        Counters::default()
    }
    /// The solver's changing state, for a checkpoint ([`crate::checkpoint`]); taken between
    /// [`Solver::advance`] calls.
    ///
    /// # Errors
    /// [`crate::Error::Checkpoint`] when the backend cannot save it; device readback failures.
    fn save_state(&mut self) -> Result<Vec<u8>> {
        Err(crate::Error::Checkpoint(format!(
            "the {} backend cannot save its state",
            self.backend()
        )))
    }
    /// Continues from a state saved by [`Solver::save_state`] of the same backend and model.
    ///
    /// # Errors
    /// [`crate::Error::Checkpoint`] when the state does not fit this solver.
    fn restore_state(&mut self, _state: &[u8]) -> Result<()> {
        Err(crate::Error::Checkpoint(format!(
            "the {} backend cannot restore a state",
            self.backend()
        )))
    }
    /// Optional per-stage timings (stage name, seconds).
    fn stage_seconds(&self) -> Vec<(String, f64)> {
        Vec::new()
    }
}
