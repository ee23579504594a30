//! Criterion benches over the same stages `ricochet bench` times: the CPU reference step and, when
//! an adapter exists, a batch of GPU steps, on the generated bench block.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};

use ricochet::plan::Plan;
use ricochet::step::cpu::CpuSolver;

fn cpu_step(c: &mut Criterion) {
    let mut group = c.benchmark_group("cpu_step");
    for cells in [32usize, 100] {
        let scene = ricochet::bench::scene(cells).expect("bench scene");
        let model = ricochet::run::model(&scene).expect("model");
        let plan = Plan::new(&scene, &model);
        let ne = model.element_count() as u64;
        let mut solver = CpuSolver::new(model, plan, ricochet::run::schedule(&scene));
        solver.run_steps(2);
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
        let model = ricochet::run::model(&scene).expect("model");
        let plan = Plan::new(&scene, &model);
        let ne = model.element_count() as u64;
        let mut solver = ricochet::gpu::GpuSolver::new(
            ctx.clone(),
            &model,
            &plan,
            ricochet::run::schedule(&scene),
        )
        .expect("gpu solver");
        group.throughput(Throughput::Elements(64 * ne));
        group.bench_function(format!("{}_elements", ne), |b| {
            b.iter(|| solver.time_stage("step", 64).expect("steps"))
        });
    }
    group.finish();
}

criterion_group!(benches, cpu_step, gpu_steps);
criterion_main!(benches);
