//! Throughput benchmark: a generated impact-like block of N x N quads (no contact), run for a
//! fixed number of steps on the CPU reference or the GPU, reported as element-cycles per second.
//!
//! In the same run, alternating in rounds (medians reported), it also measures what the step costs
//! beyond the bare element-and-update loop (the full step over the bare loop: a scene without
//! contact should run as fast as the bare loop), and what a contact pair adds per step: the block
//! resting on a base, with and without a `[[contact]]` between them.

use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

use serde::Serialize;

use crate::error::{Error, Result};
use crate::gpu::{GpuContext, GpuSolver};
use crate::model::Model;
use crate::plan::Plan;
use crate::scene::Scene;
use crate::step::cpu::CpuSolver;
use crate::step::element::{evaluate_with, quad_geometry, Dissipation, QuadGeometry};
use crate::step::Solver;

/// Rounds by default: each variant is timed this many times, alternating, and medians reported.
pub const DEFAULT_ROUNDS: u32 = 5;

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
    /// Steps timed (of the full step; the same number of each other variant).
    pub steps: u64,
    /// Wall seconds of the timed steps.
    pub wall_seconds: f64,
    /// Elements x steps / wall seconds.
    pub element_cycles_per_second: f64,
    /// Steps per second.
    pub steps_per_second: f64,
    /// GPU: share of the step per stage (each stage timed alone over the same steps).
    pub stage_shares: Vec<(String, f64)>,
    /// Rounds: each variant timed `steps / rounds` steps per round, in alternation.
    pub rounds: u32,
    /// Wall seconds of the bare loop (element forces and node update only) over `steps` steps.
    pub bare_seconds: f64,
    /// Median over the rounds of (full step time) / (bare loop time), same steps, same run.
    pub full_over_bare: f64,
    /// Elements of the contact comparison (the block and its base).
    pub contact_elements: usize,
    /// Median over the rounds of the extra wall seconds per step of the block on its base with a
    /// `[[contact]]` over the same two bodies without it.
    pub contact_seconds_per_step: f64,
    /// Median over the rounds of that extra time as a share of the step with contact.
    pub contact_share: f64,
    /// Broad-phase searches of the contact run.
    pub contact_searches: u64,
}

/// The block of [`scene`]: `cells` x `cells` quads, 0.1 m wide.
fn block_text(cells: usize) -> String {
    format!(
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
    )
}

/// The bench scene: a steel block of `cells` x `cells` plane-strain quads, 0.1 m wide, squeezed by
/// an initial velocity field (compression along x, like the first microseconds of an impact), with
/// the default viscous hourglass control and bulk viscosity.
///
/// # Errors
/// None in practice (the text is generated); scene errors otherwise.
pub fn scene(cells: usize) -> Result<Scene> {
    Scene::parse(&block_text(cells), Path::new("bench.toml"))
}

/// The contact bench scene: the block of [`scene`] resting on a base of `cells` x max(1, cells / 8)
/// square elements of the same size (matching nodes along the interface), at rest. The block's
/// velocity field moves its bottom face down into the base (1.5 m/s), so the contact is active on
/// every interface node. With `contact`, a `[[contact]]` with the defaults (Lagrange, two passes)
/// between them; without, the same two bodies pass through each other (the bench's steps move
/// them by a fraction of an element).
///
/// # Errors
/// None in practice (the text is generated); scene errors otherwise.
pub fn contact_scene(cells: usize, contact: bool) -> Result<Scene> {
    let ny = (cells / 8).max(1);
    let h = 0.1 / cells as f64;
    let mut text = block_text(cells);
    text.push_str(&format!(
        r#"
[[body]]
name = "base"
material = "steel"
mesh = {{ rectangle = {{ origin = [0.0, {y0:e}], size = [0.1, {height:e}], cells = [{cells}, {ny}] }} }}
"#,
        y0 = -(ny as f64) * h,
        height = ny as f64 * h,
    ));
    if contact {
        text.push_str("\n[[contact]]\nbodies = [\"block\", \"base\"]\n");
    }
    Scene::parse(&text, Path::new("bench_contact.toml"))
}

fn build(scene: &Scene) -> Result<(Model, Plan)> {
    let model = crate::run::model(scene)?;
    let plan = Plan::new(scene, &model);
    Ok((model, plan))
}

/// The median of `x` (NaN when empty).
fn median(mut x: Vec<f64>) -> f64 {
    if x.is_empty() {
        return f64::NAN;
    }
    x.sort_by(f64::total_cmp);
    let n = x.len();
    if n % 2 == 1 {
        x[n / 2]
    } else {
        0.5 * (x[n / 2 - 1] + x[n / 2])
    }
}

