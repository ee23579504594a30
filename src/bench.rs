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

use crate::element::{evaluate_with, Dissipation};
use crate::error::{Error, Result};
use crate::geometry::{quad_geometry, QuadGeometry};
use crate::gpu::{GpuContext, GpuSolver};
use crate::model::Model;
use crate::plan::Plan;
use crate::scene::Scene;
use crate::step::cpu::CpuSolver;
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

/// The text of the block of [`scene`]: `cells` x `cells` quads, 0.1 m wide.
pub fn block_text(cells: usize) -> String {
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

/// The text of [`contact_scene`].
pub fn contact_text(cells: usize, contact: bool) -> String {
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
    text
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
    Scene::parse(
        &contact_text(cells, contact),
        Path::new("bench_contact.toml"),
    )
}

fn build(scene: &Scene) -> Result<(Model, Plan)> {
    // Before meshing: a size beyond the machine's memory is refused, not allocated.
    crate::run::check_memory(scene)?;
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
                self.dissipation[e] = out.dissipation;
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
/// [`crate::gpu::state::MAX_BATCH`] steps, and of the contact scene with and without its contact
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
    let batch = crate::gpu::state::MAX_BATCH as u64;
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

// ---------------------------------------------------------------------------------------------
// Contact scenes (the second table): the block pressed into its base, a striker into a plate and
// a pile of disks on a wall, at a chosen size, each timed with and without its `[[contact]]`.
// ---------------------------------------------------------------------------------------------

/// Striker side [m] of [`striker_text`] (the plate is 5 x 1 of it).
pub const STRIKER_SIDE: f64 = 0.01;
/// Impact velocity [m/s] of [`striker_text`]: v0 / c = 0.05 for steel (c about 6000 m/s).
pub const STRIKER_VELOCITY: f64 = 300.0;
/// O-grid cells of each disk of [`pile_text`] (3 x 6^2 = 108 elements per disk).
pub const PILE_DISK_CELLS: usize = 6;
/// Disk radius [m] of [`pile_text`].
pub const PILE_RADIUS: f64 = 0.005;
/// Fall velocity [m/s] of [`pile_text`].
pub const PILE_VELOCITY: f64 = 20.0;

/// How [`pile_text`] puts its disks in contact.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PileContact {
    /// One `[[contact]]` with `bodies = "all"` (the default).
    All,
    /// One `[[contact]]` per pair of disks (`side^2 (side^2 - 1) / 2` of them): a fallback for
    /// builds whose scene parser does not know `bodies = "all"`; for small piles only.
    Pairs,
}

/// The run settings of a generated contact scene (`ricochet run` of the committed files); the
/// bench replaces the end time and the output intervals (see [`bench_schedule`]).
fn run_header(comment: &str, end_time: f64, history: f64, fields: f64) -> String {
    let mut s = String::new();
    for line in comment.lines() {
        s.push_str("# ");
        s.push_str(line);
        s.push('\n');
    }
    s.push_str(&format!(
        "\n[run]\nend_time = {end_time:e}\nhistory_interval = {history:e}\nfield_interval = {fields:e}\n"
    ));
    s
}

/// The striker scene of `n`: a steel striker of n x n quads (10 mm square) hitting a steel plate
/// of 5n x n quads (50 x 10 mm, its bottom edge fixed by a `[[boundary]]`) at
/// [`STRIKER_VELOCITY`] (v0 / c = 0.05, so that the contact search is due every few steps),
/// plane strain, neo-Hookean, with the default bulk viscosity and viscous hourglass control. The
/// striker starts half an element above the plate, centred, shifted by a quarter element so that
/// the nodes do not match, and the contact starts within the first steps. 6 n^2 elements
/// (n = 41, 129, 408 for about 1e4, 1e5, 1e6). With `contact`, one Lagrange `[[contact]]`
/// between the two bodies; without, the striker passes into the plate.
pub fn striker_text(n: usize, contact: bool) -> String {
    let n = n.max(1);
    let s = STRIKER_SIDE;
    let h = s / n as f64;
    let mut text = run_header(
        &format!(
            "Contact bench scene (ricochet bench --scene striker), generated by\n\
             ricochet::bench::striker_text({n}, {contact}): {e} elements.\n\
             A steel striker ({n} x {n} quads, 10 mm) hits a plate ({p} x {n} quads, 50 x 10 mm,\n\
             bottom edge fixed) at {v} m/s (v0 / c = 0.05), neo-Hookean, Lagrange contact.",
            e = 6 * n * n,
            p = 5 * n,
            v = STRIKER_VELOCITY,
        ),
        2.0e-5,
        2.0e-7,
        4.0e-6,
    );
    text.push_str(&format!(
        r#"
[[material]]
name = "steel"
model = "neo_hookean"
density = 7850.0
youngs_modulus = 2.1e11
poisson_ratio = 0.3

[[body]]
name = "striker"
material = "steel"
mesh = {{ rectangle = {{ origin = [{sx:e}, {sy:e}], size = [{s:e}, {s:e}], cells = [{n}, {n}] }} }}
initial_velocity = [0.0, {vy:?}]

[[body]]
name = "plate"
material = "steel"
mesh = {{ rectangle = {{ origin = [0.0, 0.0], size = [{pw:e}, {s:e}], cells = [{pn}, {n}] }} }}

[[boundary]]
body = "plate"
region = {{ min = [{lo:e}, {lo:e}], max = [{hi:e}, {top:e}] }}
velocity = {{ x = 0.0, y = 0.0 }}
"#,
        sx = 2.0 * s + 0.25 * h,
        sy = s + 0.5 * h,
        vy = -STRIKER_VELOCITY,
        pw = 5.0 * s,
        pn = 5 * n,
        lo = -0.5 * h,
        hi = 5.0 * s + 0.5 * h,
        top = 0.5 * h,
    ));
    if contact {
        text.push_str("\n[[contact]]\nbodies = [\"striker\", \"plate\"]\nmethod = \"lagrange\"\n");
    }
    text
}

/// The striker scene of [`striker_text`], parsed.
///
/// # Errors
/// None in practice (the text is generated); scene errors otherwise.
pub fn striker_scene(n: usize, contact: bool) -> Result<Scene> {
    Scene::parse(&striker_text(n, contact), Path::new("bench_striker.toml"))
}

/// Elements of one disk of `cells` O-grid cells (see [`crate::mesh::disk`]).
pub fn disk_elements(cells: usize) -> usize {
    cells * cells + 4 * cells * (cells / 2).max(1)
}

/// The pile scene of `side`: side x side steel disks ([`PILE_RADIUS`], [`PILE_DISK_CELLS`]
/// cells, 108 elements each) on a grid with gaps of a tenth of the radius, every other row
/// shifted by a quarter of the pitch, falling at about [`PILE_VELOCITY`] (each disk's velocity
/// perturbed by up to 1 m/s in x and y, deterministically, so that they do not fall as rigid
/// columns) onto a rigid wall (Lagrange) a tenth of the radius below the lowest row; plane
/// strain, linear elastic. `side` = 10, 32, 100 for about 1e4, 1e5, 1e6 elements (108 side^2).
/// `contact`: `None` for the run without contact (the disks pass through each other, the wall
/// stays), else the disks' `[[contact]]` (see [`PileContact`]).
pub fn pile_text(side: usize, contact: Option<PileContact>) -> String {
    let side = side.max(1);
    let disks = side * side;
    let r = PILE_RADIUS;
    let gap = 0.1 * r;
    let pitch = 2.0 * r + gap;
    let how = match contact {
        None => "no contact between the disks",
        Some(PileContact::All) => "one [[contact]] over all bodies",
        Some(PileContact::Pairs) => "one [[contact]] per pair of disks",
    };
    let mut text = run_header(
        &format!(
            "Contact bench scene (ricochet bench --scene pile), generated by\n\
             ricochet::bench::pile_text({side}, {contact:?}): {e} elements.\n\
             {disks} steel disks ({side} x {side}, R = 5 mm, {c} cells, {d} elements each) fall at\n\
             about {v} m/s onto a rigid wall; {how}.",
            e = disks * disk_elements(PILE_DISK_CELLS),
            c = PILE_DISK_CELLS,
            d = disk_elements(PILE_DISK_CELLS),
            v = PILE_VELOCITY,
        ),
        1.0e-3,
        1.0e-5,
        1.0e-4,
    );
    text.push_str(
        r#"
[[material]]
name = "steel"
model = "linear_elastic"
density = 7850.0
youngs_modulus = 2.1e11
poisson_ratio = 0.3
"#,
    );
    for j in 0..side {
        for i in 0..side {
            let shift = if j % 2 == 1 { 0.25 } else { 0.0 };
            let x = (i as f64 + 0.5 + shift) * pitch;
            let y = gap + r + j as f64 * pitch;
            let vx = 0.5 * ((i * 7 + j * 3) % 5) as f64 - 1.0;
            let vy = -PILE_VELOCITY + 0.5 * ((i * 3 + j * 5 + 2) % 5) as f64 - 1.0;
            text.push_str(&format!(
                r#"
[[body]]
name = "d{k}"
material = "steel"
mesh = {{ disk = {{ center = [{x:e}, {y:e}], radius = {r:e}, cells = {c} }} }}
initial_velocity = [{vx:?}, {vy:?}]
"#,
                k = j * side + i,
                c = PILE_DISK_CELLS,
            ));
        }
    }
    text.push_str(
        "\n[[rigid_wall]]\nname = \"floor\"\npoint = [0.0, 0.0]\nnormal = [0.0, 1.0]\n\
         method = \"lagrange\"\n",
    );
    match contact {
        None => {}
        Some(PileContact::All) => text
            .push_str("\n[[contact]]\nname = \"pile\"\nbodies = \"all\"\nmethod = \"lagrange\"\n"),
        Some(PileContact::Pairs) => {
            for a in 0..disks {
                for b in a + 1..disks {
                    text.push_str(&format!(
                        "\n[[contact]]\nbodies = [\"d{a}\", \"d{b}\"]\nmethod = \"lagrange\"\n"
                    ));
                }
            }
        }
    }
    text
}

/// The pile scene of [`pile_text`], parsed.
///
/// # Errors
/// Scene errors: `PileContact::All` where `bodies = "all"` is not supported yet.
pub fn pile_scene(side: usize, contact: Option<PileContact>) -> Result<Scene> {
    Scene::parse(&pile_text(side, contact), Path::new("bench_pile.toml"))
}

/// The contact scenes of the second bench table.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ContactScene {
    /// The block pressed into its base ([`contact_scene`]); size: cells per side of the block.
    Pair,
    /// A striker into a plate at v0 / c = 0.05 ([`striker_text`]); size: striker cells per side.
    Striker,
    /// A pile of disks dropped onto a rigid wall ([`pile_text`]); size: disks per side.
    Pile,
}

