//! Finite Fourier series excitation trajectories (`docs/book/src/identification.md` §7.1).
//!
//! Per coordinate `j`, with `w_f = 2π f0` (`f0` = [`FourierTrajectory::base_frequency_hz`])
//! and `L` = [`FourierTrajectory::order`]:
//!
//! ```text
//! q_j(t)   = q_j0 + Σ_{l=1..L}  a_jl/(w_f l) sin(w_f l t) − b_jl/(w_f l) cos(w_f l t)
//! q̇_j(t)   =        Σ_{l=1..L}  a_jl cos(w_f l t) + b_jl sin(w_f l t)
//! q̈_j(t)   =        Σ_{l=1..L} −a_jl w_f l sin(w_f l t) + b_jl w_f l cos(w_f l t)
//! ```
//!
//! The motion is periodic with period `1 / f0` and its velocity has zero mean. The
//! coordinates are the model's generalized coordinates (rad or m), as in the 2019
//! package.
//!
//! # JSON
//!
//! ```json
//! {"order": 2, "base_frequency_hz": 0.18, "q0": [0.1, -0.2],
//!  "a": [[0.1, 0.0], [0.05, 0.02]], "b": [[0.0, 0.1], [0.0, -0.03]],
//!  "coordinates": ["q1", "q2"]}
//! ```
//!
//! `a` and `b` have one row per coordinate and `order` columns; `coordinates` is
//! optional (when present, [`crate::simulate`] checks it against the model's). Other keys
//! (e.g. `criterion`, `comment`) are ignored, so an optimizer can store its report beside
//! the coefficients. `base_freq_hz` is accepted for `base_frequency_hz`.
//!
//! The 2019 package's coefficient files (one flat `coefficients` array per trajectory,
//! `[q0, a1..aL, b1..bL]` per coordinate) are read by
//! [`FourierTrajectory::from_wpi_file`].

use std::collections::BTreeMap;
use std::f64::consts::PI;
use std::path::Path;

use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};
use thiserror::Error;

/// Highest base frequency of a trajectory, Hz: far above any arm's bandwidth (the dVRK's
/// trajectories use 0.1 to 0.2 Hz), low enough that the accelerations of coefficients
/// within range stay finite.
pub const MAX_BASE_FREQUENCY_HZ: f64 = 1e3;

/// Why a Fourier trajectory could not be read or is not usable. Messages name the file
/// (or source) and the offending field.
#[derive(Debug, Error)]
pub enum FourierError {
    /// The file could not be read.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },
    /// The file is not valid JSON of the expected shape.
    #[error("{path}: not a Fourier trajectory: {message}")]
    Json {
        /// The file (or the name of the text).
        path: String,
        /// The parser's message.
        message: String,
    },
    /// Inconsistent sizes or values out of range.
    #[error("{source_name}: invalid Fourier trajectory: {message}")]
    Invalid {
        /// The file or the trajectory's origin.
        source_name: String,
        /// Which field is wrong and how.
        message: String,
    },
    /// A 2019-layout file without the requested trajectory.
    #[error("{path}: no trajectory {name:?} (available: {available})")]
    UnknownName {
        /// The 2019 coefficient file.
        path: String,
        /// The trajectory asked for.
        name: String,
        /// The names the file has, comma-separated.
        available: String,
    },
}

/// A periodic excitation trajectory: a finite Fourier series per model coordinate.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FourierTrajectory {
    /// Number of harmonics `L` (≥ 1).
    pub order: usize,
    /// Base frequency `f0`, Hz; the period is `1 / f0`.
    #[serde(alias = "base_freq_hz")]
    pub base_frequency_hz: f64,
    /// Offsets `q_j0`, rad or m, one per coordinate.
    pub q0: Vec<f64>,
    /// Sine coefficients `a_jl` (velocity amplitudes, rad/s or m/s): one row per
    /// coordinate, `order` columns.
    pub a: Vec<Vec<f64>>,
    /// Cosine coefficients `b_jl` (rad/s or m/s), same shape as `a`.
    pub b: Vec<Vec<f64>>,
    /// Coordinate names (optional; empty: unnamed).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub coordinates: Vec<String>,
    /// The robot the trajectory was designed for (`excite` records its model's name;
    /// `None`: unknown, as in the 2019 files). Every robot's coordinates are named
    /// `q1..qn`, so this is what tells a PSM trajectory given to the MTM
    /// ([`FourierTrajectory::robot_mismatch`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub robot: Option<String>,
}

