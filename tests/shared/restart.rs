//! Checkpoint and restart checks shared by the CPU and GPU tests: a run stopped and continued
//! with `ricochet run --restart` must leave the same `history.csv`, `fields.pvd` and VTU files,
//! byte for byte, as the run that was never stopped.

use std::path::Path;

use ricochet::checkpoint::Checkpointing;
use ricochet::model::Model;
use ricochet::plan::Plan;
use ricochet::run::{run_with, RunOptions, RunResult};
use ricochet::scene::Scene;
use ricochet::step::Solver;

/// Copies the folder `from` (files and subfolders) to `to`.
pub fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).expect("create the copy");
    for e in std::fs::read_dir(from).expect("read the folder") {
        let e = e.expect("entry");
        let target = to.join(e.file_name());
        if e.file_type().expect("type").is_dir() {
            copy_dir(&e.path(), &target);
        } else {
            std::fs::copy(e.path(), &target).expect("copy a file");
        }
    }
}

/// The output files a run writes (`history.csv`, `fields.pvd`, `fields/*`), by relative path.
fn outputs(dir: &Path) -> Vec<String> {
    let mut files = vec!["history.csv".to_string()];
    if dir.join("fields.pvd").is_file() {
        files.push("fields.pvd".into());
        let mut vtu: Vec<String> = std::fs::read_dir(dir.join("fields"))
            .expect("fields/")
            .map(|e| format!("fields/{}", e.expect("entry").file_name().to_string_lossy()))
            .collect();
        vtu.sort();
        files.extend(vtu);
    }
    files
}

/// Asserts that `b` holds the same output files as `a`, byte for byte; returns how many.
pub fn assert_same_outputs(a: &Path, b: &Path) -> usize {
    let (fa, fb) = (outputs(a), outputs(b));
    assert_eq!(fa, fb, "the two runs wrote different files");
    for f in &fa {
        let (x, y) = (
            std::fs::read(a.join(f)).expect("read"),
            std::fs::read(b.join(f)).expect("read"),
        );
        if x != y {
            let at = x.iter().zip(&y).position(|(p, q)| p != q).unwrap_or(0);
            let line = x[..at].iter().filter(|&&c| c == b'\n').count() + 1;
            panic!(
                "{f} differs between {} and {} (sizes {} and {}; first at byte {at}, line {line})",
                a.display(),
                b.display(),
                x.len(),
                y.len()
            );
        }
    }
    fa.len()
}

/// `summary.json` of `dir`.
pub fn summary(dir: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(dir.join("summary.json")).expect("summary.json");
    serde_json::from_str(&text).expect("summary.json is JSON")
}

/// Runs `scene` (from the file `path` with text `text`, and `--end-time` `end_override`) with
/// `solver` into `out`, interrupted (as by a signal, through the progress callback) once it passes
/// half its end time; checkpoints are on with an interval longer than the run, so the only
/// checkpoint is the interruption's.
#[allow(clippy::too_many_arguments)]
pub fn run_interrupted_halfway(
    scene: &Scene,
    model: &Model,
    plan: &Plan,
    solver: &mut dyn Solver,
    out: &Path,
    path: &Path,
    text: &str,
    end_override: Option<f64>,
) -> RunResult {
    let half = scene.run.end_time / 2.0;
    let mut stop = |t: f64, _end: f64, _n: u64| (t > half).then(|| "stopped".to_string());
    let options = RunOptions {
        checkpointing: Some(Checkpointing {
            interval: 10.0,
            scene_path: path.to_path_buf(),
            scene_text: text.to_string(),
            end_time_override: end_override,
        }),
        resume: None,
    };
    let r = run_with(scene, model, plan, solver, out, Some(&mut stop), options)
        .expect("the interrupted run");
    assert_eq!(r.summary.status, "interrupted");
    r
}
