//! The perturbed Lagrangian (Belytschko X.5.8) on the CPU reference: its defining property, the
//! consistent H distributing the penalty along the surface (see `tests/shared/perturbed_scene.rs`).

use crate::common::*;

#[path = "../shared/perturbed_scene.rs"]
pub mod perturbed_scene;
use perturbed_scene::*;

/// Runs the scene `text` (a quad with `method`) to rest: (penetrations of the base nodes, reactions from
/// statics, kinetic over strain energy at the end).
fn settle(text: &str, method: &str) -> ([f64; 2], [f64; 2], f64) {
    let (model, run) = Stepper::finish(text, method);
    let last = run.samples.last().expect("samples");
    (
        penetrations(&model.position, run.solver.displacement()),
        reactions(&model.mass[..4], &model.position[..4]),
        last.kinetic / last.internal,
    )
}

#[test]
fn perturbed_lagrange_distributes_the_penalty_by_the_consistent_h() {
    // Off-centre weight: the penalty tilts the base by (R0 - R1) / (R0 + R1), the consistent H
    // by three times that, with the same mean penetration (sum of p = W / k for both); on a wall
    // and on a base (node to segment). Centred: a uniform penetration, the same for both.
    //
    // On the base the statics hold less exactly: its top edge bends under the quad (the springs'
    // normals tilt by about 1e-5, and the penetration is measured against the interpolated edge),
    // and the frictionless quad drifts sideways at a steady terminal speed under the mass damping
    // (kinetic/strain energy 1.2e-9, constant): tolerances 1e-3 and 1e-8 there.
    for (what, scene, tol, rest) in [
        ("wall", quad_on_wall as fn(&str, f64) -> String, 1e-4, 1e-12),
        ("base", quad_on_base, 1e-3, 1e-8),
    ] {
        let (pp, r, kp) = settle(&scene("penalty", 0.6), "penalty");
        let (pl, _, kl) = settle(&scene("perturbed_lagrange", 0.6), "perturbed_lagrange");
        let rt = (r[0] - r[1]) / (r[0] + r[1]);
        eprintln!(
            "quad on a {what}, off-centre weight: reactions {r:?} N; penalty p = {pp:?} m, tilt \
             {:.6} (statics {rt:.6}); perturbed Lagrange p = {pl:?} m, tilt {:.6} (3 x statics \
             {:.6}); kinetic/strain {kp:.1e} / {kl:.1e}",
            tilt(pp),
            tilt(pl),
            3.0 * rt
        );
        assert!(kp < rest && kl < rest, "{what}: not settled: {kp:e} {kl:e}");
        assert!(rt > 0.1, "the weight sits off-centre: {rt}");
        // Node by node: each node's spring carries its own reaction.
        assert!(
            (tilt(pp) / rt - 1.0).abs() < tol,
            "{what}: penalty tilt {}",
            tilt(pp)
        );
        // Consistent: three times the tilt (up to the sides' sliver of contact at the corners,
        // O(p / h) = 1e-5 here).
        assert!(
            (tilt(pl) / (3.0 * rt) - 1.0).abs() < tol,
            "{what}: tilt {}",
            tilt(pl)
        );
        let (sp, sl) = (pp[0] + pp[1], pl[0] + pl[1]);
        assert!(
            (sl / sp - 1.0).abs() < tol,
            "{what}: mean penetration {sl} against {sp}"
        );
        let (pp, _, _) = settle(&scene("penalty", 1.0), "penalty");
        let (pl, _, _) = settle(&scene("perturbed_lagrange", 1.0), "perturbed_lagrange");
        eprintln!(
            "quad on a {what}, centred weight: penalty p = {pp:?} m, perturbed Lagrange {pl:?} m"
        );
        for i in 0..2 {
            assert!(
                (pl[i] / pp[i] - 1.0).abs() < tol,
                "{what}: {pl:?} against {pp:?}"
            );
        }
    }
}

#[test]
fn check_names_each_contact_method() {
    let dir = tmp_dir("perturbed_check");
    let path = dir.join("quad.toml");
    std::fs::write(&path, quad_on_base("perturbed_lagrange", 0.6)).expect("write");
    let out = run_bin(&["check", path.to_str().expect("utf-8 path")]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}");
    // The base's contact (no wall): one table, perturbed Lagrange.
    assert!(text.contains("  methods  perturbed_lagrange 1"), "{text}");
    let wall = quad_on_wall("penalty", 0.6).replace(
        "[[rigid_wall]]",
        "[[body]]\nname = \"other\"\nmaterial = \"steel\"\nmesh = { rectangle = { origin = [3.0, 0.0], size = [1.0, 1.0], cells = [1, 1] } }\n\n[[contact]]\nbodies = [\"block\", \"other\"]\n\n[[rigid_wall]]",
    );
    std::fs::write(&path, wall).expect("write");
    let out = run_bin(&["check", path.to_str().expect("utf-8 path")]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("  methods  lagrange 1, penalty 1"), "{text}");
}
