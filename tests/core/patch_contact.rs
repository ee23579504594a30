//! The contact patch test of `REFERENCES.md` section 3 (Taylor & Papadopoulos 1991) on the CPU
//! reference path: two plane-strain steel blocks touching along y = 0.5 with non-matching meshes
//! (4/3, 5/4 and 8/6 elements along x, two layers each), a uniform pressure p = 1e-3 E on the top
//! edge ramped slowly, mass damping, u_y = 0 at y = 0 and u_x = 0 on x = 0. Once the blocks have
//! settled, every element must carry sigma_yy = -p, sigma_xx = sigma_xy = 0.
//!
//! Two-pass Lagrange contact passes (error below 1e-4 p asserted; measured about 1e-9 p).
//! One pass does not on non-nested meshes, and the test asserts that this known failure is
//! reproduced. Two-pass penalty is not exact either (the springs let the surfaces interpenetrate
//! unevenly); its error is reported and bounded.

use ricochet::output::history::EnergyAudit;
use ricochet::plan::Stage;
use ricochet::run::schedule;
use ricochet::step::cpu::CpuSolver;
use ricochet::step::{Event, Sample, Solver};

use crate::common::*;

#[path = "../shared/patch_scene.rs"]
pub mod patch_scene;
use patch_scene::*;

/// What a settled run gives.
struct Settled {
    /// Largest |sigma_yy + p|, |sigma_xx|, |sigma_xy| over all elements, over p.
    stress_error: f64,
    /// Vertical contact force on the upper block over p (1 m wide, unit thickness): exact 1.
    contact_force: f64,
    /// Largest nodal speed at the end (m/s).
    max_speed: f64,
    /// Largest energy-balance error over the run.
    energy_error: f64,
    /// Kinetic over strain energy at the end.
    kinetic_ratio: f64,
    /// Largest penetration at the end (m).
    penetration: f64,
    /// Smallest step taken (s).
    dt_min: f64,
}

/// Runs [`scene`] to its end.
fn settle(lower: usize, upper: usize, first: &str, contact: &str) -> Settled {
    settle_scene(&scene(lower, upper, first, contact), first)
}

/// Runs the patch-test scene `text` to its end (`first` as for [`settle`]).
fn settle_scene(text: &str, first: &str) -> Settled {
    let (scene, model, plan) = build(text);
    // The history reports the contact force on the first body.
    let sign = if first == "upper" { 1.0 } else { -1.0 };
    assert!(plan.has(Stage::Pressure) && plan.has(Stage::MassDamping));
    let mut solver = CpuSolver::new(model.clone(), plan, schedule(&scene));
    let mut events = Vec::new();
    let mut samples: Vec<Sample> = Vec::new();
    'run: loop {
        solver.advance(&mut events).expect("CPU solver");
        for ev in events.drain(..) {
            match ev {
                Event::Sample(s) => samples.push(s),
                Event::Failed(f) => panic!("the run failed: {}", f.message),
                Event::Done => break 'run,
                Event::Snapshot(_) => {}
            }
        }
    }
    let mut audit = EnergyAudit::default();
    let energy_error = samples
        .iter()
        .map(|s| audit.error(s))
        .fold(0.0f64, f64::max);
    let last = samples.last().expect("samples");
    let stress_error = stress_error(&model, solver.displacement());
    let max_speed = solver
        .velocity()
        .iter()
        .map(|v| v[0].hypot(v[1]))
        .fold(0.0f64, f64::max);
    Settled {
        stress_error,
        contact_force: sign * last.contacts[0].force[1] / P,
        max_speed,
        energy_error,
        kinetic_ratio: last.kinetic.abs() / last.internal,
        penetration: last.contacts[0].max_penetration,
        dt_min: samples.iter().map(|s| s.dt).fold(f64::INFINITY, f64::min),
    }
}

