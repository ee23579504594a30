//! The block bench (the first table): the block of [`super::scene`] timed on the CPU reference
//! ([`cpu`]) or on the GPU ([`gpu`]), in rounds alternating the full step, the bare
//! element-and-update loop, and the block on its base with and without its contact.

use std::sync::Arc;

use super::scenes::{build, contact_scene, scene};
use super::table::{row, solver_adapter, BenchRow};
use super::timing::{per_round, stopped, timed, timed_steps, BareLoop, Rounds};
use crate::error::Result;
use crate::gpu::{GpuContext, GpuSolver};
use crate::model::Model;
use crate::plan::Plan;
use crate::scene::Scene;
use crate::step::cpu::CpuSolver;
use crate::step::Solver;

/// The size of a block bench and how its steps are split into rounds.
struct Block {
    cells: usize,
    elements: usize,
    rounds: u32,
    per: u64,
}

impl Block {
    /// The block of `cells`, built, and `steps` split over `rounds` (at least one).
    fn new(cells: usize, steps: u64, rounds: u32) -> Result<(Block, Scene, Model, Plan)> {
        let rounds = rounds.max(1);
        let per = per_round(steps, rounds);
        let scene = scene(cells)?;
        let (model, plan) = build(&scene)?;
        let block = Block {
            cells,
            elements: model.element_count(),
            rounds,
            per,
        };
        Ok((block, scene, model, plan))
    }

    /// Steps timed of each variant.
    fn total(&self) -> u64 {
        self.per * u64::from(self.rounds)
    }

    /// The row of the rounds `r`: the full step's wall time and throughput, its ratio to the bare
    /// loop, and what the contact pair of `contact_elements` added with `contact_searches`.
    fn row(
        &self,
        backend: &str,
        adapter: String,
        r: &Rounds,
        stage_shares: Vec<(String, f64)>,
        contact_elements: usize,
        contact_searches: u64,
    ) -> BenchRow {
        let (full_over_bare, extra, share) = r.ratios(self.per);
        let mut row = row(
            backend,
            adapter,
            self.cells,
            self.elements,
            self.total(),
            r.full.iter().sum(),
            stage_shares,
        );
        row.rounds = self.rounds;
        row.bare_seconds = r.bare.iter().sum();
        row.full_over_bare = full_over_bare;
        row.contact_elements = contact_elements;
        row.contact_seconds_per_step = extra;
        row.contact_share = share;
        row.contact_searches = contact_searches;
        row
    }
}

/// Times the CPU reference on the bench scene: `rounds` rounds of `steps / rounds` steps of the
/// full step, the bare loop, and the contact scene with and without its contact, alternating.
///
/// # Errors
/// Scene errors, or [`crate::Error::Bench`] when a run stops before it took all its steps.
pub fn cpu(cells: usize, steps: u64, rounds: u32) -> Result<BenchRow> {
    let (block, scene, model, plan) = Block::new(cells, steps, rounds)?;
    let per = block.per;
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
        block.rounds,
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
    let total = block.total();
    for (what, s) in [
        ("CPU", &full),
        ("CPU contact", &with),
        ("CPU free", &without),
    ] {
        if s.steps() != total + 2 {
            return Err(stopped(what, s.steps(), total + 2));
        }
    }
    let searches = with.counters().contact_searches;
    Ok(block.row(
        "cpu",
        solver_adapter(),
        &r,
        Vec::new(),
        contact_elements,
        searches,
    ))
}

/// Wall seconds of `steps` steps of the stage `name` of `solver` alone, in submissions of at
/// most [`crate::gpu::state::MAX_BATCH`] steps.
fn stage_seconds(solver: &mut GpuSolver, name: &str, steps: u64) -> Result<f64> {
    let batch = u64::from(crate::gpu::state::MAX_BATCH);
    let mut t = 0.0;
    for k in 0..steps.div_ceil(batch) {
        t += solver.time_stage(name, (steps - k * batch).min(batch) as u32)?;
    }
    Ok(t)
}

/// Times the GPU of `ctx`: `rounds` rounds of `steps / rounds` steps of the full step as a run
/// takes them ([`GpuSolver::run_steps`]: batches read back in turn, each recorded while the
/// device runs the one before on GPUs, as the CPU's full step is timed), of the bare loop
/// (element and node kernels only, in submissions of at most [`crate::gpu::state::MAX_BATCH`]
/// steps, from submission to the device's end: [`GpuSolver::time_stage`]), and of the contact
/// scene with and without its contact (with the host searches the contact kernel asks for),
/// alternating; then each stage alone over the same steps for the shares. Before 2026-11-28 the
/// full step was timed as the bare loop is, with its recording in the time: on an NVIDIA H200 the
/// host's recording of the 10^6 block's 200 steps took longer than the device's (BENCHMARKS.md).
///
/// # Errors
/// Scene or device errors, or [`crate::Error::Bench`] when a contact run stops before its steps.
pub fn gpu(ctx: Arc<GpuContext>, cells: usize, steps: u64, rounds: u32) -> Result<BenchRow> {
    let (block, scene, model, plan) = Block::new(cells, steps, rounds)?;
    let per = block.per;
    let adapter = ctx.adapter_name();
    let mut solver = GpuSolver::new(ctx.clone(), &model, &plan, crate::run::schedule(&scene))?;
    solver.run_steps(2)?; // warm-up (pipelines, first sample)
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
    let r = Rounds::measure(
        block.rounds,
        [
            &mut || timed_steps(&mut **solver_cell.borrow_mut(), per, "GPU block"),
            &mut || stage_seconds(&mut solver_cell.borrow_mut(), "bare", per),
            &mut || timed_steps(&mut with, per, "GPU contact"),
            &mut || timed_steps(&mut without, per, "GPU free"),
        ],
    )?;
    let wall: f64 = r.full.iter().sum();
    let mut shares = Vec::new();
    for name in ["element", "node", "control"] {
        let t = stage_seconds(&mut solver, name, block.total())?;
        shares.push((name.to_string(), t / wall));
    }
    let searches = with.counters().contact_searches;
    Ok(block.row("gpu", adapter, &r, shares, contact_elements, searches))
}
