//! Coulomb friction with Lagrange and penalty contact on the CPU reference (the verification cases of
//! `assets/verification/` cover the floor: sliding to rest, the incline, rolling): a block
//! sliding on a second, clamped block through node-to-segment contact decelerates at mu g as on
//! a rigid floor, its friction work is the kinetic energy it loses, and the history has the
//! `friction_work` and `<name>.ft` columns.

use ricochet::run::{run, schedule};
use ricochet::step::cpu::CpuSolver;

use crate::common::*;

#[path = "../shared/friction_scenes.rs"]
mod scenes;
use scenes::*;

/// A history row: time, block velocity, friction work, ft and fy of the first contact.
type Row = (f64, f64, f64, f64, f64);

/// The rows of a CPU run of `text`, its energy balance and the block's mass.
fn rows(text: &str, name: &str) -> (Vec<Row>, f64, f64) {
    let (sc, model, plan) = build(text);
    let dir = tmp_dir(name);
    let mut solver = CpuSolver::new(model.clone(), plan.clone(), schedule(&sc));
    let r = run(&sc, &model, &plan, &mut solver, &dir, None).expect("run");
    let header = std::fs::read_to_string(dir.join("history.csv")).expect("history");
    let header = header.lines().next().unwrap_or_default().to_string();
    let _ = std::fs::remove_dir_all(&dir);
    assert_eq!(r.summary.status, "completed", "{}", r.summary.message);
    assert!(
        header.contains(",contact_energy,friction_work,"),
        "{header}"
    );
    assert!(header.contains(".ft"), "{header}");
    let out = r
        .samples
        .iter()
        .map(|(s, _)| {
            (
                s.time,
                s.body_velocity[0][0],
                s.friction,
                s.contacts[0].ft,
                s.contacts[0].force[1],
            )
        })
        .collect();
    (out, r.summary.max_energy_error, model.bodies[0].mass)
}

#[test]
fn a_block_sliding_on_a_clamped_block_decelerates_at_mu_g() {
    for (name, text) in sliding_cases(2.0e-3) {
        let (rows, balance, mass) = rows(&text, &format!("friction-{name}"));
        // Least-squares deceleration over the run.
        let points: Vec<(f64, f64)> = rows.iter().map(|r| (r.0, r.1)).collect();
        let a = ricochet::verify::metric::line_fit(&points).expect("rows").0;
        // The friction work is the kinetic energy the block lost (the base barely moves).
        let last = rows.last().expect("rows");
        let lost = 0.5 * mass * (1.0 - last.1 * last.1);
        // The friction force is mu times the normal force, against the motion, over the rows in
        // contact (averaged over the run: the normal force rings under the sudden weight).
        let (ft, fy): (f64, f64) = rows[1..]
            .iter()
            .fold((0.0, 0.0), |(a, b), r| (a + r.3.abs(), b + r.4.abs()));
        eprintln!(
            "{name}: deceleration {a:.2} m/s^2 (mu g {:.2}), friction work {:.5} J/m against the \
             lost kinetic energy {lost:.5}, ft / fy {:.4}, balance {balance:.1e}",
            MU * G,
            last.2,
            ft / fy
        );
        assert!(
            (-a / (MU * G) - 1.0).abs() < 0.01,
            "{name}: deceleration {a}"
        );
        assert!(
            (last.2 / lost - 1.0).abs() < 0.02,
            "{name}: friction work {}",
            last.2
        );
        assert!(
            (ft / fy / MU - 1.0).abs() < 0.01,
            "{name}: ft / fy {}",
            ft / fy
        );
        assert!(balance < 1e-6, "{name}: energy balance {balance:e}");
    }
}

/// `friction_stiffness` scales the tangential spring of penalty friction, which counts in the
/// stable step when it is the stiffer: k_t = 4 k halves the springs' step 2 / omega; a softer
/// one leaves it to the normal spring.
#[test]
fn friction_stiffness_sets_the_tangential_spring_and_its_stable_step() {
    let step = |extra: &str| {
        let text = block_on_floor(1.0e-3, "penalty") + extra;
        let (_, model, _) = build(&text);
        ricochet::contact::ContactSet::new(&model)
            .expect("a wall")
            .penalty_step()
            .expect("penalty springs")
            .0
    };
    let (one, stiff, soft) = (
        step(""),
        step("friction_stiffness = 4.0\n"),
        step("friction_stiffness = 0.25\n"),
    );
    eprintln!("penalty step: k_t = k {one:.4e}, 4 k {stiff:.4e}, k / 4 {soft:.4e}");
    assert!((stiff / one - 0.5).abs() < 1e-12);
    assert_eq!(soft, one);
    // Frictionless, the tangential spring does not exist and does not count.
    let (_, model, _) = build(&block_on_floor(1.0e-3, "penalty").replace("friction = 0.3", ""));
    let frictionless = ricochet::contact::ContactSet::new(&model)
        .and_then(|c| c.penalty_step().map(|p| p.0))
        .expect("penalty springs");
    assert_eq!(frictionless, one);
}

#[test]
fn check_prints_the_friction_and_the_gravity() {
    let dir = tmp_dir("friction-check");
    let file = dir.join("block.toml");
    std::fs::write(
        &file,
        block_on_block(1.0e-3, "lagrange")
            .replace("gravity = [", "gravity_ramp = 1.0e-4\ngravity = ["),
    )
    .expect("write");
    let o = run_bin(&["check", file.to_str().unwrap()]);
    let out = String::from_utf8_lossy(&o.stdout);
    let _ = std::fs::remove_dir_all(&dir);
    assert_eq!(o.status.code(), Some(0), "{out}");
    assert!(
        out.contains("friction Coulomb: sliding mu = 0.3 (lagrange)"),
        "{out}"
    );
    assert!(
        out.contains("gravity    [0e0, -9.81e2] m/s^2 on every node, ramped in over 1e-4 s"),
        "{out}"
    );
    assert!(out.contains("-> gravity ->"), "{out}");
    // Penalty friction: the tangential spring's stiffness.
    let dir = tmp_dir("friction-check-penalty");
    let file = dir.join("floor.toml");
    let text = block_on_floor(1.0e-3, "penalty") + "friction_stiffness = 0.25\n";
    std::fs::write(&file, text).expect("write");
    let o = run_bin(&["check", file.to_str().unwrap()]);
    let out = String::from_utf8_lossy(&o.stdout);
    let _ = std::fs::remove_dir_all(&dir);
    assert!(
        out.contains("friction Coulomb: floor mu = 0.3 (penalty, regularized, k_t = 0.25 k)"),
        "{out}"
    );
}
