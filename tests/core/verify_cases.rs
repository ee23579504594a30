//! The verification cases as data (`assets/verification/`): every file parses and expands at every
//! level; a bad case file is refused naming the file and key; a missed bound makes `verify` exit 4
//! and name the case, method, backend and metric.

use std::path::Path;

use ricochet::verify::{read_cases, Case};

use crate::common::*;

#[test]
fn every_case_file_parses_and_expands_into_a_valid_scene_at_every_level() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/verification");
    let cases = read_cases(&dir).expect("case files");
    assert!(cases.len() >= 6);
    for c in &cases {
        assert_eq!(
            c.file.file_stem().and_then(|s| s.to_str()),
            Some(c.case.name.as_str()),
            "file name = case name"
        );
        for level in c.levels.quick.iter().chain(&c.levels.full) {
            for method in &c.case.methods {
                let text = c.expand(level, method).expect("expands");
                let scene = ricochet::scene::Scene::parse(&text, &c.file)
                    .unwrap_or_else(|e| panic!("{}: {e}", c.case.name));
                ricochet::model::Model::build(&scene)
                    .unwrap_or_else(|e| panic!("{}: {e}", c.case.name));
            }
        }
    }
}

/// A one-level rods case on the CPU, with `metric` appended.
fn tiny_case(metric: &str) -> String {
    let rods = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/verification/rods.toml"),
    )
    .expect("rods case");
    let start = rods.find("[[metric]]").expect("metrics");
    let end = rods.find("# Penalty at omega").expect("method keys");
    rods[..start]
        .replace(
            "methods = [\"lagrange\", \"penalty\"]",
            "methods = [\"lagrange\"]",
        )
        .replace("plot = \"target_velocity\"", "")
        .replace(
            "quick = [{ n = 20 }, { n = 40 }, { n = 80 }]",
            "quick = [{ n = 20 }]",
        )
        + metric
        + "\n"
        + &rods[end..]
}

/// `ricochet verify --quick --backend cpu` on the case files of `cases`.
fn quick_cpu_verify(cases: &Path, out: &Path) -> std::process::Output {
    run_bin(&[
        "verify",
        "--quick",
        "--backend",
        "cpu",
        "--cases",
        cases.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ])
}

#[test]
fn a_bad_case_file_is_refused_naming_the_file_and_key() {
    let dir = tmp_dir("verify-bad");
    let cases = dir.join("cases");
    std::fs::create_dir_all(&cases).unwrap();
    let bad = tiny_case(
        "[[metric]]\nname = \"v\"\nkind = \"body_velocity\"\nbody = \"target\"\nreference = 10.0\nbound = \"0.1 / m\"\n",
    );
    let file = cases.join("bad.toml");
    std::fs::write(&file, bad).unwrap();
    let err = Case::read(&file).expect_err("unknown variable in a bound");
    let msg = err.to_string();
    assert!(
        msg.contains("bad.toml")
            && msg.contains("metric[0].bound")
            && msg.contains("unknown variable `m`"),
        "{msg}"
    );
    let o = quick_cpu_verify(&cases, &dir.join("out"));
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("metric[0].bound"), "{stderr}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_missed_bound_makes_verify_exit_4_and_name_the_case() {
    let dir = tmp_dir("verify-miss");
    let cases = dir.join("cases");
    std::fs::create_dir_all(&cases).unwrap();
    // The target leaves at 9.859 m/s at n = 20 (REFERENCES.md: 1.4 % dispersive tail): 1e-6 misses.
    let case = tiny_case(
        "[[metric]]\nname = \"target_velocity\"\nkind = \"body_velocity\"\nbody = \"target\"\nreference = 10.0\nbound = 1.0e-6\n",
    );
    std::fs::write(cases.join("rods.toml"), case).unwrap();
    let out = dir.join("out");
    let o = quick_cpu_verify(&cases, &out);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert_eq!(o.status.code(), Some(4), "{stdout}");
    assert!(
        stdout.contains("FAILED rods / lagrange / cpu / level 0 (n = 20): target_velocity = 9.859"),
        "{stdout}"
    );
    let report = std::fs::read_to_string(out.join("report.md")).expect("report");
    assert!(report.contains("1 bound(s) missed"), "{report}");
    assert!(out.join("rods.svg").exists() && out.join("rods.png").exists());
    let _ = std::fs::remove_dir_all(&dir);
}
