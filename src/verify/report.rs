//! The verification outputs: `results.csv` (one line per metric per run) and `report.md` (per
//! case: the reference, the measured values per level, the observed convergence orders, and the
//! verdict against the case's bounds).

use std::fmt::Write as _;
use std::path::Path;

use super::case::BoundValue;
use super::{Options, Outcome, Row};
use crate::error::{Error, Result};

fn write(path: &Path, text: &str) -> Result<()> {
    std::fs::write(path, text).map_err(|source| Error::Write {
        path: path.to_path_buf(),
        source,
    })
}

/// Writes `results.csv`: `case,method,backend,level,elements,steps,wall_seconds,metric,reference,
/// value,relative_error`, then `size,element_cycles,energy_error,bound,pass`.
///
/// # Errors
/// [`Error::Write`].
pub fn write_csv(path: &Path, rows: &[Row]) -> Result<()> {
    let mut s = String::from(
        "case,method,backend,level,elements,steps,wall_seconds,metric,reference,value,\
         relative_error,size,element_cycles,energy_error,bound,pass\n",
    );
    for r in rows {
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{:.6},{},{:e},{:e},{:e},{},{},{:e},{},{}",
            r.case,
            r.method,
            r.backend,
            r.level,
            r.elements,
            r.steps,
            r.wall_seconds,
            r.metric,
            r.reference,
            r.value,
            r.relative_error,
            r.size,
            r.elements as u64 * r.steps,
            r.energy_error,
            r.bound.map_or(String::new(), |b| format!("{b:e}")),
            r.pass.map_or(String::new(), |p| p.to_string()),
        );
    }
    write(path, &s)
}

/// Observed convergence order between two levels: ln(e0 / e1) / ln(s1 / s0).
pub fn order(e0: f64, e1: f64, s0: f64, s1: f64) -> Option<f64> {
    (e0 > 0.0 && e1 > 0.0 && s1 != s0 && e0.is_finite() && e1.is_finite())
        .then(|| (e0 / e1).ln() / (s1 / s0).ln())
}

