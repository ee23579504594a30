//! A run as `ricochet run` makes it, for any front end (the command line, `src/cli/run.rs`, and
//! whatever else runs scenes: many runs of one scene, a binding running one in-process): a
//! [`RunRequest`] (a scene file, or a checkpoint to continue, with a [`Backend`] and an adapter)
//! is loaded and checked into a [`Prepared`] run; that builds its solver as `--backend
//! auto|cpu|gpu --adapter NAME` does ([`choose_solver`]) and runs it into its output folder with
//! checkpoints, stopped by an [`Interrupt`] and reporting progress to a callback, to a
//! [`RunOutcome`]. Nothing here prints: notices go to a callback. [`execute`] is the three steps
//! in one call.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use crate::checkpoint::{Checkpoint, Checkpointing};
use crate::error::{Error, Result};
use crate::gpu::{GpuContext, GpuSolver};
use crate::model::Model;
use crate::plan::Plan;
use crate::scene::Scene;
use crate::step::cpu::CpuSolver;
use crate::step::{Schedule, Solver};

use super::{
    check_gpu_limits, check_limits, check_memory, run_with, schedule, Interrupt, RunOptions,
    RunResult,
};

/// Where a run's solver runs (`ricochet run --backend`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Backend {
    /// The GPU when a hardware adapter exists (or the adapter is named, by the request or by
    /// `WGPU_ADAPTER_NAME`), else the CPU reference, with a notice: a software adapter such as
    /// Mesa lavapipe is slower than the CPU reference.
    #[default]
    Auto,
    /// The f64 CPU reference.
    Cpu,
    /// The GPU; an error when no adapter exists.
    Gpu,
}

/// What a run starts from.
#[derive(Debug, Clone)]
pub enum Start {
    /// A scene file (`ricochet run SCENE`).
    Scene {
        /// The scene file (TOML).
        path: PathBuf,
        /// Overrides `run.end_time` (`--end-time`).
        end_time: Option<f64>,
        /// Output folder (`--out`); `out/<scene name>` when `None`.
        out: Option<PathBuf>,
        /// Overrides `run.checkpoint_interval` (`--checkpoint-interval`).
        checkpoint_interval: Option<f64>,
    },
    /// The run whose output folder holds a `checkpoint.bin`, continued into that folder on the
    /// checkpoint's backend, with its scene, end time and checkpoint interval (`--restart DIR`).
    Restart(PathBuf),
}

/// A run to make: what it starts from, and where its solver runs.
#[derive(Debug, Clone)]
pub struct RunRequest {
    /// The scene file or the checkpoint.
    pub start: Start,
    /// The backend (a restart takes its checkpoint's instead).
    pub backend: Backend,
    /// The adapter, by a substring of its name; `None` leaves the choice to
    /// `WGPU_ADAPTER_NAME`, then to [`GpuContext::new`].
    pub adapter: Option<String>,
}

impl RunRequest {
    /// A run of the scene file `path` as the scene says, on [`Backend::Auto`].
    pub fn scene(path: impl Into<PathBuf>) -> Self {
        Self {
            start: Start::Scene {
                path: path.into(),
                end_time: None,
                out: None,
                checkpoint_interval: None,
            },
            backend: Backend::Auto,
            adapter: None,
        }
    }

    /// The run whose checkpoint is in the output folder `dir`, continued there.
    pub fn restart(dir: impl Into<PathBuf>) -> Self {
        Self {
            start: Start::Restart(dir.into()),
            backend: Backend::Auto,
            adapter: None,
        }
    }

    /// Loads and checks the scene (or the checkpoint and its scene), its model and plan, and
    /// the output folder and checkpointing of the run.
    ///
    /// # Errors
    /// [`Error::Read`], [`Error::Parse`] or [`Error::Invalid`] for a scene that cannot be read or
    /// is refused (an `end_time` or `checkpoint_interval` not positive and finite included);
    /// [`Error::Checkpoint`] for a checkpoint that cannot be continued.
    pub fn prepare(&self) -> Result<Prepared> {
        match &self.start {
            Start::Restart(dir) => {
                let resume = Checkpoint::read(dir)?;
                let scene = resume.scene(dir)?;
                let (model, plan) = model_and_plan(&scene)?;
                let checkpointing = Checkpointing {
                    interval: resume.interval,
                    scene_path: resume.scene_path.clone(),
                    scene_text: resume.scene_text.clone(),
                    end_time_override: resume.end_time_override,
                };
                // A restart continues on the checkpoint's backend.
                let backend = if resume.backend == "cpu" {
                    Backend::Cpu
                } else {
                    Backend::Gpu
                };
                Ok(Prepared {
                    scene,
                    model,
                    plan,
                    out: dir.clone(),
                    checkpointing: Some(checkpointing),
                    resume: Some(resume),
                    backend,
                    adapter: self.adapter.clone(),
                })
            }
            Start::Scene {
                path,
                end_time,
                out,
                checkpoint_interval,
            } => {
                // The text is read once: the scene run and the one a checkpoint keeps are the
                // same.
                let text = Scene::read_text(path)?;
                let (scene, model, plan) = load_text(&text, path, *end_time)?;
                let out = out
                    .clone()
                    .unwrap_or_else(|| PathBuf::from("out").join(&scene.name));
                let checkpointing = match checkpoint_interval.or(scene.run.checkpoint_interval) {
                    Some(t) if !(t.is_finite() && t > 0.0) => {
                        return Err(Error::Invalid {
                            file: path.clone(),
                            key: "--checkpoint-interval".into(),
                            value: format!("{t:?}"),
                            reason: "must be a positive finite number of seconds".into(),
                        })
                    }
                    Some(t) => Some(Checkpointing {
                        interval: t,
                        scene_path: path.clone(),
                        scene_text: text,
                        end_time_override: *end_time,
                    }),
                    None => None,
                };
                Ok(Prepared {
                    scene,
                    model,
                    plan,
                    out,
                    checkpointing,
                    resume: None,
                    backend: self.backend,
                    adapter: self.adapter.clone(),
                })
            }
        }
    }
}

