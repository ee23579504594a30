//! Python values to TOML (scene dicts and override values) and JSON to Python (plans), and the
//! library's [`ricochet::Error`] as Python exceptions: `SceneError` (a `ValueError`) for a scene
//! that cannot be read, parsed or validated, with the command line's exit-2 message and the
//! error's `file`, `key`, `value` and `reason` as attributes; `RicochetError` (a `RuntimeError`)
//! for everything else.

use pyo3::exceptions::{PyRuntimeError, PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyList, PyString, PyTuple};
use toml::Value;

pyo3::create_exception!(
    ricochet,
    SceneError,
    PyValueError,
    "A scene (or study) that cannot be read, parsed or validated: the message is the command \
     line's exit-2 message; `file`, `key`, `value` and `reason` say where and why (`key`, \
     `value` and `reason` are None for a read or TOML error)."
);
pyo3::create_exception!(
    ricochet,
    RicochetError,
    PyRuntimeError,
    "A run or study that could not be made (a GPU that cannot be used, an output folder in use, \
     a checkpoint that cannot be continued, a file that cannot be written)."
);

/// `e` as a Python exception: [`SceneError`] for read, parse and validation errors, else
/// [`RicochetError`].
pub fn error(py: Python<'_>, e: ricochet::Error) -> PyErr {
    use ricochet::Error as E;
    let message = e.to_string();
    let (file, key, value, reason) = match &e {
        E::Read { file, .. } | E::Parse { file, .. } => (Some(file.clone()), None, None, None),
        E::Invalid {
            file,
            key,
            value,
            reason,
        } => (
            Some(file.clone()),
            Some(key.clone()),
            Some(value.clone()),
            Some(reason.clone()),
        ),
        _ => return RicochetError::new_err(message),
    };
    let err = SceneError::new_err(message);
    let v = err.value(py);
    let set = |name: &str, x: Option<String>| v.setattr(name, x);
    let file = file.map(|f| f.to_string_lossy().into_owned());
    if let Err(e) = set("file", file)
        .and_then(|()| set("key", key))
        .and_then(|()| set("value", value))
        .and_then(|()| set("reason", reason))
    {
        return e;
    }
    err
}

/// A Python value as TOML: bool, int, float (numpy scalars included), str, sequences (lists,
/// tuples, numpy arrays) and dicts with string keys.
///
/// # Errors
/// `TypeError` for anything else (None included: TOML has no null).
pub fn to_toml(x: &Bound<'_, PyAny>) -> PyResult<Value> {
    if x.is_instance_of::<PyBool>() {
        return Ok(Value::Boolean(x.extract()?));
    }
    if x.is_instance_of::<PyFloat>() {
        return Ok(Value::Float(x.extract()?));
    }
    if x.is_instance_of::<PyString>() {
        return Ok(Value::String(x.extract()?));
    }
    if let Ok(d) = x.cast::<PyDict>() {
        let mut table = toml::Table::new();
        for (k, v) in d.iter() {
            let key: String = k
                .extract()
                .map_err(|_| PyTypeError::new_err(format!("a scene key must be a str, not {k}")))?;
            table.insert(key, to_toml(&v)?);
        }
        return Ok(Value::Table(table));
    }
    if x.is_instance_of::<PyList>() || x.is_instance_of::<PyTuple>() {
        let items: Vec<Bound<'_, PyAny>> = x.try_iter()?.collect::<PyResult<_>>()?;
        return Ok(Value::Array(
            items.iter().map(to_toml).collect::<PyResult<_>>()?,
        ));
    }
    // numpy: arrays and scalars through `tolist()` (plain Python values).
    if x.hasattr("tolist")? && x.hasattr("dtype")? {
        return to_toml(&x.call_method0("tolist")?);
    }
    if let Ok(i) = x.extract::<i64>() {
        return Ok(Value::Integer(i));
    }
    if let Ok(f) = x.extract::<f64>() {
        return Ok(Value::Float(f));
    }
    Err(PyTypeError::new_err(format!(
        "{} cannot be a scene value (bool, int, float, str, a list or a dict)",
        x.get_type().name()?
    )))
}

/// A JSON value as Python (dicts, lists, str, int, float, bool, None).
pub fn from_json<'py>(py: Python<'py>, v: &serde_json::Value) -> PyResult<Bound<'py, PyAny>> {
    use serde_json::Value as J;
    Ok(match v {
        J::Null => py.None().into_bound(py),
        J::Bool(b) => PyBool::new(py, *b).to_owned().into_any(),
        J::Number(n) => match (n.as_i64(), n.as_u64()) {
            (Some(i), _) => i.into_pyobject(py)?.into_any(),
            (None, Some(u)) => u.into_pyobject(py)?.into_any(),
            _ => n.as_f64().unwrap_or(f64::NAN).into_pyobject(py)?.into_any(),
        },
        J::String(s) => PyString::new(py, s).into_any(),
        J::Array(a) => {
            let items: Vec<Bound<'py, PyAny>> = a
                .iter()
                .map(|x| from_json(py, x))
                .collect::<PyResult<_>>()?;
            PyList::new(py, items)?.into_any()
        }
        J::Object(o) => {
            let d = PyDict::new(py);
            for (k, x) in o {
                d.set_item(k, from_json(py, x)?)?;
            }
            d.into_any()
        }
    })
}

/// A TOML value as Python (tables as dicts, dates as their text).
pub fn from_toml<'py>(py: Python<'py>, v: &Value) -> PyResult<Bound<'py, PyAny>> {
    Ok(match v {
        Value::String(s) => PyString::new(py, s).into_any(),
        Value::Integer(i) => i.into_pyobject(py)?.into_any(),
        Value::Float(f) => f.into_pyobject(py)?.into_any(),
        Value::Boolean(b) => PyBool::new(py, *b).to_owned().into_any(),
        Value::Datetime(d) => PyString::new(py, &d.to_string()).into_any(),
        Value::Array(a) => {
            let items: Vec<Bound<'py, PyAny>> = a
                .iter()
                .map(|x| from_toml(py, x))
                .collect::<PyResult<_>>()?;
            PyList::new(py, items)?.into_any()
        }
        Value::Table(t) => {
            let d = PyDict::new(py);
            for (k, x) in t {
                d.set_item(k, from_toml(py, x)?)?;
            }
            d.into_any()
        }
    })
}
