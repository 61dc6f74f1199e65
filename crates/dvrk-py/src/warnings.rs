//! The library's warnings as Python ``UserWarning``s, for every function that has some
//! (a fit's repeated inputs, an export's undetermined values, an excitation's limits).

use pyo3::prelude::*;

/// Each line as a Python ``UserWarning`` (what the command line prints as `warning:`).
pub(crate) fn warn_all(py: Python<'_>, lines: &[String]) -> PyResult<()> {
    for line in lines {
        PyErr::warn(
            py,
            &py.get_type::<pyo3::exceptions::PyUserWarning>(),
            &std::ffi::CString::new(line.as_str())?,
            1,
        )?;
    }
    Ok(())
}
