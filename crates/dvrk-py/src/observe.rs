//! `observe` and `Observation`: the map and reduce of a fit over many processes or
//! machines (Dask, Ray, multiprocessing), on the library's observation states.

use std::path::PathBuf;
use std::sync::Arc;

use dvrk_ident::ObservationState;
use dvrk_ident::Silent;
use dvrk_ident::{LogSource, ObserveRequest};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyList};

use crate::classes::ModelPy;
use crate::convert::background;
use crate::data::{absolute, fail_ident, JointLogPy};
use crate::errors::{from_ident, input};
use crate::json::to_python;

/// The training logs of a fit reduced to their R factors (see :func:`observe`): the
/// robot and processing they were reduced for, each log's provenance and factors, and
/// all of them merged. Observations of the same robot and processing merge (``a + b``,
/// :meth:`merge`) into the observation of all their logs, in any order and grouping
/// (exact up to rounding), and :func:`fit` fits them with the result of a fit of the
/// logs themselves. They pickle (as :meth:`__bytes__`), so Dask, Ray or
/// ``multiprocessing`` can carry them between processes.
///
/// ``bytes(obs)`` is the file of ``dvrk-ident observe --out`` (layout in
/// docs/book/src/distributed.md), :meth:`from_bytes` reads it back, :meth:`write` /
/// :meth:`read` use files.
#[pyclass(name = "Observation", module = "dvrk_ident", frozen)]
pub struct ObservationPy {
    pub inner: Arc<ObservationState>,
}

fn wrap(state: ObservationState) -> ObservationPy {
    ObservationPy {
        inner: Arc::new(state),
    }
}

#[pymethods]
impl ObservationPy {
    /// An observation from the bytes of :meth:`__bytes__` (or of a state file).
    #[staticmethod]
    fn from_bytes(data: &[u8]) -> PyResult<Self> {
        ObservationState::from_bytes(data, "<bytes>")
            .map(wrap)
            .map_err(from_ident)
    }

    /// Reads a state file of ``dvrk-ident observe --out``.
    #[staticmethod]
    fn read(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        let state = py
            .detach(move || ObservationState::read(&path))
            .map_err(from_ident)?;
        Ok(wrap(state))
    }

    /// Writes the state file (atomically), for ``dvrk-ident fit --states``.
    fn write(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        let inner = self.inner.clone();
        py.detach(move || inner.write(&path)).map_err(from_ident)
    }

    fn __bytes__<'py>(&self, py: Python<'py>) -> Bound<'py, PyBytes> {
        PyBytes::new(py, &self.inner.to_bytes())
    }

    /// Pickling (and ``copy.deepcopy``): the bytes.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
        let py = slf.py();
        let bytes = PyBytes::new(py, &slf.get().inner.to_bytes());
        let args = (bytes,).into_pyobject(py)?.into_any();
        Ok((slf.get_type().getattr("from_bytes")?, args))
    }

    /// The observation of the logs of both (these first). Refuses observations of
    /// another robot, processing or Stribeck velocity with an ``InputError``.
    fn merge(&self, py: Python<'_>, other: &Bound<'_, ObservationPy>) -> PyResult<Self> {
        let (a, b) = (self.inner.clone(), other.get().inner.clone());
        py.detach(move || {
            let mut total = (*a).clone();
            total.merge(&b).map(|()| total)
        })
        .map(wrap)
        .map_err(from_ident)
    }

    fn __add__(&self, py: Python<'_>, other: &Bound<'_, ObservationPy>) -> PyResult<Self> {
        self.merge(py, other)
    }

    /// The robot's name.
    #[getter]
    fn robot(&self) -> String {
        self.inner.robot.clone()
    }

    /// Processed samples of all the logs.
    #[getter]
    fn samples(&self) -> usize {
        self.inner.samples()
    }

    /// The logs, in order: ``{path, sha256, bytes, source, samples}``.
    #[getter]
    fn logs<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let list = PyList::empty(py);
        for (info, samples) in self.inner.logs() {
            let d = PyDict::new(py);
            d.set_item("path", &info.path)?;
            d.set_item("sha256", &info.sha256)?;
            d.set_item("bytes", info.bytes)?;
            d.set_item("source", &info.source)?;
            d.set_item("samples", samples)?;
            list.append(d)?;
        }
        Ok(list)
    }

    /// The processing settings the logs were reduced with (``FitResult.settings``'s
    /// ``processing`` layout).
    #[getter]
    fn processing<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_python(py, &self.inner.processing)
    }

    fn __repr__(&self) -> String {
        format!(
            "Observation(robot={}, {} log(s), {} samples)",
            self.inner.robot,
            self.inner.logs().len(),
            self.inner.samples()
        )
    }
}

