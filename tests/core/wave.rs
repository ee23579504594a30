//! 1D waves in a rod strip: plane stress, nu = 0, square elements, one element high, no bulk
//! viscosity, a fixed step dt = C h / c. Such a strip is exactly the lumped-mass 1D chain (each
//! node pair carries half of the chain's node mass and half of each spring force; the motion
//! along x is uniform over the height, so it excites neither hourglass nor lateral modes),
//! whose central-difference dispersion is sin(omega dt / 2) = C sin(k h / 2)
//! (`REFERENCES.md` section 2).
//!
//! (a) Dispersion: a standing wave v(x, 0) = V cos(k x) on a free-free rod is an exact discrete
//!     eigenmode (k L = 2 pi); its modal velocity obeys v^{n+3/2} + v^{n-1/2} =
//!     2 cos(omega dt) v^{n+1/2}, which gives omega and the phase-speed error c_h / c - 1.
//! (b) A step: the rod moves at v0 and its left end is held. A tension front rho c v0 runs to
//!     the free end and comes back with the velocity reversed and the stress released. The
//!     stress next to the held end overshoots by the table's factor (1.071 at C = 0.9, 1.086 at
//!     C = 0.5), which the test also reproduces with an independent 1D chain.

use std::f64::consts::PI;

use ricochet::output::fields::element_fields;
use ricochet::plan::Plan;

use crate::common::*;
use crate::scene_text::{fixed_step_run, STEEL_NU0};

const H: f64 = 0.01; // element size (m)
const T: f64 = 0.01; // thickness (m)

fn bar_speed() -> f64 {
    (E_STEEL / RHO_STEEL).sqrt()
}

fn rod_scene(cells: usize, c_number: f64, steps: usize, hourglass: &str, boundary: bool) -> String {
    let dt = c_number * H / bar_speed();
    let mut s = format!(
        r#"
{run}

{STEEL_NU0}

[[body]]
name = "rod"
material = "steel"
formulation = "plane_stress"
thickness = {T}
mesh = {{ rectangle = {{ origin = [0.0, 0.0], size = [{len}, {H}], cells = [{cells}, 1] }} }}
hourglass = {{ form = "{hourglass}", coefficient = 0.1 }}
initial_velocity = [5.0, 0.0]
"#,
        run = fixed_step_run(dt * steps as f64, dt),
        len = H * cells as f64,
    );
    if boundary {
        s.push_str(
            r#"
[[boundary]]
body = "rod"
region = { min = [-1.0e-9, -1.0], max = [1.0e-9, 1.0] }
velocity = { x = 0.0 }
"#,
        );
    }
    s
}

/// Phase-speed error c_h / c - 1 of the standing wave with `ppw` nodes per wavelength at
/// Courant number `c_number`, measured from the solver; also checks that the motion stays in
/// the mode.
fn measured_phase_error(ppw: usize, c_number: f64, hourglass: &str) -> f64 {
    let steps = 300;
    let text = rod_scene(ppw, c_number, steps, hourglass, false);
    let scene = parse(&text);
    let mut model = ricochet::run::model(&scene).unwrap();
    let k = 2.0 * PI / (ppw as f64 * H);
    let vamp = 1.0;
    let shape: Vec<f64> = model.position.iter().map(|x| (k * x[0]).cos()).collect();
    for (v, s) in model.velocity.iter_mut().zip(&shape) {
        *v = [vamp * s, 0.0];
    }
    let plan = Plan::new(&scene, &model);
    let dt = scene.run.time_step.unwrap();
    let sched = every_step(scene.run.end_time, Some(dt), 0.9, 0.5 * dt);
    let mut stepper = Stepper::new(model.clone(), plan, sched);
    let norm: f64 = (0..shape.len())
        .map(|i| model.mass[i] * shape[i] * shape[i])
        .sum();
    let mut amp = Vec::new();
    loop {
        let more = stepper.advance();
        let v = stepper.solver.velocity();
        let a = (0..v.len())
            .map(|i| model.mass[i] * v[i][0] * shape[i])
            .sum::<f64>()
            / norm;
        for i in 0..v.len() {
            assert!(
                (v[i][0] - a * shape[i]).abs() < 1e-9 * vamp && v[i][1].abs() < 1e-9 * vamp,
                "node {i} left the standing wave at step {}",
                amp.len()
            );
        }
        amp.push(a);
        if !more {
            break;
        }
    }
    assert!(stepper.failure.is_none(), "{:?}", stepper.failure);
    assert_eq!(amp.len(), steps + 1);
    // Least squares on the three-term recurrence (amp[n] is v^{n+1/2}).
    let (mut num, mut den) = (0.0, 0.0);
    for n in 1..amp.len() - 1 {
        num += amp[n] * (amp[n + 1] + amp[n - 1]);
        den += 2.0 * amp[n] * amp[n];
    }
    let omega = (num / den).acos() / dt;
    omega / (k * bar_speed()) - 1.0
}

