//! The time loop of a run: advances a [`Solver`] (the CPU reference, [`crate::step::cpu`], or the
//! GPU, [`crate::gpu`]) batch by batch, writes history, fields, checkpoints and `summary.json`,
//! and stops on instability or when the progress callback asks. Shared by both backends.

use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::checkpoint::{digest, mesh_digests, Checkpoint, Checkpointing};
use crate::error::{Error, Result};
use crate::model::Model;
use crate::output::fields::FieldWriter;
use crate::output::history::{EnergyAudit, HistoryWriter};
use crate::output::lock::OutputLock;
use crate::output::summary::Summary;
use crate::output::{create_dir, write_file};
use crate::plan::Plan;
use crate::scene::Scene;
use crate::step::{Event, Sample, Solver};

/// Progress callback, called after each batch of steps with (simulated time, end time, steps):
/// `Some(cause)` stops the run there with `status = "interrupted"` and `cause` as its message
/// (the history is flushed and the summary written as for any other end).
pub type Progress<'a> = &'a mut dyn FnMut(f64, f64, u64) -> Option<String>;

/// Everything a finished run produced, besides the files.
#[derive(Debug, Clone)]
pub struct RunResult {
    /// The summary (also written to `summary.json`).
    pub summary: Summary,
    /// All history samples with their energy errors.
    pub samples: Vec<(Sample, f64)>,
    /// Output folder.
    pub out_dir: PathBuf,
}

/// Checkpoints and restarts of a run ([`run_with`]).
#[derive(Debug, Clone, Default)]
pub struct RunOptions {
    /// Write a checkpoint every so much simulated time (and when the run is interrupted).
    pub checkpointing: Option<Checkpointing>,
    /// Continue from this checkpoint (of a run of the same scene into the same `out_dir`).
    pub resume: Option<Checkpoint>,
}

/// Runs `solver` to the end of `scene`, writing `history.csv`, `summary.json` and, when the scene
/// asks for them, the fields into `out_dir` ([`run_with`] without checkpoints).
///
/// # Errors
/// I/O errors on the outputs and backend failures. An unstable run is not an error: it ends with
/// `status = "failed"` in the summary.
pub fn run(
    scene: &Scene,
    model: &Model,
    plan: &Plan,
    solver: &mut dyn Solver,
    out_dir: &Path,
    progress: Option<Progress<'_>>,
) -> Result<RunResult> {
    run_with(
        scene,
        model,
        plan,
        solver,
        out_dir,
        progress,
        RunOptions::default(),
    )
}

