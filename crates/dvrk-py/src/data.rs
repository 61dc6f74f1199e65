//! Joint-space logs: `JointLog` (a trajectory as read or built from numpy), `Prepared`
//! (processed samples in model coordinates), `read_log`, `list_topics`.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use dvrk_ident::log::{self, mcap, LogFormat, ReadOptions};
use dvrk_ident::simulate::to_model_coordinates;
use dvrk_ident::validate::Prepared;
use dvrk_ident::{Coordinates, JointLog};
use nalgebra::DMatrix;
use numpy::{PyArrayDyn, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PySlice, PyTuple};

use crate::classes::ModelPy;
use crate::convert::{array, background, float_array, fmt_shape, matrix, py_str, Failure};
use crate::errors::{from_ident, from_log, input, log_kind};
use crate::frame;
use crate::json::to_python;

/// A joint-space log: sample times and one row per sample of positions, velocities
/// (optional) and efforts, in the robot's measured joints or in its model coordinates.
///
/// Read one with :func:`read_log`, build one from numpy arrays or pandas DataFrames::
///
///     >>> t = np.arange(2000) / 200.0                       # s, uniform
///     >>> data = di.JointLog(t, q, tau, dq=dq)                   # model coordinates q1..qn
///     >>> data = di.JointLog(t, q_meas, tau_meas, joint_names=psm.measured_joints)
///     >>> data = di.JointLog.from_dataframe(df, psm)             # position.<joint> columns
///
/// ``time``: float seconds, or ``datetime64``/``timedelta64`` (any unit, pandas
/// datetimes too) or integer nanoseconds, which are converted exactly to seconds from
/// the first sample (ROS stamps as float seconds have lost their nanoseconds
/// already). Times must increase strictly. ``q`` (rad or m), ``tau`` (N·m or N) and
/// ``dq`` (rad/s or m/s; ``None``: differentiate the filtered positions) have shape
/// ``(N, joints)``; every value must be finite. Joint names come from
/// ``joint_names``, else from the columns of DataFrames (a ``position.`` prefix
/// dropped; ``tau`` and ``dq`` columns are matched to ``q``'s by name), else are the
/// coordinate names ``q1..qn``. ``coordinates`` (``"model"`` or ``"measured"``)
/// defaults to ``"model"`` when every name is ``q<k>``, else ``"measured"``: measured
/// joints are matched to the robot's by name (any order, extra joints ignored).
///
/// ``data[a:b]`` is a slice of the samples (times kept), :meth:`concat` joins logs
/// into one (one clock: the filters then run across the joints; give a fit a list of
/// logs to keep them apart), :meth:`to_dataframe` gives a DataFrame; ``JointLog`` pickles
/// (multiprocessing, joblib, ``copy.deepcopy``). Arrays returned by the attributes
/// are copies.
#[pyclass(name = "JointLog", module = "dvrk_ident", frozen)]
pub struct JointLogPy {
    pub log: Arc<JointLog>,
    /// The file it was read from (for the result's provenance).
    pub path: Option<PathBuf>,
}

/// A 2-D float64 array as a matrix (any number of rows and columns).
fn matrix_arg(py: Python<'_>, obj: &Bound<'_, PyAny>, name: &str) -> PyResult<DMatrix<f64>> {
    let arr = float_array(py, obj, name)?;
    let ro = arr.readonly();
    let view = ro.as_array();
    match view.shape() {
        [r, c] => {
            let data: Vec<f64> = view.iter().copied().collect();
            Ok(DMatrix::from_row_slice(*r, *c, &data))
        }
        s => Err(input(format!(
            "{name}: expected a 2-D array (samples, joints), got shape {}",
            fmt_shape(s)
        ))),
    }
}

fn parse_coordinates(text: &str) -> PyResult<Coordinates> {
    crate::convert::named("coordinates", text)
}

/// `None` / `"auto"`: detect; otherwise a log format's name (`wpi`, `csv`, `mcap`, ...).
pub fn parse_format(text: Option<&str>) -> PyResult<Option<LogFormat>> {
    match text {
        None => Ok(None),
        Some(t) if t.eq_ignore_ascii_case("auto") => Ok(None),
        Some(t) => crate::convert::named("format", t).map(Some),
    }
}

