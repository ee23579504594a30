//! The `ricochet` command line: `run`, `plot`, `check`, `bench`, `verify`, `study` and `collect`. The arguments are in
//! `cli/args.rs` and each command's body in its own module under `cli/`; what a run does (load,
//! choose the backend, run, checkpoint, restart, stop) is the library's, [`ricochet::run`].

mod cli;

use std::process::ExitCode;

use clap::Parser;

use cli::args::{Cli, Command};

/// Exit status for bad input.
const EXIT_INPUT: u8 = 2;
/// Exit status for a run that went unstable.
const EXIT_FAILED_RUN: u8 = 3;
/// Exit status of `verify` when a case misses its bound.
const EXIT_VERIFY_FAILED: u8 = 4;

fn main() -> ExitCode {
    // Output piped into a reader that stops early (`ricochet check scene.toml | head`): end
    // quietly on SIGPIPE, as command-line tools do, instead of panicking on the failed print.
    #[cfg(unix)]
    // SAFETY: restoring the default action of one signal before any thread starts.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    let args = Cli::parse();
    match dispatch(args) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e}");
            for cause in e.chain().skip(1) {
                eprintln!("  caused by: {cause}");
            }
            let input = e
                .downcast_ref::<ricochet::Error>()
                .map(|r| {
                    matches!(
                        r,
                        ricochet::Error::Read { .. }
                            | ricochet::Error::Parse { .. }
                            | ricochet::Error::Invalid { .. }
                            | ricochet::Error::Checkpoint(_)
                            | ricochet::Error::InUse { .. }
                    )
                })
                .unwrap_or(false);
            ExitCode::from(if input { EXIT_INPUT } else { 1 })
        }
    }
}

/// Hands the command to its module.
fn dispatch(args: Cli) -> anyhow::Result<ExitCode> {
    match args.command {
        Command::Run(a) => cli::run::run(a),
        Command::Plot(a) => cli::plot::plot(a),
        Command::Check(a) => cli::check::check(a),
        Command::Bench(a) => cli::bench::bench(a),
        Command::Verify(a) => cli::verify::verify(a),
        Command::Study(a) => cli::study::study(a),
        Command::Collect(a) => cli::collect::collect(a),
    }
}
