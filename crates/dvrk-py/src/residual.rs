//! `external_torque` (`dvrk_ident::residual::external_torque`, the computation of
//! `dvrk-ident residual`) and the real-time `MomentumObserver`
//! (`dvrk_model::MomentumObserver`).

use std::sync::Arc;

use dvrk_ident::residual::{
    external_torque as residual_of, ResidualOptions, TipWrench, DEFAULT_OBSERVER_GAIN,
    DEFAULT_WRENCH_RCOND, WRENCH_COMPONENTS,
};
use dvrk_model::{Model, MomentumObserver, Workspace};
use numpy::PyArrayDyn;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::classes::{FitResultPy, ModelPy};
use crate::convert::{array, background, matrix, vector};
use crate::data::{fail_ident, JointLogPy};
use crate::errors::{from_ident, input};
use crate::overrides::parse_joints;
use crate::robot::{params_of, Params};

// The signatures' defaults are written out (Python's signature shows a literal, not a
// constant's name): the library's default gain.
const _: () = assert!(DEFAULT_OBSERVER_GAIN == 20.0);
const _: () = assert!(DEFAULT_WRENCH_RCOND == 1e-6);

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
/// - ``robot``: the :class:`Model` to evaluate (default: the result's);
/// - ``wrench``: a frame of the robot (the PSM's ``"tool_tip"``), as ``--wrench``: the
///   residual also as a Cartesian wrench at the frame's origin, the least-squares
///   solution of ``tau_ext = J(q)ᵀ·F`` (model coordinates), the directions the joints
///   cannot sense at a pose reported, not estimated; ``wrench_rcond`` (default 1e-6) its
///   relative threshold on the singular values of ``Jᵀ``, as ``--wrench-rcond``.
///
/// Returns a dict: ``source``, ``joints`` (names), ``time`` (s, ``(N,)``),
/// ``residual`` and ``observer`` (``(N, dof)``), ``rms`` (of ``residual`` per joint),
/// ``noise_floor`` (the fit's training RMS error per joint, ``metrics.train.rms``, or
/// ``None`` when the result's metrics are in other joints), ``observer_gain``. With
/// ``as_dataframe=True``: a pandas DataFrame of ``time``, ``residual.<joint>`` and
/// ``observer.<joint>`` columns whose ``attrs`` hold ``source``, ``joints``, ``rms``,
/// ``noise_floor`` and ``observer_gain``.
///
/// With ``wrench``, the dict's ``wrench`` is a dict: ``frame``, ``rcond``, ``components``
/// (``fx fy fz mx my mz``: force N, moment N·m about the frame's origin), ``base``
/// ``(N, 6)`` in the base frame's axes, ``tip`` ``(N, 6)`` in the frame's own axes,
/// ``rank`` ``(N,)`` (directions sensed, out of 6), ``unsensed_base`` and
/// ``unsensed_tip`` (per sample a ``(6 − rank, 6)`` array of unit directions along which
/// the wrench is unknown; ``wrench["base"]`` has no component along them); without it,
/// ``None``. The DataFrame adds ``wrench_base.<c>``, ``wrench_tip.<c>`` and
/// ``wrench_rank`` columns and ``attrs["wrench_frame"]``.
///
/// Example::
///
///     >>> r = di.external_torque(result, di.read_log("loaded.mcap", psm))
///     >>> r["rms"] / r["noise_floor"]   # well above 1: something the fit did not see
#[pyfunction]
#[pyo3(signature = (result, data, robot = None, *, observer_gain = 20.0, joints = None, wrench = None, wrench_rcond = 1e-6, as_dataframe = false, **options))]
#[allow(clippy::too_many_arguments)]
pub fn external_torque<'py>(
    py: Python<'py>,
    result: &Bound<'py, FitResultPy>,
    data: &Bound<'py, JointLogPy>,
    robot: Option<&Bound<'py, ModelPy>>,
    observer_gain: f64,
    joints: Option<&str>,
    wrench: Option<String>,
    wrench_rcond: f64,
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
        wrench,
        wrench_rcond,
    };
    let log = data.get().log.clone();
    let res = background(py, move || {
        residual_of(&model, &params, &fitted, &log, &options).map_err(fail_ident)
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
        let components: Vec<String> = WRENCH_COMPONENTS.map(String::from).into();
        if let Some(w) = &res.wrench {
            cols.extend(crate::frame::matrix_columns(
                "wrench_base",
                &components,
                &w.in_base,
            ));
            cols.extend(crate::frame::matrix_columns(
                "wrench_tip",
                &components,
                &w.in_tip,
            ));
            cols.push((
                "wrench_rank".into(),
                w.rank.iter().map(|&r| r as f64).collect(),
            ));
        }
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
        attrs.set_item("wrench_frame", res.wrench.as_ref().map(|w| w.frame.clone()))?;
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
    let wrench = res
        .wrench
        .as_ref()
        .map(|w| wrench_dict(py, w))
        .transpose()?;
    out.set_item("wrench", wrench)?;
    Ok(out.into_any())
}

/// The `wrench` entry of [`external_torque`]'s dict.
fn wrench_dict<'py>(py: Python<'py>, w: &TipWrench) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("frame", &w.frame)?;
    d.set_item("rcond", w.rcond)?;
    d.set_item("components", WRENCH_COMPONENTS.to_vec())?;
    d.set_item("base", matrix(py, &w.in_base))?;
    d.set_item("tip", matrix(py, &w.in_tip))?;
    let rank: Vec<usize> = w.rank.clone();
    d.set_item("rank", numpy::PyArray1::from_vec(py, rank))?;
    let directions = |all: &[Vec<[f64; 6]>]| {
        all.iter()
            .map(|dirs| {
                array(
                    py,
                    dirs.iter().flatten().copied().collect(),
                    &[dirs.len(), 6],
                )
            })
            .collect::<Vec<_>>()
    };
    d.set_item("unsensed_base", directions(&w.unsensed_in_base))?;
    d.set_item("unsensed_tip", directions(&w.unsensed_in_tip))?;
    Ok(d)
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
        let observer =
            MomentumObserver::new(&model, &gains).map_err(|e| input(crate::errors::text(&e)))?;
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
        let (q, dq, tau) =
            crate::robot::state_of(py, &self.model, q, Some(dq), ("tau", Some(tau)))?;
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