impl JointLogPy {
    pub fn new(log: JointLog, path: Option<PathBuf>) -> Self {
        JointLogPy {
            log: Arc::new(log),
            path,
        }
    }
}

/// Columns of `m` reordered from `names` to `order` (the same joints), or an error.
fn reorder(
    m: DMatrix<f64>,
    names: &[String],
    order: &[String],
    what: &str,
) -> PyResult<DMatrix<f64>> {
    if names == order {
        return Ok(m);
    }
    let mut out = DMatrix::zeros(m.nrows(), order.len());
    if names.len() != order.len() {
        return Err(input(format!(
            "{what}: columns {names:?} are not the joints of q {order:?}"
        )));
    }
    for (j, name) in order.iter().enumerate() {
        let k = names.iter().position(|n| n == name).ok_or_else(|| {
            input(format!(
                "{what}: columns {names:?} are not the joints of q {order:?}"
            ))
        })?;
        out.set_column(j, &m.column(k));
    }
    Ok(out)
}

fn coordinates_arg(text: Option<&str>, names: &[String]) -> PyResult<Coordinates> {
    match text {
        Some(t) => parse_coordinates(t),
        None => frame::infer_coordinates(names, None),
    }
}

#[pymethods]
impl JointLogPy {
    #[new]
    #[pyo3(signature = (time, q, tau, dq = None, *, joint_names = None, coordinates = None, source = "numpy"))]
    #[allow(clippy::too_many_arguments)]
    fn py_new(
        py: Python<'_>,
        time: &Bound<'_, PyAny>,
        q: &Bound<'_, PyAny>,
        tau: &Bound<'_, PyAny>,
        dq: Option<&Bound<'_, PyAny>>,
        joint_names: Option<Vec<String>>,
        coordinates: Option<&str>,
        source: &str,
    ) -> PyResult<Self> {
        let q_names = frame::column_names(q)?;
        let dof_q = matrix_arg(py, q, "q")?;
        let names = match (joint_names, &q_names) {
            (Some(names), Some(cols)) if names != *cols => {
                return Err(input(format!(
                    "joint_names {names:?} differ from q's columns {cols:?}"
                )))
            }
            (Some(names), _) => names,
            (None, Some(cols)) => cols.clone(),
            (None, None) => match coordinates.map(parse_coordinates).transpose()? {
                Some(Coordinates::Measured) => return Err(input(
                    "joint_names are required in measured coordinates (e.g. robot.measured_joints)",
                )),
                _ => (1..=dof_q.ncols()).map(|j| format!("q{j}")).collect(),
            },
        };
        let coordinates = coordinates_arg(coordinates, &names)?;
        let with_names = |obj: &Bound<'_, PyAny>, what: &str| -> PyResult<DMatrix<f64>> {
            let m = matrix_arg(py, obj, what)?;
            match frame::column_names(obj)? {
                Some(cols) => reorder(m, &cols, &names, what),
                None => Ok(m),
            }
        };
        let tau = with_names(tau, "tau")?;
        let dq = match dq.filter(|d| !d.is_none()) {
            Some(d) => Some(with_names(d, "dq")?),
            None => None,
        };
        let log = JointLog {
            time: frame::times(py, time, "time")?,
            q: dof_q,
            dq,
            tau,
            joint_names: names,
            coordinates,
            source: source.to_string(),
        };
        log.validate().map_err(|e| input(crate::errors::text(&e)))?;
        Ok(JointLogPy::new(log, None))
    }

    /// A log from a pandas DataFrame laid out as the headered CSV: a ``time`` column
    /// (or ``time=`` another one, or the index: datetime, timedelta or float), and
    /// ``position.<joint>``, ``effort.<joint>`` and optionally ``velocity.<joint>``
    /// columns for each joint (also ``q.``, ``tau.``, ``dq.``), or a two-level column
    /// MultiIndex ``(signal, joint)``. Times as in :class:`JointLog`. With ``robot``, the
    /// joints must all be its coordinates (model coordinates) or all its measured
    /// joints (measured coordinates); without, names ``q<k>`` are model coordinates.
    /// :meth:`to_dataframe` gives this layout back.
    #[staticmethod]
    #[pyo3(signature = (df, robot = None, *, time = None, source = "dataframe"))]
    fn from_dataframe(
        py: Python<'_>,
        df: &Bound<'_, PyAny>,
        robot: Option<&Bound<'_, ModelPy>>,
        time: Option<&str>,
        source: &str,
    ) -> PyResult<Self> {
        let c = frame::read_frame(py, df, time)?;
        let model = robot.map(|r| r.get().model.clone());
        let coordinates = frame::infer_coordinates(&c.joints, model.as_deref())?;
        let log = JointLog {
            time: frame::times(py, &c.time, "time")?,
            q: c.q,
            dq: c.dq,
            tau: c.tau,
            joint_names: c.joints,
            coordinates,
            source: source.to_string(),
        };
        log.validate().map_err(|e| input(crate::errors::text(&e)))?;
        Ok(JointLogPy::new(log, None))
    }

    /// The samples as a pandas DataFrame: ``time`` (s), ``position.<joint>``,
    /// ``velocity.<joint>`` (when measured), ``effort.<joint>``, the headered CSV's
    /// layout (:meth:`from_dataframe` reads it back).
    fn to_dataframe<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let t = &self.log;
        let mut cols = vec![("time".to_string(), t.time.clone())];
        cols.extend(frame::matrix_columns("position", &t.joint_names, &t.q));
        if let Some(dq) = &t.dq {
            cols.extend(frame::matrix_columns("velocity", &t.joint_names, dq));
        }
        cols.extend(frame::matrix_columns("effort", &t.joint_names, &t.tau));
        frame::dataframe(py, cols)
    }

    /// ``data[a:b]`` (a slice, positive step): those samples, times kept.
    fn __getitem__(&self, index: &Bound<'_, PyAny>) -> PyResult<JointLogPy> {
        let slice = index
            .cast::<PySlice>()
            .map_err(|_| input("JointLog: index with a slice of samples, e.g. data[100:500]"))?;
        let ind = slice.indices(self.log.len() as isize)?;
        if ind.step <= 0 {
            return Err(input(
                "JointLog: a slice must keep the time order (positive step)",
            ));
        }
        let rows: Vec<usize> = (ind.start..ind.stop)
            .step_by(ind.step as usize)
            .map(|k| k as usize)
            .collect();
        Ok(JointLogPy::new(self.log.select_rows(&rows), None))
    }

    /// The samples of several logs as one (same joints, coordinates and velocities;
    /// each log's times after the previous log's). One log has one clock: processing
    /// will filter across the joins. To fit logs that were recorded apart, give
    /// :func:`fit` the list instead.
    #[staticmethod]
    #[pyo3(signature = (logs, *, source = None))]
    fn concat(logs: Vec<Bound<'_, JointLogPy>>, source: Option<String>) -> PyResult<JointLogPy> {
        let Some(first) = logs.first() else {
            return Err(input("concat: no logs"));
        };
        let f = first.get().log.clone();
        let mut time = Vec::new();
        let (mut q, mut dq, mut tau) = (Vec::new(), Vec::new(), Vec::new());
        let mut sources = Vec::new();
        for (k, d) in logs.iter().enumerate() {
            let t = &d.get().log;
            if t.joint_names != f.joint_names || t.coordinates != f.coordinates {
                return Err(input(format!(
                    "concat: log {k} has joints {:?} ({} coordinates), log 0 {:?} ({})",
                    t.joint_names, t.coordinates, f.joint_names, f.coordinates
                )));
            }
            if t.dq.is_some() != f.dq.is_some() {
                return Err(input(format!(
                    "concat: log {k} {} velocities, log 0 {}",
                    if t.dq.is_some() { "has" } else { "has no" },
                    if f.dq.is_some() { "has" } else { "has none" }
                )));
            }
            if let (Some(last), Some(next)) = (time.last(), t.time.first()) {
                if next <= last {
                    return Err(input(format!(
                        "concat: log {k} starts at {next} s, not after the previous log's end at {last} s"
                    )));
                }
            }
            time.extend_from_slice(&t.time);
            for i in 0..t.len() {
                q.extend(t.q.row(i).iter());
                tau.extend(t.tau.row(i).iter());
                if let Some(d) = &t.dq {
                    dq.extend(d.row(i).iter());
                }
            }
            sources.push(t.source.clone());
        }
        let (n, dof) = (time.len(), f.dof());
        let log = JointLog {
            time,
            q: DMatrix::from_row_slice(n, dof, &q),
            dq: f.dq.as_ref().map(|_| DMatrix::from_row_slice(n, dof, &dq)),
            tau: DMatrix::from_row_slice(n, dof, &tau),
            joint_names: f.joint_names.clone(),
            coordinates: f.coordinates,
            source: source.unwrap_or_else(|| sources.join(" + ")),
        };
        log.validate().map_err(|e| input(crate::errors::text(&e)))?;
        Ok(JointLogPy::new(log, None))
    }

    /// Pickling (and ``copy.deepcopy``): the arrays and names.
    fn __reduce__<'py>(
        slf: &Bound<'py, Self>,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        let py = slf.py();
        let d = slf.get();
        let t = &d.log;
        let args = PyTuple::new(
            py,
            [
                array(py, t.time.clone(), &[t.len()]).into_any(),
                matrix(py, &t.q).into_any(),
                matrix(py, &t.tau).into_any(),
                match &t.dq {
                    Some(m) => matrix(py, m).into_any(),
                    None => py.None().into_bound(py),
                },
                t.joint_names.clone().into_pyobject(py)?.into_any(),
                t.coordinates.to_string().into_pyobject(py)?.into_any(),
                t.source.clone().into_pyobject(py)?.into_any(),
                d.path.clone().into_pyobject(py)?.into_any(),
            ],
        )?;
        Ok((slf.get_type().getattr("_restore")?, args))
    }

    /// The inverse of ``__reduce__``.
    #[staticmethod]
    #[allow(clippy::too_many_arguments)]
    fn _restore(
        py: Python<'_>,
        time: &Bound<'_, PyAny>,
        q: &Bound<'_, PyAny>,
        tau: &Bound<'_, PyAny>,
        dq: Option<&Bound<'_, PyAny>>,
        joint_names: Vec<String>,
        coordinates: &str,
        source: String,
        path: Option<PathBuf>,
    ) -> PyResult<JointLogPy> {
        let arr = float_array(py, time, "time")?;
        let time: Vec<f64> = arr.readonly().as_array().iter().copied().collect();
        let log = JointLog {
            time,
            q: matrix_arg(py, q, "q")?,
            dq: dq.map(|d| matrix_arg(py, d, "dq")).transpose()?,
            tau: matrix_arg(py, tau, "tau")?,
            joint_names,
            coordinates: parse_coordinates(coordinates)?,
            source,
        };
        log.validate().map_err(|e| input(crate::errors::text(&e)))?;
        Ok(JointLogPy::new(log, path))
    }

    /// Sample times, s, shape ``(N,)``.
    #[getter]
    fn time<'py>(&self, py: Python<'py>) -> Bound<'py, PyArrayDyn<f64>> {
        let n = self.log.time.len();
        array(py, self.log.time.clone(), &[n])
    }

    /// Positions, rad or m, shape ``(N, joints)``.
    #[getter]
    fn q<'py>(&self, py: Python<'py>) -> Bound<'py, PyArrayDyn<f64>> {
        matrix(py, &self.log.q)
    }

    /// Measured velocities, rad/s or m/s, shape ``(N, joints)``, or ``None``.
    #[getter]
    fn dq<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArrayDyn<f64>>> {
        self.log.dq.as_ref().map(|d| matrix(py, d))
    }

    /// Efforts, N·m or N, shape ``(N, joints)``.
    #[getter]
    fn tau<'py>(&self, py: Python<'py>) -> Bound<'py, PyArrayDyn<f64>> {
        matrix(py, &self.log.tau)
    }

    /// One name per column.
    #[getter]
    fn joint_names(&self) -> Vec<String> {
        self.log.joint_names.clone()
    }

    /// ``"measured"`` (the robot's measured joints, e.g. ROS names) or ``"model"``
    /// (the model's coordinates).
    #[getter]
    fn coordinates(&self) -> String {
        self.log.coordinates.to_string()
    }

    /// Where the data came from (the file, or ``source`` of the constructor).
    #[getter]
    fn source(&self) -> String {
        self.log.source.clone()
    }

    /// The file the data were read from, or ``None``.
    #[getter]
    fn path(&self) -> Option<PathBuf> {
        self.path.clone()
    }

    /// Number of joints (columns).
    #[getter]
    fn dof(&self) -> usize {
        self.log.dof()
    }

    /// Sampling rate estimate, Hz (inverse median time step), or ``None``.
    #[getter]
    fn rate(&self) -> Option<f64> {
        self.log.rate_hz()
    }

    fn __len__(&self) -> usize {
        self.log.len()
    }

    /// The data in ``robot``'s model coordinates: columns matched to its measured
    /// joints by name, ``q = M⁻¹ q_measured``, ``dq = M⁻¹ dq_measured``,
    /// ``tau = Mᵀ tau_measured``. JointLog already in model coordinates are returned as
    /// they are (after checking the number of joints).
    fn to_model(&self, py: Python<'_>, robot: &Bound<'_, ModelPy>) -> PyResult<JointLogPy> {
        let model = robot.get().model.clone();
        let log = self.log.clone();
        let t = py
            .detach(move || to_model_coordinates(&model, &log))
            .map_err(from_ident)?;
        Ok(JointLogPy::new(t, self.path.clone()))
    }

    /// Writes the data as a log, atomically. ``format``: ``"csv"`` (headered:
    /// ``time, position.<joint>, velocity.<joint>, effort.<joint>``), ``"wpi"`` (the
    /// 2019 layout: model coordinates with velocities, no time) or ``"mcap"`` (ROS 2
    /// ``sensor_msgs/msg/JointState`` on ``topic``, default ``/measured_js``); default
    /// from the extension (``.mcap``, else ``csv``).
    #[pyo3(signature = (path, format = None, topic = None))]
    fn write(
        &self,
        py: Python<'_>,
        path: PathBuf,
        format: Option<&str>,
        topic: Option<String>,
    ) -> PyResult<()> {
        let format = parse_format(format)?.unwrap_or_else(|| {
            if path
                .extension()
                .is_some_and(|e| e.eq_ignore_ascii_case("mcap"))
            {
                LogFormat::Mcap
            } else {
                LogFormat::Csv
            }
        });
        if topic.is_some() && format != LogFormat::Mcap {
            return Err(input("topic: only MCAP logs have topics"));
        }
        let log = self.log.clone();
        py.detach(move || match (format, topic) {
            (LogFormat::Mcap, Some(topic)) => {
                mcap::write_mcap(&path, &log, &topic, &mcap::McapWriteOptions::default())
            }
            (format, _) => log::write(&path, &log, format),
        })
        .map_err(from_log)
    }

    fn __repr__(&self) -> String {
        format!(
            "JointLog({} samples, {} joints, {} coordinates, velocities {}, source={})",
            self.log.len(),
            self.log.dof(),
            self.log.coordinates,
            if self.log.dq.is_some() {
                "measured"
            } else {
                "absent"
            },
            py_str(&self.log.source)
        )
    }
}

