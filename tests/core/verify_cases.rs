//! The verification cases as data (`assets/verification/`): every file parses and expands at every
//! level; a bad case file is refused naming the file and key; a missed bound makes `verify` exit 4
//! and name the case, method, backend and metric.

use std::path::Path;

use ricochet::verify::{read_cases, Case};

use crate::common::*;

#[test]
fn the_built_in_cases_are_the_case_files_and_verify_runs_from_any_folder() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/verification");
    let files = read_cases(&dir).expect("case files");
    let built_in = ricochet::verify::embedded_cases().expect("built-in cases");
    let names = |c: &[Case]| -> Vec<String> { c.iter().map(|c| c.case.name.clone()).collect() };
    assert_eq!(
        names(&built_in),
        names(&files),
        "EMBEDDED lists every case file"
    );
    for (name, text) in ricochet::verify::EMBEDDED {
        assert_eq!(
            std::fs::read_to_string(dir.join(name)).expect("case file"),
            text,
            "{name}"
        );
    }
    // From a folder without assets/: the built-in cases.
    let cwd = tmp_dir("verify-anywhere");
    let o = std::process::Command::new(bin())
        .current_dir(&cwd)
        .args(["verify", "--quick", "--backend", "cpu", "--case", "rods"])
        .output()
        .expect("run verify");
    let out = String::from_utf8_lossy(&o.stdout);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{out}\n{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(out.contains("all cases pass their bounds"), "{out}");
    assert!(cwd.join("out/verification/report.md").exists());
    let _ = std::fs::remove_dir_all(&cwd);
}

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
                ricochet::run::model(&scene).unwrap_or_else(|e| panic!("{}: {e}", c.case.name));
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

