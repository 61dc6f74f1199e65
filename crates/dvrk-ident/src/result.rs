//! The result document of a fit (JSON, schema in docs/book/src/fit.md); what other tools
//! read of it is written by [`crate::export`].
//!
//! Scripts rely on at least: `method`, `parameters` {name: value}, `base_parameters`,
//! `consistency` [{`link`, `min_eigenvalue`}], `solver` {`status`, `converged`,
//! `seconds`}, `metrics` {`train`, `test`: {`relative_error`, `rms`}}.

use std::path::Path;

use indexmap::IndexMap;
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

use crate::error::{IdentError, NotFiniteCause};
use crate::settings::FitSettings;

mod parameters;
mod payload;
mod selection;
pub use parameters::{
    BaseParameterResult, Consistency, LinkDetermined, LinkResult, ParameterStatus,
};
pub use payload::{PayloadIdentification, PayloadStd};
pub use selection::{CandidateScore, Folds, Selection};

use crate::estimate::SolverInfo;

/// Per-joint errors on one trajectory (model coordinates).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct JointMetrics {
    /// Model coordinate names, one per entry of `relative_error` and `rms`.
    pub joints: Vec<String>,
    /// Samples the errors cover (after trimming and decimation; the test window if any).
    pub samples: usize,
    /// `‖τ − τ̂‖ / ‖τ‖` per joint
    pub relative_error: Vec<f64>,
    /// RMS of `τ − τ̂` per joint, N·m or N
    pub rms: Vec<f64>,
}

impl JointMetrics {
    /// Refuses metrics that are not numbers (no sample in the window, a joint whose
    /// torques are all zero) rather than printing NaN: the message names `log`, and the
    /// joint and why.
    pub fn check_finite(&self, log: &str) -> Result<(), MetricsError> {
        if self.samples == 0 {
            return Err(MetricsError::NoSample { log: log.into() });
        }
        for (j, name) in self.joints.iter().enumerate() {
            if !self.relative_error[j].is_finite() || !self.rms[j].is_finite() {
                return Err(MetricsError::NotFinite {
                    log: log.into(),
                    joint: name.clone(),
                    relative_error: self.relative_error[j],
                    rms: self.rms[j],
                });
            }
        }
        Ok(())
    }
}

/// Metrics that are not numbers ([`JointMetrics::check_finite`]).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum MetricsError {
    /// No processed sample in the window.
    #[error("{log}: no processed sample is left for the metrics")]
    NoSample {
        /// The log (or what stands for it).
        log: String,
    },
    /// A joint whose errors are not finite.
    #[error(
        "{log}: joint {joint}: relative error {relative_error} and RMS {rms} are not finite (the \
         torques of the joint are all zero, so an error relative to them is undefined)"
    )]
    NotFinite {
        /// The log (or what stands for it).
        log: String,
        /// The joint's name.
        joint: String,
        /// Its relative error.
        relative_error: f64,
        /// Its RMS error, N·m or N.
        rms: f64,
    },
}

/// Train and test errors of a fit, per joint (the result's `metrics`).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Metrics {
    /// Errors on the training logs, all of them together.
    pub train: JointMetrics,
    /// Errors on the test logs (`--test`, within the test window); `None` without them.
    pub test: Option<JointMetrics>,
}

/// Provenance of an input: a log, or the result file a prior was read from.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct InputInfo {
    /// `train`, `test` or `prior`
    pub role: String,
    /// The file or rosbag2 folder; empty for samples that were not read from one.
    pub path: String,
    /// SHA-256 of the file (of a rosbag2 folder: of its metadata.yaml and its files in
    /// order, concatenated), or of the samples (time, q, dq, tau as little-endian f64,
    /// row by row) when there is no file.
    pub sha256: String,
    /// Bytes hashed.
    pub bytes: u64,
    /// Where the samples came from (e.g. the file and the topics read).
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub source: String,
    /// This log's own metrics.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub metrics: Option<JointMetrics>,
    /// A training log's own torque offset over the model's, per model coordinate (N·m
    /// or N), with `log_offsets` (`FitSettings::log_offsets`): what this log's torques
    /// add to the model's prediction, the first log's zero (its offsets are the model's
    /// `Fo`). `None` without the option.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub offset: Option<Vec<f64>>,
}

