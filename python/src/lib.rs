//! The Python binding of ricochet: the extension module `ricochet._native`, which the pure-Python
//! package `python/ricochet/` wraps (its `Scene`, `Result`, `read` and `study`). Everything here
//! calls the library as the command line does, so that a scene, an override, an error message,
//! a run's outputs and a study's table are the same from Python and from `ricochet`:
//!
//! - `scene.rs`: scenes loaded, built from text or a dict, overridden by key path
//!   ([`ricochet::scene::overrides`]), checked into a plan, and their mesh as numpy arrays;
//! - `run.rs`: a run in-process ([`ricochet::run::Prepared::run`]) with the GIL released, Ctrl-C
//!   read between batches of steps, and restarts;
//! - `study.rs`: a study's cases prepared ([`ricochet::study::cases`]) and its table collected
//!   ([`ricochet::study::collect`]);
//! - `convert.rs`: Python values to and from TOML and JSON, and the library's errors as Python
//!   exceptions.
//!
//! No GPU twin: the GPU is reached through the library's own solver choice.

use pyo3::prelude::*;

mod convert;
mod run;
mod scene;
mod study;

/// The module `ricochet._native`.
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("SceneError", py.get_type::<convert::SceneError>())?;
    m.add("RicochetError", py.get_type::<convert::RicochetError>())?;
    m.add_class::<scene::SceneCore>()?;
    m.add_function(wrap_pyfunction!(run::restart, m)?)?;
    m.add_function(wrap_pyfunction!(study::study_prepare, m)?)?;
    m.add_function(wrap_pyfunction!(study::case_action, m)?)?;
    m.add_function(wrap_pyfunction!(study::case_finished, m)?)?;
    m.add_function(wrap_pyfunction!(study::collect, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
