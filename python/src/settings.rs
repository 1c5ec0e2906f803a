//! Keyword arguments as the tables of a scene file. `Scene.from_arrays` and the gates given as
//! dicts turn their Python values into TOML and hand the text to the library, which checks it
//! exactly as it checks a file (same fields, same ranges, same messages), so nothing of the
//! scene or gate format is repeated here.

use crate::errors::input_error;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};

/// A Python value as a TOML value: bool, int, float, str, sequences (lists, tuples, numpy
/// arrays) and dicts with string keys; `None` where the value is `None` (the key is left out).
/// `what` names the value in messages.
pub fn to_toml(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Option<toml::Value>> {
    let py = obj.py();
    if obj.is_none() {
        return Ok(None);
    }
    if obj.is_instance_of::<PyBool>() {
        return Ok(Some(toml::Value::Boolean(obj.extract()?)));
    }
    if obj.is_instance_of::<PyInt>() {
        let v: i64 = obj
            .extract()
            .map_err(|_| input_error(py, format!("{what}: integer {obj} is out of range")))?;
        return Ok(Some(toml::Value::Integer(v)));
    }
    if obj.is_instance_of::<PyFloat>() {
        return Ok(Some(toml::Value::Float(obj.extract()?)));
    }
    if obj.is_instance_of::<PyString>() {
        return Ok(Some(toml::Value::String(obj.extract()?)));
    }
    if let Ok(d) = obj.cast::<PyDict>() {
        return Ok(Some(toml::Value::Table(table(d, what)?)));
    }
    // numpy arrays and scalars: their Python values.
    if obj.hasattr("tolist")? && !obj.is_instance_of::<PyList>() {
        return to_toml(&obj.call_method0("tolist")?, what);
    }
    if obj.is_instance_of::<PyList>() || obj.is_instance_of::<PyTuple>() {
        let mut items = Vec::new();
        for (i, item) in obj.try_iter()?.enumerate() {
            let item = item?;
            match to_toml(&item, &format!("{what}[{i}]"))? {
                Some(v) => items.push(v),
                None => {
                    return Err(input_error(py, format!("{what}[{i}]: None is not a value")));
                }
            }
        }
        return Ok(Some(toml::Value::Array(items)));
    }
    let type_name = obj.get_type().name()?;
    Err(input_error(
        py,
        format!("{what}: expected a number, a string, a list or a dict, got {type_name}"),
    ))
}

/// A dict with string keys as a TOML table; entries whose value is `None` are left out.
pub fn table(d: &Bound<'_, PyDict>, what: &str) -> PyResult<toml::Table> {
    let py = d.py();
    let mut out = toml::Table::new();
    for (k, v) in d.iter() {
        let key: String = k
            .extract()
            .map_err(|_| input_error(py, format!("{what}: keys must be strings, got {k}")))?;
        if let Some(value) = to_toml(&v, &format!("{what}.{key}"))? {
            out.insert(key, value);
        }
    }
    Ok(out)
}

/// A table as TOML text.
pub fn text(py: Python<'_>, table: &toml::Table, what: &str) -> PyResult<String> {
    toml::to_string(table)
        .map_err(|e| input_error(py, format!("{what}: cannot be written as TOML ({e})")))
}

/// A library error about generated TOML (named `name`, line numbers of text nobody wrote)
/// with its location dropped: "Scene.from_arrays: camera.fov_y must be …".
pub fn without_location(e: pgt::PgtError, name: &str) -> pgt::PgtError {
    match e {
        pgt::PgtError::Input { path, message, .. } if path.as_os_str() == name => {
            pgt::PgtError::Usage(format!("{name}: {message}"))
        }
        e => e,
    }
}
