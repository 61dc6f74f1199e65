//! The names of the development builds before 0.1.0, still accepted with a
//! `DeprecationWarning` until 0.2.0 (the vocabulary is now the library's: `Model`,
//! `JointLog`, `FitResult`, `FourierTrajectory`).

use pyo3::exceptions::{PyAttributeError, PyDeprecationWarning};
use pyo3::prelude::*;

/// Old class name → new class name.
pub const RENAMED: &[(&str, &str)] = &[
    ("Robot", "Model"),
    ("Data", "JointLog"),
    ("Result", "FitResult"),
    ("Trajectory", "FourierTrajectory"),
];

/// Warns that `old` is deprecated in favour of `new`, pointing at the caller's line.
pub fn warn(py: Python<'_>, old: &str, new: &str) -> PyResult<()> {
    PyErr::warn(
        py,
        &py.get_type::<PyDeprecationWarning>(),
        &std::ffi::CString::new(format!(
            "dvrk_ident.{old} is deprecated and will be removed in 0.2.0: \
             use dvrk_ident.{new}"
        ))?,
        1,
    )
}

/// The module's `__getattr__` (PEP 562): the old class names, with a warning.
#[pyfunction(name = "__getattr__")]
pub fn module_getattr(py: Python<'_>, name: &str) -> PyResult<Py<PyAny>> {
    let Some((old, new)) = RENAMED.iter().find(|(old, _)| *old == name) else {
        return Err(PyAttributeError::new_err(format!(
            "module 'dvrk_ident' has no attribute '{name}'"
        )));
    };
    warn(py, old, new)?;
    Ok(py.import("dvrk_ident")?.getattr(*new)?.unbind())
}
