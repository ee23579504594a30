//! The contact bench (the second table): a [`ContactScene`] of a chosen size timed with and
//! without its `[[contact]]` (and with friction, and with failure, when asked) on the CPU reference
//! ([`cpu_contact`]), the GPU ([`gpu_contact`]) or both in the same rounds ([`both_contact`]).

use std::path::Path;
use std::sync::Arc;

use super::scenes::{
    bench_schedule, build, with_failure, with_friction, ContactScene, PileContact,
};
use super::table::{solver_adapter, ContactRow};
use super::timing::{alternate, median, per_round, stopped, timed_steps, Timed};
use crate::error::{Error, Result};
use crate::gpu::{GpuContext, GpuSolver};
use crate::model::Model;
use crate::plan::Plan;
use crate::scene::Scene;
use crate::step::cpu::CpuSolver;

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
    /// A principal-strain limit for a variant with failure and erosion on every material
    /// ([`with_failure`]): what eroding elements, and contact that follows them, cost a step.
    pub failure: Option<f64>,
    /// Plain projected Gauss-Seidel sweeps instead of the extrapolated ones, on both backends
    /// ([`crate::contact::extrapolation`]): a comparison.
    pub plain_sweeps: bool,
    /// Whether the GPU's one-workgroup solve sweeps 2 x 2 blocks of node pairs (`None`: the
    /// adapter's default, [`crate::gpu::contact::pair_blocks`]): a comparison.
    pub pair_blocks: Option<bool>,
    /// How the GPU's one-workgroup solve colours its constraints (`None`: the adapter's default,
    /// [`crate::gpu::contact::parallel_colouring`]): a comparison.
    pub parallel_colouring: Option<bool>,
    /// Where the GPU's one-workgroup solve keeps its sweeps' state (`None`: the adapter's
    /// default, [`crate::gpu::contact::local_sweeps`]): a comparison.
    pub local_sweeps: Option<bool>,
    /// How the GPU's contact search is dispatched (`None`: the default,
    /// [`crate::gpu::contact::search::search_one_path`]): a comparison.
    pub search_one: Option<bool>,
    /// Threads of the GPU's one-workgroup contact kernels (`None`: the adapter's default,
    /// [`crate::gpu::contact::one_group`]): a comparison.
    pub group: Option<u32>,
    /// The GPU's contact stage after the search in one workgroup (`Some(true)`: on any adapter,
    /// with the one-workgroup solve whatever the size) or in its per-item kernels
    /// (`Some(false)`); `None`: the default ([`crate::gpu::contact::one::one_path`]). A
    /// comparison.
    pub one: Option<bool>,
    /// Whether the GPU records each batch while the device runs the one before
    /// ([`GpuSolver::set_record_ahead`]) or only after its readback (`None`: the adapter's
    /// default, [`crate::gpu::solver::record_ahead`]): a comparison.
    pub record_ahead: Option<bool>,
}

/// Warm-up steps of a contact row unless asked for more: two, the first search included.
pub const DEFAULT_WARMUP: u64 = 2;

impl ContactTiming {
    /// `steps` steps in `rounds` rounds after [`DEFAULT_WARMUP`], the pile in one `[[contact]]`,
    /// every other choice the default.
    pub fn new(steps: u64, rounds: u32) -> Self {
        ContactTiming {
            steps,
            rounds,
            warmup: DEFAULT_WARMUP,
            pile: PileContact::All,
            friction: None,
            failure: None,
            plain_sweeps: false,
            pair_blocks: None,
            parallel_colouring: None,
            local_sweeps: None,
            search_one: None,
            group: None,
            one: None,
            record_ahead: None,
        }
    }
}

/// The GPU's contact options of `timing` (the contact stage in one workgroup takes the
/// one-workgroup solve with its re-checks inside: neither the per-colour solve nor split
/// re-checks).
pub fn contact_options(timing: &ContactTiming) -> crate::gpu::contact::ContactOptions {
    let one = timing.one == Some(true);
    crate::gpu::contact::ContactOptions {
        multi: one.then_some(false),
        split: one.then_some(false),
        one: timing.one,
        plain_sweeps: timing.plain_sweeps,
        pair_blocks: timing.pair_blocks,
        parallel_colouring: timing.parallel_colouring,
        local_sweeps: timing.local_sweeps,
        search_one: timing.search_one,
        group: timing.group,
        ..Default::default()
    }
}

