//! `ricochet study STUDY`: the command line's face of the library's studies
//! ([`ricochet::study`]): loads and checks the study, prepares its folder, then runs the cases
//! here (a progress line on stderr, SIGINT and SIGTERM passed to the running cases, which
//! checkpoint) or writes and submits the Slurm job array (`--slurm`), and collects the results.

use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Duration;

use anyhow::Context;

use ricochet::run::Backend;
use ricochet::study::cases::{prepare, write_record};
use ricochet::study::local::{run_cases, workers, Progress, Runner};
use ricochet::study::slurm::{self, SlurmOptions};
use ricochet::study::threshold::{search, Outcome};
use ricochet::study::{collect, Kind, Study};

use super::args::StudyArgs;
use super::signals::Signals;

/// `ricochet study STUDY`: exit status 0 when every case completed, 1 when some failed (they are
/// in results.csv with their status), 128 + the signal's number when interrupted.
pub fn study(args: StudyArgs) -> anyhow::Result<ExitCode> {
    let study = Study::load(&args.study)?;
    let root = args
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("out").join(&study.name));
    let backend: Backend = args.backend.map_or(study.backend, Into::into);
    let program = std::env::current_exe().context("finding the ricochet binary")?;
    if args.slurm {
        return on_slurm(&study, &root, backend, program, &args);
    }
    let adapters = if backend == Backend::Cpu {
        Vec::new()
    } else {
        ricochet::gpu::context::visible_adapters()?
    };
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let runner = Runner {
        program,
        workers: workers(backend, args.workers.map(|n| n as usize), &adapters, cores),
    };
    let on = match &runner.workers[0].adapter {
        Some(_) => format!(
            "{} GPU worker(s): adapters {}",
            runner.workers.len(),
            runner
                .workers
                .iter()
                .filter_map(|w| w.adapter.clone())
                .collect::<Vec<_>>()
                .join(", ")
        ),
        None => format!(
            "{} worker(s) on the {}",
            runner.workers.len(),
            if runner.workers[0].backend == Backend::Gpu {
                "GPU"
            } else {
                "CPU reference"
            }
        ),
    };
    let signals = Signals::register()?;
    let mut line = ProgressLine::default();
    if let Kind::Threshold(t) = &study.kind {
        eprintln!(
            "study {}: threshold of {} in [{}, {}] to {} ({}), {on}; folder {}",
            study.name,
            study.parameters[t.parameter].name,
            t.bracket[0],
            t.bracket[1],
            t.tolerance,
            t.condition.text,
            root.display()
        );
        let outcome = search(&study, &root, &runner, signals.interrupt(), &mut |p| {
            line.show(p)
        });
        line.end();
        let outcome = outcome?;
        let results = collect(&root)?;
        results.write(&root)?;
        return Ok(match outcome {
            Outcome::Found(a) => {
                println!(
                    "threshold: {} = {} (the condition {:?} flips in [{}, {}]); {} runs \
                     (a grid at that tolerance: {}); {}",
                    a.parameter,
                    a.value,
                    a.condition,
                    a.bracket[0],
                    a.bracket[1],
                    a.runs,
                    a.grid_runs,
                    root.join("threshold.json").display()
                );
                ExitCode::SUCCESS
            }
            Outcome::Interrupted => {
                println!("threshold search interrupted; rerun the same command to continue it");
                ExitCode::from(signals.exit_code().unwrap_or(1))
            }
        });
    }
    let cases = study.cases();
    prepare(&study, &root, &cases)?;
    write_record(&study, &root, &cases)?;
    eprintln!(
        "study {}: {} cases ({}), {on}; folder {}",
        study.name,
        cases.len(),
        study.kind.keyword(),
        root.display()
    );
    let ids: Vec<String> = cases.iter().map(|c| c.id.clone()).collect();
    let ran = run_cases(&root, &ids, &runner, signals.interrupt(), &mut |p| {
        line.show(p)
    });
    line.end();
    ran?;
    finish(&root, signals.exit_code())
}

