//! Hourglass modes. On a structured mesh the checkerboard field u_x = d (-1)^(i+j) is the
//! hourglass mode of every element: one-point quadrature sees no strain, so without control it
//! costs no energy and meets no force (a zero-energy mode). With control it is an exact
//! eigenmode of the lumped-mass mesh (every node's force and mass scale with the number of its
//! elements), so the discrete dynamics are known in closed form:
//! - stiffness form, spring k = kappa (lambda + 2 mu) A t (b.b) / (gamma.gamma): omega^2 = 4 k / m_e
//!   (m_e = rho t A / 4 per element node) and central difference gives cos(omega_h dt) =
//!   1 - omega^2 dt^2 / 2; the energy swings between kinetic and the stored hourglass energy;
//! - viscous form, damper c = kappa rho c0 A t |b| / (gamma.gamma): with the lagged velocity,
//!   v^{n+1/2} = (1 - 4 c dt / m_e) v^{n-1/2} exactly; the lost kinetic energy is reported as
//!   hourglass work.
//!
//! The runs go through `run::run`, and the checks read `history.csv`.

use ricochet::geometry::HOURGLASS_BASE;
use ricochet::model::Model;
use ricochet::plan::Plan;
use ricochet::run;
use ricochet::scene::Scene;
use ricochet::step::cpu::CpuSolver;

use crate::common::*;
use crate::scene_text::{fixed_step_run, STEEL};

const H: f64 = 0.01; // element size (m)
const T: f64 = 0.01; // thickness (m)
const NX: usize = 4;
const NY: usize = 3;

fn scene_text(form: &str, coefficient: f64, dt: f64, steps: usize) -> String {
    format!(
        r#"
{run}

{STEEL}

[[body]]
name = "block"
material = "steel"
formulation = "plane_strain"
thickness = {T}
mesh = {{ rectangle = {{ origin = [0.0, 0.0], size = [{sx}, {sy}], cells = [{NX}, {NY}] }} }}
hourglass = {{ form = "{form}", coefficient = {coefficient} }}
"#,
        run = fixed_step_run(dt * steps as f64, dt),
        sx = H * NX as f64,
        sy = H * NY as f64,
    )
}

/// Checkerboard sign of node (i, j) of the structured rectangle.
fn checker(node: usize) -> f64 {
    let (i, j) = (node % (NX + 1), node / (NX + 1));
    if (i + j) % 2 == 0 {
        1.0
    } else {
        -1.0
    }
}

#[test]
fn checkerboard_is_the_hourglass_mode_of_every_element() {
    let (_, model, _) = build(&scene_text("none", 0.1, 1e-7, 1));
    for q in &model.quads {
        let s = checker(q[0] as usize);
        for a in 0..4 {
            assert_eq!(checker(q[a] as usize), s * HOURGLASS_BASE[a]);
        }
    }
}

#[test]
fn hourglass_mode_meets_no_force_without_control_and_is_resisted_with_it() {
    let d = 1e-5; // 0.1 % of the element size
                  // Force scale: a strain d/h acting on an edge of length h.
    let scale = E_STEEL * T * d;
    // No control: a zero-energy mode, no force but round-off.
    let (_, model, _) = build(&scene_text("none", 0.1, 1e-7, 1));
    let u: Vec<[f64; 2]> = (0..model.node_count())
        .map(|i| [d * checker(i), 0.0])
        .collect();
    let zero = vec![[0.0; 2]; model.node_count()];
    let f = assemble(&model, &u, &zero);
    let fmax = f.iter().fold(0.0f64, |m, x| m.max(x[0].hypot(x[1])));
    println!(
        "hourglass mode without control: largest nodal force {:.2e} of E t d",
        fmax / scale
    );
    assert!(
        fmax < 1e-9 * scale,
        "form none: hourglass mode force {fmax:e} N"
    );
    // Stiffness form: restoring, with f.u = -2 W (linear springs) and W = sum 1/2 k q^2.
    let (_, model, _) = build(&scene_text("stiffness", 0.1, 1e-7, 1));
    let f = assemble(&model, &u, &zero);
    let work: f64 = (0..model.node_count())
        .map(|i| f[i][0] * u[i][0] + f[i][1] * u[i][1])
        .sum();
    let p = model.params(0);
    // Scaled with 2 mu (not the dilatational modulus); A (b.b) / (gamma.gamma) = 1/2 for a square.
    let k = 0.1 * 2.0 * p.mu * T / 2.0;
    let stored = model.element_count() as f64 * 0.5 * k * (4.0 * d).powi(2);
    assert!(work < 0.0, "stiffness form must oppose the mode");
    assert!(
        rel(-0.5 * work, stored, stored) < 1e-12,
        "work {work:e} J vs stored {stored:e} J"
    );
    // Viscous form: the force opposes the hourglass velocity.
    let (_, model, _) = build(&scene_text("viscous", 0.1, 1e-7, 1));
    let f = assemble(&model, &zero, &u);
    let power: f64 = (0..model.node_count()).map(|i| f[i][0] * u[i][0]).sum();
    assert!(
        power < 0.0,
        "viscous form must oppose the mode (power {power:e})"
    );
}

