//! The identification pipeline: log → model coordinates → known forces removed →
//! processing → weighted observation → estimator → parameters, metrics and the result
//! document. [`fit`] works on logs in memory; [`stream::fit_stream`] on logs read from
//! disk block by block, for logs larger than memory, with the same result.

pub mod delay;
mod joints;
pub mod stream;

pub use joints::{units, JointMap};

use dvrk_model::{inertia, BaseParameters, Model, Workspace};
use nalgebra::DMatrix;

use crate::error::IdentError;
use crate::estimate::ols::{base_least_squares, representative, BaseEstimate};
use crate::estimate::sdp::{solve_sdp, PriorMetric, SdpOptions};
use crate::joint_log::{Coordinates, JointLog};
use crate::observation::{Observation, Samples};
use crate::progress::{Progress, Silent};
use crate::result::*;
use crate::signal::stream::process_in_blocks;
use crate::signal::Processing;

pub use crate::settings::{BoundsSet, FitSettings, Method};

/// Friction and motor inertia count as non-negative down to `-ELEMENT_TOLERANCE`
/// (N·m, N·m·s/rad, kg·m²): zero up to rounding. A converged semidefinite fit meets its
/// sign bounds exactly (projected after the solve, `estimate::sdp`), so its verdict
/// never hangs on Clarabel's feasibility tolerance (1e-8 relative).
pub const ELEMENT_TOLERANCE: f64 = 1e-9;

/// Processed samples in model coordinates, known forces subtracted from the torques.
#[derive(Clone, Debug)]
pub struct Prepared {
    /// The log the samples came from (a file, or a name given in Python), for messages.
    pub source: String,
    /// Time of each processed sample, s (after trimming and decimation).
    pub time: Vec<f64>,
    /// Positions in model coordinates, samples × coordinates, rad or m (filtered).
    pub q: DMatrix<f64>,
    /// Velocities, rad/s or m/s (measured or differentiated, filtered).
    pub dq: DMatrix<f64>,
    /// Accelerations, rad/s² or m/s² (differentiated from the raw velocity, filtered).
    pub ddq: DMatrix<f64>,
    /// N·m or N, known forces subtracted
    pub tau: DMatrix<f64>,
}

impl Prepared {
    /// The samples as the regressor and the metrics read them.
    pub fn samples(&self) -> Samples<'_> {
        Samples {
            q: &self.q,
            dq: &self.dq,
            ddq: &self.ddq,
            tau: &self.tau,
        }
    }

    /// Number of processed samples.
    pub fn len(&self) -> usize {
        self.q.nrows()
    }

    /// Whether no sample is left.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// The trajectory in model coordinates: columns matched to the robot's measured joint
/// names (any order, extra joints ignored), then `q = M⁻¹ q_measured`,
/// `q̇ = M⁻¹ q̇_measured`, `τ = Mᵀ τ_measured`.
pub fn to_model_coordinates(model: &Model, traj: &JointLog) -> Result<JointLog, IdentError> {
    let n = model.dof();
    let mismatch = |message: String| IdentError::Mismatch {
        source_name: traj.source.clone(),
        message,
    };
    if traj.coordinates == Coordinates::Model {
        // A headered CSV tells model coordinates by their names `q1..qn`; a robot whose
        // measured joints carry those very names through a non-identity coupling would
        // make such a file ambiguous.
        if model.measured.joints == traj.joint_names
            && model.measured.coupling != DMatrix::identity(n, n)
        {
            return Err(mismatch(format!(
                "the log's joints `{}` are both robot {}'s model coordinates and its measured \
                 joints, which differ by a coupling: rename the measured joints",
                traj.joint_names.join(", "),
                model.name
            )));
        }
        if traj.dof() != n {
            return Err(mismatch(format!(
                "the log has {} joints in model coordinates but robot {} has {n} coordinates",
                traj.dof(),
                model.name
            )));
        }
        let coupling = &model.measured.coupling;
        check_ranges(model, traj, |i, k| {
            (0..n).fold(0.0, |acc, j| acc + coupling[(k, j)] * traj.q[(i, j)])
        })?;
        return Ok(traj.clone());
    }
    let mut cols = Vec::with_capacity(n);
    for name in &model.measured.joints {
        match traj.joint_names.iter().position(|j| j == name) {
            Some(c) => cols.push(c),
            None => {
                return Err(mismatch(format!(
                    "joint `{name}` of robot {} is missing (the log has: {})",
                    model.name,
                    traj.joint_names.join(", ")
                )))
            }
        }
    }
    check_ranges(model, traj, |i, k| traj.q[(i, cols[k])])?;
    let minv = model
        .measured_to_model_matrix()
        .ok_or_else(|| mismatch("the robot's coupling matrix is singular".into()))?;
    let mt = model.measured.coupling.transpose();
    let rows = traj.len();
    // `x · Mᵀ` of the picked columns, summed in a fixed order per sample, so that a
    // sample maps to the same bits whatever block of a log it comes in.
    let map = |x: &DMatrix<f64>, m: &DMatrix<f64>| {
        DMatrix::from_fn(rows, n, |i, j| {
            (0..n).fold(0.0, |acc, k| acc + x[(i, cols[k])] * m[(j, k)])
        })
    };
    let q = map(&traj.q, &minv);
    let dq = traj.dq.as_ref().map(|d| map(d, &minv));
    let tau = map(&traj.tau, &mt);
    Ok(JointLog {
        time: traj.time.clone(),
        q,
        dq,
        tau,
        joint_names: model.coordinates.clone(),
        coordinates: Coordinates::Model,
        source: traj.source.clone(),
    })
}

