//! The command line's arguments, as clap reads them and `ricochet --help` shows them: the
//! commands and their options. Each command's body is in the module named for it beside this one
//! (`run.rs`, `plot.rs`, `check.rs`, `bench.rs`, `verify.rs`).

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand, ValueEnum};

/// The command line: one command.
#[derive(Parser)]
#[command(
    name = "ricochet",
    version,
    about = "Explicit contact-impact simulation of 2D solids on the GPU"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

/// The commands.
#[derive(Subcommand)]
pub enum Command {
    /// Run a scene.
    Run(RunArgs),
    /// Draw a run's pictures from its output folder into OUT/plots/: energies, contact forces and
    /// body velocities against time, and the deformed mesh filled by a field at chosen snapshots.
    Plot(PlotArgs),
    /// Throughput benchmark on a generated N x N block (no contact), with the full step over the
    /// bare element-and-update loop and the cost of a contact pair, in the same run; and, with
    /// --scene, contact scenes (pair, striker, pile) with and without their contact.
    Bench(BenchArgs),
    /// Validate a scene and print its plan.
    Check(CheckArgs),
    /// Run the verification suite (assets/verification/): error against wall time per case,
    /// method and backend; writes results.csv, report.md and one plot per case.
    Verify(VerifyArgs),
    /// Run a study: the cases of a study file (a base scene with keys varied: a grid, lists, a
    /// Latin hypercube, or a threshold search), here (one worker per hardware GPU, else per CPU
    /// core) or as a Slurm job array (--slurm); a rerun continues where it stopped.
    Study(StudyArgs),
    /// Collect a study's folder into DIR/results.csv and DIR/results.json: one row per case with
    /// its status, parameters and collected figures.
    Collect(CollectArgs),
}

/// The options of `ricochet run`.
#[derive(Args)]
pub struct RunArgs {
    /// Scene file (TOML); not with --restart, which takes the scene of the checkpoint.
    #[arg(required_unless_present = "restart")]
    pub scene: Option<PathBuf>,
    /// Backend.
    #[arg(long, value_enum, default_value = "auto")]
    pub backend: Backend,
    /// Output folder (default out/<scene name>).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Override run.end_time.
    #[arg(long)]
    pub end_time: Option<f64>,
    /// Adapter: an index (0, 1, ...: discrete first, then by PCI bus id), a PCI bus id
    /// (0000:3b:00.0) or a name substring; also by name from WGPU_ADAPTER_NAME. Within
    /// CUDA_VISIBLE_DEVICES / ROCR_VISIBLE_DEVICES when set.
    #[arg(long)]
    pub adapter: Option<String>,
    /// Then draw the pictures of the run (as `ricochet plot OUT`).
    #[arg(long)]
    pub plots: bool,
    /// Write OUT/checkpoint.bin every T seconds of simulated time (and when interrupted),
    /// replacing the previous one; overrides run.checkpoint_interval.
    #[arg(long, value_name = "T")]
    pub checkpoint_interval: Option<f64>,
    /// Continue the run whose output folder DIR holds a checkpoint.bin, into DIR, on the
    /// checkpoint's backend (and the same scene, end time and checkpoint interval).
    #[arg(long, value_name = "DIR", conflicts_with_all = ["scene", "out", "end_time", "checkpoint_interval"])]
    pub restart: Option<PathBuf>,
}

/// The options of `ricochet plot`.
#[derive(Args)]
pub struct PlotArgs {
    /// The run's output folder (with history.csv, summary.json, fields.pvd), or a study's folder
    /// (with study.json) with --figure and --against.
    pub out: PathBuf,
    /// A study's collected figure to draw (into DIR/plots/<FIGURE>_vs_<PARAM>.png).
    #[arg(long, requires = "against", conflicts_with_all = ["field", "times", "range", "animate"])]
    pub figure: Option<String>,
    /// The study's parameter the figure is drawn against (one line per combination of the
    /// other parameters).
    #[arg(long, requires = "figure")]
    pub against: Option<String>,
    /// Field of the field pictures (default von_mises).
    #[arg(long, value_parser = ["von_mises", "pressure", "velocity", "displacement", "plastic_strain"])]
    pub field: Option<String>,
    /// Snapshot times (s): the snapshot nearest each; default all, or 12 evenly spaced.
    #[arg(long, num_args = 1.., allow_negative_numbers = true)]
    pub times: Vec<f64>,
    /// Colour range LO HI of the field pictures (default: the smallest and largest value over
    /// the chosen snapshots); values outside take the end colours.
    #[arg(long, num_args = 2, value_names = ["LO", "HI"], allow_negative_numbers = true)]
    pub range: Option<Vec<f64>>,
    /// Also write field_<name>.gif with the chosen snapshots as frames.
    #[arg(long)]
    pub animate: bool,
    /// Picture format.
    #[arg(long, value_enum, default_value = "png")]
    pub format: PlotFormat,
}

