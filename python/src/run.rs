//! A run in-process, as `ricochet run` makes it ([`ricochet::run::Prepared`]): the model, the
//! solver and the time loop built and run with the GIL released, so that other Python threads go
//! on. Between batches of steps the loop takes the GIL back for a moment to run Python's signal
//! handlers ([`Python::check_signals`]: Ctrl-C) and the progress callback; a Ctrl-C sets the run's
//! [`Interrupt`] flag `SIGINT`, so the run stops after the batch under way with the summary
//! `interrupted by SIGINT at ...`, complete outputs and a checkpoint when the scene writes them,
//! as the command line's run does.

use std::path::PathBuf;
use std::sync::atomic::Ordering;

use pyo3::exceptions::PyKeyboardInterrupt;
use pyo3::prelude::*;
use pyo3::types::PyTuple;

use ricochet::checkpoint::Checkpointing;
use ricochet::run::{Backend, Interrupt, Prepared, RunRequest};

use crate::convert::error;
use crate::scene::SceneCore;

/// `backend` (`"auto"`, `"cpu"` or `"gpu"`) as the library's.
fn backend(word: &str) -> PyResult<Backend> {
    match word {
        "auto" => Ok(Backend::Auto),
        "cpu" => Ok(Backend::Cpu),
        "gpu" => Ok(Backend::Gpu),
        other => Err(pyo3::exceptions::PyValueError::new_err(format!(
            "backend must be \"auto\", \"cpu\" or \"gpu\", not {other:?}"
        ))),
    }
}

/// Runs the scene of `core` (its text with the overrides applied is `text`, kept in checkpoints)
/// into `out` (`out/<scene name>` by default).
pub fn run_scene<'py>(
    py: Python<'py>,
    core: &SceneCore,
    text: String,
    backend_word: &str,
    out: Option<PathBuf>,
    adapter: Option<String>,
    progress: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyAny>> {
    let backend = backend(backend_word)?;
    let scene = core.scene.clone();
    let path = core.path.clone();
    let prepared = py
        .detach(move || -> Result<Prepared, ricochet::Error> {
            let (model, plan) = ricochet::run::model_and_plan(&scene)?;
            let out = out.unwrap_or_else(|| PathBuf::from("out").join(&scene.name));
            // As `RunRequest::prepare` does for a scene file (no `--checkpoint-interval`).
            let checkpointing = scene.run.checkpoint_interval.map(|t| Checkpointing {
                interval: t,
                scene_path: path,
                scene_text: text,
                end_time_override: None,
            });
            Ok(Prepared {
                scene,
                model,
                plan,
                out,
                checkpointing,
                resume: None,
                backend,
                adapter,
            })
        })
        .map_err(|e| error(py, e))?;
    drive(py, prepared, progress)
}

/// Continues the run whose output folder `out` holds a checkpoint, as `ricochet run --restart
/// OUT` does (on the checkpoint's backend).
#[pyfunction]
#[pyo3(signature = (out, adapter=None, progress=None))]
pub fn restart<'py>(
    py: Python<'py>,
    out: PathBuf,
    adapter: Option<String>,
    progress: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyAny>> {
    let mut request = RunRequest::restart(out);
    request.adapter = adapter;
    let prepared = py
        .detach(move || request.prepare())
        .map_err(|e| error(py, e))?;
    drive(py, prepared, progress)
}

/// Builds the solver of `prepared` and runs it with the GIL released; returns (status, message,
/// output folder, notices, the exception the progress callback raised or None).
fn drive<'py>(
    py: Python<'py>,
    prepared: Prepared,
    progress: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyAny>> {
    let mut interrupt = Interrupt::new();
    let sigint = interrupt.flag("SIGINT");
    let raised = interrupt.flag("an exception in the progress callback");
    let mut notices: Vec<String> = Vec::new();
    let mut callback_error: Option<PyErr> = None;
    let outcome = py.detach(|| {
        let mut solver = prepared.solver(&mut |n| notices.push(n.to_string()))?;
        prepared.run(solver.as_mut(), &interrupt, &mut |t, end, steps| {
            Python::attach(|py| {
                if let Err(e) = py.check_signals() {
                    if e.is_instance_of::<PyKeyboardInterrupt>(py) {
                        sigint.store(true, Ordering::Relaxed);
                    } else {
                        callback_error.get_or_insert(e);
                        raised.store(true, Ordering::Relaxed);
                    }
                }
                if let Some(cb) = &progress {
                    if let Err(e) = cb.call1(py, (t, end, steps)) {
                        if e.is_instance_of::<PyKeyboardInterrupt>(py) {
                            sigint.store(true, Ordering::Relaxed);
                        } else {
                            callback_error.get_or_insert(e);
                            raised.store(true, Ordering::Relaxed);
                        }
                    }
                }
            });
        })
    });
    let outcome = outcome.map_err(|e| error(py, e))?;
    let s = &outcome.result.summary;
    let callback_error = callback_error.map(|e| e.into_value(py).into_any());
    Ok(PyTuple::new(
        py,
        [
            s.status.clone().into_pyobject(py)?.into_any(),
            s.message.clone().into_pyobject(py)?.into_any(),
            outcome.result.out_dir.clone().into_pyobject(py)?.into_any(),
            notices.into_pyobject(py)?.into_any(),
            match callback_error {
                Some(e) => e.into_bound(py),
                None => py.None().into_bound(py),
            },
        ],
    )?
    .into_any())
}