/// One trajectory of the 2019 package's coefficient file.
#[derive(Deserialize)]
struct WpiEntry {
    dof: usize,
    order: usize,
    base_freq_hz: f64,
    coefficients: Vec<f64>,
}

#[derive(Deserialize)]
struct WpiFile {
    trajectories: BTreeMap<String, WpiEntry>,
}

fn read_text(path: &Path) -> Result<String, FourierError> {
    dvrk_model::input::read_text(path).map_err(|source| FourierError::Io {
        path: path.display().to_string(),
        source,
    })
}

impl FourierTrajectory {
    /// Number of coordinates.
    pub fn dof(&self) -> usize {
        self.q0.len()
    }

    /// Period `1 / f0`, s.
    pub fn period_s(&self) -> f64 {
        1.0 / self.base_frequency_hz
    }

    /// Angular base frequency `w_f = 2π f0`, rad/s.
    pub fn angular_frequency(&self) -> f64 {
        2.0 * PI * self.base_frequency_hz
    }

    /// Checks sizes (`q0`, `a`, `b`, `coordinates`), that the order is at least 1, the
    /// base frequency in (0, `MAX_BASE_FREQUENCY_HZ`] and every coefficient finite and
    /// at most [`dvrk_model::input::MAX_ANGLE_RAD`] in magnitude. `source` names the input
    /// in the message.
    pub fn validate(&self, source: &str) -> Result<(), FourierError> {
        let bad = |message: String| {
            Err(FourierError::Invalid {
                source_name: source.to_string(),
                message,
            })
        };
        let n = self.dof();
        if n == 0 {
            return bad("q0 is empty: no coordinate".into());
        }
        if self.order == 0 {
            return bad("order must be at least 1".into());
        }
        if !(self.base_frequency_hz.is_finite()
            && self.base_frequency_hz > 0.0
            && self.base_frequency_hz <= MAX_BASE_FREQUENCY_HZ)
        {
            return bad(format!(
                "base_frequency_hz must be positive and at most {MAX_BASE_FREQUENCY_HZ:e} Hz, \
                 got {}",
                dvrk_model::input::show(self.base_frequency_hz)
            ));
        }
        // A coefficient is a position (rad or m) or a velocity amplitude (rad/s or m/s):
        // beyond MAX_ANGLE_RAD the positions it gives are no arm's, and their criterion
        // and feasibility overflow (q0 = 1e308 was evaluated to a condition number of inf).
        let magnitude = |name: String, v: f64| {
            dvrk_model::input::check_magnitude(v, dvrk_model::input::MAX_ANGLE_RAD, "").map_err(
                |m| FourierError::Invalid {
                    source_name: source.to_string(),
                    message: format!("{name} {m}"),
                },
            )
        };
        for (name, m) in [("a", &self.a), ("b", &self.b)] {
            if m.len() != n {
                return bad(format!(
                    "{name} has {} rows but q0 has {n} coordinates",
                    m.len()
                ));
            }
            for (j, row) in m.iter().enumerate() {
                if row.len() != self.order {
                    return bad(format!(
                        "{name}[{j}] has {} coefficients, expected order = {}",
                        row.len(),
                        self.order
                    ));
                }
                for (l, &v) in row.iter().enumerate() {
                    magnitude(format!("{name}[{j}][{l}]"), v)?;
                }
            }
        }
        for (j, &v) in self.q0.iter().enumerate() {
            magnitude(format!("q0[{j}]"), v)?;
        }
        if !self.coordinates.is_empty() && self.coordinates.len() != n {
            return bad(format!(
                "{} coordinate names for {n} coordinates",
                self.coordinates.len()
            ));
        }
        Ok(())
    }