/// The bare element-and-update loop on the CPU: what the element kernel does every step (gather,
/// stress, hourglass and bulk-viscosity forces scattered to the nodes, the dissipative state and
/// its work, each element's stable step and inversion measure, kept as a running minimum), then
/// the central-difference velocity and displacement update, at a fixed step; nothing else (no step
/// control or failure handling, no energies, boundaries, loads, contact or outputs). The floor a
/// step of a scene without contact is compared with.
struct BareLoop {
    model: Model,
    geometry: Vec<QuadGeometry>,
    inv_mass: Vec<f64>,
    u: Vec<[f64; 2]>,
    v: Vec<[f64; 2]>,
    f: Vec<[f64; 2]>,
    dissipation: Vec<Dissipation>,
    dt: f64,
    /// Smallest element step and corner measure of the last step, and the work so far (kept so
    /// that the element evaluation is not pruned as unused).
    dt_min: f64,
    min_corner: f64,
    work: f64,
}

impl BareLoop {
    fn new(model: Model, dt: f64) -> Self {
        let (nn, ne) = (model.node_count(), model.element_count());
        Self {
            geometry: model.corners.iter().map(quad_geometry).collect(),
            inv_mass: model.mass.iter().map(|m| 1.0 / m).collect(),
            u: vec![[0.0; 2]; nn],
            v: model.velocity.clone(),
            f: vec![[0.0; 2]; nn],
            dissipation: vec![Dissipation::default(); ne],
            model,
            dt,
            dt_min: f64::INFINITY,
            min_corner: f64::INFINITY,
            work: 0.0,
        }
    }

    fn run_steps(&mut self, steps: u64) {
        let dt = self.dt;
        for _ in 0..steps {
            for f in &mut self.f {
                *f = [0.0; 2];
            }
            let (mut dt_min, mut min_corner) = (f64::INFINITY, f64::INFINITY);
            for e in 0..self.model.element_count() {
                let q = self.model.quads[e];
                let ue = q.map(|i| self.u[i as usize]);
                let ve = q.map(|i| self.v[i as usize]);
                let out = evaluate_with(
                    self.model.params(e),
                    &self.geometry[e],
                    &self.model.corners[e],
                    &ue,
                    &ve,
                    &self.dissipation[e],
                    dt,
                );
                for a in 0..4 {
                    let n = q[a] as usize;
                    self.f[n][0] += out.force[a][0];
                    self.f[n][1] += out.force[a][1];
                }
                dt_min = dt_min.min(out.dt);
                min_corner = min_corner.min(out.min_corner);
                self.work += out.hourglass_work + out.bulk_work;
                self.dissipation[e] = Dissipation {
                    hourglass_q: out.hourglass_q,
                    bulk_p: out.bulk_p,
                };
            }
            self.dt_min = std::hint::black_box(dt_min);
            self.min_corner = std::hint::black_box(min_corner);
            for ((v, f), m) in self.v.iter_mut().zip(&self.f).zip(&self.inv_mass) {
                v[0] += dt * m * f[0];
                v[1] += dt * m * f[1];
            }
            for (u, v) in self.u.iter_mut().zip(&self.v) {
                u[0] += dt * v[0];
                u[1] += dt * v[1];
            }
        }
        self.work = std::hint::black_box(self.work);
    }
}

/// Times `f(steps)` and returns the wall seconds.
fn timed(f: impl FnOnce() -> Result<()>) -> Result<f64> {
    let t0 = Instant::now();
    f()?;
    Ok(t0.elapsed().as_secs_f64())
}

/// Per-round wall seconds of the four variants, timed in alternation (the order reversed every
/// other round, so that a drift of the machine's speed falls on all of them alike).
#[derive(Default)]
struct Rounds {
    full: Vec<f64>,
    bare: Vec<f64>,
    contact: Vec<f64>,
    free: Vec<f64>,
}

impl Rounds {
    /// Runs `rounds` rounds of `variants` (full, bare, contact, free) in alternation.
    fn measure(rounds: u32, variants: [&mut dyn FnMut() -> Result<f64>; 4]) -> Result<Rounds> {
        let mut r = Rounds::default();
        for k in 0..rounds {
            let mut order = [0usize, 1, 2, 3];
            if k % 2 == 1 {
                order.reverse();
            }
            for i in order {
                let t = (variants[i])()?;
                match i {
                    0 => r.full.push(t),
                    1 => r.bare.push(t),
                    2 => r.contact.push(t),
                    _ => r.free.push(t),
                }
            }
        }
        Ok(r)
    }

    /// (median full / bare, median extra seconds per step of the contact, median contact share).
    fn ratios(&self, per_round: u64) -> (f64, f64, f64) {
        let pairs = |a: &[f64], b: &[f64], g: &dyn Fn(f64, f64) -> f64| {
            median(a.iter().zip(b).map(|(x, y)| g(*x, *y)).collect())
        };
        (
            pairs(&self.full, &self.bare, &|f, b| f / b),
            pairs(&self.contact, &self.free, &|c, f| {
                (c - f) / per_round as f64
            }),
            pairs(&self.contact, &self.free, &|c, f| (c - f) / c),
        )
    }
}

