//! A scene pays only for what it uses: the exact stage list of the plan of scenes that differ by
//! one feature each, `ricochet check` printing it, no contact state (nor broad phase) on the CPU
//! without contact, and `ricochet bench` reporting its ratios (full step over the bare loop, the
//! share of a contact pair) at a tiny size.

use ricochet::plan::Stage;
use ricochet::step::cpu::CpuSolver;
use ricochet::step::Solver;

use crate::common::{build, every_step, run_bin, tmp_dir};

#[path = "../shared/plan_scenes.rs"]
mod scenes;
use scenes::{cases, plan_line};

#[test]
fn every_plan_has_exactly_the_stages_its_scene_uses() {
    for (name, text, expected) in cases() {
        let (_, model, plan) = build(&text);
        assert_eq!(plan.stages, expected, "{name}: plan {plan}");
        // The counts agree with the stages.
        assert_eq!(
            plan.contacts + plan.walls > 0,
            plan.has(Stage::Contact),
            "{name}"
        );
        assert_eq!(
            plan.constrained_nodes > 0,
            plan.has(Stage::VelocityBoundaries),
            "{name}"
        );
        assert_eq!(plan.pressure_nodes > 0, plan.has(Stage::Pressure), "{name}");
        assert_eq!(
            plan.viscous_hourglass_elements > 0,
            plan.has(Stage::HourglassViscous),
            "{name}"
        );
        assert_eq!(
            plan.stiffness_hourglass_elements > 0,
            plan.has(Stage::HourglassStiffness),
            "{name}"
        );
        assert_eq!(
            (plan.nodes, plan.elements),
            (model.node_count(), model.element_count())
        );
    }
}

#[test]
fn check_prints_the_plan_of_every_scene() {
    let dir = tmp_dir("plan_check");
    for (name, text, expected) in cases() {
        let path = dir.join(format!("{name}.toml"));
        std::fs::write(&path, &text).expect("write scene");
        let out = run_bin(&["check", path.to_str().expect("utf-8 path")]);
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(
            out.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let line = plan_line(&expected);
        assert!(
            stdout.lines().any(|l| l == line),
            "{name}: expected the line {line:?} in\n{stdout}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn cpu_solver_has_contact_state_and_searches_only_with_contact() {
    for (name, text, _) in cases() {
        let (_, model, plan) = build(&text);
        let contact = plan.has(Stage::Contact);
        let mut solver = CpuSolver::new(model, plan, every_step(1e-5, None, 0.9, 1e-6));
        // The contact set holds the broad phase (the BVH of the master segments): none at all
        // without contact.
        assert_eq!(solver.contact().is_some(), contact, "{name}");
        solver.run_steps(3);
        assert_eq!(solver.steps(), 3, "{name}");
        assert_eq!(solver.counters().contact_searches > 0, contact, "{name}");
    }
}

#[test]
fn bench_reports_the_full_over_bare_ratio_and_the_contact_share_at_a_tiny_size() {
    // Reported, finite and of the right sign: how large they are is for BENCHMARKS.md, not a test.
    let dir = tmp_dir("plan_bench");
    let json = dir.join("bench.json");
    let out = run_bin(&[
        "bench",
        "--backend",
        "cpu",
        "--cells",
        "6",
        "--steps",
        "30",
        "--rounds",
        "3",
        "--json",
        json.to_str().expect("utf-8 path"),
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        stdout.contains("full/bare") && stdout.contains("contact"),
        "{stdout}"
    );
    assert!(
        stdout.contains("full step / bare element+update loop = ")
            && stdout.contains("a contact pair"),
        "{stdout}"
    );
    let rows: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).expect("bench json"))
            .expect("valid JSON");
    let rows = rows.as_array().expect("an array of rows");
    assert_eq!(rows.len(), 1);
    let r = &rows[0];
    let num = |key: &str| -> f64 {
        r[key]
            .as_f64()
            .unwrap_or_else(|| panic!("{key} is not a number: {r}"))
    };
    assert_eq!(r["backend"], "cpu");
    assert_eq!(
        (num("elements"), num("steps"), num("rounds")),
        (36.0, 30.0, 3.0)
    );
    assert_eq!(num("contact_elements"), 36.0 + 6.0);
    for key in ["wall_seconds", "bare_seconds", "full_over_bare"] {
        let x = num(key);
        assert!(x.is_finite() && x > 0.0, "{key} = {x}");
    }
    let share = num("contact_share");
    assert!(share.is_finite() && share < 1.0, "contact_share = {share}");
    assert!(num("contact_seconds_per_step").is_finite());
    assert!(num("contact_searches") >= 1.0);
    let _ = std::fs::remove_dir_all(&dir);
}
