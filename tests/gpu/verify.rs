//! `ricochet verify --quick` on both backends (lavapipe in CI): every case of
//! `assets/verification/` passes its bounds, and the CSV, report and plots are written.

use std::path::Path;
use std::process::Command;

use crate::{context, GPU_LOCK};

#[test]
fn quick_verify_passes_on_cpu_and_gpu_and_writes_the_report_and_plots() {
    let Some(_) = context() else { return };
    let _g = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let out = std::env::temp_dir().join(format!("ricochet-verify-{}", std::process::id()));
    let o = Command::new(env!("CARGO_BIN_EXE_ricochet"))
        .current_dir(root)
        .args([
            "verify",
            "--quick",
            "--backend",
            "both",
            "--jobs",
            "2",
            "--out",
        ])
        .arg(&out)
        .output()
        .expect("run ricochet verify");
    let stdout = String::from_utf8_lossy(&o.stdout);
    let stderr = String::from_utf8_lossy(&o.stderr);
    eprintln!("{stdout}");
    assert_eq!(o.status.code(), Some(0), "{stdout}\n{stderr}");
    assert!(stdout.contains("all cases pass their bounds"), "{stdout}");
    let cases: Vec<String> = std::fs::read_dir(root.join("assets/verification"))
        .expect("cases folder")
        .filter_map(|e| e.ok())
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .map(|p| p.file_stem().unwrap().to_string_lossy().into_owned())
        .collect();
    assert!(cases.len() >= 6, "{cases:?}");
    let csv = std::fs::read_to_string(out.join("results.csv")).expect("results.csv");
    let header = csv.lines().next().unwrap_or("");
    assert!(
        header.starts_with(
            "case,method,backend,level,elements,steps,wall_seconds,metric,reference,value,relative_error"
        ),
        "{header}"
    );
    let report = std::fs::read_to_string(out.join("report.md")).expect("report.md");
    for case in &cases {
        // File names and case names agree in this folder. A case may declare the backends
        // that run it (`backends = ["cpu"]`: a model the GPU backend does not run yet).
        let text = std::fs::read_to_string(root.join(format!("assets/verification/{case}.toml")))
            .expect("case file");
        // A case with no quick ladder (too costly for the suite) is left out and listed.
        if text.lines().any(|l| l.trim() == "quick = []") {
            assert!(
                report.contains(&format!("- `{case}`: ")),
                "{case}: not listed as full-ladder only"
            );
            assert!(
                !csv.lines().any(|l| l.starts_with(&format!("{case},"))),
                "{case} ran in --quick"
            );
            continue;
        }
        let cpu_only = text.lines().any(|l| l.trim() == "backends = [\"cpu\"]");
        let backends: &[&str] = if cpu_only { &["cpu"] } else { &["cpu", "gpu"] };
        for &backend in backends {
            assert!(
                csv.lines()
                    .any(|l| l.starts_with(&format!("{case},"))
                        && l.contains(&format!(",{backend},"))),
                "{case} on {backend} missing from results.csv"
            );
        }
        assert!(
            report.contains(&format!("## {case}:")),
            "{case} missing from the report"
        );
        for ext in ["svg", "png"] {
            let f = out.join(format!("{case}.{ext}"));
            let len = std::fs::metadata(&f).map(|m| m.len()).unwrap_or(0);
            assert!(len > 1000, "{} is {len} bytes", f.display());
        }
    }
    // Every judged row passed; every row has a finite value.
    for l in csv.lines().skip(1) {
        let cols: Vec<&str> = l.split(',').collect();
        assert_eq!(cols.len(), 16, "{l}");
        assert_ne!(cols[15], "false", "{l}");
        assert!(cols[9].parse::<f64>().is_ok_and(f64::is_finite), "{l}");
    }
    let _ = std::fs::remove_dir_all(&out);
}