/// How far beyond a joint's physical range a log may go, as a fraction of the range's
/// width. The check is for the gross mistakes (another arm's log, degrees for radians),
/// not for joint limits: simulated and excitation logs go beyond the physical stops
/// (the 2019 PSM excitation limits let the jaw open to 3 rad, and the bundled example
/// reaches 1.79 rad against the instruments' 1.40), while another arm's log leaves
/// the range by far more than its width (the MTM's 2019 log read as a PSM's:
/// insertion −0.15 to 0.59 m against 0 to 0.24 m, wrist yaw to 5.2 rad, jaw ±10 rad).
pub const RANGE_MARGIN: f64 = 1.0;

/// Refuses a log whose measured joint `k` (positions `q_measured(i, k)` of sample `i`)
/// leaves the robot's physical range ([`dvrk_model::Measured::ranges`]) by more than
/// [`RANGE_MARGIN`], naming the joint, the range seen and the robot's.
fn check_ranges(
    model: &Model,
    traj: &JointLog,
    q_measured: impl Fn(usize, usize) -> f64,
) -> Result<(), IdentError> {
    for (k, range) in model.measured.ranges.iter().enumerate() {
        let Some([lo, hi]) = *range else { continue };
        let margin = RANGE_MARGIN * (hi - lo);
        let (seen_lo, seen_hi) = (0..traj.len())
            .map(|i| q_measured(i, k))
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
                (a.min(x), b.max(x))
            });
        if seen_lo < lo - margin || seen_hi > hi + margin {
            let unit = if model.measured.is_length(k, &model.coordinate_is_length) {
                "m"
            } else {
                "rad"
            };
            return Err(IdentError::Mismatch {
                source_name: traj.source.clone(),
                message: format!(
                    "joint {} runs from {seen_lo:.3} to {seen_hi:.3} {unit}, outside robot {}'s \
                     range {} to {} {unit}: is this a log of another arm, or in \
                     other units?",
                    model.measured.joints[k],
                    model.name,
                    dvrk_model::input::show(lo),
                    dvrk_model::input::show(hi)
                ),
            });
        }
    }
    Ok(())
}

/// Subtracts the known forces (e.g. the MTM cable) from the torques of `t` (model
/// coordinates), evaluated on the raw positions as in 2019.
pub(crate) fn subtract_known_forces(model: &Model, t: &mut JointLog) {
    if !model.has_known_forces() {
        return;
    }
    let n = model.dof();
    let mut q = vec![0.0; n];
    let mut known = vec![0.0; n];
    for k in 0..t.len() {
        for (j, qj) in q.iter_mut().enumerate() {
            *qj = t.q[(k, j)];
        }
        known.fill(0.0);
        model.add_known_forces(&q, &mut known);
        for (j, kj) in known.iter().enumerate() {
            t.tau[(k, j)] -= kj;
        }
    }
}

/// Model coordinates, known forces subtracted (on the raw positions, as in 2019), then
/// processed by the block processor ([`process_in_blocks`]: equal to
/// [`crate::signal::process`] to 1e-12 relative, and to the last bit to what
/// [`stream::fit_stream`] sees of the same log read from its file).
pub fn prepare(
    model: &Model,
    traj: &JointLog,
    processing: &Processing,
) -> Result<Prepared, IdentError> {
    let mut t = to_model_coordinates(model, traj)?;
    subtract_known_forces(model, &mut t);
    let p = process_in_blocks(std::slice::from_ref(&t), processing).map_err(|error| {
        IdentError::Signal {
            source_name: t.source.clone(),
            error,
        }
    })?;
    if p.is_empty() {
        return Err(IdentError::Mismatch {
            source_name: t.source.clone(),
            message: "no sample left after processing (log too short for the trimming?)".into(),
        });
    }
    Ok(Prepared {
        source: t.source,
        time: p.time,
        q: p.q,
        dq: p.dq,
        ddq: p.ddq,
        tau: p.tau,
    })
}

