//! Gravity (`run.gravity`): a body force m g on every node, its work in `external_work`. Free fall
//! is exact for central differences (u = g t^2 / 2 at every step, v = g t at t_n), with a closed
//! energy balance; a block resting on a rigid wall is held by a mean wall force m g.

use ricochet::plan::Stage;
use ricochet::run::{run, schedule};
use ricochet::step::cpu::CpuSolver;

use crate::common::*;

#[path = "../shared/gravity_scene.rs"]
mod scene;
use scene::*;

#[test]
fn free_fall_is_exact_and_its_energy_balance_closes() {
    let (sc, model, plan) = build(&block_scene(0.05, 9.0e-4, 3.0e-7, 50, false));
    assert!(plan.has(Stage::Gravity));
    let dir = tmp_dir("gravity-free-fall");
    let mut solver = CpuSolver::new(model.clone(), plan.clone(), schedule(&sc));
    let r = run(&sc, &model, &plan, &mut solver, &dir, None).expect("run");
    let _ = std::fs::remove_dir_all(&dir);
    assert_eq!(r.summary.status, "completed", "{}", r.summary.message);
    let t = 9.0e-4;
    // Every node falls by g t^2 / 2; the velocity at t_n is g t_n in every row.
    let worst_u = solver
        .displacement()
        .iter()
        .map(|u| (u[0].abs()).max((u[1] + 0.5 * G * t * t).abs()))
        .fold(0.0f64, f64::max);
    let mut worst_v = 0.0f64;
    for (s, _) in &r.samples {
        let v = s.body_velocity[0];
        worst_v = worst_v.max(v[0].abs()).max((v[1] + G * s.time).abs());
        // The kinetic energy in the conserved form, m v^{n-1/2} v^{n+1/2} / 2 =
        // m g^2 (t^2 - dt^2 / 4) / 2, and the work of gravity since t = 0 equal to its change.
        let dt = 3.0e-7;
        let m = model.bodies[0].mass;
        let kinetic = 0.5 * m * G * G * (s.time * s.time - 0.25 * dt * dt);
        let s0 = &r.samples[0].0;
        let (dk, dw) = (s.kinetic - s0.kinetic, s.external - s0.external);
        let scale = 0.5 * m * (G * t).powi(2);
        assert!(
            (s.kinetic - kinetic).abs() <= 1e-10 * kinetic.abs()
                && (dw - dk).abs() <= 1e-12 * scale,
            "t = {:e}: kinetic {:e} against {kinetic:e}, work {dw:e} against {dk:e}",
            s.time,
            s.kinetic
        );
    }
    eprintln!(
        "free fall: displacement error {worst_u:.2e} m of {:.3e}, velocity error {worst_v:.2e} m/s, \
         energy balance {:.2e}",
        0.5 * G * t * t,
        r.summary.max_energy_error
    );
    assert!(worst_u < 1e-12 * 0.5 * G * t * t, "{worst_u:e}");
    assert!(worst_v < 1e-12 * G * t, "{worst_v:e}");
    assert!(r.summary.max_energy_error < 1e-12);
}

#[test]
fn a_block_resting_on_a_wall_is_held_by_its_weight() {
    // Lagrange wall at y = 0 under the block from t = 0: the wall force averaged over 2000 rows
    // (many periods of the block's vibration under its suddenly applied weight) is m g, the
    // block neither sinks nor moves, the energy balance closes.
    let (sc, model, plan) = build(&block_scene(0.0, 2.0e-3, 0.0, 2000, true));
    let dir = tmp_dir("gravity-rest");
    let mut solver = CpuSolver::new(model.clone(), plan.clone(), schedule(&sc));
    let r = run(&sc, &model, &plan, &mut solver, &dir, None).expect("run");
    let _ = std::fs::remove_dir_all(&dir);
    assert_eq!(r.summary.status, "completed", "{}", r.summary.message);
    let weight = model.bodies[0].mass * G;
    let rows: Vec<_> = r.samples.iter().map(|s| &s.0).collect();
    let mean = rows.iter().map(|s| s.contacts[0].force[1]).sum::<f64>() / rows.len() as f64;
    let sink = solver
        .displacement()
        .iter()
        .zip(&model.position)
        .filter(|(_, p)| p[1] == 0.0)
        .map(|(u, _)| u[1])
        .fold(0.0f64, f64::min);
    eprintln!(
        "resting block: mean wall force {:.5} of m g, lowest bottom node {sink:.2e} m, balance {:.2e}",
        mean / weight,
        r.summary.max_energy_error
    );
    let moving = rows
        .iter()
        .map(|s| s.body_velocity[0][1].abs())
        .fold(0.0f64, f64::max);
    assert!(
        (mean / weight - 1.0).abs() < 0.01,
        "{mean} against {weight}"
    );
    // Against the 1.96 m/s it would reach falling freely.
    assert!(moving < 1e-3 * G * 2.0e-3, "{moving}");
    assert!(sink > -1e-9, "{sink}");
    assert!(r.summary.max_energy_error < 1e-6);
}