impl ContactScene {
    /// All contact scenes, in table order.
    pub const ALL: [ContactScene; 3] = [
        ContactScene::Pair,
        ContactScene::Striker,
        ContactScene::Pile,
    ];

    /// The scene's name in the table and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            ContactScene::Pair => "pair",
            ContactScene::Striker => "striker",
            ContactScene::Pile => "pile",
        }
    }

    /// Elements of the scene of `size`.
    pub fn elements(self, size: usize) -> usize {
        let size = size.max(1);
        match self {
            ContactScene::Pair => size * size + size * (size / 8).max(1),
            ContactScene::Striker => 6 * size * size,
            ContactScene::Pile => size * size * disk_elements(PILE_DISK_CELLS),
        }
    }

    /// The size whose scene has about `elements` elements (at least 1): the block's cells per
    /// side (elements / 1.125), the striker's n (elements / 6; 41, 129, 408 for 1e4, 1e5, 1e6),
    /// the pile's disks per side (about 100 elements per disk; 10, 32, 100).
    pub fn size_for(self, elements: usize) -> usize {
        let per = match self {
            ContactScene::Pair => 1.125,
            ContactScene::Striker => 6.0,
            ContactScene::Pile => 100.0,
        };
        ((elements as f64 / per).sqrt().round() as usize).max(1)
    }

    /// The scene text of `size`, with or without its contact (`pile`: how the pile's disks are
    /// put in contact).
    pub fn text(self, size: usize, contact: bool, pile: PileContact) -> String {
        match self {
            ContactScene::Pair => contact_text(size, contact),
            ContactScene::Striker => striker_text(size, contact),
            ContactScene::Pile => pile_text(size, contact.then_some(pile)),
        }
    }

    /// The parsed scene of [`ContactScene::text`].
    ///
    /// # Errors
    /// Scene errors (the pile's `bodies = "all"` where it is not supported yet).
    pub fn scene(self, size: usize, contact: bool, pile: PileContact) -> Result<Scene> {
        let name = format!("bench_{}.toml", self.name());
        Scene::parse(&self.text(size, contact, pile), Path::new(&name))
    }
}