impl FitResult {
    /// With per-log offsets (`settings.log_offsets`): which offsets a use of the result
    /// on a log applies, the model's `Fo`, those of the first training log (the other
    /// training logs' own, in `inputs[].offset`, belong to those recordings). `None`
    /// without them.
    pub fn offset_note(&self) -> Option<String> {
        if !self.settings.log_offsets {
            return None;
        }
        let first = self.inputs.iter().find(|i| i.role == "train")?;
        let name = if first.path.is_empty() {
            &first.source
        } else {
            &first.path
        };
        Some(format!(
            "torque offsets: the model's Fo, fitted on the first training log ({name}); the \
             other training logs' own offsets (the result's inputs[].offset) are not applied"
        ))
    }
}

/// A result's `robot_source` (`builtin:psm`, or a path) as [`dvrk_model::Model::load`]
/// takes it.
pub(crate) fn loadable_robot(robot_source: &str) -> &str {
    robot_source
        .strip_prefix("builtin:")
        .unwrap_or(robot_source)
}

impl InputInfo {
    /// Hashes a log file, or the files of a rosbag2 folder, reading them in pieces.
    pub fn from_file(role: &str, path: &Path) -> Result<InputInfo, IdentError> {
        let files = crate::log::files_of(path)?;
        let mut hash = Sha256::new();
        let mut bytes = 0;
        for f in &files {
            let io = |source: std::io::Error| IdentError::Io {
                file: f.display().to_string(),
                source,
            };
            let mut file = std::fs::File::open(f).map_err(io)?;
            bytes += std::io::copy(&mut file, &mut hash).map_err(io)?;
        }
        Ok(InputInfo {
            role: role.into(),
            path: path.display().to_string(),
            sha256: format!("{:x}", hash.finalize()),
            bytes,
            source: String::new(),
            metrics: None,
            offset: None,
        })
    }

    /// Hashes samples that were not read from a file (see [`InputInfo::sha256`]).
    pub fn from_samples(role: &str, log: &crate::JointLog) -> InputInfo {
        let mut hash = Sha256::new();
        let mut bytes = 0u64;
        let mut put = |v: f64| {
            hash.update(v.to_le_bytes());
            bytes += 8;
        };
        for k in 0..log.len() {
            put(log.time[k]);
            for m in [Some(&log.q), log.dq.as_ref(), Some(&log.tau)]
                .into_iter()
                .flatten()
            {
                for v in m.row(k).iter() {
                    put(*v);
                }
            }
        }
        InputInfo {
            role: role.into(),
            path: String::new(),
            sha256: format!("{:x}", hash.finalize()),
            bytes,
            source: String::new(),
            metrics: None,
            offset: None,
        }
    }
}

/// The result of a fit.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct FitResult {
    /// The program and version that wrote the document, `dvrk-ident X.Y.Z`.
    pub tool: String,
    /// The robot's name from its description, e.g. `psm`.
    pub robot: String,
    /// Where the robot came from: `builtin:<name>` or the description file's path (see
    /// [`FitResult::robot`]).
    pub robot_source: String,
    /// The estimator: `ols`, `wls`, `irls` or `sdp`.
    pub method: String,
    /// Every setting of the fit (processing, bounds, prior...): what `fit --states` and a re-run
    /// repeat, and what `validate`, `report` and `export` apply.
    pub settings: FitSettings,
    /// Provenance and own metrics of every log read (train, test) and of a prior's file.
    pub inputs: Vec<InputInfo>,
    /// Every parameter by name (barycentric: inertia about the frame origin, first
    /// moment, mass; friction; motor inertia; spring). For least squares, a
    /// representative: base parameters on their kept columns, zero elsewhere.
    pub parameters: IndexMap<String, f64>,
    /// The parameter names in the model's order (the order of `parameters`, for readers
    /// that do not keep JSON key order).
    pub parameter_order: Vec<String>,
    /// What the data determined of each parameter ([`ParameterStatus`]); empty in results
    /// written before it (then nothing is known, and nothing is warned about).
    #[serde(default, skip_serializing_if = "IndexMap::is_empty")]
    pub parameter_status: IndexMap<String, ParameterStatus>,
    /// Standard parameters per link.
    pub links: Vec<LinkResult>,
    /// The identifiable combinations with their values and standard deviations.
    pub base_parameters: Vec<BaseParameterResult>,
    /// Smallest pseudo-inertia eigenvalue of each link.
    pub consistency: Vec<Consistency>,
    /// Every link pseudo-inertia positive definite, friction/motor inertia ≥ 0 and, with
    /// a Stribeck term, `Fc + Fs ≥ 0`.
    pub physically_consistent: bool,
    /// How the solver ended; `solver.converged` false means the numbers are NOT a result.
    pub solver: SolverInfo,
    /// Row weights per coordinate used by the estimator (1/N·m or 1/N).
    pub weights: Vec<f64>,
    /// Observation rows (samples × coordinates).
    pub rows: usize,
    /// Condition number of the weighted base regressor.
    pub condition_number: f64,
    /// Residual variance of the weighted least-squares fit.
    pub sigma2: f64,
    /// Per-joint errors of the fitted model on the training and test logs.
    pub metrics: Metrics,
    /// The measurement delays estimated by `delay auto` (applied through
    /// `settings.processing.delay_s`, which holds them for validate, report, export).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub delay: Option<DelayEstimate>,
    /// The friction model chosen by held-out error (`select`, see
    /// `crate::fit::select`): the folds, every candidate's held-out errors and the
    /// one chosen, whose terms `settings` holds.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub selection: Option<Selection>,
    /// With an entropic prior (`settings.prior`): the sum over links of the log-det
    /// divergence of the fitted pseudo-inertia from the prior's (no units; 0 at the
    /// prior).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub prior_divergence: Option<f64>,
    /// A rigid payload the arm carries, identified on top of this fit by `dvrk-ident
    /// payload` ([`crate::payload`]): `parameters`, `links` and the rest stay the arm's
    /// own, and every use of the result as a model ([`FitResult::params_for`]: validate,
    /// residual, report, every export, the C ABI) adds the payload to its frame's link.
    /// `None` in results without one (and in every result written before it).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub payload: Option<ResultPayload>,
}

