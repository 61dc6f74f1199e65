//! `Model` (a loaded model) and `BaseParameters`: kinematics, regressors and dynamics
//! over batches of samples.

use std::path::PathBuf;
use std::sync::{Arc, OnceLock};

use dvrk_ident::FitSettings;
use dvrk_model::{BaseParameters, Model, Workspace};
use numpy::PyArrayDyn;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::classes::{ModelPy, Origin};
use crate::convert::{array, per_sample, py_str, rows, rows_or_zeros, vector, Rows};
use crate::errors::{error, from_ident, from_model, input, Kind};
use crate::json::to_python;

impl ModelPy {
    pub fn new(model: Model, origin: Origin) -> Self {
        ModelPy {
            model: Arc::new(model),
            base: OnceLock::new(),
            origin,
            fit: None,
        }
    }

    /// The model `origin` describes, with the model options of the fit `fit` if given
    /// (built without the GIL).
    pub(crate) fn build(
        py: Python<'_>,
        origin: Origin,
        fit: Option<FitSettings>,
    ) -> PyResult<ModelPy> {
        let model = py
            .detach(|| origin.build(fit.as_ref()))
            .map_err(from_ident)?;
        Ok(ModelPy::fitted(model, origin, fit))
    }

    /// `model`, built from `origin` with the model options of the fit `fit`.
    pub(crate) fn fitted(model: Model, origin: Origin, fit: Option<FitSettings>) -> ModelPy {
        ModelPy {
            fit: fit.map(Box::new),
            ..ModelPy::new(model, origin)
        }
    }

    /// The robot of a fit result (`FitResult::robot`: a built-in name or file) with the
    /// fit's model options (Stribeck and Dahl terms, mounting pitch, bounds).
    pub fn of_result(py: Python<'_>, robot: &str, fit: FitSettings) -> PyResult<ModelPy> {
        let name = robot.to_string();
        let (model, origin, fit) = py
            .detach(move || {
                let (model, origin) = Origin::load(&name)?;
                let model = fit.model(&model)?.into_owned();
                Ok::<_, dvrk_ident::IdentError>((model, origin, fit))
            })
            .map_err(from_ident)?;
        Ok(ModelPy::fitted(model, origin, Some(fit)))
    }

    /// The base parameters, computed once (about 10 ms for the PSM) without the GIL.
    pub fn base_parameters(&self, py: Python<'_>) -> PyResult<Arc<BaseParameters>> {
        if let Some(b) = self.base.get() {
            return Ok(b.clone());
        }
        let model = self.model.clone();
        let b = py
            .detach(move || model.base_parameters())
            .map_err(from_model)?;
        Ok(self.base.get_or_init(|| Arc::new(b)).clone())
    }

    pub fn params(&self, py: Python<'_>, obj: &Bound<'_, PyAny>) -> PyResult<Params> {
        params_of(py, &self.model, obj)
    }

    /// `f(workspace, q_k, out_k)` for each sample `q_k` of the positions `q` (rad or m)
    /// with a workspace of `model` (the robot's, or a fit result's),
    /// the results shaped `(N, *shape)`, or `shape` for one 1-D sample: the body of every
    /// method of the positions alone (gravity, mass matrix, known forces, kinematics).
    fn map_positions<'py, F>(
        &self,
        py: Python<'py>,
        model: &Model,
        q: &Bound<'py, PyAny>,
        shape: &[usize],
        mut f: F,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>>
    where
        F: FnMut(&mut Workspace, &[f64], &mut [f64]) + Send,
    {
        let q = rows(py, q, model.dof(), "q", &model.coordinates)?;
        let mut ws = Workspace::new(model);
        let width = shape.iter().product();
        let out = per_sample(py, q.rows, width, |k, out| f(&mut ws, q.row(k), out))?;
        Ok(array(py, out, &q.shape(shape)))
    }
}

/// Parameter values with the model that evaluates them.
pub struct Params {
    /// The robot's own model, or for a fit `FitResult` the model it was fitted with
    /// (its Stribeck terms add parameters), so a result is always evaluated with as many
    /// parameters as it has.
    pub model: Arc<Model>,
    pub values: Vec<f64>,
}