/// A run loaded and checked, ready for its solver ([`Prepared::solver`]) and its time loop
/// ([`Prepared::run`]).
#[derive(Debug, Clone)]
pub struct Prepared {
    /// The scene (with the end-time override applied).
    pub scene: Scene,
    /// Its model, overlaps at t = 0 resolved.
    pub model: Model,
    /// Its plan.
    pub plan: Plan,
    /// The output folder.
    pub out: PathBuf,
    /// Checkpoints to write, if any.
    pub checkpointing: Option<Checkpointing>,
    /// The checkpoint the run continues from, on a restart.
    pub resume: Option<Checkpoint>,
    /// The backend (the checkpoint's on a restart).
    pub backend: Backend,
    /// The adapter asked for.
    pub adapter: Option<String>,
}

impl Prepared {
    /// The solver of the run on its backend ([`choose_solver`]); on a restart on another adapter
    /// than the checkpoint's, a notice that the results may differ in the last bits.
    ///
    /// # Errors
    /// As [`choose_solver`].
    pub fn solver(&self, notice: &mut dyn FnMut(&str)) -> Result<Box<dyn Solver>> {
        let solver = choose_solver(
            self.backend,
            self.adapter.as_deref(),
            &self.scene,
            &self.model,
            &self.plan,
            notice,
        )?;
        if let Some(c) = self
            .resume
            .as_ref()
            .filter(|c| c.adapter != solver.adapter())
        {
            notice(&format!(
                "the checkpoint was written on {}, this run is on {}: the run \
                 continues, but its results may differ in the last bits from the run that was \
                 never stopped",
                c.adapter,
                solver.adapter()
            ));
        }
        Ok(solver)
    }

    /// Runs `solver` (from [`Prepared::solver`]) into the output folder ([`super::run_with`]
    /// with the checkpointing and resume of the request). After every batch of steps it calls
    /// `progress` with (simulated time, end time, steps), then reads `interrupt`: a flag set
    /// there stops the run as interrupted by that flag's cause.
    ///
    /// # Errors
    /// As [`super::run_with`]. A run that goes unstable or is interrupted is not an error: see
    /// [`RunOutcome::ending`].
    pub fn run(
        self,
        solver: &mut dyn Solver,
        interrupt: &Interrupt,
        progress: &mut dyn FnMut(f64, f64, u64),
    ) -> Result<RunOutcome> {
        let mut cause = None;
        let mut tick = |t: f64, end: f64, steps: u64| {
            progress(t, end, steps);
            interrupt.caught().map(|c| {
                cause = Some(c.to_string());
                format!("interrupted by {c}")
            })
        };
        let result = run_with(
            &self.scene,
            &self.model,
            &self.plan,
            solver,
            &self.out,
            Some(&mut tick),
            RunOptions {
                checkpointing: self.checkpointing,
                resume: self.resume,
            },
        )?;
        let ending = match result.summary.status.as_str() {
            "completed" => Ending::Completed,
            "interrupted" => Ending::Interrupted(cause.unwrap_or_default()),
            _ => Ending::Failed(result.summary.message.clone()),
        };
        Ok(RunOutcome { ending, result })
    }
}

/// How a run ended.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Ending {
    /// It reached its end time.
    Completed,
    /// It went unstable: the message names the step, the time and the cause (as `summary.json`).
    Failed(String),
    /// An [`Interrupt`] flag stopped it: the cause that flag was made with (e.g. `"SIGINT"`).
    Interrupted(String),
}

