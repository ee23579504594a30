//! J2 plasticity (CPU reference): the plastic patch test of REFERENCES.md section 10 (a block in
//! uniaxial plane strain compressed past yield by prescribed velocities: elastic, first yield at
//! sigma_y / (2 mu), then the hardening slope 2 mu H / (3 mu + H), the pressure K |eps|), its
//! energy audit with the `plastic_work` column, the objectivity of the yielded state under rigid
//! rotations, and the VTU fields.

use ricochet::element::plastic::{von_mises, PlasticState};
use ricochet::model::Model;
use ricochet::output::fields::{element_fields_state, ElementFields};
use ricochet::step::cpu::CpuSolver;
use ricochet::step::{Event, Snapshot, Solver};

use crate::common::*;

#[path = "../shared/plastic_scene.rs"]
mod plastic_scene;
use plastic_scene::*;

/// Runs the block on the CPU and returns its model and snapshots.
fn run_block() -> (Model, Vec<Snapshot>) {
    run_text(&scene("ascii"))
}

fn run_text(text: &str) -> (Model, Vec<Snapshot>) {
    let (scene, model, plan) = build(text);
    let mut solver = CpuSolver::new(model.clone(), plan, ricochet::run::schedule(&scene));
    let mut snaps = Vec::new();
    let mut done = false;
    while !done {
        let mut events = Vec::new();
        solver.advance(&mut events).unwrap();
        for e in events {
            match e {
                Event::Snapshot(s) => snaps.push(s),
                Event::Done => done = true,
                Event::Failed(f) => panic!("run failed: {f:?}"),
                Event::Sample(_) => {}
            }
        }
    }
    (model, snaps)
}

fn fields(model: &Model, s: &Snapshot, e: usize) -> ElementFields {
    element_fields_state(model, &s.displacement, e, &s.plastic[e])
}

#[test]
fn uniaxial_strain_follows_the_j2_closed_form_past_yield() {
    let (model, snaps) = run_block();
    assert!(snaps.len() >= 40, "{} snapshots", snaps.len());
    let top = model
        .position
        .iter()
        .position(|p| (p[1] - SIDE).abs() < 1e-12)
        .unwrap();
    let (mut worst_vm, mut worst_p, mut yielded) = (0.0f64, 0.0f64, 0);
    let k = bulk_modulus();
    for s in &snaps {
        // The engineering strain of the block: u_y of the top over its height, the bottom
        // moving by the opposite amount.
        let x = -2.0 * s.displacement[top][1] / SIDE;
        let closed = von_mises_closed(x);
        for e in 0..model.element_count() {
            let f = fields(&model, s, e);
            worst_vm = worst_vm.max((f.von_mises - closed).abs() / YIELD);
            // The pressure follows K |eps| up to the finite-strain terms (1.5 |eps| relative).
            let p = k * x;
            if x > 0.0 {
                worst_p = worst_p.max((f.pressure - p).abs() / (p * x));
            }
            // The state is uniform: every element as the first, to round-off.
            let f0 = fields(&model, s, 0);
            assert!((f.von_mises - f0.von_mises).abs() < 1e-6 * YIELD);
            assert!((f.plastic_strain - f0.plastic_strain).abs() < 1e-12);
        }
        if s.plastic[0].alpha > 0.0 {
            yielded += 1;
        }
    }
    let last = snaps.last().unwrap();
    let x = -2.0 * last.displacement[top][1] / SIDE;
    // The prescribed motion, to round-off; the run ends within a step of END.
    assert!((x - RATE * last.time).abs() < 1e-9, "final strain {x}");
    assert!(
        last.time >= END && last.time < 1.01 * END,
        "final time {}",
        last.time
    );
    // Past yield (at |eps| = 3.8e-4 of 1e-2) most of the path is plastic.
    assert!(
        yielded > snaps.len() / 2,
        "{yielded} of {} yielded",
        snaps.len()
    );
    // The plastic strain of the closed form: d eps_p = 2 mu d|eps| / (3 mu + H).
    let mu = E / (2.0 * (1.0 + NU));
    let alpha = 2.0 * mu * (x - YIELD / (2.0 * mu)) / (3.0 * mu + HARDENING);
    let got = last.plastic[0].alpha;
    assert!(
        (got - alpha).abs() < 2e-2 * alpha,
        "eps_p {got} against {alpha}"
    );
    eprintln!(
        "plastic patch test: largest |sigma_vm - closed form| = {worst_vm:.2e} sigma_y; pressure \
         within {worst_p:.2} |eps| of K |eps|; eps_p {got:.5e} against {alpha:.5e}"
    );
    assert!(worst_vm < 1e-3, "von Mises off by {worst_vm:e} sigma_y");
    assert!(worst_p < 2.0, "pressure off by {worst_p} |eps| relative");
}