/// The parameters of an array, a `{name: value}` mapping or a fit `FitResult` (refused,
/// in one line, when it was fitted for another robot).
pub fn params_of(py: Python<'_>, model: &Arc<Model>, obj: &Bound<'_, PyAny>) -> PyResult<Params> {
    if let Ok(r) = obj.cast::<crate::classes::FitResultPy>() {
        let inner = &r.get().inner;
        let fitted = shared(
            model,
            inner.model_for(model, "FitResult").map_err(from_ident)?,
        );
        let values = inner.params_for(&fitted).map_err(from_ident)?;
        return Ok(Params {
            model: fitted,
            values,
        });
    }
    let values = if obj.cast::<PyDict>().is_ok() || obj.hasattr("keys")? {
        let items = obj.call_method0("items")?;
        let mut values: Vec<(String, f64)> = Vec::new();
        for item in items.try_iter()? {
            let (k, v): (String, Bound<'_, PyAny>) = item?.extract().map_err(|e| {
                input(format!(
                    "params: expected a mapping of names to numbers: {e}"
                ))
            })?;
            let v: f64 = v
                .extract()
                .map_err(|_| input(format!("params: parameter {k} is not a number")))?;
            values.push((k, v));
        }
        model
            .params_from_named(values.iter().map(|(k, v)| (k.as_str(), *v)), "params")
            .map_err(from_model)?
    } else {
        vector(
            py,
            obj,
            Some(model.n_params()),
            "params",
            &model.param_names(),
        )?
    };
    Ok(Params {
        model: model.clone(),
        values,
    })
}

/// `model` itself when `cow` borrows it, else the copy `cow` made (with a fit's model
/// options), shared.
pub fn shared(model: &Arc<Model>, cow: std::borrow::Cow<'_, Model>) -> Arc<Model> {
    match cow {
        std::borrow::Cow::Borrowed(_) => model.clone(),
        std::borrow::Cow::Owned(m) => Arc::new(m),
    }
}

/// `q`, `dq` and a third signal of the robot state (`ddq`, or `tau` as `last` names
/// it; zeros when `None`) as batches of the same shape, each named in errors.
pub(crate) fn state_of(
    py: Python<'_>,
    model: &Model,
    q: &Bound<'_, PyAny>,
    dq: Option<&Bound<'_, PyAny>>,
    (last, third): (&str, Option<&Bound<'_, PyAny>>),
) -> PyResult<(Rows, Rows, Rows)> {
    let labels = &model.coordinates;
    let q = rows(py, q, model.dof(), "q", labels)?;
    let dq = rows_or_zeros(py, dq, &q, "dq", "q", labels)?;
    let third = rows_or_zeros(py, third, &q, last, "q", labels)?;
    Ok((q, dq, third))
}

fn load(py: Python<'_>, name_or_path: PathBuf) -> PyResult<ModelPy> {
    let name = name_or_path.to_string_lossy().to_string();
    let (model, origin) = py.detach(move || Origin::load(&name)).map_err(from_model)?;
    Ok(ModelPy::new(model, origin))
}

/// The regressor of the samples `q`, `dq`, `ddq` (`(N*dof, cols)`, `(dof, cols)` for one
/// 1-D sample): every column, or `base`'s independent ones. `Model.regressor`,
/// `Model.base_regressor` and `BaseParameters.regressor`.
fn regressor_array<'py>(
    py: Python<'py>,
    model: &Model,
    base: Option<&BaseParameters>,
    q: &Bound<'py, PyAny>,
    dq: Option<&Bound<'py, PyAny>>,
    ddq: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    let (q, dq, ddq) = state_of(py, model, q, dq, ("ddq", ddq))?;
    let (n, p) = (model.dof(), model.n_params());
    let cols = base.map_or(p, |b| b.rank());
    let mut ws = Workspace::new(model);
    let mut full = vec![0.0; n * p];
    let out = per_sample(py, q.rows, n * cols, |k, out| match base {
        None => model.regressor_into(&mut ws, q.row(k), dq.row(k), ddq.row(k), out),
        Some(b) => {
            model.regressor_into(&mut ws, q.row(k), dq.row(k), ddq.row(k), &mut full);
            b.select_into(&full, p, out);
        }
    })?;
    Ok(array(py, out, &[q.rows * n, cols]))
}

#[pymethods]
impl ModelPy {
    /// Same as :meth:`Model.load`.
    #[new]
    fn py_new(py: Python<'_>, name_or_path: PathBuf) -> PyResult<Self> {
        load(py, name_or_path)
    }