/// A result's `payload` section: the body (`frame`, `mass` kg, `com` m in that frame,
/// `inertia` kg·m² about the centre of mass, `xx yy zz xy xz yz`: the fields of a
/// `simulate --payload` file) and, when it was identified from logs, how.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct ResultPayload {
    /// The payload.
    #[serde(flatten)]
    pub body: dvrk_model::Payload,
    /// How it was identified; `None` for a payload written by hand.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub identification: Option<PayloadIdentification>,
}

impl FitResult {
    /// The statuses of a link's 10 parameters `[Lxx … Lzz, lx, ly, lz, m]` (named as
    /// [`dvrk_model::Param::inertia_block`] names them), or `None` for a result written
    /// before parameter statuses.
    pub fn link_status(&self, link: &LinkResult) -> Option<[(String, ParameterStatus); 10]> {
        let block: Vec<(String, ParameterStatus)> = dvrk_model::Param::inertia_block(link.frame)
            .map(|p| {
                let s = self.parameter_status.get(&p.name).copied();
                s.map(|s| (p.name, s))
            })
            .collect::<Option<_>>()?;
        block.try_into().ok()
    }

    /// The parameter vector in the model's order: the fitted `parameters`, with the
    /// result's `payload` (if any) added to its frame's link parameters, so that the
    /// model is the arm with its load. Errors name a payload frame `model` lacks.
    pub fn params_for(&self, model: &dvrk_model::Model) -> Result<Vec<f64>, IdentError> {
        let mut params = model.params_from_named(
            self.parameters.iter().map(|(k, v)| (k.as_str(), *v)),
            "result",
        )?;
        if let Some(p) = &self.payload {
            p.body.add_to(model, &mut params, "result")?;
        }
        Ok(params)
    }

    /// Refuses `model` when it is not the robot this result was fitted for, in one line
    /// (`fit.json was fitted for mtm, not psm`) rather than through the list of
    /// parameters the two do not share; `source` names the result.
    pub fn check_robot(&self, model: &dvrk_model::Model, source: &str) -> Result<(), IdentError> {
        if self.robot == model.name {
            return Ok(());
        }
        Err(IdentError::WrongRobot {
            result: source.to_string(),
            fitted: self.robot.clone(),
            given: model.name.clone(),
        })
    }

