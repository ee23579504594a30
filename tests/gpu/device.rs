//! The device check on this machine's adapter (lavapipe in CI), at small sizes: the probe's copy
//! against its CPU reference and its figures, the per-stage profile (or the notice of an adapter
//! without timestamp queries), and `benches/device.sh` end to end with `RICOCHET_DEVICE_SMALL=1`,
//! every JSON file it writes parsed.

use super::*;

use std::process::Command;

use ricochet::bench::{ContactScene, ProfileScene};
use ricochet::gpu::probe::{self, ProbeKernels};

/// The copy writes the CPU reference's pattern exactly, on an odd length over a 2D grid (at most
/// 7 workgroups a row) and over one row; the probes give finite, positive figures.
#[test]
fn the_probe_copies_its_pattern_and_reports_finite_figures() {
    let Some(ctx) = context() else { return };
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let kernels = ProbeKernels::new(&ctx.device);
    for (elements, max_dim) in [(4_099u64, 7u32), (1, 7), (70_001, 65_535)] {
        let got = probe::copied(&ctx, &kernels, elements, max_dim).expect("copy");
        assert_eq!(got.len() as u64, elements);
        for (i, g) in got.iter().enumerate() {
            assert_eq!(*g, probe::pattern(i as u32), "element {i} of {elements}");
        }
    }
    let report = ricochet::bench::probe(&ctx, 1 << 20, 50, 3).expect("probe");
    let b = &report.bandwidth;
    assert!(b.verified, "the copy checked");
    assert_eq!((b.bytes, b.repeats, b.seconds.len()), (1 << 20, 3, 3));
    assert_eq!(
        b.timer,
        if ctx.timestamps {
            "timestamps"
        } else {
            "wall clock"
        }
    );
    for x in [
        b.gb_per_s,
        b.gb_per_s_best,
        report.block_bound_element_cycles_per_second,
    ] {
        assert!(x.is_finite() && x > 0.0, "{x}");
    }
    assert!(b.gb_per_s_best >= b.gb_per_s);
    let d = &report.dispatch;
    assert_eq!((d.dispatches, d.repeats), (50, 3));
    for x in [d.chained_us, d.empty_us, d.chained_wall_us, d.empty_wall_us] {
        assert!(x.is_finite() && x > 0.0, "{x} us per dispatch");
    }
    assert_eq!(report.block_bytes_per_element_cycle, 320.0);
    let json: serde_json::Value =
        serde_json::from_str(&serde_json::to_string(&report).expect("json")).expect("parses");
    assert_eq!(json["bandwidth"]["verified"], true);
    assert!(ricochet::bench::probe_summary(&report).contains("GB/s"));
}

/// The profile times every part of a step of the block and of the striker in contact, with
/// the element and node stages' bytes; an adapter without timestamp queries gives none, and
/// the notice says why.
#[test]
fn the_profile_times_every_part_or_says_why_not() {
    let Some(ctx) = context() else { return };
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    for (which, size) in [
        (ProfileScene::Block, 6),
        (ProfileScene::Contact(ContactScene::Striker), 4),
    ] {
        let row = ricochet::bench::profile(ctx.clone(), which, size, (30, 12), Default::default())
            .expect("profile");
        let Some(row) = row else {
            assert!(
                !ctx.timestamps,
                "no profile although the adapter has timestamps"
            );
            assert!(ricochet::bench::no_timestamps(&ctx).contains("no timestamp queries"));
            continue;
        };
        assert_eq!((row.scene.as_str(), row.size), (which.name(), size));
        assert_eq!((row.warmup, row.steps), (30, 12));
        assert_eq!(
            row.parts_us.len(),
            ricochet::gpu::solver::PROFILE_PARTS.len()
        );
        for (name, us) in &row.parts_us {
            assert!(us.is_finite() && *us >= 0.0, "{name}: {us} us");
        }
        let sum: f64 = row.parts_us.iter().map(|(_, us)| us).sum();
        assert!(row.total_us > 0.0 && (row.total_us - sum).abs() <= 1e-9 * sum);
        assert!(row.forces_bytes > 0.0 && row.update_bytes > 0.0);
        assert!(row.forces_gb_per_s.is_finite() && row.update_gb_per_s.is_finite());
        // The whole step's device time (one pass a batch) and wall time (as a run takes them).
        for us in [row.step_device_us, row.step_wall_us] {
            assert!(us.is_finite() && us > 0.0, "{us} us a step");
        }
        if which == ProfileScene::Block {
            // 36 elements, 49 nodes of the block: the traffic table's 168 B per element and
            // 32 B per node in the forces part, 48 and 72 in the update part.
            assert_eq!((row.elements, row.nodes), (36, 49));
            assert_eq!(row.forces_bytes, (36 * 168 + 49 * 32) as f64);
            assert_eq!(row.update_bytes, (36 * 48 + 49 * 72) as f64);
        } else {
            assert!(row.sweeps_mean > 0.0, "the striker is in contact");
        }
        let table = ricochet::bench::profile_table(&[row]);
        assert!(table.contains(which.name()) && table.contains("solve"));
    }
}

