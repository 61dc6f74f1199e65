//! `external_torque` (`dvrk_ident::residual::external_torque`, the computation of
//! `dvrk-ident residual`) and the real-time `MomentumObserver`
//! (`dvrk_model::MomentumObserver`).

use std::sync::Arc;

use dvrk_ident::residual::{
    external_torque as residual_of, ResidualOptions, DEFAULT_OBSERVER_GAIN,
};
use dvrk_model::{Model, MomentumObserver, Workspace};
use numpy::PyArrayDyn;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::classes::{FitResultPy, ModelPy};
use crate::convert::{array, background, matrix, rows, rows_or_zeros, vector};
use crate::data::{fail_ident, JointLogPy};
use crate::errors::{from_ident, input};
use crate::overrides::parse_joints;
use crate::robot::{params_of, Params};

// The signatures' defaults are written out (Python's signature shows a literal, not a
// constant's name): the library's default gain.
const _: () = assert!(DEFAULT_OBSERVER_GAIN == 20.0);

/// The joint torques the identified model does not explain in ``data`` (a
/// :class:`JointLog`), as ``dvrk-ident residual RESULT LOG``: per processed sample
/// ``tau_measured − tau_model(q, dq, ddq)`` (N·m or N), with the result's processing
/// (filters, delays, trimming), friction, springs and known forces — the prediction
/// :meth:`FitResult.validate` scores, kept sample by sample — beside the momentum
/// observer's estimate of the same torque (no acceleration needed; a first-order lag of
/// gain ``observer_gain``, 1/s, default 20) and the noise floor.
///
/// The sign: the torque the joints apply beyond the model (``+g`` of a payload the
/// model does not know), the opposite of the torque the environment applies.
///
/// - ``joints``: ``"model"`` or ``"measured"`` (default: the fit's), as ``--joints``;
/// - ``**options``: the processing options of :func:`prepare` (``cutoff``,
///   ``filter_order``, ``filter_torque``, ``trim``, ``decimate``, ``min_speed``,
///   ``resample``) replace the result's, as the command's processing flags;
/// - ``robot``: the :class:`Model` to evaluate (default: the result's).
///
/// Returns a dict: ``source``, ``joints`` (names), ``time`` (s, ``(N,)``),
/// ``residual`` and ``observer`` (``(N, dof)``), ``rms`` (of ``residual`` per joint),
/// ``noise_floor`` (the fit's training RMS error per joint, ``metrics.train.rms``, or
/// ``None`` when the result's metrics are in other joints), ``observer_gain``. With
/// ``as_dataframe=True``: a pandas DataFrame of ``time``, ``residual.<joint>`` and
/// ``observer.<joint>`` columns whose ``attrs`` hold ``source``, ``joints``, ``rms``,
/// ``noise_floor`` and ``observer_gain``.
///
/// Example::
///
///     >>> r = di.external_torque(result, di.read_log("loaded.mcap", psm))
///     >>> r["rms"] / r["noise_floor"]   # well above 1: something the fit did not see
#[pyfunction]
#[pyo3(signature = (result, data, robot = None, *, observer_gain = 20.0, joints = None, as_dataframe = false, **options))]
#[allow(clippy::too_many_arguments)]
pub fn external_torque<'py>(
    py: Python<'py>,
    result: &Bound<'py, FitResultPy>,
    data: &Bound<'py, JointLogPy>,
    robot: Option<&Bound<'py, ModelPy>>,
    observer_gain: f64,
    joints: Option<&str>,
    as_dataframe: bool,
    options: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyAny>> {
    let r = result.get();
    let model = r.model(py, robot)?;
    let params = r.inner.params_for(&model).map_err(from_ident)?;
    let mut fitted = r.inner.clone();
    fitted.settings = crate::overrides::options("external_torque", options)?.apply(fitted.settings);
    let options = ResidualOptions {
        joints: joints.map(parse_joints).transpose()?,
        observer_gain,
    };
    let traj = data.get().traj.clone();
    let res = background(py, move || {
        residual_of(&model, &params, &fitted, &traj, &options).map_err(fail_ident)
    })?;
    let n = res.joints.len();
    if as_dataframe {
        let mut cols = vec![("time".to_string(), res.time.clone())];
        cols.extend(crate::frame::matrix_columns(
            "residual",
            &res.joints,
            &res.external,
        ));
        cols.extend(crate::frame::matrix_columns(
            "observer",
            &res.joints,
            &res.observer,
        ));
        let df = crate::frame::dataframe(py, cols)?;
        let attrs = df.getattr("attrs")?;
        attrs.set_item("source", &res.source)?;
        attrs.set_item("joints", &res.joints)?;
        attrs.set_item("rms", array(py, res.rms.clone(), &[n]))?;
        attrs.set_item(
            "noise_floor",
            res.noise_floor.clone().map(|f| array(py, f, &[n])),
        )?;
        attrs.set_item("observer_gain", observer_gain)?;
        return Ok(df);
    }
    let out = PyDict::new(py);
    out.set_item("source", &res.source)?;
    out.set_item("joints", &res.joints)?;
    let samples = res.time.len();
    out.set_item("time", array(py, res.time, &[samples]))?;
    out.set_item("residual", matrix(py, &res.external))?;
    out.set_item("observer", matrix(py, &res.observer))?;
    out.set_item("rms", array(py, res.rms, &[n]))?;
    out.set_item("noise_floor", res.noise_floor.map(|f| array(py, f, &[n])))?;
    out.set_item("observer_gain", observer_gain)?;
    Ok(out.into_any())
}