/// The augmented Lagrangian's defining property: the multipliers carry the pressure, so the
/// settled blocks keep no penetration of the spring's and pass the patch test like Lagrange
/// contact (two-pass within 1e-4 p), with the penalty's default spring (s = 2), which the penalty
/// method would need over 100 x stiffer for the same penetration: the penalty at 100 x the
/// stiffness still penetrates deeper, at a step over 5 x shorter. The run settings are those of
/// the verification case `patch_augmented` (mass damping 2.4e4 /s, 30 ms: the update's rate is
/// half the damping; see its file).
#[test]
fn augmented_lagrange_passes_the_patch_test_with_a_soft_spring() {
    let s = 2.0;
    let run = |lower: usize, upper: usize, contact: &str| {
        let text = scene(lower, upper, "upper", contact)
            .replace("end_time = 1.0e-2", "end_time = 3.0e-2")
            .replace("mass_damping = 1.2e4", "mass_damping = 2.4e4");
        settle_scene(&text, "upper")
    };
    for (lower, upper) in MESHES {
        let r = run(
            lower,
            upper,
            &format!("method = \"augmented_lagrange\"\ntwo_pass = true\npenalty_scale = {s}"),
        );
        let pen = run(
            lower,
            upper,
            &format!("method = \"penalty\"\ntwo_pass = true\npenalty_scale = {s}"),
        );
        let stiff = run(
            lower,
            upper,
            &format!(
                "method = \"penalty\"\ntwo_pass = true\npenalty_scale = {}",
                100.0 * s
            ),
        );
        eprintln!(
            "contact patch test, two-pass augmented Lagrange (s = {s}), {lower}/{upper}: stress \
             error {:.2e} p, contact force {:.10} p, penetration {:.2e} m, dt {:.3e} s; penalty at \
             s = {s}: {:.2e} m, error {:.2e} p, dt {:.3e} s; at {}: {:.2e} m, error {:.2e} p, dt \
             {:.3e} s; kinetic/strain {:.1e}, energy error {:.1e}",
            r.stress_error,
            r.contact_force,
            r.penetration,
            r.dt_min,
            pen.penetration,
            pen.stress_error,
            pen.dt_min,
            100.0 * s,
            stiff.penetration,
            stiff.stress_error,
            stiff.dt_min,
            r.kinetic_ratio,
            r.energy_error
        );
        assert!(r.kinetic_ratio < 1e-9, "not settled: {:e}", r.kinetic_ratio);
        assert!(r.stress_error < 1e-4, "stress error {:e} p", r.stress_error);
        assert!((r.contact_force - 1.0).abs() < 1e-4);
        // The penalty with the same spring misses the patch test (3-4e-2 p).
        assert!(pen.stress_error > 1e-2, "penalty {:e} p", pen.stress_error);
        assert!(
            r.penetration < 1e-2 * pen.penetration && r.penetration < stiff.penetration,
            "penetration {:e} m, the penalty's {:e} m, at 100 x {:e} m",
            r.penetration,
            pen.penetration,
            stiff.penetration
        );
        // The soft spring's step (within the variation of the element step as the blocks
        // deform), about sqrt(100) = 10 x the stiff one's.
        assert!(
            (r.dt_min / pen.dt_min - 1.0).abs() < 1e-3,
            "dt {:e} s",
            r.dt_min
        );
        assert!(r.dt_min > 5.0 * stiff.dt_min, "dt {:e} s", r.dt_min);
        assert!(r.energy_error < 1e-5, "energy error {:e}", r.energy_error);
    }
}

#[test]
fn two_pass_lagrange_passes_the_contact_patch_test() {
    // Bound from the Done-when criterion: 1e-4 p. Measured: see the printed errors.
    for (lower, upper) in MESHES {
        for first in ["upper", "lower"] {
            let r = settle(
                lower,
                upper,
                first,
                "method = \"lagrange\"\ntwo_pass = true",
            );
            eprintln!(
                "contact patch test, two-pass Lagrange, {lower}/{upper}, first body {first}: \
                 stress error {:.2e} p, contact force {:.10} p, max speed {:.1e} m/s, \
                 kinetic/strain {:.1e}, energy error {:.1e}",
                r.stress_error, r.contact_force, r.max_speed, r.kinetic_ratio, r.energy_error
            );
            assert!(
                r.kinetic_ratio < 1e-9,
                "{lower}/{upper}: not settled, kinetic/strain energy {:e}",
                r.kinetic_ratio
            );
            assert!(
                r.stress_error < 1e-4,
                "{lower}/{upper}, first {first}: stress error {:e} p",
                r.stress_error
            );
            assert!(
                (r.contact_force - 1.0).abs() < 1e-4,
                "{lower}/{upper}: contact force {} p",
                r.contact_force
            );
            assert!(r.energy_error < 1e-5, "energy error {:e}", r.energy_error);
        }
    }
}

