//! The threshold search of a study (`kind = "threshold"`): the value of one parameter at which a
//! condition on a collected figure flips, found by k-section: the two ends of the bracket first,
//! then each round `k` points evenly inside the bracket, run in parallel, the bracket narrowed to
//! the two neighbours between which the condition flips, until it is at most `tolerance` wide
//! (bisection when k = 1). Its cases are ordinary cases of the study's folder, found again by
//! their value on a rerun (a rerun recomputes nothing that completed). The answer goes to
//! `DIR/threshold.json`. Nothing here prints. Host-side only, no GPU twin.

use std::path::Path;

use serde::Serialize;

use super::cases::{case_dir, case_out, prepare, read_record, write_json, write_record, Case};
use super::collect::{case_state, figure, CaseStatus};
use super::local::{run_cases, Progress, Runner};
use super::spec::{Kind, Study, Threshold};
use crate::error::{Error, Result};
use crate::run::Interrupt;

/// One point of the search.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Point {
    /// The case.
    pub id: String,
    /// The parameter's value.
    pub value: f64,
    /// The figure of the condition.
    pub figure: f64,
    /// Whether the condition holds there.
    pub holds: bool,
}

/// What a threshold search found (`DIR/threshold.json`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Answer {
    /// The parameter searched (its name).
    pub parameter: String,
    /// The scene key it overrides.
    pub key: String,
    /// The condition.
    pub condition: String,
    /// The threshold: the middle of the final bracket.
    pub value: f64,
    /// The final bracket: the condition flips between its ends.
    pub bracket: [f64; 2],
    /// Whether the condition holds at the lower end of the bracket (and not at the upper one), or
    /// the reverse.
    pub holds_below: bool,
    /// The tolerance asked for (the final bracket is at most this wide).
    pub tolerance: f64,
    /// Points run per round.
    pub points_per_round: usize,
    /// Rounds after the two ends.
    pub rounds: usize,
    /// Cases run (the two ends included).
    pub runs: usize,
    /// Cases a grid would need to resolve the threshold to the same tolerance:
    /// ceil(width / tolerance) + 1.
    pub grid_runs: usize,
    /// Every point, in the order the search ran them.
    pub points: Vec<Point>,
}

/// How a search ended.
#[derive(Debug, Clone, PartialEq)]
pub enum Outcome {
    /// It found the threshold.
    Found(Answer),
    /// An interrupt stopped it; a rerun continues it.
    Interrupted,
}

/// The points of a round: `k` values evenly inside (lo, hi).
pub fn round_points(lo: f64, hi: f64, k: usize) -> Vec<f64> {
    (1..=k)
        .map(|j| lo + (hi - lo) * j as f64 / (k + 1) as f64)
        .collect()
}

/// The bracket after a round: `ends` (lo, hi) with the condition `holds_lo` at lo, and the
/// round's points with whether the condition holds at each: the neighbours between which it first
/// differs from `holds_lo`.
pub fn narrow(ends: [f64; 2], holds_lo: bool, points: &[(f64, bool)]) -> [f64; 2] {
    let mut lo = ends[0];
    for &(x, holds) in points {
        if holds != holds_lo {
            return [lo, x];
        }
        lo = x;
    }
    [lo, ends[1]]
}

/// Rounds of `k` points that take a bracket of `width` to at most `tolerance`.
pub fn rounds_needed(width: f64, tolerance: f64, k: usize) -> usize {
    let mut w = width;
    let mut n = 0;
    while w > tolerance && n < 200 {
        w /= (k + 1) as f64;
        n += 1;
    }
    n
}

