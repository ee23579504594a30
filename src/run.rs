//! The run driver: advances a [`Solver`], writes history, fields and summary, and stops on
//! instability. Shared by both backends.

use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::checkpoint::{Checkpoint, Checkpointing};
use crate::error::{Error, Result};
use crate::model::Model;
use crate::output::fields::FieldWriter;
use crate::output::history::{EnergyAudit, HistoryWriter};
use crate::output::summary::Summary;
use crate::output::{create_dir, write_file};
use crate::plan::Plan;
use crate::scene::Scene;
use crate::step::{Event, Sample, Schedule, Solver};

/// Progress callback, called after each batch of steps with (simulated time, end time, steps):
/// `Some(cause)` stops the run there with `status = "interrupted"` and `cause` as its message
/// (the history is flushed and the summary written as for any other end).
pub type Progress<'a> = &'a mut dyn FnMut(f64, f64, u64) -> Option<String>;

/// Memory of a CPU reference run per element (bytes), measured as the peak resident size of a
/// 1000 x 1000 block run without field output on the 2-core machine (443 MB for 10^6 elements).
pub const BYTES_PER_ELEMENT: u64 = 450;
/// Further memory per element when fields are written (the VTU text of a snapshot and its element
/// fields; the same run with fields peaked at 903 MB).
pub const FIELD_BYTES_PER_ELEMENT: u64 = 460;
/// Further memory per element of a J2 plastic body: its plastic state (5 f64) and the copy a
/// snapshot takes.
pub const PLASTIC_BYTES_PER_ELEMENT: u64 = 80;

/// Elements of each body as its mesh specification gives them, without meshing.
pub fn element_counts(scene: &Scene) -> Vec<u64> {
    use crate::scene::MeshSpec;
    scene
        .bodies
        .iter()
        .map(|b| match &b.mesh {
            MeshSpec::Explicit { quads, .. } => quads.len() as u64,
            MeshSpec::Gmsh { mesh, .. } => mesh.quads.len() as u64,
            MeshSpec::Rectangle { cells, .. } => cells[0] as u64 * cells[1] as u64,
            // The O-grid: a c x c core and four c x (c / 2) blocks.
            MeshSpec::Disk { cells, .. } => 3 * (*cells as u64) * (*cells as u64),
        })
        .collect()
}

/// Bytes a CPU reference run of `scene` needs (estimate from [`BYTES_PER_ELEMENT`] and
/// [`FIELD_BYTES_PER_ELEMENT`]).
pub fn memory_estimate(scene: &Scene) -> u64 {
    let per = BYTES_PER_ELEMENT
        + if scene.run.field_interval.is_some() {
            FIELD_BYTES_PER_ELEMENT
        } else {
            0
        };
    let plastic: u64 = element_counts(scene)
        .iter()
        .zip(&scene.bodies)
        .filter(|(_, b)| {
            scene.materials[b.material].model == crate::scene::MaterialModel::J2Plastic
        })
        .map(|(n, _)| n.saturating_mul(PLASTIC_BYTES_PER_ELEMENT))
        .sum();
    element_counts(scene)
        .iter()
        .sum::<u64>()
        .saturating_mul(per)
        .saturating_add(plastic)
}

/// The memory this machine has available (`MemAvailable` of `/proc/meminfo`), if known.
pub fn available_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// Refuses, before meshing, a scene whose estimated memory ([`memory_estimate`]) exceeds what
/// the machine has available, naming the mesh key of its largest body.
///
/// # Errors
/// [`Error::Invalid`] naming the key, the value and both amounts.
pub fn check_memory(scene: &Scene) -> Result<()> {
    let need = memory_estimate(scene);
    let Some(have) = available_memory() else {
        return Ok(());
    };
    if need <= have {
        return Ok(());
    }
    let counts = element_counts(scene);
    let (key, value) = largest_mesh(scene);
    let gib = |b: u64| b as f64 / (1u64 << 30) as f64;
    Err(Error::Invalid {
        file: scene.file.clone(),
        key,
        value,
        reason: format!(
            "{} elements in all need about {:.1} GiB, more than the {:.1} GiB this machine has \
             available",
            counts.iter().sum::<u64>(),
            gib(need),
            gib(have)
        ),
    })
}

/// The mesh key and value of the body with the most elements (for messages about sizes).
fn largest_mesh(scene: &Scene) -> (String, String) {
    let counts = element_counts(scene);
    let (bi, &n) = counts
        .iter()
        .enumerate()
        .max_by_key(|(_, n)| **n)
        .unwrap_or((0, &0));
    match scene.bodies.get(bi).map(|b| &b.mesh) {
        Some(crate::scene::MeshSpec::Rectangle { cells, .. }) => (
            format!("body[{bi}].mesh.rectangle.cells"),
            format!("{cells:?}"),
        ),
        Some(crate::scene::MeshSpec::Disk { cells, .. }) => {
            (format!("body[{bi}].mesh.disk.cells"), format!("{cells}"))
        }
        Some(crate::scene::MeshSpec::Gmsh { .. }) => {
            (format!("body[{bi}].mesh.gmsh"), format!("{n} elements"))
        }
        Some(crate::scene::MeshSpec::Explicit { .. }) | None => {
            (format!("body[{bi}].mesh.quads"), format!("{n} elements"))
        }
    }
}

