//! `identify_payload`: `dvrk-ident payload` over a :class:`FitResult` and logs.

use dvrk_ident::payload::identify_payload as identify;
use pyo3::prelude::*;

use crate::classes::{FitResultPy, ModelPy};
use crate::convert::background;
use crate::data::fail_ident;
use crate::fit::logs_arg;

/// A rigid payload fixed to frame ``frame``, estimated from ``data`` (a
/// :class:`JointLog` or a list of them) of the arm carrying it with the rest of the
/// model held at ``result`` (its processing, delays and friction), as ``dvrk-ident
/// payload``: physically consistent (positive semidefinite pseudo-inertia). Returns
/// ``result`` with the payload added: its :attr:`FitResult.payload` is ``{frame, mass,
/// com, inertia, identification}`` (kg, m in the frame, kg·m² about the centre of mass
/// ``xx yy zz xy xz yz``; ``identification`` says which quantities the logs determine,
/// ``determined``, with their standard deviations ``std``, ``None`` where they do not),
/// and validation, residuals and exports of it use the arm with its load.
#[pyfunction]
#[pyo3(signature = (result, data, *, frame, robot = None))]
pub fn identify_payload(
    py: Python<'_>,
    result: &Bound<'_, FitResultPy>,
    data: &Bound<'_, PyAny>,
    frame: String,
    robot: Option<&Bound<'_, ModelPy>>,
) -> PyResult<FitResultPy> {
    let logs: Vec<_> = logs_arg(data, "data")?
        .into_iter()
        .map(|(log, _)| log)
        .collect();
    let model = result.get().model(py, robot)?;
    let params = result.get().params(&model)?;
    let inner = result.get().inner.clone();
    let loaded = background(py, move || {
        let logs: Vec<_> = logs.iter().map(|l| (**l).clone()).collect();
        let estimate = identify(&model, &params, &inner, &logs, &frame).map_err(fail_ident)?;
        Ok(estimate.applied_to(&inner))
    })?;
    Ok(FitResultPy::new(
        loaded,
        robot
            .map(|r| r.clone().unbind())
            .or_else(|| result.get().robot.as_ref().map(|r| r.clone_ref(py))),
    ))
}