/// Processed samples as the estimators see them: the log mapped to model coordinates,
/// known forces (e.g. the MTM cable) subtracted from the torques, the motion low-pass
/// filtered (the torques too with the ``filter_torque`` setting), differentiated and
/// trimmed. Attributes ``time`` (s, ``(N,)``), ``q``, ``dq``, ``ddq``, ``tau``
/// (``(N, dof)``), ``joint_names``, ``joints``: shown in the model coordinates, or in
/// the arm's measured joints (``joints="measured"``: ``q = M·q_model``,
/// ``tau = M⁻ᵀ·tau_model``).
#[pyclass(name = "Prepared", module = "dvrk_ident", frozen)]
pub struct PreparedPy {
    /// In model coordinates: what the inverse dynamics reads.
    pub inner: Arc<Prepared>,
    /// In the joints shown (`inner` itself for the model coordinates).
    pub shown: Arc<Prepared>,
    pub joint_names: Vec<String>,
    pub joints: dvrk_ident::Joints,
}

impl PreparedPy {
    /// `p` (model coordinates) shown in the joints of `map`.
    pub fn new(p: Prepared, map: &dvrk_ident::validate::JointMap) -> PreparedPy {
        let inner = Arc::new(p);
        let shown = match map.prepared(&inner) {
            std::borrow::Cow::Borrowed(_) => inner.clone(),
            std::borrow::Cow::Owned(shown) => Arc::new(shown),
        };
        PreparedPy {
            inner,
            shown,
            joint_names: map.names.clone(),
            joints: map.joints,
        }
    }
}

