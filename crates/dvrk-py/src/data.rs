//! Joint-space logs: `Data` (a trajectory as read or built from numpy), `Prepared`
//! (processed samples in model coordinates), `read_log`, `list_topics`.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use dvrk_ident::fit::{to_model_coordinates, Prepared};
use dvrk_ident::log::{self, mcap, LogFormat};
use dvrk_ident::trajectory::{Coordinates, Trajectory};
use nalgebra::DMatrix;
use numpy::{PyArrayDyn, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::prelude::*;

use crate::convert::{array, background, float_array, fmt_shape, matrix, py_str, Failure};
use crate::errors::{from_ident, from_log, ident_kind, input, log_kind, Kind};
use crate::json::to_python;
use crate::robot::Robot;

/// A joint-space log: sample times and one row per sample of positions, velocities
/// (optional) and efforts, in the robot's measured joints or in its model coordinates.
///
/// Read one with :func:`read_log`, or build one from numpy arrays::
///
///     >>> t = np.arange(2000) / 200.0                       # s, uniform
///     >>> data = di.Data(t, q, tau, dq=dq)                   # model coordinates q1..qn
///     >>> data = di.Data(t, q_meas, tau_meas, joint_names=psm.measured_joints,
///     ...                coordinates="measured")
///
/// ``time`` (s) must increase strictly; ``q`` (rad or m), ``tau`` (N·m or N) and ``dq``
/// (rad/s or m/s; ``None``: differentiate the filtered positions) have shape
/// ``(N, joints)``; every value must be finite. ``joint_names`` default to the
/// coordinate names ``q1..qn`` in model coordinates and are required in measured
/// ones, where they are matched to the robot's measured joints by name (any order,
/// extra joints ignored). Arrays returned by the attributes are copies.
#[pyclass(name = "Data", module = "dvrk_ident", frozen)]
pub struct DataPy {
    pub traj: Arc<Trajectory>,
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
    match text.to_ascii_lowercase().as_str() {
        "model" => Ok(Coordinates::Model),
        "measured" => Ok(Coordinates::Measured),
        other => Err(input(format!(
            "coordinates: expected \"model\" or \"measured\", got {other:?}"
        ))),
    }
}

/// `None` / `"auto"`: detect; `wpi`, `wpi-csv`, `2019`, `csv`, `mcap`.
pub fn parse_format(text: Option<&str>) -> PyResult<Option<LogFormat>> {
    match text.map(|t| t.to_ascii_lowercase()) {
        None => Ok(None),
        Some(t) if t == "auto" => Ok(None),
        Some(t) if t == "wpi-csv" || t == "wpi_csv" => Ok(Some(LogFormat::Wpi)),
        Some(t) => t.parse::<LogFormat>().map(Some).map_err(|e| {
            input(format!(
                "format: {e} (also accepted: wpi-csv, 2019, auto or None)"
            ))
        }),
    }
}

impl DataPy {
    pub fn new(traj: Trajectory, path: Option<PathBuf>) -> Self {
        DataPy {
            traj: Arc::new(traj),
            path,
        }
    }
}

#[pymethods]
impl DataPy {
    #[new]
    #[pyo3(signature = (time, q, tau, dq = None, *, joint_names = None, coordinates = "model", source = "numpy"))]
    #[allow(clippy::too_many_arguments)]
    fn py_new(
        py: Python<'_>,
        time: &Bound<'_, PyAny>,
        q: &Bound<'_, PyAny>,
        tau: &Bound<'_, PyAny>,
        dq: Option<&Bound<'_, PyAny>>,
        joint_names: Option<Vec<String>>,
        coordinates: &str,
        source: &str,
    ) -> PyResult<Self> {
        let coordinates = parse_coordinates(coordinates)?;
        let q = matrix_arg(py, q, "q")?;
        let tau = matrix_arg(py, tau, "tau")?;
        let dq = match dq.filter(|d| !d.is_none()) {
            Some(d) => Some(matrix_arg(py, d, "dq")?),
            None => None,
        };
        let time_arr = float_array(py, time, "time")?;
        let time_ro = time_arr.readonly();
        if time_ro.ndim() != 1 {
            return Err(input(format!(
                "time: expected a 1-D array of N sample times, got shape {}",
                fmt_shape(time_ro.shape())
            )));
        }
        let time: Vec<f64> = time_ro.as_array().iter().copied().collect();
        let dof = q.ncols();
        let joint_names =
            match (joint_names, coordinates) {
                (Some(names), _) => names,
                (None, Coordinates::Model) => (1..=dof).map(|j| format!("q{j}")).collect(),
                (None, Coordinates::Measured) => return Err(input(
                    "joint_names are required in measured coordinates (e.g. robot.measured_joints)",
                )),
            };
        let traj = Trajectory {
            time,
            q,
            dq,
            tau,
            joint_names,
            coordinates,
            source: source.to_string(),
        };
        traj.validate().map_err(|e| input(e.to_string()))?;
        Ok(DataPy::new(traj, None))
    }

    /// Sample times, s, shape ``(N,)``.
    #[getter]
    fn time<'py>(&self, py: Python<'py>) -> Bound<'py, PyArrayDyn<f64>> {
        let n = self.traj.time.len();
        array(py, self.traj.time.clone(), &[n])
    }

    /// Positions, rad or m, shape ``(N, joints)``.
    #[getter]
    fn q<'py>(&self, py: Python<'py>) -> Bound<'py, PyArrayDyn<f64>> {
        matrix(py, &self.traj.q)
    }

    /// Measured velocities, rad/s or m/s, shape ``(N, joints)``, or ``None``.
    #[getter]
    fn dq<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArrayDyn<f64>>> {
        self.traj.dq.as_ref().map(|d| matrix(py, d))
    }

    /// Efforts, N·m or N, shape ``(N, joints)``.
    #[getter]
    fn tau<'py>(&self, py: Python<'py>) -> Bound<'py, PyArrayDyn<f64>> {
        matrix(py, &self.traj.tau)
    }

    /// One name per column.
    #[getter]
    fn joint_names(&self) -> Vec<String> {
        self.traj.joint_names.clone()
    }

    /// ``"measured"`` (the robot's measured joints, e.g. ROS names) or ``"model"``
    /// (the model's coordinates).
    #[getter]
    fn coordinates(&self) -> String {
        self.traj.coordinates.to_string()
    }

    /// Where the data came from (the file, or ``source`` of the constructor).
    #[getter]
    fn source(&self) -> String {
        self.traj.source.clone()
    }

    /// The file the data were read from, or ``None``.
    #[getter]
    fn path(&self) -> Option<PathBuf> {
        self.path.clone()
    }

    /// Number of joints (columns).
    #[getter]
    fn dof(&self) -> usize {
        self.traj.dof()
    }

    /// Sampling rate estimate, Hz (inverse median time step), or ``None``.
    #[getter]
    fn rate(&self) -> Option<f64> {
        self.traj.rate_hz()
    }

    fn __len__(&self) -> usize {
        self.traj.len()
    }

    /// The data in ``robot``'s model coordinates: columns matched to its measured
    /// joints by name, ``q = M⁻¹ q_measured``, ``dq = M⁻¹ dq_measured``,
    /// ``tau = Mᵀ tau_measured``. Data already in model coordinates are returned as
    /// they are (after checking the number of joints).
    fn to_model(&self, py: Python<'_>, robot: &Bound<'_, Robot>) -> PyResult<DataPy> {
        let model = robot.get().model.clone();
        let traj = self.traj.clone();
        let t = py
            .detach(move || to_model_coordinates(&model, &traj))
            .map_err(from_ident)?;
        Ok(DataPy::new(t, self.path.clone()))
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
        let traj = self.traj.clone();
        py.detach(move || match (format, topic) {
            (LogFormat::Mcap, Some(topic)) => {
                mcap::write_mcap(&path, &traj, &topic, &mcap::McapWriteOptions::default())
            }
            (format, _) => log::write(&path, &traj, format),
        })
        .map_err(from_log)
    }

    fn __repr__(&self) -> String {
        format!(
            "Data({} samples, {} joints, {} coordinates, velocities {}, source={})",
            self.traj.len(),
            self.traj.dof(),
            self.traj.coordinates,
            if self.traj.dq.is_some() {
                "measured"
            } else {
                "absent"
            },
            py_str(&self.traj.source)
        )
    }
}