    /// The model that evaluates this result's parameters, given the robot it is used
    /// with: `model` itself, or a copy with the fit's model options (Stribeck terms,
    /// bounds). Refuses another robot ([`FitResult::check_robot`]).
    pub fn model_for<'m>(
        &self,
        model: &'m dvrk_model::Model,
        source: &str,
    ) -> Result<std::borrow::Cow<'m, dvrk_model::Model>, IdentError> {
        self.check_robot(model, source)?;
        self.settings.model(model)
    }

    /// The robot the result records, as [`dvrk_model::Model::load`] takes it: a
    /// built-in name or a description path.
    pub fn robot(&self) -> &str {
        loadable_robot(&self.robot_source)
    }

    /// The model this result's parameters belong to: its recorded robot (or `robot`
    /// instead), with the fit's model options (Stribeck terms) applied.
    pub fn model(&self, robot: Option<&str>) -> Result<dvrk_model::Model, IdentError> {
        let robot = robot.unwrap_or_else(|| self.robot());
        let model = dvrk_model::Model::load(robot)?;
        Ok(self.settings.model(&model)?.into_owned())
    }

    /// The result document as pretty-printed JSON (the file `--out` writes).
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).expect("serializable")
    }

    /// Every number of the document with its place, e.g. `("links[2].mass", 1.5)`.
    fn numbers(&self) -> Vec<(String, f64)> {
        let mut out: Vec<(String, f64)> = Vec::new();
        let mut put = |place: String, v: f64| out.push((place, v));
        for (k, v) in &self.parameters {
            put(format!("parameters.{k}"), *v);
        }
        for l in &self.links {
            put(format!("links.{}.mass", l.link), l.mass);
            for (i, c) in l.com.iter().enumerate() {
                put(format!("links.{}.com[{i}]", l.link), *c);
            }
            for (i, c) in l.inertia_com.iter().enumerate() {
                put(format!("links.{}.inertia_com[{i}]", l.link), *c);
            }
        }
        for b in &self.base_parameters {
            put(format!("base_parameters.{}.value", b.name), b.value);
            put(format!("base_parameters.{}.std", b.name), b.std);
        }
        for c in &self.consistency {
            put(
                format!("consistency.{}.min_eigenvalue", c.link),
                c.min_eigenvalue,
            );
        }
        put("solver.seconds".into(), self.solver.seconds);
        for (i, w) in self.weights.iter().enumerate() {
            put(format!("weights[{i}]"), *w);
        }
        put("condition_number".into(), self.condition_number);
        put("sigma2".into(), self.sigma2);
        if let Some(d) = &self.delay {
            for (i, (v, s)) in d.delay_s.iter().zip(&d.std_s).enumerate() {
                put(format!("delay.delay_s[{i}]"), *v);
                put(format!("delay.std_s[{i}]"), *s);
            }
            put("delay.residual".into(), d.residual);
        }
        if let Some(d) = self.prior_divergence {
            put("prior_divergence".into(), d);
        }
        if let Some(p) = &self.payload {
            put("payload.mass".into(), p.body.mass);
            for (i, c) in p.body.com.iter().enumerate() {
                put(format!("payload.com[{i}]"), *c);
            }
            for (i, c) in p.body.inertia.iter().enumerate() {
                put(format!("payload.inertia[{i}]"), *c);
            }
            if let Some(id) = &p.identification {
                for (place, v) in id.numbers() {
                    put(format!("payload.identification.{place}"), v);
                }
            }
        }
        if let Some(p) = &self.settings.prior {
            put("settings.prior.weight".into(), p.weight);
            for (k, v) in &p.parameters {
                put(format!("settings.prior.parameters.{k}"), *v);
            }
        }
        let roles = [
            ("train", Some(&self.metrics.train)),
            ("test", self.metrics.test.as_ref()),
        ];
        for (role, m) in roles {
            let Some(m) = m else { continue };
            for (j, name) in m.joints.iter().enumerate() {
                if let Some(v) = m.relative_error.get(j) {
                    put(format!("metrics.{role}.relative_error.{name}"), *v);
                }
                if let Some(v) = m.rms.get(j) {
                    put(format!("metrics.{role}.rms.{name}"), *v);
                }
            }
        }
        out
    }

    /// Warnings for inputs that are the same data (equal SHA-256 of their files or
    /// samples): a training log given twice is fitted twice (its standard errors shrink
    /// by √2 without new information), and a test log equal to a training log measures
    /// training error, not generalization. What the command line prints on stderr and
    /// Python warns; the fit itself is not refused, as a lab may mean it.
    pub fn repeated_inputs(&self) -> Vec<String> {
        let logs: Vec<&InputInfo> = self
            .inputs
            .iter()
            .filter(|i| i.role == "train" || i.role == "test")
            .collect();
        let name = |i: &InputInfo| {
            let what = if i.path.is_empty() {
                &i.source
            } else {
                &i.path
            };
            format!("{} log {what}", i.role)
        };
        let mut out = Vec::new();
        for (k, later) in logs.iter().enumerate() {
            if let Some(first) = logs[..k].iter().find(|e| e.sha256 == later.sha256) {
                let why = match (first.role.as_str(), later.role.as_str()) {
                    ("train", "test") | ("test", "train") => {
                        "its errors are training errors, not a test of generalization"
                    }
                    ("train", _) => {
                        "fitted twice, which shrinks the standard errors by √2 with no new \
                         information"
                    }
                    _ => "its errors are counted twice",
                };
                out.push(format!(
                    "{} is the same data as {} (SHA-256 {}…): {why}",
                    name(later),
                    name(first),
                    &later.sha256[..later.sha256.len().min(12)]
                ));
            }
        }
        out
    }

    /// Checks that every number of the result is finite: a result is only ever written,
    /// printed or returned when it is. The error names the first bad field and, for the
    /// usual causes, why.
    pub fn check_finite(&self) -> Result<(), IdentError> {
        let Some((place, v)) = self.numbers().into_iter().find(|(_, v)| !v.is_finite()) else {
            return Ok(());
        };
        let cause = if place.starts_with("metrics.") {
            let role = if place.starts_with("metrics.test") {
                self.metrics.test.as_ref()
            } else {
                Some(&self.metrics.train)
            };
            if role.is_some_and(|m| m.samples == 0) {
                NotFiniteCause::NoSample
            } else if place.contains(".relative_error.") {
                NotFiniteCause::ZeroTorques
            } else {
                NotFiniteCause::Unknown
            }
        } else {
            NotFiniteCause::Overflow
        };
        Err(IdentError::NotFinite {
            robot: self.robot.clone(),
            place,
            value: v,
            cause,
        })
    }

    /// Reads a result document; `source` names it in errors. Every number must be finite
    /// and the parameters within ±[`dvrk_model::input::MAX_VALUE`].
    pub fn from_json(text: &str, source: &str) -> Result<FitResult, IdentError> {
        let result: FitResult = serde_json::from_str(text).map_err(|e| IdentError::Format {
            file: source.into(),
            message: format!("not a dvrk-ident result: {e}"),
        })?;
        for (place, v) in result.numbers() {
            let max = if place.starts_with("parameters.")
                || place.starts_with("links.")
                || place.starts_with("payload.")
            {
                dvrk_model::input::MAX_VALUE
            } else {
                f64::MAX
            };
            dvrk_model::input::check_magnitude(v, max, "").map_err(|m| IdentError::Format {
                file: source.into(),
                message: format!("{place}: {m}"),
            })?;
        }
        Ok(result)
    }

    /// Reads a result file (at most [`dvrk_model::input::MAX_TEXT_BYTES`]).
    pub fn read(path: &Path) -> Result<FitResult, IdentError> {
        let text = dvrk_model::input::read_text(path).map_err(|source| IdentError::Io {
            file: path.display().to_string(),
            source,
        })?;
        FitResult::from_json(&text, &path.display().to_string())
    }
}

