//! The augmented Lagrangian (Belytschko X.5.7) on the CPU reference: its defining property, the
//! multipliers carrying a persistent contact's force so that no penetration of the spring's is
//! left (the quad of `tests/shared/perturbed_scene.rs` at rest on a wall and on a base), and the
//! scene keys it refuses. The patch test is in `patch_contact.rs`.

use crate::common::*;

use crate::perturbed::perturbed_scene::*;

/// What a settled quad gives.
struct Rest {
    /// Penetrations of the base nodes (m).
    p: [f64; 2],
    /// The contact force on the quad along y over its weight.
    force: f64,
    /// Kinetic over strain energy at the end.
    kinetic: f64,
    /// Largest energy-balance error over the run.
    energy_error: f64,
}

fn settle(text: &str, method: &str) -> Rest {
    let (model, run) = Stepper::finish(text, method);
    let last = run.samples.last().expect("samples");
    let weight: f64 = model.mass[..4].iter().map(|m| m * G).sum();
    let mut audit = ricochet::output::history::EnergyAudit::default();
    let energy_error = run
        .samples
        .iter()
        .map(|s| audit.error(s))
        .fold(0.0f64, f64::max);
    Rest {
        p: penetrations(&model.position, run.solver.displacement()),
        force: last.contacts[0].force[1].abs() / weight,
        kinetic: last.kinetic / last.internal,
        energy_error,
    }
}

#[test]
fn augmented_lagrange_leaves_no_penetration_in_a_persistent_contact() {
    // The off-centre quad at rest under gravity: the penalty's springs carry the weight at a
    // penetration W / k; the augmented Lagrangian's multipliers take it over (Uzawa's update at
    // half the mass damping, 1.5e3 /s over the 50 ms), so the penetration left is below 1e-2 of
    // the penalty's with the same spring, the force still the weight, the step the spring's.
    for (what, scene) in [
        ("wall", quad_on_wall as fn(&str, f64) -> String),
        ("base", quad_on_base),
    ] {
        let pen = settle(&scene("penalty", 0.6), "penalty");
        let al = settle(&scene("augmented_lagrange", 0.6), "augmented_lagrange");
        eprintln!(
            "quad on a {what}: penalty p = {:?} m, force {:.8} W; augmented Lagrange p = {:?} m, \
             force {:.8} W, kinetic/strain {:.1e}, energy error {:.1e}",
            pen.p, pen.force, al.p, al.force, al.kinetic, al.energy_error
        );
        for i in 0..2 {
            assert!(pen.p[i] > 0.0, "{what}: penalty p = {:?}", pen.p);
            assert!(
                al.p[i].abs() < 1e-2 * pen.p[i],
                "{what}: penetration {:?} m against the penalty's {:?} m",
                al.p,
                pen.p
            );
        }
        assert!(
            (al.force - 1.0).abs() < 1e-6,
            "{what}: force {} W",
            al.force
        );
        assert!(al.kinetic < 1e-8, "{what}: not settled: {:e}", al.kinetic);
        assert!(
            al.energy_error < 1e-5,
            "{what}: energy error {:e}",
            al.energy_error
        );
    }
}