/// Runs the threshold search of `study` (of kind threshold) into the folder `root` with
/// `runner`: the rounds one after the other, each round's cases in parallel on the workers.
/// Cases already completed in `root` with the same value are reused. Writes `root/study.json`
/// as the cases accumulate, and `root/threshold.json` at the end.
///
/// # Errors
/// [`Error::Study`] when the condition is the same at both ends of the bracket, or a case the
/// search needs did not complete (it cannot tell on which side the case lies); as
/// [`prepare`] and [`run_cases`].
pub fn search(
    study: &Study,
    root: &Path,
    runner: &Runner,
    interrupt: &Interrupt,
    progress: &mut dyn FnMut(&Progress),
) -> Result<Outcome> {
    let Kind::Threshold(t) = &study.kind else {
        return Err(Error::Study(format!(
            "{}: not a threshold study",
            study.file.display()
        )));
    };
    let width = study.id_width();
    // The cases of an earlier run into this folder, by their value.
    let mut cases: Vec<Case> = Vec::new();
    if let Ok(record) = read_record(root) {
        for (id, values) in record.cases {
            let Some(x) = values.get(t.parameter).and_then(|v| v.as_f64()) else {
                continue;
            };
            cases.push(study.case_at(cases.len(), width, t.parameter, x));
            if cases.last().is_some_and(|c| c.id != id) {
                // Not this study's numbering: start afresh (prepare refuses a changed folder).
                cases.clear();
                break;
            }
        }
    }
    let k = t
        .points_per_round
        .unwrap_or(runner.workers.len())
        .clamp(1, 64);
    let mut points: Vec<Point> = Vec::new();
    let mut run = |xs: &[f64], cases: &mut Vec<Case>| -> Result<Option<Vec<Point>>> {
        let mut round = Vec::with_capacity(xs.len());
        for &x in xs {
            let case = match cases
                .iter()
                .find(|c| c.values[t.parameter].as_float().map(f64::to_bits) == Some(x.to_bits()))
            {
                Some(c) => c.clone(),
                None => {
                    let c = study.case_at(cases.len(), width, t.parameter, x);
                    cases.push(c.clone());
                    c
                }
            };
            round.push(case);
        }
        prepare(study, root, &round)?;
        write_record(study, root, cases)?;
        let ids: Vec<String> = round.iter().map(|c| c.id.clone()).collect();
        run_cases(root, &ids, runner, interrupt, progress)?;
        let mut out = Vec::with_capacity(round.len());
        for (case, &x) in round.iter().zip(xs) {
            let state = case_state(&case_dir(root, &case.id));
            match state.status {
                CaseStatus::Completed => {}
                CaseStatus::Interrupted | CaseStatus::NotRun if interrupt.caught().is_some() => {
                    return Ok(None)
                }
                other => {
                    return Err(Error::Study(format!(
                        "threshold search: case {} ({} = {x}) {other}{}: the search cannot tell \
                         on which side of the threshold it lies (narrow the bracket, or fix the \
                         case)",
                        case.id,
                        study.parameters[t.parameter].name,
                        if state.message.is_empty() {
                            String::new()
                        } else {
                            format!(" ({})", state.message)
                        }
                    )))
                }
            }
            out.push(point(study, t, root, case, x)?);
        }
        Ok(Some(out))
    };
    let Some(ends) = run(&t.bracket, &mut cases)? else {
        return Ok(Outcome::Interrupted);
    };
    let (holds_lo, holds_hi) = (ends[0].holds, ends[1].holds);
    points.extend(ends);
    if holds_lo == holds_hi {
        return Err(Error::Study(format!(
            "threshold search: the condition {:?} {} at both ends of the bracket [{}, {}] \
             ({} = {} and {}): no threshold inside it",
            t.condition.text,
            if holds_lo { "holds" } else { "fails" },
            t.bracket[0],
            t.bracket[1],
            t.condition.figure,
            points[0].figure,
            points[1].figure
        )));
    }
    let mut bracket = t.bracket;
    let mut rounds = 0;
    while bracket[1] - bracket[0] > t.tolerance {
        let xs = round_points(bracket[0], bracket[1], k);
        let Some(round) = run(&xs, &mut cases)? else {
            return Ok(Outcome::Interrupted);
        };
        let pairs: Vec<(f64, bool)> = round.iter().map(|p| (p.value, p.holds)).collect();
        bracket = narrow(bracket, holds_lo, &pairs);
        points.extend(round);
        rounds += 1;
    }
    let p = &study.parameters[t.parameter];
    let span = t.bracket[1] - t.bracket[0];
    let answer = Answer {
        parameter: p.name.clone(),
        key: p.key.text.clone(),
        condition: t.condition.text.clone(),
        value: 0.5 * (bracket[0] + bracket[1]),
        bracket,
        holds_below: holds_lo,
        tolerance: t.tolerance,
        points_per_round: k,
        rounds,
        runs: points.len(),
        grid_runs: (span / t.tolerance).ceil() as usize + 1,
        points,
    };
    write_json(&root.join("threshold.json"), &answer)?;
    Ok(Outcome::Found(answer))
}

/// The search's point of the completed case `case` at `x`.
fn point(study: &Study, t: &Threshold, root: &Path, case: &Case, x: f64) -> Result<Point> {
    let f = study
        .figures
        .iter()
        .find(|f| f.name == t.condition.figure)
        .ok_or_else(|| Error::Study(format!("no figure {:?}", t.condition.figure)))?;
    let value = figure(&case_out(root, &case.id), f)?.ok_or_else(|| {
        Error::Study(format!(
            "threshold search: case {} has no value of {:?}",
            case.id, f.name
        ))
    })?;
    Ok(Point {
        id: case.id.clone(),
        value: x,
        figure: value,
        holds: t.condition.holds(value),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The search's arithmetic on a condition known in closed form (x >= 6.3847).
    #[test]
    fn k_section_brackets_a_known_threshold_in_fewer_runs_than_a_grid() {
        let threshold = 6.3847;
        for k in [1, 2, 4] {
            let mut bracket = [1.0, 20.0];
            let mut runs = 2;
            while bracket[1] - bracket[0] > 0.01 {
                let xs = round_points(bracket[0], bracket[1], k);
                runs += xs.len();
                let pairs: Vec<(f64, bool)> = xs.iter().map(|&x| (x, x >= threshold)).collect();
                bracket = narrow(bracket, false, &pairs);
            }
            assert!(
                bracket[0] < threshold && threshold <= bracket[1],
                "{bracket:?}"
            );
            assert!(bracket[1] - bracket[0] <= 0.01);
            assert_eq!(runs, 2 + k * rounds_needed(19.0, 0.01, k));
            assert!(runs < 1901, "{runs}");
        }
        assert_eq!(rounds_needed(19.0, 0.01, 1), 11);
    }
}
