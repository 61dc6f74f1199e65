//! A joint-space log in memory: time stamps, positions, optional velocities and efforts.
//!
//! Every reader in [`crate::log`] produces a [`JointLog`] and every processing step in
//! dvrk-ident's `signal` consumes one, so this is the one place that states what a well-formed
//! log is (see [`JointLog::validate`]). Matrices have one row per sample and one column
//! per joint, the layout of the CSV files they come from.

use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};
use thiserror::Error;

/// Which joint space the columns of a [`JointLog`] are expressed in.
///
/// The dVRK publishes *measured* joints (its ROS joint names); the identification models
/// use *model* coordinates (motor-side angles for the coupled wrist joints). The two are
/// related by the model's coupling matrix `M` (`q_measured = M q_model`,
/// `tau_model = Mᵀ tau_measured`), which is applied elsewhere; the trajectory only records
/// which one it holds so that nothing maps twice or not at all.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Coordinates {
    /// The robot's measured joint space (e.g. dVRK 2.x ROS joint names).
    Measured,
    /// The model's generalized coordinates (e.g. `q1..q7` of `robots/psm.toml`).
    Model,
}

impl std::fmt::Display for Coordinates {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(crate::names::Named::name(*self))
    }
}

impl crate::names::Named for Coordinates {
    const WHAT: &'static str = "coordinates";
    const NAMES: &'static [(&'static str, Self)] = &[
        ("measured", Coordinates::Measured),
        ("model", Coordinates::Model),
    ];
    const CANONICAL: usize = 2;
}

impl std::str::FromStr for Coordinates {
    type Err = crate::names::UnknownName;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        <Self as crate::names::Named>::parse_name(s)
    }
}

/// Which signal of a trajectory a value belongs to, for error messages.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Signal {
    /// Time stamps, s.
    Time,
    /// Joint positions, rad or m.
    Position,
    /// Joint velocities, rad/s or m/s.
    Velocity,
    /// Joint efforts, N·m or N.
    Effort,
}

impl Signal {
    /// The largest magnitude a logged value of this signal may have: time 1e11 s (absolute
    /// Unix stamps, 3000 years), positions 1e6 rad or m, velocities 1e6 rad/s or m/s,
    /// efforts 1e6 N·m or N. Every arm is orders of magnitude below; above, sums of
    /// squares over a log (and products in the regressor) would lose every digit or
    /// overflow, so a value beyond is refused, not scaled.
    pub fn max_magnitude(self) -> f64 {
        match self {
            Signal::Time => 1e11,
            Signal::Position | Signal::Velocity | Signal::Effort => 1e6,
        }
    }

    /// The unit of the signal, for messages.
    pub fn unit(self) -> &'static str {
        match self {
            Signal::Time => "s",
            Signal::Position => "rad or m",
            Signal::Velocity => "rad/s or m/s",
            Signal::Effort => "N·m or N",
        }
    }
}

impl std::fmt::Display for Signal {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Signal::Time => "time",
            Signal::Position => "position",
            Signal::Velocity => "velocity",
            Signal::Effort => "effort",
        })
    }
}

