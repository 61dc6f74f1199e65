//! The fit options as keyword arguments (`**options` of `fit`, `observe` and
//! `prepare`): each named as the library's option ([`Setting::name`]), converted in one
//! place ([`options`]) by the library's one conversion
//! ([`Overrides::from_values`]). The type stub lists them; a test checks it
//! against [`options_table`], so an option the stub misses fails a test.

use std::path::PathBuf;
use std::sync::Arc;

use dvrk_ident::FitSettings;
use dvrk_ident::Joints;
use dvrk_ident::{Overrides, PriorSource, Setting, SettingError};
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyString};

use crate::classes::FitResultPy;
use crate::errors::{input, setting_keyword as keyword};
use crate::json::from_python;

/// `joints=`: ``"model"`` or ``"measured"``.
pub(crate) fn parse_joints(text: &str) -> PyResult<Joints> {
    crate::convert::named("joints", text)
}

/// The options each function takes as keyword arguments, by function.
pub(crate) const FUNCTIONS: [(&str, &[Setting]); 4] = [
    ("fit", Setting::ALL),
    ("observe", Setting::OBSERVE),
    ("prepare", Setting::PROCESSING),
    ("external_torque", Setting::PROCESSING),
];

/// `dvrk_ident._options`: `{function: [option name, ...]}` in the library's order (the
/// stub's test reads it).
pub(crate) fn options_table<'py>(py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
    let table = PyDict::new(py);
    for (function, settings) in FUNCTIONS {
        let names: Vec<&str> = settings.iter().map(|s| s.name()).collect();
        table.set_item(function, names)?;
    }
    Ok(table)
}

/// An option's value refused, named as its keyword: a value of the wrong type is
/// Python's `TypeError`, any other `InputError`.
fn setting_error(e: SettingError) -> PyErr {
    refused(keyword(e.setting), &e.message)
}

/// The value of `keyword` refused by the library's conversion with `message`: a value
/// of the wrong type is Python's `TypeError`, any other `InputError`.
pub(crate) fn refused(keyword: &str, message: &str) -> PyErr {
    let text = format!("{keyword}: {message}");
    if message.starts_with("invalid type") {
        PyTypeError::new_err(text)
    } else {
        input(text)
    }
}

/// `function() got an unexpected keyword argument 'name'`, as Python's own.
pub(crate) fn unexpected(function: &str, name: &str) -> PyErr {
    PyTypeError::new_err(format!(
        "{function}() got an unexpected keyword argument '{name}'"
    ))
}

/// The fit options among `function`'s keyword arguments (`None`: not given) as the
/// library's overrides; a keyword that is not one of `function`'s options is a
/// `TypeError`, as Python's own.
pub(crate) fn options(function: &str, kwargs: Option<&Bound<'_, PyDict>>) -> PyResult<Overrides> {
    let scope = FUNCTIONS
        .iter()
        .find(|(f, _)| *f == function)
        .map_or(&[][..], |(_, s)| *s);
    let mut values = Vec::new();
    let mut in_memory = None;
    for (key, value) in kwargs.into_iter().flatten() {
        let name: String = key.extract()?;
        let setting = Setting::from_name(&name)
            .filter(|s| scope.contains(s))
            .ok_or_else(|| unexpected(function, &name))?;
        if value.is_none() {
            continue;
        }
        if setting == Setting::Prior {
            if let Ok(r) = value.cast::<FitResultPy>() {
                in_memory = Some(PriorSource::Result(Arc::new(r.get().inner.clone())));
                continue;
            }
            // A path-like object as its path.
            if !value.is_instance_of::<PyString>() {
                let path: PathBuf = value.extract().map_err(|_| {
                    input("prior: expected \"nominal\", the path of a result document, or a FitResult")
                })?;
                values.push((
                    setting,
                    serde_json::Value::String(path.display().to_string()),
                ));
                continue;
            }
        }
        values.push((setting, json(&value, keyword(setting))?));
    }
    let mut overrides = Overrides::from_values(values).map_err(setting_error)?;
    if in_memory.is_some() {
        overrides.prior = in_memory;
    }
    Ok(overrides)
}

/// A keyword's value as the option's value: booleans, text, numbers (Python's and
/// NumPy's; a non-finite number as its text, which the option's own check refuses) and
/// sequences of them. `keyword` names the argument in errors.
pub(crate) fn json(value: &Bound<'_, PyAny>, keyword: &str) -> PyResult<serde_json::Value> {
    use serde_json::Value;
    // Python's bool and NumPy's (`numpy.bool_`, which has no `__index__` but reads as
    // a number); not an int.
    if let Ok(b) = value.extract::<bool>() {
        return Ok(Value::Bool(b));
    }
    if value.is_instance_of::<PyString>() {
        return Ok(Value::String(value.extract()?));
    }
    if value.hasattr("__index__")? {
        if let Ok(n) = value.extract::<i64>() {
            return Ok(Value::from(n));
        }
        if let Ok(n) = value.extract::<u64>() {
            return Ok(Value::from(n));
        }
    }
    if let Ok(x) = value.extract::<f64>() {
        return Ok(serde_json::Number::from_f64(x)
            .map_or_else(|| Value::String(x.to_string()), Value::Number));
    }
    if let Ok(items) = value.try_iter() {
        return items
            .map(|item| json(&item?, keyword))
            .collect::<PyResult<Vec<_>>>()
            .map(Value::Array);
    }
    Err(PyTypeError::new_err(format!(
        "{keyword}: unexpected {}",
        value.get_type().name()?
    )))
}

/// The base settings: `settings` (the result document's `settings` layout; missing
/// fields take the defaults) or the defaults.
pub(crate) fn base(py: Python<'_>, settings: Option<&Bound<'_, PyAny>>) -> PyResult<FitSettings> {
    match settings.filter(|s| !s.is_none()) {
        Some(obj) => from_python::<FitSettings>(py, obj, "settings"),
        None => Ok(FitSettings::default()),
    }
}