/// Processed samples in model coordinates, as the estimators see them: the log mapped
/// to model coordinates, known forces (e.g. the MTM cable) subtracted from the
/// torques, the motion low-pass filtered (the torques too with the ``filter_torque``
/// setting), differentiated and trimmed. Attributes ``time`` (s,
/// ``(N,)``), ``q``, ``dq``, ``ddq``, ``tau`` (``(N, dof)``), ``joint_names``.
#[pyclass(name = "Prepared", module = "dvrk_ident", frozen)]
pub struct PreparedPy {
    pub inner: Arc<Prepared>,
    pub joint_names: Vec<String>,
}

#[pymethods]
impl PreparedPy {
    /// Times of the kept samples, s, shape ``(N,)``.
    #[getter]
    fn time<'py>(&self, py: Python<'py>) -> Bound<'py, PyArrayDyn<f64>> {
        let n = self.inner.time.len();
        array(py, self.inner.time.clone(), &[n])
    }

    /// Filtered positions, rad or m, ``(N, dof)``.
    #[getter]
    fn q<'py>(&self, py: Python<'py>) -> Bound<'py, PyArrayDyn<f64>> {
        matrix(py, &self.inner.q)
    }

    /// Velocities, rad/s or m/s, ``(N, dof)``.
    #[getter]
    fn dq<'py>(&self, py: Python<'py>) -> Bound<'py, PyArrayDyn<f64>> {
        matrix(py, &self.inner.dq)
    }

    /// Accelerations, rad/s² or m/s², ``(N, dof)``.
    #[getter]
    fn ddq<'py>(&self, py: Python<'py>) -> Bound<'py, PyArrayDyn<f64>> {
        matrix(py, &self.inner.ddq)
    }

    /// Filtered torques, N·m or N, known forces subtracted, ``(N, dof)``.
    #[getter]
    fn tau<'py>(&self, py: Python<'py>) -> Bound<'py, PyArrayDyn<f64>> {
        matrix(py, &self.inner.tau)
    }

    /// The model's coordinate names (the columns).
    #[getter]
    fn joint_names(&self) -> Vec<String> {
        self.joint_names.clone()
    }

    /// Where the data came from.
    #[getter]
    fn source(&self) -> String {
        self.inner.source.clone()
    }

    fn __len__(&self) -> usize {
        self.inner.len()
    }

    fn __repr__(&self) -> String {
        format!(
            "Prepared({} samples, {} coordinates, source={})",
            self.inner.len(),
            self.joint_names.len(),
            py_str(&self.inner.source)
        )
    }
}