#[pymethods]
impl PreparedPy {
    /// Times of the kept samples, s, shape ``(N,)``.
    #[getter]
    fn time<'py>(&self, py: Python<'py>) -> Bound<'py, PyArrayDyn<f64>> {
        let n = self.shown.time.len();
        array(py, self.shown.time.clone(), &[n])
    }

    /// Filtered positions, rad or m, ``(N, dof)``.
    #[getter]
    fn q<'py>(&self, py: Python<'py>) -> Bound<'py, PyArrayDyn<f64>> {
        matrix(py, &self.shown.q)
    }

    /// Velocities, rad/s or m/s, ``(N, dof)``.
    #[getter]
    fn dq<'py>(&self, py: Python<'py>) -> Bound<'py, PyArrayDyn<f64>> {
        matrix(py, &self.shown.dq)
    }

    /// Accelerations, rad/s² or m/s², ``(N, dof)``.
    #[getter]
    fn ddq<'py>(&self, py: Python<'py>) -> Bound<'py, PyArrayDyn<f64>> {
        matrix(py, &self.shown.ddq)
    }

    /// Filtered torques, N·m or N, known forces subtracted, ``(N, dof)``.
    #[getter]
    fn tau<'py>(&self, py: Python<'py>) -> Bound<'py, PyArrayDyn<f64>> {
        matrix(py, &self.shown.tau)
    }

    /// The names of the columns: the model's coordinates, or the arm's measured joints.
    #[getter]
    fn joint_names(&self) -> Vec<String> {
        self.joint_names.clone()
    }

    /// ``"model"`` or ``"measured"``: the joints the arrays are in.
    #[getter]
    fn joints(&self) -> &'static str {
        self.joints.name()
    }

    /// Where the data came from.
    #[getter]
    fn source(&self) -> String {
        self.shown.source.clone()
    }

    /// The samples as a pandas DataFrame: ``time`` (s), then ``position.<q>``,
    /// ``velocity.<q>``, ``acceleration.<q>`` and ``effort.<q>`` per joint.
    fn to_dataframe<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let p = &self.shown;
        let names = &self.joint_names;
        let mut cols = vec![("time".to_string(), p.time.clone())];
        cols.extend(frame::matrix_columns("position", names, &p.q));
        cols.extend(frame::matrix_columns("velocity", names, &p.dq));
        cols.extend(frame::matrix_columns("acceleration", names, &p.ddq));
        cols.extend(frame::matrix_columns("effort", names, &p.tau));
        frame::dataframe(py, cols)
    }

    fn __len__(&self) -> usize {
        self.shown.len()
    }

    fn __repr__(&self) -> String {
        format!(
            "Prepared({} samples, {} {} joints, source={})",
            self.shown.len(),
            self.joint_names.len(),
            self.joints.name(),
            py_str(&self.shown.source)
        )
    }
}

