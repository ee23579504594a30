//! The run as a library call (`ricochet::run::execute`, which the command line's `run` wraps): a
//! scene run to its end with its progress reported, and an [`Interrupt`] flag that stops a run as
//! `interrupted`, with its summary and checkpoint, from which a restart through the same call
//! ends with the outputs of the run never stopped, byte for byte.

use std::path::{Path, PathBuf};
use std::sync::atomic::Ordering;

use ricochet::checkpoint::Checkpoint;
use ricochet::run::{execute, Backend, Ending, Interrupt, RunOutcome, RunRequest, Start};

use crate::common::tmp_dir;

/// `run.end_time` of the runs: 200 steps of the vibrating block, 3 snapshots.
const END: f64 = 4e-5;

/// A CPU run of the vibrating block to [`END`] into `out`, with checkpoints every `checkpoint`
/// seconds.
fn request(out: &Path, checkpoint: Option<f64>) -> RunRequest {
    RunRequest {
        start: Start::Scene {
            path: Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/vibrating_block.toml"),
            end_time: Some(END),
            out: Some(out.to_path_buf()),
            checkpoint_interval: checkpoint,
        },
        backend: Backend::Cpu,
        adapter: None,
    }
}

/// Runs `request`, asserting that it gave no notice; returns the outcome and the progress calls.
fn run(
    request: &RunRequest,
    interrupt: &Interrupt,
    mut on_tick: impl FnMut(f64, f64),
) -> (RunOutcome, Vec<(f64, f64, u64)>) {
    let mut notices = Vec::new();
    let mut ticks = Vec::new();
    let outcome = execute(
        request,
        interrupt,
        &mut |n| notices.push(n.to_string()),
        &mut |t, end, steps| {
            ticks.push((t, end, steps));
            on_tick(t, end);
        },
    )
    .expect("the run");
    assert!(notices.is_empty(), "{notices:?}");
    (outcome, ticks)
}

/// `summary.json` of `dir`.
fn summary(dir: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(dir.join("summary.json")).expect("summary.json");
    serde_json::from_str(&text).expect("summary.json is JSON")
}

/// `history.csv`, `fields.pvd` and the VTU files of a run, by relative path.
fn outputs(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut files = vec![PathBuf::from("history.csv"), PathBuf::from("fields.pvd")];
    let mut vtu: Vec<PathBuf> = std::fs::read_dir(dir.join("fields"))
        .expect("fields/")
        .map(|e| Path::new("fields").join(e.expect("entry").file_name()))
        .collect();
    vtu.sort();
    files.extend(vtu);
    files
        .into_iter()
        .map(|f| {
            let bytes = std::fs::read(dir.join(&f)).expect("read an output");
            (f, bytes)
        })
        .collect()
}

#[test]
fn a_scene_runs_to_its_end_through_the_library_call() {
    let out = tmp_dir("library-run");
    let (outcome, ticks) = run(&request(&out, None), &Interrupt::new(), |_, _| {});
    assert_eq!(outcome.ending, Ending::Completed);
    let s = &outcome.result.summary;
    assert_eq!(s.status, "completed");
    assert_eq!(s.backend, "cpu");
    assert!(s.end_time >= END * (1.0 - 1e-9), "{}", s.end_time);
    assert_eq!(outcome.result.out_dir, out);
    assert_eq!(summary(&out)["status"], "completed");
    // Progress after every batch but the last: the end time, growing times and steps.
    assert!(ticks.len() > 1, "{ticks:?}");
    assert!(ticks.iter().all(|&(_, end, _)| end == END));
    assert!(ticks.windows(2).all(|w| w[0].0 < w[1].0 && w[0].2 < w[1].2));
    let &(t, _, steps) = ticks.last().expect("a tick");
    assert!(t < s.end_time && steps < s.steps, "{t:e} {steps}");
    let history = std::fs::read_to_string(out.join("history.csv")).expect("history.csv");
    assert_eq!(history.lines().count() - 1, s.history_rows);
    let pvd = std::fs::read_to_string(out.join("fields.pvd")).expect("fields.pvd");
    assert!(s.snapshots > 0);
    assert_eq!(pvd.matches("<DataSet").count(), s.snapshots);
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn an_interrupt_flag_stops_a_run_and_a_restart_finishes_it() {
    let base = tmp_dir("library-interrupt");
    let (a, b) = (base.join("a"), base.join("b"));
    let mut interrupt = Interrupt::new();
    let stop = interrupt.flag("a stop request");
    // Checkpoints every second of simulated time: the only one is the interruption's.
    let (outcome, _) = run(&request(&a, Some(1.0)), &interrupt, |t, end| {
        if t > end / 2.0 {
            stop.store(true, Ordering::Relaxed);
        }
    });
    assert_eq!(outcome.ending, Ending::Interrupted("a stop request".into()));
    let s = &outcome.result.summary;
    assert_eq!(s.status, "interrupted");
    assert!(
        s.message
            .starts_with("interrupted by a stop request at step "),
        "{}",
        s.message
    );
    assert!(s.end_time > END / 2.0 && s.end_time < END, "{}", s.end_time);
    let written = summary(&a);
    assert_eq!(written["status"], "interrupted");
    assert_eq!(written["message"], s.message.as_str());
    let c = Checkpoint::read(&a).expect("the interruption's checkpoint");
    assert_eq!((c.steps, c.time), (s.steps, s.end_time));

    // Continued from the checkpoint, through the same call, on the checkpoint's backend.
    let (outcome, _) = run(&RunRequest::restart(&a), &Interrupt::new(), |_, _| {});
    assert_eq!(outcome.ending, Ending::Completed);
    assert_eq!(outcome.result.summary.backend, "cpu");
    // The outputs of the run never stopped.
    let (never, _) = run(&request(&b, None), &Interrupt::new(), |_, _| {});
    assert_eq!(never.ending, Ending::Completed);
    assert_eq!(outcome.result.summary.steps, never.result.summary.steps);
    let (oa, ob) = (outputs(&a), outputs(&b));
    assert_eq!(oa.len(), ob.len());
    for ((fa, xa), (fb, xb)) in oa.iter().zip(&ob) {
        assert_eq!(fa, fb);
        assert!(xa == xb, "{} differs", fa.display());
    }
    let _ = std::fs::remove_dir_all(&base);
}