/// Steps per round: `steps` split over `rounds` (at least one each).
fn per_round(steps: u64, rounds: u32) -> u64 {
    steps.div_ceil(u64::from(rounds.max(1))).max(1)
}

fn stopped(what: &str, taken: u64, wanted: u64) -> Error {
    Error::Bench(format!(
        "the {what} run stopped after {taken} of {wanted} steps"
    ))
}

/// Times the CPU reference on the bench scene: `rounds` rounds of `steps / rounds` steps of the
/// full step, the bare loop, and the contact scene with and without its contact, alternating.
///
/// # Errors
/// Scene errors, or [`Error::Bench`] when a run stops before it took all its steps.
pub fn cpu(cells: usize, steps: u64, rounds: u32) -> Result<BenchRow> {
    let rounds = rounds.max(1);
    let per = per_round(steps, rounds);
    let scene = scene(cells)?;
    let (model, plan) = build(&scene)?;
    let ne = model.element_count();
    let mut full = CpuSolver::new(model.clone(), plan, crate::run::schedule(&scene));
    full.run_steps(2); // warm-up, and past the first output step
    let dt = scene.run.time_step_scale * full.stable_step().0;
    let mut bare = BareLoop::new(model, dt);
    bare.run_steps(2);
    let solver = |contact: bool| -> Result<(CpuSolver, usize)> {
        let s = contact_scene(cells, contact)?;
        let (m, p) = build(&s)?;
        let n = m.element_count();
        let mut solver = CpuSolver::new(m, p, crate::run::schedule(&s));
        solver.run_steps(2); // warm-up, first search
        Ok((solver, n))
    };
    let (mut with, contact_elements) = solver(true)?;
    let (mut without, _) = solver(false)?;
    let r = Rounds::measure(
        rounds,
        [
            &mut || {
                timed(|| {
                    full.run_steps(per);
                    Ok(())
                })
            },
            &mut || {
                timed(|| {
                    bare.run_steps(per);
                    Ok(())
                })
            },
            &mut || {
                timed(|| {
                    with.run_steps(per);
                    Ok(())
                })
            },
            &mut || {
                timed(|| {
                    without.run_steps(per);
                    Ok(())
                })
            },
        ],
    )?;
    let total = per * u64::from(rounds);
    for (what, s) in [
        ("CPU", &full),
        ("CPU contact", &with),
        ("CPU free", &without),
    ] {
        if s.steps() != total + 2 {
            return Err(stopped(what, s.steps(), total + 2));
        }
    }
    let (full_over_bare, extra, share) = r.ratios(per);
    let mut row = row(
        "cpu",
        solver_adapter(),
        cells,
        ne,
        total,
        r.full.iter().sum(),
        Vec::new(),
    );
    row.rounds = rounds;
    row.bare_seconds = r.bare.iter().sum();
    row.full_over_bare = full_over_bare;
    row.contact_elements = contact_elements;
    row.contact_seconds_per_step = extra;
    row.contact_share = share;
    row.contact_searches = with.counters().contact_searches;
    Ok(row)
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
        rounds: 1,
        bare_seconds: f64::NAN,
        full_over_bare: f64::NAN,
        contact_elements: 0,
        contact_seconds_per_step: f64::NAN,
        contact_share: f64::NAN,
        contact_searches: 0,
    }
}