/// Runs the scene with the checkerboard velocity V and returns (model, modal velocity
/// amplitudes v^{n+1/2} per step, history header and rows).
fn run_mode(
    form: &str,
    coefficient: f64,
    dt: f64,
    steps: usize,
) -> (Model, Vec<f64>, Vec<String>, Vec<Vec<f64>>) {
    let v0 = 1.0;
    let text = scene_text(form, coefficient, dt, steps);
    let scene: Scene = parse(&text);
    let mut model = ricochet::run::model(&scene).unwrap();
    for i in 0..model.node_count() {
        model.velocity[i] = [v0 * checker(i), 0.0];
    }
    let plan = Plan::new(&scene, &model);
    // Modal amplitudes, stepping a copy of the solver.
    let mut stepper = Stepper::new(model.clone(), plan.clone(), run::schedule(&scene));
    let mass: f64 = model.mass.iter().sum();
    let mut amp = Vec::new();
    loop {
        let more = stepper.advance();
        let v = stepper.solver.velocity();
        let a: f64 = (0..v.len())
            .map(|i| model.mass[i] * v[i][0] * checker(i))
            .sum::<f64>()
            / mass;
        amp.push(a);
        // The motion stays in the mode: no y velocity, same |v_x| at every node. Round-off:
        // the off-diagonal F entries (sum_a u_a b_a, not offset by 1) pick up ~1e-16 of the
        // hourglass displacement, which the elastic stiffness (~1/kappa times the hourglass
        // stiffness) turns into ~1e-12 v0 per step. Measured: up to ~1e-11 v0. Tolerance 1e-9 v0.
        for (i, vi) in v.iter().enumerate() {
            assert!(vi[1].abs() <= 1e-9 * v0, "{form}: node {i} vy {}", vi[1]);
            assert!(
                (vi[0] - a * checker(i)).abs() <= 1e-9 * v0,
                "{form}: node {i} left the mode: vx {} vs {}",
                vi[0],
                a * checker(i)
            );
        }
        if !more {
            break;
        }
    }
    assert!(stepper.failure.is_none(), "{:?}", stepper.failure);
    // The same run through the driver, for history.csv.
    let dir = tmp_dir(&format!("hourglass-{form}"));
    let mut solver = CpuSolver::new(model.clone(), plan.clone(), run::schedule(&scene));
    let result = run::run(&scene, &model, &plan, &mut solver, &dir, None).unwrap();
    assert_eq!(
        result.summary.status, "completed",
        "{}",
        result.summary.message
    );
    let (header, rows) = read_csv(&dir.join("history.csv"));
    assert_eq!(rows.len(), steps + 1, "one history row per step");
    let _ = std::fs::remove_dir_all(&dir);
    (model, amp, header, rows)
}

#[test]
fn uncontrolled_hourglass_mode_persists_with_no_energy() {
    let (_, amp, header, rows) = run_mode("none", 0.1, 1e-7, 50);
    // The mode meets no force: the velocity never changes.
    for a in &amp {
        assert!((a - 1.0).abs() < 1e-12, "amplitude {a}");
    }
    let (hg, ke) = (
        column(&header, "hourglass_energy"),
        column(&header, "kinetic_energy"),
    );
    let ke0 = rows[0][ke];
    for r in &rows {
        assert_eq!(r[hg], 0.0, "hourglass energy must be zero without control");
        assert!(rel(r[ke], ke0, ke0) < 1e-12);
    }
}