    /// Loads a robot: a built-in name (``"psm"``, ``"psm_simplified"``, ``"mtm"``, ``"ecm"``, ``"psm_si"``, ``"psm_si_tool"``, ``"ecm_si"``) or a
    /// path to a ``.toml`` description or a ``.urdf`` file.
    ///
    /// Raises ``InputError`` (a ``ValueError``) for an unknown name or a wrong
    /// description, ``DvrkIOError`` (an ``OSError``) for an unreadable file.
    #[staticmethod]
    fn load(py: Python<'_>, name_or_path: PathBuf) -> PyResult<Self> {
        load(py, name_or_path)
    }

    /// A robot from the text of a ``.toml`` description; ``source`` names it in messages.
    #[staticmethod]
    #[pyo3(signature = (text, source = "<string>"))]
    fn from_toml(py: Python<'_>, text: &str, source: &str) -> PyResult<Self> {
        let (text, source) = (text.to_string(), source.to_string());
        ModelPy::build(py, Origin::Toml { text, source }, None)
    }

    /// A robot from the text of a URDF file; ``source`` names it in messages.
    #[staticmethod]
    #[pyo3(signature = (text, source = "<string>"))]
    fn from_urdf(py: Python<'_>, text: &str, source: &str) -> PyResult<Self> {
        let (text, source) = (text.to_string(), source.to_string());
        ModelPy::build(py, Origin::Urdf { text, source }, None)
    }