/// The schedule of a bench run of `scene`: its own step control, but no end (1e3 s) and no
/// outputs due during the bench (history every 1e3 s, no fields).
pub fn bench_schedule(scene: &Scene) -> crate::step::Schedule {
    let mut s = crate::run::schedule(scene);
    s.end_time = 1.0e3;
    s.history_interval = 1.0e3;
    s.field_interval = None;
    s
}

/// How a contact scene is timed ([`cpu_contact`], [`gpu_contact`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactTiming {
    /// Steps timed of each variant, split over `rounds` rounds in alternation.
    pub steps: u64,
    /// Rounds (medians reported).
    pub rounds: u32,
    /// Steps each variant runs before the timed ones (at least 2: the first search): the pile's
    /// disks reach the wall after about 440 steps, its bottom row all touches by 600.
    pub warmup: u64,
    /// How the pile puts its disks in contact.
    pub pile: PileContact,
    /// A Coulomb coefficient for a third variant with friction on every contact and wall.
    pub friction: Option<f64>,
    /// Plain projected Gauss-Seidel sweeps instead of the extrapolated ones, on both backends
    /// ([`crate::contact::extrapolation`]): a comparison.
    pub plain_sweeps: bool,
}

/// Warm-up steps of a contact row unless asked for more: two, the first search included.
pub const DEFAULT_WARMUP: u64 = 2;

