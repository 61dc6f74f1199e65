//! Excitation trajectories: `FourierTrajectory` (a Fourier trajectory file), `excite` (the
//! optimizer of `dvrk-ident excite`) and `evaluate_trajectory` (its `--evaluate`).

use std::path::PathBuf;

use dvrk_ident::excite::optimize::{self, Excitation, ExciteOption, ExciteOptions};
use dvrk_ident::excite::{ExciteError, FourierError, FourierTrajectory};
use dvrk_ident::Silent;
use numpy::PyArrayDyn;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::classes::ModelPy;
use crate::convert::{array, background, matrix, rows, vector, Failure};
use crate::errors::{error, excite_kind, fourier_kind, input};
use crate::json::{to_python, write_document};
use crate::limits::limits_of;
use crate::overrides::{json, refused, unexpected};

/// A float64 numpy array.
type Array<'py> = Bound<'py, PyArrayDyn<f64>>;

fn fail_excite(e: ExciteError) -> Failure {
    (excite_kind(&e), crate::errors::text(&e))
}

fn from_excite(e: ExciteError) -> PyErr {
    error(excite_kind(&e), crate::errors::text(&e))
}

fn from_fourier(e: FourierError) -> PyErr {
    error(fourier_kind(&e), crate::errors::text(&e))
}

/// The functions that take excitation options as keywords, and which.
const FUNCTIONS: [(&str, &[ExciteOption]); 2] = [
    ("excite", ExciteOption::ALL),
    ("evaluate_trajectory", ExciteOption::EVALUATE),
];

/// `dvrk_ident._excite_options`: `{function: {keyword: default}}` in the library's
/// order (the stub's test checks the stub's defaults against it).
pub(crate) fn options_table<'py>(py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
    let table = PyDict::new(py);
    for (function, options) in FUNCTIONS {
        let defaults = PyDict::new(py);
        for o in options {
            defaults.set_item(o.name(), to_python(py, &o.default_value())?)?;
        }
        table.set_item(function, defaults)?;
    }
    Ok(table)
}