    /// Pickling (and ``copy.deepcopy``): a built-in robot by name, a description by its
    /// text, so the copy does not depend on the file.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
        let py = slf.py();
        let r = slf.get();
        let (kind, text, source) = match &r.origin {
            Origin::Builtin(name) => ("builtin", name.clone(), String::new()),
            Origin::Toml { text, source } => ("toml", text.clone(), source.clone()),
            Origin::Urdf { text, source } => ("urdf", text.clone(), source.clone()),
        };
        // The fit's settings as their JSON document (the result's `settings`).
        let fit = r
            .fit
            .as_ref()
            .map(|s| serde_json::to_string(s).expect("serializable"));
        let args = (kind, text, source, fit).into_pyobject(py)?.into_any();
        Ok((slf.get_type().getattr("_restore")?, args))
    }

    /// The inverse of ``__reduce__``.
    #[staticmethod]
    fn _restore(
        py: Python<'_>,
        kind: &str,
        text: String,
        source: String,
        fit: Option<String>,
    ) -> PyResult<Self> {
        let origin = match kind {
            "builtin" => Origin::Builtin(text),
            "toml" => Origin::Toml { text, source },
            "urdf" => Origin::Urdf { text, source },
            other => return Err(input(format!("Model: unknown pickled kind {other:?}"))),
        };
        let fit = fit
            .map(|text| serde_json::from_str::<FitSettings>(&text))
            .transpose()
            .map_err(|e| input(format!("Model: pickled fit settings: {e}")))?;
        ModelPy::build(py, origin, fit)
    }

    /// Names of the built-in robots.
    #[staticmethod]
    fn builtin_names() -> Vec<&'static str> {
        Model::builtin_names()
    }

    /// Model name (from the description).
    #[getter]
    fn name(&self) -> String {
        self.model.name.clone()
    }

    /// Where the robot came from: ``builtin:psm`` or the file path.
    #[getter]
    fn source(&self) -> String {
        self.model.source.clone()
    }

    /// Generalized (model) coordinate names, in order: the columns of ``q``.
    #[getter]
    fn coordinates(&self) -> Vec<String> {
        self.model.coordinates.clone()
    }

    /// Measured joint names (e.g. the dVRK's ROS joint names), one per coordinate.
    #[getter]
    fn measured_joints(&self) -> Vec<String> {
        self.model.measured.joints.clone()
    }

    /// ``(dof, dof)`` coupling ``M``: ``q_measured = M @ q_model``,
    /// ``tau_model = M.T @ tau_measured``.
    #[getter]
    fn coupling<'py>(&self, py: Python<'py>) -> Bound<'py, PyArrayDyn<f64>> {
        crate::convert::matrix(py, &self.model.measured.coupling)
    }

    /// Parameter names in regressor column order (2019 convention: ``L1xx`` ... ``m1``,
    /// ``Fc1``, ``Fv1``, ``Fo1``, ``Ia1``, ``K1``, ...).
    #[getter]
    fn parameter_names(&self) -> Vec<String> {
        self.model.param_names()
    }

    /// Number of generalized coordinates.
    #[getter]
    fn dof(&self) -> usize {
        self.model.dof()
    }

    /// Number of parameters (columns of the full regressor).
    #[getter]
    fn n_parameters(&self) -> usize {
        self.model.n_params()
    }

    /// Frame names, base first: the frame axis of :meth:`forward_kinematics`.
    #[getter]
    fn frame_names(&self) -> Vec<String> {
        self.model.frame_names()
    }

    /// The description's excitation limits as a dict in the layout of a limits file:
    /// ``{"limits": [{"expr", "position", "velocity", "acceleration"}, ...],
    /// "cartesian_limits": [{"frame", "min", "max"}, ...]}`` (rad, m and their rates;
    /// box corners in metres, base frame). Edit a copy and pass it to
    /// :func:`excite` as ``limits=`` (which replaces the robot's limits), e.g. to add a
    /// box on a frame origin.
    #[getter]
    fn limits<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        crate::limits::limits_dict(py, &self.model)
    }

    /// Gravity in the base frame, m/s², shape ``(3,)``.
    #[getter]
    fn gravity_vector<'py>(&self, py: Python<'py>) -> Bound<'py, PyArrayDyn<f64>> {
        let g = self.model.gravity;
        array(py, vec![g[0], g[1], g[2]], &[3])
    }

    /// The description's nominal parameters (e.g. a URDF's inertials), shape
    /// ``(n_parameters,)``, or ``None`` when some parameter has no nominal value.
    #[getter]
    fn nominal_parameters<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArrayDyn<f64>>> {
        self.model.nominal_parameters().map(|v| {
            let n = v.len();
            array(py, v, &[n])
        })
    }

    /// The document of ``dvrk-ident model ROBOT --json`` as a dict (coordinates,
    /// measured joints, coupling, frames, parameters, base parameters, gravity).
    fn summary<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let base = self.base_parameters(py)?;
        to_python(py, &self.model.summary(&base))
    }

    /// The base (identifiable) parameters: ``names``, ``expressions``, ``independent``
    /// (kept regressor columns), ``combination`` (``K``, with ``beta = K @ params``).
    /// Computed once per robot.
    fn base(&self, py: Python<'_>) -> PyResult<BaseParametersPy> {
        Ok(BaseParametersPy::new(
            self.model.clone(),
            self.base_parameters(py)?,
        ))
    }

    /// The regressor ``H(q, dq, ddq)`` with ``tau = H @ params``: for ``N`` samples,
    /// shape ``(N*dof, n_parameters)``, the samples' ``dof × n_parameters`` blocks
    /// stacked (row ``k*dof + j`` is coordinate ``j`` of sample ``k``); for one 1-D
    /// sample, ``(dof, n_parameters)``. Known forces (e.g. the MTM cable) are not part
    /// of it.
    ///
    /// Example::
    ///
    ///     >>> H = psm.regressor(q, dq, ddq)            # q, dq, ddq: (N, 7)
    ///     >>> tau = (H @ params).reshape(-1, psm.dof)  # == psm.inverse_dynamics(params, q, dq, ddq)
    #[pyo3(signature = (q, dq = None, ddq = None))]
    fn regressor<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'py, PyAny>,
        dq: Option<&Bound<'py, PyAny>>,
        ddq: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        regressor_array(py, &self.model, None, q, dq, ddq)
    }

    /// The base regressor: the columns ``base().independent`` of :meth:`regressor`,
    /// shape ``(N*dof, rank)`` (``(dof, rank)`` for one sample), with
    /// ``tau = Hb @ base().project(params)``.
    #[pyo3(signature = (q, dq = None, ddq = None))]
    fn base_regressor<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'py, PyAny>,
        dq: Option<&Bound<'py, PyAny>>,
        ddq: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let base = self.base_parameters(py)?;
        regressor_array(py, &self.model, Some(&base), q, dq, ddq)
    }

    /// Inverse dynamics ``tau = H(q, dq, ddq) @ params`` (N·m or N): links, friction,
    /// springs, motor inertias; known forces (e.g. the MTM cable) excluded — add
    /// :meth:`known_forces` to predict a measured torque. Shape ``(N, dof)``, or
    /// ``(dof,)`` for one sample.
    #[pyo3(signature = (params, q, dq = None, ddq = None))]
    fn inverse_dynamics<'py>(
        &self,
        py: Python<'py>,
        params: &Bound<'py, PyAny>,
        q: &Bound<'py, PyAny>,
        dq: Option<&Bound<'py, PyAny>>,
        ddq: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let Params { model, values } = self.params(py, params)?;
        let (q, dq, ddq) = state_of(py, &self.model, q, dq, ("ddq", ddq))?;
        let n = model.dof();
        let mut ws = Workspace::new(&model);
        let out = per_sample(py, q.rows, n, |k, out| {
            model.inverse_dynamics(&mut ws, &values, q.row(k), dq.row(k), ddq.row(k), out)
        })?;
        Ok(array(py, out, &q.shape(&[n])))
    }

    /// Gravity torque ``g(q)`` of the links alone (no friction, spring or known force),
    /// shape ``(N, dof)`` or ``(dof,)``.
    fn gravity<'py>(
        &self,
        py: Python<'py>,
        params: &Bound<'py, PyAny>,
        q: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let Params { model, values } = self.params(py, params)?;
        self.map_positions(py, &model, q, &[model.dof()], |ws, q, out| {
            model.gravity_torque(ws, &values, q, out)
        })
    }

    /// A URDF of the whole robot with the inertials of ``params`` (an array, a
    /// ``{name: value}`` mapping or a fit ``FitResult``), as ``dvrk-ident export --urdf``
    /// generates it: one link per frame, mimic joints for the couplings, what URDF
    /// cannot hold listed in its header. Raises ``ModelError`` for parameters that are
    /// not rigid bodies.
    fn to_urdf(&self, py: Python<'_>, params: &Bound<'_, PyAny>) -> PyResult<String> {
        let Params { model, values } = self.params(py, params)?;
        py.detach(move || model.to_urdf(&values))
            .map_err(from_model)
    }

    /// Mass matrix ``M(q)`` (motor inertias included), shape ``(N, dof, dof)``, or
    /// ``(dof, dof)`` for one 1-D sample.
    fn mass_matrix<'py>(
        &self,
        py: Python<'py>,
        params: &Bound<'py, PyAny>,
        q: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let Params { model, values } = self.params(py, params)?;
        let n = model.dof();
        let mut col_major = vec![0.0; n * n];
        self.map_positions(py, &model, q, &[n, n], |ws, q, out| {
            model.mass_matrix_into(ws, &values, q, &mut col_major);
            for r in 0..n {
                for c in 0..n {
                    out[r * n + c] = col_major[c * n + r];
                }
            }
        })
    }

    /// Forward dynamics: accelerations under torques ``tau`` (as measured: known forces
    /// are subtracted first) with friction, springs and gravity; shape ``(N, dof)`` or
    /// ``(dof,)``. Raises ``SolverError`` if the mass matrix is not positive definite.
    fn forward_dynamics<'py>(
        &self,
        py: Python<'py>,
        params: &Bound<'py, PyAny>,
        q: &Bound<'py, PyAny>,
        dq: &Bound<'py, PyAny>,
        tau: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let Params { model, values } = self.params(py, params)?;
        let (q, dq, tau) = state_of(py, &self.model, q, Some(dq), ("tau", Some(tau)))?;
        let n = model.dof();
        let mut ws = Workspace::new(&model);
        let mut singular = None;
        let out = per_sample(py, q.rows, n, |k, out| {
            match model.forward_dynamics(&mut ws, &values, q.row(k), dq.row(k), tau.row(k)) {
                Some(a) => out.copy_from_slice(a.as_slice()),
                None => {
                    singular.get_or_insert(k);
                    out.fill(f64::NAN);
                }
            }
        })?;
        if let Some(k) = singular {
            return Err(error(
                Kind::Solver,
                format!("forward_dynamics: the mass matrix is not positive definite at sample {k} (the parameters are not physical)"),
            ));
        }
        Ok(array(py, out, &q.shape(&[n])))
    }

    /// Known generalized forces at ``q`` (e.g. the MTM gravity-compensation cable),
    /// shape ``(N, dof)`` or ``(dof,)``; zeros for a robot without any.
    fn known_forces<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let model = &self.model;
        self.map_positions(py, model, q, &[model.dof()], |_, q, out| {
            out.fill(0.0);
            model.add_known_forces(q, out)
        })
    }

    /// Poses of every frame in the base frame, base included (index 0, the identity),
    /// as 4×4 homogeneous matrices (m): shape ``(N, len(frame_names), 4, 4)``, or
    /// ``(len(frame_names), 4, 4)`` for one sample.
    fn forward_kinematics<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let model = &self.model;
        let frames = model.frames.len() + 1;
        self.map_positions(py, model, q, &[frames, 4, 4], |ws, q, out| {
            model.forward_kinematics(ws, q);
            for (i, block) in out.chunks_mut(16).enumerate() {
                let h = ws.pose(i).to_homogeneous();
                for (r, row) in h.iter().enumerate() {
                    block[4 * r..4 * r + 4].copy_from_slice(row);
                }
            }
        })
    }

    fn __repr__(&self) -> String {
        format!(
            "Model({}, dof={}, parameters={}, source={})",
            py_str(&self.model.name),
            self.model.dof(),
            self.model.n_params(),
            py_str(&self.model.source)
        )
    }
}