/// The options of `ricochet bench`.
#[derive(Args)]
pub struct BenchArgs {
    /// Backend(s).
    #[arg(long, value_enum, default_value = "auto")]
    pub backend: BenchBackend,
    /// Scenes: the block (first table) and/or the contact scenes (second table).
    #[arg(long, value_enum, num_args = 1.., default_values_t = [BenchScene::Block])]
    pub scene: Vec<BenchScene>,
    /// Cells per side of the block scene (elements = N^2); several allowed.
    #[arg(long, num_args = 1.., default_values_t = [32usize, 100, 316, 1000])]
    pub cells: Vec<usize>,
    /// Element targets of the contact scenes (each mapped to the nearest size); several
    /// allowed.
    #[arg(long, num_args = 1.., default_values_t = [10_000usize, 100_000, 1_000_000])]
    pub elements: Vec<usize>,
    /// The pile with one [[contact]] per pair of disks instead of `bodies = "all"` (a
    /// fallback where that does not parse; small piles only).
    #[arg(long)]
    pub pile_pairs: bool,
    /// Also time each contact scene with this Coulomb coefficient on its contacts and walls
    /// (a third variant in the same rounds): what friction adds to a contact step.
    #[arg(long)]
    pub friction: Option<f64>,
    /// Also time each contact scene with failure on every material (a variant in the same
    /// rounds): its elements erode at this largest principal strain (0.03 if none is given;
    /// elements about to invert erode too), and its contact follows the erosion: what erosion
    /// costs a contact step.
    #[arg(long, num_args = 0..=1, default_missing_value = "0.03")]
    pub failure: Option<f64>,
    /// Steps timed per size.
    #[arg(long, default_value_t = 200)]
    pub steps: u64,
    /// Rounds the steps are split into, each variant timed in alternation (medians reported).
    #[arg(long, default_value_t = ricochet::bench::DEFAULT_ROUNDS)]
    pub rounds: u32,
    /// Steps each variant of a contact scene runs before the timed ones (at least 2, the
    /// first search): e.g. 600 to time the pile in contact (its disks reach the wall after
    /// about 440 steps).
    #[arg(long, default_value_t = ricochet::bench::DEFAULT_WARMUP)]
    pub warmup: u64,
    /// Time the contact scenes with plain projected Gauss-Seidel sweeps instead of the
    /// extrapolated ones (both backends): a comparison.
    #[arg(long)]
    pub plain_sweeps: bool,
    /// Whether the GPU's one-workgroup contact solve sweeps 2 x 2 blocks (the two constraints
    /// of a node pair met from both passes solved together, as on the CPU reference) or each
    /// constraint on its own (default: blocks on GPUs, not on CPU adapters;
    /// `ricochet::gpu::contact::pair_blocks`): a comparison, for the tables and --profile.
    #[arg(long, value_enum)]
    pub pair_blocks: Option<BenchPairBlocks>,
    /// How the GPU's one-workgroup contact solve colours its constraints (default: in parallel
    /// rounds on GPUs, in slot order on CPU adapters; `ricochet::gpu::contact::parallel_colouring`):
    /// a comparison, for the tables and --profile.
    #[arg(long, value_enum)]
    pub colouring: Option<BenchColouring>,
    /// Where the GPU's one-workgroup contact solve keeps the packed nodes' records and the
    /// multipliers during its sweeps (default: in workgroup memory where they fit on GPUs,
    /// through storage on CPU adapters; `ricochet::gpu::contact::local_sweeps`): a comparison,
    /// for the tables and --profile.
    #[arg(long, value_enum)]
    pub sweep_memory: Option<BenchSweepMemory>,
    /// Record each GPU batch of steps only after the readback of the one before, instead of
    /// while the device runs it (`GpuSolver::set_record_ahead`; the GPUs' default, not the CPU
    /// adapters'): a comparison for the contact scenes' tables.
    #[arg(long)]
    pub no_record_ahead: bool,
    /// How the GPU's contact search is dispatched (default: in one workgroup for small contact
    /// sets on GPUs, and for larger ones while searches are rare; per item on CPU adapters;
    /// `ricochet::gpu::contact::search::search_one_path`, `search_switch`): a comparison, for the
    /// tables and --profile.
    #[arg(long, value_enum)]
    pub search: Option<BenchSearch>,
    /// Threads of the GPU's one-workgroup contact kernels (the one-workgroup solve, the
    /// search's scans and the reports' end): a power of two from 8 to the adapter's largest
    /// workgroup, at most 1024 (default: 256 on GPUs, 8 on CPU adapters;
    /// `ricochet::gpu::contact::one_group`): a comparison, for the tables and --profile.
    #[arg(long)]
    pub contact_group: Option<u32>,
    /// How the GPU's contact stage after the search is dispatched (default: in one workgroup on
    /// CPU adapters with a small contact set, per item otherwise; `ricochet::gpu::contact::one`):
    /// `one` takes it in one workgroup on any adapter (with the one-workgroup solve, whatever
    /// the size), a comparison for the tables and --profile.
    #[arg(long, value_enum)]
    pub contact_stage: Option<BenchContactStage>,
    /// Also write the table(s) as JSON: the block rows as an array; with a contact scene,
    /// an object {"block": [...], "contact": [...]}; with --probe or --profile, its report.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Adapter name (substring), also from WGPU_ADAPTER_NAME.
    #[arg(long)]
    pub adapter: Option<String>,
    /// The device check's probe and profile.
    #[command(flatten)]
    pub device: super::bench::DeviceArgs,
}