/// One backend's solvers of a contact scene, as [`contact_rows`] times them: with and without
/// the scene's `[[contact]]`, and with friction when asked.
struct Side<'a> {
    backend: &'static str,
    adapter: String,
    /// Whether its solve sweeps 2 x 2 blocks of node pairs (the CPU reference always does).
    pair_blocks: bool,
    with: &'a mut dyn Timed,
    without: &'a mut dyn Timed,
    friction: Option<&'a mut dyn Timed>,
    failure: Option<&'a mut dyn Timed>,
}

impl Side<'_> {
    fn variants(&mut self) -> Vec<(&'static str, &mut dyn Timed)> {
        let mut v: Vec<(&'static str, &mut dyn Timed)> =
            vec![("contact", &mut *self.with), ("free", &mut *self.without)];
        if let Some(f) = self.friction.as_mut() {
            v.push(("friction", &mut **f));
        }
        if let Some(f) = self.failure.as_mut() {
            v.push(("failure", &mut **f));
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
    let failure_before: Vec<_> = sides
        .iter()
        .map(|s| s.failure.as_ref().map(|f| f.count()))
        .collect();
    let cpu_first = sides.first().is_some_and(|s| s.backend == "cpu");
    let meta: Vec<(&'static str, String, bool)> = sides
        .iter()
        .map(|s| (s.backend, s.adapter.clone(), s.pair_blocks))
        .collect();
    // Every variant of every side, in one alternation.
    let mut runs: Vec<Box<dyn FnMut() -> Result<f64> + '_>> = Vec::new();
    let mut names = Vec::new();
    for side in &mut sides {
        let backend = side.backend;
        let variants = side.variants();
        names.push(variants.iter().map(|v| v.0).collect::<Vec<_>>());
        for (what, s) in variants {
            let name = format!("{backend} {} {what}", which.name());
            runs.push(Box::new(move || timed_steps(s, per, &name)));
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
        let t = &times[at..at + names[k].len()];
        at += names[k].len();
        let after = side.with.count();
        let wall: f64 = t[0].iter().sum();
        // A variant's steps per second, and the median over the rounds of what it adds to a
        // step with contact (microseconds).
        let extra = |what: &str| match names[k].iter().position(|n| *n == what) {
            Some(i) => (
                Some(total as f64 / t[i].iter().sum::<f64>()),
                Some(median(
                    t[i].iter()
                        .zip(&t[0])
                        .map(|(f, c)| 1e6 * (f - c) / per as f64)
                        .collect(),
                )),
            ),
            None => (None, None),
        };
        let (friction_steps_per_second, friction_us_per_step) = extra("friction");
        let (failure_steps_per_second, failure_us_per_step) = extra("failure");
        // The failure variant's follows of erosion in the timed steps, and their mean host time.
        let follows = side.failure.as_ref().zip(failure_before[k]).map(|(f, b)| {
            let a = f.count();
            (
                a.erosion_follows - b.erosion_follows,
                a.erosion_follow_seconds - b.erosion_follow_seconds,
            )
        });
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
            pair_blocks: meta[k].2,
            wall_seconds: wall,
            steps_per_second: total as f64 / wall,
            free_seconds: t[1].iter().sum(),
            contact_share: median(t[0].iter().zip(&t[1]).map(|(c, f)| (c - f) / c).collect()),
            friction: timing.friction,
            friction_steps_per_second,
            friction_us_per_step,
            sweeps_mean: after.contact_sweeps_mean,
            friction_sweeps_mean: side
                .friction
                .as_ref()
                .map(|f| f.count().contact_sweeps_mean),
            failure: timing.failure,
            failure_steps_per_second,
            failure_us_per_step,
            failure_eroded: side.failure.as_ref().map(|f| f.count().eroded_elements),
            failure_follows: follows.map(|(n, _)| n),
            failure_follow_us: follows.map(|(n, t)| if n > 0 { 1e6 * t / n as f64 } else { 0.0 }),
            searches,
            searches_per_100_steps: 100.0 * searches as f64 / total as f64,
            bytes_read_back_per_step: (after.bytes_read_back - before[k].bytes_read_back) as f64
                / total as f64,
            record_us_per_step: 1e6 * (after.record_seconds - before[k].record_seconds)
                / total as f64,
            vs_cpu,
        });
    }
    Ok(rows)
}

/// What a contact scene variant adds to the scene: friction on its contacts and walls (a
/// Coulomb coefficient, see [`with_friction`]) or failure on its materials (a principal-strain
/// limit, see [`with_failure`]).
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Variant {
    pub friction: Option<f64>,
    pub failure: Option<f64>,
}

/// Builds the model, plan and schedule of a contact scene variant.
pub(super) fn contact_build(
    which: ContactScene,
    size: usize,
    contact: bool,
    pile: PileContact,
    variant: Variant,
) -> Result<(Model, Plan, crate::step::Schedule)> {
    let mut text = which.text(size, contact, pile);
    if let Some(mu) = variant.friction {
        text = with_friction(&text, mu);
    }
    if let Some(strain) = variant.failure {
        text = with_failure(&text, strain);
    }
    let name = format!("bench_{}.toml", which.name());
    let scene = Scene::parse(&text, Path::new(&name))?;
    let (model, plan) = build(&scene)?;
    Ok((model, plan, bench_schedule(&scene)))
}

/// The solvers of a contact scene on one backend: with and without its `[[contact]]`, with
/// friction when `timing.friction` asks and with failure when `timing.failure` asks; and the
/// model with contact.
type Solvers<S> = (Model, S, S, Option<S>, Option<S>);

/// The variants with friction and with failure that `timing` asks for.
fn extras(timing: &ContactTiming) -> [Option<Variant>; 2] {
    [
        timing.friction.map(|mu| Variant {
            friction: Some(mu),
            failure: None,
        }),
        timing.failure.map(|strain| Variant {
            friction: None,
            failure: Some(strain),
        }),
    ]
}

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
    let none = Variant::default();
    let (model, plan, schedule) = contact_build(which, size, true, pile, none)?;
    let with = plain((model.clone(), plan, schedule));
    let without = plain(contact_build(which, size, false, pile, none)?);
    let [rough, failing] = extras(timing).map(|v| {
        v.map(|v| contact_build(which, size, true, pile, v).map(plain))
            .transpose()
    });
    Ok((model, with, without, rough?, failing?))
}

fn gpu_solvers(
    ctx: &Arc<GpuContext>,
    which: ContactScene,
    size: usize,
    timing: &ContactTiming,
) -> Result<Solvers<GpuSolver>> {
    let pile = timing.pile;
    let options = contact_options(timing);
    let solver = |(m, p, s): (Model, Plan, crate::step::Schedule)| {
        let mut g = GpuSolver::with_options(ctx.clone(), &m, &p, s, None, options)?;
        if let Some(on) = timing.record_ahead {
            g.set_record_ahead(on);
        }
        Ok::<_, crate::Error>(g)
    };
    let none = Variant::default();
    let (model, plan, schedule) = contact_build(which, size, true, pile, none)?;
    let with = solver((model.clone(), plan, schedule))?;
    let without = solver(contact_build(which, size, false, pile, none)?)?;
    let [rough, failing] = extras(timing).map(|v| {
        v.map(|v| contact_build(which, size, true, pile, v).and_then(solver))
            .transpose()
    });
    Ok((model, with, without, rough?, failing?))
}

/// Whether the GPU of `ctx` sweeps 2 x 2 blocks of node pairs with `timing`'s options.
fn gpu_pairs(ctx: &GpuContext, timing: &ContactTiming) -> bool {
    timing
        .pair_blocks
        .unwrap_or_else(|| crate::gpu::contact::pair_blocks(ctx.info.device_type))
}

/// The model with contact of `solvers`, and the side of `backend` on `adapter` that times them.
fn side<'a, S: Timed>(
    backend: &'static str,
    adapter: String,
    pair_blocks: bool,
    (model, with, without, rough, failing): &'a mut Solvers<S>,
) -> (&'a Model, Side<'a>) {
    let side = Side {
        backend,
        adapter,
        pair_blocks,
        with,
        without,
        friction: rough.as_mut().map(|s| s as &mut dyn Timed),
        failure: failing.as_mut().map(|s| s as &mut dyn Timed),
    };
    (model, side)
}

