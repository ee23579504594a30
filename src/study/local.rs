//! A study's cases run on this machine: a pool of workers ([`workers`]: one per hardware GPU
//! adapter, each case given its adapter, else one per CPU core on the CPU reference), each
//! running its cases one at a time as child processes of the ricochet binary (`ricochet run
//! case/scene.toml --out case/out`, or `ricochet run --restart case/out` for a case interrupted
//! with a checkpoint), so that a crash or an unstable run of one case cannot take the study down.
//! A completed or failed run is not run again. An [`Interrupt`] sends SIGTERM to the running
//! children (they checkpoint and stop) and starts no new case; progress goes to a callback.
//! Nothing here prints. Host-side only, no GPU twin.

use std::collections::VecDeque;
use std::fs::OpenOptions;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::{mpsc, Mutex};
use std::time::{Duration, Instant};

use super::cases::{case_dir, case_out, case_scene};
use super::collect::{case_state, CaseStatus, EXIT_FILE, LOG_FILE};
use crate::error::{Error, Result};
use crate::run::{Backend, Interrupt};

/// Where one worker runs its cases.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Worker {
    /// The backend of its runs (`--backend`).
    pub backend: Backend,
    /// Its adapter (`--adapter`, an index into the adapters a run sees), on the GPU.
    pub adapter: Option<String>,
}

/// The workers of a study on this machine. `adapters` lists the adapters a run may open, in the
/// order `--adapter INDEX` counts them, each with whether it is a software one
/// ([`crate::gpu::context::visible_adapters`]); `cores` is the number of CPU cores.
///
/// On [`Backend::Auto`], one worker per hardware adapter when there is one (each runs its cases
/// on its adapter), else `cores` workers on the CPU reference; on [`Backend::Cpu`], `cores`
/// workers; on [`Backend::Gpu`], one per hardware adapter, or per adapter when none is hardware.
/// `count` sets the number of workers instead (GPU workers then take the adapters in turn).
pub fn workers(
    backend: Backend,
    count: Option<usize>,
    adapters: &[(String, bool)],
    cores: usize,
) -> Vec<Worker> {
    let hardware: Vec<usize> = (0..adapters.len()).filter(|&i| !adapters[i].1).collect();
    let gpus: Vec<usize> = match backend {
        Backend::Cpu => Vec::new(),
        Backend::Auto => hardware,
        Backend::Gpu if hardware.is_empty() => (0..adapters.len()).collect(),
        Backend::Gpu => hardware,
    };
    if gpus.is_empty() {
        let backend = if backend == Backend::Gpu {
            Backend::Gpu
        } else {
            Backend::Cpu
        };
        return vec![
            Worker {
                backend,
                adapter: None,
            };
            count.unwrap_or(cores).max(1)
        ];
    }
    let n = count.unwrap_or(gpus.len()).max(1);
    (0..n)
        .map(|k| Worker {
            backend: Backend::Gpu,
            adapter: Some(gpus[k % gpus.len()].to_string()),
        })
        .collect()
}

/// What a worker does with a case.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Action {
    /// Nothing: its run ended (completed or failed).
    Skip(CaseStatus),
    /// Continue its run from its checkpoint (`run --restart`).
    Restart,
    /// Run it from the start (its old output removed).
    Fresh,
}

/// What to do with the case whose folder is `dir`: a run that ended is kept, one that stopped
/// with a checkpoint continues, anything else runs from the start.
pub fn action(dir: &Path) -> Action {
    let s = case_state(dir);
    if s.finished {
        Action::Skip(s.status)
    } else if s.checkpoint {
        Action::Restart
    } else {
        Action::Fresh
    }
}

/// The arguments of the ricochet binary for `action` on case `id` of the study folder `root`,
/// run by `worker`.
pub fn run_arguments(root: &Path, id: &str, action: &Action, worker: &Worker) -> Vec<String> {
    let path = |p: PathBuf| p.to_string_lossy().into_owned();
    let mut args: Vec<String> = match action {
        Action::Restart => vec!["run".into(), "--restart".into(), path(case_out(root, id))],
        _ => vec![
            "run".into(),
            path(case_scene(root, id)),
            "--out".into(),
            path(case_out(root, id)),
        ],
    };
    args.push("--backend".into());
    args.push(
        match worker.backend {
            Backend::Auto => "auto",
            Backend::Cpu => "cpu",
            Backend::Gpu => "gpu",
        }
        .into(),
    );
    if let Some(a) = &worker.adapter {
        args.push("--adapter".into());
        args.push(a.clone());
    }
    args
}

/// The study's progress, as the callback of [`run_cases`] sees it.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Progress {
    /// Cases in this run of the study.
    pub total: usize,
    /// Cases whose runs completed (now or before).
    pub done: usize,
    /// Cases that failed (now or before).
    pub failed: usize,
    /// Cases interrupted in this run.
    pub interrupted: usize,
    /// Cases running now.
    pub running: usize,
    /// Cases found finished from an earlier run, not run again.
    pub skipped: usize,
    /// Estimated time to the end: the mean wall time of the cases run so far, times the cases
    /// left over the workers.
    pub eta: Option<Duration>,
    /// The case that has just ended (its id and status), if any.
    pub ended: Option<(String, CaseStatus)>,
}