/// [`run`] with checkpoints ([`crate::checkpoint`]): with `options.checkpointing`, a checkpoint
/// is written into `out_dir` at the first batch of steps ending at or after each multiple of the
/// interval, and when the run is interrupted; with `options.resume`, the solver's state, the
/// energy audit and the outputs continue from that checkpoint (`history.csv` cut back to its
/// rows, `fields.pvd` to its snapshots), so that the outputs end as those of the run that was
/// never stopped. `RunResult::samples` then holds the samples after the checkpoint only.
///
/// # Errors
/// As [`run`]; [`Error::Checkpoint`] when the checkpoint does not fit the solver or outputs.
#[allow(clippy::too_many_arguments)]
pub fn run_with(
    scene: &Scene,
    model: &Model,
    plan: &Plan,
    solver: &mut dyn Solver,
    out_dir: &Path,
    progress: Option<Progress<'_>>,
    options: RunOptions,
) -> Result<RunResult> {
    create_dir(out_dir)?;
    // Held until the run returns: a second run into this folder is refused meanwhile.
    let _lock = OutputLock::acquire(out_dir)?;
    let bodies: Vec<String> = model.bodies.iter().map(|b| b.name.clone()).collect();
    let contacts = model.interface_names();
    let history_path = out_dir.join("history.csv");
    let format = scene.run.field_format;
    let mut audit = EnergyAudit::default();
    let mut loop_seconds = 0.0;
    let mut rows_before = 0usize;
    let (mut history, mut fields) = match &options.resume {
        None => (
            HistoryWriter::create(
                &history_path,
                &bodies,
                &contacts,
                model.has_plasticity(),
                model.has_friction(),
                model.has_erosion(),
                !model.radius.is_empty(),
            )?,
            match scene.run.field_interval {
                Some(_) => Some(FieldWriter::new(out_dir, format)?),
                None => None,
            },
        ),
        Some(c) => {
            if c.backend != solver.backend() {
                return Err(Error::Checkpoint(format!(
                    "the checkpoint is of the {} backend; this run is on {}",
                    c.backend,
                    solver.backend()
                )));
            }
            // The state's own messages say what did not fit; the file is named here.
            solver.restore_state(&c.solver).map_err(|e| match e {
                Error::Checkpoint(m) => Error::Checkpoint(format!(
                    "{}: {m}",
                    out_dir.join(crate::checkpoint::FILE).display()
                )),
                e => e,
            })?;
            // The state decoded is the one the checkpoint describes (the solver's own time and
            // step count, not only the checkpoint's copies of them).
            if solver.time().to_bits() != c.time.to_bits() || solver.steps() != c.steps {
                return Err(Error::Checkpoint(format!(
                    "{}: its solver state is at step {}, t = {:e} s, but the checkpoint says step \
                     {}, t = {:e} s: damaged",
                    out_dir.join(crate::checkpoint::FILE).display(),
                    solver.steps(),
                    solver.time(),
                    c.steps,
                    c.time
                )));
            }
            // Every file the restart keeps is checked before any is changed.
            c.check_snapshots(out_dir)?;
            audit = c.audit.clone();
            loop_seconds = c.loop_seconds;
            rows_before = c.history_rows as usize;
            (
                HistoryWriter::resume(
                    &history_path,
                    c.history_bytes,
                    c.history_rows,
                    c.history_digest,
                    model.has_plasticity(),
                    model.has_friction(),
                    model.has_erosion(),
                )?,
                match scene.run.field_interval {
                    Some(_) => Some(FieldWriter::resume(
                        out_dir,
                        format,
                        model,
                        c.snapshots.clone(),
                    )?),
                    None => None,
                },
            )
        }
    };
    let interval = options.checkpointing.as_ref().map(|c| c.interval);
    let meshes = mesh_digests(scene);
    let next_after = |t: f64| interval.map(|i| ((t / i).floor() + 1.0) * i);
    let mut next_checkpoint = next_after(solver.time());
    // A summary saying "running" before the first step: an unwritable or full output folder is
    // found now, not after the whole run, and a crash leaves that status behind.
    write_summary(
        out_dir,
        &summary_now(
            scene,
            plan,
            solver,
            (None, None, None),
            "running",
            String::new(),
            0.0,
            0.0,
            0,
            0,
        ),
    )?;
    let mut samples = Vec::new();
    let mut events = Vec::new();
    let mut failure: Option<String> = None;
    let mut interrupted: Option<String> = None;
    let mut progress = progress;
    let checkpoint = |solver: &mut dyn Solver,
                      history: &mut HistoryWriter,
                      fields: &Option<FieldWriter>,
                      audit: &EnergyAudit,
                      loop_seconds: f64|
     -> Result<()> {
        let Some(c) = &options.checkpointing else {
            return Ok(());
        };
        let (history_bytes, history_rows) = history.flush()?;
        let solver_state = solver.save_state()?;
        Checkpoint {
            scene_path: c.scene_path.clone(),
            scene_text: c.scene_text.clone(),
            scene_digest: digest(c.scene_text.as_bytes()),
            meshes: meshes.clone(),
            end_time_override: c.end_time_override,
            interval: c.interval,
            backend: solver.backend().to_string(),
            adapter: solver.adapter(),
            steps: solver.steps(),
            time: solver.time(),
            history_bytes,
            history_rows,
            history_digest: history.digest(),
            snapshots: fields
                .as_ref()
                .map(|f| f.entries().to_vec())
                .unwrap_or_default(),
            audit: audit.clone(),
            loop_seconds,
            solver_digest: digest(&solver_state),
            solver: solver_state,
        }
        .write(out_dir)
    };
    'outer: loop {
        let t0 = Instant::now();
        solver.advance(&mut events)?;
        loop_seconds += t0.elapsed().as_secs_f64();
        // A solver that has ended without saying how (a restored state marked finished without
        // its end) would be asked again forever. (A GPU solver's step and time are those of its
        // last readback: an advance that returns for the progress callback before a history row
        // leaves them as they were, so they cannot tell.)
        if events.is_empty() && solver.finished() {
            let why = format!(
                "the solver stopped at step {}, t = {:e} s, before the end time {:e} s without \
                 saying why",
                solver.steps(),
                solver.time(),
                scene.run.end_time
            );
            if options.resume.is_some() {
                return Err(Error::Checkpoint(format!(
                    "{}: {why}: its saved state is damaged",
                    out_dir.join(crate::checkpoint::FILE).display()
                )));
            }
            failure = Some(why);
            break 'outer;
        }
        for ev in events.drain(..) {
            match ev {
                Event::Sample(s) => {
                    let err = audit.error(&s);
                    history.row(&s, err)?;
                    if !(err.is_finite() && EnergyAudit::total(&s).is_finite()) {
                        failure = Some(format!(
                            "step {}, t = {:e} s: the energies are not finite (kinetic {:e}, \
                             internal {:e}, hourglass {:e}, viscous {:e}, contact {:e}, external \
                             {:e}): a velocity, load or material value of the scene overflows",
                            s.step,
                            s.time,
                            s.kinetic,
                            s.internal,
                            s.hourglass,
                            s.viscous,
                            s.contact,
                            s.external
                        ));
                        samples.push((s, f64::INFINITY));
                        break 'outer;
                    }
                    if err > scene.run.energy_error_limit {
                        failure = Some(format!(
                            "step {}, t = {:e} s: energy balance error {:.3e} exceeds run.energy_error_limit = {} \
                             (kinetic {:e}, internal {:e}, hourglass {:e}, viscous {:e}, contact {:e}, external {:e})",
                            s.step, s.time, err, scene.run.energy_error_limit, s.kinetic, s.internal,
                            s.hourglass, s.viscous, s.contact, s.external
                        ));
                        samples.push((s, err));
                        break 'outer;
                    }
                    samples.push((s, err));
                }
                Event::Snapshot(snap) => {
                    if let Some(f) = fields.as_mut() {
                        f.write(model, &snap)?;
                    }
                }
                Event::Done => break 'outer,
                Event::Failed(f) => {
                    failure = Some(format!(
                        "step {}, t = {:e} s: {}",
                        f.step, f.time, f.message
                    ));
                    break 'outer;
                }
            }
        }
        if next_checkpoint.is_some_and(|t| solver.time() >= t) {
            checkpoint(solver, &mut history, &fields, &audit, loop_seconds)?;
            next_checkpoint = next_after(solver.time());
        }
        if let Some(p) = progress.as_mut() {
            if let Some(cause) = p(solver.time(), scene.run.end_time, solver.steps()) {
                checkpoint(solver, &mut history, &fields, &audit, loop_seconds)?;
                interrupted = Some(format!(
                    "{cause} at step {}, t = {:e} s (of {:e} s)",
                    solver.steps(),
                    solver.time(),
                    scene.run.end_time
                ));
                break 'outer;
            }
        }
    }
    history.finish()?;
    let status = if failure.is_some() {
        "failed"
    } else if interrupted.is_some() {
        "interrupted"
    } else {
        "completed"
    };
    // (A device lost by now already failed the run: the summary says so without it.)
    let max_temperature = max_temperature(model, solver).unwrap_or_default();
    let eroded_inverted = if model.erode_inverted {
        solver.eroded_inverted_now().ok()
    } else {
        None
    };
    let eroded_small_step = if model.erode_min_dt > 0.0 {
        solver.eroded_small_step_now().ok()
    } else {
        None
    };
    let summary = summary_now(
        scene,
        plan,
        solver,
        (max_temperature, eroded_inverted, eroded_small_step),
        status,
        failure.or(interrupted).unwrap_or_default(),
        loop_seconds,
        // Over the rows with finite energies (a run with others has failed, saying so).
        audit.max_error,
        rows_before + samples.len(),
        fields.as_ref().map(|f| f.count()).unwrap_or(0),
    );
    write_summary(out_dir, &summary)?;
    Ok(RunResult {
        summary,
        samples,
        out_dir: out_dir.to_path_buf(),
    })
}