/// One row of the contact-scene table.
#[derive(Debug, Clone, Serialize)]
pub struct ContactRow {
    /// The scene.
    pub scene: ContactScene,
    /// "cpu" or "gpu".
    pub backend: String,
    /// Adapter or processor.
    pub adapter: String,
    /// Size parameter of the scene (see [`ContactScene`]).
    pub size: usize,
    /// Elements.
    pub elements: usize,
    /// Bodies.
    pub bodies: usize,
    /// Steps timed of each variant (with and without contact).
    pub steps: u64,
    /// Rounds the steps were split into, the two variants timed in alternation.
    pub rounds: u32,
    /// Steps each variant ran before the timed ones.
    pub warmup: u64,
    /// Plain projected Gauss-Seidel sweeps (not extrapolated).
    pub plain_sweeps: bool,
    /// Wall seconds of the timed steps with contact.
    pub wall_seconds: f64,
    /// Steps per second with contact.
    pub steps_per_second: f64,
    /// Wall seconds of the same steps without the scene's `[[contact]]` (walls kept).
    pub free_seconds: f64,
    /// Median over the rounds of (with - without) / with: the contact share of the step.
    pub contact_share: f64,
    /// With `--friction`: the Coulomb coefficient of the third variant (the contacts and walls
    /// with friction), else `None`.
    pub friction: Option<f64>,
    /// With `--friction`: steps per second of the variant with friction.
    pub friction_steps_per_second: Option<f64>,
    /// With `--friction`: median over the rounds of (with friction - with) / steps, in
    /// microseconds: what friction adds to a contact step.
    pub friction_us_per_step: Option<f64>,
    /// Lagrange contact: the solver's sweeps per step with constraints, mean over the run so
    /// far (0 without Lagrange constraints).
    pub sweeps_mean: f64,
    /// With `--friction`: the same for the variant with friction.
    pub friction_sweeps_mean: Option<f64>,
    /// Broad-phase searches during the timed steps with contact.
    pub searches: u64,
    /// Searches per 100 timed steps.
    pub searches_per_100_steps: f64,
    /// Bytes read back from the device per timed step with contact (0 on the CPU).
    pub bytes_read_back_per_step: f64,
    /// Timed against the CPU reference in the same rounds (`--backend both`): the median over
    /// the rounds of the CPU reference's time for the steps with contact over this backend's,
    /// i.e. this backend's speed as a multiple of the CPU's. `None` on the CPU's own row and
    /// where the CPU reference was not timed alongside.
    pub vs_cpu: Option<f64>,
}

/// Times `variants` in `rounds` rounds, alternating (the order reversed every other round, so
/// that a drift of the machine's speed falls on all of them alike); returns each variant's
/// per-round wall seconds.
fn alternate(
    rounds: u32,
    variants: &mut [&mut dyn FnMut() -> Result<f64>],
) -> Result<Vec<Vec<f64>>> {
    let mut times = vec![Vec::new(); variants.len()];
    let mut order: Vec<usize> = (0..variants.len()).collect();
    for k in 0..rounds {
        if k > 0 {
            order.reverse();
        }
        for &i in &order {
            let t = (variants[i])()?;
            times[i].push(t);
        }
    }
    Ok(times)
}

/// A solver of one variant of a contact scene, as the bench drives it.
trait Timed {
    /// Takes `steps` steps; the steps taken.
    fn take(&mut self, steps: u64) -> Result<u64>;
    /// The solver's counters.
    fn count(&self) -> crate::step::Counters;
}

impl Timed for CpuSolver {
    fn take(&mut self, steps: u64) -> Result<u64> {
        let before = self.steps();
        self.run_steps(steps);
        Ok(self.steps() - before)
    }
    fn count(&self) -> crate::step::Counters {
        self.counters()
    }
}

impl Timed for GpuSolver {
    fn take(&mut self, steps: u64) -> Result<u64> {
        self.run_steps(steps)
    }
    fn count(&self) -> crate::step::Counters {
        self.counters()
    }
}

/// One backend's solvers of a contact scene, as [`contact_rows`] times them: with and without
/// the scene's `[[contact]]`, and with friction when asked.
struct Side<'a> {
    backend: &'static str,
    adapter: String,
    with: &'a mut dyn Timed,
    without: &'a mut dyn Timed,
    friction: Option<&'a mut dyn Timed>,
}

impl Side<'_> {
    fn variants(&mut self) -> Vec<(&'static str, &mut dyn Timed)> {
        let mut v: Vec<(&'static str, &mut dyn Timed)> =
            vec![("contact", &mut *self.with), ("free", &mut *self.without)];
        if let Some(f) = self.friction.as_mut() {
            v.push(("friction", &mut **f));
        }
        v
    }
}