/// The closed form of `REFERENCES.md` section 2: omega dt / 2 = asin(C sin(k h / 2)).
fn analytic_phase_error(ppw: usize, c_number: f64) -> f64 {
    let kh = 2.0 * PI / ppw as f64;
    2.0 * (c_number * (0.5 * kh).sin()).asin() / (kh * c_number) - 1.0
}

#[test]
fn standing_wave_matches_the_dispersion_table() {
    // (points per wavelength, C, table value, half a unit of the table's last digit)
    let table = [
        (10, 0.5, -1.24e-2, 0.005e-2),
        (10, 0.9, -3.23e-3, 0.005e-3),
        (20, 0.5, -3.09e-3, 0.005e-3),
        (20, 0.9, -7.87e-4, 0.005e-4),
    ];
    for (ppw, c_number, reference, half_unit) in table {
        for hourglass in ["stiffness", "none"] {
            let got = measured_phase_error(ppw, c_number, hourglass);
            let exact = analytic_phase_error(ppw, c_number);
            println!(
                "dispersion: {ppw} points per wavelength, C = {c_number}, {hourglass}: c_h/c - 1 = {got:.6e} (closed form {exact:.6e}, table {reference:e})"
            );
            // The recurrence is exact, so only round-off separates the solver from the closed
            // form (acos near 1 amplifies it by 1/sin(omega dt) ~ 10).
            assert!(
                (got - exact).abs() < 1e-9,
                "{ppw} ppw, C = {c_number}: {got:e} vs closed form {exact:e}"
            );
            assert!(
                (got - reference).abs() <= half_unit,
                "{ppw} ppw, C = {c_number}: {got:e} vs table {reference:e}"
            );
        }
    }
}

/// Stress histories of an independent lumped-mass 1D chain (unit-free: rho = E = h = v0 = 1, so
/// c = 1 and stresses are in units of rho c v0), N elements, left node held from the first
/// update, initial velocity 1. Returns the element stresses at each t_n, n = 0..=steps.
fn chain(cells: usize, c_number: f64, steps: usize) -> Vec<Vec<f64>> {
    let n = cells + 1;
    let mut m = vec![1.0; n];
    m[0] = 0.5;
    m[n - 1] = 0.5;
    let mut u = vec![0.0; n];
    let mut v = vec![1.0; n];
    let dt = c_number;
    let mut out = Vec::new();
    for step in 0..=steps {
        let s: Vec<f64> = (0..cells).map(|e| u[e + 1] - u[e]).collect();
        let mut f = vec![0.0; n];
        for e in 0..cells {
            f[e] += s[e];
            f[e + 1] -= s[e];
        }
        out.push(s);
        let dtn = if step == 0 { 0.5 * dt } else { dt };
        for i in 0..n {
            v[i] += dtn * f[i] / m[i];
        }
        v[0] = 0.0;
        for i in 0..n {
            u[i] += dt * v[i];
        }
    }
    out
}

/// What the step-pulse run measured.
struct Pulse {
    dt: f64,
    /// Max over time of the stress next to the held end / (rho c v0).
    overshoot: f64,
    /// Arrival time of the front at the midpoint (velocity crossing v0/2), minus L/(2c), in steps.
    arrival_steps: f64,
    /// Right-end velocity before the front arrives (t <= 0.75 L/c), / v0: (min, max).
    end_velocity_before: (f64, f64),
    /// Right-end velocity for t in [1.25, 1.75] L/c, / v0: (min, mean, max).
    end_velocity_after: (f64, f64, f64),
    /// Stress in the right quarter at t = 1.5 L/c, / (rho c v0): (mean, rms, max |.|).
    quarter_stress: (f64, f64, f64),
    /// Largest difference to the 1D chain over all elements and steps, / (rho c v0).
    chain_difference: f64,
}

