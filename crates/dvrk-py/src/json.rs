//! Documents (results, summaries, settings) cross the boundary as JSON, so that Python
//! sees exactly the structure of the CLI's JSON output.

use std::path::Path;

use dvrk_ident::log::write_atomic;
use dvrk_ident::IdentError;
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use serde::de::DeserializeOwned;
use serde::Serialize;

use crate::errors::{from_ident, input};

/// `json.loads(serde_json::to_string(value))`: dicts, lists, floats (exact), `None`
/// for non-finite numbers (as in the CLI's output).
pub fn to_python<'py, T: Serialize + ?Sized>(
    py: Python<'py>,
    value: &T,
) -> PyResult<Bound<'py, PyAny>> {
    static LOADS: PyOnceLock<Py<PyAny>> = PyOnceLock::new();
    let text = serde_json::to_string(value).expect("serializable");
    LOADS.import(py, "json", "loads")?.call1((text,))
}

/// A value from a JSON-compatible Python object (`json.dumps`, then serde).
pub fn from_python<T: DeserializeOwned>(
    py: Python<'_>,
    obj: &Bound<'_, PyAny>,
    what: &str,
) -> PyResult<T> {
    static DUMPS: PyOnceLock<Py<PyAny>> = PyOnceLock::new();
    let text: String = DUMPS
        .import(py, "json", "dumps")?
        .call1((obj,))
        .map_err(|e| input(format!("{what}: not JSON-compatible: {e}")))?
        .extract()?;
    serde_json::from_str(&text).map_err(|e| input(format!("{what}: {e}")))
}

/// The `write` of every class with a JSON document: `text` written to `path` atomically
/// (temporary file and rename), without the GIL.
pub fn write_document(py: Python<'_>, path: &Path, text: String) -> PyResult<()> {
    py.detach(move || {
        write_atomic(path, |w| w.write_all(text.as_bytes())).map_err(IdentError::from)
    })
    .map_err(from_ident)
}
