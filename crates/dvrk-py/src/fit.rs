//! `fit`, `prepare` and the fit `FitResult`.

use std::path::PathBuf;
use std::sync::Arc;

use dvrk_ident::excite::FourierTrajectory;
use dvrk_ident::export::Export;
use dvrk_ident::validate::{joint_metrics, predict, prepare as prepare_data, JointMap};
use dvrk_ident::JointLog;
use dvrk_ident::Joints;
use dvrk_ident::Silent;
use dvrk_ident::{FitRequest, LogSource, Streaming, Training};
use dvrk_ident::{FitResult, FitSettings};
use dvrk_model::Model;
use numpy::PyArrayDyn;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::classes::{FitResultPy, ModelPy};
use crate::convert::{array, background, matrix, py_bool, py_str};
use crate::data::{fail_ident, JointLogPy, PreparedPy};
use crate::errors::{error, fourier_kind, from_ident, from_io, from_model, input, Kind};
use crate::excite::FourierTrajectoryPy;
use crate::json::{to_python, write_document};
use crate::observe::observations_arg;
use crate::warnings::warn_all;

/// A :class:`JointLog` or a list of them: the samples and the files they were read from.
pub(crate) fn logs_arg(
    obj: &Bound<'_, PyAny>,
    name: &str,
) -> PyResult<Vec<(Arc<JointLog>, Option<PathBuf>)>> {
    let one = |d: &Bound<'_, PyAny>| -> PyResult<(Arc<JointLog>, Option<PathBuf>)> {
        let d = d.cast::<JointLogPy>().map_err(|_| {
            input(format!(
                "{name}: expected a JointLog or a list of JointLog, got {}",
                d.get_type()
            ))
        })?;
        Ok((d.get().log.clone(), d.get().path.clone()))
    };
    if obj.cast::<JointLogPy>().is_ok() {
        return Ok(vec![one(obj)?]);
    }
    let logs = obj
        .try_iter()
        .map_err(|_| input(format!("{name}: expected a JointLog or a list of JointLog")))?
        .map(|d| one(&d?))
        .collect::<PyResult<Vec<_>>>()?;
    if logs.is_empty() {
        return Err(input(format!("{name}: an empty list of logs")));
    }
    Ok(logs)
}

fn samples(logs: Vec<(Arc<JointLog>, Option<PathBuf>)>) -> Vec<LogSource> {
    logs.into_iter()
        .map(|(samples, file)| LogSource::Samples { samples, file })
        .collect()
}