/// Why a [`JointLog`] is not usable. Every variant names the trajectory's `source`
/// (usually the file it was read from) so that a message is actionable on its own.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum JointLogError {
    /// No samples or no joints.
    #[error("{source_name}: empty trajectory ({samples} samples, {joints} joints)")]
    Empty {
        /// The trajectory's `source`.
        source_name: String,
        /// Number of samples (rows).
        samples: usize,
        /// Number of joints (columns).
        joints: usize,
    },
    /// Matrices, time vector and joint names disagree in size.
    #[error(
        "{source_name}: {what} has shape {rows}x{cols}, expected {expected_rows}x{expected_cols}"
    )]
    Shape {
        /// The trajectory's `source`.
        source_name: String,
        /// Which field is wrong (`"dq"`, `"tau"`, `"time"`, `"joint_names"`).
        what: &'static str,
        /// Its number of rows.
        rows: usize,
        /// Its number of columns.
        cols: usize,
        /// The number of rows it should have (samples).
        expected_rows: usize,
        /// The number of columns it should have (joints).
        expected_cols: usize,
    },
    /// A NaN or infinite value.
    #[error("{source_name}: non-finite {signal} value {value} for joint {column:?} at sample {row} (0-based)")]
    NonFinite {
        /// The trajectory's `source`.
        source_name: String,
        /// Which signal.
        signal: Signal,
        /// Joint name (or `"time"`).
        column: String,
        /// Sample index, 0-based.
        row: usize,
        /// The offending value.
        value: f64,
    },
    /// A finite value beyond [`Signal::max_magnitude`].
    #[error("{source_name}: {signal} value {} for joint {column:?} at sample {row} (0-based) is beyond the accepted ±{:e} {}", dvrk_model::input::show(*value), signal.max_magnitude(), signal.unit())]
    OutOfRange {
        /// The trajectory's `source`.
        source_name: String,
        /// Which signal.
        signal: Signal,
        /// Joint name (or `"time"`).
        column: String,
        /// Sample index, 0-based.
        row: usize,
        /// The offending value.
        value: f64,
    },
    /// Time stamps that do not strictly increase.
    #[error("{source_name}: time is not strictly increasing at sample {row} (0-based): {previous} s then {current} s")]
    NonMonotonicTime {
        /// The trajectory's `source`.
        source_name: String,
        /// Index of the second of the two samples, 0-based.
        row: usize,
        /// Time of sample `row - 1`, s.
        previous: f64,
        /// Time of sample `row`, s.
        current: f64,
    },
    /// A time step deviates from the median step by more than the allowed tolerance
    /// (a gap or jitter): filtering and finite differences assume uniform sampling.
    /// The steps are shown rounded ([`dvrk_model::input::show_approx`]).
    #[error("{source_name}: non-uniform sampling at sample {row} (0-based): step {} s vs median {} s (relative tolerance {tolerance}); resample the log first with {}", dvrk_model::input::show_approx(*step_s), dvrk_model::input::show_approx(*median_step_s), crate::hint::Hint::ResampleHz)]
    NonUniform {
        /// The trajectory's `source`.
        source_name: String,
        /// Index of the second sample of the offending step, 0-based.
        row: usize,
        /// The offending step, s.
        step_s: f64,
        /// The median step, s.
        median_step_s: f64,
        /// Relative tolerance that was exceeded.
        tolerance: f64,
    },
    /// Fewer than two samples: no sampling rate can be estimated.
    #[error(
        "{source_name}: at least 2 samples are needed to estimate the sampling rate, got {samples}"
    )]
    TooFewSamples {
        /// The trajectory's `source`.
        source_name: String,
        /// Number of samples.
        samples: usize,
    },
}

/// A joint-space log: `time` (s) and one row per sample in `q`, `dq`, `tau`.
///
/// Units follow the joint type: rad, rad/s and N·m for revolute joints, m, m/s and N for
/// prismatic ones. `dq == None` means the log has no velocity measurement and velocities
/// are to be obtained by differentiating (filtered) positions.
#[derive(Clone, Debug, PartialEq)]
pub struct JointLog {
    /// Sample times, s, strictly increasing.
    pub time: Vec<f64>,
    /// Positions, rad or m; rows = samples, columns = joints.
    pub q: DMatrix<f64>,
    /// Measured velocities, rad/s or m/s, same shape as `q`; `None`: differentiate `q`.
    pub dq: Option<DMatrix<f64>>,
    /// Efforts (torques or forces), N·m or N, same shape as `q`.
    pub tau: DMatrix<f64>,
    /// One name per column.
    pub joint_names: Vec<String>,
    /// Which joint space the columns are in.
    pub coordinates: Coordinates,
    /// Where the data came from (file path or a description), used in error messages.
    pub source: String,
}

/// Sample times `k / rate_hz` (s) for `k = 0..n`, the implicit clock of logs without
/// time stamps (e.g. the 2019 CSV files, 200 Hz).
///
/// ```rust
/// let t = dvrk_logs::uniform_time(3, 200.0);
/// assert_eq!(t, vec![0.0, 0.005, 0.01]);
/// ```
pub fn uniform_time(n: usize, rate_hz: f64) -> Vec<f64> {
    (0..n).map(|k| k as f64 / rate_hz).collect()
}

impl JointLog {
    /// Number of samples (rows).
    pub fn len(&self) -> usize {
        self.q.nrows()
    }

    /// `true` when there are no samples.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Number of joints (columns).
    pub fn dof(&self) -> usize {
        self.q.ncols()
    }