/// Collects the study in `root`, prints the counts, and gives the exit status.
fn finish(root: &Path, signal: Option<u8>) -> anyhow::Result<ExitCode> {
    let results = collect(root)?;
    results.write(root)?;
    let [completed, failed, interrupted, not_run] = results.counts();
    println!(
        "{}: {completed} completed, {failed} failed, {interrupted} interrupted, {not_run} not \
         run; {}",
        results.record.name,
        root.join("results.csv").display()
    );
    for r in &results.rows {
        if r.state.status == ricochet::study::CaseStatus::Failed {
            println!("  case {} failed: {}", r.id, r.state.message);
        }
    }
    Ok(match signal {
        Some(code) => ExitCode::from(code),
        None if failed + interrupted + not_run > 0 => ExitCode::from(1),
        None => ExitCode::SUCCESS,
    })
}

/// `--slurm`: the scripts written, and submitted unless `--no-submit`; with `--wait`, waits for
/// the collect job.
fn on_slurm(
    study: &Study,
    root: &Path,
    backend: Backend,
    program: PathBuf,
    args: &StudyArgs,
) -> anyhow::Result<ExitCode> {
    if matches!(study.kind, Kind::Threshold(_)) {
        anyhow::bail!(
            "{}: a threshold study runs its rounds one after another; run it here (without \
             --slurm), or make a grid over the bracket for the cluster",
            study.file.display()
        );
    }
    let cases = study.cases();
    prepare(study, root, &cases)?;
    write_record(study, root, &cases)?;
    let mut opts = SlurmOptions::new(program, backend);
    opts.partition = args.partition.clone();
    opts.account = args.account.clone();
    opts.max_parallel = args.max_parallel.map(|k| k as usize);
    opts.gpus_per_task = args.gpus_per_task;
    opts.cpus_per_task = args.cpus_per_task;
    opts.time = args.time.clone();
    opts.signal_seconds = args.signal_seconds;
    opts.extra = args.sbatch.clone();
    let ids: Vec<String> = cases.iter().map(|c| c.id.clone()).collect();
    let scripts = slurm::write_scripts(&study.name, root, &ids, &opts)?;
    println!(
        "slurm: {} and {} ({} array tasks)",
        scripts.array.display(),
        scripts.collect.display(),
        ids.len()
    );
    if args.no_submit {
        println!(
            "not submitted: sbatch --parsable {} and then sbatch \
             --dependency=afterany:<array id> {}",
            scripts.array.display(),
            scripts.collect.display()
        );
        return Ok(ExitCode::SUCCESS);
    }
    let submitted = slurm::submit(&scripts)?;
    println!(
        "submitted: job array {} and collect job {} (after the array)",
        submitted.array, submitted.collect
    );
    if !args.wait {
        return Ok(ExitCode::SUCCESS);
    }
    while slurm::queued(&submitted.collect)? {
        std::thread::sleep(Duration::from_millis(500));
    }
    finish(root, None)
}

/// The progress line on stderr: redrawn in place on a terminal, one line per ended case
/// otherwise.
#[derive(Default)]
struct ProgressLine {
    drawn: bool,
}

impl ProgressLine {
    fn show(&mut self, p: &Progress) {
        use std::io::IsTerminal as _;
        let eta = p
            .eta
            .map(|d| format!(", ETA {}", hms(d)))
            .unwrap_or_default();
        let text = format!(
            "{}/{} done, {} failed, {} running{}{eta}",
            p.done,
            p.total,
            p.failed,
            p.running,
            if p.interrupted > 0 {
                format!(", {} interrupted", p.interrupted)
            } else {
                String::new()
            }
        );
        let mut err = std::io::stderr().lock();
        if err.is_terminal() {
            let _ = write!(err, "\r\x1b[2K{text}");
            self.drawn = true;
        } else if let Some((id, status)) = &p.ended {
            let _ = writeln!(err, "case {id} {status}: {text}");
        }
    }

    fn end(&mut self) {
        if self.drawn {
            eprintln!();
            self.drawn = false;
        }
    }
}

/// `1h02m03s`, `2m03s`, `4s`.
fn hms(d: Duration) -> String {
    let s = d.as_secs();
    match (s / 3600, s / 60 % 60, s % 60) {
        (0, 0, s) => format!("{s}s"),
        (0, m, s) => format!("{m}m{s:02}s"),
        (h, m, s) => format!("{h}h{m:02}m{s:02}s"),
    }
}