fn step_pulse(c_number: f64, hourglass: &str) -> Pulse {
    let cells = 100;
    let len = cells as f64 * H;
    let c = bar_speed();
    let v0 = 5.0;
    let dt = c_number * H / c;
    let steps = (1.75 * len / c / dt).ceil() as usize;
    let scene = parse(&rod_scene(cells, c_number, steps, hourglass, true));
    let model = ricochet::run::model(&scene).unwrap();
    assert_eq!(
        model.constraints.len(),
        2,
        "the two left-end nodes are held"
    );
    let plan = Plan::new(&scene, &model);
    let sched = every_step(scene.run.end_time, Some(dt), 0.9, 0.5 * dt);
    let mut stepper = Stepper::new(model.clone(), plan, sched);
    let reference = chain(cells, c_number, steps);
    let sigma0 = RHO_STEEL * c * v0;
    let (mid_bottom, mid_top) = (cells / 2, cells + 1 + cells / 2);
    let (end_bottom, end_top) = (cells, 2 * cells + 1);
    let mut overshoot = 0.0f64;
    let mut chain_difference = 0.0f64;
    let mut mid_v: Vec<(f64, f64)> = Vec::new(); // (t_{n+1/2}, v / v0)
    let mut before = (f64::INFINITY, f64::NEG_INFINITY);
    let (mut after_min, mut after_max, mut after_sum, mut after_n) =
        (f64::INFINITY, f64::NEG_INFINITY, 0.0, 0);
    let mut quarter = (0.0, 0.0, 0.0);
    let target_step = (1.5 * len / c / dt).round() as usize;
    let mut n = 0usize;
    loop {
        // One step per call: the sample is at t_n, the velocities are v^{n+1/2}, and (unless
        // the run just ended) the displacements already are u_{n+1}.
        let more = stepper.advance();
        let t_n = stepper.samples.last().unwrap().time;
        let v = stepper.solver.velocity();
        for node in [mid_bottom, mid_top, end_bottom, end_top] {
            assert!(v[node][1].abs() < 1e-9 * v0);
        }
        assert!(
            (v[mid_bottom][0] - v[mid_top][0]).abs() < 1e-12 * v0,
            "the strip moves as a 1D rod"
        );
        mid_v.push((t_n + 0.5 * dt, v[mid_bottom][0] / v0));
        let t_half = t_n + 0.5 * dt;
        let ve = v[end_bottom][0] / v0;
        if t_half <= 0.75 * len / c {
            before = (before.0.min(ve), before.1.max(ve));
        }
        if t_half >= 1.25 * len / c && t_half <= 1.75 * len / c {
            after_min = after_min.min(ve);
            after_max = after_max.max(ve);
            after_sum += ve;
            after_n += 1;
        }
        if !more {
            break;
        }
        n += 1;
        // u_n for this n (after the step's displacement update).
        let u = stepper.solver.displacement();
        let m = stepper.solver.model();
        let stresses: Vec<f64> = (0..cells)
            .map(|e| element_fields(m, u, e).stress[0] / sigma0)
            .collect();
        overshoot = overshoot.max(stresses[0]);
        for e in 0..cells {
            chain_difference = chain_difference.max((stresses[e] - reference[n][e]).abs());
        }
        if n == target_step {
            let q: Vec<f64> = stresses[3 * cells / 4..].to_vec();
            let mean = q.iter().sum::<f64>() / q.len() as f64;
            let rms = (q.iter().map(|x| x * x).sum::<f64>() / q.len() as f64).sqrt();
            let max = q.iter().fold(0.0f64, |a, x| a.max(x.abs()));
            quarter = (mean, rms, max);
        }
    }
    assert!(stepper.failure.is_none(), "{:?}", stepper.failure);
    // Arrival: first crossing of v0/2 by the midpoint velocity, interpolated.
    let mut arrival = None;
    for w in mid_v.windows(2) {
        let ((t0, a), (t1, b)) = (w[0], w[1]);
        if a > 0.5 && b <= 0.5 {
            arrival = Some(t0 + (a - 0.5) / (a - b) * (t1 - t0));
            break;
        }
    }
    let arrival = arrival.expect("the front never reached the midpoint");
    Pulse {
        dt,
        overshoot,
        arrival_steps: (arrival - 0.5 * len / c) / dt,
        end_velocity_before: before,
        end_velocity_after: (after_min, after_sum / after_n as f64, after_max),
        quarter_stress: quarter,
        chain_difference,
    }
}

