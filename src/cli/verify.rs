//! `ricochet verify`: runs the verification suite ([`ricochet::verify::verify`]), its progress
//! lines on stderr, and prints where the report went and each case that missed its bound.

use std::process::ExitCode;

use super::args::{VerifyArgs, VerifyBackend};

/// `ricochet verify`: exit status `EXIT_VERIFY_FAILED` (4) when a case misses its bound.
pub fn verify(args: VerifyArgs) -> anyhow::Result<ExitCode> {
    let VerifyArgs {
        quick,
        backend,
        out,
        cases,
        case,
        adapter,
        jobs,
    } = args;
    let opts = ricochet::verify::Options {
        quick,
        cpu: backend != VerifyBackend::Gpu,
        gpu: backend != VerifyBackend::Cpu,
        cases,
        only: case,
        out,
        adapter: adapter.or_else(|| std::env::var("WGPU_ADAPTER_NAME").ok()),
        jobs: jobs as usize,
    };
    let outcome = ricochet::verify::verify(&opts, |line| eprintln!("{line}"))?;
    println!(
        "verify: {} cases, {} runs, report {}",
        outcome.cases.len(),
        outcome
            .rows
            .iter()
            .map(|r| (&r.case, &r.method, &r.backend, r.level))
            .collect::<std::collections::BTreeSet<_>>()
            .len(),
        opts.out.join("report.md").display()
    );
    if outcome.failures.is_empty() {
        println!("all cases pass their bounds");
        Ok(ExitCode::SUCCESS)
    } else {
        for f in &outcome.failures {
            println!("FAILED {f}");
        }
        Ok(ExitCode::from(crate::EXIT_VERIFY_FAILED))
    }
}
