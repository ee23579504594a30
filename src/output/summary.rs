//! `summary.json`: how the run ended and what it cost.

use serde::Serialize;

/// The run summary written to `summary.json`.
#[derive(Debug, Clone, Serialize)]
pub struct Summary {
    /// "completed", "failed" (the run went unstable; see `message`) or "interrupted" (by SIGINT or
    /// SIGTERM; `message` says where); "running" while the run goes on (written before the first
    /// step, so that an unwritable output folder is found at once).
    pub status: String,
    /// Empty when completed; the diagnostic when failed; the signal, step and time when
    /// interrupted.
    pub message: String,
    /// Scene name.
    pub scene: String,
    /// "cpu" or "gpu".
    pub backend: String,
    /// Adapter or processor.
    pub adapter: String,
    /// Nodes.
    pub nodes: usize,
    /// Elements.
    pub elements: usize,
    /// Steps taken.
    pub steps: u64,
    /// Simulated time reached.
    pub end_time: f64,
    /// Wall-clock seconds of the time loop.
    pub wall_seconds: f64,
    /// Elements x steps / wall seconds.
    pub element_cycles_per_second: f64,
    /// Smallest step taken.
    pub dt_min: f64,
    /// Largest step taken.
    pub dt_max: f64,
    /// Largest relative energy-balance error over the history rows.
    pub max_energy_error: f64,
    /// Command-buffer submissions (GPU backend; 0 on the CPU).
    pub gpu_submissions: u64,
    /// Readbacks from the GPU (0 on the CPU).
    pub gpu_readbacks: u64,
    /// Contact broad-phase searches (0 without contact): one every step means the nodes move
    /// more than half the search margin per step.
    pub contact_searches: u64,
    /// Bytes read back from the device over the run (GPU; 0 on the CPU): history rows,
    /// snapshots and small counters only.
    pub bytes_read_back: u64,
    /// Lagrange contact: projected Gauss-Seidel sweeps per step that has Lagrange constraints,
    /// mean and largest (0 without).
    pub contact_sweeps_mean: f64,
    /// See `contact_sweeps_mean`.
    pub contact_sweeps_max: u64,
    /// Lagrange contact: steps whose residual stayed above the tolerance (their sweeps stopped
    /// at the sweep limit): `contact::SWEEP_TOLERANCE` on the CPU, on the GPU the step's stop
    /// (`gpu::contact::solve::STOP_PENETRATION`, between `STOP_FLOOR` and 1 times `TOLERANCE`).
    pub contact_unconverged: u64,
    /// Lagrange contact: the largest residual of a step, the largest change of a gap (or of a
    /// tangential slip) in the step's last sweep over the search margin (0 without), on both
    /// backends (the GPU's in f32); `None` only in summaries written before the GPU measured it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub contact_residual_max: Option<f64>,
    /// Penalty contact: impulses bounded by the perfectly plastic impulse (constraint-steps
    /// whose spring was too stiff for the step, (omega dt)^2 > 1): the spring energy they kept
    /// stays in `contact_energy` after release. 0: every spring acted unchanged.
    #[serde(default)]
    pub contact_penalty_bounded: u64,
    /// Failure criteria: one line per material that has them ("steel: plastic_strain 0.8");
    /// no key in `summary.json` for a scene without failure.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub failure: Vec<String>,
    /// Johnson-Cook thermal softening with adiabatic heating: one line per material that has it
    /// ("steel: thermal softening m 1, ..."); no key in `summary.json` for a scene without.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub thermal: Vec<String>,
    /// The highest element temperature at the end (K), for a scene with thermal softening; no
    /// key without.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_temperature: Option<f64>,
    /// Elements eroded by the end of the run (failed, about to invert with
    /// `run.erosion.inverted`, or with a stable step below `run.erosion.min_time_step`); no key
    /// without failure or erosion.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub eroded_elements: Option<u64>,
    /// Of `eroded_elements`, those eroded because they were about to invert (with
    /// `run.erosion.inverted`; no key without).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub eroded_inverted: Option<u64>,
    /// Of `eroded_elements`, those eroded because their stable step fell below
    /// `run.erosion.min_time_step` (no key without it).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub eroded_small_step: Option<u64>,
    /// Seconds per stage where the backend measures them.
    pub stage_seconds: Vec<(String, f64)>,
    /// History rows written.
    pub history_rows: usize,
    /// Field snapshots written.
    pub snapshots: usize,
}
