//! `ricochet run` and `ricochet run --restart DIR`: the command line's face of the library's run
//! ([`ricochet::run::RunRequest`], which loads the scene or checkpoint, chooses the backend and
//! runs). Here are only what a terminal needs: the restart line and the notices, SIGINT and
//! SIGTERM ([`super::signals`]) and the progress bar ([`super::progress`]) wired to the run, the
//! one-line summary, `--plots`, and the exit status.

use std::process::ExitCode;

use anyhow::Context;

use ricochet::run::{Ending, RunRequest, Start};

use super::args::RunArgs;
use super::plot::draw;
use super::progress::Bar;
use super::signals::Signals;

/// `ricochet run`: exit status 0, `EXIT_FAILED_RUN` (3) for a run that went unstable, or 128 +
/// the signal's number for an interrupted one.
pub fn run(args: RunArgs) -> anyhow::Result<ExitCode> {
    let RunArgs {
        scene,
        backend,
        out,
        end_time,
        adapter,
        plots,
        checkpoint_interval,
        restart,
    } = args;
    let start = match (restart, scene) {
        (Some(dir), _) => Start::Restart(dir),
        (None, Some(path)) => Start::Scene {
            path,
            end_time,
            out,
            checkpoint_interval,
        },
        (None, None) => anyhow::bail!("a scene file or --restart DIR is required"),
    };
    let request = RunRequest {
        start,
        backend: backend.into(),
        adapter,
    };
    let prepared = request.prepare()?;
    if let Some(c) = &prepared.resume {
        println!(
            "restarting {} from its checkpoint at step {}, t = {:e} s ({} backend)",
            prepared.scene.file.display(),
            c.steps,
            c.time,
            c.backend
        );
    }
    let mut solver = prepared.solver(&mut |notice| eprintln!("notice: {notice}"))?;
    let signals = Signals::register()?;
    let bar = Bar::on_stderr();
    let file = prepared.scene.file.clone();
    let outcome = prepared
        .run(
            solver.as_mut(),
            signals.interrupt(),
            &mut |t, end, steps| bar.tick(t, end, steps),
        )
        .with_context(|| format!("running {}", file.display()))?;
    bar.finish();
    let out = &outcome.result.out_dir;
    let s = &outcome.result.summary;
    println!(
        "{}: {} on {} ({}): {} steps to t = {:.4e} s in {:.2} s ({:.3e} element-cycles/s), max energy error {:.2e}; outputs in {}",
        s.scene,
        s.status,
        s.backend,
        s.adapter,
        s.steps,
        s.end_time,
        s.wall_seconds,
        s.element_cycles_per_second,
        s.max_energy_error,
        out.display()
    );
    if let Some(n) = s.eroded_inverted {
        println!(
            "erosion: {} elements eroded, {n} of them about to invert (run.erosion.inverted)",
            s.eroded_elements.unwrap_or(0)
        );
    }
    if let Some(n) = s.eroded_small_step {
        println!(
            "erosion: {} elements eroded, {n} of them for a stable step below \
             run.erosion.min_time_step",
            s.eroded_elements.unwrap_or(0)
        );
    }
    if let Some(t) = s.max_temperature {
        println!("thermal softening: highest element temperature {t:.1} K at the end");
    }
    if s.contact_searches > 0 {
        println!(
            "contact: {} broad-phase searches in {} steps",
            s.contact_searches, s.steps
        );
        if s.contact_penalty_bounded > 0 {
            println!(
                "contact: {} penalty impulses bounded by the perfectly plastic impulse \
                 (springs stiff for the step, omega dt > 1, as in an impact's first steps): \
                 the spring energy they held is lost (in contact_energy)",
                s.contact_penalty_bounded
            );
        }
        if s.steps >= 20 && 2 * s.contact_searches > s.steps {
            eprintln!(
                "warning: contact nodes moved more than half the search margin in most steps, \
                 so the search ran (almost) every step instead of every few: the margin is half \
                 the shortest contact edge; fast impacts on fine surfaces cost a search per step"
            );
        }
    }
    if let Some(w) = ricochet::run::convergence_warning(
        &s.backend,
        s.steps,
        s.contact_unconverged,
        s.contact_residual_max,
    ) {
        eprintln!("warning: {w}");
    }
    let failed = match &outcome.ending {
        Ending::Interrupted(_) => {
            eprintln!(
                "{}; history, fields and summary.json are complete up to there",
                s.message
            );
            return Ok(ExitCode::from(signals.exit_code().unwrap_or(1)));
        }
        Ending::Failed(message) => {
            eprintln!("error: {message}");
            true
        }
        Ending::Completed => false,
    };
    if plots {
        draw(out, &ricochet::plot::PlotOptions::default())?;
    }
    Ok(ExitCode::from(if failed {
        crate::EXIT_FAILED_RUN
    } else {
        0
    }))
}