    /// The samples at `rows` (indices in time order), joints, coordinates and source
    /// kept: a part of a log (Python's `log[a:b:step]`, the tests' training windows).
    ///
    /// ```rust
    /// use dvrk_logs::{uniform_time, Coordinates, JointLog};
    /// use nalgebra::DMatrix;
    ///
    /// let log = JointLog {
    ///     time: uniform_time(4, 200.0),
    ///     q: DMatrix::from_fn(4, 1, |k, _| k as f64),
    ///     dq: None,
    ///     tau: DMatrix::zeros(4, 1),
    ///     joint_names: vec!["q1".into()],
    ///     coordinates: Coordinates::Model,
    ///     source: "sim".into(),
    /// };
    /// let part = log.select_rows(&[1, 3]);
    /// assert_eq!((part.time, part.q[(1, 0)]), (vec![0.005, 0.015], 3.0));
    /// ```
    pub fn select_rows(&self, rows: &[usize]) -> JointLog {
        let pick =
            |m: &DMatrix<f64>| DMatrix::from_fn(rows.len(), m.ncols(), |i, j| m[(rows[i], j)]);
        JointLog {
            time: rows.iter().map(|&k| self.time[k]).collect(),
            q: pick(&self.q),
            dq: self.dq.as_ref().map(pick),
            tau: pick(&self.tau),
            joint_names: self.joint_names.clone(),
            coordinates: self.coordinates,
            source: self.source.clone(),
        }
    }

    /// Sample `k` as one row `[q, dq, tau]` (`3·dof` values; dq zeros when not
    /// measured) into `row`: the layout the block resampler and processor take.
    pub fn stacked_row(&self, k: usize, row: &mut [f64]) {
        let n = self.dof();
        for j in 0..n {
            row[j] = self.q[(k, j)];
            row[n + j] = self.dq.as_ref().map_or(0.0, |d| d[(k, j)]);
            row[2 * n + j] = self.tau[(k, j)];
        }
    }

    /// Sampling rate estimate, Hz: the inverse of the median time step, so that a few gaps
    /// or jittery stamps do not bias it. `None` with fewer than two samples or a
    /// non-positive median step.
    ///
    /// ```rust
    /// use dvrk_logs::{Coordinates, JointLog, uniform_time};
    /// use nalgebra::DMatrix;
    /// let n = 5;
    /// let log = JointLog {
    ///     time: uniform_time(n, 200.0),
    ///     q: DMatrix::zeros(n, 1),
    ///     dq: None,
    ///     tau: DMatrix::zeros(n, 1),
    ///     joint_names: vec!["q1".into()],
    ///     coordinates: Coordinates::Model,
    ///     source: "example".into(),
    /// };
    /// assert!((log.rate_hz().unwrap() - 200.0).abs() < 1e-9);
    /// ```
    pub fn rate_hz(&self) -> Option<f64> {
        let step = median_step(&self.time)?;
        (step > 0.0 && step.is_finite()).then(|| 1.0 / step)
    }

    /// Checks that the trajectory is usable: non-empty, consistent shapes, all values
    /// finite and within [`Signal::max_magnitude`], time strictly increasing. The first problem found is returned; it names the
    /// source, the signal and joint (column) and the 0-based sample (row).
    pub fn validate(&self) -> Result<(), JointLogError> {
        let (n, dof) = (self.q.nrows(), self.q.ncols());
        if n == 0 || dof == 0 {
            return Err(JointLogError::Empty {
                source_name: self.source.clone(),
                samples: n,
                joints: dof,
            });
        }
        self.validate_rows(0, None)
    }

