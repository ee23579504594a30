//! What a study's cases gave: each case's status read from its folder ([`case_state`]: its
//! `out/summary.json`, the exit status its runner recorded), its figures read from
//! `summary.json` and `history.csv` ([`figure`]), and the study's table ([`collect`]):
//! `results.csv` and its JSON twin `results.json`, one row per case in the study's order, the same
//! bytes whether the cases ran on this machine or on Slurm. Host-side only, no GPU twin.

use std::fmt;
use std::path::Path;

use super::cases::{case_dir, case_out, read_record, write_file, write_json, Record};
use super::spec::{Figure, Reduce, Source};
use crate::error::{Error, Result};

/// How a case stands.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum CaseStatus {
    /// Its run reached its end time.
    Completed,
    /// Its run went unstable (`summary.json` says why), or it could not run (the exit status and
    /// the last error line of `run.log`).
    Failed,
    /// Its run was stopped (a signal, a time limit, a killed job): a rerun continues it from its
    /// checkpoint.
    Interrupted,
    /// It has not run.
    NotRun,
}

impl CaseStatus {
    /// The word of `results.csv`.
    pub fn word(self) -> &'static str {
        match self {
            CaseStatus::Completed => "completed",
            CaseStatus::Failed => "failed",
            CaseStatus::Interrupted => "interrupted",
            CaseStatus::NotRun => "not run",
        }
    }
}

impl fmt::Display for CaseStatus {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.word())
    }
}

/// A case's status and what it says of itself.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CaseState {
    /// The status.
    pub status: CaseStatus,
    /// `summary.json`'s message, or why the case could not run; empty when completed or not run.
    pub message: String,
    /// Whether its run ended by itself (completed or failed in `summary.json`): a rerun skips it.
    pub finished: bool,
    /// Whether it has a checkpoint to continue from (`out/checkpoint.bin`).
    pub checkpoint: bool,
}

/// The file in a case's folder where its runner records the exit status of the run's last
/// attempt.
pub const EXIT_FILE: &str = "exit";

/// The file in a case's folder that collects the output of its runs.
pub const LOG_FILE: &str = "run.log";

/// The state of the case whose folder is `dir`: from `out/summary.json` when the run ended
/// (completed, failed or interrupted); a summary still "running" is a run that was killed
/// (interrupted, or failed when its runner recorded an exit status other than a signal's); without
/// a summary, failed when its runner recorded an exit status (the scene or the adapter was
/// refused: the last `error:` line of `run.log` says why), else not run.
pub fn case_state(dir: &Path) -> CaseState {
    let out = dir.join("out");
    let checkpoint = out.join("checkpoint.bin").is_file();
    let summary: Option<serde_json::Value> = std::fs::read_to_string(out.join("summary.json"))
        .ok()
        .and_then(|t| serde_json::from_str(&t).ok());
    let exit: Option<i32> = std::fs::read_to_string(dir.join(EXIT_FILE))
        .ok()
        .and_then(|t| t.trim().parse().ok());
    let state = |status, message: String, finished| CaseState {
        status,
        message,
        finished,
        checkpoint,
    };
    let message = summary
        .as_ref()
        .and_then(|s| s["message"].as_str())
        .unwrap_or("")
        .to_string();
    match summary.as_ref().and_then(|s| s["status"].as_str()) {
        Some("completed") => state(CaseStatus::Completed, String::new(), true),
        Some("failed") => state(CaseStatus::Failed, message, true),
        Some("interrupted") => state(CaseStatus::Interrupted, message, false),
        Some(_) => match exit {
            Some(code) if !is_signal(code) => state(
                CaseStatus::Failed,
                format!(
                    "the run stopped without ending (exit status {code}){}",
                    last_error(dir)
                ),
                false,
            ),
            _ => state(
                CaseStatus::Interrupted,
                "the run was stopped before it could end (killed)".into(),
                false,
            ),
        },
        None => match exit {
            Some(code) if is_signal(code) => state(
                CaseStatus::Interrupted,
                format!("stopped before its run started (exit status {code})"),
                false,
            ),
            Some(code) => state(
                CaseStatus::Failed,
                format!(
                    "the run did not start (exit status {code}){}",
                    last_error(dir)
                ),
                false,
            ),
            None => state(CaseStatus::NotRun, String::new(), false),
        },
    }
}

