//! Load curves: a velocity or a pressure given as a table of `[time, value]` points.
//!
//! The bar of REFERENCES.md section 1 (steel, plane stress, nu = 0, A = h t), its left end held
//! at u = 0, its right end pulled at v(t) rising linearly from 0 to V over t_r and held. Until
//! the wave reflected at the left end comes back (2 L / c), the pulled end sees a semi-infinite
//! bar: its reaction is A rho c v(t), and the work done on the bar is
//! W(t) = A rho c (V^2 t_r / 3 + V^2 (t - t_r)) for t > t_r. The energy balance closes to
//! round-off with the prescribed value at t_{n+1/2} and t_{n-1/2} in the reaction's work (and
//! twice the reaction on the first, half, step). Measured: work within 4.5e-4, reaction within
//! 1.5e-5 of A rho c V, energy balance 1.2e-11.

use ricochet::output::history::EnergyAudit;
use ricochet::plan::Plan;

use crate::common::*;

#[path = "../shared/load_curve_scene.rs"]
mod load_curve_scene;
use load_curve_scene::*;

#[test]
fn ramped_then_held_pull_gives_the_wave_reaction_and_closes_the_energy_balance() {
    let (scene, model, plan) = build(&bar_scene(&format!("[[0.0, 0.0], [{RAMP:e}, {V}]]")));
    let schedule = every_step(scene.run.end_time, scene.run.time_step, 0.9, 1e-9);
    let mut st = Stepper::new(model, plan, schedule);
    while st.advance() {}
    assert!(st.failure.is_none(), "{:?}", st.failure);
    let c = (E / RHO).sqrt();
    let impedance = H * T * RHO * c;
    let exact = |t: f64| {
        if t < RAMP {
            impedance * V * V * t.powi(3) / (3.0 * RAMP * RAMP)
        } else {
            impedance * V * V * (RAMP / 3.0 + (t - RAMP))
        }
    };
    let mut audit = EnergyAudit::default();
    let (mut worst_w, mut worst_f) = (0.0f64, 0.0f64);
    let reflect = 2.0 * L / c;
    let mut prev: Option<(f64, f64)> = None;
    for s in &st.samples {
        audit.error(s);
        if s.time > 2.0 * RAMP && s.time < reflect - 2.0e-5 {
            worst_w = worst_w.max((s.external - exact(s.time)).abs() / exact(s.time));
            // The reaction from the work's rate over one step: dW/dt = F V once the ramp is done.
            if let Some((t0, w0)) = prev {
                let f = (s.external - w0) / (s.time - t0) / V;
                worst_f = worst_f.max((f - impedance * V).abs() / (impedance * V));
            }
            prev = Some((s.time, s.external));
        }
    }
    println!(
        "pulled bar: work within {worst_w:.2e} of A rho c V^2 (t - 2 t_r / 3), reaction within \
         {worst_f:.2e} of A rho c V = {:.4e} N, energy balance {:.2e}",
        impedance * V,
        audit.max_error
    );
    assert!(worst_w < 5e-3, "work differs by {worst_w:e} relative");
    assert!(worst_f < 2e-2, "reaction differs by {worst_f:e} relative");
    assert!(
        audit.max_error < 1e-6,
        "energy balance error {:e}",
        audit.max_error
    );
}

#[test]
fn a_constant_table_is_the_constant_and_a_one_point_table_is_a_constant() {
    // The same bar pulled at the constant V, written three ways: the same history bit for bit.
    let runs: Vec<Vec<(f64, f64, f64)>> = [
        format!("{V}"),
        format!("[[0.0, {V}]]"),
        format!("[[0.0, {V}], [1.0e-4, {V}]]"),
    ]
    .iter()
    .map(|v| {
        let (scene, model, plan) = build(&bar_scene(v));
        let schedule = every_step(1.0e-4, scene.run.time_step, 0.9, 1e-9);
        let plan: Plan = plan;
        let mut st = Stepper::new(model, plan, schedule);
        while st.advance() {}
        st.samples
            .iter()
            .map(|s| (s.kinetic, s.internal, s.external))
            .collect()
    })
    .collect();
    assert!(runs[0].len() > 100);
    assert_eq!(runs[0], runs[1]);
    assert_eq!(runs[0], runs[2]);
}

#[test]
fn a_pressure_curve_is_the_pressure_ramp_it_describes() {
    // `ramp = t_r` and the curve [[0, 0], [t_r, p]] load the bar's right end identically.
    // The bar with its left end held and no pulled end (the scene's second boundary dropped).
    let full = bar_scene("0.0");
    let cut = full
        .find("\n[[boundary]]\nbody = \"bar\"\nregion = { min = [0.9")
        .expect("the pulled end's table");
    let base = &full[..cut];
    let with = |load: &str| {
        let text = format!(
            "{base}\n[[pressure]]\nbody = \"bar\"\nregion = {{ min = [{}, -1.0], max = [{}, 1.0] }}\n{load}\n",
            L - 1e-9,
            L + 1e-9
        );
        let (scene, model, plan) = build(&text);
        let schedule = every_step(1.0e-4, scene.run.time_step, 0.9, 1e-9);
        let mut st = Stepper::new(model, plan, schedule);
        while st.advance() {}
        st.samples
            .iter()
            .map(|s| (s.kinetic, s.internal, s.external))
            .collect::<Vec<_>>()
    };
    let a = with(&format!("value = -1.0e6\nramp = {RAMP:e}"));
    let b = with(&format!("value = [[0.0, 0.0], [{RAMP:e}, -1.0e6]]"));
    assert!(a.len() > 100);
    let worst = a
        .iter()
        .zip(&b)
        .map(|(x, y)| (x.2 - y.2).abs() / x.2.abs().max(1e-30))
        .fold(0.0f64, f64::max);
    assert!(worst < 1e-12, "external work differs by {worst:e} relative");
}
