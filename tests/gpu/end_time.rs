//! Very short end times on the GPU (issue 40, item 9): an end time of about 1e-28 s or less ran
//! forever at t = 0, because the kernels' ticks per second (`2^40 / end_time` as an `f32`)
//! overflowed to infinity, so that the last step's clip made dt 0 and no tick ever passed. The
//! run now ends as the CPU reference's does, in one step, and an end time too short for the
//! GPU's `f32` ticks is refused at once with a message saying to run it on the CPU.

use super::*;

use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

/// `ricochet run spinning_disk.toml --backend BACKEND --end-time END --out OUT`, killed after 120 s:
/// (output, whether it had to be killed).
fn run_bounded(backend: &str, end: &str, out: &Path) -> (Output, bool) {
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/spinning_disk.toml");
    let mut child = Command::new(env!("CARGO_BIN_EXE_ricochet"))
        .args([
            "run",
            scene.to_str().unwrap(),
            "--backend",
            backend,
            "--end-time",
            end,
            "--out",
            out.to_str().unwrap(),
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start the binary");
    let t0 = Instant::now();
    let mut killed = false;
    while child.try_wait().expect("wait").is_none() {
        if t0.elapsed() > Duration::from_secs(120) {
            let _ = child.kill();
            killed = true;
            break;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    (child.wait_with_output().expect("output"), killed)
}

fn summary(out: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap()
}

#[test]
fn an_end_time_of_1e_28_s_ends_on_the_gpu_as_on_the_cpu() {
    let Some(_ctx) = context() else { return };
    let _guard = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let base = std::env::temp_dir().join(format!("ricochet-gpu-end-time-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&base);
    for end in ["1e-24", "1e-28", "1e-30"] {
        let (cpu, gpu) = (
            base.join(format!("cpu-{end}")),
            base.join(format!("gpu-{end}")),
        );
        let (o, killed) = run_bounded("cpu", end, &cpu);
        assert!(!killed && o.status.code() == Some(0), "cpu {end}: {o:?}");
        let (o, killed) = run_bounded("gpu", end, &gpu);
        assert!(!killed, "the GPU run to {end} s hung: {o:?}");
        assert_eq!(o.status.code(), Some(0), "gpu {end}: {o:?}");
        let (c, g) = (summary(&cpu), summary(&gpu));
        assert_eq!(g["status"], "completed", "{end}");
        assert_eq!(g["steps"], c["steps"], "{end}: steps");
        let t: f64 = end.parse().unwrap();
        let history = std::fs::read_to_string(gpu.join("history.csv")).unwrap();
        let last = history.lines().last().unwrap();
        let final_time: f64 = last.split(',').next().unwrap().parse().unwrap();
        assert!(
            (final_time - t).abs() <= 1e-6 * t,
            "{end}: the GPU ended at {final_time:e} s"
        );
    }
    // Below what f32 ticks can count: refused at once, saying so.
    let (o, killed) = run_bounded("gpu", "1e-35", &base.join("gpu-1e-35"));
    assert!(!killed, "the GPU run to 1e-35 s hung: {o:?}");
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("run.end_time") && err.contains("--backend cpu"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&base);
}