#[test]
fn stiffness_hourglass_oscillates_at_its_exact_discrete_frequency_and_stores_energy() {
    let dt = 5e-7;
    let steps = 200;
    let (model, amp, header, rows) = run_mode("stiffness", 0.1, dt, steps);
    let p = model.params(0);
    let k = 0.1 * 2.0 * p.mu * T / 2.0;
    let m_e = p.density * T * H * H / 4.0;
    let omega2 = 4.0 * k / m_e;
    let cos_exact = 1.0 - 0.5 * omega2 * dt * dt;
    // Least-squares fit of a^{n+3/2} + a^{n-1/2} = 2 cos(omega_h dt) a^{n+1/2}.
    let (mut num, mut den) = (0.0, 0.0);
    for n in 1..amp.len() - 1 {
        num += amp[n] * (amp[n + 1] + amp[n - 1]);
        den += 2.0 * amp[n] * amp[n];
    }
    let cos_fit = num / den;
    println!(
        "stiffness hourglass: omega dt = {:.4}, cos fit {cos_fit:.15} vs exact {cos_exact:.15}",
        omega2.sqrt() * dt
    );
    assert!((cos_fit - cos_exact).abs() < 1e-12);
    // Energy: the hourglass column takes all of it at the turning points; the balance closes.
    let (hg, ke, err) = (
        column(&header, "hourglass_energy"),
        column(&header, "kinetic_energy"),
        column(&header, "energy_error"),
    );
    let e0 = rows[0][ke];
    let hg_max = rows.iter().fold(0.0f64, |m, r| m.max(r[hg]));
    let err_max = rows.iter().fold(0.0f64, |m, r| m.max(r[err]));
    println!(
        "stiffness hourglass: max hourglass energy {:.6} E0, max energy error {err_max:.2e}",
        hg_max / e0
    );
    assert!(rows.iter().all(|r| r[hg] >= 0.0));
    assert!(
        hg_max > 0.95 * e0,
        "hourglass energy peaks at {hg_max:e} J, E0 = {e0:e} J"
    );
    assert!(err_max < 1e-12, "energy error {err_max:e}");
}

#[test]
fn viscous_hourglass_damps_at_its_exact_rate_and_reports_the_work() {
    let dt = 5e-7;
    let steps = 30;
    let kappa = 0.05;
    let (model, amp, header, rows) = run_mode("viscous", kappa, dt, steps);
    let p = model.params(0);
    let c0 = (2.0 * p.mu / p.density).sqrt(); // the shear-modulus speed sqrt(2 mu / rho)
                                              // |b| = sqrt(2) / h for a square, gamma.gamma = 4.
    let damp = kappa * p.density * c0 * H * H * T * (2.0f64).sqrt() / H / 4.0;
    let m_e = p.density * T * H * H / 4.0;
    let r_exact = 1.0 - 4.0 * damp * dt / m_e;
    for n in 1..amp.len() {
        let r = amp[n] / amp[n - 1];
        assert!(
            (r - r_exact).abs() < 1e-12,
            "step {n}: decay factor {r} vs {r_exact}"
        );
    }
    let (hg, ke, err) = (
        column(&header, "hourglass_energy"),
        column(&header, "kinetic_energy"),
        column(&header, "energy_error"),
    );
    let e0 = rows[0][ke];
    let last = rows.last().unwrap();
    let err_max = rows.iter().fold(0.0f64, |m, r| m.max(r[err]));
    println!(
        "viscous hourglass: decay factor {r_exact:.6} per step; kinetic {:.3e} E0 and hourglass work {:.6} E0 at the end; max energy error {err_max:.2e}",
        last[ke] / e0,
        last[hg] / e0
    );
    for w in rows.windows(2) {
        assert!(w[1][hg] >= w[0][hg], "dissipated work must not decrease");
    }
    assert!(last[hg] > 0.9 * e0, "hourglass work {:e} J", last[hg]);
    // The trapezoidal pairing of the dissipated work closes the balance exactly for fixed steps.
    assert!(err_max < 1e-12, "energy error {err_max:e}");
}
