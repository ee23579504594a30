//! Studies run on this machine.

use std::time::{Duration, Instant, SystemTime};

use crate::common::{bin, repo, results, run, scratch, study_file};

/// The modification time of every case's `exit` file (written once per run of the case).
fn run_stamps(dir: &std::path::Path) -> Vec<(String, SystemTime)> {
    let mut v: Vec<(String, SystemTime)> = std::fs::read_dir(dir.join("cases"))
        .unwrap()
        .flatten()
        .filter_map(|e| {
            let t = std::fs::metadata(e.path().join("exit"))
                .ok()?
                .modified()
                .ok()?;
            Some((e.file_name().to_string_lossy().into_owned(), t))
        })
        .collect();
    v.sort();
    v
}

/// The 12-case grid of `assets/studies/rods_grid.toml`: every case completed, its figures those of
/// a single run of the scene, each case's folder with its scene and manifest; a rerun runs
/// nothing and writes the same table; `plot` draws a figure against a parameter.
#[test]
fn the_grid_study_runs_collects_and_reruns_nothing() {
    let dir = scratch("grid");
    let out = dir.join("grid");
    let study = repo("assets/studies/rods_grid.toml");
    run(
        bin().arg("study").arg(&study).arg("--out").arg(&out).args([
            "--backend",
            "cpu",
            "--workers",
            "2",
        ]),
        0,
    );
    let rows = results(&out);
    assert_eq!(rows.len(), 13, "{rows:#?}");
    assert_eq!(
        rows[0],
        "id,status,v0,target_thickness,target_v,striker_v,peak_force,contact_loss,steps"
    );
    assert!(
        rows[1..].iter().all(|r| r.contains(",completed,")),
        "{rows:#?}"
    );
    // Case 0008 is the shipped scene itself (v0 = 10, the same target): its figures are those of
    // the scene run alone (REFERENCES.md section 1: the target leaves at about v0).
    let single = dir.join("single");
    run(
        bin()
            .arg("run")
            .arg(repo("assets/rods_impact.toml"))
            .arg("--out")
            .arg(&single)
            .args(["--backend", "cpu"]),
        0,
    );
    let history = std::fs::read_to_string(single.join("history.csv")).unwrap();
    let header: Vec<&str> = history.lines().next().unwrap().split(',').collect();
    let last: Vec<&str> = history.lines().last().unwrap().split(',').collect();
    let col = |name: &str| last[header.iter().position(|c| *c == name).unwrap()];
    let target_v: f64 = col("target.vx").parse().unwrap();
    let row: Vec<&str> = rows[9].split(',').collect();
    assert_eq!(&row[..4], ["0008", "completed", "10", "0.004"]);
    assert_eq!(row[4].parse::<f64>().unwrap().to_bits(), target_v.to_bits());
    assert!((target_v - 10.0).abs() < 0.1, "{target_v}");
    let case = out.join("cases/0008");
    let manifest: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(case.join("manifest.json")).unwrap())
            .unwrap();
    assert_eq!(
        manifest["parameters"][0]["key"],
        "body[striker].initial_velocity[0]"
    );
    assert_eq!(manifest["parameters"][0]["value"], 10.0);
    let scene = std::fs::read_to_string(case.join("scene.toml")).unwrap();
    let scene: toml::Table = toml::from_str(&scene).unwrap();
    assert_eq!(
        scene["body"][0]["initial_velocity"][0].as_float(),
        Some(10.0)
    );
    assert_eq!(scene["body"][1]["thickness"].as_float(), Some(0.004));

    // A rerun recomputes nothing and writes the same table.
    let before = run_stamps(&out);
    assert_eq!(before.len(), 12);
    let csv = std::fs::read(out.join("results.csv")).unwrap();
    std::thread::sleep(Duration::from_millis(20));
    run(
        bin()
            .arg("study")
            .arg(&study)
            .arg("--out")
            .arg(&out)
            .args(["--backend", "cpu"]),
        0,
    );
    assert_eq!(run_stamps(&out), before, "a completed case ran again");
    assert_eq!(std::fs::read(out.join("results.csv")).unwrap(), csv);
    // collect alone writes the same table.
    std::fs::remove_file(out.join("results.csv")).unwrap();
    run(bin().arg("collect").arg(&out), 0);
    assert_eq!(std::fs::read(out.join("results.csv")).unwrap(), csv);
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("results.json")).unwrap()).unwrap();
    assert_eq!(json["cases"].as_array().unwrap().len(), 12);
    assert_eq!(json["cases"][8]["figures"]["target_v"], target_v);

    // A changed study in the same folder is refused (exit 2), naming the study file.
    let changed = dir.join("changed.toml");
    std::fs::write(
        &changed,
        std::fs::read_to_string(&study)
            .unwrap()
            .replace(
                "../rods_impact.toml",
                &repo("assets/rods_impact.toml").display().to_string(),
            )
            .replace("values = [0.004, 0.008]", "values = [0.004, 0.006]"),
    )
    .unwrap();
    let o = run(bin().arg("study").arg(&changed).arg("--out").arg(&out), 2);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("changed.toml") && err.contains("another version"),
        "{err}"
    );

    // The figure against a parameter.
    let o = run(
        bin()
            .arg("plot")
            .arg(&out)
            .args(["--figure", "target_v", "--against", "v0"]),
        0,
    );
    let png = out.join("plots/target_v_vs_v0.png");
    assert!(String::from_utf8_lossy(&o.stdout).contains("target_v_vs_v0.png"));
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[1..4], b"PNG");
    let o = run(
        bin()
            .arg("plot")
            .arg(&out)
            .args(["--figure", "nope", "--against", "v0"]),
        2,
    );
    assert!(String::from_utf8_lossy(&o.stderr).contains("target_v"));
    let _ = std::fs::remove_dir_all(&dir);
}