fn check_pulse(c_number: f64, table_overshoot: f64, hourglass: &str) {
    let p = step_pulse(c_number, hourglass);
    println!(
        "step pulse C = {c_number} ({hourglass}): dt {:.4e} s, overshoot {:.5} (table {table_overshoot}), arrival at L/2c {:+.3} steps, right end v/v0 before {:?}, after (min, mean, max) ({:.4}, {:.5}, {:.4}), right-quarter stress at 1.5 L/c mean {:+.4} rms {:.4} max {:.4}, max difference to the 1D chain {:.2e}",
        p.dt,
        p.overshoot,
        p.arrival_steps,
        p.end_velocity_before,
        p.end_velocity_after.0,
        p.end_velocity_after.1,
        p.end_velocity_after.2,
        p.quarter_stress.0,
        p.quarter_stress.1,
        p.quarter_stress.2,
        p.chain_difference
    );
    // The strip is the 1D chain: equal to round-off (stresses ~1, f64).
    assert!(
        p.chain_difference < 1e-9,
        "strip differs from the 1D chain by {:e} rho c v0",
        p.chain_difference
    );
    // Overshoot: the table gives 3-4 digits, so half a unit of its last digit.
    assert!(
        (p.overshoot - table_overshoot).abs() <= 5e-4,
        "overshoot {} vs table {table_overshoot}",
        p.overshoot
    );
    // Arrival within a couple of steps of L / (2c). (The half-amplitude point of the dispersed
    // front lags by a fraction of a step that grows like (travel)^(1/3); measured 1.3 steps at
    // C = 0.5 and 0.4 at C = 0.9 after 50 elements.)
    assert!(
        p.arrival_steps.abs() <= 2.0,
        "front reached the midpoint {} steps from L/(2c)",
        p.arrival_steps
    );
    // Before the front arrives the free end still moves at +v0 (exactly: nothing reached it).
    assert!(
        (p.end_velocity_before.0 - 1.0).abs() < 1e-9
            && (p.end_velocity_before.1 - 1.0).abs() < 1e-9,
        "right end before arrival {:?}",
        p.end_velocity_before
    );
    // After reflection from the free end the velocity there is reversed: -v0 on average (the
    // dispersive ringing trailing the reflected front averages out over half a transit; 1 %),
    // and never positive.
    let (lo, mean, hi) = p.end_velocity_after;
    assert!(
        (mean + 1.0).abs() < 0.01,
        "mean reflected velocity {mean} v0"
    );
    assert!(
        hi < 0.0 && lo > -1.5,
        "reflected velocity range [{lo}, {hi}] v0"
    );
    // And the stress there is released (the reflected compression cancels the tension): on
    // average over the right quarter it is zero, and only the ringing that trails the dispersed
    // front remains (measured rms 0.036 at C = 0.9, 0.045 at C = 0.5), against 1 before
    // reflection. A reflection with the wrong sign would double the tension instead.
    let (mean, rms, max) = p.quarter_stress;
    assert!(mean.abs() < 0.02, "right-quarter mean stress {mean}");
    assert!(
        rms < 0.1 && max < 0.2,
        "right-quarter stress rms {rms} max {max}"
    );
}

#[test]
fn step_pulse_at_courant_0_9() {
    check_pulse(0.9, 1.071, "stiffness");
}

#[test]
fn step_pulse_at_courant_0_5() {
    check_pulse(0.5, 1.086, "none");
}

#[test]
fn the_independent_chain_reproduces_the_table_overshoots() {
    // Guards the reference chain itself against REFERENCES.md section 2 (1.0097 at C = 0.99).
    for (c_number, table) in [(0.99, 1.0097), (0.9, 1.071), (0.5, 1.086)] {
        let s = chain(100, c_number, (50.0 / c_number) as usize);
        let max = s.iter().fold(0.0f64, |m, x| m.max(x[0]));
        assert!(
            (max - table).abs() <= 5e-4,
            "C = {c_number}: {max} vs {table}"
        );
    }
}