/// The base (identifiable) parameters of a robot: ``beta = combination @ params``, and
/// the base regressor is the full regressor's ``independent`` columns, so that
/// ``H @ params == H[:, independent] @ beta``.
///
/// Attributes: ``names`` (leading parameter of each), ``expressions`` (e.g.
/// ``"L2xy + L6xy + 0.2159*l2x"``), ``independent`` (column indices), ``combination``
/// (``(rank, n_parameters)`` array), ``rank``.
#[pyclass(name = "BaseParameters", module = "dvrk_ident", frozen)]
pub struct BaseParametersPy {
    model: Arc<Model>,
    base: Arc<BaseParameters>,
    /// Name of the leading (kept) parameter of each base parameter.
    #[pyo3(get)]
    names: Vec<String>,
    /// Each base parameter as a readable combination of parameters.
    #[pyo3(get)]
    expressions: Vec<String>,
    /// Columns of the full regressor kept as the base regressor (increasing).
    #[pyo3(get)]
    independent: Vec<usize>,
}

impl BaseParametersPy {
    /// The lists Python reads as attributes are copied once here (the class is frozen).
    fn new(model: Arc<Model>, base: Arc<BaseParameters>) -> Self {
        BaseParametersPy {
            names: base.names.clone(),
            expressions: base.expressions.clone(),
            independent: base.independent.clone(),
            model,
            base,
        }
    }
}

