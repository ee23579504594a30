//! The `ricochet` command line: `run`, `check`, `bench` and `verify`.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::Context;
use clap::{Parser, Subcommand, ValueEnum};

use ricochet::gpu::{GpuContext, GpuSolver};
use ricochet::model::Model;
use ricochet::plan::Plan;
use ricochet::scene::Scene;
use ricochet::step::cpu::CpuSolver;
use ricochet::step::Solver;
use std::sync::Arc;

#[derive(Parser)]
#[command(
    name = "ricochet",
    version,
    about = "Explicit contact-impact simulation of 2D solids on the GPU"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum Backend {
    /// The GPU when a hardware adapter exists (or --adapter / WGPU_ADAPTER_NAME names one), else
    /// the CPU reference, with a one-line notice (a software adapter such as Mesa lavapipe is
    /// slower than the CPU reference).
    Auto,
    /// The f64 CPU reference.
    Cpu,
    /// The GPU; an error when no adapter exists.
    Gpu,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum BenchBackend {
    /// Both when a GPU exists, else the CPU.
    Auto,
    /// CPU reference only.
    Cpu,
    /// GPU only.
    Gpu,
    /// CPU and GPU in the same run (ratios comparable).
    Both,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum BenchScene {
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

#[derive(Subcommand)]
enum Command {
    /// Run a scene.
    Run {
        /// Scene file (TOML); not with --restart, which takes the scene of the checkpoint.
        #[arg(required_unless_present = "restart")]
        scene: Option<PathBuf>,
        /// Backend.
        #[arg(long, value_enum, default_value = "auto")]
        backend: Backend,
        /// Output folder (default out/<scene name>).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Override run.end_time.
        #[arg(long)]
        end_time: Option<f64>,
        /// Adapter name (substring), also from WGPU_ADAPTER_NAME.
        #[arg(long)]
        adapter: Option<String>,
        /// Then draw the pictures of the run (as `ricochet plot OUT`).
        #[arg(long)]
        plots: bool,
        /// Write OUT/checkpoint.bin every T seconds of simulated time (and when interrupted),
        /// replacing the previous one; overrides run.checkpoint_interval.
        #[arg(long, value_name = "T")]
        checkpoint_interval: Option<f64>,
        /// Continue the run whose output folder DIR holds a checkpoint.bin, into DIR, on the
        /// checkpoint's backend (and the same scene, end time and checkpoint interval).
        #[arg(long, value_name = "DIR", conflicts_with_all = ["scene", "out", "end_time", "checkpoint_interval"])]
        restart: Option<PathBuf>,
    },
    /// Draw a run's pictures from its output folder into OUT/plots/: energies, contact forces and
    /// body velocities against time, and the deformed mesh filled by a field at chosen snapshots.
    Plot {
        /// The run's output folder (with history.csv, summary.json, fields.pvd).
        out: PathBuf,
        /// Field of the field pictures (default von_mises).
        #[arg(long, value_parser = ["von_mises", "pressure", "velocity", "displacement", "plastic_strain"])]
        field: Option<String>,
        /// Snapshot times (s): the snapshot nearest each; default all, or 12 evenly spaced.
        #[arg(long, num_args = 1.., allow_negative_numbers = true)]
        times: Vec<f64>,
        /// Colour range LO HI of the field pictures (default: the smallest and largest value over
        /// the chosen snapshots); values outside take the end colours.
        #[arg(long, num_args = 2, value_names = ["LO", "HI"], allow_negative_numbers = true)]
        range: Option<Vec<f64>>,
        /// Also write field_<name>.gif with the chosen snapshots as frames.
        #[arg(long)]
        animate: bool,
        /// Picture format.
        #[arg(long, value_enum, default_value = "png")]
        format: PlotFormat,
    },
    /// Throughput benchmark on a generated N x N block (no contact), with the full step over the
    /// bare element-and-update loop and the cost of a contact pair, in the same run; and, with
    /// --scene, contact scenes (pair, striker, pile) with and without their contact.
    Bench {
        /// Backend(s).
        #[arg(long, value_enum, default_value = "auto")]
        backend: BenchBackend,
        /// Scenes: the block (first table) and/or the contact scenes (second table).
        #[arg(long, value_enum, num_args = 1.., default_values_t = [BenchScene::Block])]
        scene: Vec<BenchScene>,
        /// Cells per side of the block scene (elements = N^2); several allowed.
        #[arg(long, num_args = 1.., default_values_t = [32usize, 100, 316, 1000])]
        cells: Vec<usize>,
        /// Element targets of the contact scenes (each mapped to the nearest size); several
        /// allowed.
        #[arg(long, num_args = 1.., default_values_t = [10_000usize, 100_000, 1_000_000])]
        elements: Vec<usize>,
        /// The pile with one [[contact]] per pair of disks instead of `bodies = "all"` (a
        /// fallback where that does not parse; small piles only).
        #[arg(long)]
        pile_pairs: bool,
        /// Also time each contact scene with this Coulomb coefficient on its contacts and walls
        /// (a third variant in the same rounds): what friction adds to a contact step.
        #[arg(long)]
        friction: Option<f64>,
        /// Steps timed per size.
        #[arg(long, default_value_t = 200)]
        steps: u64,
        /// Rounds the steps are split into, each variant timed in alternation (medians reported).
        #[arg(long, default_value_t = ricochet::bench::DEFAULT_ROUNDS)]
        rounds: u32,
        /// Steps each variant of a contact scene runs before the timed ones (at least 2, the
        /// first search): e.g. 600 to time the pile in contact (its disks reach the wall after
        /// about 440 steps).
        #[arg(long, default_value_t = ricochet::bench::DEFAULT_WARMUP)]
        warmup: u64,
        /// Time the contact scenes with plain projected Gauss-Seidel sweeps instead of the
        /// extrapolated ones (both backends): a comparison.
        #[arg(long)]
        plain_sweeps: bool,
        /// Also write the table(s) as JSON: the block rows as an array; with a contact scene,
        /// an object {"block": [...], "contact": [...]}.
        #[arg(long)]
        json: Option<PathBuf>,
        /// Adapter name (substring), also from WGPU_ADAPTER_NAME.
        #[arg(long)]
        adapter: Option<String>,
    },
    /// Validate a scene and print its plan.
    Check {
        /// Scene file (TOML).
        scene: PathBuf,
    },
    /// Run the verification suite (assets/verification/): error against wall time per case,
    /// method and backend; writes results.csv, report.md and one plot per case.
    Verify {
        /// The short ladders (a few minutes on a 2-core machine).
        #[arg(long)]
        quick: bool,
        /// Backend(s).
        #[arg(long, value_enum, default_value = "both")]
        backend: VerifyBackend,
        /// Output folder.
        #[arg(long, default_value = "out/verification")]
        out: PathBuf,
        /// Folder of case files to run instead of the built-in ones (those of
        /// assets/verification/, embedded in the binary).
        #[arg(long)]
        cases: Option<PathBuf>,
        /// Only these cases (by name); all when omitted.
        #[arg(long, num_args = 1..)]
        case: Vec<String>,
        /// Adapter name (substring), also from WGPU_ADAPTER_NAME.
        #[arg(long)]
        adapter: Option<String>,
    },
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum PlotFormat {
    /// PNG.
    Png,
    /// SVG.
    Svg,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum VerifyBackend {
    /// The f64 CPU reference.
    Cpu,
    /// The GPU (an adapter is required).
    Gpu,
    /// Both, in the same run (an adapter is required).
    Both,
}

/// Exit status for bad input.
const EXIT_INPUT: u8 = 2;
/// Exit status for a run that went unstable.
const EXIT_FAILED_RUN: u8 = 3;
/// Exit status of `verify` when a case misses its bound.
const EXIT_VERIFY_FAILED: u8 = 4;

fn main() -> ExitCode {
    // Output piped into a reader that stops early (`ricochet check scene.toml | head`): end
    // quietly on SIGPIPE, as command-line tools do, instead of panicking on the failed print.
    #[cfg(unix)]
    // SAFETY: restoring the default action of one signal before any thread starts.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    let cli = Cli::parse();
    match dispatch(cli) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e}");
            for cause in e.chain().skip(1) {
                eprintln!("  caused by: {cause}");
            }
            let input = e
                .downcast_ref::<ricochet::Error>()
                .map(|r| {
                    matches!(
                        r,
                        ricochet::Error::Read { .. }
                            | ricochet::Error::Parse { .. }
                            | ricochet::Error::Invalid { .. }
                            | ricochet::Error::Checkpoint(_)
                    )
                })
                .unwrap_or(false);
            ExitCode::from(if input { EXIT_INPUT } else { 1 })
        }
    }
}

fn load(path: &Path, end_time: Option<f64>) -> anyhow::Result<(Scene, Model, Plan)> {
    let mut scene = Scene::load(path)?;
    if let Some(t) = end_time {
        if !(t.is_finite() && t > 0.0) {
            return Err(ricochet::Error::Invalid {
                file: path.to_path_buf(),
                key: "--end-time".into(),
                value: format!("{t:?}"),
                reason: "must be a positive finite number".into(),
            }
            .into());
        }
        scene.run.end_time = t;
    }
    let (model, plan) = prepare(&scene)?;
    Ok((scene, model, plan))
}

/// The GPU solver of a scene on `ctx`, after checking that its buffers fit the adapter.
fn gpu_solver(
    ctx: GpuContext,
    scene: &Scene,
    model: &Model,
    plan: &Plan,
    schedule: ricochet::step::Schedule,
) -> anyhow::Result<Box<dyn Solver>> {
    let limits = ctx.device.limits();
    ricochet::run::check_gpu_limits(
        scene,
        model,
        &ctx.adapter_name(),
        limits.max_storage_buffer_binding_size,
        limits.max_buffer_size,
    )?;
    Ok(Box::new(GpuSolver::new(
        Arc::new(ctx),
        model,
        plan,
        schedule,
    )?))
}

/// The checks of a loaded scene, its model and its plan.
fn prepare(scene: &Scene) -> anyhow::Result<(Model, Plan)> {
    ricochet::run::check_memory(scene)?;
    let model = ricochet::run::model(scene)?;
    ricochet::run::check_limits(scene, &model)?;
    let plan = Plan::new(scene, &model);
    Ok((model, plan))
}

fn dispatch(cli: Cli) -> anyhow::Result<ExitCode> {
    match cli.command {
        Command::Bench {
            backend,
            scene,
            cells,
            elements,
            pile_pairs,
            friction,
            steps,
            rounds,
            warmup,
            plain_sweeps,
            json,
            adapter,
        } => {
            if rounds == 0 || steps == 0 {
                anyhow::bail!("--steps and --rounds must be positive");
            }
            let all = scene.contains(&BenchScene::All);
            let block = all || scene.contains(&BenchScene::Block);
            let contact_scenes: Vec<ricochet::bench::ContactScene> =
                ricochet::bench::ContactScene::ALL
                    .into_iter()
                    .filter(|c| {
                        all || scene.contains(&match c {
                            ricochet::bench::ContactScene::Pair => BenchScene::Pair,
                            ricochet::bench::ContactScene::Striker => BenchScene::Striker,
                            ricochet::bench::ContactScene::Pile => BenchScene::Pile,
                        })
                    })
                    .collect();
            if let Some(mu) = friction.filter(|mu| !(mu.is_finite() && *mu > 0.0)) {
                anyhow::bail!("--friction {mu}: must be a finite positive Coulomb coefficient");
            }
            if block && cells.contains(&0) {
                anyhow::bail!("--cells must be positive");
            }
            if !contact_scenes.is_empty() && elements.contains(&0) {
                anyhow::bail!("--elements must be positive");
            }
            // Sizes beyond the machine's memory: refused before anything runs, naming the option.
            let too_big = |key: &str, value: usize, scene: ricochet::Result<Scene>| match scene
                .and_then(|s| ricochet::run::check_memory(&s))
            {
                Err(ricochet::Error::Invalid {
                    key: inner,
                    value: v,
                    reason,
                    ..
                }) => Err(ricochet::Error::Invalid {
                    file: PathBuf::from("ricochet bench"),
                    key: key.into(),
                    value: value.to_string(),
                    reason: format!("the generated scene's `{inner}` = {v}: {reason}"),
                }),
                other => other,
            };
            if block {
                for &n in &cells {
                    too_big("--cells", n, ricochet::bench::contact_scene(n, true))?;
                }
            }
            for &which in &contact_scenes {
                for &target in &elements {
                    let scene = which.scene(
                        which.size_for(target),
                        true,
                        ricochet::bench::PileContact::All,
                    );
                    too_big("--elements", target, scene)?;
                }
            }
            let ctx = match backend {
                BenchBackend::Cpu => None,
                BenchBackend::Auto => GpuContext::new(adapter.as_deref()).ok().map(Arc::new),
                BenchBackend::Gpu | BenchBackend::Both => {
                    Some(Arc::new(GpuContext::new(adapter.as_deref())?))
                }
            };
            let run_cpu = matches!(
                backend,
                BenchBackend::Cpu | BenchBackend::Both | BenchBackend::Auto
            );
            let mut rows = Vec::new();
            if block {
                for &n in &cells {
                    if run_cpu {
                        rows.push(ricochet::bench::cpu(n, steps, rounds)?);
                        eprint!("{}", ricochet::bench::table(&rows[rows.len() - 1..]));
                    }
                    if let Some(ctx) = &ctx {
                        rows.push(ricochet::bench::gpu(ctx.clone(), n, steps, rounds)?);
                        eprint!("{}", ricochet::bench::table(&rows[rows.len() - 1..]));
                    }
                }
            }
            let pile = if pile_pairs {
                ricochet::bench::PileContact::Pairs
            } else {
                ricochet::bench::PileContact::All
            };
            let mut contact_rows = Vec::new();
            let mut push = |what: String, row: ricochet::Result<ricochet::bench::ContactRow>| {
                match row {
                    Ok(row) => {
                        eprint!(
                            "{}",
                            ricochet::bench::contact_table(std::slice::from_ref(&row))
                        );
                        contact_rows.push(row);
                    }
                    // A scene a backend cannot run (the GPU's body limit, `bodies = "all"` where
                    // it does not parse) is reported and skipped; the others go on.
                    Err(e) => eprintln!("{what}: skipped: {e}"),
                }
            };
            for &which in &contact_scenes {
                for &target in &elements {
                    let size = which.size_for(target);
                    let what = |backend: &str| {
                        format!(
                            "{} {backend} {} elements",
                            which.name(),
                            which.elements(size)
                        )
                    };
                    let timing = ricochet::bench::ContactTiming {
                        steps,
                        rounds,
                        warmup,
                        pile,
                        friction,
                        plain_sweeps,
                    };
                    if let (true, Some(ctx)) = (run_cpu, &ctx) {
                        // Both backends in the same alternating rounds (the GPU row's ratio to
                        // the CPU's); where that fails (a scene the GPU cannot run), apart.
                        match ricochet::bench::both_contact(ctx.clone(), which, size, &timing) {
                            Ok(rows) => {
                                for row in rows {
                                    let backend = row.backend.clone();
                                    push(what(&backend), Ok(row));
                                }
                                continue;
                            }
                            Err(e) => {
                                eprintln!("{}: the CPU and GPU apart: {e}", what("cpu and gpu"))
                            }
                        }
                    }
                    if run_cpu {
                        let row = ricochet::bench::cpu_contact(which, size, &timing);
                        push(what("cpu"), row);
                    }
                    if let Some(ctx) = &ctx {
                        let row = ricochet::bench::gpu_contact(ctx.clone(), which, size, &timing);
                        push(what("gpu"), row);
                    }
                }
            }
            if block {
                println!("{}", ricochet::bench::table(&rows));
                print!("{}", ricochet::bench::summary(&rows));
            }
            if !contact_rows.is_empty() {
                if block {
                    println!();
                }
                print!("{}", ricochet::bench::contact_table(&contact_rows));
            }
            if let Some(path) = json {
                let text = if contact_scenes.is_empty() {
                    serde_json::to_string_pretty(&rows)?
                } else {
                    serde_json::to_string_pretty(
                        &serde_json::json!({ "block": rows, "contact": contact_rows }),
                    )?
                };
                std::fs::write(&path, text)
                    .with_context(|| format!("writing {}", path.display()))?;
            }
            Ok(ExitCode::SUCCESS)
        }
        Command::Verify {
            quick,
            backend,
            out,
            cases,
            case,
            adapter,
        } => {
            let opts = ricochet::verify::Options {
                quick,
                cpu: backend != VerifyBackend::Gpu,
                gpu: backend != VerifyBackend::Cpu,
                cases,
                only: case,
                out,
                adapter: adapter.or_else(|| std::env::var("WGPU_ADAPTER_NAME").ok()),
            };
            let outcome = ricochet::verify::verify(&opts, |line| eprintln!("{line}"))?;
            println!(
                "verify: {} cases, {} runs, report {}",
                outcome.cases.len(),
                outcome
                    .rows
                    .iter()
                    .map(|r| (&r.case, &r.method, &r.backend, r.level))
                    .collect::<std::collections::BTreeSet<_>>()
                    .len(),
                opts.out.join("report.md").display()
            );
            if outcome.failures.is_empty() {
                println!("all cases pass their bounds");
                Ok(ExitCode::SUCCESS)
            } else {
                for f in &outcome.failures {
                    println!("FAILED {f}");
                }
                Ok(ExitCode::from(EXIT_VERIFY_FAILED))
            }
        }
        Command::Check { scene } => {
            let (scene, model, plan) = load(&scene, None)?;
            check(&scene, model, &plan)?;
            Ok(ExitCode::SUCCESS)
        }
        Command::Run {
            scene,
            backend,
            out,
            end_time,
            adapter,
            plots,
            checkpoint_interval,
            restart,
        } => {
            let resume = match &restart {
                Some(dir) => Some(ricochet::checkpoint::Checkpoint::read(dir)?),
                None => None,
            };
            let (scene, model, plan, out, checkpointing) = match (&resume, scene) {
                (Some(c), _) => {
                    let scene = c.scene()?;
                    let (model, plan) = prepare(&scene)?;
                    let out = restart.clone().unwrap_or_default();
                    let checkpointing = ricochet::checkpoint::Checkpointing {
                        interval: c.interval,
                        scene_path: c.scene_path.clone(),
                        scene_text: c.scene_text.clone(),
                        end_time_override: c.end_time_override,
                    };
                    println!(
                        "restarting {} from its checkpoint at step {}, t = {:e} s ({} backend)",
                        scene.file.display(),
                        c.steps,
                        c.time,
                        c.backend
                    );
                    (scene, model, plan, out, Some(checkpointing))
                }
                (None, Some(path)) => {
                    let (scene, model, plan) = load(&path, end_time)?;
                    let out = out.unwrap_or_else(|| PathBuf::from("out").join(&scene.name));
                    let interval = checkpoint_interval.or(scene.run.checkpoint_interval);
                    let checkpointing = match interval {
                        Some(t) if !(t.is_finite() && t > 0.0) => {
                            return Err(ricochet::Error::Invalid {
                                file: path.clone(),
                                key: "--checkpoint-interval".into(),
                                value: format!("{t:?}"),
                                reason: "must be a positive finite number of seconds".into(),
                            }
                            .into())
                        }
                        Some(t) => Some(ricochet::checkpoint::Checkpointing {
                            interval: t,
                            scene_path: path.clone(),
                            // Loaded just above, so readable and at most SCENE_MAX_BYTES.
                            scene_text: std::fs::read_to_string(&path).map_err(|source| {
                                ricochet::Error::Read {
                                    file: path.clone(),
                                    source,
                                }
                            })?,
                            end_time_override: end_time,
                        }),
                        None => None,
                    };
                    (scene, model, plan, out, checkpointing)
                }
                (None, None) => anyhow::bail!("a scene file or --restart DIR is required"),
            };
            // A restart continues on the checkpoint's backend.
            let backend = match resume.as_ref().map(|c| c.backend.as_str()) {
                Some("cpu") => Backend::Cpu,
                Some(_) => Backend::Gpu,
                None => backend,
            };
            let schedule = ricochet::run::schedule(&scene);
            let cpu = || -> Box<dyn Solver> {
                Box::new(CpuSolver::new(model.clone(), plan.clone(), schedule))
            };
            let mut solver: Box<dyn Solver> = match backend {
                Backend::Cpu => cpu(),
                Backend::Auto => match GpuContext::new(adapter.as_deref()) {
                    Ok(ctx) if ctx.is_software() && !adapter_named(adapter.as_deref()) => {
                        eprintln!(
                            "notice: the only GPU adapter is a software one ({}): running on the \
                             CPU reference, which is faster here (--backend gpu uses the adapter)",
                            ctx.adapter_name()
                        );
                        cpu()
                    }
                    Ok(ctx) => gpu_solver(ctx, &scene, &model, &plan, schedule)?,
                    Err(e) => {
                        eprintln!("notice: {e}; running on the CPU");
                        cpu()
                    }
                },
                Backend::Gpu => {
                    let ctx = GpuContext::new(adapter.as_deref())?;
                    gpu_solver(ctx, &scene, &model, &plan, schedule)?
                }
            };
            if let Some(c) = resume.as_ref().filter(|c| c.adapter != solver.adapter()) {
                eprintln!(
                    "notice: the checkpoint was written on {}, this run is on {}: the run \
                     continues, but its results may differ in the last bits from the run that was \
                     never stopped",
                    c.adapter,
                    solver.adapter()
                );
            }
            let signals = Signals::register()?;
            let bar = progress_bar();
            let mut tick = |t: f64, end: f64, steps: u64| {
                if let Some(b) = &bar {
                    b.set_position((t / end * 10_000.0).min(10_000.0) as u64);
                    b.set_message(format!("t = {t:.4e} s, {steps} steps"));
                }
                signals
                    .caught()
                    .map(|(name, _)| format!("interrupted by {name}"))
            };
            let result = ricochet::run::run_with(
                &scene,
                &model,
                &plan,
                solver.as_mut(),
                &out,
                Some(&mut tick),
                ricochet::run::RunOptions {
                    checkpointing,
                    resume,
                },
            )
            .with_context(|| format!("running {}", scene.file.display()))?;
            if let Some(b) = bar {
                b.finish_and_clear();
            }
            let s = &result.summary;
            println!(
                "{}: {} on {} ({}): {} steps to t = {:.4e} s in {:.2} s ({:.3e} element-cycles/s), max energy error {:.2e}; outputs in {}",
                s.scene,
                s.status,
                s.backend,
                s.adapter,
                s.steps,
                s.end_time,
                s.wall_seconds,
                s.element_cycles_per_second,
                s.max_energy_error,
                out.display()
            );
            if s.contact_searches > 0 {
                println!(
                    "contact: {} broad-phase searches in {} steps",
                    s.contact_searches, s.steps
                );
                if s.contact_penalty_bounded > 0 {
                    println!(
                        "contact: {} penalty impulses bounded by the perfectly plastic impulse \
                         (springs stiff for the step, omega dt > 1, as in an impact's first steps): \
                         the spring energy they held is lost (in contact_energy)",
                        s.contact_penalty_bounded
                    );
                }
                if s.steps >= 20 && 2 * s.contact_searches > s.steps {
                    eprintln!(
                        "warning: contact nodes moved more than half the search margin in most steps, \
                         so the search ran (almost) every step instead of every few: the margin is half \
                         the shortest contact edge; fast impacts on fine surfaces cost a search per step"
                    );
                }
            }
            if s.status == "interrupted" {
                eprintln!(
                    "{}; history, fields and summary.json are complete up to there",
                    s.message
                );
                let code = signals.caught().map(|(_, code)| code).unwrap_or(1);
                return Ok(ExitCode::from(code));
            }
            let failed = s.status != "completed";
            if failed {
                eprintln!("error: {}", s.message);
            }
            if plots {
                draw(&out, &ricochet::plot::PlotOptions::default())?;
            }
            Ok(ExitCode::from(if failed { EXIT_FAILED_RUN } else { 0 }))
        }
        Command::Plot {
            out,
            field,
            times,
            range,
            animate,
            format,
        } => {
            let opts = ricochet::plot::PlotOptions {
                field: field
                    .as_deref()
                    .and_then(ricochet::plot::field::Field::parse),
                times,
                range: range.map(|r| (r[0], r[1])),
                animate,
                format: match format {
                    PlotFormat::Png => ricochet::plot::Format::Png,
                    PlotFormat::Svg => ricochet::plot::Format::Svg,
                },
            };
            draw(&out, &opts)?;
            Ok(ExitCode::SUCCESS)
        }
    }
}

/// SIGINT and SIGTERM during a run: each sets a flag that the run checks after every batch of
/// steps (it then flushes the history and writes `summary.json` with status "interrupted"); a
/// second signal of the same kind ends the process at once.
struct Signals {
    int: Arc<std::sync::atomic::AtomicBool>,
    term: Arc<std::sync::atomic::AtomicBool>,
}

impl Signals {
    fn register() -> anyhow::Result<Self> {
        use signal_hook::consts::{SIGINT, SIGTERM};
        use signal_hook::flag;
        let int = Arc::new(std::sync::atomic::AtomicBool::new(false));
        let term = Arc::new(std::sync::atomic::AtomicBool::new(false));
        for (sig, f, code) in [(SIGINT, &int, 130), (SIGTERM, &term, 143)] {
            // Order matters: the conditional shutdown sees the flag set by the first signal.
            flag::register_conditional_shutdown(sig, code, Arc::clone(f))?;
            flag::register(sig, Arc::clone(f))?;
        }
        Ok(Self { int, term })
    }

    /// The signal caught, if any: (name, exit status 128 + number).
    fn caught(&self) -> Option<(&'static str, u8)> {
        use std::sync::atomic::Ordering::Relaxed;
        if self.int.load(Relaxed) {
            Some(("SIGINT", 130))
        } else if self.term.load(Relaxed) {
            Some(("SIGTERM", 143))
        } else {
            None
        }
    }
}

/// Whether the user named an adapter (`--adapter` or `WGPU_ADAPTER_NAME`).
fn adapter_named(adapter: Option<&str>) -> bool {
    adapter.is_some_and(|a| !a.is_empty())
        || std::env::var("WGPU_ADAPTER_NAME").is_ok_and(|a| !a.is_empty())
}

/// Draws the pictures of the run in `out` and says where they went.
fn draw(out: &Path, opts: &ricochet::plot::PlotOptions) -> anyhow::Result<()> {
    let t0 = std::time::Instant::now();
    let report = ricochet::plot::plot(out, opts)?;
    for note in &report.notes {
        eprintln!("note: {note}");
    }
    let field = match (report.field, report.range) {
        (Some(f), Some((lo, hi))) => format!(
            ", {} {} pictures on [{lo:.4e}, {hi:.4e}]{}",
            report.pictures.len(),
            f.name(),
            if report.gif_frames > 0 {
                format!(" and a GIF of {} frames", report.gif_frames)
            } else {
                String::new()
            }
        ),
        _ => String::new(),
    };
    println!(
        "plots: {} files in {}{field} ({:.2} s)",
        report.files.len(),
        report.dir.display(),
        t0.elapsed().as_secs_f64()
    );
    Ok(())
}

fn progress_bar() -> Option<indicatif::ProgressBar> {
    if !std::io::stderr().is_terminal() {
        return None;
    }
    let bar = indicatif::ProgressBar::new(10_000);
    let style = indicatif::ProgressStyle::with_template(
        "{bar:40} {percent:>3}% {msg} [{per_sec}, ETA {eta}]",
    )
    .ok()?;
    bar.set_style(style);
    Some(bar)
}

fn check(scene: &Scene, model: Model, plan: &Plan) -> anyhow::Result<()> {
    let schedule = ricochet::run::schedule(scene);
    let mut contact = ricochet::contact::ContactSet::new(&model);
    let solver = CpuSolver::new(model, plan.clone(), schedule);
    let model = solver.model();
    let (dt_element, e) = solver.stable_step();
    let dt = contact
        .as_ref()
        .map_or(dt_element, |c| c.limit_step(dt_element));
    let step = scene
        .run
        .time_step
        .unwrap_or(scene.run.time_step_scale * dt);
    if let Some(fixed) = scene.run.time_step {
        if fixed > dt {
            return Err(ricochet::Error::Invalid {
                file: scene.file.clone(),
                key: "run.time_step".into(),
                value: format!("{fixed:e}"),
                reason: format!("exceeds the stable step {dt:e} (set by element {e})"),
            }
            .into());
        }
    }
    let steps = (scene.run.end_time / step).ceil() as u64;
    println!("scene      {} ({})", scene.name, scene.file.display());
    println!(
        "model      {} nodes, {} elements, {} bodies, {} constrained nodes",
        plan.nodes,
        plan.elements,
        model.bodies.len(),
        plan.constrained_nodes
    );
    for b in &model.bodies {
        println!(
            "  body     {:<16} {} nodes, {} elements, mass {:.6e} kg, c_d {:.1} m/s, hourglass {:?}",
            b.name,
            b.nodes.len(),
            b.elements.len(),
            b.mass,
            b.params.dilatational_speed(),
            b.params.hourglass
        );
        if let Some(ricochet::scene::MeshSpec::Gmsh { file, group, mesh }) = scene
            .bodies
            .iter()
            .find(|sb| sb.name == b.name)
            .map(|sb| &sb.mesh)
        {
            let tris = mesh.triangles();
            println!(
                "           Gmsh {} group `{group}`: {} quads (4-node), {tris} triangles (3-node), {} nodes{}",
                file.display(),
                mesh.quads.len() - tris,
                mesh.nodes.len(),
                if mesh.reoriented > 0 {
                    format!(", {} turned counter-clockwise", mesh.reoriented)
                } else {
                    String::new()
                }
            );
            if let Some((i, area, edge)) = mesh.smallest() {
                println!(
                    "           smallest element: Gmsh tag {}, area {area:.4e} m^2, shortest edge {edge:.4e} m",
                    mesh.element_tags[i]
                );
            }
        }
        if b.params.formulation == ricochet::scene::Formulation::Axisymmetric {
            println!("           axisymmetric (x = r; masses, forces and energies per radian)");
        }
        if b.params.model == ricochet::scene::MaterialModel::J2Plastic {
            let p = &b.params;
            if p.jc_b != 0.0 || p.jc_c != 0.0 {
                println!(
                    "           J2 plastic, Johnson-Cook: a {:e} Pa, b {:e} Pa, n {}, c {}, reference strain rate {:e} 1/s",
                    p.yield_stress, p.jc_b, p.jc_n, p.jc_c, p.jc_rate0
                );
            } else {
                println!(
                    "           J2 plastic: yield stress {:e} Pa, hardening modulus {:e} Pa",
                    p.yield_stress, p.hardening
                );
            }
        }
    }
    println!(
        "time step  stable {dt:.4e} s (element {e}); step {step:.4e} s; about {steps} steps to {:e} s",
        scene.run.end_time
    );
    if let Some(c) = contact.as_mut() {
        let groups: Vec<&ricochet::scene::Contact> =
            model.contacts.iter().filter(|c| c.group).collect();
        let mut group_bodies: Vec<usize> = groups.iter().flat_map(|c| c.bodies.clone()).collect();
        group_bodies.sort_unstable();
        group_bodies.dedup();
        let self_bodies: usize = groups
            .iter()
            .filter(|c| c.self_contact)
            .map(|c| c.bodies.len())
            .sum();
        let names = c.names();
        println!(
            "contact    {} contact tables ({} pairs, {} groups over {} bodies, self-contact on {}), \
             {} walls{}; search margin {:.4e} m",
            plan.contacts,
            plan.contacts - groups.len(),
            groups.len(),
            group_bodies.len(),
            self_bodies,
            plan.walls,
            if names.len() <= 8 {
                format!(": {}", names.join(", "))
            } else {
                String::new()
            },
            c.margin()
        );
        // How the tables and walls enforce contact (counts per method, in the scene's words).
        let mut methods: Vec<(&str, usize)> = Vec::new();
        for m in model
            .contacts
            .iter()
            .map(|c| c.method)
            .chain(model.walls.iter().map(|w| w.method))
        {
            match methods.iter_mut().find(|(w, _)| *w == m.word()) {
                Some((_, n)) => *n += 1,
                None => methods.push((m.word(), 1)),
            }
        }
        let methods: Vec<String> = methods.iter().map(|(w, n)| format!("{w} {n}")).collect();
        println!("  methods  {}", methods.join(", "));
        let rates: Vec<String> = model
            .contacts
            .iter()
            .map(|c| (&c.name, c.method, c.augmentation_rate))
            .chain(
                model
                    .walls
                    .iter()
                    .map(|w| (&w.name, w.method, w.augmentation_rate)),
            )
            .filter(|(_, m, _)| *m == ricochet::scene::ContactMethod::AugmentedLagrange)
            .map(|(n, _, r)| format!("{n} {r} /s"))
            .collect();
        if !rates.is_empty() {
            println!(
                "  augment  {} (the multipliers' update rate, below run.mass_damping = {} /s)",
                rates.join(", "),
                scene.run.mass_damping
            );
        }
        match c.penalty_step() {
            Some((dp, what)) => println!(
                "  penalty  {what} alone allows {dp:.4e} s; with the elements {dt:.4e} s: {}",
                if dt < 0.99 * dt_element {
                    format!("it controls dt (element step {dt_element:.4e} s)")
                } else {
                    "the elements control dt".to_string()
                }
            ),
            None => {
                let mass_form = model
                    .contacts
                    .iter()
                    .map(|c| (c.method, c.penalty_form))
                    .chain(model.walls.iter().map(|w| (w.method, w.penalty_form)))
                    .any(|(m, f)| m.has_springs() && f == ricochet::scene::PenaltyForm::Mass);
                if mass_form {
                    println!(
                        "  penalty  mass form k = s m* / dt^2 at dt = {:.4e} s: no effect on the stable step",
                        model.initial_step()
                    );
                } else {
                    println!("  lagrange no effect on the stable step");
                }
            }
        }
        let friction: Vec<String> = model
            .contacts
            .iter()
            .map(|c| (&c.name, c.friction, c.method, c.friction_stiffness))
            .chain(
                model
                    .walls
                    .iter()
                    .map(|w| (&w.name, w.friction, w.method, w.friction_stiffness)),
            )
            .filter(|(_, mu, _, _)| *mu > 0.0)
            .map(|(n, mu, m, kt)| {
                let how = match m {
                    ricochet::scene::ContactMethod::Lagrange => "lagrange".to_string(),
                    ricochet::scene::ContactMethod::Penalty => {
                        format!("penalty, regularized, k_t = {kt} k")
                    }
                    // Refused by the scene reader (normal multipliers only).
                    m @ (ricochet::scene::ContactMethod::PerturbedLagrange
                    | ricochet::scene::ContactMethod::AugmentedLagrange) => m.word().to_string(),
                };
                format!("{n} mu = {mu} ({how})")
            })
            .collect();
        if !friction.is_empty() {
            println!("  friction Coulomb: {}", friction.join(", "));
        }
        let overlaps = &model.initial_overlaps;
        if overlaps.is_empty() {
            println!("  overlaps none at t = 0");
        }
        for o in overlaps.iter().take(20) {
            println!(
                "  overlap  {}: node {} penetrated {:.4e} m at t = 0; moved onto the surface (no strain)",
                o.interface, o.node, o.depth
            );
        }
        if overlaps.len() > 20 {
            println!("  overlap  ... {} in all", overlaps.len());
        }
    }
    for c in model.contacts.iter().filter(|c| c.surfaces.is_some()) {
        if let Some(faces) = &c.surfaces {
            let named: Vec<String> = faces
                .iter()
                .zip(&c.bodies)
                .map(|((name, edges), &b)| {
                    format!(
                        "`{name}` of {} ({} edges)",
                        model.bodies[b].name,
                        edges.len()
                    )
                })
                .collect();
            println!("  faces    {}: {}", c.name, named.join(" against "));
        }
    }
    for b in &scene.boundaries {
        let curve = |c: &Option<ricochet::scene::LoadCurve>, axis: &str| {
            c.as_ref().map(|c| {
                let last = c.points.last().copied().unwrap_or([0.0; 2]);
                format!(
                    ", v{axis} a load curve of {} points ({:e} m/s from {:e} s)",
                    c.points.len(),
                    last[1],
                    last[0]
                )
            })
        };
        let curves = [curve(&b.curve_x, "x"), curve(&b.curve_y, "y")]
            .into_iter()
            .flatten()
            .collect::<String>();
        let group = b
            .group
            .as_ref()
            .map(|g| format!(" on group `{}` ({} nodes)", g.name, g.nodes.len()));
        if group.is_some() || !curves.is_empty() {
            println!("boundary   {}{}{curves}", b.key, group.unwrap_or_default());
        }
    }
    for (i, p) in model.pressures.iter().enumerate() {
        let ramp = match (&p.curve, p.ramp) {
            (Some(c), _) => format!(
                ", a load curve of {} points ({:e} Pa from {:e} s)",
                c.points.len(),
                c.points.last().map_or(0.0, |q| q[1]),
                c.points.last().map_or(0.0, |q| q[0])
            ),
            (None, Some(r)) => format!(", ramped over {r:e} s"),
            (None, None) => String::new(),
        };
        println!(
            "pressure   pressure[{i}]: {:e} Pa on {} edges ({} nodes){ramp}",
            p.value,
            p.edges,
            p.nodes.len()
        );
    }
    if model.gravity != [0.0; 2] {
        println!(
            "gravity    [{:e}, {:e}] m/s^2 on every node{}",
            model.gravity[0],
            model.gravity[1],
            if model.gravity_ramp > 0.0 {
                format!(", ramped in over {:e} s", model.gravity_ramp)
            } else {
                String::new()
            }
        );
    }
    if model.mass_damping > 0.0 {
        println!(
            "damping    mass-proportional, alpha = {:e} 1/s (critical for the mode omega = {:e} rad/s)",
            model.mass_damping,
            0.5 * model.mass_damping
        );
    }
    let bytes_cpu = ricochet::run::memory_estimate(scene);
    let have = ricochet::run::available_memory()
        .map(|b| format!(" of {:.1} MiB available", b as f64 / 1048576.0))
        .unwrap_or_default();
    println!(
        "memory     about {:.1} MiB (CPU reference peak, from {} + {} bytes per element with \
         fields){have}",
        bytes_cpu as f64 / 1048576.0,
        ricochet::run::BYTES_PER_ELEMENT,
        ricochet::run::FIELD_BYTES_PER_ELEMENT
    );
    let r = &scene.run;
    let mut outputs = format!(
        "history every {:e} s (about {:.0} rows)",
        r.history_interval,
        (r.end_time / r.history_interval).floor() + 1.0
    );
    if let Some(f) = r.field_interval {
        let format = match r.field_format {
            ricochet::scene::FieldFormat::Binary => "binary VTU, Float32, zlib",
            ricochet::scene::FieldFormat::Binary64 => "binary VTU, Float64, zlib",
            ricochet::scene::FieldFormat::Ascii => "ASCII VTU",
        };
        outputs.push_str(&format!(
            ", fields every {f:e} s (about {:.0} snapshots, {format})",
            (r.end_time / f).floor() + 1.0
        ));
    }
    if let Some(c) = r.checkpoint_interval {
        outputs.push_str(&format!(", a checkpoint every {c:e} s"));
    }
    println!("outputs    {outputs}");
    println!("plan       {plan}");
    Ok(())
}