/// Times the solvers of every side of a contact scene (each with and without its contact, and
/// with friction when asked) in alternating rounds, all sides in the same rounds (after
/// `timing.warmup` warm-up steps each, at least 2: the first search included), and fills a row
/// per side. The sides after a first `"cpu"` side get [`ContactRow::vs_cpu`].
fn contact_rows(
    which: ContactScene,
    size: usize,
    model: &Model,
    mut sides: Vec<Side<'_>>,
    mu: Option<f64>,
    timing: &ContactTiming,
) -> Result<Vec<ContactRow>> {
    let rounds = timing.rounds.max(1);
    let per = per_round(timing.steps, rounds);
    let warmup = timing.warmup.max(DEFAULT_WARMUP);
    for side in &mut sides {
        let backend = side.backend;
        for (what, s) in side.variants() {
            let taken = s.take(warmup)?;
            if taken < warmup {
                return Err(stopped(
                    &format!("{backend} {} {what} warm-up", which.name()),
                    taken,
                    warmup,
                ));
            }
        }
    }
    let before: Vec<_> = sides.iter().map(|s| s.with.count()).collect();
    let cpu_first = sides.first().is_some_and(|s| s.backend == "cpu");
    let meta: Vec<(&'static str, String)> = sides
        .iter()
        .map(|s| (s.backend, s.adapter.clone()))
        .collect();
    // Every variant of every side, in one alternation.
    let mut runs: Vec<Box<dyn FnMut() -> Result<f64> + '_>> = Vec::new();
    let mut counts = Vec::new();
    for side in &mut sides {
        let backend = side.backend;
        let variants = side.variants();
        counts.push(variants.len());
        for (what, s) in variants {
            runs.push(Box::new(move || {
                let t0 = Instant::now();
                let taken = s.take(per)?;
                let t = t0.elapsed().as_secs_f64();
                if taken < per {
                    return Err(stopped(
                        &format!("{backend} {} {what}", which.name()),
                        taken,
                        per,
                    ));
                }
                Ok(t)
            }));
        }
    }
    let mut refs: Vec<&mut dyn FnMut() -> Result<f64>> =
        runs.iter_mut().map(|r| &mut **r as _).collect();
    let times = alternate(rounds, &mut refs)?;
    drop(refs);
    drop(runs);
    let total = per * u64::from(rounds);
    let mut rows = Vec::new();
    let mut at = 0;
    for (k, side) in sides.iter().enumerate() {
        let t = &times[at..at + counts[k]];
        at += counts[k];
        let after = side.with.count();
        let wall: f64 = t[0].iter().sum();
        let (friction_steps_per_second, friction_us_per_step) = match t.get(2) {
            Some(tf) => (
                Some(total as f64 / tf.iter().sum::<f64>()),
                Some(median(
                    tf.iter()
                        .zip(&t[0])
                        .map(|(f, c)| 1e6 * (f - c) / per as f64)
                        .collect(),
                )),
            ),
            None => (None, None),
        };
        let vs_cpu = (cpu_first && k > 0)
            .then(|| median(times[0].iter().zip(&t[0]).map(|(c, g)| c / g).collect()));
        let searches = after.contact_searches - before[k].contact_searches;
        rows.push(ContactRow {
            scene: which,
            backend: meta[k].0.to_string(),
            adapter: meta[k].1.clone(),
            size,
            elements: model.element_count(),
            bodies: model.bodies.len(),
            steps: total,
            rounds,
            warmup,
            plain_sweeps: timing.plain_sweeps,
            wall_seconds: wall,
            steps_per_second: total as f64 / wall,
            free_seconds: t[1].iter().sum(),
            contact_share: median(t[0].iter().zip(&t[1]).map(|(c, f)| (c - f) / c).collect()),
            friction: mu,
            friction_steps_per_second,
            friction_us_per_step,
            sweeps_mean: after.contact_sweeps_mean,
            friction_sweeps_mean: side
                .friction
                .as_ref()
                .map(|f| f.count().contact_sweeps_mean),
            searches,
            searches_per_100_steps: 100.0 * searches as f64 / total as f64,
            bytes_read_back_per_step: (after.bytes_read_back - before[k].bytes_read_back) as f64
                / total as f64,
            vs_cpu,
        });
    }
    Ok(rows)
}

/// `text` with `friction = mu` in every `[[contact]]` and `[[rigid_wall]]` table (the line goes
/// right under the table's header, so the tables keep their other keys).
pub fn with_friction(text: &str, mu: f64) -> String {
    let mut s = String::with_capacity(text.len() + 64);
    for line in text.lines() {
        s.push_str(line);
        s.push('\n');
        if matches!(line.trim(), "[[contact]]" | "[[rigid_wall]]") {
            s.push_str(&format!("friction = {mu:?}\n"));
        }
    }
    s
}

/// Builds the model, plan and schedule of a contact scene variant (`friction`: the Coulomb
/// coefficient put on its contacts and walls, see [`with_friction`]).
fn contact_build(
    which: ContactScene,
    size: usize,
    contact: bool,
    pile: PileContact,
    friction: Option<f64>,
) -> Result<(Model, Plan, crate::step::Schedule)> {
    let mut text = which.text(size, contact, pile);
    if let Some(mu) = friction {
        text = with_friction(&text, mu);
    }
    let name = format!("bench_{}.toml", which.name());
    let scene = Scene::parse(&text, Path::new(&name))?;
    let (model, plan) = build(&scene)?;
    Ok((model, plan, bench_schedule(&scene)))
}

/// The solvers of a contact scene on one backend: with and without its `[[contact]]`, and with
/// friction when `timing.friction` asks; and the model with contact.
type Solvers<S> = (Model, S, S, Option<S>);

fn cpu_solvers(
    which: ContactScene,
    size: usize,
    timing: &ContactTiming,
) -> Result<Solvers<CpuSolver>> {
    let pile = timing.pile;
    let plain = |(m, p, s): (Model, Plan, crate::step::Schedule)| {
        let mut solver = CpuSolver::new(m, p, s);
        if let Some(c) = solver.contact_mut() {
            c.set_plain_sweeps(timing.plain_sweeps);
        }
        solver
    };
    let (model, plan, schedule) = contact_build(which, size, true, pile, None)?;
    let with = plain((model.clone(), plan, schedule));
    let without = plain(contact_build(which, size, false, pile, None)?);
    let rough = match timing.friction {
        Some(mu) => Some(plain(contact_build(which, size, true, pile, Some(mu))?)),
        None => None,
    };
    Ok((model, with, without, rough))
}

fn gpu_solvers(
    ctx: &Arc<GpuContext>,
    which: ContactScene,
    size: usize,
    timing: &ContactTiming,
) -> Result<Solvers<GpuSolver>> {
    let pile = timing.pile;
    let options = crate::gpu::contact::ContactOptions {
        plain_sweeps: timing.plain_sweeps,
        ..Default::default()
    };
    let solver = |(m, p, s): (Model, Plan, crate::step::Schedule)| {
        GpuSolver::with_options(ctx.clone(), &m, &p, s, None, options)
    };
    let (model, plan, schedule) = contact_build(which, size, true, pile, None)?;
    let with = solver((model.clone(), plan, schedule))?;
    let without = solver(contact_build(which, size, false, pile, None)?)?;
    let rough = match timing.friction {
        Some(mu) => Some(solver(contact_build(which, size, true, pile, Some(mu))?)?),
        None => None,
    };
    Ok((model, with, without, rough))
}

fn side<'a, S: Timed>(
    backend: &'static str,
    adapter: String,
    (_, with, without, rough): &'a mut Solvers<S>,
) -> Side<'a> {
    Side {
        backend,
        adapter,
        with,
        without,
        friction: rough.as_mut().map(|s| s as &mut dyn Timed),
    }
}