/// The library's excitation options from `function`'s arguments: those it takes by
/// position (`given`) and its keyword arguments (`None`: the default), converted by
/// the library's one conversion ([`ExciteOptions::from_values`]). A keyword that is not
/// one of `function`'s options is a `TypeError`, as Python's own.
fn excite_options(
    function: &str,
    given: &[(ExciteOption, Option<&Bound<'_, PyAny>>)],
    kwargs: Option<&Bound<'_, PyDict>>,
) -> PyResult<ExciteOptions> {
    let scope = FUNCTIONS
        .iter()
        .find(|(f, _)| *f == function)
        .map_or(&[][..], |(_, s)| *s);
    let mut values = Vec::new();
    for (option, value) in given {
        if let Some(value) = value.filter(|v| !v.is_none()) {
            values.push((*option, json(value, option.name())?));
        }
    }
    for (key, value) in kwargs.into_iter().flatten() {
        let name: String = key.extract()?;
        let option = ExciteOption::from_name(&name)
            .filter(|o| scope.contains(o) && !given.iter().any(|(g, _)| g == o))
            .ok_or_else(|| unexpected(function, &name))?;
        if !value.is_none() {
            values.push((option, json(&value, option.name())?));
        }
    }
    ExciteOptions::from_values(values).map_err(|e| refused(e.option.name(), &e.message))
}

/// Coefficients `a` or `b`: a 2-D array of `order` columns, one row per coordinate.
fn coefficient_rows(
    py: Python<'_>,
    obj: &Bound<'_, PyAny>,
    order: usize,
    name: &str,
) -> PyResult<Vec<Vec<f64>>> {
    let r = rows(py, obj, order, name, &[])?;
    if r.single {
        return Err(input(format!(
            "{name}: expected a 2-D array (coordinates, order {order}), got shape ({order},)"
        )));
    }
    Ok(r.data.chunks(order.max(1)).map(<[f64]>::to_vec).collect())
}

/// A periodic excitation trajectory: per model coordinate ``j``, ``q_j(t) = q0_j +
/// Σ_l (a_jl sin(l w t) − b_jl cos(l w t)) / (l w)`` with ``w = 2π f0``, ``l = 1..order``
/// (the 2019 package's formula; ``a``, ``b`` are velocity amplitudes, rad/s or m/s).
/// The JSON layout of ``dvrk-ident excite --out`` (``order``, ``base_frequency_hz``,
/// ``q0``, ``a``, ``b``, optional ``coordinates``).
///
/// Example::
///
///     >>> t = di.FourierTrajectory(order=1, base_frequency_hz=0.5, q0=[0.2], a=[[1.0]], b=[[0.0]])
///     >>> q, dq, ddq = t.sample([0.0, 0.5])
///     >>> dq[0, 0]
///     1.0
#[pyclass(name = "FourierTrajectory", module = "dvrk_ident", frozen)]
pub struct FourierTrajectoryPy {
    pub inner: FourierTrajectory,
}

#[pymethods]
impl FourierTrajectoryPy {
    /// Pickling (and ``copy.deepcopy``): the JSON document of :meth:`write`.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
        let py = slf.py();
        let args = (slf.get().inner.to_json(),).into_pyobject(py)?.into_any();
        Ok((slf.get_type().getattr("_restore")?, args))
    }

    /// The inverse of ``__reduce__``.
    #[staticmethod]
    fn _restore(text: &str) -> PyResult<Self> {
        Ok(FourierTrajectoryPy {
            inner: FourierTrajectory::from_json_str(text, "<pickle>")
                .map_err(|e| input(crate::errors::text(&e)))?,
        })
    }

    #[new]
    #[pyo3(signature = (order, base_frequency_hz, q0, a, b, coordinates = None))]
    fn py_new(
        py: Python<'_>,
        order: usize,
        base_frequency_hz: f64,
        q0: &Bound<'_, PyAny>,
        a: &Bound<'_, PyAny>,
        b: &Bound<'_, PyAny>,
        coordinates: Option<Vec<String>>,
    ) -> PyResult<Self> {
        let inner = FourierTrajectory {
            order,
            base_frequency_hz,
            q0: vector(py, q0, None, "q0", &[])?,
            a: coefficient_rows(py, a, order, "a")?,
            b: coefficient_rows(py, b, order, "b")?,
            coordinates: coordinates.unwrap_or_default(),
            robot: None,
        };
        inner.validate("FourierTrajectory").map_err(from_fourier)?;
        Ok(FourierTrajectoryPy { inner })
    }

    /// Reads a trajectory file: the JSON of ``dvrk-ident excite`` (any file with the
    /// five keys), or with ``pick`` the named trajectory (e.g. ``"psm_one"``) of a
    /// 2019-layout coefficient file.
    #[staticmethod]
    #[pyo3(signature = (path, pick = None))]
    fn read(path: PathBuf, pick: Option<&str>) -> PyResult<Self> {
        let inner = match pick {
            Some(name) => FourierTrajectory::from_wpi_file(&path, name),
            None => FourierTrajectory::from_json_file(&path),
        }
        .map_err(from_fourier)?;
        Ok(FourierTrajectoryPy { inner })
    }

    /// Parses the JSON layout; ``source`` names the text in error messages.
    #[staticmethod]
    #[pyo3(signature = (text, source = "<string>"))]
    fn from_json(text: &str, source: &str) -> PyResult<Self> {
        let inner = FourierTrajectory::from_json_str(text, source).map_err(from_fourier)?;
        Ok(FourierTrajectoryPy { inner })
    }

    /// The trajectory names of a 2019-layout coefficient file (sorted).
    #[staticmethod]
    fn wpi_names(path: PathBuf) -> PyResult<Vec<String>> {
        FourierTrajectory::wpi_names(&path).map_err(from_fourier)
    }

    /// Deprecated name of :meth:`wpi_names`.
    #[staticmethod]
    fn wpi2019_names(py: Python<'_>, path: PathBuf) -> PyResult<Vec<String>> {
        crate::deprecated::warn(
            py,
            "FourierTrajectory.wpi2019_names",
            "FourierTrajectory.wpi_names",
        )?;
        Self::wpi_names(path)
    }

    /// Number of harmonics ``L``.
    #[getter]
    fn order(&self) -> usize {
        self.inner.order
    }

    /// Base frequency ``f0``, Hz.
    #[getter]
    fn base_frequency_hz(&self) -> f64 {
        self.inner.base_frequency_hz
    }

    /// Period ``1 / f0``, s.
    #[getter]
    fn period(&self) -> f64 {
        self.inner.period_s()
    }

    /// Number of coordinates.
    #[getter]
    fn dof(&self) -> usize {
        self.inner.dof()
    }

    /// Offsets, rad or m: shape ``(dof,)``.
    #[getter]
    fn q0<'py>(&self, py: Python<'py>) -> Bound<'py, PyArrayDyn<f64>> {
        let n = self.inner.dof();
        array(py, self.inner.q0.clone(), &[n])
    }

    /// Sine coefficients, rad/s or m/s: shape ``(dof, order)``.
    #[getter]
    fn a<'py>(&self, py: Python<'py>) -> Bound<'py, PyArrayDyn<f64>> {
        let (n, l) = (self.inner.dof(), self.inner.order);
        array(py, self.inner.a.concat(), &[n, l])
    }

    /// Cosine coefficients, rad/s or m/s: shape ``(dof, order)``.
    #[getter]
    fn b<'py>(&self, py: Python<'py>) -> Bound<'py, PyArrayDyn<f64>> {
        let (n, l) = (self.inner.dof(), self.inner.order);
        array(py, self.inner.b.concat(), &[n, l])
    }

    /// Coordinate names (empty when the file has none).
    #[getter]
    fn coordinates(&self) -> Vec<String> {
        self.inner.coordinates.clone()
    }

    /// Positions, velocities and accelerations (model coordinates: rad or m, and their
    /// rates) at the times ``time`` (s, 1-D): three arrays of shape ``(N, dof)``.
    fn sample<'py>(
        &self,
        py: Python<'py>,
        time: &Bound<'py, PyAny>,
    ) -> PyResult<(Array<'py>, Array<'py>, Array<'py>)> {
        let t = vector(py, time, None, "time", &[])?;
        let inner = &self.inner;
        let (q, dq, ddq) = py.detach(|| inner.sample(&t));
        Ok((matrix(py, &q), matrix(py, &dq), matrix(py, &ddq)))
    }

    /// One period of setpoints at ``rate`` Hz in ``robot``'s MEASURED joint space (what a
    /// dVRK script plays back, the CSV of ``excite --csv``): ``(time, positions)`` with
    /// ``time`` of shape ``(N,)`` (s, from 0) and ``positions`` ``(N,
    /// len(robot.measured_joints))`` (rad or m).
    #[pyo3(signature = (robot, rate = dvrk_ident::excite::setpoints::DEFAULT_RATE_HZ))]
    fn setpoints<'py>(
        &self,
        py: Python<'py>,
        robot: &Bound<'py, ModelPy>,
        rate: f64,
    ) -> PyResult<(Array<'py>, Array<'py>)> {
        let model = &robot.get().model;
        let (t, q) = dvrk_ident::excite::setpoints::setpoints(model, &self.inner, rate)
            .map_err(from_excite)?;
        let n = t.len();
        Ok((array(py, t, &[n]), matrix(py, &q)))
    }

    /// The JSON document (values round-trip exactly).
    fn to_json(&self) -> String {
        self.inner.to_json()
    }

    /// The document as a dict.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_python(py, &self.inner)
    }

    /// Writes :meth:`to_json` to ``path`` atomically (temporary file and rename).
    fn write(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        write_document(py, &path, self.inner.to_json())
    }

    fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
        other
            .cast::<FourierTrajectoryPy>()
            .is_ok_and(|o| o.get().inner == self.inner)
    }

    fn __repr__(&self) -> String {
        format!(
            "FourierTrajectory(order={}, base_frequency_hz={}, dof={})",
            self.inner.order,
            self.inner.base_frequency_hz,
            self.inner.dof()
        )
    }
}