/// Every JSON file in `dir`, parsed, by name.
fn json_files(dir: &Path) -> Vec<(String, serde_json::Value)> {
    let mut out = Vec::new();
    for entry in std::fs::read_dir(dir).expect("results folder") {
        let path = entry.expect("entry").path();
        if path.extension().is_some_and(|e| e == "json") {
            let text = std::fs::read_to_string(&path).expect("read");
            let value = serde_json::from_str(&text)
                .unwrap_or_else(|e| panic!("{} does not parse: {e}\n{text}", path.display()));
            let name = path.file_name().map(|n| n.to_string_lossy().into_owned());
            out.push((name.unwrap_or_default(), value));
        }
    }
    out.sort_by(|a, b| a.0.cmp(&b.0));
    out
}

/// The one folder that a run of the device check wrote into `out`.
fn results_folder(out: &Path) -> std::path::PathBuf {
    let folders: Vec<_> = std::fs::read_dir(out)
        .expect("out")
        .map(|e| e.expect("entry").path())
        .collect();
    assert_eq!(folders.len(), 1, "{folders:?}");
    folders[0].clone()
}

/// `benches/device.sh` with tiny sizes: every step runs, into one folder named by the date and
/// the adapter, and every JSON file it writes parses; with no time budget every step is
/// recorded as skipped, and the exit status says so.
#[test]
fn the_device_script_runs_end_to_end_at_small_sizes() {
    let Some(_ctx) = context() else { return };
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let out = std::env::temp_dir().join(format!("ricochet-device-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let run = |budget: &str| {
        Command::new("bash")
            .arg(root.join("benches/device.sh"))
            .arg(env!("CARGO_BIN_EXE_ricochet"))
            .arg(&out)
            .env("RICOCHET_DEVICE_SMALL", "1")
            .env("RICOCHET_DEVICE_BUDGET", budget)
            .env("RICOCHET_DEVICE_DATE", "2026-11-27")
            .env("RICOCHET_DEVICE_COMMIT", "0123abc")
            .output()
            .expect("bash runs")
    };
    let o = run("300");
    let log = format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(o.status.success(), "{log}");
    let dir = results_folder(&out);
    let folder = dir.file_name().map(|n| n.to_string_lossy().into_owned());
    assert!(
        folder
            .as_deref()
            .is_some_and(|f| f.starts_with("2026-11-27_")
                && f.len() > 11
                && f.chars()
                    .all(|c| c.is_ascii_alphanumeric() || "-_".contains(c))),
        "{folder:?}"
    );
    assert!(dir.join("device.log").is_file());
    let files = json_files(&dir);
    let names: Vec<&str> = files.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(
        names,
        [
            "bench_block.json",
            "bench_erosion.json",
            "bench_pile.json",
            "bench_striker.json",
            "meta.json",
            "probe.json",
            "profile.json"
        ],
        "{log}"
    );
    let get = |name: &str| &files.iter().find(|(n, _)| n == name).expect(name).1;
    let meta = get("meta.json");
    assert_eq!(meta["date"], "2026-11-27");
    assert_eq!(meta["commit"], "0123abc");
    assert_eq!(meta["small"], true);
    assert!(meta["version"]
        .as_str()
        .is_some_and(|v| v.starts_with("ricochet ")));
    assert_eq!(meta["adapter"], get("probe.json")["adapter"]);
    let steps = meta["steps"].as_array().expect("steps");
    let step_names: Vec<&str> = steps.iter().filter_map(|s| s["name"].as_str()).collect();
    assert_eq!(
        step_names,
        [
            "probe",
            "block",
            "striker",
            "pile",
            "profile",
            "erosion",
            "colouring",
            "ahead",
            "search",
            "search-one",
            "group-512",
            "group-1024",
            "pairs",
            "storage",
            "stage-one"
        ]
    );
    for s in steps {
        assert_eq!(s["status"], "ok", "{s}");
        assert_eq!(s["exit"], 0, "{s}");
    }
    // The serial colouring's profile: in device.log alone.
    assert!(steps[6]["file"].is_null());
    let device_log = std::fs::read_to_string(dir.join("device.log")).expect("device.log");
    assert!(device_log.contains("--colouring serial"), "{device_log}");
    // The batches recorded after each readback: in device.log alone.
    assert!(steps[7]["file"].is_null());
    assert!(device_log.contains("--no-record-ahead"), "{device_log}");
    // The per-item search's profile: in device.log alone.
    assert!(steps[8]["file"].is_null());
    assert!(device_log.contains("--search items"), "{device_log}");
    // The search in one workgroup and the contact kernels at 512 and 1024 threads: the same.
    for (k, flag) in [
        (9, "--search one"),
        (10, "--contact-group 512"),
        (11, "--contact-group 1024"),
        (12, "--pair-blocks"),
        (13, "--sweep-memory storage"),
        (14, "--contact-stage one --search one"),
    ] {
        assert!(steps[k]["file"].is_null());
        assert!(device_log.contains(flag), "{device_log}");
    }
    assert_eq!(get("probe.json")["bandwidth"]["verified"], true);
    let block = get("bench_block.json").as_array().expect("the block rows");
    assert_eq!(block.len(), 1);
    assert_eq!(block[0]["backend"], "gpu");
    for (file, scene) in [
        ("bench_striker.json", "striker"),
        ("bench_pile.json", "pile"),
    ] {
        let rows = get(file)["contact"].as_array().expect("contact rows");
        assert!(
            !rows.is_empty() && rows.iter().all(|r| r["scene"] == scene),
            "{file}"
        );
        assert!(rows.iter().all(|r| r["warmup"] == 10));
    }
    // The striker with failure: the variant's rate beside the contact step's.
    let rows = get("bench_erosion.json")["contact"]
        .as_array()
        .expect("erosion rows");
    assert!(!rows.is_empty());
    for r in rows {
        assert_eq!(r["scene"], "striker");
        assert!(
            r["failure_steps_per_second"]
                .as_f64()
                .is_some_and(|v| v > 0.0),
            "{r}"
        );
    }
    let profile = get("profile.json");
    match profile["timestamps"].as_bool() {
        Some(true) => assert!(!profile["rows"].as_array().expect("rows").is_empty()),
        _ => assert!(profile["notice"].is_string()),
    }
    let _ = std::fs::remove_dir_all(&out);

    // No budget: every step skipped, recorded, and the exit status 3.
    let o = run("0");
    assert_eq!(o.status.code(), Some(3));
    let dir = results_folder(&out);
    assert!(dir.ends_with("2026-11-27_unknown-adapter"), "{dir:?}");
    let files = json_files(&dir);
    assert_eq!(files.len(), 1, "meta.json alone");
    let steps = files[0].1["steps"].as_array().expect("steps").clone();
    assert_eq!(steps.len(), 15);
    assert!(steps
        .iter()
        .all(|s| s["status"] == "skipped" && s["file"].is_null()));
    let _ = std::fs::remove_dir_all(&out);
}