/// Predicted torques `H(q, q̇, q̈)·π` for every sample (known forces excluded, as the
/// prepared torques).
pub fn predict(model: &Model, params: &[f64], data: &Prepared) -> DMatrix<f64> {
    let n = model.dof();
    let mut ws = Workspace::new(model);
    let mut out = DMatrix::zeros(data.len(), n);
    let (mut q, mut dq, mut ddq, mut tau) =
        (vec![0.0; n], vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let s = data.samples();
    for k in 0..data.len() {
        s.read(k, &mut q, &mut dq, &mut ddq);
        model.inverse_dynamics(&mut ws, params, &q, &dq, &ddq, &mut tau);
        for j in 0..n {
            out[(k, j)] = tau[j];
        }
    }
    out
}

/// Per-joint relative error `‖τ − τ̂‖ / ‖τ‖` and RMS error over the first `window`
/// samples (all if `None`), computed like 2019 on torques without known forces, in the
/// joints of `joints` ([`JointMap`]: the model coordinates or the measured joints).
pub fn joint_metrics(
    model: &Model,
    params: &[f64],
    data: &Prepared,
    window: Option<usize>,
    joints: &JointMap,
) -> Result<JointMetrics, IdentError> {
    let mut sums = MetricSums::new(model);
    sums.add(model, params, data.samples(), window);
    sums.metrics(joints)
}

/// Running sums of the torques' and the prediction errors' second moments, fed sample
/// block by sample block: the metrics of a log without holding it. A pass over the
/// samples ([`MetricSums::add`]) sums the whole matrices `Σ e·eᵀ`, `Σ τ·τᵀ` (coordinates
/// × coordinates), from which the metrics in any joints follow
/// ([`JointMap::torque_gram`]); sums from the observation's factors
/// ([`MetricSums::from_factors`]) hold only their diagonals, the model coordinates'.
#[derive(Clone, Debug)]
pub struct MetricSums {
    /// `Σ (τ − τ̂)(τ − τ̂)ᵀ` over the samples (only the diagonal without `cross`).
    e2: DMatrix<f64>,
    /// `Σ τ·τᵀ` (only the diagonal without `cross`).
    t2: DMatrix<f64>,
    /// Whether the off-diagonal sums are there (every part came from a pass).
    cross: bool,
    samples: usize,
}

impl MetricSums {
    /// Empty sums for `model`'s coordinates.
    pub fn new(model: &Model) -> Self {
        let n = model.dof();
        MetricSums {
            e2: DMatrix::zeros(n, n),
            t2: DMatrix::zeros(n, n),
            cross: true,
            samples: 0,
        }
    }

    /// Samples summed so far.
    pub fn samples(&self) -> usize {
        self.samples
    }

    /// Adds the sums of other samples (another log): the sums of both.
    pub fn merge(&mut self, other: &MetricSums) {
        self.e2 += &other.e2;
        self.t2 += &other.t2;
        self.cross &= other.cross;
        self.samples += other.samples;
    }

    /// The sums of the samples whose per-coordinate factors (unweighted, from
    /// [`Observation::assemble_per_coordinate`]) are `parts`: `‖R_j·[π; −1]‖²` is the
    /// squared error of coordinate `j`'s rows and `‖R_j·e_τ‖²` their squared torque,
    /// exactly up to rounding, so the training metrics of a long log need no pass over
    /// it. (The prediction is `H·π`, which the inverse dynamics equals to rounding.)
    /// The factors of separate coordinates hold no cross terms: these sums give the
    /// metrics in model coordinates only.
    pub fn from_factors(parts: &[Observation], params: &[f64]) -> MetricSums {
        let mut x = params.to_vec();
        x.push(-1.0);
        let p = params.len();
        let x = nalgebra::DVector::from_column_slice(&x);
        MetricSums {
            e2: DMatrix::from_diagonal(&nalgebra::DVector::from_iterator(
                parts.len(),
                parts.iter().map(|o| (o.r() * &x).norm_squared()),
            )),
            t2: DMatrix::from_diagonal(&nalgebra::DVector::from_iterator(
                parts.len(),
                parts.iter().map(|o| o.r().column(p).norm_squared()),
            )),
            cross: false,
            samples: parts.first().map_or(0, Observation::rows),
        }
    }

    /// Adds the errors of `params` on the next samples, up to `window` samples in all
    /// (`None`: no limit).
    pub fn add(
        &mut self,
        model: &Model,
        params: &[f64],
        samples: Samples<'_>,
        window: Option<usize>,
    ) {
        let rows = window.map_or(samples.len(), |w| {
            samples.len().min(w.saturating_sub(self.samples))
        });
        let n = model.dof();
        let mut ws = Workspace::new(model);
        let (mut q, mut dq, mut ddq) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        let mut err = DMatrix::zeros(rows, n);
        let mut tau = vec![0.0; n];
        for k in 0..rows {
            samples.read(k, &mut q, &mut dq, &mut ddq);
            model.inverse_dynamics(&mut ws, params, &q, &dq, &ddq, &mut tau);
            for j in 0..n {
                err[(k, j)] = samples.tau[(k, j)] - tau[j];
            }
        }
        let measured = samples.tau.rows(0, rows);
        // The upper triangle summed sample by sample into the running sums (the
        // diagonal's bits those of a per-joint sum), then mirrored.
        for a in 0..n {
            for b in a..n {
                for k in 0..rows {
                    self.e2[(a, b)] += err[(k, a)] * err[(k, b)];
                    self.t2[(a, b)] += measured[(k, a)] * measured[(k, b)];
                }
            }
        }
        for a in 0..n {
            for b in 0..a {
                self.e2[(a, b)] = self.e2[(b, a)];
                self.t2[(a, b)] = self.t2[(b, a)];
            }
        }
        self.samples += rows;
    }

    /// RMS error per model coordinate, N·m or N.
    fn rms(&self) -> Vec<f64> {
        self.e2
            .diagonal()
            .iter()
            .map(|e2| (e2 / self.samples.max(1) as f64).sqrt())
            .collect()
    }

    /// IRLS weights: `1 / rms` per model coordinate (1 where the error is zero).
    pub fn inverse_rms(&self) -> Vec<f64> {
        self.rms()
            .into_iter()
            .map(|std| if std > 0.0 { 1.0 / std } else { 1.0 })
            .collect()
    }

    /// The relative and RMS errors per joint of `joints` of the samples summed so far
    /// (a joint without torque gets a NaN relative error). Errors for coupled joints
    /// from sums without cross terms ([`MetricSums::from_factors`]).
    pub fn metrics(&self, joints: &JointMap) -> Result<JointMetrics, IdentError> {
        let (e2, t2) = if joints.is_identity() {
            (self.e2.diagonal(), self.t2.diagonal())
        } else if self.cross {
            (
                joints.torque_gram(&self.e2).diagonal(),
                joints.torque_gram(&self.t2).diagonal(),
            )
        } else {
            return Err(IdentError::Setting {
                name: "joints".into(),
                message: format!(
                    "the errors in {}'s measured joints need a pass over the samples, and                      these sums come from the observation's factors",
                    joints.robot
                ),
            });
        };
        let samples = self.samples.max(1) as f64;
        Ok(JointMetrics {
            joints: joints.names.clone(),
            samples: self.samples,
            relative_error: e2
                .iter()
                .zip(t2.iter())
                .map(|(e2, t2)| {
                    if *t2 > 0.0 {
                        (e2 / t2).sqrt()
                    } else {
                        f64::NAN
                    }
                })
                .collect(),
            rms: e2.iter().map(|e2| (e2 / samples).sqrt()).collect(),
        })
    }
}

/// Running per-joint range of the processed torques: the WLS weights of a log read in
/// blocks.
#[derive(Clone, Debug)]
pub struct TorqueRange {
    min: Vec<f64>,
    max: Vec<f64>,
}

impl TorqueRange {
    /// An empty range over `joints` coordinates.
    pub fn new(joints: usize) -> Self {
        TorqueRange {
            min: vec![f64::INFINITY; joints],
            max: vec![f64::NEG_INFINITY; joints],
        }
    }

    /// The torques of more samples (one row per sample).
    pub fn add(&mut self, tau: &DMatrix<f64>) {
        for j in 0..tau.ncols() {
            let c = tau.column(j);
            if !c.is_empty() {
                self.min[j] = self.min[j].min(c.min());
                self.max[j] = self.max[j].max(c.max());
            }
        }
    }

    /// The range of both sample sets.
    pub fn merge(&mut self, other: &TorqueRange) {
        for (a, b) in self.min.iter_mut().zip(&other.min) {
            *a = a.min(*b);
        }
        for (a, b) in self.max.iter_mut().zip(&other.max) {
            *a = a.max(*b);
        }
    }

    /// The smallest and largest torque per joint, N·m or N (±∞ before any sample).
    pub fn bounds(&self) -> (&[f64], &[f64]) {
        (&self.min, &self.max)
    }

    /// A range from its bounds (e.g. read back from a file).
    pub fn from_bounds(min: Vec<f64>, max: Vec<f64>) -> Self {
        TorqueRange { min, max }
    }

    /// Joint weights `1 / (max − min)` (1/N·m or 1/N; 1 for a constant torque).
    pub fn weights(&self) -> Vec<f64> {
        self.min
            .iter()
            .zip(&self.max)
            .map(|(lo, hi)| {
                let range = hi - lo;
                if range > 0.0 {
                    1.0 / range
                } else {
                    1.0
                }
            })
            .collect()
    }
}

/// Joint weights `1 / (max − min)` of the prepared torques (1/N·m or 1/N).
pub fn range_weights(data: &Prepared) -> Vec<f64> {
    let mut r = TorqueRange::new(data.tau.ncols());
    r.add(&data.tau);
    r.weights()
}

pub(crate) fn not_excited(source: &str, e: crate::estimate::ols::NotExcited) -> IdentError {
    IdentError::RankDeficient {
        source_name: source.to_string(),
        message: format!(
            "the data do not determine the base parameters ({} rows); undetermined: {}. \
             Use a longer or more exciting trajectory.",
            e.rows,
            e.parameters.join(", ")
        ),
    }
}

/// A log given to a fit: its samples and, when they were read from one, the file or
/// rosbag2 folder (hashed into the result's provenance; without one, the samples are).
#[derive(Clone, Copy, Debug)]
pub struct LogData<'a> {
    /// The samples, in the log's joints (mapped to model coordinates by the fit).
    pub samples: &'a JointLog,
    /// The file or rosbag2 folder they were read from, hashed into `inputs`; `None` hashes
    /// the samples.
    pub file: Option<&'a std::path::Path>,
}

