//! A study from Python (`ricochet.study`): its cases prepared by the study library code
//! ([`ricochet::study::cases::prepare`] and [`ricochet::study::cases::write_record`], as `ricochet
//! study` does: each case's materialised `scene.toml` and `manifest.json` under
//! `DIR/cases/<id>/`), what a worker does with a case ([`ricochet::study::local::action`]), and
//! the table collected by the code of `ricochet collect` ([`ricochet::study::collect`]). The
//! cases themselves run on a Python executor (`python/ricochet/_study.py`).

use std::path::PathBuf;

use pyo3::prelude::*;

use ricochet::study::cases::{case_dir, prepare, write_record};
use ricochet::study::local::{action, Action};
use ricochet::study::{Kind, Study};

use crate::convert::error;

/// Reads and checks the study text `text` (of the study file `path`), writes its cases under
/// `root` and its record `root/study.json`; returns (the study's name, its backend, the cases'
/// ids in order).
#[pyfunction]
pub fn study_prepare(
    py: Python<'_>,
    text: &str,
    path: PathBuf,
    root: PathBuf,
) -> PyResult<(String, String, Vec<String>)> {
    let study = Study::parse(text, &path).map_err(|e| error(py, e))?;
    if matches!(study.kind, Kind::Threshold(_)) {
        return Err(pyo3::exceptions::PyValueError::new_err(
            "a threshold study (kind = \"threshold\") runs through `ricochet study` only: its \
             rounds depend on the figures of the last",
        ));
    }
    let cases = study.cases();
    py.detach(|| {
        prepare(&study, &root, &cases)?;
        write_record(&study, &root, &cases)
    })
    .map_err(|e| error(py, e))?;
    let backend = match study.backend {
        ricochet::run::Backend::Auto => "auto",
        ricochet::run::Backend::Cpu => "cpu",
        ricochet::run::Backend::Gpu => "gpu",
    };
    Ok((
        study.name,
        backend.to_string(),
        cases.into_iter().map(|c| c.id).collect(),
    ))
}

/// What a worker does with case `id` of the study folder `root`: `"skip"` (its run ended),
/// `"restart"` (continue from its checkpoint) or `"fresh"` (run from the start, its old output
/// removed first).
#[pyfunction]
pub fn case_action(root: PathBuf, id: &str) -> &'static str {
    match action(&case_dir(&root, id)) {
        Action::Skip(_) => "skip",
        Action::Restart => "restart",
        Action::Fresh => "fresh",
    }
}

/// The status word of case `id` of the study folder `root` (`completed`, `failed`,
/// `interrupted`, `not run`), as `results.csv` gives it.
#[pyfunction]
pub fn case_finished(root: PathBuf, id: &str) -> &'static str {
    ricochet::study::collect::case_state(&case_dir(&root, id))
        .status
        .word()
}

/// Collects the study folder `root` as `ricochet collect` does, writes `results.csv` and
/// `results.json` there, and returns the CSV text.
#[pyfunction]
pub fn collect(py: Python<'_>, root: PathBuf) -> PyResult<String> {
    py.detach(|| {
        let results = ricochet::study::collect(&root)?;
        results.write(&root)?;
        Ok(results.csv())
    })
    .map_err(|e: ricochet::Error| error(py, e))
}
