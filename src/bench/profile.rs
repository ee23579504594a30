//! Where a step's device time goes (`ricochet bench --profile`): a bench scene (the block or a
//! contact scene with its contact) run on the GPU for some warm-up steps, then profiled with
//! [`crate::gpu::GpuSolver::profile_steps`] (each part of a step in its own pass between
//! timestamp queries), as device microseconds per step by part, with the bytes that the traffic
//! model of [`super::bytes`] gives the element and node stages and the bandwidth that makes. An
//! adapter without timestamp queries gives no rows and a [`ProfileReport::notice`]. GPU only:
//! the CPU reference has no device time to split.

use std::sync::Arc;

use serde::Serialize;

use super::bytes::{bytes_per_step, traffic};
use super::contact::contact_build;
use super::scenes::{build, scene, ContactScene, PileContact};
use crate::error::Result;
use crate::gpu::solver::PROFILE_PARTS;
use crate::gpu::{GpuContext, GpuSolver};
use crate::step::Solver;

/// A scene to profile.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ProfileScene {
    /// The bench block of `size` x `size` cells ([`super::scene`]).
    Block,
    /// A contact scene of `size` ([`ContactScene`]) with its contact (the pile with
    /// `bodies = "all"`).
    Contact(ContactScene),
}

impl ProfileScene {
    /// The scene's name in the table.
    pub fn name(self) -> &'static str {
        match self {
            ProfileScene::Block => "block",
            ProfileScene::Contact(c) => c.name(),
        }
    }
}

/// One profiled scene.
#[derive(Debug, Clone, Serialize)]
pub struct ProfileRow {
    /// The scene: `block`, `pair`, `striker` or `pile`.
    pub scene: String,
    /// The adapter.
    pub adapter: String,
    /// Size parameter (the block's cells per side, see [`ContactScene`] otherwise).
    pub size: usize,
    /// Elements.
    pub elements: usize,
    /// Nodes.
    pub nodes: usize,
    /// Bodies.
    pub bodies: usize,
    /// Steps run before the profiled ones.
    pub warmup: u64,
    /// Steps profiled.
    pub steps: u64,
    /// Device microseconds per step of each part ([`PROFILE_PARTS`]), in step order.
    pub parts_us: Vec<(String, f64)>,
    /// Their sum.
    pub total_us: f64,
    /// Lagrange sweeps per step with constraints, mean over the run so far (0 without).
    pub sweeps_mean: f64,
    /// Contact searches in the profiled steps.
    pub searches: u64,
    /// Bytes a step of the `forces` part moves by the traffic model (the element kernel, the
    /// stable-step reduction and its control), with the scene's compiled features.
    pub forces_bytes: f64,
    /// The same for the `update` part (the node kernel; velocity boundaries not counted).
    pub update_bytes: f64,
    /// `forces_bytes` over the `forces` part's time, in GB/s (1e9 B/s).
    pub forces_gb_per_s: f64,
    /// `update_bytes` over the `update` part's time, in GB/s.
    pub update_gb_per_s: f64,
    /// Device microseconds per step of whole batches of steps, each in one pass between two
    /// timestamps ([`crate::gpu::GpuSolver::profile_whole_steps`], as many steps as profiled):
    /// the step without the passes between its parts that `parts_us` needs.
    pub step_device_us: f64,
    /// Wall microseconds per step of the same number of steps taken as a run takes them
    /// ([`crate::gpu::GpuSolver::run_steps`]: batches recorded ahead, readbacks); beyond
    /// `step_device_us`, the host's time the device waited for.
    pub step_wall_us: f64,
}

/// The profile of a set of scenes on one adapter.
#[derive(Debug, Clone, Serialize)]
pub struct ProfileReport {
    /// The adapter.
    pub adapter: String,
    /// Whether the adapter has timestamp queries (without them, no rows).
    pub timestamps: bool,
    /// Why there are no rows, when there are none.
    pub notice: Option<String>,
    /// One row per scene and size.
    pub rows: Vec<ProfileRow>,
}

/// The notice of an adapter without timestamp queries.
pub fn no_timestamps(ctx: &GpuContext) -> String {
    format!(
        "{} has no timestamp queries: no per-stage device profile",
        ctx.adapter_name()
    )
}