impl<'a> LogData<'a> {
    /// Samples without a file.
    pub fn new(samples: &'a JointLog) -> Self {
        LogData {
            samples,
            file: None,
        }
    }
}

/// Runs the whole fit on one log. `test` (optional) is validated with
/// `settings.test_window`. See [`fit_logs`] for several logs.
pub fn fit(
    model: &Model,
    train: &JointLog,
    test: Option<&JointLog>,
    settings: &FitSettings,
) -> Result<FitResult, IdentError> {
    fit_with_progress(model, train, test, settings, &Silent)
}

/// [`fit`] announcing its stages (processing, assembling with a sample count, solving)
/// to `progress`.
pub fn fit_with_progress(
    model: &Model,
    train: &JointLog,
    test: Option<&JointLog>,
    settings: &FitSettings,
    progress: &dyn Progress,
) -> Result<FitResult, IdentError> {
    let test: Vec<LogData> = test.into_iter().map(LogData::new).collect();
    fit_logs(model, &[LogData::new(train)], &test, settings, progress)
}

/// The fit of several logs (the entry point of the command line and of Python): each
/// log is processed on its own (filters, trimming and differentiation never cross a
/// log boundary), then the observations of the training logs are merged, the WLS
/// weights come from all their torques, and the metrics are summed over the logs. The
/// test metrics cover the first `settings.test_window` samples of each test log. The
/// result's `inputs` lists every log (training first) with its hash and its own
/// metrics; `metrics` holds those of all the training (test) logs together.
///
/// [`stream::fit_stream_logs`] reads the same logs from disk with the same result.
pub fn fit_logs(
    model: &Model,
    train: &[LogData<'_>],
    test: &[LogData<'_>],
    settings: &FitSettings,
    progress: &dyn Progress,
) -> Result<FitResult, IdentError> {
    if train.is_empty() {
        return Err(no_training_log());
    }
    let model_cow = settings.model(model)?;
    let model: &Model = &model_cow;
    let mut settings = std::borrow::Cow::Borrowed(settings);
    let delays = match settings.delay_search_s {
        Some(max_s) => {
            progress.stage("estimating the measurement delays", None);
            let found = delay::estimate_delays(model, train, &settings, max_s)?;
            progress.finish();
            settings.to_mut().processing.delay_s = found.delay_s.clone();
            Some(found)
        }
        None => None,
    };
    let settings: &FitSettings = &settings;
    progress.stage("processing", None);
    let data = prepare_logs(model, train, &settings.processing)?;
    let test_data = prepare_logs(model, test, &settings.processing)?;
    progress.finish();
    let observed = Observed::of_prepared(model, train, &data, progress)?;
    let train_pass = |params: &[f64]| {
        Ok(data
            .iter()
            .map(|d| {
                let mut sums = MetricSums::new(model);
                sums.add(model, params, d.samples(), None);
                sums
            })
            .collect())
    };
    let test_pass =
        |params: &[f64]| test_inputs(model, test, &test_data, params, settings.test_window);
    let mut result = fit_observed(
        model,
        &observed,
        settings,
        MetricPasses {
            train: Some(&train_pass),
            test: &test_pass,
        },
        progress,
    )?;
    result.delay = delays;
    result.check_finite()?;
    Ok(result)
}

/// Refuses the delay search where the samples are not in memory (a streamed fit, a fit
/// of observation states): it needs every log processed at many shifts.
pub(crate) fn no_delay_search(settings: &FitSettings, what: &str) -> Result<(), IdentError> {
    match settings.delay_search_s {
        Some(_) => Err(IdentError::Setting {
            name: "delay".into(),
            message: format!(
                "the delay search (delay auto) needs the logs in memory, which {what} does \
                 not hold: estimate the delays on a shorter log and give them fixed"
            ),
        }),
        None => Ok(()),
    }
}

/// Each log prepared ([`prepare`]) on its own.
pub(crate) fn prepare_logs(
    model: &Model,
    logs: &[LogData<'_>],
    processing: &Processing,
) -> Result<Vec<Prepared>, IdentError> {
    logs.iter()
        .map(|l| prepare(model, l.samples, processing))
        .collect()
}

/// The test logs' provenance and the metrics of `params` on them (the first `window`
/// samples of each).
pub(crate) fn test_inputs(
    model: &Model,
    logs: &[LogData<'_>],
    prepared: &[Prepared],
    params: &[f64],
    window: Option<usize>,
) -> Result<Vec<(InputInfo, MetricSums)>, IdentError> {
    logs.iter()
        .zip(prepared)
        .map(|(log, p)| {
            let mut sums = MetricSums::new(model);
            sums.add(model, params, p.samples(), window);
            Ok((log_info("test", log, &p.source)?, sums))
        })
        .collect()
}

/// The provenance of a log: its file hashed, or its samples when it has none.
fn log_info(role: &str, log: &LogData<'_>, source: &str) -> Result<InputInfo, IdentError> {
    let mut info = match log.file {
        Some(file) => InputInfo::from_file(role, file)?,
        None => InputInfo::from_samples(role, log.samples),
    };
    info.source = source.to_string();
    Ok(info)
}

/// One training log reduced: its provenance (role `train`, no metrics yet) and its
/// unweighted per-coordinate factors ([`Observation::assemble_per_coordinate`]), from
/// which its own training metrics come.
#[derive(Clone, Debug)]
pub struct ObservedLog {
    /// The log's provenance (role, path, hash) and, once fitted, its own metrics.
    pub info: InputInfo,
    /// The log's unweighted factors, one per model coordinate.
    pub parts: Vec<Observation>,
}

/// The training logs reduced to everything a fit needs of them: each log's factors,
/// all of them merged, and the running torque range of the WLS weights. What
/// [`fit_logs`] and [`stream::fit_stream_logs`] build before the estimator, and what an
/// observation state file ([`crate::state`]) holds, so that a fit of states equals the
/// fit of their logs.
#[derive(Clone, Debug)]
pub struct Observed {
    /// Each training log's own reduction, in the order given.
    pub logs: Vec<ObservedLog>,
    /// The logs' factors merged, one per coordinate.
    pub parts: Vec<Observation>,
    /// The torque range of all the logs, per coordinate: the WLS and SDP weights.
    pub range: TorqueRange,
}

impl Observed {
    /// Logs prepared in memory ([`prepare`]), reduced one after the other.
    pub(crate) fn of_prepared(
        model: &Model,
        logs: &[LogData<'_>],
        prepared: &[Prepared],
        progress: &dyn Progress,
    ) -> Result<Observed, IdentError> {
        let total: usize = prepared.iter().map(Prepared::len).sum();
        progress.stage("assembling the observation", Some(total as u64));
        let mut observed: Option<Observed> = None;
        for (log, d) in logs.iter().zip(prepared) {
            let mut range = TorqueRange::new(model.dof());
            range.add(&d.tau);
            let parts = Observation::assemble_per_coordinate(model, d.samples(), progress);
            let info = log_info("train", log, &d.source)?;
            Observed::push(&mut observed, ObservedLog { info, parts }, range);
        }
        progress.finish();
        observed.ok_or_else(no_training_log)
    }

    /// One more log after those of `observed` (the first makes it).
    pub(crate) fn push(observed: &mut Option<Observed>, log: ObservedLog, range: TorqueRange) {
        match observed {
            None => {
                *observed = Some(Observed {
                    parts: log.parts.clone(),
                    logs: vec![log],
                    range,
                })
            }
            Some(o) => {
                merge_parts(&mut o.parts, &log.parts);
                o.range.merge(&range);
                o.logs.push(log);
            }
        }
    }

    /// The logs of `other` after these: factors merged (exact up to rounding, in any
    /// order), ranges joined, logs listed in order.
    pub fn merge(&mut self, other: &Observed) {
        merge_parts(&mut self.parts, &other.parts);
        self.range.merge(&other.range);
        self.logs.extend(other.logs.iter().cloned());
    }

    /// Processed samples of all the logs.
    pub fn samples(&self) -> usize {
        self.parts.first().map_or(0, Observation::rows)
    }
}

/// The fit of reduced training logs (the shared end of [`fit_logs`],
/// [`stream::fit_stream_logs`] and the fit of observation states): the weights, the
/// estimator, the training metrics from each log's factors (no pass over the samples),
/// the test logs' metrics from `test` (given the parameters), the document. `model` is
/// the model of the settings ([`FitSettings::model`]).
pub(crate) fn fit_observed(
    model: &Model,
    observed: &Observed,
    settings: &FitSettings,
    passes: MetricPasses<'_>,
    progress: &dyn Progress,
) -> Result<FitResult, IdentError> {
    let joints = JointMap::new(model, settings.joints)?;
    let base = model.base_parameters()?;
    let n = model.dof();
    let started = std::time::Instant::now();
    let weights = match settings.method {
        Method::Ols | Method::Irls => vec![1.0; n],
        Method::Wls | Method::Sdp => observed.range.weights(),
    };
    let source = joined_sources(observed.logs.iter().map(|l| l.info.source.as_str()));
    let run = Run {
        source: &source,
        started,
        progress,
    };
    let estimated = estimate(model, &base, &observed.parts, weights, settings, &run)?;
    // Training metrics from each log's factors, no second pass over the samples; a
    // pass where coupled measured joints need the cross terms the factors lack.
    let train_sums: Vec<MetricSums> = if joints.is_identity() {
        observed
            .logs
            .iter()
            .map(|log| MetricSums::from_factors(&log.parts, &estimated.params))
            .collect()
    } else {
        match passes.train {
            Some(pass) => pass(&estimated.params)?,
            None => {
                return Err(IdentError::Setting {
                    name: "joints".into(),
                    message: format!(
                        "the training errors in {}'s measured joints need the logs' \
                         samples, which observation states do not hold: fit the states in \
                         model coordinates, then validate on the logs in measured joints",
                        model.name
                    ),
                })
            }
        }
    };
    let tested = (passes.test)(&estimated.params)?;
    let test_sums: Vec<MetricSums> = tested.iter().map(|(_, s)| s.clone()).collect();
    let mut inputs = Vec::with_capacity(observed.logs.len() + tested.len());
    for (log, sums) in observed.logs.iter().zip(&train_sums) {
        let mut info = log.info.clone();
        info.metrics = Some(sums.metrics(&joints)?);
        inputs.push(info);
    }
    for (mut info, sums) in tested {
        info.metrics = Some(sums.metrics(&joints)?);
        inputs.push(info);
    }
    let test_metrics = match test_sums.is_empty() {
        true => None,
        false => Some(summed(model, &test_sums).metrics(&joints)?),
    };
    let mut result = build_result(
        model,
        &base,
        settings,
        estimated,
        Metrics {
            train: summed(model, &train_sums).metrics(&joints)?,
            test: test_metrics,
        },
    )?;
    result.inputs = inputs;
    result.check_finite()?;
    Ok(result)
}

/// The passes over the samples a fit's metrics may need, given the parameters: the
/// test logs' sums (with their provenance) always, the training logs' sums (one per
/// log, in order) only for coupled measured joints ([`FitSettings::joints`]); `None`
/// where the samples are not at hand (observation states).
pub(crate) struct MetricPasses<'a> {
    pub train: Option<TrainPass<'a>>,
    pub test: TestPass<'a>,
}

/// The training logs' metric sums for the given parameters.
pub(crate) type TrainPass<'a> = &'a dyn Fn(&[f64]) -> Result<Vec<MetricSums>, IdentError>;
/// The test logs' provenance and metric sums for the given parameters.
pub(crate) type TestPass<'a> =
    &'a dyn Fn(&[f64]) -> Result<Vec<(InputInfo, MetricSums)>, IdentError>;

pub(crate) fn no_training_log() -> IdentError {
    IdentError::Mismatch {
        source_name: "fit".into(),
        message: "no training log".into(),
    }
}

/// The per-coordinate observations of one more log merged into those of the logs
/// before it.
pub(crate) fn merge_parts(total: &mut [Observation], log: &[Observation]) {
    for (o, l) in total.iter_mut().zip(log) {
        o.merge(l);
    }
}

/// The sums of several logs together, in order.
pub(crate) fn summed(model: &Model, logs: &[MetricSums]) -> MetricSums {
    let mut total = MetricSums::new(model);
    for s in logs {
        total.merge(s);
    }
    total
}

/// The logs' names for messages, joined by ` + `.
pub(crate) fn joined_sources<'a>(sources: impl Iterator<Item = &'a str>) -> String {
    sources.collect::<Vec<_>>().join(" + ")
}

/// What the estimator made of an observation.
pub(crate) struct Estimated {
    /// Every parameter (the SDP's, or the least-squares representative).
    pub params: Vec<f64>,
    /// The (last) weighted least-squares estimate of the base parameters.
    pub estimate: BaseEstimate,
    /// The per-coordinate weights of that estimate.
    pub weights: Vec<f64>,
    pub solver: SolverInfo,
    /// Rows of the weighted observation.
    pub rows: usize,
    /// With an entropic prior, `Σ_links d(J‖J₀)` at `params`.
    pub prior_divergence: Option<f64>,
}

/// What an [`estimate`] reports to: the data's name (in its errors), when the fit
/// started (the solver time counts from it) and where its progress goes.
#[derive(Clone, Copy)]
pub(crate) struct Run<'a> {
    pub source: &'a str,
    pub started: std::time::Instant,
    pub progress: &'a dyn Progress,
}

/// The estimator on the per-coordinate observation parts, shared by the in-memory and
/// the streamed fit so that both give the same document: weighted least squares from
/// `weights`; for IRLS, passes re-weighted by the inverse residual RMS of each
/// coordinate (from the parts, [`MetricSums::from_factors`]: no pass over the data);
/// then the semidefinite program or the least-squares representative.
/// `source` names the data when they do not determine the base parameters.
pub(crate) fn estimate(
    model: &Model,
    base: &BaseParameters,
    parts: &[Observation],
    mut weights: Vec<f64>,
    settings: &FitSettings,
    run: &Run<'_>,
) -> Result<Estimated, IdentError> {
    let Run {
        source,
        started,
        progress,
    } = *run;
    let p = model.n_params();
    let mut obs = Observation::weighted(parts, &weights);
    let mut estimate: BaseEstimate =
        base_least_squares(&obs, base).map_err(|e| not_excited(source, e))?;
    let mut solver = SolverInfo {
        name: "qr".into(),
        status: crate::estimate::SolverStatus::Solved,
        converged: true,
        seconds: 0.0,
        iterations: 1,
        tolerance: None,
    };
    if settings.method == Method::Irls {
        for it in 0..settings.irls_iterations {
            let pi = representative(base, &estimate.beta, p);
            weights = MetricSums::from_factors(parts, &pi).inverse_rms();
            obs = Observation::weighted(parts, &weights);
            estimate = base_least_squares(&obs, base).map_err(|e| not_excited(source, e))?;
            solver.iterations = it as u32 + 2;
        }
    }
    let mut prior_divergence = None;
    let params = if settings.method == Method::Sdp {
        progress.stage("solving the semidefinite program", None);
        let prior = settings.prior.as_ref();
        let options = SdpOptions {
            regularization: settings.sdp_regularization,
            prior: crate::settings::Prior::values_for(prior, model)?,
            prior_weight: prior.map_or(0.0, |p| p.weight),
            prior_metric: prior.map_or(PriorMetric::default(), |p| p.metric),
            ..SdpOptions::default()
        };
        let sol = solve_sdp(model, obs.r(), &options)?;
        progress.finish();
        solver = SolverInfo {
            name: "clarabel".into(),
            status: sol.status,
            converged: sol.converged,
            seconds: sol.seconds,
            iterations: sol.iterations,
            tolerance: Some(options.tolerance),
        };
        prior_divergence = sol.divergence;
        sol.params
    } else {
        solver.seconds = started.elapsed().as_secs_f64();
        representative(base, &estimate.beta, p)
    };
    Ok(Estimated {
        params,
        estimate,
        weights,
        solver,
        rows: obs.rows(),
        prior_divergence,
    })
}

pub(crate) fn build_result(
    model: &Model,
    base: &BaseParameters,
    settings: &FitSettings,
    estimated: Estimated,
    metrics: Metrics,
) -> Result<FitResult, IdentError> {
    let Estimated {
        params,
        estimate,
        weights,
        solver,
        rows,
        prior_divergence,
    } = estimated;
    let beta = base.project(&params);
    let names = model.param_names();
    let mut links = Vec::new();
    let mut consistency = Vec::new();
    for &j in model.link_frames() {
        let f = model.frame(j);
        let p0 = f.inertia.expect("link");
        let bary = &params[p0..p0 + 10];
        let std = inertia::standard_from_barycentric(bary);
        let min_eig = inertia::pseudo_inertia_min_eigenvalue(bary);
        links.push(LinkResult {
            frame: j,
            link: f.name.clone(),
            mass: std.mass,
            com: std.com,
            inertia_com: std.inertia_com,
        });
        consistency.push(Consistency {
            frame: j,
            link: f.name.clone(),
            min_eigenvalue: min_eig,
            consistent: min_eig > 0.0,
        });
    }
    let base_parameters = (0..base.rank())
        .map(|i| BaseParameterResult {
            name: base.names[i].clone(),
            expression: base.expressions[i].clone(),
            value: beta[i],
            std: estimate.std[i],
        })
        .collect();
    // Sign conditions hold up to rounding (see `ELEMENT_TOLERANCE`).
    let tol = -ELEMENT_TOLERANCE;
    let elements_ok = params.iter().all(|v| v.is_finite())
        && model
            .frames
            .iter()
            .flat_map(|f| &f.elements)
            .all(|e| e.consistent(&params, tol));
    let result = FitResult {
        tool: format!("dvrk-ident {}", env!("CARGO_PKG_VERSION")),
        robot: model.name.clone(),
        robot_source: model.source.clone(),
        method: settings.method.name().into(),
        settings: settings.clone(),
        inputs: Vec::new(),
        parameters: names.iter().cloned().zip(params.iter().copied()).collect(),
        parameter_order: names,
        links,
        base_parameters,
        consistency,
        physically_consistent: elements_ok
            && model.link_frames().iter().all(|&j| {
                let p0 = model.frame(j).inertia.expect("link");
                inertia::pseudo_inertia_min_eigenvalue(&params[p0..p0 + 10]) > 0.0
            }),
        solver,
        weights,
        rows,
        condition_number: estimate.condition_number,
        sigma2: estimate.sigma2,
        metrics,
        delay: None,
        prior_divergence,
    };
    result.check_finite()?;
    Ok(result)
}