/// An optimized excitation trajectory (:func:`excite`) with its criterion and the
/// dense feasibility check.
#[pyclass(name = "Excitation", module = "dvrk_ident", frozen)]
pub struct ExcitationPy {
    inner: Excitation,
}

#[pymethods]
impl ExcitationPy {
    /// The optimized :class:`FourierTrajectory`.
    #[getter]
    fn trajectory(&self) -> FourierTrajectoryPy {
        FourierTrajectoryPy {
            inner: self.inner.trajectory.clone(),
        }
    }

    /// ``{"name": "condition" | "log_det", "value": float}``.
    #[getter]
    fn criterion<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_python(py, &self.inner.evaluation.criterion)
    }

    /// Always ``True``: an infeasible optimum raises ``SolverError`` instead.
    #[getter]
    fn feasible(&self) -> bool {
        self.inner.evaluation.feasibility.feasible
    }

    /// The dense check (``samples``, ``rate_hz``, ``worst``: the tightest margin,
    /// ``violated``), as in :func:`evaluate_trajectory`.
    #[getter]
    fn feasibility<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_python(py, &self.inner.evaluation.feasibility)
    }

    /// The criterion of each start's final trajectory (``None``: not refined).
    #[getter]
    fn starts(&self) -> Vec<Option<f64>> {
        self.inner.starts.clone()
    }

    /// The document of ``dvrk-ident excite --out``: the trajectory keys plus
    /// ``criterion`` and ``feasibility``.
    fn to_json(&self) -> String {
        serde_json::to_string_pretty(&self.inner.to_json_value()).expect("serializable")
    }

    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_python(py, &self.inner.to_json_value())
    }

    /// Writes :meth:`to_json` to ``path`` atomically.
    fn write(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        write_document(py, &path, self.to_json())
    }

    fn __repr__(&self) -> String {
        let c = &self.inner.evaluation.criterion;
        format!(
            "Excitation({}={:.6}, order={}, base_frequency_hz={})",
            c.name, c.value, self.inner.trajectory.order, self.inner.trajectory.base_frequency_hz
        )
    }
}

