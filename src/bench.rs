//! Throughput benchmark: a generated impact-like block of N x N quads (no contact), run for a
//! fixed number of steps on the CPU reference or the GPU, reported as element-cycles per second.

use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

use serde::Serialize;

use crate::error::Result;
use crate::gpu::{GpuContext, GpuSolver};
use crate::model::Model;
use crate::plan::Plan;
use crate::scene::Scene;
use crate::step::cpu::CpuSolver;
use crate::step::Solver;

/// One row of the bench table.
#[derive(Debug, Clone, Serialize)]
pub struct BenchRow {
    /// "cpu" or "gpu".
    pub backend: String,
    /// Adapter or processor.
    pub adapter: String,
    /// Cells per side.
    pub cells: usize,
    /// Elements.
    pub elements: usize,
    /// Steps timed.
    pub steps: u64,
    /// Wall seconds of the timed steps.
    pub wall_seconds: f64,
    /// Elements x steps / wall seconds.
    pub element_cycles_per_second: f64,
    /// Steps per second.
    pub steps_per_second: f64,
    /// GPU: share of the step per stage (each stage timed alone over the same steps).
    pub stage_shares: Vec<(String, f64)>,
}

/// The bench scene: a steel block of `cells` x `cells` plane-strain quads, 0.1 m wide, squeezed by
/// an initial velocity field (compression along x, like the first microseconds of an impact), with
/// the default viscous hourglass control and bulk viscosity.
pub fn scene(cells: usize) -> Result<Scene> {
    let text = format!(
        r#"
[run]
end_time = 1.0e3
history_interval = 1.0e3

[[material]]
name = "steel"
model = "linear_elastic"
density = 7850.0
youngs_modulus = 2.1e11
poisson_ratio = 0.3

[[body]]
name = "block"
material = "steel"
mesh = {{ rectangle = {{ origin = [0.0, 0.0], size = [0.1, 0.1], cells = [{cells}, {cells}] }} }}
velocity_gradient = [[-100.0, 0.0], [0.0, 30.0]]
"#
    );
    Scene::parse(&text, Path::new("bench.toml"))
}

/// Times `steps` steps of the CPU reference on the bench scene.
///
/// # Errors
/// Scene errors only.
pub fn cpu(cells: usize, steps: u64) -> Result<BenchRow> {
    let scene = scene(cells)?;
    let model = Model::build(&scene)?;
    let plan = Plan::new(&scene, &model);
    let ne = model.element_count();
    let mut solver = CpuSolver::new(model, plan, crate::run::schedule(&scene));
    solver.run_steps(2); // warm-up, and past the first output step
    let t0 = Instant::now();
    solver.run_steps(steps);
    let wall = t0.elapsed().as_secs_f64();
    if solver.steps() != steps + 2 {
        return Err(crate::error::Error::Bench(format!(
            "the CPU run stopped after {} of {} steps",
            solver.steps(),
            steps + 2
        )));
    }
    Ok(row(
        "cpu",
        solver_adapter(),
        cells,
        ne,
        steps,
        wall,
        Vec::new(),
    ))
}

fn solver_adapter() -> String {
    "CPU reference (f64, 1 thread)".to_string()
}

fn row(
    backend: &str,
    adapter: String,
    cells: usize,
    elements: usize,
    steps: u64,
    wall: f64,
    stage_shares: Vec<(String, f64)>,
) -> BenchRow {
    BenchRow {
        backend: backend.to_string(),
        adapter,
        cells,
        elements,
        steps,
        wall_seconds: wall,
        element_cycles_per_second: elements as f64 * steps as f64 / wall,
        steps_per_second: steps as f64 / wall,
        stage_shares,
    }
}

/// Times `steps` steps on the GPU of `ctx`, in submissions of [`crate::gpu::solver::MAX_BATCH`]
/// steps at most, then each stage alone over the same number of steps for the shares.
///
/// # Errors
/// Scene or device errors.
pub fn gpu(ctx: Arc<GpuContext>, cells: usize, steps: u64) -> Result<BenchRow> {
    let scene = scene(cells)?;
    let model = Model::build(&scene)?;
    let plan = Plan::new(&scene, &model);
    let ne = model.element_count();
    let adapter = ctx.adapter_name();
    let mut solver = GpuSolver::new(ctx, &model, &plan, crate::run::schedule(&scene))?;
    let batch = crate::gpu::solver::MAX_BATCH as u64;
    let chunks =
        |steps: u64| (0..steps.div_ceil(batch)).map(move |k| (steps - k * batch).min(batch) as u32);
    solver.time_stage("step", 2)?; // warm-up (pipelines, first sample)
    let mut wall = 0.0;
    for n in chunks(steps) {
        wall += solver.time_stage("step", n)?;
    }
    let mut shares = Vec::new();
    for stage in ["element", "node", "control"] {
        let mut t = 0.0;
        for n in chunks(steps) {
            t += solver.time_stage(stage, n)?;
        }
        shares.push((stage.to_string(), t / wall));
    }
    Ok(row("gpu", adapter, cells, ne, steps, wall, shares))
}

/// Formats rows as a table.
pub fn table(rows: &[BenchRow]) -> String {
    let mut s = format!(
        "{:<7} {:>9} {:>7} {:>10} {:>12} {:>12}  {}\n",
        "backend", "elements", "steps", "wall [s]", "elem-cyc/s", "steps/s", "stage shares"
    );
    for r in rows {
        let shares: Vec<String> = r
            .stage_shares
            .iter()
            .map(|(n, x)| format!("{n} {:.0}%", 100.0 * x))
            .collect();
        s.push_str(&format!(
            "{:<7} {:>9} {:>7} {:>10.3} {:>12.3e} {:>12.1}  {}\n",
            r.backend,
            r.elements,
            r.steps,
            r.wall_seconds,
            r.element_cycles_per_second,
            r.steps_per_second,
            shares.join(", ")
        ));
    }
    s
}