/// Writes `report.md`.
///
/// # Errors
/// [`Error::Write`].
pub fn write_markdown(path: &Path, out: &Outcome, opts: &Options) -> Result<()> {
    let mut s = String::new();
    let _ = writeln!(s, "# ricochet verification report\n");
    let mut backend = Vec::new();
    if opts.cpu {
        backend.push("cpu");
    }
    if opts.gpu {
        backend.push("gpu");
    }
    let backend = if backend.len() == 2 {
        "both"
    } else {
        backend.first().copied().unwrap_or("cpu")
    };
    let _ = writeln!(
        s,
        "Made by `ricochet verify{} --backend {backend} --out {}`{}.\n",
        if opts.quick { " --quick" } else { "" },
        opts.out.display(),
        if opts.only.is_empty() {
            String::new()
        } else {
            format!(" (cases {})", opts.only.join(", "))
        }
    );
    for (b, name) in &out.adapters {
        let _ = writeln!(s, "- `{b}`: {name}");
    }
    if opts.jobs > 1 {
        let _ = writeln!(
            s,
            "\nThe runs were made {} at a time (`--jobs {}`): each wall time was measured while \
             others ran, so the times are longer than those of runs made one at a time.",
            opts.jobs, opts.jobs
        );
    }
    let _ = writeln!(
        s,
        "\nEach case runs a refinement ladder; the error of a metric is |value - reference| / scale \
         (scale: the reference, or the case's stated scale). A case passes when every judged \
         error (the finest level, or every level where the case says so) is within its bound. \
         Wall time is the time loop's (no pipeline compilation, no output setup). Observed order: \
         ln(e_i-1 / e_i) / ln(size_i / size_i-1).\n"
    );
    if !out.full_only.is_empty() {
        let _ = writeln!(
            s,
            "Not run here (no quick ladder; `ricochet verify --case NAME` runs its full ladder):\n"
        );
        for (name, title) in &out.full_only {
            let _ = writeln!(s, "- `{name}`: {title}");
        }
        s.push('\n');
    }
    if out.failures.is_empty() {
        let _ = writeln!(s, "**All {} cases pass their bounds.**\n", out.cases.len());
    } else {
        let _ = writeln!(s, "**{} bound(s) missed:**\n", out.failures.len());
        for f in &out.failures {
            let _ = writeln!(s, "- {f}");
        }
        s.push('\n');
    }
    for case in &out.cases {
        let name = &case.case.name;
        let _ = writeln!(s, "## {name}: {}\n", case.case.title);
        let _ = writeln!(s, "Reference: {}.\n", case.case.reference);
        let _ = writeln!(s, "![{name}]({name}.svg)\n");
        let _ = writeln!(
            s,
            "| metric | reference | scale | bound | judged |\n| --- | --- | --- | --- | --- |"
        );
        for m in &case.metric {
            let bound = m
                .bound
                .as_ref()
                .map_or("(reported only)".to_string(), |b| b.to_string());
            let number = |v: &BoundValue| match v {
                BoundValue::Number(x) => format!("{x:.6e}"),
                BoundValue::Expr(e) => format!("`{e}`"),
            };
            let _ = writeln!(
                s,
                "| {} | {} | {} | {bound} | {}{} |",
                m.name,
                number(&m.reference),
                m.scale.as_ref().map_or("reference".to_string(), number),
                if m.every_level {
                    "every level"
                } else {
                    "finest level"
                },
                m.methods
                    .as_ref()
                    .map_or(String::new(), |v| format!(" ({} only)", v.join(", ")))
            );
        }
        s.push('\n');
        let rows: Vec<&Row> = out.rows.iter().filter(|r| &r.case == name).collect();
        let mut groups: Vec<(String, String)> = Vec::new();
        for r in &rows {
            let key = (r.method.clone(), r.backend.clone());
            if !groups.contains(&key) {
                groups.push(key);
            }
        }
        for (method, backend) in groups {
            let g: Vec<&&Row> = rows
                .iter()
                .filter(|r| r.method == method && r.backend == backend)
                .collect();
            let metrics: Vec<String> = {
                let mut v: Vec<String> = Vec::new();
                for r in &g {
                    if !v.contains(&r.metric) {
                        v.push(r.metric.clone());
                    }
                }
                v
            };
            let mut levels: Vec<usize> = g.iter().map(|r| r.level).collect();
            levels.dedup();
            let _ = writeln!(s, "### {method}, {backend}\n");
            let _ = write!(
                s,
                "| {} | elements | steps | wall s | energy error |",
                case.case.size
            );
            for m in &metrics {
                let _ = write!(s, " {m} | error | order |");
            }
            s.push('\n');
            let _ = write!(s, "| ---: | ---: | ---: | ---: | ---: |");
            for _ in &metrics {
                s.push_str(" ---: | ---: | ---: |");
            }
            s.push('\n');
            let mut prev: Vec<Option<(f64, f64)>> = vec![None; metrics.len()];
            for l in levels {
                let at: Vec<&&&Row> = g.iter().filter(|r| r.level == l).collect();
                let Some(first) = at.first() else { continue };
                // The level's other variables (a striking velocity), beside its size.
                let ladder = if opts.quick {
                    &case.levels.quick
                } else {
                    &case.levels.full
                };
                let others: Vec<String> = ladder
                    .get(l)
                    .map(|vars| {
                        vars.iter()
                            .filter(|(k, _)| **k != case.case.size)
                            .map(|(k, v)| format!("{k} = {v}"))
                            .collect()
                    })
                    .unwrap_or_default();
                let others = if others.is_empty() {
                    String::new()
                } else {
                    format!(" ({})", others.join(", "))
                };
                let _ = write!(
                    s,
                    "| {}{others} | {} | {} | {:.3} | {:.1e} |",
                    first.size, first.elements, first.steps, first.wall_seconds, first.energy_error
                );
                for (k, m) in metrics.iter().enumerate() {
                    match at.iter().find(|r| &r.metric == m) {
                        Some(r) => {
                            let mark = match r.pass {
                                Some(true) => " ✓",
                                Some(false) => " ✗",
                                None => "",
                            };
                            let ord = prev[k]
                                .and_then(|(e0, s0)| order(e0, r.relative_error, s0, r.size))
                                .map_or(String::new(), |p| format!("{p:.2}"));
                            // A reference that depends on the level's variables: beside the
                            // value.
                            let reference = case
                                .metric
                                .iter()
                                .find(|x| &x.name == m)
                                .filter(|x| matches!(x.reference, BoundValue::Expr(_)))
                                .map_or(String::new(), |_| {
                                    format!(" (reference {:.4e})", r.reference)
                                });
                            let _ = write!(
                                s,
                                " {:.6e}{reference} | {:.2e}{mark} | {ord} |",
                                r.value, r.relative_error
                            );
                            prev[k] = Some((r.relative_error, r.size));
                        }
                        None => s.push_str(" | | |"),
                    }
                }
                s.push('\n');
            }
            let notes: Vec<String> = g
                .iter()
                .filter(|r| !r.note.is_empty())
                .map(|r| format!("- level {} {}: {}", r.level, r.metric, r.note))
                .collect();
            if !notes.is_empty() {
                s.push('\n');
                s.push_str(&notes.join("\n"));
                s.push('\n');
            }
            s.push('\n');
        }
    }
    write(path, &s)
}