/// How to run a study's cases here.
#[derive(Debug, Clone)]
pub struct Runner {
    /// The ricochet binary the children run (the command line passes its own,
    /// `std::env::current_exe()`; a binding passes the path of an installed one).
    pub program: PathBuf,
    /// The workers.
    pub workers: Vec<Worker>,
}

/// A message from a worker thread.
enum Event {
    Started,
    Ended(String, CaseStatus, Option<Duration>),
}

/// How often a worker checks its child and the interrupt.
const POLL: Duration = Duration::from_millis(20);

/// Runs the cases `ids` of the study folder `root` with `runner`'s workers, each case as
/// [`action`] says, and returns each case's status in the order of `ids`. After every change it
/// calls `progress`. When a flag of `interrupt` is set, the workers send SIGTERM to their children
/// (which write their checkpoint and stop) and take no new case; the cases left are "not run".
///
/// # Errors
/// [`Error::Write`] when a case's log or exit file cannot be written; [`Error::Study`] when the
/// ricochet binary cannot be started.
pub fn run_cases(
    root: &Path,
    ids: &[String],
    runner: &Runner,
    interrupt: &Interrupt,
    progress: &mut dyn FnMut(&Progress),
) -> Result<Vec<(String, CaseStatus)>> {
    let queue: Mutex<VecDeque<(usize, String)>> =
        Mutex::new(ids.iter().cloned().enumerate().collect());
    let results: Mutex<Vec<CaseStatus>> = Mutex::new(vec![CaseStatus::NotRun; ids.len()]);
    let (tx, rx) = mpsc::channel::<Event>();
    let mut state = Progress {
        total: ids.len(),
        ..Progress::default()
    };
    let mut first_error: Option<Error> = None;
    let mut run_times: Vec<Duration> = Vec::new();
    std::thread::scope(|scope| {
        let mut handles = Vec::new();
        for worker in &runner.workers {
            let (queue, results, tx) = (&queue, &results, tx.clone());
            handles.push(scope.spawn(move || -> Result<()> {
                loop {
                    if interrupt.caught().is_some() {
                        return Ok(());
                    }
                    let Some((k, id)) = queue.lock().ok().and_then(|mut q| q.pop_front()) else {
                        return Ok(());
                    };
                    let dir = case_dir(root, &id);
                    let act = action(&dir);
                    if let Action::Skip(status) = act {
                        if let Ok(mut r) = results.lock() {
                            r[k] = status;
                        }
                        let _ = tx.send(Event::Ended(id, status, None));
                        continue;
                    }
                    let _ = tx.send(Event::Started);
                    let started = Instant::now();
                    let status = run_one(root, &id, &act, worker, &runner.program, interrupt)?;
                    if let Ok(mut r) = results.lock() {
                        r[k] = status;
                    }
                    let _ = tx.send(Event::Ended(id, status, Some(started.elapsed())));
                }
            }));
        }
        drop(tx);
        let workers = runner.workers.len().max(1);
        for event in rx {
            match event {
                Event::Started => state.running += 1,
                Event::Ended(id, status, took) => {
                    match took {
                        Some(t) => {
                            state.running = state.running.saturating_sub(1);
                            if status == CaseStatus::Completed || status == CaseStatus::Failed {
                                run_times.push(t);
                            }
                        }
                        None => state.skipped += 1,
                    }
                    match status {
                        CaseStatus::Completed => state.done += 1,
                        CaseStatus::Failed => state.failed += 1,
                        CaseStatus::Interrupted => state.interrupted += 1,
                        CaseStatus::NotRun => {}
                    }
                    let left = state.total - state.done - state.failed - state.interrupted;
                    state.eta = (!run_times.is_empty()).then(|| {
                        let mean = run_times.iter().sum::<Duration>() / run_times.len() as u32;
                        mean * left.div_ceil(workers) as u32
                    });
                    state.ended = Some((id, status));
                }
            }
            progress(&state);
            state.ended = None;
        }
        for h in handles {
            match h.join() {
                Ok(Ok(())) => {}
                Ok(Err(e)) => {
                    first_error.get_or_insert(e);
                }
                Err(_) => {
                    first_error.get_or_insert(Error::Study("a worker thread panicked".into()));
                }
            }
        }
    });
    if let Some(e) = first_error {
        return Err(e);
    }
    let results = results.into_inner().unwrap_or_default();
    Ok(ids.iter().cloned().zip(results).collect())
}