/// Exit statuses of a run stopped by a signal (130, 143: caught; 137: killed).
fn is_signal(code: i32) -> bool {
    matches!(code, 130 | 137 | 143) || code < 0
}

/// `: <the last line of run.log that starts with "error:">`, or nothing.
fn last_error(dir: &Path) -> String {
    std::fs::read_to_string(dir.join(LOG_FILE))
        .ok()
        .and_then(|log| {
            log.lines()
                .rev()
                .find(|l| l.starts_with("error:"))
                .map(|l| format!(": {}", l.trim_start_matches("error:").trim()))
        })
        .unwrap_or_default()
}

/// The value of `figure` for the run whose output folder is `out`; `None` when the run has no
/// such value (an `at` time it did not reach, an empty history).
///
/// # Errors
/// [`Error::Read`] / [`Error::Parse`] when `summary.json` or `history.csv` cannot be read, and
/// [`Error::Parse`] naming the file when it has no such number or column (listing those it has).
pub fn figure(out: &Path, figure: &Figure) -> Result<Option<f64>> {
    match &figure.source {
        Source::Summary(key) => {
            let path = out.join("summary.json");
            let text = std::fs::read_to_string(&path).map_err(|source| Error::Read {
                file: path.clone(),
                source,
            })?;
            let v: serde_json::Value = serde_json::from_str(&text).map_err(|e| Error::Parse {
                file: path.clone(),
                message: e.to_string(),
            })?;
            match &v[key.as_str()] {
                serde_json::Value::Number(n) => Ok(n.as_f64()),
                serde_json::Value::Null => Ok(None),
                _ => Err(Error::Parse {
                    file: path,
                    message: format!(
                        "no number {key:?} (figure {:?}); numbers there: {:?}",
                        figure.name,
                        v.as_object()
                            .map(|o| o
                                .iter()
                                .filter(|(_, x)| x.is_number())
                                .map(|(k, _)| k.as_str())
                                .collect::<Vec<_>>())
                            .unwrap_or_default()
                    ),
                }),
            }
        }
        Source::History { column, reduce } => {
            let path = out.join("history.csv");
            let text = std::fs::read_to_string(&path).map_err(|source| Error::Read {
                file: path.clone(),
                source,
            })?;
            let mut lines = text.lines().filter(|l| !l.starts_with('#'));
            let header: Vec<&str> = lines.next().unwrap_or("").split(',').collect();
            let k = header
                .iter()
                .position(|c| c == column)
                .ok_or_else(|| Error::Parse {
                    file: path.clone(),
                    message: format!(
                        "no column {column:?} (figure {:?}); columns: {header:?}",
                        figure.name
                    ),
                })?;
            let mut rows: Vec<(f64, f64)> = Vec::new();
            for (i, line) in lines.enumerate() {
                let cells: Vec<&str> = line.split(',').collect();
                let number = |j: usize| cells.get(j).and_then(|s| s.trim().parse::<f64>().ok());
                match (number(0), number(k)) {
                    (Some(t), Some(x)) => rows.push((t, x)),
                    _ => {
                        return Err(Error::Parse {
                            file: path.clone(),
                            message: format!("row {} is not numbers: {line:?}", i + 1),
                        })
                    }
                }
            }
            Ok(reduced(&rows, *reduce))
        }
    }
}

/// `rows` (time, value) reduced: the last value, the largest or smallest (NaN rows ignored), or
/// the value at a time, interpolated linearly between the rows around it (`None` outside them).
pub fn reduced(rows: &[(f64, f64)], reduce: Reduce) -> Option<f64> {
    let finite = || rows.iter().map(|r| r.1).filter(|x| !x.is_nan());
    match reduce {
        Reduce::Final => rows.last().map(|r| r.1),
        Reduce::Max => finite().reduce(f64::max),
        Reduce::Min => finite().reduce(f64::min),
        Reduce::At(t) => {
            let i = rows.iter().position(|r| r.0 >= t)?;
            if rows[i].0 == t || i == 0 {
                return (rows[i].0 == t).then_some(rows[i].1);
            }
            let ((t0, x0), (t1, x1)) = (rows[i - 1], rows[i]);
            Some(x0 + (x1 - x0) * (t - t0) / (t1 - t0))
        }
    }
}