/// A reference and a scale given as expressions over the case's variables, the residual velocity
/// of a projectile (the striker keeps 1.4 % of its speed: the wave solution's dispersive tail),
/// and a case with no quick ladder, which `verify --quick` leaves out, says so and lists in the
/// report.
#[test]
fn expression_references_residual_velocity_and_full_only_cases() {
    let dir = tmp_dir("verify-expr");
    let cases = dir.join("cases");
    std::fs::create_dir_all(&cases).unwrap();
    // The target leaves at 9.859 m/s at n = 20 (1.4 % below v0), the striker at 0.141 m/s.
    let case = tiny_case(concat!(
        "[[metric]]\nname = \"target_velocity\"\nkind = \"body_velocity\"\nbody = \"target\"\n",
        "reference = \"v0 * (1 - 0.28 / n)\"\nscale = \"v0 / 10\"\nbound = 0.01\n\n",
        "[[metric]]\nname = \"striker_residual\"\nkind = \"residual_velocity\"\nbody = \"striker\"\n",
        "reference = \"0.014 * v0\"\nscale = \"v0\"\nbound = 1.0e-3\n",
    ));
    std::fs::write(cases.join("rods.toml"), &case).unwrap();
    let full_only = case
        .replace("name = \"rods\"", "name = \"rods_full\"")
        .replace("quick = [{ n = 20 }]", "quick = []");
    assert!(full_only.contains("quick = []"));
    std::fs::write(cases.join("rods_full.toml"), full_only).unwrap();
    let out = dir.join("out");
    let o = quick_cpu_verify(&cases, &out);
    let stdout = String::from_utf8_lossy(&o.stdout);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{stdout}\n{stderr}");
    assert!(
        format!("{stdout}{stderr}").contains("rods_full: not run (no quick ladder"),
        "{stdout}\n{stderr}"
    );
    let csv = std::fs::read_to_string(out.join("results.csv")).expect("results.csv");
    let row = |metric: &str| -> Vec<String> {
        csv.lines()
            .find(|l| l.starts_with("rods,") && l.contains(&format!(",{metric},")))
            .unwrap_or_else(|| panic!("{metric} in {csv}"))
            .split(',')
            .map(str::to_string)
            .collect()
    };
    // The evaluated reference is in the CSV: 10 (1 - 0.014) = 9.86 m/s.
    let target = row("target_velocity");
    let reference: f64 = target[8].parse().unwrap();
    assert!((reference - 9.86).abs() < 1e-12, "{target:?}");
    let value: f64 = target[9].parse().unwrap();
    assert!((value - 9.859).abs() < 1e-3, "{target:?}");
    let striker = row("striker_residual");
    let residual: f64 = striker[9].parse().unwrap();
    assert!((residual - 0.1406).abs() < 1e-3, "{striker:?}");
    assert_eq!(striker[15], "true", "{striker:?}");
    assert!(!csv.lines().any(|l| l.starts_with("rods_full,")), "{csv}");
    let report = std::fs::read_to_string(out.join("report.md")).expect("report");
    assert!(report.contains("- `rods_full`: "), "{report}");
    assert!(report.contains("`v0 * (1 - 0.28 / n)`"), "{report}");
    // An expression over an unknown variable is refused when the file is read, naming the key.
    let unknown = tiny_case(concat!(
        "[[metric]]\nname = \"v\"\nkind = \"body_velocity\"\nbody = \"target\"\n",
        "reference = \"v0 * m\"\nbound = 0.1\n",
    ));
    let file = dir.join("unknown.toml");
    std::fs::write(&file, unknown).unwrap();
    let msg = Case::read(&file).expect_err("unknown variable").to_string();
    assert!(
        msg.contains("unknown.toml")
            && msg.contains("metric[0].reference")
            && msg.contains("unknown variable `m`"),
        "{msg}"
    );
    // A scale that is not > 0 for a run's variables is that run's error, not a pass.
    let bad = tiny_case(concat!(
        "[[metric]]\nname = \"v\"\nkind = \"body_velocity\"\nbody = \"target\"\n",
        "reference = 10.0\nscale = \"v0 - 10\"\nbound = 0.1\n",
    ));
    std::fs::remove_file(cases.join("rods_full.toml")).unwrap();
    std::fs::write(cases.join("rods.toml"), bad).unwrap();
    let o = quick_cpu_verify(&cases, &dir.join("out-bad"));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert_eq!(o.status.code(), Some(4), "{stdout}");
    let report = std::fs::read_to_string(dir.join("out-bad/report.md")).expect("report");
    assert!(report.contains("scale 0 is not > 0"), "{report}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A plane-strain block [-0.5, 0.5] x [0, 0.5] pressed by p = 1e-3 E onto a frictionless rigid
/// wall (ramped, mass damping: dynamic relaxation). Exact: uniaxial stress sigma_yy = -p, so
/// every node on the wall carries the (nominal) contact pressure p, and the loaded zone is the
/// whole bottom, of reference width 1.
const BLOCK_ON_WALL: &str = concat!(
    r#"
[case]
name = "block"
title = "Block pressed on a rigid wall"
reference = "uniaxial stress"
methods = ["lagrange"]
size = "n"
cost_exponent = 3.0

[vars]
p = 2.1e8

[levels]
quick = [{ n = 8 }]
full = [{ n = 8 }]

[[metric]]
name = "peak_pressure"
kind = "peak_pressure"
body = "block"
contact = "wall"
reference = 2.1e8

[[metric]]
name = "half_width"
kind = "contact_half_width"
body = "block"
contact = "wall"
reference = 0.5

[[metric]]
name = "contact_force"
kind = "final_force"
contact = "wall"
component = "y"
reference = 2.1e8

[[metric]]
name = "kinetic_ratio"
kind = "kinetic_ratio"
reference = 0.0
scale = 1.0

[template]
scene = '''
[run]
end_time = 1.0e-2
history_interval = 1.0e-3
mass_damping = 1.2e4

"#,
    steel!(),
    r#"

[[body]]
name = "block"
material = "steel"
formulation = "plane_strain"
hourglass = { form = "stiffness", coefficient = 0.1 }
mesh = { rectangle = { origin = [-0.5, 0.0], size = [1.0, 0.5], cells = [${n}, ${n / 2}] } }

[[rigid_wall]]
name = "wall"
point = [0.0, 0.0]
normal = [0.0, 1.0]
method = "lagrange"

[[pressure]]
body = "block"
region = { min = [-0.51, 0.49], max = [0.51, 0.51] }
value = ${p}
ramp = 2.0e-3

[[boundary]]
body = "block"
region = { min = [-0.01, -0.01], max = [0.01, 0.51] }
velocity = { x = 0.0 }
'''
"#
);

#[test]
fn contact_pressure_metrics_give_the_uniform_pressure_of_a_block_pressed_on_a_wall() {
    let dir = tmp_dir("verify-pressure");
    let cases = dir.join("cases");
    std::fs::create_dir_all(&cases).unwrap();
    std::fs::write(cases.join("block.toml"), BLOCK_ON_WALL).unwrap();
    let out = dir.join("out");
    let o = quick_cpu_verify(&cases, &out);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert_eq!(o.status.code(), Some(0), "{stdout}");
    let csv = std::fs::read_to_string(out.join("results.csv")).expect("results.csv");
    let value = |metric: &str| -> f64 {
        let line = csv
            .lines()
            .find(|l| l.split(',').nth(7) == Some(metric))
            .unwrap_or_else(|| panic!("{metric} missing: {csv}"));
        line.split(',').nth(9).unwrap().parse().unwrap()
    };
    let p = 2.1e8;
    // Every wall node carries p (corners: half the force over half the tributary length).
    assert!((value("peak_pressure") / p - 1.0).abs() < 1e-6, "{csv}");
    // The whole bottom is loaded.
    assert!((value("half_width") / 0.5 - 1.0).abs() < 1e-12, "{csv}");
    assert!((value("contact_force") / p - 1.0).abs() < 1e-6, "{csv}");
    assert!(value("kinetic_ratio") < 1e-6, "{csv}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_friction_cases_pass_their_bounds_on_the_cpu() {
    // REFERENCES.md section 7 (assets/verification/): the block sliding to rest, the block on a
    // 30-degree incline sliding (mu = 0.3) and sticking (mu = 0.7), the disk sliding into
    // rolling; their quick ladders on the CPU reference, every level judged.
    let out = tmp_dir("verify-friction");
    let o = run_bin(&[
        "verify",
        "--quick",
        "--backend",
        "cpu",
        "--case",
        "sliding_block",
        "incline_slide",
        "incline_stick",
        "rolling_disk",
        "--out",
        out.to_str().unwrap(),
    ]);
    let results = std::fs::read_to_string(out.join("results.csv")).expect("results.csv");
    eprintln!("{results}");
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    for metric in [
        "stop_time",
        "distance",
        "friction_work",
        "acceleration",
        "drift",
        "rolling_speed",
        "energy_balance",
    ] {
        assert!(
            results.contains(&format!(",{metric},")),
            "no {metric} in\n{results}"
        );
    }
    let _ = std::fs::remove_dir_all(&out);
}

/// `verify --jobs 2` makes two CPU runs at a time and gives the same rows in the same order as
/// `--jobs 1` (every column of `results.csv` but the wall times), says so in its report, and
/// `--jobs 0` is refused.
#[test]
fn verify_jobs_give_the_same_rows_in_the_same_order() {
    let run = |jobs: &str| {
        let out = tmp_dir(&format!("verify-jobs-{jobs}"));
        let o = std::process::Command::new(bin())
            .args(["verify", "--quick", "--backend", "cpu", "--jobs", jobs])
            .args(["--case", "rods", "rod_wall", "patch_test", "--out"])
            .arg(&out)
            .output()
            .expect("run verify");
        let text = |b: &[u8]| String::from_utf8_lossy(b).into_owned();
        (o.status.code(), text(&o.stdout), text(&o.stderr), out)
    };
    let mut csv = Vec::new();
    for jobs in ["1", "2"] {
        let (code, stdout, stderr, out) = run(jobs);
        assert_eq!(code, Some(0), "--jobs {jobs}: {stdout}\n{stderr}");
        assert!(stdout.contains("all cases pass their bounds"), "{stdout}");
        let report = std::fs::read_to_string(out.join("report.md")).expect("report.md");
        assert_eq!(
            report.contains("2 at a time (`--jobs 2`)"),
            jobs == "2",
            "--jobs {jobs}: the report says how the runs were made"
        );
        let text = std::fs::read_to_string(out.join("results.csv")).expect("results.csv");
        let header: Vec<&str> = text.lines().next().unwrap_or("").split(',').collect();
        let wall = header
            .iter()
            .position(|h| *h == "wall_seconds")
            .expect("wall_seconds");
        let rows: Vec<String> = text
            .lines()
            .map(|l| {
                let mut f: Vec<&str> = l.split(',').collect();
                f.remove(wall);
                f.join(",")
            })
            .collect();
        assert!(rows.len() > 10, "{text}");
        csv.push(rows);
        let _ = std::fs::remove_dir_all(&out);
    }
    assert_eq!(csv[0], csv[1], "--jobs 2 changed the rows or their order");
    let (code, _, stderr, out) = run("0");
    let _ = std::fs::remove_dir_all(&out);
    assert_eq!(code, Some(2), "{stderr}");
    assert!(stderr.contains("--jobs"), "{stderr}");
}