/// A case whose run fails (a fixed time step ten times the stable one) is reported as failed in
/// `results.csv` with its message in `results.json`, and the other cases complete.
#[test]
fn a_failing_case_is_reported_and_the_others_complete() {
    let dir = scratch("failing");
    let study = study_file(
        &dir,
        "failing",
        r#"
[[parameter]]
name = "dt"
key = "run.time_step"
values = [4.350184725e-6, 4.350184725e-5, 2.0e-6]

[[parameter]]
key = "run.history_interval"
values = [4.350184725e-6]

[[collect]]
name = "target_v"
history = "target.vx"
"#,
    );
    let out = dir.join("out");
    let o = run(bin().arg("study").arg(&study).arg("--out").arg(&out), 1);
    assert!(
        String::from_utf8_lossy(&o.stdout).contains("case 0001 failed"),
        "{}",
        String::from_utf8_lossy(&o.stdout)
    );
    let rows = results(&out);
    assert!(rows[1].starts_with("0000,completed,"), "{rows:#?}");
    assert!(rows[2].starts_with("0001,failed,"), "{rows:#?}");
    assert!(
        rows[2].ends_with(','),
        "a failed case has no figure: {rows:#?}"
    );
    assert!(rows[3].starts_with("0002,completed,"), "{rows:#?}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("results.json")).unwrap()).unwrap();
    let message = json["cases"][1]["message"].as_str().unwrap();
    assert!(message.contains("stable step"), "{message}");
    // A rerun does not run the failed case again.
    let before = run_stamps(&out);
    run(bin().arg("study").arg(&study).arg("--out").arg(&out), 1);
    assert_eq!(run_stamps(&out), before);
    let _ = std::fs::remove_dir_all(&dir);
}

/// SIGTERM to a study stops its running case (which checkpoints) and starts no other: the
/// completed cases stay, the rerun runs only what is left (the interrupted case from its
/// checkpoint), and the table equals that of a study never stopped.
#[test]
fn an_interrupted_study_continues_where_it_stopped() {
    let dir = scratch("interrupted");
    let body = r#"
[[parameter]]
name = "v0"
key = "body[striker].initial_velocity[0]"
values = [1.0, 2.0, 3.0]

[[parameter]]
key = "run.end_time"
values = [0.06]

[[collect]]
name = "target_v"
history = "target.vx"

[[collect]]
name = "steps"
summary = "steps"
"#;
    let study = study_file(&dir, "long", body);
    let out = dir.join("out");
    let child = bin()
        .arg("study")
        .arg(&study)
        .arg("--out")
        .arg(&out)
        .args(["--workers", "1"])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // Wait until the second case is under way (the first completed), then stop the study.
    let started = Instant::now();
    let second = out.join("cases/0001/out/history.csv");
    while !second.exists() {
        assert!(
            started.elapsed() < Duration::from_secs(60),
            "case 0001 never started"
        );
        std::thread::sleep(Duration::from_millis(5));
    }
    std::thread::sleep(Duration::from_millis(100));
    // SAFETY: kill(2) on the pid of a child not yet waited for.
    unsafe {
        libc::kill(child.id() as i32, libc::SIGTERM);
    }
    let o = child.wait_with_output().unwrap();
    assert_eq!(
        o.status.code(),
        Some(143),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let rows = results(&out);
    assert!(rows[1].starts_with("0000,completed,"), "{rows:#?}");
    let interrupted_or_done =
        rows[2].starts_with("0001,interrupted,") || rows[2].starts_with("0001,completed,");
    assert!(interrupted_or_done, "{rows:#?}");
    assert!(rows[3].starts_with("0002,not run,"), "{rows:#?}");
    let first = run_stamps(&out)
        .into_iter()
        .find(|(id, _)| id == "0000")
        .unwrap();
    run(bin().arg("study").arg(&study).arg("--out").arg(&out), 0);
    assert_eq!(
        run_stamps(&out)
            .into_iter()
            .find(|(id, _)| id == "0000")
            .unwrap(),
        first,
        "the completed case ran again"
    );
    if rows[2].contains(",interrupted,") {
        let log = std::fs::read_to_string(out.join("cases/0001/run.log")).unwrap();
        assert!(log.contains("from its checkpoint"), "{log}");
    }
    // The same table as a study never stopped.
    let straight = dir.join("straight");
    run(
        bin().arg("study").arg(&study).arg("--out").arg(&straight),
        0,
    );
    assert_eq!(results(&out), results(&straight));
    let _ = std::fs::remove_dir_all(&dir);
}

/// The threshold search of `assets/studies/rods_threshold.toml` finds the impact velocity at
/// which the first step's kinetic energy reaches 10 J, whose closed form is
/// v0 = sqrt(20 / (0.785 (1 - 1/160))) = 5.06339 m/s (README, "Studies"), within its tolerance,
/// in fewer runs than a grid at that tolerance; a rerun runs nothing.
#[test]
fn the_threshold_search_finds_the_closed_form_in_fewer_runs_than_a_grid() {
    let dir = scratch("threshold");
    let out = dir.join("out");
    let study = repo("assets/studies/rods_threshold.toml");
    let o = run(
        bin()
            .arg("study")
            .arg(&study)
            .arg("--out")
            .arg(&out)
            .args(["--workers", "2"]),
        0,
    );
    assert!(String::from_utf8_lossy(&o.stdout).contains("threshold: v0 = "));
    let answer: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("threshold.json")).unwrap())
            .unwrap();
    let exact = (20.0_f64 / (0.785 * (1.0 - 1.0 / 160.0))).sqrt();
    let value = answer["value"].as_f64().unwrap();
    let lo = answer["bracket"][0].as_f64().unwrap();
    let hi = answer["bracket"][1].as_f64().unwrap();
    assert!(hi - lo <= 0.01, "{answer}");
    assert!(lo <= exact && exact <= hi, "{exact} not in [{lo}, {hi}]");
    assert!((value - exact).abs() <= 0.01, "{value} against {exact}");
    // Two ends, then rounds of two points (one per worker) until the bracket is 0.01 wide:
    // 19 / 3^7 < 0.01 < 19 / 3^6, so 2 + 2 * 7 = 16 runs where a grid at 0.01 takes 1901.
    assert_eq!(answer["points_per_round"], 2);
    assert_eq!(answer["runs"], 16, "{answer}");
    assert_eq!(answer["grid_runs"], 1901);
    assert_eq!(results(&out).len(), 17);
    let before = run_stamps(&out);
    run(
        bin()
            .arg("study")
            .arg(&study)
            .arg("--out")
            .arg(&out)
            .args(["--workers", "2"]),
        0,
    );
    assert_eq!(run_stamps(&out), before, "a rerun ran cases again");
    let _ = std::fs::remove_dir_all(&dir);
}