/// The options of `ricochet check`.
#[derive(Args)]
pub struct CheckArgs {
    /// Scene file (TOML), or a study file (with a [study] table): every case's scene is
    /// materialised and checked.
    pub scene: PathBuf,
}

/// The options of `ricochet study`.
#[derive(Args)]
pub struct StudyArgs {
    /// Study file (TOML).
    pub study: PathBuf,
    /// The study's folder (default out/<study name>): DIR/cases/<id>/, DIR/results.csv.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Workers on this machine (default: one per hardware GPU adapter, else one per CPU core).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=1024))]
    pub workers: Option<u32>,
    /// Backend of the runs (default the study's `backend`, else auto).
    #[arg(long, value_enum)]
    pub backend: Option<Backend>,
    /// Run the cases as a Slurm job array: write DIR/slurm/array.sh and collect.sh and submit
    /// them with sbatch.
    #[arg(long)]
    pub slurm: bool,
    /// With --slurm: the partition.
    #[arg(long, requires = "slurm")]
    pub partition: Option<String>,
    /// With --slurm: the account.
    #[arg(long, requires = "slurm")]
    pub account: Option<String>,
    /// With --slurm: at most K array tasks at once (the `%K` throttle).
    #[arg(long, value_name = "K", requires = "slurm", value_parser = clap::value_parser!(u32).range(1..))]
    pub max_parallel: Option<u32>,
    /// With --slurm: GPUs per task (`--gpus-per-task`).
    #[arg(long, value_name = "N", requires = "slurm")]
    pub gpus_per_task: Option<u32>,
    /// With --slurm: CPUs per task (`--cpus-per-task`, default 1).
    #[arg(long, value_name = "N", requires = "slurm", value_parser = clap::value_parser!(u32).range(1..))]
    pub cpus_per_task: Option<u32>,
    /// With --slurm: each task's time limit (`--time`, Slurm's forms: MM, HH:MM:SS, D-HH).
    #[arg(long, value_name = "T", requires = "slurm")]
    pub time: Option<String>,
    /// With --slurm: seconds before the time limit at which a task's run checkpoints, stops and
    /// requeues its task (`--signal=B:TERM@S`).
    #[arg(long, value_name = "S", requires = "slurm", default_value_t = 120)]
    pub signal_seconds: u32,
    /// With --slurm: a further sbatch option for both scripts (`--sbatch=--mem=4G`); repeatable.
    #[arg(
        long,
        value_name = "OPTION",
        requires = "slurm",
        allow_hyphen_values = true
    )]
    pub sbatch: Vec<String>,
    /// With --slurm: write the scripts without submitting them.
    #[arg(long, requires = "slurm")]
    pub no_submit: bool,
    /// With --slurm: wait until the collect job has ended, then print the results' counts.
    #[arg(long, requires = "slurm", conflicts_with = "no_submit")]
    pub wait: bool,
}