    /// [`JointLog::validate`] of a block of a longer log, without the emptiness
    /// check: rows are numbered from `first_row`, and time must also increase from
    /// `previous_time` (the log's sample before the block).
    pub fn validate_rows(
        &self,
        first_row: usize,
        previous_time: Option<f64>,
    ) -> Result<(), JointLogError> {
        let (n, dof) = (self.q.nrows(), self.q.ncols());
        let src = || self.source.clone();
        let shape_err = |what, rows, cols| JointLogError::Shape {
            source_name: src(),
            what,
            rows,
            cols,
            expected_rows: n,
            expected_cols: dof,
        };
        if self.time.len() != n {
            return Err(shape_err("time", self.time.len(), 1));
        }
        if self.joint_names.len() != dof {
            return Err(shape_err("joint_names", 1, self.joint_names.len()));
        }
        if self.tau.shape() != (n, dof) {
            return Err(shape_err("tau", self.tau.nrows(), self.tau.ncols()));
        }
        if let Some(dq) = &self.dq {
            if dq.shape() != (n, dof) {
                return Err(shape_err("dq", dq.nrows(), dq.ncols()));
            }
        }
        // Report the earliest bad sample across signals: scan row by row.
        for row in 0..n {
            let t = self.time[row];
            if !t.is_finite() {
                return Err(JointLogError::NonFinite {
                    source_name: src(),
                    signal: Signal::Time,
                    column: "time".into(),
                    row: first_row + row,
                    value: t,
                });
            }
            if t.abs() > Signal::Time.max_magnitude() {
                return Err(JointLogError::OutOfRange {
                    source_name: src(),
                    signal: Signal::Time,
                    column: "time".into(),
                    row: first_row + row,
                    value: t,
                });
            }
            let signals = [
                (Signal::Position, Some(&self.q)),
                (Signal::Velocity, self.dq.as_ref()),
                (Signal::Effort, Some(&self.tau)),
            ];
            for (signal, m) in signals {
                let Some(m) = m else { continue };
                for col in 0..dof {
                    let v = m[(row, col)];
                    if !v.is_finite() {
                        return Err(JointLogError::NonFinite {
                            source_name: src(),
                            signal,
                            column: self.joint_names[col].clone(),
                            row: first_row + row,
                            value: v,
                        });
                    }
                    if v.abs() > signal.max_magnitude() {
                        return Err(JointLogError::OutOfRange {
                            source_name: src(),
                            signal,
                            column: self.joint_names[col].clone(),
                            row: first_row + row,
                            value: v,
                        });
                    }
                }
            }
            let previous = if row > 0 {
                Some(self.time[row - 1])
            } else {
                previous_time
            };
            if let Some(previous) = previous.filter(|&p| t <= p) {
                return Err(JointLogError::NonMonotonicTime {
                    source_name: src(),
                    row: first_row + row,
                    previous,
                    current: t,
                });
            }
        }
        Ok(())
    }

    /// Checks that every time step is within `relative_tolerance` of the median step and
    /// returns the sampling rate, Hz (inverse median step). Zero-phase filtering and
    /// central differences assume a uniform clock; a log with gaps must be resampled
    /// (dvrk-ident's `signal::resample_linear`) or rejected, and this says where the first
    /// gap is. Call [`JointLog::validate`] first.
    pub fn check_uniform(&self, relative_tolerance: f64) -> Result<f64, JointLogError> {
        let median = median_step(&self.time).ok_or_else(|| JointLogError::TooFewSamples {
            source_name: self.source.clone(),
            samples: self.time.len(),
        })?;
        for (k, w) in self.time.windows(2).enumerate() {
            let step = w[1] - w[0];
            let within = (step - median).abs() <= relative_tolerance * median;
            if !within {
                return Err(JointLogError::NonUniform {
                    source_name: self.source.clone(),
                    row: k + 1,
                    step_s: step,
                    median_step_s: median,
                    tolerance: relative_tolerance,
                });
            }
        }
        Ok(1.0 / median)
    }
}