/// Runs one case as a child process and returns its status: `action` (not a skip) by `worker`,
/// its output appended to the case's `run.log` and its exit status written to the case's `exit`
/// file; SIGTERM to the child when `interrupt` is set.
fn run_one(
    root: &Path,
    id: &str,
    action: &Action,
    worker: &Worker,
    program: &Path,
    interrupt: &Interrupt,
) -> Result<CaseStatus> {
    let dir = case_dir(root, id);
    if *action == Action::Fresh {
        let _ = std::fs::remove_dir_all(case_out(root, id));
    }
    let _ = std::fs::remove_file(dir.join(EXIT_FILE));
    let log_path = dir.join(LOG_FILE);
    let write_err = |source| Error::Write {
        path: log_path.clone(),
        source,
    };
    let mut log = OpenOptions::new()
        .create(true)
        .append(true)
        .open(&log_path)
        .map_err(write_err)?;
    let args = run_arguments(root, id, action, worker);
    writeln!(log, "$ ricochet {}", args.join(" ")).map_err(write_err)?;
    let err_log = log.try_clone().map_err(write_err)?;
    let mut child: Child = Command::new(program)
        .args(&args)
        .stdin(Stdio::null())
        .stdout(Stdio::from(log))
        .stderr(Stdio::from(err_log))
        .spawn()
        .map_err(|e| Error::Study(format!("cannot start {}: {e}", program.display())))?;
    let mut signalled = false;
    let status = loop {
        match child.try_wait() {
            Ok(Some(status)) => break status,
            Ok(None) => {}
            Err(e) => return Err(Error::Study(format!("waiting for case {id}'s run: {e}"))),
        }
        if !signalled && interrupt.caught().is_some() {
            terminate(&mut child);
            signalled = true;
        }
        std::thread::sleep(POLL);
    };
    let code = exit_code(&status);
    super::cases::write_file(&dir.join(EXIT_FILE), &format!("{code}\n"))?;
    Ok(case_state(&dir).status)
}

/// SIGTERM to `child` (on Unix; elsewhere it is killed): it writes its checkpoint and stops.
fn terminate(child: &mut Child) {
    #[cfg(unix)]
    {
        if let Ok(pid) = i32::try_from(child.id()) {
            // SAFETY: kill(2) on the pid of a child this process has not reaped yet (`try_wait`
            // has not returned its status), so the pid is still that child's.
            unsafe {
                libc::kill(pid, libc::SIGTERM);
            }
        }
    }
    #[cfg(not(unix))]
    {
        let _ = child.kill();
    }
}

/// The exit status as a shell reports it: the code, or 128 + the signal that ended the process.
fn exit_code(status: &std::process::ExitStatus) -> i32 {
    #[cfg(unix)]
    {
        use std::os::unix::process::ExitStatusExt as _;
        if let Some(sig) = status.signal() {
            return 128 + sig;
        }
    }
    status.code().unwrap_or(1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn workers_are_one_per_hardware_adapter_else_the_cores() {
        let lavapipe = [("llvmpipe".to_string(), true)];
        let node = [
            ("H100 a".to_string(), false),
            ("H100 b".to_string(), false),
            ("llvmpipe".to_string(), true),
        ];
        let cpu = |n| {
            vec![
                Worker {
                    backend: Backend::Cpu,
                    adapter: None
                };
                n
            ]
        };
        assert_eq!(workers(Backend::Auto, None, &lavapipe, 2), cpu(2));
        assert_eq!(workers(Backend::Auto, None, &[], 3), cpu(3));
        assert_eq!(workers(Backend::Cpu, None, &node, 4), cpu(4));
        assert_eq!(workers(Backend::Cpu, Some(1), &node, 4), cpu(1));
        let gpu = |a: &str| Worker {
            backend: Backend::Gpu,
            adapter: Some(a.into()),
        };
        assert_eq!(
            workers(Backend::Auto, None, &node, 16),
            [gpu("0"), gpu("1")]
        );
        assert_eq!(
            workers(Backend::Auto, Some(3), &node, 16),
            [gpu("0"), gpu("1"), gpu("0")]
        );
        assert_eq!(workers(Backend::Gpu, None, &lavapipe, 2), [gpu("0")]);
        assert_eq!(
            workers(Backend::Gpu, None, &[], 2),
            vec![
                Worker {
                    backend: Backend::Gpu,
                    adapter: None
                };
                2
            ]
        );
    }

    #[test]
    fn arguments_run_the_scene_or_restart_from_the_checkpoint() {
        let root = Path::new("/s");
        let w = Worker {
            backend: Backend::Gpu,
            adapter: Some("1".into()),
        };
        assert_eq!(
            run_arguments(root, "0003", &Action::Fresh, &w),
            [
                "run",
                "/s/cases/0003/scene.toml",
                "--out",
                "/s/cases/0003/out",
                "--backend",
                "gpu",
                "--adapter",
                "1"
            ]
        );
        let w = Worker {
            backend: Backend::Cpu,
            adapter: None,
        };
        assert_eq!(
            run_arguments(root, "0003", &Action::Restart, &w),
            ["run", "--restart", "/s/cases/0003/out", "--backend", "cpu"]
        );
    }
}
