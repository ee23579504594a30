//! Limits a run is held to before it starts: the memory a CPU reference run needs against what
//! the machine has ([`check_memory`]), the GPU buffers against the adapter's limits
//! ([`check_gpu_limits`]), and the steps, history rows and snapshots of the schedule
//! ([`check_limits`]). Both backends are checked here, on the CPU, before anything runs.

use crate::error::{Error, Result};
use crate::model::Model;
use crate::scene::Scene;

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

pub use crate::input::available_memory;

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

/// The step `ricochet check` reports for a run of `scene`: the stable step of its solver
/// (`dt_element`, set by element `e`) limited by `contact`'s penalty springs, and the step taken
/// (the fixed `run.time_step`, or `time_step_scale` times the stable step), as `(stable, taken)`.
///
/// # Errors
/// [`Error::Invalid`] naming `run.time_step` when a fixed step exceeds the stable step.
pub fn checked_step(
    scene: &Scene,
    (dt_element, e): (f64, usize),
    contact: Option<&crate::contact::ContactSet>,
) -> Result<(f64, f64)> {
    let dt = contact.map_or(dt_element, |c| c.limit_step(dt_element));
    match scene.run.time_step {
        Some(fixed) if fixed > dt => Err(Error::Invalid {
            file: scene.file.clone(),
            key: "run.time_step".into(),
            value: format!("{fixed:e}"),
            reason: format!("exceeds the stable step {dt:e} (set by element {e})"),
        }),
        Some(fixed) => Ok((dt, fixed)),
        None => Ok((dt, scene.run.time_step_scale * dt)),
    }
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