/// The generalized-momentum observer of ``dvrk_model`` (De Luca & Mattone 2003), as a
/// controller runs it: ``robot`` (a :class:`Model`), its ``params`` (a vector, a dict
/// or a :class:`FitResult`, as for :meth:`Model.inverse_dynamics`) and ``gains`` (1/s,
/// one number or one per coordinate, positive: coordinate ``k``'s estimate follows the
/// external torque with a first-order lag of time constant ``1/gains[k]`` s).
///
/// :meth:`update` takes each sample ``q`` (rad or m), ``dq`` (rad/s or m/s) and the
/// applied torque ``tau`` (N·m or N per model coordinate, as measured: known forces are
/// the model's) with the step ``dt`` (s) since the previous sample, and returns the
/// estimate of ``tau − tau_model`` (the sign of :func:`external_torque`). The first
/// update (and the first after :meth:`reset`) only stores the sample and returns zeros.
///
/// Example::
///
///     >>> obs = di.MomentumObserver(psm, result, gains=20.0)
///     >>> for q, dq, tau in samples:
///     ...     tau_ext = obs.update(q, dq, tau, dt=0.005)
/// `gains=`: one gain for every coordinate, or one each.
#[derive(FromPyObject)]
pub enum Gains<'py> {
    One(f64),
    Each(Bound<'py, PyAny>),
}

#[pyclass(name = "MomentumObserver", module = "dvrk_ident")]
pub struct MomentumObserverPy {
    model: Arc<Model>,
    params: Vec<f64>,
    ws: Workspace,
    observer: MomentumObserver,
}

#[pymethods]
impl MomentumObserverPy {
    #[new]
    #[pyo3(
        signature = (robot, params, gains = Gains::One(DEFAULT_OBSERVER_GAIN)),
        text_signature = "(robot, params, gains=20.0)"
    )]
    fn py_new(
        py: Python<'_>,
        robot: &Bound<'_, ModelPy>,
        params: &Bound<'_, PyAny>,
        gains: Gains<'_>,
    ) -> PyResult<Self> {
        let Params { model, values } = params_of(py, &robot.get().model, params)?;
        let n = model.dof();
        let gains = match gains {
            Gains::One(g) => vec![g; n],
            Gains::Each(g) => vector(py, &g, Some(n), "gains", &model.coordinates)?,
        };
        let observer = MomentumObserver::new(&model, &gains).map_err(|e| input(e.to_string()))?;
        Ok(MomentumObserverPy {
            ws: Workspace::new(&model),
            model,
            params: values,
            observer,
        })
    }

    /// One sample (``q``, ``dq``, ``tau`` of shape ``(dof,)``; returns the estimate,
    /// ``(dof,)``) or ``N`` consecutive samples (shape ``(N, dof)``; returns the estimate
    /// after each, ``(N, dof)``). ``dt``: the step in s before each sample, one number or
    /// ``N`` (the first one counts from the previous update), positive.
    fn update<'py>(
        &mut self,
        py: Python<'py>,
        q: &Bound<'py, PyAny>,
        dq: &Bound<'py, PyAny>,
        tau: &Bound<'py, PyAny>,
        dt: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let n = self.model.dof();
        let labels = &self.model.coordinates;
        let q = rows(py, q, n, "q", labels)?;
        let dq = rows_or_zeros(py, Some(dq), &q, "dq", "q", labels)?;
        let tau = rows_or_zeros(py, Some(tau), &q, "tau", "q", labels)?;
        let steps = match dt.extract::<f64>() {
            Ok(d) => vec![d; q.rows],
            Err(_) => vector(py, dt, Some(q.rows), "dt", &[])?,
        };
        if let Some((k, d)) = steps
            .iter()
            .enumerate()
            .find(|(_, d)| !(d.is_finite() && **d > 0.0))
        {
            return Err(input(format!(
                "dt: the step must be positive and finite (s), got {d} (sample {k})"
            )));
        }
        let mut out = vec![0.0; q.rows * n];
        let Self {
            model,
            params,
            ws,
            observer,
        } = self;
        // About 1 µs a sample: without the GIL, in one piece.
        py.detach(|| {
            for (k, o) in out.chunks_mut(n).enumerate() {
                let r =
                    observer.update(model, ws, params, q.row(k), dq.row(k), tau.row(k), steps[k]);
                o.copy_from_slice(r);
            }
        });
        if let Some(k) = out.iter().position(|x| !x.is_finite()) {
            self.observer.reset();
            return Err(input(format!(
                "the estimate is not finite at sample {} (the parameters and motion overflow); the observer is reset",
                k / n
            )));
        }
        Ok(array(py, out, &q.shape(&[n])))
    }

    /// Forgets the previous sample and the estimate: the next update starts again.
    fn reset(&mut self) {
        self.observer.reset();
    }

    /// The gains, 1/s per coordinate, ``(dof,)``.
    #[getter]
    fn gains<'py>(&self, py: Python<'py>) -> Bound<'py, PyArrayDyn<f64>> {
        let g = self.observer.gains().to_vec();
        let n = g.len();
        array(py, g, &[n])
    }

    /// The current estimate (zeros before the second update), ``(dof,)``.
    #[getter]
    fn estimate<'py>(&self, py: Python<'py>) -> Bound<'py, PyArrayDyn<f64>> {
        let e = self.observer.estimate().to_vec();
        let n = e.len();
        array(py, e, &[n])
    }

    /// Number of model coordinates.
    #[getter]
    fn dof(&self) -> usize {
        self.model.dof()
    }

    fn __repr__(&self) -> String {
        format!(
            "MomentumObserver(robot={}, gains={:?})",
            crate::convert::py_str(&self.model.name),
            self.observer.gains()
        )
    }
}