/// The delays found, recorded in the result (`delay`) and applied through
/// `settings.processing.delay_s`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DelayEstimate {
    /// Per coordinate, s.
    pub delay_s: Vec<f64>,
    /// Standard error per coordinate from the residual's curvature, s (see the module
    /// documentation); the search range where the residual is flat there.
    pub std_s: Vec<f64>,
    /// The search range `[0, max_s]`, s.
    pub max_s: f64,
    /// The weighted residual sum of squares of the least-squares fit at `delay_s` (the
    /// method's first weights: 1 for OLS and IRLS, 1/torque range for WLS and SDP).
    pub residual: f64,
    /// Coordinate sweeps until no delay moved by more than 1e-7 s.
    pub sweeps: usize,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn input_hash_is_the_sha256_of_the_whole_file() {
        let dir = std::env::temp_dir().join(format!("dvrk-hash-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        // The FIPS 180-2 example "abc".
        let abc = dir.join("abc");
        std::fs::write(&abc, b"abc").unwrap();
        let info = InputInfo::from_file("train", &abc).unwrap();
        assert_eq!(
            info.sha256,
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
        );
        assert_eq!(info.bytes, 3);
        // Several read blocks: the digest of the bytes at once.
        let big = dir.join("big");
        let bytes: Vec<u8> = (0..2_500_000u32).map(|i| (i * 7 + i / 13) as u8).collect();
        std::fs::write(&big, &bytes).unwrap();
        let info = InputInfo::from_file("test", &big).unwrap();
        assert_eq!(info.sha256, format!("{:x}", Sha256::digest(&bytes)));
        assert_eq!(info.bytes, bytes.len() as u64);
        assert!(InputInfo::from_file("test", &dir.join("missing")).is_err());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
