//! `compare`: two results side by side (`dvrk_ident::compare`).

use std::sync::Arc;

use dvrk_ident::compare::{compare as compare_results, Side, TestLog};
use dvrk_ident::{FitResult, JointLog};
use dvrk_model::Model;
use pyo3::prelude::*;

use crate::classes::FitResultPy;
use crate::convert::background;
use crate::data::fail_ident;
use crate::fit::logs_arg;
use crate::json::to_python;

/// Two results side by side, the document of ``dvrk-ident compare A B --test LOG...
/// --json`` as a dict:
///
/// - ``a``, ``b``: each result's name, robot, method, convergence, rows, condition
///   number and residual variance;
/// - ``differences``: every setting (``settings.…``, and ``tool``, ``robot_source``)
///   whose values differ, ``{path, a, b}`` (``None`` where one result has no such
///   setting);
/// - ``base_parameters``: ``{comparable, reason, parameters}``, each parameter
///   ``{name, expression, a: {value, std}, b: {value, std}, difference (b − a),
///   sigmas}`` with ``sigmas = |a − b| / sqrt(std_a² + std_b²)``; base parameters are
///   matched by name and expression, and ``reason`` says why they do not all match
///   (e.g. a Stribeck model option on one side only);
/// - ``parameters``, ``link_masses``: ``{name, a, b}`` for every parameter and link mass;
/// - ``tests``: for each log of ``test`` (a :class:`JointLog` or a list),
///   ``{log, a, b}`` with each result's :meth:`FitResult.validate` metrics there: its own
///   model and processing settings, over the first ``test_window`` processed samples.
///
/// ``names``: how the two results are named in the document and in errors (default
/// ``("a", "b")``; the command line uses the file names); a log is named by the file
/// it was read from, else by its source. Results of different robots raise
/// ``InputError``.
///
/// Example::
///
///     >>> doc = di.compare(di.FitResult.read("ols.json"), di.FitResult.read("wls.json"),
///     ...                  test=di.read_log("test.mcap", psm))
///     >>> [d["path"] for d in doc["differences"]]
///     ['settings.method', 'settings.processing.filter.cutoff_hz']
#[pyfunction]
#[pyo3(signature = (a, b, test = None, *, test_window = None, names = None))]
pub fn compare<'py>(
    py: Python<'py>,
    a: &Bound<'py, FitResultPy>,
    b: &Bound<'py, FitResultPy>,
    test: Option<&Bound<'py, PyAny>>,
    test_window: Option<usize>,
    names: Option<(String, String)>,
) -> PyResult<Bound<'py, PyAny>> {
    let (name_a, name_b) = names.unwrap_or_else(|| ("a".into(), "b".into()));
    let logs: Vec<(String, Arc<JointLog>)> = match test {
        None => Vec::new(),
        Some(t) => logs_arg(t, "test")?
            .into_iter()
            .map(|(log, path)| {
                let name = path
                    .map(|p| p.display().to_string())
                    .unwrap_or_else(|| log.source.clone());
                (name, log)
            })
            .collect(),
    };
    let side = |r: &Bound<'py, FitResultPy>| -> PyResult<(FitResult, Arc<Model>)> {
        Ok((r.get().inner.clone(), r.get().model(py, None)?))
    };
    let ((ra, ma), (rb, mb)) = (side(a)?, side(b)?);
    let doc = background(py, move || {
        let a = Side {
            name: &name_a,
            result: &ra,
            model: &ma,
        };
        let b = Side {
            name: &name_b,
            result: &rb,
            model: &mb,
        };
        let tests: Vec<TestLog<'_>> = logs
            .iter()
            .map(|(name, log)| TestLog {
                name,
                samples: [log, log],
            })
            .collect();
        compare_results(&a, &b, &tests, test_window).map_err(fail_ident)
    })?;
    to_python(py, &doc)
}