/// Optimizes an excitation trajectory for ``robot``: ``dvrk-ident excite`` (same
/// options and defaults, same result for the same seed).
///
/// Minimizes the condition number of the column-normalized base regressor over one
/// period (``criterion="log_det"``: maximizes its log-determinant) subject to the
/// limits: ``None`` (the robot description's ``[[limits]]`` and
/// ``[[cartesian_limits]]``), a limits file path, or a dict in that file's layout, e.g.
/// ``{"limits": [{"expr": "q1", "position": [-1, 1], "velocity": [-2, 2]}],
/// "cartesian_limits": [{"frame": "tip", "min": [-1, -1, 0.1], "max": [1, 1, 1]}]}``
/// (box corners in metres, base frame; ``float("inf")`` leaves a side open). A file
/// or dict replaces the robot's limits: start from a copy of :attr:`Model.limits` to
/// add to them.
/// ``rest=True``: zero velocity and acceleration at the start and end of the period.
/// ``init``: a :class:`FourierTrajectory` (same order and base frequency) refined by the
/// first start. Deterministic for a ``seed``.
///
/// The result passed the dense check (``check_rate`` Hz, at least 1 kHz); when no
/// start gives a feasible trajectory, ``SolverError`` is raised; limits that admit no
/// motion raise ``InputError``. Runs without the GIL; Ctrl-C raises
/// ``KeyboardInterrupt`` (the optimization finishes in the background, discarded).
///
/// Example::
///
///     >>> ex = di.excite(di.Model.load("psm_simplified"), order=6, f0=0.18, seed=0)
///     >>> ex.criterion["value"], ex.feasible
///     >>> ex.trajectory.write("traj.json")
#[pyfunction]
#[pyo3(signature = (robot, order = None, f0 = None, *, limits = None, init = None, **options))]
pub fn excite(
    py: Python<'_>,
    robot: &Bound<'_, ModelPy>,
    order: Option<&Bound<'_, PyAny>>,
    f0: Option<&Bound<'_, PyAny>>,
    limits: Option<&Bound<'_, PyAny>>,
    init: Option<&Bound<'_, FourierTrajectoryPy>>,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<ExcitationPy> {
    let given = [(ExciteOption::Order, order), (ExciteOption::F0, f0)];
    let opts = ExciteOptions {
        init: init.map(|t| t.get().inner.clone()),
        ..excite_options("excite", &given, options)?
    };
    let model = robot.get().model.clone();
    let base = robot.get().base_parameters(py)?;
    let limits = limits_of(&model, limits)?;
    let inner = background(py, move || {
        optimize::optimize(&model, &base, &limits, &opts, &Silent).map_err(fail_excite)
    })?;
    Ok(ExcitationPy { inner })
}

/// Evaluates any trajectory against ``robot``: ``dvrk-ident excite --evaluate --json``.
/// Returns ``{"criterion": {"name", "value"}, "feasible", "worst_violation",
/// "violated", "check_samples", "check_rate_hz"}``; ``worst_violation`` is the largest
/// excess over every limit and sample of the dense check (``limit``, ``quantity``,
/// ``time_s``, ``value``, ``bound``, ``excess``; a negative excess is the tightest
/// margin), ``violated`` lists every violated limit, worst first. ``limits`` as in
/// :func:`excite`.
///
/// Example::
///
///     >>> old = di.FourierTrajectory.read("wpi2019_excitation_trajectories.json", pick="psm_one")
///     >>> di.evaluate_trajectory(di.Model.load("psm_simplified"), old)["feasible"]
///     False
#[pyfunction]
#[pyo3(signature = (robot, trajectory, *, limits = None, **options))]
pub fn evaluate_trajectory<'py>(
    py: Python<'py>,
    robot: &Bound<'py, ModelPy>,
    trajectory: &Bound<'py, FourierTrajectoryPy>,
    limits: Option<&Bound<'py, PyAny>>,
    options: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyAny>> {
    let opts = excite_options("evaluate_trajectory", &[], options)?;
    let model = robot.get().model.clone();
    let base = robot.get().base_parameters(py)?;
    let limits = limits_of(&model, limits)?;
    let traj = trajectory.get().inner.clone();
    if let Some(warning) = traj.robot_mismatch(&model, "the trajectory") {
        crate::warnings::warn_all(py, &[warning])?;
    }
    let ev = background(py, move || {
        optimize::evaluate(
            &model,
            &base,
            &traj,
            &limits,
            opts.criterion,
            opts.samples_per_harmonic,
            opts.check_rate_hz,
        )
        .map_err(fail_excite)
    })?;
    to_python(py, &ev.to_json_value())
}