#[pymethods]
impl BaseParametersPy {
    /// ``K``, shape ``(rank, n_parameters)``: ``beta = K @ params``.
    #[getter]
    fn combination<'py>(&self, py: Python<'py>) -> Bound<'py, PyArrayDyn<f64>> {
        crate::convert::matrix(py, &self.base.combination)
    }

    /// Number of base parameters.
    #[getter]
    fn rank(&self) -> usize {
        self.base.rank()
    }

    fn __len__(&self) -> usize {
        self.base.rank()
    }

    /// ``beta = combination @ params``, shape ``(rank,)``; ``params`` as in
    /// :meth:`Model.inverse_dynamics`.
    fn project<'py>(
        &self,
        py: Python<'py>,
        params: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let p = params_of(py, &self.model, params)?;
        if !Arc::ptr_eq(&p.model, &self.model) {
            return Err(input(format!(
                "params: this FitResult's model has {} parameters (its fit added Stribeck \
                 terms), not the {} of these base parameters: project it with \
                 result.load_robot().base()",
                p.model.n_params(),
                self.model.n_params()
            )));
        }
        let beta = self.base.project(&p.values);
        let r = beta.len();
        Ok(array(py, beta, &[r]))
    }

    /// The base regressor, as :meth:`Model.base_regressor`.
    #[pyo3(signature = (q, dq = None, ddq = None))]
    fn regressor<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'py, PyAny>,
        dq: Option<&Bound<'py, PyAny>>,
        ddq: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        regressor_array(py, &self.model, Some(&self.base), q, dq, ddq)
    }

    /// ``{"names", "expressions", "independent", "combination"}`` with plain lists.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        d.set_item("names", &self.base.names)?;
        d.set_item("expressions", &self.base.expressions)?;
        d.set_item("independent", &self.base.independent)?;
        let k = &self.base.combination;
        let rows = PyList::empty(py);
        for r in 0..k.nrows() {
            rows.append(k.row(r).iter().copied().collect::<Vec<f64>>())?;
        }
        d.set_item("combination", rows)?;
        Ok(d)
    }

    fn __repr__(&self) -> String {
        format!(
            "BaseParameters(rank={}, of {} parameters of {})",
            self.base.rank(),
            self.model.n_params(),
            py_str(&self.model.name)
        )
    }
}