fn fail_log(e: log::LogError) -> Failure {
    (log_kind(&e), e.to_string())
}

pub fn fail_ident(e: dvrk_ident::IdentError) -> Failure {
    (ident_kind(&e), e.to_string())
}

/// Reads a log into :class:`Data`.
///
/// ``format``: ``None`` (from the file: ``.mcap`` is MCAP; a first row of numbers is
/// the 2019 layout, anything else a headered CSV), ``"wpi"``/``"wpi-csv"`` (the 2019
/// layout: no header, ``q, dq, tau`` columns in model coordinates, no time stamps:
/// ``rate`` in Hz is required), ``"csv"`` (headered: ``time``, ``position.<joint>``,
/// optional ``velocity.<joint>``, ``effort.<joint>``) or ``"mcap"`` (ROS 2
/// ``sensor_msgs/msg/JointState``, measured joints). ``rate`` is ignored for logs with
/// time stamps.
///
/// MCAP only: ``topic`` (a topic or a list, merged, the first one the clock; default:
/// the automatic choice), ``time_source`` (``"header"`` stamps, default, ``"log"`` or
/// ``"publish"`` times). ``resample`` (Hz, any format): resample to a uniform rate by
/// linear interpolation, as the CLI's ``--resample``; otherwise a log with gaps or
/// jitter is refused by the processing.
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
#[pyo3(signature = (path, robot = None, format = None, rate = None, topic = None, time_source = None, resample = None))]
#[allow(clippy::too_many_arguments)]
pub fn read_log(
    py: Python<'_>,
    path: PathBuf,
    robot: Option<&Bound<'_, Robot>>,
    format: Option<&str>,
    rate: Option<f64>,
    topic: Option<&Bound<'_, PyAny>>,
    time_source: Option<&str>,
    resample: Option<f64>,
) -> PyResult<DataPy> {
    let format = parse_format(format)?;
    let topics: Vec<String> = match topic.filter(|t| !t.is_none()) {
        None => Vec::new(),
        Some(t) => match t.extract::<String>() {
            Ok(s) => vec![s],
            Err(_) => t
                .extract::<Vec<String>>()
                .map_err(|_| input("topic: expected a topic name or a list of topic names"))?,
        },
    };
    let time_source = match time_source {
        None => mcap::TimeSource::default(),
        Some(s) => s
            .parse::<mcap::TimeSource>()
            .map_err(|e| input(format!("time_source: {e}")))?,
    };
    let given_time_source = time_source != mcap::TimeSource::default();
    let model = robot.map(|r| r.get().model.clone());
    let file = path.clone();
    let traj = background(py, move || {
        let format = match format {
            Some(f) => f,
            None => log::detect_format(&file).map_err(fail_log)?,
        };
        if format != LogFormat::Mcap && (!topics.is_empty() || given_time_source) {
            return Err((
                Kind::Input,
                format!(
                    "{}: topic and time_source apply to MCAP logs only, this is a {format} log",
                    file.display()
                ),
            ));
        }
        let traj = match (format, rate) {
            (LogFormat::Wpi, Some(rate)) => {
                log::read_wpi(&file, rate, model.as_ref().map(|m| m.dof()))
            }
            (LogFormat::Mcap, _) => mcap::read_mcap(
                &file,
                &mcap::McapOptions {
                    topics,
                    time_source,
                    resample_hz: resample,
                },
            ),
            (format, rate) => log::read(&file, Some(format), rate),
        }
        .map_err(fail_log)?;
        let traj = match resample {
            Some(hz) if format != LogFormat::Mcap => {
                log::resample(&file, traj, hz).map_err(fail_log)?
            }
            _ => traj,
        };
        if let Some(model) = &model {
            to_model_coordinates(model, &traj).map_err(fail_ident)?;
        }
        Ok(traj)
    })?;
    Ok(DataPy::new(traj, Some(absolute(&path))))
}

fn absolute(path: &Path) -> PathBuf {
    std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf())
}

/// The topics of an MCAP file: a list of dicts ``{topic, schema_name,
/// message_encoding, messages}``.
#[pyfunction]
pub fn list_topics<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyAny>> {
    let topics = py
        .detach(move || mcap::list_topics(&path))
        .map_err(from_log)?;
    to_python(py, &topics)
}