/// Times the GPU of `ctx`: `rounds` rounds of `steps / rounds` steps of the full step and of the
/// bare loop (element and node kernels only), each in submissions of at most
/// [`crate::gpu::solver::MAX_BATCH`] steps, and of the contact scene with and without its contact
/// (with the host searches the contact kernel asks for), alternating; then each stage alone over
/// the same steps for the shares.
///
/// # Errors
/// Scene or device errors, or [`Error::Bench`] when a contact run stops before its steps.
pub fn gpu(ctx: Arc<GpuContext>, cells: usize, steps: u64, rounds: u32) -> Result<BenchRow> {
    let rounds = rounds.max(1);
    let per = per_round(steps, rounds);
    let scene = scene(cells)?;
    let (model, plan) = build(&scene)?;
    let ne = model.element_count();
    let adapter = ctx.adapter_name();
    let mut solver = GpuSolver::new(ctx.clone(), &model, &plan, crate::run::schedule(&scene))?;
    let batch = crate::gpu::solver::MAX_BATCH as u64;
    let chunks =
        |steps: u64| (0..steps.div_ceil(batch)).map(move |k| (steps - k * batch).min(batch) as u32);
    solver.time_stage("step", 2)?; // warm-up (pipelines, first sample)
    solver.time_stage("bare", 2)?;
    let contact = |contact: bool| -> Result<(GpuSolver, usize)> {
        let s = contact_scene(cells, contact)?;
        let (m, p) = build(&s)?;
        let mut g = GpuSolver::new(ctx.clone(), &m, &p, crate::run::schedule(&s))?;
        g.run_steps(2)?; // warm-up, first search
        Ok((g, m.element_count()))
    };
    let (mut with, contact_elements) = contact(true)?;
    let (mut without, _) = contact(false)?;
    let solver_cell = std::cell::RefCell::new(&mut solver);
    let stage = |name: &str| -> Result<f64> {
        let mut s = solver_cell.borrow_mut();
        let mut t = 0.0;
        for n in chunks(per) {
            t += s.time_stage(name, n)?;
        }
        Ok(t)
    };
    let run = |g: &mut GpuSolver, what: &str| -> Result<f64> {
        let mut taken = 0;
        let t = timed(|| {
            taken = g.run_steps(per)?;
            Ok(())
        })?;
        if taken < per {
            return Err(stopped(what, taken, per));
        }
        Ok(t)
    };
    let r = Rounds::measure(
        rounds,
        [
            &mut || stage("step"),
            &mut || stage("bare"),
            &mut || run(&mut with, "GPU contact"),
            &mut || run(&mut without, "GPU free"),
        ],
    )?;
    let total = per * u64::from(rounds);
    let wall: f64 = r.full.iter().sum();
    let mut shares = Vec::new();
    for name in ["element", "node", "control"] {
        let mut t = 0.0;
        for n in chunks(total) {
            t += solver.time_stage(name, n)?;
        }
        shares.push((name.to_string(), t / wall));
    }
    let (full_over_bare, extra, share) = r.ratios(per);
    let mut row = row("gpu", adapter, cells, ne, total, wall, shares);
    row.rounds = rounds;
    row.bare_seconds = r.bare.iter().sum();
    row.full_over_bare = full_over_bare;
    row.contact_elements = contact_elements;
    row.contact_seconds_per_step = extra;
    row.contact_share = share;
    row.contact_searches = with.counters().contact_searches;
    Ok(row)
}

/// Formats rows as a table.
pub fn table(rows: &[BenchRow]) -> String {
    let mut s = format!(
        "{:<7} {:>9} {:>7} {:>10} {:>12} {:>12} {:>9} {:>12} {:>8}  {}\n",
        "backend",
        "elements",
        "steps",
        "wall [s]",
        "elem-cyc/s",
        "steps/s",
        "full/bare",
        "contact [us]",
        "contact",
        "stage shares"
    );
    for r in rows {
        let shares: Vec<String> = r
            .stage_shares
            .iter()
            .map(|(n, x)| format!("{n} {:.0}%", 100.0 * x))
            .collect();
        s.push_str(&format!(
            "{:<7} {:>9} {:>7} {:>10.3} {:>12.3e} {:>12.1} {:>9.3} {:>12.2} {:>7.1}%  {}\n",
            r.backend,
            r.elements,
            r.steps,
            r.wall_seconds,
            r.element_cycles_per_second,
            r.steps_per_second,
            r.full_over_bare,
            1e6 * r.contact_seconds_per_step,
            100.0 * r.contact_share,
            shares.join(", ")
        ));
    }
    s
}

/// The ratios of each row in words: the full step over the bare loop, and what the contact pair
/// adds per step.
pub fn summary(rows: &[BenchRow]) -> String {
    let mut s = String::new();
    for r in rows {
        s.push_str(&format!(
            "{} {} elements: full step / bare element+update loop = {:.3} (median of {} rounds); \
             a contact pair (block on a base, {} elements, {} searches) adds {:.2} us per step, \
             {:.1} % of the step with contact\n",
            r.backend,
            r.elements,
            r.full_over_bare,
            r.rounds,
            r.contact_elements,
            r.contact_searches,
            1e6 * r.contact_seconds_per_step,
            100.0 * r.contact_share
        ));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_of_odd_even_and_empty() {
        assert_eq!(median(vec![3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(vec![4.0, 1.0, 2.0, 3.0]), 2.5);
        assert!(median(Vec::new()).is_nan());
    }

    #[test]
    fn contact_scene_has_the_pair_only_when_asked() {
        let (m, p) = build(&contact_scene(8, true).expect("scene")).expect("model");
        assert_eq!((m.bodies.len(), p.contacts), (2, 1));
        assert_eq!(m.element_count(), 64 + 8);
        let (_, p) = build(&contact_scene(8, false).expect("scene")).expect("model");
        assert_eq!(p.contacts, 0);
    }
}