    /// A warning when the trajectory was designed for another robot than `model` (its
    /// limits, its coordinates' meaning: the PSM's q3 is an insertion in m, the MTM's an
    /// angle), naming both; `None` when it is `model`'s or its robot is unknown.
    ///
    /// ```
    /// use dvrk_ident::excite::FourierTrajectory;
    /// let mut f = FourierTrajectory::from_json_str(
    ///     r#"{"order": 1, "base_frequency_hz": 0.1, "q0": [0.0], "a": [[0.1]], "b": [[0.0]],
    ///        "robot": "psm"}"#,
    ///     "t.json",
    /// )
    /// .unwrap();
    /// let model = dvrk_model::Model::builtin("mtm").unwrap();
    /// assert_eq!(
    ///     f.robot_mismatch(&model, "t.json").unwrap(),
    ///     "t.json was designed for robot psm, not mtm"
    /// );
    /// f.robot = None;
    /// assert!(f.robot_mismatch(&model, "t.json").is_none());
    /// ```
    pub fn robot_mismatch(&self, model: &dvrk_model::Model, source: &str) -> Option<String> {
        match &self.robot {
            Some(robot) if *robot != model.name => Some(format!(
                "{source} was designed for robot {robot}, not {}",
                model.name
            )),
            _ => None,
        }
    }

    /// Position (rad or m), velocity and acceleration of every coordinate at time `t`
    /// (s), written into the first `dof()` entries of `q`, `dq`, `ddq`. Allocates
    /// nothing.
    ///
    /// # Panics
    /// If a slice is shorter than [`FourierTrajectory::dof`] or the coefficient rows are
    /// shorter than `order` (see [`FourierTrajectory::validate`]).
    ///
    /// ```rust
    /// use dvrk_ident::excite::FourierTrajectory;
    /// let f = FourierTrajectory {
    ///     order: 1, base_frequency_hz: 0.5, q0: vec![0.2],
    ///     a: vec![vec![1.0]], b: vec![vec![0.0]], coordinates: vec![], robot: None,
    /// };
    /// let (mut q, mut dq, mut ddq) = ([0.0], [0.0], [0.0]);
    /// f.eval(0.0, &mut q, &mut dq, &mut ddq);
    /// assert_eq!((q[0], dq[0], ddq[0]), (0.2, 1.0, 0.0));
    /// ```
    pub fn eval(&self, t: f64, q: &mut [f64], dq: &mut [f64], ddq: &mut [f64]) {
        let n = self.dof();
        assert!(
            q.len() >= n && dq.len() >= n && ddq.len() >= n,
            "FourierTrajectory::eval: output slices shorter than {n}"
        );
        let wf = self.angular_frequency();
        for j in 0..n {
            let (mut p, mut v, mut acc) = (self.q0[j], 0.0, 0.0);
            for l in 0..self.order {
                let w = wf * (l + 1) as f64;
                let (s, c) = (w * t).sin_cos();
                let (a, b) = (self.a[j][l], self.b[j][l]);
                p += (a * s - b * c) / w;
                v += a * c + b * s;
                acc += w * (b * c - a * s);
            }
            q[j] = p;
            dq[j] = v;
            ddq[j] = acc;
        }
    }

    /// Positions, velocities and accelerations at the given times (s): three matrices
    /// with one row per time and one column per coordinate.
    pub fn sample(&self, time: &[f64]) -> (DMatrix<f64>, DMatrix<f64>, DMatrix<f64>) {
        let n = self.dof();
        let (mut q, mut dq, mut ddq) = (
            DMatrix::zeros(time.len(), n),
            DMatrix::zeros(time.len(), n),
            DMatrix::zeros(time.len(), n),
        );
        let (mut qk, mut dqk, mut ddqk) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        for (k, &t) in time.iter().enumerate() {
            self.eval(t, &mut qk, &mut dqk, &mut ddqk);
            for j in 0..n {
                q[(k, j)] = qk[j];
                dq[(k, j)] = dqk[j];
                ddq[(k, j)] = ddqk[j];
            }
        }
        (q, dq, ddq)
    }

