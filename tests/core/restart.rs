//! Checkpoint and restart on the CPU reference (`run --checkpoint-interval`, `run --restart`):
//! a run continued from its last checkpoint, after a crash (outputs written past the checkpoint)
//! or after an interruption, ends with the same history and fields, byte for byte, as the run
//! that was never stopped; with contact (a Lagrange wall, a general contact with searches).

use std::path::{Path, PathBuf};

use ricochet::checkpoint::Checkpoint;
use ricochet::scene::Scene;
use ricochet::step::cpu::CpuSolver;

use crate::common::*;

#[path = "../shared/restart.rs"]
pub mod shared_restart;
use shared_restart::{assert_same_outputs, copy_dir, run_interrupted_halfway, summary};

fn asset(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets")
        .join(name)
}

fn restart_cpu(dir: &Path) -> std::process::Output {
    run_bin(&["run", "--restart", dir.to_str().unwrap()])
}

#[test]
fn restart_after_a_crash_continues_from_the_last_checkpoint() {
    // The finished run's folder holds its last periodic checkpoint and the outputs written after
    // it, as a run killed there would: the restart cuts them back and recomputes them.
    let base = tmp_dir("restart-crash");
    for (scene, interval) in [("disk_wall.toml", "3e-5"), ("pile.toml", "3e-4")] {
        let a = base.join(format!("{scene}-a"));
        let o = run_cpu(&asset(scene), &a, &["--checkpoint-interval", interval]);
        assert_eq!(o.status.code(), Some(0), "{o:?}");
        let c = Checkpoint::read(&a).expect("the run left a checkpoint");
        let end = summary(&a)["end_time"].as_f64().unwrap();
        let i: f64 = interval.parse().unwrap();
        assert!(
            c.time >= (end / i).floor() * i - 1e-6 * i && c.time < end,
            "{}",
            c.time
        );
        assert_eq!(c.backend, "cpu");
        let b = base.join(format!("{scene}-b"));
        copy_dir(&a, &b);
        let o = restart_cpu(&b);
        assert_eq!(o.status.code(), Some(0), "{o:?}");
        let files = assert_same_outputs(&a, &b);
        let (sa, sb) = (summary(&a), summary(&b));
        for key in [
            "status",
            "steps",
            "history_rows",
            "snapshots",
            "contact_searches",
        ] {
            assert_eq!(sa[key], sb[key], "{scene}: {key}");
        }
        println!(
            "{scene}: restart from t = {:e} s gave the same {files} files",
            c.time
        );
    }
    let _ = std::fs::remove_dir_all(&base);
}

#[test]
fn interrupted_run_restarts_to_the_same_outputs() {
    // Interrupted halfway (as by SIGINT, through the progress callback), the run writes a
    // checkpoint where it stopped; the restart completes it.
    let base = tmp_dir("restart-interrupt");
    // The plastic bar: its plastic state and work are part of the checkpoint.
    for scene in ["disk_wall.toml", "pile.toml", "plastic_bar_wall.toml"] {
        let path = asset(scene);
        let a = base.join(format!("{scene}-a"));
        let o = run_cpu(&path, &a, &[]);
        assert_eq!(o.status.code(), Some(0), "{o:?}");

        let text = std::fs::read_to_string(&path).unwrap();
        let scene_v = Scene::parse(&text, &path).unwrap();
        let model = ricochet::run::model(&scene_v).unwrap();
        let plan = ricochet::plan::Plan::new(&scene_v, &model);
        let mut solver = CpuSolver::new(
            model.clone(),
            plan.clone(),
            ricochet::run::schedule(&scene_v),
        );
        let b = base.join(format!("{scene}-b"));
        let r =
            run_interrupted_halfway(&scene_v, &model, &plan, &mut solver, &b, &path, &text, None);
        let c = Checkpoint::read(&b).expect("checkpoint at the interruption");
        assert_eq!(c.steps, r.summary.steps);
        assert!(c.time > scene_v.run.end_time / 2.0 && c.time < scene_v.run.end_time);

        let o = restart_cpu(&b);
        assert_eq!(o.status.code(), Some(0), "{o:?}");
        assert!(
            String::from_utf8_lossy(&o.stdout).contains("restarting"),
            "{o:?}"
        );
        assert_same_outputs(&a, &b);
        assert_eq!(summary(&b)["status"], "completed");
        assert_eq!(summary(&a)["steps"], summary(&b)["steps"]);
    }
    let _ = std::fs::remove_dir_all(&base);
}

#[test]
fn bad_checkpoints_and_intervals_exit_2_naming_them() {
    let base = tmp_dir("restart-bad");
    // No checkpoint in the folder.
    let o = restart_cpu(&base);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("checkpoint.bin") && err.contains("--checkpoint-interval"),
        "{err}"
    );
    // Not a checkpoint; a checkpoint cut short.
    let a = base.join("a");
    let o = run_cpu(&asset("pile.toml"), &a, &["--checkpoint-interval", "4e-4"]);
    assert_eq!(o.status.code(), Some(0), "{o:?}");
    let bytes = std::fs::read(a.join("checkpoint.bin")).unwrap();
    for (what, broken) in [
        ("not a ricochet checkpoint", b"hello world".to_vec()),
        ("cut short", bytes[..bytes.len() / 2].to_vec()),
    ] {
        std::fs::write(a.join("checkpoint.bin"), broken).unwrap();
        let o = restart_cpu(&a);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert!(
            err.contains("checkpoint.bin") && err.contains(what),
            "{err}"
        );
    }
    // A history shorter than the checkpoint's (another run's folder).
    std::fs::write(a.join("checkpoint.bin"), &bytes).unwrap();
    std::fs::write(a.join("history.csv"), "time\n").unwrap();
    let o = restart_cpu(&a);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("history.csv"), "{err}");
    // Intervals that are not positive finite numbers.
    for bad in ["0", "-1e-5", "inf", "NaN"] {
        let o = run_cpu(
            &asset("pile.toml"),
            &base.join("c"),
            &[&format!("--checkpoint-interval={bad}")],
        );
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{bad}: {err}");
        assert!(err.contains("--checkpoint-interval"), "{bad}: {err}");
    }
    let _ = std::fs::remove_dir_all(&base);
}