fn only(mut rows: Vec<ContactRow>) -> Result<ContactRow> {
    rows.pop()
        .ok_or_else(|| Error::Bench("a contact scene gave no row".into()))
}

/// Times the CPU reference on a contact scene of `size`: `rounds` rounds of `steps / rounds`
/// steps with and without the scene's `[[contact]]`, alternating; with `friction`, also the
/// scene with that Coulomb coefficient on its contacts and walls (a third variant).
///
/// # Errors
/// Scene errors, or [`Error::Bench`] when a run stops before it took all its steps.
pub fn cpu_contact(which: ContactScene, size: usize, timing: &ContactTiming) -> Result<ContactRow> {
    let mut cpu = cpu_solvers(which, size, timing)?;
    let model = cpu.0.clone();
    let sides = vec![side("cpu", solver_adapter(), &mut cpu)];
    only(contact_rows(
        which,
        size,
        &model,
        sides,
        timing.friction,
        timing,
    )?)
}

/// Times the GPU of `ctx` on a contact scene of `size`, as [`cpu_contact`] (with
/// [`GpuSolver::run_steps`], the host searches the contact kernel asks for included).
///
/// # Errors
/// Scene or device errors (the GPU backend limits the number of bodies), or [`Error::Bench`]
/// when a run stops before it took all its steps.
pub fn gpu_contact(
    ctx: Arc<GpuContext>,
    which: ContactScene,
    size: usize,
    timing: &ContactTiming,
) -> Result<ContactRow> {
    let mut gpu = gpu_solvers(&ctx, which, size, timing)?;
    let model = gpu.0.clone();
    let sides = vec![side("gpu", ctx.adapter_name(), &mut gpu)];
    only(contact_rows(
        which,
        size,
        &model,
        sides,
        timing.friction,
        timing,
    )?)
}

