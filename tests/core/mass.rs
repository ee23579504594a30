//! Mass: the lumped mass of a body equals rho t (area of its mesh) -- the rectangle's area, the
//! area of the polygon inscribed in the disk (the O-grid's boundary has 4n straight edges), the
//! explicit mesh's area -- and it is a constant array during a run. A free body (no
//! boundaries) keeps its momentum to round-off, whatever its internal motion.

use std::f64::consts::PI;

use ricochet::model::Model;
use ricochet::run;
use ricochet::step::cpu::CpuSolver;

use crate::common::*;
use crate::scene_text::STEEL;

fn one_body(mesh: &str, extra: &str) -> String {
    format!(
        r#"
[run]
end_time = 2.0e-4
history_interval = 1.0e-5

{STEEL}

[[body]]
name = "b"
material = "steel"
thickness = 0.02
mesh = {mesh}
{extra}
"#
    )
}

fn total_mass(model: &Model) -> f64 {
    model.mass.iter().sum()
}

#[test]
fn rectangle_mass_is_rho_t_area() {
    let (_, model, _) = build(&one_body(
        "{ rectangle = { origin = [-3.0, 7.0], size = [0.3, 0.2], cells = [7, 5] } }",
        "",
    ));
    let exact = 7850.0 * 0.02 * 0.3 * 0.2;
    // Measured relative error ~1e-16.
    assert!(rel(total_mass(&model), exact, exact) < 1e-13);
    assert!(rel(model.bodies[0].mass, exact, exact) < 1e-13);
    assert!(model.mass.iter().all(|&m| m > 0.0));
    // Lumping of a uniform rectangle: corner nodes m/4 of one element, edges 2x, interior 4x.
    let m_e = exact / 35.0 / 4.0;
    assert!(rel(model.mass[0], m_e, m_e) < 1e-12);
    assert!(rel(model.mass[1], 2.0 * m_e, m_e) < 1e-12);
    assert!(rel(model.mass[9], 4.0 * m_e, m_e) < 1e-12);
}

#[test]
fn disk_mass_is_rho_t_times_the_inscribed_polygon_area() {
    for cells in [2usize, 5, 8, 16] {
        let r = 0.05;
        let (_, model, _) = build(&one_body(
            &format!("{{ disk = {{ center = [1.0, -2.0], radius = {r}, cells = {cells} }} }}"),
            "",
        ));
        let k = 4 * cells;
        let polygon = 0.5 * k as f64 * r * r * (2.0 * PI / k as f64).sin();
        let exact = 7850.0 * 0.02 * polygon;
        let got = total_mass(&model);
        assert!(
            rel(got, exact, exact) < 1e-13,
            "cells {cells}: mass {got} vs {exact}"
        );
        // The test distinguishes the polygon from the circle: they differ by (1 - sin x / x).
        let circle = 7850.0 * 0.02 * PI * r * r;
        assert!(rel(got, circle, circle) > 1e-4, "cells {cells}");
    }
}

#[test]
fn explicit_mesh_mass_is_rho_t_area() {
    // Two quads of a trapezoid: area = (1.0 + 0.6) / 2 * 0.5 = 0.4.
    let (_, model, _) = build(&one_body(
        "{ nodes = [[0.0, 0.0], [0.5, 0.0], [1.0, 0.0], [0.8, 0.5], [0.5, 0.5], [0.2, 0.5]], quads = [[0, 1, 4, 5], [1, 2, 3, 4]] }",
        "",
    ));
    let exact = 7850.0 * 0.02 * 0.4;
    assert!(rel(total_mass(&model), exact, exact) < 1e-13);
}

#[test]
fn free_body_conserves_mass_and_momentum() {
    // A free block with a translation, a spin and a stretching velocity field, viscous hourglass
    // and bulk viscosity on, variable step: all internal forces of an element sum to zero, so
    // the momentum must stay put to round-off. Measured: drift 6.6e-16 of sum m|v| over 337 steps.
    let text = one_body(
        "{ rectangle = { origin = [0.0, 0.0], size = [0.1, 0.05], cells = [20, 10] } }",
        "initial_velocity = [3.0, -2.0]\nangular_velocity = 150.0\nvelocity_gradient = [[-80.0, 20.0], [10.0, 50.0]]",
    );
    let (scene, model, plan) = build(&text);
    assert!(plan.has_dissipation());
    let momentum = |m: &Model, v: &[[f64; 2]]| {
        let mut p = [0.0; 2];
        let mut scale = 0.0;
        for (w, vi) in m.mass.iter().zip(v) {
            p[0] += w * vi[0];
            p[1] += w * vi[1];
            scale += w * vi[0].hypot(vi[1]);
        }
        (p, scale)
    };
    let (p0, scale) = momentum(&model, &model.velocity);
    let mass0 = model.mass.clone();
    let total = total_mass(&model);
    // The initial momentum is the rigid translation: the spin and gradient are about the centroid.
    assert!(rel(p0[0], 3.0 * total, scale) < 1e-14 && rel(p0[1], -2.0 * total, scale) < 1e-14);

    let dir = tmp_dir("momentum");
    let mut solver = CpuSolver::new(model.clone(), plan.clone(), run::schedule(&scene));
    let result = run::run(&scene, &model, &plan, &mut solver, &dir, None).unwrap();
    assert_eq!(
        result.summary.status, "completed",
        "{}",
        result.summary.message
    );
    assert!(result.summary.steps > 300);
    let (p1, _) = momentum(solver.model(), solver.velocity());
    let drift = (p1[0] - p0[0]).hypot(p1[1] - p0[1]) / scale;
    println!(
        "free body: {} steps, momentum drift {drift:.2e} of sum m|v|",
        result.summary.steps
    );
    assert!(drift < 1e-12, "momentum drift {drift:e}");
    assert_eq!(solver.model().mass, mass0, "the mass array must not change");
    // And the history's body velocity (momentum / mass) stays at the translation velocity.
    let (header, rows) = read_csv(&dir.join("history.csv"));
    let (vx, vy) = (column(&header, "b.vx"), column(&header, "b.vy"));
    for r in &rows {
        assert!(
            (r[vx] - 3.0).abs() < 1e-12 && (r[vy] + 2.0).abs() < 1e-12,
            "{r:?}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