/// The row of one backend's side of a contact scene, timed alone.
fn alone(
    which: ContactScene,
    size: usize,
    (model, side): (&Model, Side<'_>),
    timing: &ContactTiming,
) -> Result<ContactRow> {
    contact_rows(which, size, model, vec![side], timing)?
        .pop()
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
    alone(
        which,
        size,
        side("cpu", solver_adapter(), true, &mut cpu),
        timing,
    )
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
    alone(
        which,
        size,
        side("gpu", ctx.adapter_name(), gpu_pairs(&ctx, timing), &mut gpu),
        timing,
    )
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
    let (model, cpu) = side("cpu", solver_adapter(), true, &mut cpu);
    let (_, gpu) = side("gpu", ctx.adapter_name(), gpu_pairs(&ctx, timing), &mut gpu);
    contact_rows(which, size, model, vec![cpu, gpu], timing)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bench::{contact_table, pile_text};

    fn timing(steps: u64, rounds: u32, pile: PileContact, friction: Option<f64>) -> ContactTiming {
        ContactTiming {
            pile,
            friction,
            ..ContactTiming::new(steps, rounds)
        }
    }

    /// `one` reaches the GPU's options: asked for, the stage in one workgroup takes the
    /// one-workgroup solve with its re-checks inside, on any adapter (`Path::choose` refuses it
    /// with the per-colour solve or split re-checks); not asked for, the adapter decides.
    #[test]
    fn the_contact_stage_asked_for_reaches_the_gpu_options() {
        let one = contact_options(&ContactTiming {
            one: Some(true),
            ..ContactTiming::new(1, 1)
        });
        assert_eq!(
            (one.one, one.multi, one.split),
            (Some(true), Some(false), Some(false))
        );
        let items = contact_options(&ContactTiming {
            one: Some(false),
            ..ContactTiming::new(1, 1)
        });
        assert_eq!(
            (items.one, items.multi, items.split),
            (Some(false), None, None)
        );
        assert_eq!(
            contact_options(&ContactTiming::new(1, 1)),
            crate::gpu::contact::ContactOptions::default()
        );
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
    fn failure_rows_time_a_variant_with_failure_on_every_material() {
        let text = crate::bench::with_failure(&crate::bench::striker_text(4, true), 0.03);
        assert_eq!(
            text.matches("failure = { principal_strain = 0.03 }\n")
                .count(),
            1,
            "the one steel"
        );
        assert_eq!(text.matches("erosion = { inverted = true }\n").count(), 1);
        let scene = Scene::parse(&text, Path::new("striker.toml")).expect("parses");
        assert!(scene.run.erode_inverted);
        let timing = ContactTiming {
            failure: Some(0.03),
            ..timing(4, 2, PileContact::All, Some(0.3))
        };
        let row = cpu_contact(ContactScene::Striker, 4, &timing).expect("row");
        assert_eq!((row.failure, row.friction), (Some(0.03), Some(0.3)));
        assert!(row.failure_steps_per_second.is_some_and(|f| f > 0.0));
        assert!(row.failure_us_per_step.is_some_and(f64::is_finite));
        assert!(row.failure_eroded.is_some());
        assert!(row.failure_follows.is_some());
        assert!(row.failure_follow_us.is_some_and(|us| us >= 0.0));
        let table = contact_table(&[row]);
        assert!(table.contains("failure [us/st]") && table.contains("friction [us/st]"));
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
