//! J2 plasticity and the axisymmetric formulation on the GPU: the plastic patch test's stress
//! path (REFERENCES.md section 10) on lavapipe against the closed form (1e-3 sigma_y) and against
//! the CPU reference at every snapshot (1e-5 sigma_y), and the plastic work of both backends.
//! (The element kernel against the CPU on random yielded states is in `tests/gpu.rs`; the Taylor
//! bar and the thick cylinder run on both backends in `ricochet verify`.)

use ricochet::gpu::GpuSolver;
use ricochet::model::Model;
use ricochet::output::fields::element_fields_state;
use ricochet::run::schedule;
use ricochet::step::cpu::CpuSolver;
use ricochet::step::{Event, Sample, Snapshot, Solver};

use crate::{context, load, GPU_LOCK};

#[path = "../shared/plastic_scene.rs"]
mod plastic_scene;
use plastic_scene::*;

fn drive(solver: &mut dyn Solver) -> (Vec<Snapshot>, Vec<Sample>) {
    let (mut snaps, mut samples) = (Vec::new(), Vec::new());
    let mut done = false;
    while !done {
        let mut events = Vec::new();
        solver.advance(&mut events).expect("advance");
        for e in events {
            match e {
                Event::Snapshot(s) => snaps.push(s),
                Event::Sample(s) => samples.push(s),
                Event::Done => done = true,
                Event::Failed(f) => panic!("run failed: {f:?}"),
            }
        }
    }
    (snaps, samples)
}

fn von_mises(model: &Model, s: &Snapshot, e: usize) -> f64 {
    element_fields_state(model, &s.displacement, e, &s.plastic[e]).von_mises
}

#[test]
fn the_plastic_stress_path_matches_the_closed_form_and_the_cpu() {
    path_against_cpu(&scene("binary"), None);
}

#[test]
fn the_johnson_cook_path_matches_the_cpu() {
    path_against_cpu(&rate_scene("binary", 0.1), Some(0.1));
}

/// Runs `text` on both backends; checks the GPU's stress path against the closed form (linear
/// hardening, `rate` None; or the steady Johnson-Cook flow stress at the end) and the CPU's.
fn path_against_cpu(text: &str, rate: Option<f64>) {
    let Some(ctx) = context() else { return };
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let (scene, model, plan) = load(text, "plastic_patch");
    let mut cpu = CpuSolver::new(model.clone(), plan.clone(), schedule(&scene));
    let mut gpu = GpuSolver::new(ctx, &model, &plan, schedule(&scene)).expect("gpu solver");
    let (cs, csamples) = drive(&mut cpu);
    let (gs, gsamples) = drive(&mut gpu);
    assert_eq!(cs.len(), gs.len());
    assert!(gs.len() >= 40);
    let top = model
        .position
        .iter()
        .position(|p| (p[1] - SIDE).abs() < 1e-12)
        .expect("top node");
    let (mut to_closed, mut to_cpu) = (0.0f64, 0.0f64);
    let mut yielded = 0;
    for (c, g) in cs.iter().zip(&gs) {
        assert_eq!(c.step, g.step);
        let x = -2.0 * g.displacement[top][1] / SIDE;
        for e in 0..model.element_count() {
            let vg = von_mises(&model, g, e);
            if rate.is_none() {
                to_closed = to_closed.max((vg - von_mises_closed(x)).abs() / YIELD);
            }
            to_cpu = to_cpu.max((vg - von_mises(&model, c, e)).abs() / YIELD);
        }
        if g.plastic[0].alpha > 0.0 {
            yielded += 1;
        }
    }
    if let Some(c) = rate {
        let g = gs.last().expect("snapshots");
        let x = -2.0 * g.displacement[top][1] / SIDE;
        to_closed = (von_mises(&model, g, 0) - rate_flow(x, c)).abs() / YIELD;
    }
    let (wc, wg) = (
        csamples.last().expect("rows").plastic,
        gsamples.last().expect("rows").plastic,
    );
    eprintln!(
        "GPU plastic patch: |sigma_vm - closed form| <= {to_closed:.2e} sigma_y, |GPU - CPU| <= \
         {to_cpu:.2e} sigma_y over {} snapshots ({yielded} yielded); plastic work {wg:.6e} J \
         (CPU {wc:.6e} J)",
        gs.len()
    );
    assert!(yielded > gs.len() / 2);
    assert!(to_closed < 1e-3, "{to_closed:e}");
    // Linear hardening: 1e-5 sigma_y (the bound). Johnson-Cook adds an f32 Newton
    // iteration on (a + b eps_p^n)(1 + c ln rate) each yielded step: 2e-5.
    let bound = if rate.is_some() { 2e-5 } else { 1e-5 };
    assert!(to_cpu < bound, "{to_cpu:e}");
    assert!(
        (wg - wc).abs() < 1e-3 * wc,
        "plastic work {wg} against {wc}"
    );
}

#[test]
fn only_plastic_and_axisymmetric_scenes_get_their_element_state() {
    let Some(ctx) = context() else { return };
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let elastic = scene("binary").replace("model = \"j2_plastic\"", "model = \"neo_hookean\"");
    let elastic = elastic.replace(
        &format!("yield_stress = {YIELD:e}\nhardening_modulus = {HARDENING:e}\n"),
        "",
    );
    for (text, plastic) in [(scene("binary"), true), (elastic, false)] {
        let (scene, model, plan) = load(&text, "state");
        let gpu = GpuSolver::new(ctx.clone(), &model, &plan, schedule(&scene)).expect("gpu");
        let names: Vec<&str> = gpu.state().allocated.iter().map(|(n, _)| *n).collect();
        assert_eq!(
            names.contains(&"element_plastic_state"),
            plastic,
            "{names:?}"
        );
        assert_eq!(gpu.kernels().features.plastic, plastic);
        assert_eq!(gpu.state().params.plastic, u32::from(plastic));
        assert!(!gpu.kernels().features.axisymmetric);
    }
}