fn write_summary(out_dir: &Path, summary: &Summary) -> Result<()> {
    let json = serde_json::to_string_pretty(summary).unwrap_or_default();
    write_file(&out_dir.join("summary.json"), &(json + "\n"))
}

/// The highest temperature of the elements of `model`'s bodies with Johnson-Cook thermal
/// softening now (K; `None` without: no readback then).
fn max_temperature(model: &Model, solver: &mut dyn Solver) -> Result<Option<f64>> {
    if !model.bodies.iter().any(|b| b.params.has_thermal()) {
        return Ok(None);
    }
    let plastic = solver.plastic_now()?;
    let mut max = f64::NEG_INFINITY;
    for b in model.bodies.iter().filter(|b| b.params.has_thermal()) {
        for e in b.elements.clone() {
            let heat = plastic.get(e).map_or(0.0, |p| p.heat);
            max = max.max(b.params.room_temperature + heat);
        }
    }
    Ok(max.is_finite().then_some(max))
}

/// The summary of `solver`'s run so far (`max_temperature`: the highest element temperature,
/// for a scene with thermal softening; `eroded_inverted`: the elements eroded about to invert,
/// with `run.erosion.inverted`; `eroded_small_step`: those eroded for a stable step below
/// `run.erosion.min_time_step`).
#[allow(clippy::too_many_arguments)]
fn summary_now(
    scene: &Scene,
    plan: &Plan,
    solver: &dyn Solver,
    (max_temperature, eroded_inverted, eroded_small_step): (Option<f64>, Option<u64>, Option<u64>),
    status: &str,
    message: String,
    loop_seconds: f64,
    max_energy_error: f64,
    history_rows: usize,
    snapshots: usize,
) -> Summary {
    let counters = solver.counters();
    let steps = solver.steps();
    let (dt_min, dt_max) = if steps > 0 {
        solver.dt_range()
    } else {
        (0.0, 0.0)
    };
    Summary {
        status: status.to_string(),
        message,
        scene: scene.name.clone(),
        backend: solver.backend().to_string(),
        adapter: solver.adapter(),
        nodes: plan.nodes,
        elements: plan.elements,
        steps,
        end_time: solver.time(),
        wall_seconds: loop_seconds,
        element_cycles_per_second: if loop_seconds > 0.0 {
            plan.elements as f64 * steps as f64 / loop_seconds
        } else {
            0.0
        },
        dt_min,
        dt_max,
        max_energy_error,
        gpu_submissions: counters.submissions,
        gpu_readbacks: counters.readbacks,
        contact_searches: counters.contact_searches,
        bytes_read_back: counters.bytes_read_back,
        contact_sweeps_mean: counters.contact_sweeps_mean,
        contact_sweeps_max: counters.contact_sweeps_max,
        contact_unconverged: counters.contact_unconverged,
        contact_residual_max: Some(counters.contact_residual_max),
        contact_penalty_bounded: counters.contact_penalty_bounded,
        failure: scene
            .materials
            .iter()
            .filter_map(|m| Some(format!("{}: {}", m.name, m.failure?.describe())))
            .collect(),
        thermal: scene
            .materials
            .iter()
            .filter_map(|m| {
                let t = m.plasticity?.johnson_cook?.thermal?;
                Some(format!("{}: {}", m.name, t.describe()))
            })
            .collect(),
        max_temperature,
        eroded_elements: plan
            .has(crate::plan::Stage::Failure)
            .then_some(counters.eroded_elements),
        eroded_inverted,
        eroded_small_step,
        stage_seconds: solver.stage_seconds(),
        history_rows,
        snapshots,
    }
}