/// The logs of `data`: a :class:`JointLog` (its samples), a path (read as :func:`read_log`
/// reads it for the robot, with its absolute path for the provenance) or a list of them.
fn log_sources(data: &Bound<'_, PyAny>) -> PyResult<Vec<LogSource>> {
    let one = |d: &Bound<'_, PyAny>| -> PyResult<LogSource> {
        if let Ok(d) = d.cast::<JointLogPy>() {
            return Ok(LogSource::Samples {
                samples: d.get().log.clone(),
                file: d.get().path.clone(),
            });
        }
        let path: PathBuf = d.extract().map_err(|_| {
            input(format!(
                "data: expected a JointLog, a path or a list of them, got {}",
                d.get_type()
            ))
        })?;
        Ok(LogSource::File(absolute(&path)))
    };
    let single = data.cast::<JointLogPy>().is_ok()
        || data.extract::<String>().is_ok()
        || data.hasattr("__fspath__")?;
    if single {
        return Ok(vec![one(data)?]);
    }
    let logs = data
        .try_iter()
        .map_err(|_| input("data: expected a JointLog, a path or a list of them"))?
        .map(|d| one(&d?))
        .collect::<PyResult<Vec<_>>>()?;
    if logs.is_empty() {
        return Err(input("data: an empty list of logs"));
    }
    Ok(logs)
}

/// The map of a fit over many processes: the logs of ``data`` (a :class:`JointLog`, a path
/// read with :func:`read_log`, or a list of them) processed as :func:`fit` processes
/// them (same keywords and defaults: ``cutoff``, ``filter_torque``, ``trim``,
/// ``decimate``, ``min_speed``, ``resample``, ``stribeck``, ``settings``) and reduced to
/// an :class:`Observation` (``dvrk-ident observe``). ``fit(robot, [observe(robot, p) for p in
/// paths])`` is ``fit(robot, [read_log(p, robot) for p in paths])``.
///
/// Example (Dask)::
///
///     >>> import dask.bag as db
///     >>> obs = db.from_sequence(paths).map(lambda p: di.observe(psm, p)).fold(
///     ...     lambda a, b: a + b).compute()
///     >>> result = di.fit(psm, obs, method="wls")
#[pyfunction]
#[pyo3(signature = (robot, data, *, settings = None, **options))]
pub fn observe(
    py: Python<'_>,
    robot: &Bound<'_, ModelPy>,
    data: &Bound<'_, PyAny>,
    settings: Option<&Bound<'_, PyAny>>,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<ObservationPy> {
    let request = ObserveRequest {
        settings: crate::overrides::base(py, settings)?,
        overrides: crate::overrides::options("observe", options)?,
        ..ObserveRequest::new(log_sources(data)?)
    };
    let model = robot.get().model.clone();
    let state = background(py, move || request.run(&model, &Silent).map_err(fail_ident))?;
    Ok(wrap(state))
}

/// `data` as observations, when it is one or a list of them (`None` otherwise).
pub fn observations_arg(data: &Bound<'_, PyAny>) -> PyResult<Option<Vec<Arc<ObservationState>>>> {
    if let Ok(o) = data.cast::<ObservationPy>() {
        return Ok(Some(vec![o.get().inner.clone()]));
    }
    // Lists and tuples only: an iterator would be used up by the look.
    if !(data.is_instance_of::<PyList>() || data.is_instance_of::<pyo3::types::PyTuple>()) {
        return Ok(None);
    }
    let items = data.try_iter()?;
    let items: Vec<Bound<'_, PyAny>> = items.collect::<PyResult<_>>()?;
    let states: Vec<_> = items
        .iter()
        .filter_map(|i| {
            i.cast::<ObservationPy>()
                .ok()
                .map(|o| o.get().inner.clone())
        })
        .collect();
    if states.is_empty() {
        return Ok(None);
    }
    if states.len() != items.len() {
        return Err(input(
            "data: a list mixing Observation and logs: observe the logs first",
        ));
    }
    Ok(Some(states))
}