#[test]
fn the_energy_audit_closes_with_the_plastic_work() {
    let dir = tmp_dir("plastic-audit");
    let file = dir.join("block.toml");
    std::fs::write(&file, scene("ascii")).unwrap();
    let out = dir.join("out");
    let o = run_cpu(&file, &out, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (header, rows) = read_csv(&out.join("history.csv"));
    assert_eq!(header[6], "viscous_work");
    assert_eq!(header[7], "plastic_work");
    let (w, ext, int, err) = (
        column(&header, "plastic_work"),
        column(&header, "external_work"),
        column(&header, "internal_energy"),
        column(&header, "energy_error"),
    );
    let last = rows.last().unwrap();
    // Most of the work done on the block is dissipated: per unit volume the closed form gives
    // about sigma_vm eps_p against the stored sigma_vm^2 / (6 mu) + K eps^2 / 2.
    assert!(last[w] > 0.0 && last[w] < last[ext]);
    assert!(last[int] > 0.0);
    let worst = rows.iter().map(|r| r[err]).fold(0.0, f64::max);
    eprintln!(
        "plastic audit: external {:.4e} J, internal {:.4e} J, plastic {:.4e} J, largest \
         balance error {worst:.2e}",
        last[ext], last[int], last[w]
    );
    // Second order in the step (the trapezoidal pairing of the reactions' work).
    assert!(worst < 1e-5, "energy balance error {worst:e}");
    // The fields of a plastic body carry the plastic strain and the pressure.
    let vtu = std::fs::read_dir(out.join("fields"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| p.extension().is_some_and(|x| x == "vtu"))
        .unwrap();
    let text = std::fs::read_to_string(vtu).unwrap();
    assert!(text.contains("Name=\"plastic_strain\""));
    assert!(text.contains("Name=\"pressure\""));
}

/// Rotates `u` (about the origin, by `angle`) as a rigid motion of the deformed body:
/// x' = R x, so u' = R (X + u) - X.
fn rotated(model: &Model, u: &[[f64; 2]], angle: f64) -> Vec<[f64; 2]> {
    let (s, c) = angle.sin_cos();
    model
        .position
        .iter()
        .zip(u)
        .map(|(p, d)| {
            let x = [p[0] + d[0], p[1] + d[1]];
            [c * x[0] - s * x[1] - p[0], s * x[0] + c * x[1] - p[1]]
        })
        .collect()
}

#[test]
fn a_rigid_rotation_of_the_yielded_block_leaves_its_stress_and_plastic_strain_unchanged() {
    let (model, snaps) = run_block();
    let last = snaps.last().unwrap();
    assert!(last.plastic[0].alpha > 0.0);
    for angle in [0.25, std::f64::consts::FRAC_PI_2, 2.0, -1.0] {
        let u = rotated(&model, &last.displacement, angle);
        let (s, c) = f64::sin_cos(angle);
        for e in 0..model.element_count() {
            let before = fields(&model, last, e);
            // One more evaluation from the rotated geometry with the state reached: the state
            // must come out unchanged and the stress rotated with the body.
            let st: &PlasticState = &last.plastic[e];
            let after = element_fields_state(&model, &u, e, st);
            assert!((after.plastic_strain - before.plastic_strain).abs() < 1e-12);
            assert!((after.von_mises - before.von_mises).abs() < 1e-7 * YIELD);
            assert!((after.pressure - before.pressure).abs() < 1e-7 * YIELD);
            let [xx, yy, xy, zz] = before.stress;
            let r = [
                c * c * xx - 2.0 * c * s * xy + s * s * yy,
                s * s * xx + 2.0 * c * s * xy + c * c * yy,
                c * s * (xx - yy) + (c * c - s * s) * xy,
                zz,
            ];
            for (i, (got, want)) in after.stress.iter().zip(r).enumerate() {
                assert!(
                    (got - want).abs() < 1e-7 * YIELD,
                    "angle {angle}, element {e}, component {i}: {got} against {want}"
                );
            }
            assert!((von_mises(&after.stress) - after.von_mises).abs() < 1e-7 * YIELD);
        }
    }
}

#[test]
fn a_plastic_bar_on_a_wall_dissipates_its_impact_in_plastic_work() {
    let dir = tmp_dir("plastic-bar");
    let out = dir.join("out");
    let asset = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/plastic_bar_wall.toml");
    let o = run_bin(&["run", asset, "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (header, rows) = read_csv(&out.join("history.csv"));
    let (ke, w, err) = (
        column(&header, "kinetic_energy"),
        column(&header, "plastic_work"),
        column(&header, "energy_error"),
    );
    let (first, last) = (&rows[0], rows.last().unwrap());
    let worst = rows.iter().map(|r| r[err]).fold(0.0, f64::max);
    eprintln!(
        "plastic bar: KE0 {:.4e} J, final KE {:.3e} J, plastic work {:.4e} J, energy error {worst:.2e}",
        first[ke], last[ke], last[w]
    );
    assert!(worst < 1e-3, "energy balance error {worst:e}");
    // The bar comes to rest on the wall: nearly all its energy flowed plastically.
    assert!(last[w] > 0.9 * first[ke]);
    assert!(last[ke] < 0.02 * first[ke]);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_johnson_cook_rate_term_raises_the_flow_stress_as_its_closed_form() {
    let c = 0.1;
    let (model, snaps) = run_text(&rate_scene("ascii", c));
    let last = snaps.last().unwrap();
    let top = model
        .position
        .iter()
        .position(|p| (p[1] - SIDE).abs() < 1e-12)
        .unwrap();
    let x = -2.0 * last.displacement[top][1] / SIDE;
    let want = rate_flow(x, c);
    let got = fields(&model, last, 0).von_mises;
    eprintln!(
        "Johnson-Cook rate term: sigma_vm {got:.6e} Pa against A (1 + C ln(2/3 rate)) = {want:.6e} \
         ({:.2e} of A; 1 + C ln(...) = {:.4})",
        (got - want).abs() / YIELD,
        want / YIELD
    );
    assert!((got - want).abs() < 1e-3 * YIELD);
    assert!(want > 1.4 * YIELD);
}