fn fail_log(e: log::LogError) -> Failure {
    (log_kind(&e), crate::errors::text(&e))
}

pub fn fail_ident(e: dvrk_ident::IdentError) -> Failure {
    crate::errors::ident_failure(&e)
}

/// Reads a log into :class:`JointLog`.
///
/// ``path`` is a file or a rosbag2 folder, recognized by content (``format=None``): a
/// rosbag2 folder or its ``metadata.yaml`` (MCAP or sqlite3 files, split recordings,
/// zstd/lz4 compressed files or messages), an MCAP file, a sqlite3 ``.db3``, a ROS 1
/// ``.bag`` (``sensor_msgs/JointState``), the 2019 layout (a first row of numbers: no
/// header, ``q, dq, tau`` columns in model coordinates, no time stamps: ``rate`` in Hz
/// is required) or a headered CSV (``time``, ``position.<joint>``, optional
/// ``velocity.<joint>``, ``effort.<joint>``). ``format`` forces one: ``"wpi"``
/// (``"wpi-csv"``), ``"csv"``, ``"mcap"``, ``"rosbag2"``, ``"sqlite3"``, ``"ros1"``.
/// ``rate`` is ignored for logs with time stamps.
///
/// Recordings only: ``topic`` (a topic or a list, merged, the first one the clock;
/// default: the automatic choice, which with ``robot`` pairs a dVRK arm topic with its
/// jaw topic when the robot's joints need both), ``time_source`` (``"header"`` stamps,
/// default, ``"log"`` or ``"publish"`` times). ``resample`` (Hz, any format): resample
/// to a uniform rate by linear interpolation; otherwise a log with gaps or jitter is
/// refused by the processing. ``max_unpacked_mib``: the most a compressed recording may
/// decompress to, MiB (``--max-unpacked-mib``; default 100 times its size, at least 64
/// MiB and at most 16 GiB): beyond it the file is refused as a decompression bomb.
///
/// With ``robot``, the log is checked against it (its measured joints present, or the
/// right number of model coordinates; the 2019 layout's number of joints is the
/// robot's) and a mismatch raises ``InputError``; the data are returned as read.
///
/// Example::
///
///     >>> data = di.read_log("one_results.csv", psm, format="wpi-csv", rate=200)
///     >>> data.coordinates, data.q.shape
///     ('model', (17921, 7))
#[pyfunction]
#[pyo3(signature = (path, robot = None, format = None, rate = None, topic = None, time_source = None, resample = None, max_unpacked_mib = None))]
#[allow(clippy::too_many_arguments)]
pub fn read_log(
    py: Python<'_>,
    path: PathBuf,
    robot: Option<&Bound<'_, ModelPy>>,
    format: Option<&str>,
    rate: Option<f64>,
    topic: Option<&Bound<'_, PyAny>>,
    time_source: Option<&str>,
    resample: Option<f64>,
    max_unpacked_mib: Option<u64>,
) -> PyResult<JointLogPy> {
    let topics: Vec<String> = match topic.filter(|t| !t.is_none()) {
        None => Vec::new(),
        Some(t) => match t.extract::<String>() {
            Ok(s) => vec![s],
            Err(_) => t
                .extract::<Vec<String>>()
                .map_err(|_| input("topic: expected a topic name or a list of topic names"))?,
        },
    };
    let options = ReadOptions {
        format: parse_format(format)?,
        rate_hz: rate,
        topics,
        time_source: time_source
            .map(|s| crate::convert::named("time_source", s))
            .transpose()?,
        resample_hz: resample,
        max_unpacked_mib,
        ..ReadOptions::default()
    };
    let model = robot.map(|r| r.get().model.clone());
    let file = path.clone();
    let log = background(py, move || {
        let options = match &model {
            Some(m) => options.for_model(m),
            None => options,
        };
        let log = options.read(&file).map_err(fail_log)?;
        if let Some(model) = &model {
            to_model_coordinates(model, &log).map_err(fail_ident)?;
        }
        Ok(log)
    })?;
    Ok(JointLogPy::new(log, Some(absolute(&path))))
}

/// `path` made absolute, for the provenance (the file as given when that fails).
pub fn absolute(path: &Path) -> PathBuf {
    std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf())
}

/// The topics of a recording (an MCAP, sqlite3 or ROS 1 file, or a rosbag2 folder): a
/// list of dicts ``{topic, schema_name, message_encoding, messages}``.
#[pyfunction]
pub fn list_topics<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyAny>> {
    let topics = py
        .detach(move || mcap::list_topics(&path))
        .map_err(from_log)?;
    to_python(py, &topics)
}
