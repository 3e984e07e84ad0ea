//! JSON values as Python objects and back: the summaries and reports of runs are returned as
//! dicts, and the options of a run are taken as a dict, without Python's `json` module. Its
//! import (with the `re` it imports) costs more CPU than the whole interpreter start-up of a
//! short run, and `import sepg` is kept cheap for runs of the built-in environments.
use pyo3::IntoPyObjectExt;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
use serde_json::{Map, Number, Value};

use crate::{failed, invalid};

/// `value` as a Python object: `null` as `None`, objects as dicts (keys in sorted order),
/// arrays as lists, integers as `int` and other numbers as `float`.
pub(crate) fn to_py<'py>(py: Python<'py>, value: &Value) -> PyResult<Bound<'py, PyAny>> {
    match value {
        Value::Null => Ok(py.None().into_bound(py)),
        Value::Bool(b) => b.into_bound_py_any(py),
        Value::Number(n) => match (n.as_i64(), n.as_u64(), n.as_f64()) {
            (Some(i), _, _) => i.into_bound_py_any(py),
            (None, Some(u), _) => u.into_bound_py_any(py),
            (None, None, Some(x)) => x.into_bound_py_any(py),
            (None, None, None) => Err(failed(format!("the number {n} has no float value"))),
        },
        Value::String(s) => s.into_bound_py_any(py),
        Value::Array(items) => {
            let list = PyList::empty(py);
            for item in items {
                list.append(to_py(py, item)?)?;
            }
            Ok(list.into_any())
        }
        Value::Object(map) => {
            let dict = PyDict::new(py);
            for (key, item) in map {
                dict.set_item(key, to_py(py, item)?)?;
            }
            Ok(dict.into_any())
        }
    }
}

/// A serialisable value as a Python object, through [`to_py`].
pub(crate) fn serialize_to_py<'py, T: serde::Serialize>(
    py: Python<'py>,
    value: &T,
) -> PyResult<Bound<'py, PyAny>> {
    to_py(py, &serde_json::to_value(value).map_err(failed)?)
}

/// The Python object `x` (at `path`, for messages) as a JSON value: `None`, `bool`, `int`,
/// finite `float` (numpy scalars included), `str`, lists and tuples, and dicts with string
/// keys. Anything else, or a float that is not finite, raises `InvalidInputError`.
pub(crate) fn from_py(x: &Bound<'_, PyAny>, path: &str) -> PyResult<Value> {
    if x.is_none() {
        return Ok(Value::Null);
    }
    if let Ok(b) = x.cast::<PyBool>() {
        return Ok(Value::Bool(b.is_true()));
    }
    if x.is_instance_of::<PyString>() {
        return Ok(Value::String(x.extract()?));
    }
    if let Ok(d) = x.cast::<PyDict>() {
        let mut map = Map::new();
        for (key, item) in d.iter() {
            let key: String = key
                .extract()
                .map_err(|_| invalid(format!("{path}: the keys must be strings, got {key}")))?;
            let value = from_py(&item, &format!("{path}.{key}"))?;
            map.insert(key, value);
        }
        return Ok(Value::Object(map));
    }
    if x.is_instance_of::<PyList>() || x.is_instance_of::<PyTuple>() {
        let items = x
            .try_iter()?
            .enumerate()
            .map(|(i, item)| from_py(&item?, &format!("{path}[{i}]")))
            .collect::<PyResult<_>>()?;
        return Ok(Value::Array(items));
    }
    if !x.is_instance_of::<PyFloat>() {
        if let Ok(i) = x.extract::<i64>() {
            return Ok(Value::from(i));
        }
        if let Ok(u) = x.extract::<u64>() {
            return Ok(Value::from(u));
        }
        if x.is_instance_of::<PyInt>() {
            return Err(invalid(format!("{path} = {x} is out of the 64-bit range")));
        }
    }
    if let Ok(v) = x.extract::<f64>() {
        return Number::from_f64(v)
            .map(Value::Number)
            .ok_or_else(|| invalid(format!("{path} = {v} must be finite")));
    }
    Err(invalid(format!(
        "{path}: unsupported value of type {}",
        x.get_type().name()?
    )))
}
