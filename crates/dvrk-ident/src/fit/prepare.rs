//! The first stage of a fit: a log in the robot's measured joints mapped to model
//! coordinates (its joint ranges checked), the known forces subtracted and the samples
//! processed into [`Prepared`], what the observation and the metrics read.

use dvrk_model::Model;
use nalgebra::DMatrix;

use crate::error::IdentError;
use crate::observation::Samples;
use crate::signal::stream::process_in_blocks;
use crate::signal::Processing;
use crate::{Coordinates, JointLog};

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
    pub(crate) fn samples(&self) -> Samples<'_> {
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
pub fn to_model_coordinates(model: &Model, log: &JointLog) -> Result<JointLog, IdentError> {
    let n = model.dof();
    let mismatch = |message: String| IdentError::Mismatch {
        source_name: log.source.clone(),
        message,
    };
    check_velocity_clock(log)?;
    if log.coordinates == Coordinates::Model {
        // A headered CSV tells model coordinates by their names `q1..qn`; a robot whose
        // measured joints carry those very names through a non-identity coupling would
        // make such a file ambiguous.
        if model.measured.joints == log.joint_names
            && model.measured.coupling != DMatrix::identity(n, n)
        {
            return Err(mismatch(format!(
                "the log's joints `{}` are both robot {}'s model coordinates and its measured \
                 joints, which differ by a coupling: rename the measured joints",
                log.joint_names.join(", "),
                model.name
            )));
        }
        if log.dof() != n {
            return Err(mismatch(format!(
                "the log has {} joints in model coordinates but robot {} has {n} coordinates",
                log.dof(),
                model.name
            )));
        }
        let coupling = &model.measured.coupling;
        check_ranges(model, log, |i, k| {
            (0..n).fold(0.0, |acc, j| acc + coupling[(k, j)] * log.q[(i, j)])
        })?;
        return Ok(log.clone());
    }
    let mut cols = Vec::with_capacity(n);
    for name in &model.measured.joints {
        match log.joint_names.iter().position(|j| j == name) {
            Some(c) => cols.push(c),
            None => {
                return Err(mismatch(format!(
                    "joint `{name}` of robot {} is missing (the log has: {})",
                    model.name,
                    log.joint_names.join(", ")
                )))
            }
        }
    }
    check_ranges(model, log, |i, k| log.q[(i, cols[k])])?;
    let minv = model
        .measured_to_model_matrix()
        .ok_or_else(|| mismatch("the robot's coupling matrix is singular".into()))?;
    let mt = model.measured.coupling.transpose();
    let rows = log.len();
    // `x · Mᵀ` of the picked columns, summed in a fixed order per sample, so that a
    // sample maps to the same bits whatever block of a log it comes in.
    let map = |x: &DMatrix<f64>, m: &DMatrix<f64>| {
        DMatrix::from_fn(rows, n, |i, j| {
            (0..n).fold(0.0, |acc, k| acc + x[(i, cols[k])] * m[(j, k)])
        })
    };
    let q = map(&log.q, &minv);
    let dq = log.dq.as_ref().map(|d| map(d, &minv));
    let tau = map(&log.tau, &mt);
    Ok(JointLog {
        time: log.time.clone(),
        q,
        dq,
        tau,
        joint_names: model.coordinates.clone(),
        coordinates: Coordinates::Model,
        source: log.source.clone(),
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
    log: &JointLog,
    q_measured: impl Fn(usize, usize) -> f64,
) -> Result<(), IdentError> {
    for (k, range) in model.measured.ranges.iter().enumerate() {
        let Some([lo, hi]) = *range else { continue };
        let margin = RANGE_MARGIN * (hi - lo);
        let (seen_lo, seen_hi) = (0..log.len())
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
                source_name: log.source.clone(),
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

/// How far a joint's measured velocities may disagree with its positions' rate of
/// change on the log's clock (as a ratio either way) before the log is refused. A
/// controller's velocity estimate lags and smooths, but keeps the scale (the 2019 PSM
/// logs agree within 1 %); a wrong clock or other units give a factor: the half-speed
/// PSM log of `psm_speed/` read at 200 Hz, its real 100 Hz, gives 2.0.
pub const VELOCITY_CLOCK_RATIO: f64 = 1.5;

/// Correlation below which a joint's measured velocities are too unlike its positions'
/// rate of change (noise, a joint at rest) to say anything about the clock.
const VELOCITY_CLOCK_MIN_CORRELATION: f64 = 0.9;

/// Refuses a log whose measured velocities contradict its clock: for each joint, the
/// least-squares slope of the positions' central differences on the log's time stamps
/// against the measured velocities must be within [`VELOCITY_CLOCK_RATIO`] of 1. A
/// wrong `--rate` scales every derivative (the accelerations by its square) and the
/// fit then explains inertial torques with the wrong factor; nothing downstream would
/// see it. Joints whose velocities correlate less than 0.9 with the differences are
/// not judged.
fn check_velocity_clock(log: &JointLog) -> Result<(), IdentError> {
    let Some(dq) = &log.dq else { return Ok(()) };
    let n = log.len();
    for j in 0..log.dof() {
        let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
        for i in 1..n.saturating_sub(1) {
            let dt = log.time[i + 1] - log.time[i - 1];
            // Time stamps are checked increasing and finite later; skip what is not.
            if dt.is_nan() || dt <= 0.0 {
                continue;
            }
            let x = dq[(i, j)];
            let y = (log.q[(i + 1, j)] - log.q[(i - 1, j)]) / dt;
            sxy += x * y;
            sxx += x * x;
            syy += y * y;
        }
        // `!(… >= …)` also skips a NaN (sums overflowed by huge values, which the
        // log's own magnitude check refuses).
        let correlation = sxy / (sxx * syy).sqrt();
        if !(sxx > 0.0 && syy > 0.0 && correlation >= VELOCITY_CLOCK_MIN_CORRELATION) {
            continue;
        }
        let slope = sxy / sxx;
        if !(1.0 / VELOCITY_CLOCK_RATIO..=VELOCITY_CLOCK_RATIO).contains(&slope) {
            return Err(IdentError::WrongClock {
                source_name: log.source.clone(),
                joint: log.joint_names[j].clone(),
                ratio: 1.0 / slope,
                clock_hz: log.rate_hz().map(|rate| [rate, rate / slope]),
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
/// `super::stream` sees of the same log read from its file).
pub fn prepare(
    model: &Model,
    log: &JointLog,
    processing: &Processing,
) -> Result<Prepared, IdentError> {
    let mut t = to_model_coordinates(model, log)?;
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
    /// Samples without a file (the observation states' tests).
    #[cfg(all(test, feature = "recordings"))]
    pub fn new(samples: &'a JointLog) -> Self {
        LogData {
            samples,
            file: None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use dvrk_logs::uniform_time;

    /// A two-joint log of `n` samples stamped at `stamp_hz` whose positions move as
    /// `sin(w·t)` on the true clock `true_hz` and whose velocities are `velocity(k, j)`.
    fn log(stamp_hz: f64, true_hz: f64, velocity: impl Fn(usize, usize) -> f64) -> JointLog {
        let n = 400;
        let w = [1.3, 2.1];
        JointLog {
            time: uniform_time(n, stamp_hz),
            q: DMatrix::from_fn(n, 2, |k, j| (w[j] * k as f64 / true_hz).sin()),
            dq: Some(DMatrix::from_fn(n, 2, velocity)),
            tau: DMatrix::zeros(n, 2),
            joint_names: vec!["a".into(), "b".into()],
            coordinates: Coordinates::Model,
            source: "test.csv".into(),
        }
    }

    fn cosine(true_hz: f64) -> impl Fn(usize, usize) -> f64 {
        let w = [1.3, 2.1];
        move |k, j| w[j] * (w[j] * k as f64 / true_hz).cos()
    }

    #[test]
    fn velocities_that_match_the_clock_pass() {
        check_velocity_clock(&log(200.0, 200.0, cosine(200.0))).unwrap();
        // Without measured velocities there is nothing to compare.
        let mut t = log(200.0, 200.0, cosine(200.0));
        t.dq = None;
        check_velocity_clock(&t).unwrap();
    }

    #[test]
    fn a_clock_twice_too_fast_is_refused_with_the_rate_the_velocities_imply() {
        // Recorded at 100 Hz, read as 200 Hz (the half-speed PSM log of issue 28).
        let e = check_velocity_clock(&log(200.0, 100.0, cosine(100.0))).unwrap_err();
        let m = e.to_string();
        assert!(
            m.starts_with("test.csv: the measured velocities of joint a are 0.5 times"),
            "{m}"
        );
        assert!(m.contains("at 200 Hz; they match a clock of 100 Hz"), "{m}");
        // And the other way: 200 Hz read as 100 Hz.
        let m = check_velocity_clock(&log(100.0, 200.0, cosine(200.0)))
            .unwrap_err()
            .to_string();
        assert!(
            m.contains("are 2 times") && m.contains("clock of 200 Hz"),
            "{m}"
        );
    }

    #[test]
    fn velocities_in_other_units_are_refused() {
        // Joint b's velocities in degrees per second against positions in radians.
        let c = cosine(200.0);
        let deg = move |k, j| {
            c(k, j)
                * if j == 1 {
                    180.0 / std::f64::consts::PI
                } else {
                    1.0
                }
        };
        let m = check_velocity_clock(&log(200.0, 200.0, deg))
            .unwrap_err()
            .to_string();
        assert!(m.contains("joint b are 57.3 times"), "{m}");
    }

    #[test]
    fn velocities_unlike_the_positions_are_not_judged() {
        // Noise (a pseudo-random sequence) and a joint reported at rest say nothing
        // about the clock.
        let noise = |k: usize, j: usize| (((k * 7919 + j * 104_729) % 1000) as f64 / 500.0) - 1.0;
        check_velocity_clock(&log(200.0, 100.0, noise)).unwrap();
        check_velocity_clock(&log(200.0, 100.0, |_, _| 0.0)).unwrap();
    }
}