/// A number as `results.csv` writes it: the shortest text that reads back to the same f64,
/// without an exponent from 1e-4 to 1e16 (`9.921679510450542`, `0.25`), with one outside
/// (`1.3939309720643633e-14`); `nan`, `inf`, `-inf`.
pub fn number_text(x: f64) -> String {
    if x.is_nan() {
        "nan".into()
    } else if x.is_infinite() {
        if x > 0.0 { "inf" } else { "-inf" }.into()
    } else if x == 0.0 || (1e-4..1e16).contains(&x.abs()) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// A parameter's value as `results.csv` writes it: numbers by [`number_text`], strings as they
/// are, anything else as inline JSON.
pub fn value_text(v: &serde_json::Value) -> String {
    match v {
        serde_json::Value::Number(n) => match (n.as_i64(), n.as_f64()) {
            (Some(i), _) if !n.is_f64() => i.to_string(),
            (_, Some(x)) => number_text(x),
            _ => n.to_string(),
        },
        serde_json::Value::String(s) => s.clone(),
        other => other.to_string(),
    }
}

/// A CSV field: quoted (quotes doubled) when it holds a comma, a quote or a line break.
fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// One case's row.
#[derive(Debug, Clone, PartialEq)]
pub struct Row {
    /// The case's id.
    pub id: String,
    /// Its state.
    pub state: CaseState,
    /// Its parameters' values, in the study's order.
    pub parameters: Vec<serde_json::Value>,
    /// Its figures, in the study's order (`None` unless completed, or when the run has no such
    /// value).
    pub figures: Vec<Option<f64>>,
}

/// A study's table.
#[derive(Debug, Clone, PartialEq)]
pub struct Results {
    /// The study's record (`study.json`).
    pub record: Record,
    /// One row per case, in the study's order.
    pub rows: Vec<Row>,
}

impl Results {
    /// The figure called `name` of every row, with the value of parameter `against`: (x, y) of
    /// the completed cases that have both as numbers, and the other parameters' values as a label
    /// (`v0 = 5, rho = 7850`).
    pub fn series(&self, name: &str, against: &str) -> Option<Vec<(String, f64, f64)>> {
        let f = self.record.figures.iter().position(|g| g.name == name)?;
        let p = self.record.parameters.iter().position(|q| q.0 == against)?;
        Some(
            self.rows
                .iter()
                .filter_map(|r| {
                    let x = r.parameters.get(p)?.as_f64()?;
                    let y = (*r.figures.get(f)?)?;
                    let label = self
                        .record
                        .parameters
                        .iter()
                        .zip(&r.parameters)
                        .enumerate()
                        .filter(|(k, _)| *k != p)
                        .map(|(_, ((n, _), v))| format!("{n} = {}", value_text(v)))
                        .collect::<Vec<_>>()
                        .join(", ");
                    Some((label, x, y))
                })
                .collect(),
        )
    }

    /// `results.csv`: the header `id,status,<parameters>,<figures>`, then one line per case
    /// ([`number_text`] for numbers; an empty field for a figure the case has not).
    pub fn csv(&self) -> String {
        let mut header = vec!["id".to_string(), "status".to_string()];
        header.extend(self.record.parameters.iter().map(|p| p.0.clone()));
        header.extend(self.record.figures.iter().map(|f| f.name.clone()));
        let mut out = header
            .iter()
            .map(|h| csv_field(h))
            .collect::<Vec<_>>()
            .join(",");
        out.push('\n');
        for r in &self.rows {
            let mut cells = vec![r.id.clone(), r.state.status.word().to_string()];
            cells.extend(r.parameters.iter().map(value_text));
            cells.extend(
                r.figures
                    .iter()
                    .map(|f| f.map(number_text).unwrap_or_default()),
            );
            out.push_str(
                &cells
                    .iter()
                    .map(|c| csv_field(c))
                    .collect::<Vec<_>>()
                    .join(","),
            );
            out.push('\n');
        }
        out
    }

    /// `results.json`: the study's name, parameters (name and key) and figures, and per case its
    /// id, status, message, parameters and figures (numbers, or null).
    pub fn json(&self) -> serde_json::Value {
        use serde_json::{json, Map, Value};
        let cases: Vec<Value> = self
            .rows
            .iter()
            .map(|r| {
                let parameters: Map<String, Value> = self
                    .record
                    .parameters
                    .iter()
                    .zip(&r.parameters)
                    .map(|((n, _), v)| (n.clone(), v.clone()))
                    .collect();
                let figures: Map<String, Value> = self
                    .record
                    .figures
                    .iter()
                    .zip(&r.figures)
                    .map(|(f, v)| {
                        (
                            f.name.clone(),
                            v.and_then(serde_json::Number::from_f64)
                                .map_or(Value::Null, Value::Number),
                        )
                    })
                    .collect();
                json!({
                    "id": r.id,
                    "status": r.state.status.word(),
                    "message": r.state.message,
                    "parameters": parameters,
                    "figures": figures,
                })
            })
            .collect();
        json!({
            "study": self.record.name,
            "parameters": self.record.parameters.iter().map(|(n, k)| json!({"name": n, "key": k})).collect::<Vec<_>>(),
            "figures": self.record.figures.iter().map(|f| f.name.clone()).collect::<Vec<_>>(),
            "cases": cases,
        })
    }

    /// Counts of the rows by status: (completed, failed, interrupted, not run).
    pub fn counts(&self) -> [usize; 4] {
        let mut n = [0; 4];
        for r in &self.rows {
            n[r.state.status as usize] += 1;
        }
        n
    }

    /// Writes `root/results.csv` and `root/results.json`.
    ///
    /// # Errors
    /// [`Error::Write`] when a file cannot be written.
    pub fn write(&self, root: &Path) -> Result<()> {
        write_file(&root.join("results.csv"), &self.csv())?;
        write_json(&root.join("results.json"), &self.json())
    }
}

/// The table of the study whose folder is `root`: every case of its `study.json`, its state and
/// (when completed) its figures. Writes nothing ([`Results::write`] does).
///
/// # Errors
/// [`Error::Read`] / [`Error::Parse`] when `root` is not a study's folder or a completed case's
/// `summary.json` or `history.csv` cannot be read or lacks a figure's number or column.
pub fn collect(root: &Path) -> Result<Results> {
    let record = read_record(root)?;
    let mut rows = Vec::with_capacity(record.cases.len());
    for (id, parameters) in &record.cases {
        let state = case_state(&case_dir(root, id));
        let figures = if state.status == CaseStatus::Completed {
            let out = case_out(root, id);
            record
                .figures
                .iter()
                .map(|f| figure(&out, f))
                .collect::<Result<Vec<_>>>()?
        } else {
            vec![None; record.figures.len()]
        };
        rows.push(Row {
            id: id.clone(),
            state,
            parameters: parameters.clone(),
            figures,
        });
    }
    Ok(Results { record, rows })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_read_back_to_the_same_bits() {
        for x in [
            9.921679510450542,
            0.25,
            1.3939309720643633e-14,
            -2.0155402651849665e-17,
            1e300,
            12.0,
            0.0,
            1e-4,
            9.99e-5,
        ] {
            let s = number_text(x);
            assert_eq!(s.parse::<f64>().unwrap().to_bits(), x.to_bits(), "{s}");
        }
        assert_eq!(number_text(12.0), "12");
        assert_eq!(number_text(1.5e-7), "1.5e-7");
        assert_eq!(number_text(f64::NAN), "nan");
    }

    #[test]
    fn reductions_of_a_column() {
        let rows = [(0.0, 1.0), (1.0, 3.0), (2.0, -1.0)];
        assert_eq!(reduced(&rows, Reduce::Final), Some(-1.0));
        assert_eq!(reduced(&rows, Reduce::Max), Some(3.0));
        assert_eq!(reduced(&rows, Reduce::Min), Some(-1.0));
        assert_eq!(reduced(&rows, Reduce::At(0.5)), Some(2.0));
        assert_eq!(reduced(&rows, Reduce::At(2.0)), Some(-1.0));
        assert_eq!(reduced(&rows, Reduce::At(2.5)), None);
        assert_eq!(reduced(&[], Reduce::Final), None);
    }

    #[test]
    fn csv_fields_with_commas_are_quoted() {
        assert_eq!(csv_field("a,b"), "\"a,b\"");
        assert_eq!(csv_field("say \"x\""), "\"say \"\"x\"\"\"");
        assert_eq!(csv_field("plain"), "plain");
    }
}