    /// Parses the JSON layout of the module docs and validates it; `source` names the
    /// input in messages.
    pub fn from_json_str(text: &str, source: &str) -> Result<FourierTrajectory, FourierError> {
        let f: FourierTrajectory = serde_json::from_str(text).map_err(|e| FourierError::Json {
            path: source.to_string(),
            message: e.to_string(),
        })?;
        f.validate(source)?;
        Ok(f)
    }

    /// Reads and validates a JSON trajectory file (layout in the module docs).
    pub fn from_json_file(path: impl AsRef<Path>) -> Result<FourierTrajectory, FourierError> {
        let path = path.as_ref();
        Self::from_json_str(&read_text(path)?, &path.display().to_string())
    }

    /// The JSON document (pretty-printed; values round-trip exactly).
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).expect("serializable")
    }

    /// Names of the trajectories of a 2019-layout coefficient file (sorted).
    pub fn wpi_names(path: impl AsRef<Path>) -> Result<Vec<String>, FourierError> {
        let path = path.as_ref();
        Ok(parse_wpi(path)?.trajectories.into_keys().collect())
    }

    /// Reads trajectory `name` (e.g. `psm_one`) of the 2019 package's coefficient file
    /// (`{"trajectories": {name: {"dof", "order", "base_freq_hz", "coefficients"}}}`,
    /// where `coefficients[(2L+1)·d ..][..2L+1]` are `[q0, a1..aL, b1..bL]` of model
    /// coordinate `d`). The coordinates are named `q1..qn`.
    pub fn from_wpi_file(
        path: impl AsRef<Path>,
        name: &str,
    ) -> Result<FourierTrajectory, FourierError> {
        let path = path.as_ref();
        let source = format!("{} ({name})", path.display());
        let mut file = parse_wpi(path)?;
        let Some(e) = file.trajectories.remove(name) else {
            return Err(FourierError::UnknownName {
                path: path.display().to_string(),
                name: name.to_string(),
                available: file
                    .trajectories
                    .keys()
                    .cloned()
                    .collect::<Vec<_>>()
                    .join(", "),
            });
        };
        let stride = 2 * e.order + 1;
        if e.order == 0 || e.dof == 0 || e.coefficients.len() != e.dof * stride {
            return Err(FourierError::Invalid {
                source_name: source,
                message: format!(
                    "{} coefficients cannot hold dof {} x (2 * order {} + 1)",
                    e.coefficients.len(),
                    e.dof,
                    e.order
                ),
            });
        }
        let block = |d: usize| &e.coefficients[d * stride..(d + 1) * stride];
        let f = FourierTrajectory {
            order: e.order,
            base_frequency_hz: e.base_freq_hz,
            q0: (0..e.dof).map(|d| block(d)[0]).collect(),
            a: (0..e.dof).map(|d| block(d)[1..=e.order].to_vec()).collect(),
            b: (0..e.dof)
                .map(|d| block(d)[e.order + 1..].to_vec())
                .collect(),
            coordinates: (1..=e.dof).map(|j| format!("q{j}")).collect(),
            robot: None,
        };
        f.validate(&source)?;
        Ok(f)
    }
}

