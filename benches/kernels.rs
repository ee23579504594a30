//! Criterion benches over the same stages `ricochet bench` times: the CPU reference step and, when
//! an adapter exists, a batch of GPU steps, on the generated bench block; and the contact scenes
//! of `ricochet bench --scene` (striker, pile) at about 1e4 elements.

use criterion::{criterion_group, criterion_main, BatchSize, Criterion, Throughput};

use ricochet::bench::{ContactScene, PileContact};

use ricochet::plan::Plan;
use ricochet::scene::Scene;
use ricochet::step::cpu::CpuSolver;

/// A CPU solver of `scene` after its first two steps, and its element count.
fn cpu_solver(scene: &Scene) -> (CpuSolver, u64) {
    let model = ricochet::run::model(scene).expect("model");
    let plan = Plan::new(scene, &model);
    let ne = model.element_count() as u64;
    let mut solver = CpuSolver::new(model, plan, ricochet::run::schedule(scene));
    solver.run_steps(2);
    (solver, ne)
}

/// A GPU solver of `scene` at t = 0, and its element count.
fn gpu_solver(
    ctx: &std::sync::Arc<ricochet::gpu::GpuContext>,
    scene: &Scene,
) -> (ricochet::gpu::GpuSolver, u64) {
    let model = ricochet::run::model(scene).expect("model");
    let plan = Plan::new(scene, &model);
    let ne = model.element_count() as u64;
    let solver =
        ricochet::gpu::GpuSolver::new(ctx.clone(), &model, &plan, ricochet::run::schedule(scene))
            .expect("gpu solver");
    (solver, ne)
}

fn cpu_step(c: &mut Criterion) {
    let mut group = c.benchmark_group("cpu_step");
    for cells in [32usize, 100] {
        let scene = ricochet::bench::scene(cells).expect("bench scene");
        let (mut solver, ne) = cpu_solver(&scene);
        group.throughput(Throughput::Elements(ne));
        group.bench_function(format!("{}_elements", ne), |b| {
            b.iter(|| solver.run_steps(1))
        });
    }
    group.finish();
}

fn gpu_steps(c: &mut Criterion) {
    let Ok(ctx) = ricochet::gpu::GpuContext::shared() else {
        eprintln!("gpu_steps: no adapter, skipped");
        return;
    };
    let mut group = c.benchmark_group("gpu_64_steps");
    group.sample_size(10);
    for cells in [32usize, 100] {
        let scene = ricochet::bench::scene(cells).expect("bench scene");
        let (mut solver, ne) = gpu_solver(&ctx, &scene);
        group.throughput(Throughput::Elements(64 * ne));
        group.bench_function(format!("{}_elements", ne), |b| {
            b.iter(|| solver.time_stage("step", 64).expect("steps"))
        });
    }
    group.finish();
}

/// The contact scenes at about 1e4 elements, with their contact: the pile with `bodies = "all"`,
/// or with one `[[contact]]` per pair where that does not parse yet.
fn contact_scenes() -> Vec<(String, ricochet::scene::Scene)> {
    let mut scenes = Vec::new();
    for which in [ContactScene::Striker, ContactScene::Pile] {
        let size = which.size_for(10_000);
        let scene = which
            .scene(size, true, PileContact::All)
            .or_else(|e| {
                eprintln!("{}: {e}; one [[contact]] per pair instead", which.name());
                which.scene(size, true, PileContact::Pairs)
            })
            .expect("contact bench scene");
        scenes.push((format!("{}_{}", which.name(), which.elements(size)), scene));
    }
    scenes
}

/// Each sample starts from the same state (the solver after its first two steps, cloned), so that
/// the striker does not fly off and the pile does not settle over the samples.
fn cpu_contact(c: &mut Criterion) {
    let mut group = c.benchmark_group("cpu_contact_10_steps");
    group.sample_size(10);
    for (name, scene) in contact_scenes() {
        let model = ricochet::run::model(&scene).expect("model");
        let plan = Plan::new(&scene, &model);
        let ne = model.element_count() as u64;
        let mut solver = CpuSolver::new(model, plan, ricochet::bench::bench_schedule(&scene));
        solver.run_steps(2);
        group.throughput(Throughput::Elements(10 * ne));
        group.bench_function(name, |b| {
            b.iter_batched_ref(
                || solver.clone(),
                |s| s.run_steps(10),
                BatchSize::PerIteration,
            )
        });
    }
    group.finish();
}

/// The GPU solver cannot be cloned: the samples are consecutive batches of 64 steps of one run, so
/// the striker's figure averages over its impact and what follows (it may rebound), and the pile
/// needs a GPU backend that takes its 100 bodies (skipped otherwise).
fn gpu_contact(c: &mut Criterion) {
    let Ok(ctx) = ricochet::gpu::GpuContext::shared() else {
        eprintln!("gpu_contact: no adapter, skipped");
        return;
    };
    let mut group = c.benchmark_group("gpu_contact_64_steps");
    group.sample_size(10);
    for (name, scene) in contact_scenes() {
        let model = ricochet::run::model(&scene).expect("model");
        let plan = Plan::new(&scene, &model);
        let ne = model.element_count() as u64;
        let mut solver = match ricochet::gpu::GpuSolver::new(
            ctx.clone(),
            &model,
            &plan,
            ricochet::bench::bench_schedule(&scene),
        ) {
            Ok(s) => s,
            Err(e) => {
                eprintln!("gpu_contact {name}: skipped: {e}");
                continue;
            }
        };
        solver.run_steps(2).expect("warm-up");
        group.throughput(Throughput::Elements(64 * ne));
        group.bench_function(name, |b| b.iter(|| solver.run_steps(64).expect("steps")));
    }
    group.finish();
}

/// The bench block (100 x 100) with each constitutive model: what the J2 element stage costs
/// against the elastic ones, on the CPU reference and the GPU. The J2 block's yield stress is
/// 1 MPa, so that every element yields at every step (the return and its plastic work run).
fn element_models(c: &mut Criterion) {
    let models = [
        ("linear_elastic", "model = \"linear_elastic\""),
        ("neo_hookean", "model = \"neo_hookean\""),
        (
            "j2_plastic",
            "model = \"j2_plastic\"\nyield_stress = 1.0e6\nhardening_modulus = 1.0e9",
        ),
    ];
    let scene_of = |model: &str| {
        let text = ricochet::bench::block_text(100).replace("model = \"linear_elastic\"", model);
        Scene::parse(&text, std::path::Path::new("bench.toml")).expect("scene")
    };
    let mut group = c.benchmark_group("cpu_step_by_model");
    for (name, keys) in models {
        let (mut solver, ne) = cpu_solver(&scene_of(keys));
        group.throughput(Throughput::Elements(ne));
        group.bench_function(name, |b| b.iter(|| solver.run_steps(1)));
    }
    group.finish();
    let Ok(ctx) = ricochet::gpu::GpuContext::shared() else {
        eprintln!("element_models: no adapter, GPU skipped");
        return;
    };
    let mut group = c.benchmark_group("gpu_64_steps_by_model");
    group.sample_size(10);
    for (name, keys) in models {
        let (mut solver, ne) = gpu_solver(&ctx, &scene_of(keys));
        group.throughput(Throughput::Elements(64 * ne));
        group.bench_function(name, |b| {
            b.iter(|| solver.time_stage("step", 64).expect("steps"))
        });
    }
    group.finish();
}

criterion_group!(
    benches,
    cpu_step,
    gpu_steps,
    cpu_contact,
    gpu_contact,
    element_models
);
criterion_main!(benches);
