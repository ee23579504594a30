//! `ricochet._native.SceneCore`: a scene as the Python `ricochet.Scene` holds it: the text it was
//! read from, the file it names (for messages, its name and relative mesh paths), the overrides
//! set on it by key path, and the scene they validate to. Every change goes through
//! [`Scene::parse_with`], the code a study's cases go through, so a refused value raises the
//! same message as `ricochet check` (exit 2). Also the plan of `ricochet check` as a dict, and
//! the model's mesh as numpy arrays handed over without a copy.

use std::path::PathBuf;

use numpy::{PyArray1, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use serde_json::json;

use ricochet::contact::ContactSet;
use ricochet::scene::overrides::{self, shown, KeyPath, Override};
use ricochet::scene::Scene;
use ricochet::step::cpu::CpuSolver;

use crate::convert::{error, from_json, from_toml, to_toml};

/// A scene and the overrides set on it (the Rust side of `ricochet.Scene`).
#[pyclass(module = "ricochet._native", frozen)]
#[derive(Clone)]
pub struct SceneCore {
    /// The scene text as read or given, before the overrides.
    pub text: String,
    /// The file it is read as (a scene built in Python: `<name>.toml` in the working folder).
    pub path: PathBuf,
    /// The overrides, in the order set.
    pub overrides: Vec<Override>,
    /// The validated scene with the overrides applied.
    pub scene: Scene,
}

impl SceneCore {
    /// The scene text with the overrides applied ([`overrides::materialise`]: Gmsh paths made
    /// absolute), or the text itself without overrides.
    pub fn materialised(&self) -> Result<String, ricochet::Error> {
        if self.overrides.is_empty() {
            Ok(self.text.clone())
        } else {
            overrides::materialise(&self.text, &self.path, &self.overrides)
        }
    }
}

#[pymethods]
impl SceneCore {
    /// Reads and validates the scene file `path` (as `ricochet check` does).
    #[staticmethod]
    fn load(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        let text = Scene::read_text(&path).map_err(|e| error(py, e))?;
        Self::from_text(py, text, path)
    }

    /// Validates scene text `text`, read as the file `path`.
    #[staticmethod]
    fn from_text(py: Python<'_>, text: String, path: PathBuf) -> PyResult<Self> {
        let scene = Scene::parse(&text, &path).map_err(|e| error(py, e))?;
        Ok(Self {
            text,
            path,
            overrides: Vec::new(),
            scene,
        })
    }

    /// Validates the scene given as a dict of its tables, read as the file `path`.
    #[staticmethod]
    fn from_table(py: Python<'_>, table: &Bound<'_, PyDict>, path: PathBuf) -> PyResult<Self> {
        let text = toml::to_string(&to_toml(table.as_any())?).map_err(|e| {
            pyo3::exceptions::PyValueError::new_err(format!(
                "the dict cannot be written as TOML: {e}"
            ))
        })?;
        Self::from_text(py, text, path)
    }

    /// A copy with the key at `key` (a study's key path) set to `value`, validated with every
    /// override set before it.
    fn set(&self, py: Python<'_>, key: &str, value: &Bound<'_, PyAny>) -> PyResult<Self> {
        let value = to_toml(value)?;
        let key = KeyPath::parse(key).map_err(|reason| {
            error(
                py,
                ricochet::Error::Invalid {
                    file: self.path.clone(),
                    key: key.to_string(),
                    value: shown(&value),
                    reason: format!("not a key path: {reason}"),
                },
            )
        })?;
        let mut overrides = self.overrides.clone();
        overrides.push(Override { key, value });
        let scene =
            Scene::parse_with(&self.text, &self.path, &overrides).map_err(|e| error(py, e))?;
        Ok(Self {
            text: self.text.clone(),
            path: self.path.clone(),
            overrides,
            scene,
        })
    }

    /// The scene as TOML text, overrides applied.
    fn to_toml(&self, py: Python<'_>) -> PyResult<String> {
        self.materialised().map_err(|e| error(py, e))
    }

    /// The scene's tables as a dict, overrides applied.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let text = self.materialised().map_err(|e| error(py, e))?;
        let table: toml::Table = toml::from_str(&text)
            .map_err(|e| pyo3::exceptions::PyValueError::new_err(e.to_string()))?;
        from_toml(py, &toml::Value::Table(table))
    }

    /// The scene's name (the file's stem).
    #[getter]
    fn name(&self) -> String {
        self.scene.name.clone()
    }

    /// The file the scene is read as.
    #[getter]
    fn file(&self) -> PathBuf {
        self.path.clone()
    }

    /// The overrides set, as (key path, value) pairs in order.
    #[getter]
    fn overrides<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let items: Vec<(String, Bound<'py, PyAny>)> = self
            .overrides
            .iter()
            .map(|o| Ok((o.key.text.clone(), from_toml(py, &o.value)?)))
            .collect::<PyResult<_>>()?;
        PyList::new(py, items)
    }

    /// The plan that `ricochet check` prints, as a dict.
    fn check<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let plan = plan(&self.scene).map_err(|e| error(py, e))?;
        from_json(py, &plan)
    }

    /// The model's mesh at t = 0 (overlaps resolved, as a run starts): node positions (n, 2)
    /// float64, quads (m, 4) uint32 (a triangle repeats its last node), and each element's
    /// body index (m,) uint32. The arrays own the model's buffers: nothing is copied.
    #[allow(clippy::type_complexity)]
    fn mesh<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<(
        Bound<'py, PyAny>,
        Bound<'py, PyAny>,
        Bound<'py, PyArray1<u32>>,
    )> {
        let scene = self.scene.clone();
        let model = py
            .detach(move || ricochet::run::model_and_plan(&scene))
            .map_err(|e| error(py, e))?
            .0;
        let n = model.position.len();
        let m = model.quads.len();
        let positions: Vec<f64> = bytemuck::allocation::cast_vec(model.position);
        let quads: Vec<u32> = bytemuck::allocation::cast_vec(model.quads);
        Ok((
            PyArray1::from_vec(py, positions)
                .reshape([n, 2])?
                .into_any(),
            PyArray1::from_vec(py, quads).reshape([m, 4])?.into_any(),
            PyArray1::from_vec(py, model.element_body),
        ))
    }

    /// Runs the scene in-process (see `ricochet.Scene.run`): returns (status, message, output
    /// folder, notices, exception raised by the progress callback or None).
    #[pyo3(signature = (backend, out, adapter, progress))]
    fn run<'py>(
        &self,
        py: Python<'py>,
        backend: &str,
        out: Option<PathBuf>,
        adapter: Option<String>,
        progress: Option<Py<PyAny>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let text = self.materialised().map_err(|e| error(py, e))?;
        crate::run::run_scene(py, self, text, backend, out, adapter, progress)
    }

    fn __repr__(&self) -> String {
        format!(
            "Scene({:?}, file={:?}, {} override(s))",
            self.scene.name,
            self.path.display().to_string(),
            self.overrides.len()
        )
    }
}