/// Bytes per element of the GPU backend's largest per-element buffer (`elements`: corners,
/// nodes and body of each quad, in f32), and per node and element of its largest mixed one
/// (`sample_sources`).
pub const GPU_BYTES_PER_ELEMENT: u64 = 64;
/// See [`GPU_BYTES_PER_ELEMENT`].
pub const GPU_SAMPLE_BYTES: u64 = 16;

/// Refuses, before anything is uploaded, a model whose largest GPU buffer would exceed the
/// adapter's largest storage binding or buffer (`max_binding`, `max_buffer` bytes), naming the
/// mesh key of the largest body.
///
/// # Errors
/// [`Error::Invalid`] naming the key, the value, the buffer and the limit.
pub fn check_gpu_limits(
    scene: &Scene,
    model: &Model,
    adapter: &str,
    max_binding: u64,
    max_buffer: u64,
) -> Result<()> {
    let (ne, nn) = (model.element_count() as u64, model.node_count() as u64);
    let limit = max_binding.min(max_buffer);
    // The sample sources: one entry per node and element, and one more per element with a
    // plastic body (its plastic work).
    let sampled = ne + nn + if model.has_plasticity() { ne } else { 0 };
    let need = (GPU_BYTES_PER_ELEMENT * ne).max(GPU_SAMPLE_BYTES * sampled);
    if need <= limit {
        return Ok(());
    }
    let (key, value) = largest_mesh(scene);
    let per = (limit / GPU_BYTES_PER_ELEMENT).min(limit / (2 * GPU_SAMPLE_BYTES));
    Err(Error::Invalid {
        file: scene.file.clone(),
        key,
        value,
        reason: format!(
            "{ne} elements and {nn} nodes need a GPU buffer of {need} bytes, more than the {limit} \
             bytes of the largest buffer binding of {adapter} (about {per} elements at most on it); \
             run it with --backend cpu or on a larger adapter"
        ),
    })
}

/// Most steps a run may take (run.end_time over its first step).
pub const MAX_STEPS: f64 = 1e9;
/// Most history rows a run may write (run.end_time / run.history_interval).
pub const MAX_HISTORY_ROWS: f64 = 1e7;
/// Most field snapshots a run may write (run.end_time / run.field_interval).
pub const MAX_SNAPSHOTS: f64 = 1e5;

/// The first step of a run: (the step dt^{1/2}, the elements' stable step, the element that sets
/// it), with the penalty springs and `time_step_scale` (or the fixed `time_step`) applied, and
/// the contact that shortened it, if any.
pub fn first_step(scene: &Scene, model: &Model) -> (f64, f64, usize, Option<String>) {
    let (dt_element, e) = model.initial_stable_step();
    let penalty = model
        .contacts
        .iter()
        .map(|c| c.method)
        .chain(model.walls.iter().map(|w| w.method))
        .any(|m| m.has_springs());
    let (dt_stable, by) = match penalty
        .then(|| crate::contact::ContactSet::new(model))
        .flatten()
    {
        Some(c) => (
            c.limit_step(dt_element),
            c.penalty_step().map(|(_, what)| what.to_string()),
        ),
        None => (dt_element, None),
    };
    let step = scene
        .run
        .time_step
        .unwrap_or(scene.run.time_step_scale * dt_stable);
    (step, dt_element, e, by)
}

