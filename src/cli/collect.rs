//! `ricochet collect DIR`: a study's folder collected into `DIR/results.csv` and
//! `DIR/results.json` ([`ricochet::study::collect`]), with the counts of its cases by status.

use std::process::ExitCode;

use super::args::CollectArgs;

/// `ricochet collect DIR`: exit status 0 (whatever the cases' statuses: they are in the table).
pub fn collect(args: CollectArgs) -> anyhow::Result<ExitCode> {
    let results = ricochet::study::collect(&args.dir)?;
    results.write(&args.dir)?;
    let [completed, failed, interrupted, not_run] = results.counts();
    println!(
        "{}: {} cases: {completed} completed, {failed} failed, {interrupted} interrupted, \
         {not_run} not run; {} and results.json",
        results.record.name,
        results.rows.len(),
        args.dir.join("results.csv").display()
    );
    Ok(ExitCode::SUCCESS)
}