/// The plan of `scene` as `ricochet check` prints it (`src/cli/check.rs`), as JSON: the model
/// and its bodies, the steps, contact (tables, methods, friction, overlaps), loads, memory,
/// outputs and stages (the Gmsh groups and load curves it prints are left out).
///
/// # Errors
/// As [`ricochet::run::model_and_plan`]; [`ricochet::Error::Invalid`] for a fixed
/// `run.time_step` above the stable step.
fn plan(scene: &Scene) -> Result<serde_json::Value, ricochet::Error> {
    let (model, plan) = ricochet::run::model_and_plan(scene)?;
    let schedule = ricochet::run::schedule(scene);
    let contact = ContactSet::new(&model);
    let solver = CpuSolver::new(model, plan.clone(), schedule);
    let model = solver.model();
    let (dt_element, e) = solver.stable_step();
    let (dt, step) = ricochet::run::checked_step(scene, (dt_element, e), contact.as_ref())?;
    let bodies: Vec<serde_json::Value> = model
        .bodies
        .iter()
        .map(|b| {
            json!({
                "name": b.name,
                "nodes": b.nodes.len(),
                "elements": b.elements.len(),
                "mass": b.mass,
                "wave_speed": b.params.dilatational_speed(),
                "hourglass": format!("{:?}", b.params.hourglass),
            })
        })
        .collect();
    let contact = contact.as_ref().map(|c| {
        let mut methods = serde_json::Map::new();
        for m in model
            .contacts
            .iter()
            .map(|c| c.method)
            .chain(model.walls.iter().map(|w| w.method))
        {
            let n = methods.get(m.word()).and_then(|v| v.as_u64()).unwrap_or(0);
            methods.insert(m.word().to_string(), json!(n + 1));
        }
        json!({
            "tables": plan.contacts,
            "walls": plan.walls,
            "names": c.names(),
            "margin": c.margin(),
            "methods": methods,
            "penalty_step": c.penalty_step().map(|(dp, _)| dp),
        })
    });
    let overlaps: Vec<serde_json::Value> = model
        .initial_overlaps
        .iter()
        .map(|o| json!({"interface": o.interface, "node": o.node, "depth": o.depth}))
        .collect();
    let friction: Vec<serde_json::Value> = model
        .contacts
        .iter()
        .map(|c| (&c.name, c.friction))
        .chain(model.walls.iter().map(|w| (&w.name, w.friction)))
        .filter(|(_, mu)| *mu > 0.0)
        .map(|(name, mu)| json!({"name": name, "mu": mu}))
        .collect();
    let pressures: Vec<serde_json::Value> = model
        .pressures
        .iter()
        .map(
            |p| json!({"value": p.value, "edges": p.edges, "nodes": p.nodes.len(), "ramp": p.ramp}),
        )
        .collect();
    let r = &scene.run;
    Ok(json!({
        "friction": friction,
        "pressures": pressures,
        "gravity": model.gravity,
        "gravity_ramp": model.gravity_ramp,
        "mass_damping": model.mass_damping,
        "scene": scene.name,
        "file": scene.file.to_string_lossy(),
        "nodes": plan.nodes,
        "elements": plan.elements,
        "constrained_nodes": plan.constrained_nodes,
        "bodies": bodies,
        "stable_step": dt,
        "stable_step_element": e,
        "element_step": dt_element,
        "time_step": step,
        "steps": (r.end_time / step).ceil() as u64,
        "end_time": r.end_time,
        "contact": contact,
        "overlaps": overlaps,
        "memory_bytes": ricochet::run::memory_estimate(scene),
        "history_interval": r.history_interval,
        "history_rows": (r.end_time / r.history_interval).floor() as u64 + 1,
        "field_interval": r.field_interval,
        "snapshots": r.field_interval.map(|f| (r.end_time / f).floor() as u64 + 1),
        "checkpoint_interval": r.checkpoint_interval,
        "stages": plan.stages.iter().map(|s| s.name()).collect::<Vec<_>>(),
        "plan": plan.to_string(),
    }))
}