/// Refuses a run that would not end in a stated number of steps, history rows or snapshots
/// ([`MAX_STEPS`], [`MAX_HISTORY_ROWS`], [`MAX_SNAPSHOTS`]), or whose first step is zero or not
/// finite (a `time_step_scale` or `penalty_scale` at the end of the floating-point range).
///
/// # Errors
/// [`Error::Invalid`] naming the key, the value and the limit.
pub fn check_limits(scene: &Scene, model: &Model) -> Result<()> {
    let r = &scene.run;
    let invalid = |key: &str, value: String, reason: String| Error::Invalid {
        file: scene.file.clone(),
        key: key.into(),
        value,
        reason,
    };
    let rows = r.end_time / r.history_interval;
    if rows.is_nan() || rows > MAX_HISTORY_ROWS {
        return Err(invalid(
            "run.history_interval",
            format!("{:e}", r.history_interval),
            format!(
                "{rows:.3e} history rows to run.end_time = {:e}: more than the limit of {MAX_HISTORY_ROWS:e}",
                r.end_time
            ),
        ));
    }
    if let Some(f) = r.field_interval {
        let n = r.end_time / f;
        if n.is_nan() || n > MAX_SNAPSHOTS {
            return Err(invalid(
                "run.field_interval",
                format!("{f:e}"),
                format!(
                    "{n:.3e} snapshots to run.end_time = {:e}: more than the limit of {MAX_SNAPSHOTS:e}",
                    r.end_time
                ),
            ));
        }
    }
    let (step, dt_element, e, by) = first_step(scene, model);
    let steps = r.end_time / step;
    if step.is_nan() || step <= 0.0 || steps.is_nan() || steps > MAX_STEPS {
        let shortened = by
            .as_ref()
            .map(|w| format!(", shortened by the penalty springs of {w}"))
            .unwrap_or_default();
        let why = format!(
            "the first step is {step:e} s (stable step {dt_element:e} s of element {e}{shortened}, \
             x time_step_scale {:e}): {steps:.3e} steps, more than the limit of {MAX_STEPS:e}",
            r.time_step_scale
        );
        let (key, value) = if r.time_step.is_none() && r.time_step_scale < 1e-3 {
            (
                "run.time_step_scale".to_string(),
                format!("{:e}", r.time_step_scale),
            )
        } else if let Some(w) = by.filter(|_| r.time_step.is_none()) {
            // The contact or wall whose springs set the step, by its quoted name in `w`.
            let named = |n: &str| w.ends_with(&format!("{n:?}"));
            let key = if w.starts_with("rigid wall") {
                scene.walls.iter().position(|x| named(&x.name)).map(|i| {
                    (
                        format!("rigid_wall[{i}].penalty_scale"),
                        scene.walls[i].penalty_scale,
                    )
                })
            } else {
                scene.contacts.iter().position(|x| named(&x.name)).map(|i| {
                    (
                        format!("contact[{i}].penalty_scale"),
                        scene.contacts[i].penalty_scale,
                    )
                })
            };
            match key {
                Some((k, v)) => (k, format!("{v:e}")),
                None => (format!("penalty_scale of {w}"), "(see the scene)".into()),
            }
        } else {
            ("run.end_time".to_string(), format!("{:e}", r.end_time))
        };
        return Err(invalid(&key, value, why));
    }
    Ok(())
}

/// The schedule of a scene's run.
pub fn schedule(scene: &Scene) -> Schedule {
    Schedule {
        end_time: scene.run.end_time,
        history_interval: scene.run.history_interval,
        field_interval: scene.run.field_interval,
        time_step_scale: scene.run.time_step_scale,
        time_step: scene.run.time_step,
    }
}

/// The model of a run of `scene`: [`Model::assemble`], then the contact overlaps at t = 0
/// moved onto their surfaces ([`crate::contact::overlap::resolve`]).
///
/// # Errors
/// [`crate::Error::Invalid`] for an invalid mesh, boundary or pressure box, or an overlap at t = 0
/// that cannot be resolved.
pub fn model(scene: &Scene) -> Result<Model> {
    let mut model = Model::assemble(scene)?;
    crate::contact::overlap::resolve(&mut model, scene)?;
    Ok(model)
}

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
            solver.restore_state(&c.solver)?;
            audit = c.audit.clone();
            loop_seconds = c.loop_seconds;
            rows_before = c.history_rows as usize;
            (
                HistoryWriter::resume(
                    &history_path,
                    c.history_bytes,
                    c.history_rows,
                    model.has_plasticity(),
                    model.has_friction(),
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
        Checkpoint {
            scene_path: c.scene_path.clone(),
            scene_text: c.scene_text.clone(),
            end_time_override: c.end_time_override,
            interval: c.interval,
            backend: solver.backend().to_string(),
            adapter: solver.adapter(),
            steps: solver.steps(),
            time: solver.time(),
            history_bytes,
            history_rows,
            snapshots: fields
                .as_ref()
                .map(|f| f.entries().to_vec())
                .unwrap_or_default(),
            audit: audit.clone(),
            loop_seconds,
            solver: solver.save_state()?,
        }
        .write(out_dir)
    };
    'outer: loop {
        let t0 = Instant::now();
        solver.advance(&mut events)?;
        loop_seconds += t0.elapsed().as_secs_f64();
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
    let summary = summary_now(
        scene,
        plan,
        solver,
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

/// The summary of `solver`'s run so far.
#[allow(clippy::too_many_arguments)]
fn summary_now(
    scene: &Scene,
    plan: &Plan,
    solver: &dyn Solver,
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
        contact_penalty_bounded: counters.contact_penalty_bounded,
        stage_seconds: solver.stage_seconds(),
        history_rows,
        snapshots,
    }
}