/// Median of the consecutive differences of `time`, s; `None` with fewer than 2 samples.
pub(crate) fn median_step(time: &[f64]) -> Option<f64> {
    if time.len() < 2 {
        return None;
    }
    let mut steps: Vec<f64> = time.windows(2).map(|w| w[1] - w[0]).collect();
    steps.sort_by(|a, b| a.total_cmp(b));
    let m = steps.len();
    Some(if m % 2 == 1 {
        steps[m / 2]
    } else {
        0.5 * (steps[m / 2 - 1] + steps[m / 2])
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn log(n: usize, dof: usize) -> JointLog {
        JointLog {
            time: uniform_time(n, 100.0),
            q: DMatrix::from_fn(n, dof, |i, j| (i + j) as f64),
            dq: Some(DMatrix::zeros(n, dof)),
            tau: DMatrix::from_element(n, dof, 1.0),
            joint_names: (1..=dof).map(|j| format!("q{j}")).collect(),
            coordinates: Coordinates::Model,
            source: "unit-test".into(),
        }
    }

    #[test]
    fn valid_trajectory_passes() {
        let t = log(10, 3);
        t.validate().unwrap();
        assert_eq!(t.len(), 10);
        assert_eq!(t.dof(), 3);
        assert!(!t.is_empty());
        assert!((t.rate_hz().unwrap() - 100.0).abs() < 1e-9);
        assert!((t.check_uniform(1e-6).unwrap() - 100.0).abs() < 1e-9);
    }

    #[test]
    fn empty_is_rejected() {
        let t = log(0, 3);
        let e = t.validate().unwrap_err();
        assert!(matches!(e, JointLogError::Empty { samples: 0, .. }));
        assert!(e.to_string().contains("unit-test"));
        assert!(t.rate_hz().is_none());
    }

    #[test]
    fn nan_names_source_column_row() {
        let mut t = log(10, 3);
        t.tau[(4, 1)] = f64::NAN;
        let e = t.validate().unwrap_err();
        match &e {
            JointLogError::NonFinite {
                source_name,
                signal,
                column,
                row,
                value,
            } => {
                assert_eq!(source_name, "unit-test");
                assert_eq!(*signal, Signal::Effort);
                assert_eq!(column, "q2");
                assert_eq!(*row, 4);
                assert!(value.is_nan());
            }
            other => panic!("unexpected {other:?}"),
        }
        let msg = e.to_string();
        assert!(msg.contains("unit-test"), "{msg}");
        assert!(msg.contains("\"q2\""), "{msg}");
        assert!(msg.contains("sample 4"), "{msg}");
        assert!(msg.contains("effort"), "{msg}");
    }

    #[test]
    fn inf_in_velocity_and_time() {
        let mut t = log(10, 2);
        t.dq.as_mut().unwrap()[(7, 0)] = f64::INFINITY;
        let e = t.validate().unwrap_err();
        assert!(matches!(
            e,
            JointLogError::NonFinite { signal: Signal::Velocity, row: 7, ref column, .. } if column == "q1"
        ));
        let mut t = log(10, 2);
        t.time[3] = f64::NAN;
        assert!(matches!(
            t.validate().unwrap_err(),
            JointLogError::NonFinite {
                signal: Signal::Time,
                row: 3,
                ..
            }
        ));
    }

    #[test]
    fn non_monotonic_time() {
        let mut t = log(10, 2);
        t.time[5] = t.time[4];
        let e = t.validate().unwrap_err();
        assert!(matches!(e, JointLogError::NonMonotonicTime { row: 5, .. }));
        assert!(e.to_string().contains("sample 5"));
    }

    #[test]
    fn shape_mismatch() {
        let mut t = log(10, 2);
        t.tau = DMatrix::zeros(9, 2);
        assert!(matches!(
            t.validate().unwrap_err(),
            JointLogError::Shape { what: "tau", .. }
        ));
        let mut t = log(10, 2);
        t.joint_names.pop();
        assert!(matches!(
            t.validate().unwrap_err(),
            JointLogError::Shape {
                what: "joint_names",
                ..
            }
        ));
        let mut t = log(10, 2);
        t.time.push(1.0);
        assert!(matches!(
            t.validate().unwrap_err(),
            JointLogError::Shape { what: "time", .. }
        ));
        let mut t = log(10, 2);
        t.dq = Some(DMatrix::zeros(10, 3));
        assert!(matches!(
            t.validate().unwrap_err(),
            JointLogError::Shape { what: "dq", .. }
        ));
    }

    #[test]
    fn gap_is_detected_and_rate_is_robust() {
        let mut t = log(20, 1);
        for k in 10..20 {
            t.time[k] += 0.05; // a 5-sample gap between samples 9 and 10
        }
        t.validate().unwrap();
        // The median step ignores the single gap.
        assert!((t.rate_hz().unwrap() - 100.0).abs() < 1e-9);
        let e = t.check_uniform(0.1).unwrap_err();
        assert!(matches!(e, JointLogError::NonUniform { row: 10, .. }));
    }

    #[test]
    fn median_step_even_and_odd() {
        assert_eq!(median_step(&[0.0, 1.0, 3.0]), Some(1.5));
        assert_eq!(median_step(&[0.0, 1.0, 3.0, 4.0]), Some(1.0));
        assert_eq!(median_step(&[0.0]), None);
    }
}