#[test]
fn one_pass_lagrange_fails_the_contact_patch_test_on_non_nested_meshes() {
    // The known failure (REFERENCES.md section 3): one pass transmits the pressure through the
    // slave nodes only; on non-nested meshes the master nodes between them are unsupported and
    // interpenetrate, and the stress is off by several percent whichever side is the slave.
    for (lower, upper) in MESHES {
        for (first, side) in [("upper", "coarse"), ("lower", "fine")] {
            let r = settle(
                lower,
                upper,
                first,
                "method = \"lagrange\"\ntwo_pass = false",
            );
            eprintln!(
                "contact patch test, one-pass Lagrange, {lower}/{upper}, {side} side ({first}) \
                 slave: stress error {:.3} p, contact force {:.10} p, kinetic/strain {:.1e}",
                r.stress_error, r.contact_force, r.kinetic_ratio
            );
            assert!(r.kinetic_ratio < 1e-9, "not settled: {:e}", r.kinetic_ratio);
            assert!(
                r.stress_error > 0.03,
                "{lower}/{upper}, {side} slave: one pass should fail the patch test, \
                 stress error only {:e} p",
                r.stress_error
            );
            // Equilibrium still holds globally.
            assert!((r.contact_force - 1.0).abs() < 1e-4);
        }
    }
}

#[test]
fn two_pass_penalty_is_close_but_not_exact() {
    // Penalty contact does not pass the patch test exactly: the springs carry the pressure with
    // a penetration p / k that differs from node to node on non-matching meshes. Reported, and
    // bounded (the bound is loose: a regression check, not an accuracy claim). With the default
    // penalty_scale = 0.1 the springs let the surfaces interpenetrate by about 2.5 mm here (five
    // times the elastic compression of the blocks) and the run does not settle within the
    // 10 ms: the scales 1 and 10 are used.
    for (lower, upper) in MESHES {
        for scale in [1.0, 10.0] {
            let r = settle(
                lower,
                upper,
                "upper",
                &format!("method = \"penalty\"\ntwo_pass = true\npenalty_scale = {scale}"),
            );
            eprintln!(
                "contact patch test, two-pass penalty (scale {scale}), {lower}/{upper}: stress \
                 error {:.3e} p, contact force {:.10} p, kinetic/strain {:.1e}",
                r.stress_error, r.contact_force, r.kinetic_ratio
            );
            assert!(r.kinetic_ratio < 1e-9, "not settled: {:e}", r.kinetic_ratio);
            assert!(r.stress_error < 0.5, "stress error {:e} p", r.stress_error);
            assert!((r.contact_force - 1.0).abs() < 1e-4);
        }
    }
}

#[test]
fn pressure_and_damping_stages_only_when_used_and_auto_runs_them() {
    // A scene without pressure or damping (mass_damping = 0 included) pays for neither.
    let plain = scene(4, 3, "upper", "method = \"lagrange\"")
        .replace("mass_damping = 1.2e4", "mass_damping = 0.0");
    let start = plain.find("[[pressure]]").expect("pressure table");
    let end = plain[start..].find("[[boundary]]").expect("boundary table") + start;
    let plain = format!("{}{}", &plain[..start], &plain[end..]);
    let (_, model, plan) = build(&plain);
    assert!(model.pressures.is_empty() && model.mass_damping == 0.0);
    assert!(!plan.has(Stage::Pressure) && !plan.has(Stage::MassDamping));
    assert_eq!(plan.pressure_nodes, 0);
    // With both: the stages, in order, and the loaded nodes (the top edge: upper + 1 nodes).
    let (_, _, plan) = build(&scene(4, 3, "upper", "method = \"lagrange\""));
    let names = plan.to_string();
    assert!(
        names.contains("bulk_viscosity -> pressure -> stable_step -> mass_damping -> node_update"),
        "{names}"
    );
    assert_eq!(plan.pressure_nodes, 4);
    // `--backend auto` runs a pressure-only scene (on the GPU where there is one: no stage of it is
    // CPU-only any more).
    let dir = tmp_dir("patch-auto");
    let file = dir.join("pressure_only.toml");
    let no_contact = {
        let s = scene(4, 3, "upper", "method = \"lagrange\"")
            .replace("end_time = 1.0e-2", "end_time = 1.0e-4")
            .replace("mass_damping = 1.2e4", "mass_damping = 0.0");
        let start = s.find("[[contact]]").expect("contact table");
        let end = s[start..].find("[[pressure]]").expect("pressure table") + start;
        format!("{}{}", &s[..start], &s[end..])
    };
    std::fs::write(&file, no_contact).unwrap();
    let out = dir.join("out");
    let o = run_bin(&[
        "run",
        file.to_str().unwrap(),
        "--backend",
        "auto",
        "--out",
        out.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{err}");
    assert!(!err.contains("CPU backend only"), "{err}");
    let check = run_bin(&["check", file.to_str().unwrap()]);
    let text = String::from_utf8_lossy(&check.stdout);
    assert!(
        text.contains("pressure[0]: 2.1e8 Pa on 3 edges (4 nodes)"),
        "{text}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
