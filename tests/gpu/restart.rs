//! Checkpoint and restart on the GPU: a run continued with `ricochet run --restart` on the same
//! adapter, after a crash (outputs written past the checkpoint) or an interruption, ends with
//! the same history and fields, byte for byte, as the run that was never stopped; with contact
//! (a general contact whose device search runs many times, a Lagrange wall with field output).

use super::*;

use std::path::PathBuf;
use std::process::Command;

use ricochet::checkpoint::Checkpoint;

#[path = "../shared/restart.rs"]
pub(crate) mod shared_restart;
use shared_restart::{assert_same_outputs, copy_dir, run_interrupted_halfway, summary};

fn asset(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets")
        .join(name)
}

fn tmp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!(
        "ricochet-gpu-restart-{name}-{}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn ricochet(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_ricochet"))
        .args(args)
        .output()
        .expect("run the binary")
}

/// (scene, --end-time, checkpoint interval): the 16-disk pile (32 device searches over its
/// 1 ms), the disk on a wall to 60 us (with a snapshot every 20 us) and the plastic bar on a wall
/// to 40 us (its plastic state buffer and work in the checkpoint).
const CASES: [(&str, &str, f64); 3] = [
    ("pile.toml", "1e-3", 3e-4),
    ("disk_wall.toml", "6e-5", 2.5e-5),
    ("plastic_bar_wall.toml", "4e-5", 1.5e-5),
];

#[test]
fn gpu_restart_after_a_crash_and_an_interruption_gives_the_same_outputs() {
    let Some(ctx) = context() else { return };
    let _guard = GPU_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let base = tmp_dir("both");
    for (scene, end, interval) in CASES {
        let path = asset(scene);
        // The run never stopped, with periodic checkpoints.
        let a = base.join(format!("{scene}-a"));
        let o = ricochet(&[
            "run",
            path.to_str().unwrap(),
            "--backend",
            "gpu",
            "--end-time",
            end,
            "--checkpoint-interval",
            &interval.to_string(),
            "--out",
            a.to_str().unwrap(),
        ]);
        assert_eq!(o.status.code(), Some(0), "{o:?}");
        let c = Checkpoint::read(&a).expect("the run left a checkpoint");
        assert_eq!(c.backend, "gpu");
        assert_eq!(c.adapter, ctx.adapter_name());
        let end_t: f64 = end.parse().unwrap();
        assert!(c.time > 0.5 * end_t && c.time < end_t, "{}", c.time);

        // A crash after the last checkpoint: its folder, restarted.
        let b = base.join(format!("{scene}-b"));
        copy_dir(&a, &b);
        let o = ricochet(&["run", "--restart", b.to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(0), "{o:?}");
        let files = assert_same_outputs(&a, &b);

        // An interruption halfway, in this process on the shared adapter, then a restart.
        let text = std::fs::read_to_string(&path).unwrap();
        let (mut scene_v, _, _) = load(&text, scene);
        scene_v.run.end_time = end_t;
        scene_v.file = path.clone();
        let model = ricochet::run::model(&scene_v).unwrap();
        let plan = Plan::new(&scene_v, &model);
        let mut solver =
            GpuSolver::new(ctx.clone(), &model, &plan, schedule(&scene_v)).expect("gpu solver");
        let d = base.join(format!("{scene}-d"));
        let r = run_interrupted_halfway(
            &scene_v,
            &model,
            &plan,
            &mut solver,
            &d,
            &path,
            &text,
            Some(end_t),
        );
        let o = ricochet(&["run", "--restart", d.to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(0), "{o:?}");
        assert_same_outputs(&a, &d);
        assert_eq!(summary(&a)["steps"], summary(&d)["steps"]);
        assert_eq!(
            summary(&a)["contact_searches"],
            summary(&d)["contact_searches"]
        );
        println!(
            "{scene}: GPU restarts from t = {:e} s (crash) and {:e} s (interruption) gave the \
             same {files} files",
            c.time, r.summary.end_time
        );
    }
    let _ = std::fs::remove_dir_all(&base);
}