/// The options of `ricochet collect`.
#[derive(Args)]
pub struct CollectArgs {
    /// The study's folder (with study.json).
    pub dir: PathBuf,
}

/// The options of `ricochet verify`.
#[derive(Args)]
pub struct VerifyArgs {
    /// The short ladders (a few minutes on a 2-core machine).
    #[arg(long)]
    pub quick: bool,
    /// Backend(s).
    #[arg(long, value_enum, default_value = "both")]
    pub backend: VerifyBackend,
    /// Output folder.
    #[arg(long, default_value = "out/verification")]
    pub out: PathBuf,
    /// Folder of case files to run instead of the built-in ones (those of
    /// assets/verification/, embedded in the binary).
    #[arg(long)]
    pub cases: Option<PathBuf>,
    /// Only these cases (by name); all when omitted.
    #[arg(long, num_args = 1..)]
    pub case: Vec<String>,
    /// Adapter name (substring), also from WGPU_ADAPTER_NAME.
    #[arg(long)]
    pub adapter: Option<String>,
    /// Runs at a time: 1 (the default) runs them one after another; 2 runs the GPU's beside
    /// the CPU's, each worker taking the other's runs once its own are done (with one backend,
    /// two of its runs at once). The results and the report are the same but for the wall
    /// times, each measured while other runs shared the machine.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=64))]
    pub jobs: u32,
}

/// `run --backend`: the library's [`ricochet::run::Backend`], as the command line names it.
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Backend {
    /// The GPU when a hardware adapter exists (or --adapter / WGPU_ADAPTER_NAME names one), else
    /// the CPU reference, with a one-line notice (a software adapter such as Mesa lavapipe is
    /// slower than the CPU reference).
    Auto,
    /// The f64 CPU reference.
    Cpu,
    /// The GPU; an error when no adapter exists.
    Gpu,
}

impl From<Backend> for ricochet::run::Backend {
    fn from(b: Backend) -> Self {
        match b {
            Backend::Auto => Self::Auto,
            Backend::Cpu => Self::Cpu,
            Backend::Gpu => Self::Gpu,
        }
    }
}

/// `bench --backend`.
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum BenchBackend {
    /// Both when a GPU exists, else the CPU.
    Auto,
    /// CPU reference only.
    Cpu,
    /// GPU only.
    Gpu,
    /// CPU and GPU in the same run (ratios comparable).
    Both,
}

/// `bench --scene`.
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum BenchScene {
    /// The N x N block without contact (the first table, with its contact-pair column).
    Block,
    /// The block pressed into its base (second table).
    Pair,
    /// A striker into a plate at v0 / c = 0.05 (second table).
    Striker,
    /// A pile of disks dropped onto a rigid wall, one contact over all bodies (second table).
    Pile,
    /// All of the above.
    All,
}

/// `bench --colouring`.
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum BenchColouring {
    /// Greedy in slot order, in one invocation (the CPU adapters' default).
    Serial,
    /// Greedy in a hashed order, in parallel Jones-Plassmann rounds (the GPUs' default).
    Parallel,
}

/// `bench --pair-blocks`.
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum BenchPairBlocks {
    /// Each constraint swept on its own (the CPU adapters' default).
    Off,
    /// The two constraints of a node pair met from both passes as a 2 x 2 block (the GPUs'
    /// default).
    On,
}

/// `bench --sweep-memory`.
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum BenchSweepMemory {
    /// Read and written through storage (the CPU adapters' default).
    Storage,
    /// In workgroup memory where they fit (the GPUs' default).
    Workgroup,
}

/// `bench --search`.
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum BenchSearch {
    /// In one workgroup: one dispatch a step, empty on the steps that do not search.
    One,
    /// In its eleven per-item kernels, dispatched indirectly (empty on those steps).
    Items,
}

/// `bench --contact-stage`.
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum BenchContactStage {
    /// The narrow phase, the gather, the solve, `finish` and the reports in one workgroup, one
    /// dispatch, and the node preparation in another (CPU adapters' default for small sets).
    One,
    /// Each in its own kernels over many workgroups (the GPUs' default).
    Items,
}

/// `plot --format`.
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum PlotFormat {
    /// PNG.
    Png,
    /// SVG.
    Svg,
}

/// `verify --backend`.
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum VerifyBackend {
    /// The f64 CPU reference.
    Cpu,
    /// The GPU (an adapter is required).
    Gpu,
    /// Both, in the same run (an adapter is required).
    Both,
}