/// Profiles `which` of `size` on `ctx` with the contact `options`: `warmup` steps (at least 2, the
/// first search), then `steps` profiled steps. `None` when the adapter has no timestamp queries.
///
/// # Errors
/// Scene or device errors.
pub fn profile(
    ctx: Arc<GpuContext>,
    which: ProfileScene,
    size: usize,
    (warmup, steps): (u64, u64),
    options: crate::gpu::contact::ContactOptions,
) -> Result<Option<ProfileRow>> {
    if !ctx.timestamps {
        return Ok(None);
    }
    let (model, plan, schedule) = match which {
        ProfileScene::Block => {
            let s = scene(size)?;
            let (m, p) = build(&s)?;
            (m, p, crate::run::schedule(&s))
        }
        ProfileScene::Contact(c) => {
            contact_build(c, size, true, PileContact::All, Default::default())?
        }
    };
    let mut solver = GpuSolver::with_options(ctx.clone(), &model, &plan, schedule, None, options)?;
    solver.run_steps(warmup.max(2))?;
    let before = solver.counters().contact_searches;
    let Some((taken, seconds)) = solver.profile_steps(steps)? else {
        return Ok(None);
    };
    let counters = solver.counters();
    let step_device_us = match solver.profile_whole_steps(steps)? {
        Some((_, s)) => 1e6 * s,
        None => f64::NAN,
    };
    let t0 = std::time::Instant::now();
    let walked = solver.run_steps(steps)?;
    let step_wall_us = 1e6 * t0.elapsed().as_secs_f64() / walked.max(1) as f64;
    let (elements, nodes) = (model.element_count(), model.node_count());
    let traffic = traffic(&solver.kernels().features);
    let forces_bytes = bytes_per_step(
        &traffic,
        &["element", "min_dt", "control_dt"],
        elements,
        nodes,
    );
    let update_bytes = bytes_per_step(&traffic, &["node"], elements, nodes);
    let part = |name: &str| {
        PROFILE_PARTS
            .iter()
            .position(|p| *p == name)
            .map_or(f64::NAN, |i| seconds[i])
    };
    let rate = |bytes: f64, t: f64| bytes / t / 1e9;
    Ok(Some(ProfileRow {
        scene: which.name().to_string(),
        adapter: ctx.adapter_name(),
        size,
        elements,
        nodes,
        bodies: model.bodies.len(),
        warmup: warmup.max(2),
        steps: taken,
        parts_us: PROFILE_PARTS
            .iter()
            .zip(&seconds)
            .map(|(p, t)| (p.to_string(), 1e6 * t))
            .collect(),
        total_us: 1e6 * seconds.iter().sum::<f64>(),
        sweeps_mean: counters.contact_sweeps_mean,
        searches: counters.contact_searches - before,
        forces_bytes,
        update_bytes,
        forces_gb_per_s: rate(forces_bytes, part("forces")),
        update_gb_per_s: rate(update_bytes, part("update")),
        step_device_us,
        step_wall_us,
    }))
}

/// Formats profile rows as a table: device microseconds per step by part, then the element and
/// node stages' bandwidth by the traffic model.
pub fn profile_table(rows: &[ProfileRow]) -> String {
    let mut s = format!("{:<8} {:>9}", "scene", "elements");
    for p in PROFILE_PARTS {
        s.push_str(&format!(" {:>9}", p.trim_start_matches("contact ")));
    }
    s.push_str(&format!(
        " {:>9} {:>6} {:>12} {:>12} {:>9} {:>9}\n",
        "total", "sweeps", "forces GB/s", "update GB/s", "step dev", "step wall"
    ));
    for r in rows {
        s.push_str(&format!("{:<8} {:>9}", r.scene, r.elements));
        for (_, us) in &r.parts_us {
            s.push_str(&format!(" {us:>9.1}"));
        }
        s.push_str(&format!(
            " {:>9.1} {:>6.1} {:>12.1} {:>12.1} {:>9.1} {:>9.1}\n",
            r.total_us,
            r.sweeps_mean,
            r.forces_gb_per_s,
            r.update_gb_per_s,
            r.step_device_us,
            r.step_wall_us
        ));
    }
    s.push_str(
        "(device us per step by part, timestamp queries; GB/s: the bytes of BENCHMARKS.md's \
         traffic table over the part's time; step dev: device us per step of whole batches in \
         one pass each; step wall: wall us per step as a run takes them)\n",
    );
    s
}