fn parse_wpi(path: &Path) -> Result<WpiFile, FourierError> {
    serde_json::from_str(&read_text(path)?).map_err(|e| FourierError::Json {
        path: path.display().to_string(),
        message: format!("not a 2019 coefficient file: {e}"),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn example() -> FourierTrajectory {
        FourierTrajectory {
            order: 3,
            base_frequency_hz: 0.2,
            q0: vec![0.1, -0.3],
            a: vec![vec![0.3, -0.1, 0.05], vec![0.0, 0.2, -0.07]],
            b: vec![vec![0.1, 0.02, -0.04], vec![0.15, 0.0, 0.03]],
            coordinates: vec!["q1".into(), "q2".into()],
            robot: None,
        }
    }

    #[test]
    fn derivatives_match_finite_differences() {
        let f = example();
        let h = 1e-5;
        let (mut q, mut dq, mut ddq) = ([0.0; 2], [0.0; 2], [0.0; 2]);
        let (mut qp, mut dqp, mut ddqp) = ([0.0; 2], [0.0; 2], [0.0; 2]);
        let (mut qm, mut dqm, mut ddqm) = ([0.0; 2], [0.0; 2], [0.0; 2]);
        for k in 0..50 {
            let t = 0.173 * k as f64;
            f.eval(t, &mut q, &mut dq, &mut ddq);
            f.eval(t + h, &mut qp, &mut dqp, &mut ddqp);
            f.eval(t - h, &mut qm, &mut dqm, &mut ddqm);
            for j in 0..2 {
                let v = (qp[j] - qm[j]) / (2.0 * h);
                let a = (dqp[j] - dqm[j]) / (2.0 * h);
                assert!((v - dq[j]).abs() < 1e-8, "t {t} j {j}: {v} vs {}", dq[j]);
                assert!((a - ddq[j]).abs() < 1e-8, "t {t} j {j}: {a} vs {}", ddq[j]);
            }
        }
    }

    #[test]
    fn periodic_with_zero_mean_velocity() {
        let f = example();
        assert!((f.period_s() - 5.0).abs() < 1e-15);
        let (mut a, mut b) = (
            ([0.0; 2], [0.0; 2], [0.0; 2]),
            ([0.0; 2], [0.0; 2], [0.0; 2]),
        );
        for k in 0..20 {
            let t = 0.37 * k as f64;
            f.eval(t, &mut a.0, &mut a.1, &mut a.2);
            f.eval(t + 2.0 * f.period_s(), &mut b.0, &mut b.1, &mut b.2);
            for j in 0..2 {
                assert!((a.0[j] - b.0[j]).abs() < 1e-12);
                assert!((a.1[j] - b.1[j]).abs() < 1e-12);
                assert!((a.2[j] - b.2[j]).abs() < 1e-11);
            }
        }
        // Mean velocity over one period is zero; the mean position is q0.
        let n = 1000;
        let time: Vec<f64> = (0..n).map(|k| k as f64 * f.period_s() / n as f64).collect();
        let (q, dq, _) = f.sample(&time);
        for j in 0..2 {
            assert!(dq.column(j).mean().abs() < 1e-12);
            assert!((q.column(j).mean() - f.q0[j]).abs() < 1e-12);
        }
    }

    #[test]
    fn json_round_trip_ignores_extra_keys() {
        let f = example();
        let back = FourierTrajectory::from_json_str(&f.to_json(), "mem").unwrap();
        assert_eq!(back, f);
        let text = r#"{"order": 1, "base_freq_hz": 0.5, "q0": [0.0], "a": [[1.0]],
                       "b": [[2.0]], "criterion": 12.5, "comment": "x"}"#;
        let g = FourierTrajectory::from_json_str(text, "mem").unwrap();
        assert_eq!(g.base_frequency_hz, 0.5);
        assert!(g.coordinates.is_empty());
    }

    #[test]
    fn invalid_shapes_are_named() {
        let mut f = example();
        f.b[1].pop();
        let e = f.validate("traj.json").unwrap_err().to_string();
        assert!(e.contains("traj.json") && e.contains("b[1]"), "{e}");
        let mut f = example();
        f.base_frequency_hz = 0.0;
        assert!(f
            .validate("x")
            .unwrap_err()
            .to_string()
            .contains("base_frequency_hz"));
        let mut f = example();
        f.a[0][2] = f64::NAN;
        assert!(f.validate("x").unwrap_err().to_string().contains("a[0][2]"));
        let e = FourierTrajectory::from_json_str(r#"{"order": 1}"#, "t.json").unwrap_err();
        assert!(e.to_string().contains("t.json"), "{e}");
    }
}