/// What a run ended with: how, and its summary, samples and output folder.
#[derive(Debug, Clone)]
pub struct RunOutcome {
    /// How it ended.
    pub ending: Ending,
    /// The summary (also in `summary.json`), the history samples and the output folder.
    pub result: RunResult,
}

/// A whole run in one call, printing nothing: [`RunRequest::prepare`], [`Prepared::solver`]
/// (notices to `notice`) and [`Prepared::run`].
///
/// # Errors
/// As those three.
pub fn execute(
    request: &RunRequest,
    interrupt: &Interrupt,
    notice: &mut dyn FnMut(&str),
    progress: &mut dyn FnMut(f64, f64, u64),
) -> Result<RunOutcome> {
    let prepared = request.prepare()?;
    let mut solver = prepared.solver(notice)?;
    prepared.run(solver.as_mut(), interrupt, progress)
}

/// Loads the scene file `path`, with `run.end_time` set to `end_time` when given, and its model
/// and plan ([`model_and_plan`]).
///
/// # Errors
/// As [`Scene::load`] and [`model_and_plan`]; [`Error::Invalid`] for an `end_time` that is not
/// positive and finite (named `--end-time`).
pub fn load(path: &Path, end_time: Option<f64>) -> Result<(Scene, Model, Plan)> {
    load_text(&Scene::read_text(path)?, path, end_time)
}

/// [`load`] of the scene text `text` read from `path`.
fn load_text(text: &str, path: &Path, end_time: Option<f64>) -> Result<(Scene, Model, Plan)> {
    let mut scene = Scene::parse(text, path)?;
    if let Some(t) = end_time {
        if !(t.is_finite() && t > 0.0) {
            return Err(Error::Invalid {
                file: path.to_path_buf(),
                key: "--end-time".into(),
                value: format!("{t:?}"),
                reason: "must be a positive finite number".into(),
            });
        }
        scene.run.end_time = t;
    }
    let (model, plan) = model_and_plan(&scene)?;
    Ok((scene, model, plan))
}

/// The checked model and plan of a loaded scene: its memory ([`check_memory`], before meshing),
/// its model ([`super::model`]) and its steps, rows and snapshots ([`check_limits`]).
///
/// # Errors
/// [`Error::Invalid`] from those checks and from the model.
pub fn model_and_plan(scene: &Scene) -> Result<(Model, Plan)> {
    check_memory(scene)?;
    let model = super::model(scene)?;
    check_limits(scene, &model)?;
    let plan = Plan::new(scene, &model);
    Ok((model, plan))
}

/// The solver of a scene on `backend`, as `ricochet run --backend` chooses it: on
/// [`Backend::Auto`], the GPU unless its only adapter is a software one and none is named
/// (`adapter` or `WGPU_ADAPTER_NAME`), or no adapter opens, then the CPU reference with a
/// notice saying why.
///
/// # Errors
/// On [`Backend::Gpu`], no adapter; on a GPU, a model beyond the adapter's buffer limits
/// ([`check_gpu_limits`]) or a failure building the solver.
pub fn choose_solver(
    backend: Backend,
    adapter: Option<&str>,
    scene: &Scene,
    model: &Model,
    plan: &Plan,
    notice: &mut dyn FnMut(&str),
) -> Result<Box<dyn Solver>> {
    let schedule = schedule(scene);
    let cpu =
        || -> Box<dyn Solver> { Box::new(CpuSolver::new(model.clone(), plan.clone(), schedule)) };
    Ok(match backend {
        Backend::Cpu => cpu(),
        Backend::Auto => match GpuContext::new(adapter) {
            Ok(ctx) if ctx.is_software() && !adapter_named(adapter) => {
                notice(&format!(
                    "the only GPU adapter is a software one ({}): running on the \
                     CPU reference, which is faster here (--backend gpu uses the adapter)",
                    ctx.adapter_name()
                ));
                cpu()
            }
            Ok(ctx) => gpu_solver(ctx, scene, model, plan, schedule)?,
            Err(e) => {
                notice(&format!("{e}; running on the CPU"));
                cpu()
            }
        },
        Backend::Gpu => gpu_solver(GpuContext::new(adapter)?, scene, model, plan, schedule)?,
    })
}

/// Whether an adapter is named (`adapter`, or `WGPU_ADAPTER_NAME`).
fn adapter_named(adapter: Option<&str>) -> bool {
    adapter.is_some_and(|a| !a.is_empty())
        || std::env::var("WGPU_ADAPTER_NAME").is_ok_and(|a| !a.is_empty())
}

/// The GPU solver of a scene on `ctx`, after checking that its buffers fit the adapter.
fn gpu_solver(
    ctx: GpuContext,
    scene: &Scene,
    model: &Model,
    plan: &Plan,
    schedule: Schedule,
) -> Result<Box<dyn Solver>> {
    let limits = ctx.device.limits();
    check_gpu_limits(
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
