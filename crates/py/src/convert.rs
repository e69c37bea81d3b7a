//! Values between Rust and Python: JSON values as Python objects (the
//! command line's `--json` output as dicts), parameter values as the
//! command line's `NAME=VALUE` assignments.

use pyo3::IntoPyObjectExt;
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyList, PyString};
use serde_json::Value;

/// A JSON value as the Python object `json.loads` would give.
pub(crate) fn json_to_py<'py>(py: Python<'py>, v: &Value) -> PyResult<Bound<'py, PyAny>> {
    Ok(match v {
        Value::Null => py.None().into_bound(py),
        Value::Bool(b) => PyBool::new(py, *b).to_owned().into_any(),
        Value::Number(n) => {
            if let Some(i) = n.as_i64() {
                i.into_bound_py_any(py)?
            } else if let Some(u) = n.as_u64() {
                u.into_bound_py_any(py)?
            } else {
                PyFloat::new(py, n.as_f64().unwrap_or(f64::NAN)).into_any()
            }
        }
        Value::String(s) => PyString::new(py, s).into_any(),
        Value::Array(items) => {
            let list = PyList::empty(py);
            for item in items {
                list.append(json_to_py(py, item)?)?;
            }
            list.into_any()
        }
        Value::Object(map) => {
            let dict = PyDict::new(py);
            for (k, item) in map {
                dict.set_item(k, json_to_py(py, item)?)?;
            }
            dict.into_any()
        }
    })
}

/// A parameter's value as the text of an assignment: a string as it is (an
/// expression such as `1/3`), a number as Python writes it (`repr`: the
/// shortest text that reads back to the same double).
pub(crate) fn value_text(value: &Bound<'_, PyAny>) -> PyResult<String> {
    if value.is_instance_of::<PyBool>() {
        return Err(PyTypeError::new_err(format!(
            "a parameter value is a number or an expression string, not {}",
            value.repr()?
        )));
    }
    if let Ok(s) = value.cast::<PyString>() {
        return s.extract::<String>();
    }
    if let Ok(i) = value.extract::<i64>() {
        return Ok(i.to_string());
    }
    match value.extract::<f64>() {
        Ok(f) => PyFloat::new(value.py(), f).repr()?.extract::<String>(),
        Err(_) => Err(PyTypeError::new_err(format!(
            "a parameter value is a number or an expression string, not {}",
            value.repr()?
        ))),
    }
}

/// `{name: value}` as `NAME=VALUE` assignments, in the dict's order.
pub(crate) fn assignments(params: Option<&Bound<'_, PyDict>>) -> PyResult<Vec<String>> {
    let mut out = Vec::new();
    if let Some(d) = params {
        for (k, v) in d.iter() {
            let name: String = k.extract().map_err(|_| {
                PyTypeError::new_err(format!(
                    "parameter names are strings, not {}",
                    k.repr().map(|r| r.to_string()).unwrap_or_default()
                ))
            })?;
            out.push(format!("{name}={}", value_text(&v)?));
        }
    }
    Ok(out)
}