/// Identifies the robot's parameters from logs: the pipeline of ``dvrk-ident fit``
/// (model coordinates, known forces subtracted, zero-phase low-pass, derivatives,
/// trimming, the R factor of the weighted regressor, the estimator) and the same
/// result document.
///
/// - ``method``: ``"ols"``, ``"wls"``, ``"irls"`` or ``"sdp"`` (the default: the
///   physically consistent semidefinite fit);
/// - ``cutoff``: low-pass cut-off of the motion (positions, velocities,
///   accelerations), Hz, one number or one per coordinate (default 5.4 Hz; the 2019
///   PSM/MTM fits effectively used 16.965/5.655), or ``"none"`` (or ``False``) for no
///   filter; ``filter_torque=True`` filters the torques too (the 2019 protocol);
/// - ``data``: a :class:`JointLog` or a list of them (``dvrk-ident fit a b c``): each log is
///   processed on its own (filters and trimming never cross from one to the next) and
///   their observations merged; ``result.inputs`` lists every log with its hash (of
///   the file it was read from, else of its samples) and its own metrics. Or an
///   :class:`Observation` or a list of them (:func:`observe`, ``dvrk-ident fit
///   --states``): merged in order and fitted with their own processing settings, the
///   result of the fit of their logs;
/// - ``test``: a :class:`JointLog` or a list to validate on, ``test_window``: metrics on
///   the first N processed samples of each only; ``excitation``: the
///   :class:`FourierTrajectory` the logs follow (or the path of its JSON document): with
///   ``test`` but no ``test_window`` the test metrics cover its first period (the 2019
///   protocol, ``--excitation``);
/// - ``trim`` (default 200), ``decimate``, ``min_speed`` (rad/s or m/s),
///   ``resample`` (Hz, of the samples given), ``irls_iterations``,
///   ``sdp_regularization``, ``stribeck`` (adds a Stribeck term with this velocity,
///   rad/s or m/s, to every friction element), ``dahl`` (adds Dahl friction, a
///   hysteresis over the displacement, with this stiffness, 1/rad or 1/m, to every
///   friction element, as ``--dahl``), ``position_torque`` (adds a position-dependent
///   torque, a Fourier series of this order, 1 to 3, in the joint angle, to every
///   revolute friction element, as ``--position-torque``; 0: none),
///   ``position_torque_frames`` (the frames of it by name, a list or
///   ``"upper_arm,forearm"``, as ``--position-torque-frames``), ``load_friction``
///   (``True`` adds Coulomb friction in proportion to each coordinate's torque, as
///   ``--load-friction``);
/// - ``delay``: the torques' measurement delays (``dvrk-ident fit --delay``):
///   ``"auto"`` (estimated per coordinate within 0–0.150 s, in ``result.delay`` and
///   applied through ``result.settings["processing"]["delay_s"]``), seconds for every
///   coordinate, or a list of seconds, one per coordinate (``0``: none, the default);
/// - ``bounds``: ``"physical"`` (friction ≥ 0, motor inertias ≥ 1e-6) or ``"2019"`` (≥ 0.001,
///   to reproduce the 2019 fit): the semidefinite fit's lower bounds in place of the
///   robot description's (``dvrk-ident fit --bounds``);
/// - ``ellipsoids``: ``False`` ignores the links' bounding ellipsoids of the robot
///   description, which the semidefinite fit otherwise keeps each link's mass inside
///   (``dvrk-ident fit --no-ellipsoids``);
/// - ``mounting_pitch``: the arm's mounting pitch (degrees) as the dVRK states it: gravity
///   ``(0, −9.81·sin p, −9.81·cos p)`` m/s² in the base frame, recorded in the result
///   (``dvrk-ident fit --mounting-pitch``);
/// - ``prior``: regularize the semidefinite fit toward ``"nominal"`` (the robot
///   description's nominal parameters, e.g. a URDF's inertias), a result document's
///   path or a :class:`FitResult`; ``prior_weight`` (default 0.001, relative to the data
///   term) and ``prior_metric`` (``"entropic"``, the default: the log-det divergence
///   of each link's pseudo-inertia from the prior's, or ``"euclidean"``), as
///   ``--prior``, ``--prior-weight``, ``--prior-metric``; the values used are in
///   ``result.settings["prior"]``;
/// - ``preset``: ``"dvrk"``, the settings recommended for the dVRK arms for every
///   keyword not given (``method="sdp"``, ``stribeck=0.3``, ``dahl=20``, the prior
///   toward nominal masses and the description's ``[preset]`` elements, as
///   ``--preset dvrk``); the result records what it expanded to;
/// - ``joints``: ``"model"`` (the default) or ``"measured"``: the metrics in the model
///   coordinates or in the arm's measured joints by name (``--joints``); the fit is the
///   same, and the result's ``validate``, ``prepare`` and ``predict`` show these joints
///   by default;
/// - ``settings``: a dict in the layout of ``FitResult.settings`` (missing fields take
///   the defaults), for everything else (e.g. the 2019 filter form); the keywords
///   above override it.
///
/// The keywords are the flags of ``dvrk-ident fit`` (``filter_torque`` is
/// ``--filter-torque``...), applied by the same library request
/// (``dvrk_ident::FitRequest``), so both give the same result document.
///
/// A fit whose solver did not converge raises ``NotConvergedError`` (its ``result``
/// attribute holds the unconverged :class:`FitResult`) unless ``allow_unconverged``.
///
/// The work runs without the GIL on a worker thread; Ctrl-C raises
/// ``KeyboardInterrupt`` within 50 ms, while the interrupted computation finishes in
/// the background (the library cannot cancel it) and is discarded.
///
/// Example::
///
///     >>> result = di.fit(psm, train, method="ols", cutoff=16.965, test=test,
///     ...                 test_window=1111)
///     >>> result.metrics["test"]["relative_error"]
#[pyfunction]
#[pyo3(signature = (robot, data, method = None, *, test = None, excitation = None, settings = None, allow_unconverged = false, **options))]
#[allow(clippy::too_many_arguments)]
pub fn fit(
    py: Python<'_>,
    robot: &Bound<'_, ModelPy>,
    data: &Bound<'_, PyAny>,
    method: Option<&Bound<'_, PyAny>>,
    test: Option<&Bound<'_, PyAny>>,
    excitation: Option<&Bound<'_, PyAny>>,
    settings: Option<&Bound<'_, PyAny>>,
    allow_unconverged: bool,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<FitResultPy> {
    // `method` is positional too: one of the options all the same.
    let options = match method {
        Some(m) => {
            let all = options.map_or_else(|| Ok(PyDict::new(py)), |o| o.copy())?;
            all.set_item("method", m)?;
            Some(all)
        }
        None => options.cloned(),
    };
    let overrides = crate::overrides::options("fit", options.as_ref())?;
    let train = match observations_arg(data)? {
        Some(states) => Training::Observations(states.into_iter().map(|s| (s, None)).collect()),
        None => Training::Logs(samples(logs_arg(data, "data")?)),
    };
    let test = match test.filter(|t| !t.is_none()) {
        Some(t) => samples(logs_arg(t, "test")?),
        None => Vec::new(),
    };
    let excitation = match excitation.filter(|e| !e.is_none()) {
        None => None,
        Some(e) => {
            Some(match e.cast::<FourierTrajectoryPy>() {
                Ok(t) => t.get().inner.clone(),
                Err(_) => {
                    let path: PathBuf = e.extract().map_err(|_| {
                    input("excitation: expected a FourierTrajectory or the path of its JSON document")
                })?;
                    FourierTrajectory::from_json_file(&path)
                        .map_err(|err| error(fourier_kind(&err), crate::errors::text(&err)))?
                }
            })
        }
    };
    let request = FitRequest {
        test,
        settings: crate::overrides::base(py, settings)?,
        overrides,
        excitation,
        streaming: Streaming::Never,
        ..FitRequest::new(train)
    };
    let model = robot.get().model.clone();
    let inner = background(py, move || {
        request
            .run(Some(&model), &Silent)
            .map(|outcome| outcome.result)
            .map_err(fail_ident)
    })?;
    warn_all(py, &inner.repeated_inputs())?;
    let converged = inner.solver.converged;
    let status = inner.solver.status;
    let result = FitResultPy::new(inner, Some(robot.clone().unbind()));
    if !converged && !allow_unconverged {
        let err = error(
            Kind::NotConverged,
            format!(
                "the solver did not converge (status {status}): the parameters are not a result"
            ),
        );
        err.value(py).setattr("result", Py::new(py, result)?)?;
        return Err(err);
    }
    Ok(result)
}

/// The samples an estimator sees (see :class:`Prepared`): ``data`` mapped to
/// ``robot``'s model coordinates, known forces subtracted, filtered, differentiated
/// and trimmed, with the settings of :func:`fit` (same keywords and defaults).
#[pyfunction]
#[pyo3(signature = (robot, data, *, settings = None, **options))]
pub fn prepare(
    py: Python<'_>,
    robot: &Bound<'_, ModelPy>,
    data: &Bound<'_, JointLogPy>,
    settings: Option<&Bound<'_, PyAny>>,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<PreparedPy> {
    let settings =
        crate::overrides::options("prepare", options)?.apply(crate::overrides::base(py, settings)?);
    prepared(py, robot.get().model.clone(), data.get(), settings)
}

/// `data` prepared for `model` with `settings`' processing, shown in its joints.
fn prepared(
    py: Python<'_>,
    model: Arc<Model>,
    data: &JointLogPy,
    settings: FitSettings,
) -> PyResult<PreparedPy> {
    let log = data.log.clone();
    let map = JointMap::new(&model, settings.joints).map_err(from_ident)?;
    let p = background(py, move || {
        prepare_data(&model, &log, &settings.processing).map_err(fail_ident)
    })?;
    Ok(PreparedPy::new(p, &map))
}

impl FitResultPy {
    /// The joints of a `joints=` keyword, the fit's own without one.
    fn joints(&self, joints: Option<&str>) -> PyResult<Joints> {
        match joints {
            Some(j) => crate::overrides::parse_joints(j),
            None => Ok(self.inner.settings.joints),
        }
    }

    /// The model: `robot`, else the one fitted with, else loaded from `robot_source`;
    /// with the fit's model options (Stribeck terms) applied.
    pub(crate) fn model(
        &self,
        py: Python<'_>,
        robot: Option<&Bound<'_, ModelPy>>,
    ) -> PyResult<Arc<Model>> {
        let base = if let Some(r) = robot {
            r.get().model.clone()
        } else if let Some(r) = &self.robot {
            r.get().model.clone()
        } else {
            let name = self.inner.robot().to_string();
            Arc::new(py.detach(move || Model::load(&name)).map_err(from_model)?)
        };
        let fitted = self
            .inner
            .model_for(&base, "FitResult")
            .map_err(from_ident)?;
        Ok(crate::robot::shared(&base, fitted))
    }

    /// The parameters in `model`'s order, the result's payload (if any) added.
    pub(crate) fn params(&self, model: &Model) -> PyResult<Vec<f64>> {
        self.inner.params_for(model).map_err(from_ident)
    }
}

fn with_robot(inner: FitResult, robot: Option<&Bound<'_, ModelPy>>) -> FitResultPy {
    FitResultPy::new(inner, robot.map(|r| r.clone().unbind()))
}

#[pymethods]
impl FitResultPy {
    /// A result from the JSON text of ``dvrk-ident fit --out`` / :meth:`to_json`;
    /// ``robot`` (optional) is used by :meth:`predict` and friends instead of loading
    /// ``robot_source``.
    #[staticmethod]
    #[pyo3(signature = (text, robot = None))]
    fn from_json(text: &str, robot: Option<&Bound<'_, ModelPy>>) -> PyResult<Self> {
        let inner =
            FitResult::from_json(text, "<string>").map_err(|e| input(crate::errors::text(&e)))?;
        Ok(with_robot(inner, robot))
    }

    /// Reads a result file (``dvrk-ident fit --out``).
    #[staticmethod]
    #[pyo3(signature = (path, robot = None))]
    fn read(path: PathBuf, robot: Option<&Bound<'_, ModelPy>>) -> PyResult<Self> {
        let text = dvrk_model::input::read_text(&path).map_err(|e| from_io(&path, &e))?;
        let inner = FitResult::from_json(&text, &path.display().to_string())
            .map_err(|e| input(crate::errors::text(&e)))?;
        Ok(with_robot(inner, robot))
    }

    /// The result document as JSON text, exactly as ``dvrk-ident fit --out`` writes it.
    fn to_json(&self) -> String {
        self.inner.to_json()
    }

    /// Pickling (and ``copy.deepcopy``): the document and the robot.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
        let py = slf.py();
        let r = slf.get();
        let robot = r.robot.as_ref().map(|x| x.clone_ref(py));
        let args = (r.inner.to_json(), robot).into_pyobject(py)?.into_any();
        Ok((slf.get_type().getattr("_restore")?, args))
    }

    /// The inverse of ``__reduce__``.
    #[staticmethod]
    #[pyo3(signature = (text, robot = None))]
    fn _restore(text: &str, robot: Option<&Bound<'_, ModelPy>>) -> PyResult<Self> {
        let inner =
            FitResult::from_json(text, "<pickle>").map_err(|e| input(crate::errors::text(&e)))?;
        Ok(with_robot(inner, robot))
    }

    /// The whole result document as a dict (``json.loads(to_json())``).
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_python(py, &self.inner)
    }

    /// Writes :meth:`to_json` to ``path`` atomically (temporary file and rename).
    fn write(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        write_document(py, &path, self.inner.to_json())
    }

    /// Every parameter by name, in the model's order (barycentric: inertia about the
    /// frame origin, first moment, mass; friction; motor inertia; spring). For least
    /// squares, a representative: base parameters on their kept columns, zero elsewhere.
    #[getter]
    fn parameters<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        for (k, v) in &self.inner.parameters {
            d.set_item(k, *v)?;
        }
        Ok(d)
    }

    /// The parameter values as an array in ``parameter_order`` (the robot's
    /// ``parameter_names``), for :meth:`Model.inverse_dynamics` and friends.
    #[getter]
    fn parameter_array<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let v: Vec<f64> = self
            .inner
            .parameter_order
            .iter()
            .map(|k| {
                self.inner
                    .parameters
                    .get(k)
                    .copied()
                    .ok_or_else(|| input(format!("result: parameter {k} has no value")))
            })
            .collect::<PyResult<_>>()?;
        let n = v.len();
        Ok(array(py, v, &[n]))
    }

    /// Parameter names in the model's order.
    #[getter]
    fn parameter_order(&self) -> Vec<String> {
        self.inner.parameter_order.clone()
    }

    /// What the data determined of each parameter: ``{name: "identified" |
    /// "at_lower_bound" | "at_upper_bound" | "unidentified"}`` (empty for a result
    /// written before statuses); per link, ``links[i]["determined"]``.
    #[getter]
    fn parameter_status<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_python(py, &self.inner.parameter_status)
    }

    #[getter]
    fn base_parameters<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_python(py, &self.inner.base_parameters)
    }

    #[getter]
    fn links<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_python(py, &self.inner.links)
    }

    #[getter]
    fn consistency<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_python(py, &self.inner.consistency)
    }

    #[getter]
    fn physically_consistent(&self) -> bool {
        self.inner.physically_consistent
    }

    #[getter]
    fn solver<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_python(py, &self.inner.solver)
    }

    #[getter]
    fn metrics<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_python(py, &self.inner.metrics)
    }

    /// The measurement delays estimated by ``delay="auto"``: ``{delay_s, std_s, max_s,
    /// residual, sweeps}`` (seconds), or ``None``.
    #[getter]
    fn delay<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_python(py, &self.inner.delay)
    }

    /// The friction model chosen by held-out error (``select=``): ``{folds, joints,
    /// candidates: [{candidate, relative_error, mean}], chosen}``, or ``None``.
    #[getter]
    fn selection<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_python(py, &self.inner.selection)
    }

    /// The payload the arm carries (:func:`identify_payload`): ``{frame, mass, com,
    /// inertia, identification}`` (kg, m in the frame, kg·m² about the centre of mass
    /// ``xx yy zz xy xz yz``), or ``None``. :attr:`parameters` stay the arm's own; every
    /// use of the result as a model (validate, exports) adds the payload.
    #[getter]
    fn payload<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_python(py, &self.inner.payload)
    }

    /// With an entropic prior: the summed log-det divergence of the links from the
    /// prior's (no units), or ``None``.
    #[getter]
    fn prior_divergence(&self) -> Option<f64> {
        self.inner.prior_divergence
    }

    #[getter]
    fn settings<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_python(py, &self.inner.settings)
    }

    #[getter]
    fn inputs<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_python(py, &self.inner.inputs)
    }

    #[getter]
    fn method(&self) -> String {
        self.inner.method.clone()
    }

    /// The robot's name.
    #[getter]
    fn robot(&self) -> String {
        self.inner.robot.clone()
    }

    #[getter]
    fn robot_source(&self) -> String {
        self.inner.robot_source.clone()
    }

    #[getter]
    fn tool(&self) -> String {
        self.inner.tool.clone()
    }

    /// Row weights per coordinate used by the estimator, ``(dof,)``.
    #[getter]
    fn weights<'py>(&self, py: Python<'py>) -> Bound<'py, PyArrayDyn<f64>> {
        let n = self.inner.weights.len();
        array(py, self.inner.weights.clone(), &[n])
    }

    /// The :class:`Model` of this result, whose parameters are this result's: the one it
    /// was fitted (or read) with, else loaded from ``robot_source``, with the model
    /// options of its fit (Stribeck and Dahl terms, mounting pitch: its gravity).
    fn load_robot(&self, py: Python<'_>) -> PyResult<Py<ModelPy>> {
        let settings = self.inner.settings.clone();
        if let Some(r) = &self.robot {
            let given = r.get();
            // The robot given to the fit when the fit's options change nothing in it,
            // else a copy with them.
            return match self
                .inner
                .model_for(&given.model, "FitResult")
                .map_err(from_ident)?
            {
                std::borrow::Cow::Borrowed(_) => Ok(r.clone_ref(py)),
                std::borrow::Cow::Owned(m) => {
                    Py::new(py, ModelPy::fitted(m, given.origin.clone(), Some(settings)))
                }
            };
        }
        Py::new(py, ModelPy::of_result(py, self.inner.robot(), settings)?)
    }

    /// The processed samples of ``data`` with this result's processing settings (see
    /// :class:`Prepared`); the rows :meth:`predict` returns torques for. ``joints``:
    /// ``"model"`` or ``"measured"`` (default: the fit's ``joints``).
    #[pyo3(signature = (data, robot = None, *, joints = None))]
    fn prepare(
        &self,
        py: Python<'_>,
        data: &Bound<'_, JointLogPy>,
        robot: Option<&Bound<'_, ModelPy>>,
        joints: Option<&str>,
    ) -> PyResult<PreparedPy> {
        let model = self.model(py, robot)?;
        let mut settings = self.inner.settings.clone();
        settings.joints = self.joints(joints)?;
        prepared(py, model, data.get(), settings)
    }

    /// Torques predicted by the identified parameters, ``H(q, dq, ddq) @ params``
    /// (N·m or N), shape ``(N, dof)``, without known forces, in the model coordinates
    /// or the arm's measured joints (``joints``; default: a ``Prepared``'s own, else the
    /// fit's ``joints``).
    ///
    /// ``data`` is a :class:`JointLog` (a log as read) or a :class:`Prepared`. A ``JointLog``
    /// is first processed with this result's settings, exactly as for the fit and its
    /// metrics: mapped to model coordinates, filtered, differentiated and trimmed, so
    /// row ``k`` is the sample at ``self.prepare(data).time[k]`` and compares with
    /// ``self.prepare(data).tau`` (the measured torques in the same joints, known
    /// forces such as the MTM cable subtracted). A ``Prepared`` is used as it is.
    ///
    /// ``as_dataframe=True``: a pandas DataFrame with the row's ``time`` (s) and one
    /// ``effort.<joint>`` column per joint instead of the array.
    #[pyo3(signature = (data, robot = None, *, as_dataframe = false, joints = None))]
    fn predict<'py>(
        &self,
        py: Python<'py>,
        data: &Bound<'py, PyAny>,
        robot: Option<&Bound<'py, ModelPy>>,
        as_dataframe: bool,
        joints: Option<&str>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let model = self.model(py, robot)?;
        let params = self.params(&model)?;
        let (prepared, shown) = if let Ok(p) = data.cast::<PreparedPy>() {
            if p.get().joint_names.len() != model.dof() {
                return Err(input(format!(
                    "data: prepared for {} coordinates, the robot has {}",
                    p.get().joint_names.len(),
                    model.dof()
                )));
            }
            let own = p.get().joints;
            let shown = match joints {
                Some(j) => crate::overrides::parse_joints(j)?,
                None => own,
            };
            (p.get().inner.clone(), shown)
        } else if let Ok(d) = data.cast::<JointLogPy>() {
            let settings = self.inner.settings.clone();
            (
                prepared(py, model.clone(), d.get(), settings)?.inner,
                self.joints(joints)?,
            )
        } else {
            return Err(input("data: expected a JointLog or a Prepared"));
        };
        let map = JointMap::new(&model, shown).map_err(from_ident)?;
        let times = prepared.time.clone();
        let names = map.names.clone();
        let pred = background(py, move || {
            Ok(map
                .torque(&predict(&model, &params, &prepared))
                .into_owned())
        })?;
        if as_dataframe {
            let mut cols = vec![("time".to_string(), times)];
            cols.extend(crate::frame::matrix_columns("effort", &names, &pred));
            return crate::frame::dataframe(py, cols);
        }
        Ok(matrix(py, &pred).into_any())
    }

    /// Metrics of this result on another log, as ``dvrk-ident validate``: ``{joints,
    /// samples, relative_error, rms}`` over the first ``test_window`` processed samples
    /// (all if ``None``), with this result's processing settings, in the model
    /// coordinates or the arm's measured joints (``joints``; default: the fit's).
    #[pyo3(signature = (data, test_window = None, robot = None, *, joints = None))]
    fn validate<'py>(
        &self,
        py: Python<'py>,
        data: &Bound<'py, JointLogPy>,
        test_window: Option<usize>,
        robot: Option<&Bound<'py, ModelPy>>,
        joints: Option<&str>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let model = self.model(py, robot)?;
        let params = self.params(&model)?;
        let map = JointMap::new(&model, self.joints(joints)?).map_err(from_ident)?;
        let log = data.get().log.clone();
        let processing = self.inner.settings.processing.clone();
        let m = background(py, move || {
            let p = prepare_data(&model, &log, &processing).map_err(fail_ident)?;
            joint_metrics(&model, &params, &p, test_window, &map).map_err(fail_ident)
        })?;
        to_python(py, &m)
    }

    /// The parameters in the 2019 package's ``params.json`` layout (``dvrk-ident fit
    /// --wpi-json``): per frame ``"1"``… ``{I, r, m, Fc, Fv, Fo, Im, K}``.
    #[pyo3(signature = (robot = None))]
    fn wpi_params<'py>(
        &self,
        py: Python<'py>,
        robot: Option<&Bound<'py, ModelPy>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let model = self.model(py, robot)?;
        let params = self.params(&model)?;
        let wpi = Export::WpiParams
            .build_for(&model, &params, &self.inner)
            .map_err(from_ident)?;
        warn_all(py, &wpi.undetermined)?;
        to_python(py, &wpi.document)
    }

    /// The dVRK controller's MTM gravity-compensation file (``dvrk-ident export
    /// --dvrk-gc``) as a dict: ``version`` ``"2.0"``, ``GC_controller`` with the arrays
    /// sawIntuitiveResearchKit reads, and ``dvrk_ident`` with the grid and the residuals
    /// (N·m) of the fit against the model. ``points``: grid points per joint (6 to 10).
    /// Raises ``InputError`` for a robot that is not the MTM.
    #[pyo3(signature = (robot = None, points = dvrk_ident::export::dvrk_gc::DEFAULT_POINTS))]
    fn dvrk_gc<'py>(
        &self,
        py: Python<'py>,
        robot: Option<&Bound<'py, ModelPy>>,
        points: usize,
    ) -> PyResult<Bound<'py, PyAny>> {
        let model = self.model(py, robot)?;
        let params = self.params(&model)?;
        let result = self.inner.clone();
        let gc = py
            .detach(move || Export::DvrkGc { points }.build_for(&model, &params, &result))
            .map_err(from_ident)?;
        warn_all(py, &gc.undetermined)?;
        to_python(py, &gc.document)
    }

    /// The dVRK controller's kinematic gravity-compensation file of an ``ecm``,
    /// ``psm_si`` (``psm_si_tool``) or ``ecm_si`` result (``dvrk-ident export --dvrk-kinematic-gc``) as a
    /// dict: the physical DH its ``kinematic_gc`` key names, with masses and centres of
    /// mass whose gravity, through the controller's position and effort maps, is this
    /// result's. ``endoscope``: the ECM's endoscope type (its configuration's
    /// ``endoscope``), whose mass the controller sets on the insertion link. Raises
    /// ``InputError`` for another robot, naming the export that arm has.
    #[pyo3(signature = (robot = None, *, endoscope = None))]
    fn dvrk_kinematic_gc<'py>(
        &self,
        py: Python<'py>,
        robot: Option<&Bound<'py, ModelPy>>,
        endoscope: Option<String>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let model = self.model(py, robot)?;
        let params = self.params(&model)?;
        let result = self.inner.clone();
        let gc = py
            .detach(move || {
                Export::DvrkKinematicGc {
                    endoscope: endoscope.as_deref(),
                }
                .build_for(&model, &params, &result)
            })
            .map_err(from_ident)?;
        warn_all(py, &gc.undetermined)?;
        to_python(py, &gc.document)
    }

    fn __repr__(&self) -> String {
        format!(
            "FitResult(robot={}, method={}, converged={}, physically_consistent={})",
            py_str(&self.inner.robot),
            py_str(&self.inner.method),
            py_bool(self.inner.solver.converged),
            py_bool(self.inner.physically_consistent)
        )
    }
}
