//! Joint and Cartesian limits between Python and the library: dicts in the limits
//! file's layout (the one serde schema of `dvrk_model::LimitsSpec`) both ways.

use std::path::PathBuf;

use dvrk_model::{Limits, LimitsSpec, Model};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::errors::{from_io, from_model, input};

/// `robot`'s limits (description `[[limits]]` and `[[cartesian_limits]]`) as a dict in
/// the layout of a limits file, which `excite(..., limits=...)` reads back to the same
/// limits.
pub fn limits_dict<'py>(py: Python<'py>, model: &Model) -> PyResult<Bound<'py, PyAny>> {
    let spec = LimitsSpec::of(model, &Limits::of_model(model));
    serde_pyobject::to_pyobject(py, &spec).map_err(PyErr::from)
}

/// The limits of `excite`/`evaluate_trajectory`: the description's (None), a limits
/// file (a path), or a dict in the file's layout (the same serde schema as the file).
pub(crate) fn limits_of(model: &Model, obj: Option<&Bound<'_, PyAny>>) -> PyResult<Limits> {
    let Some(obj) = obj.filter(|o| !o.is_none()) else {
        return Ok(Limits::of_model(model));
    };
    if obj.is_instance_of::<PyDict>() {
        let spec: LimitsSpec = serde_pyobject::from_pyobject(obj.clone())
            .map_err(|e| input(format!("limits: not a limits dict: {}", PyErr::from(e))))?;
        return spec.compile(model, "limits").map_err(from_model);
    }
    let path: PathBuf = obj.extract().map_err(|_| {
        input("limits: expected None (the robot's limits), a limits file path or a dict")
    })?;
    let text = dvrk_model::input::read_text(&path).map_err(|e| from_io(&path, &e))?;
    Limits::from_toml_str(model, &text, &path.display().to_string()).map_err(from_model)
}