/// Times the CPU reference and the GPU of `ctx` on a contact scene of `size` in the same
/// alternating rounds (every variant of both, the order reversed every other round), so that
/// the GPU row's [`ContactRow::vs_cpu`] compares the two under the same drift of the machine's
/// speed; the CPU's row, then the GPU's.
///
/// # Errors
/// As [`cpu_contact`] and [`gpu_contact`].
pub fn both_contact(
    ctx: Arc<GpuContext>,
    which: ContactScene,
    size: usize,
    timing: &ContactTiming,
) -> Result<Vec<ContactRow>> {
    let mut gpu = gpu_solvers(&ctx, which, size, timing)?;
    let mut cpu = cpu_solvers(which, size, timing)?;
    let model = cpu.0.clone();
    let sides = vec![
        side("cpu", solver_adapter(), &mut cpu),
        side("gpu", ctx.adapter_name(), &mut gpu),
    ];
    contact_rows(which, size, &model, sides, timing.friction, timing)
}

/// Formats contact rows as a table.
/// With `--friction`, two more columns: the steps per second with friction and what friction
/// adds to a step (microseconds); with `--plain-sweeps`, a line saying so under it.
pub fn contact_table(rows: &[ContactRow]) -> String {
    let rough = rows.iter().any(|r| r.friction.is_some());
    let mut s = format!(
        "{:<8} {:<7} {:>9} {:>6} {:>7} {:>10} {:>8} {:>15} {:>16}",
        "scene",
        "backend",
        "elements",
        "bodies",
        "steps",
        "steps/s",
        "contact",
        "searches/100 st",
        "read back [B/st]"
    );
    s.push_str(&format!(" {:>6}", "sweeps"));
    let versus = rows.iter().any(|r| r.vs_cpu.is_some());
    if versus {
        s.push_str(&format!(" {:>7}", "vs CPU"));
    }
    if rough {
        s.push_str(&format!(
            " {:>16} {:>18} {:>15}",
            "friction steps/s", "friction [us/st]", "friction sweeps"
        ));
    }
    s.push('\n');
    for r in rows {
        s.push_str(&format!(
            "{:<8} {:<7} {:>9} {:>6} {:>7} {:>10.1} {:>7.1}% {:>15.1} {:>16.0}",
            r.scene.name(),
            r.backend,
            r.elements,
            r.bodies,
            r.steps,
            r.steps_per_second,
            100.0 * r.contact_share,
            r.searches_per_100_steps,
            r.bytes_read_back_per_step
        ));
        s.push_str(&format!(" {:>6.1}", r.sweeps_mean));
        if versus {
            match r.vs_cpu {
                Some(v) => s.push_str(&format!(" {v:>7.2}")),
                None => s.push_str(&format!(" {:>7}", "-")),
            }
        }
        if rough {
            match (
                r.friction_steps_per_second,
                r.friction_us_per_step,
                r.friction_sweeps_mean,
            ) {
                (Some(f), Some(us), Some(sw)) => {
                    s.push_str(&format!(" {f:>16.1} {us:>18.2} {sw:>15.1}"))
                }
                _ => s.push_str(&format!(" {:>16} {:>18} {:>15}", "-", "-", "-")),
            }
        }
        s.push('\n');
    }
    if rows.iter().any(|r| r.plain_sweeps) {
        s.push_str("(plain projected Gauss-Seidel sweeps, not extrapolated)\n");
    }
    if versus {
        s.push_str(
            "(vs CPU: the steps with contact, CPU reference time over this backend's, median over \
             rounds timed in alternation with the CPU's)\n",
        );
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
    /// The committed scene files of assets/bench/ are the generators' output (set
    /// `RICOCHET_BLESS=1` to rewrite them).
    #[test]
    fn committed_bench_scenes_are_the_generators_output() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/bench");
        for (file, text) in [
            ("striker_1e4.toml", striker_text(41, true)),
            ("pile_1e4.toml", pile_text(10, Some(PileContact::All))),
        ] {
            let path = dir.join(file);
            if std::env::var_os("RICOCHET_BLESS").is_some() {
                std::fs::create_dir_all(&dir).expect("assets/bench");
                std::fs::write(&path, &text).expect("write");
            }
            let committed = std::fs::read_to_string(&path).expect("committed scene");
            assert!(
                committed == text,
                "{file} differs from the generator (RICOCHET_BLESS=1)"
            );
        }
    }

    #[test]
    fn sizes_map_to_the_element_targets() {
        let sizes = |s: ContactScene| [10_000, 100_000, 1_000_000].map(|e| s.size_for(e));
        assert_eq!(sizes(ContactScene::Striker), [41, 129, 408]);
        assert_eq!(sizes(ContactScene::Pile), [10, 32, 100]);
        assert_eq!(ContactScene::Pile.elements(32), 110_592);
        assert_eq!(ContactScene::Striker.elements(41), 10_086);
        assert_eq!(disk_elements(4), 48);
    }

    #[test]
    fn generated_contact_scenes_parse_with_the_expected_counts() {
        let (m, p) = build(&striker_scene(4, true).expect("striker")).expect("model");
        assert_eq!(m.element_count(), ContactScene::Striker.elements(4));
        assert_eq!((m.bodies.len(), p.contacts), (2, 1));
        let scene = striker_scene(4, false).expect("striker");
        assert_eq!((scene.boundaries.len(), scene.contacts.len()), (1, 0));
        // The pile with `bodies = "all"`, or with explicit pairs where that does not parse yet.
        let (scene, pairs) = match pile_scene(3, Some(PileContact::All)) {
            Ok(s) => (s, false),
            Err(_) => (pile_scene(3, Some(PileContact::Pairs)).expect("pile"), true),
        };
        let (m, _) = build(&scene).expect("model");
        assert_eq!(m.element_count(), ContactScene::Pile.elements(3));
        assert_eq!((m.bodies.len(), scene.walls.len()), (9, 1));
        assert_eq!(scene.contacts.len(), if pairs { 36 } else { 1 });
        let scene = pile_scene(3, None).expect("pile");
        assert_eq!((scene.contacts.len(), scene.walls.len()), (0, 1));
        for which in ContactScene::ALL {
            let s = which.scene(8, true, PileContact::Pairs).expect("scene");
            let (m, _) = build(&s).expect("model");
            assert_eq!(m.element_count(), which.elements(8), "{}", which.name());
        }
    }

    fn timing(steps: u64, rounds: u32, pile: PileContact, friction: Option<f64>) -> ContactTiming {
        ContactTiming {
            steps,
            rounds,
            warmup: DEFAULT_WARMUP,
            pile,
            friction,
            plain_sweeps: false,
        }
    }

    /// `warmup` runs each variant of a contact scene that many steps before the timed ones: the
    /// pile's disks (half a millimetre above the wall at 20 m/s, about 440 steps) are in contact
    /// in the timed steps after 600 of them, and not after the default 2.
    #[test]
    fn contact_rows_warm_up_into_contact_when_asked() {
        let cold = timing(20, 2, PileContact::All, None);
        let warm = ContactTiming {
            warmup: 600,
            ..cold
        };
        let cold = cpu_contact(ContactScene::Pile, 2, &cold).expect("bench row");
        let warm = cpu_contact(ContactScene::Pile, 2, &warm).expect("bench row");
        assert_eq!((cold.warmup, warm.warmup), (DEFAULT_WARMUP, 600));
        assert_eq!((warm.steps, warm.rounds), (20, 2));
        assert_eq!(cold.sweeps_mean, 0.0, "no contact in the first 22 steps");
        assert!(
            warm.sweeps_mean > 0.0,
            "the disks touch the wall after 600 steps"
        );
    }

    /// `plain_sweeps` reaches the CPU reference's solver: the striker's two-pass constraints take
    /// more sweeps a step plain than extrapolated, and the row says which it timed.
    #[test]
    fn plain_sweeps_reach_the_solver_and_the_row() {
        let extra = timing(40, 2, PileContact::All, None);
        let plain = ContactTiming {
            plain_sweeps: true,
            ..extra
        };
        let e = cpu_contact(ContactScene::Striker, 12, &extra).expect("bench row");
        let p = cpu_contact(ContactScene::Striker, 12, &plain).expect("bench row");
        assert_eq!((e.plain_sweeps, p.plain_sweeps), (false, true));
        assert!(e.sweeps_mean > 0.0, "the striker is in contact");
        assert!(
            p.sweeps_mean > e.sweeps_mean,
            "{} plain against {} extrapolated",
            p.sweeps_mean,
            e.sweeps_mean
        );
        assert!(contact_table(&[p]).contains("plain projected Gauss-Seidel"));
    }

    #[test]
    fn contact_rows_on_the_cpu_take_their_steps() {
        let row = cpu_contact(
            ContactScene::Striker,
            4,
            &timing(4, 2, PileContact::Pairs, None),
        )
        .expect("row");
        assert_eq!((row.steps, row.elements, row.bodies), (4, 96, 2));
        assert!(row.steps_per_second > 0.0 && row.bytes_read_back_per_step == 0.0);
        assert!(row.friction_us_per_step.is_none());
        let table = contact_table(&[row]);
        assert!(table.contains("striker") && !table.contains("friction"));
    }

    #[test]
    fn friction_rows_time_a_third_variant_with_friction_on_every_contact() {
        let text = with_friction(&pile_text(2, Some(PileContact::All)), 0.3);
        assert_eq!(
            text.matches("friction = 0.3\n").count(),
            2,
            "the wall and the pile"
        );
        let scene = Scene::parse(&text, Path::new("pile.toml")).expect("parses");
        assert!(scene.contacts.iter().all(|c| c.friction == 0.3));
        let row = cpu_contact(
            ContactScene::Pair,
            4,
            &timing(4, 2, PileContact::All, Some(0.3)),
        )
        .expect("row");
        assert_eq!(row.friction, Some(0.3));
        assert!(row.friction_steps_per_second.is_some_and(|f| f > 0.0));
        assert!(row.friction_us_per_step.is_some_and(f64::is_finite));
        let table = contact_table(&[row]);
        assert!(table.contains("friction [us/st]"));
    }
}
