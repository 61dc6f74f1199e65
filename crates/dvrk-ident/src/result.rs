//! The result document of a fit (JSON, schema in the README) and its exports.
//!
//! Scripts rely on at least: `method`, `parameters` {name: value}, `base_parameters`,
//! `consistency` [{`link`, `min_eigenvalue`}], `solver` {`status`, `converged`,
//! `seconds`}, `metrics` {`train`, `test`: {`relative_error`, `rms`}}.

use std::path::Path;

use indexmap::IndexMap;
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

use crate::error::IdentError;
use crate::fit::FitSettings;

/// Standard parameters of one link (frame axes).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct LinkResult {
    pub frame: usize,
    pub link: String,
    /// kg
    pub mass: f64,
    /// centre of mass in the link frame, m
    pub com: [f64; 3],
    /// inertia about the centre of mass `[xx, xy, xz, yy, yz, zz]`, kg·m²
    pub inertia_com: [f64; 6],
}

/// Physical consistency of one link: the smallest eigenvalue of its 4×4 pseudo-inertia.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Consistency {
    pub frame: usize,
    pub link: String,
    /// kg·m²; positive means realizable by a positive mass density
    pub min_eigenvalue: f64,
    pub consistent: bool,
}

/// One base parameter with its value and standard deviation.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct BaseParameterResult {
    pub name: String,
    pub expression: String,
    pub value: f64,
    /// Standard deviation from the least-squares fit of the same weighted data.
    pub std: f64,
}

/// Solver statistics; `converged` false means the numbers are NOT a result.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct SolverInfo {
    pub name: String,
    pub status: String,
    pub converged: bool,
    pub seconds: f64,
    pub iterations: u32,
}

/// Per-joint errors on one trajectory (model coordinates).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct JointMetrics {
    pub joints: Vec<String>,
    pub samples: usize,
    /// `‖τ − τ̂‖ / ‖τ‖` per joint
    pub relative_error: Vec<f64>,
    /// RMS of `τ − τ̂` per joint, N·m or N
    pub rms: Vec<f64>,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Metrics {
    pub train: JointMetrics,
    pub test: Option<JointMetrics>,
}

/// Provenance of an input log.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct InputInfo {
    /// `train` or `test`
    pub role: String,
    pub path: String,
    pub sha256: String,
    pub bytes: u64,
}

impl InputInfo {
    /// Hashes a file (SHA-256) for the result's provenance.
    pub fn from_file(role: &str, path: &Path) -> Result<InputInfo, IdentError> {
        let bytes = std::fs::read(path).map_err(|e| IdentError::Io {
            file: path.display().to_string(),
            message: e.to_string(),
        })?;
        Ok(InputInfo {
            role: role.into(),
            path: path.display().to_string(),
            sha256: format!("{:x}", Sha256::digest(&bytes)),
            bytes: bytes.len() as u64,
        })
    }
}

/// The result of a fit.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct FitResult {
    pub tool: String,
    pub robot: String,
    pub robot_source: String,
    pub method: String,
    pub settings: FitSettings,
    pub inputs: Vec<InputInfo>,
    /// Every parameter by name (barycentric: inertia about the frame origin, first
    /// moment, mass; friction; motor inertia; spring). For least squares, a
    /// representative: base parameters on their kept columns, zero elsewhere.
    pub parameters: IndexMap<String, f64>,
    pub parameter_order: Vec<String>,
    /// Standard parameters per link.
    pub links: Vec<LinkResult>,
    pub base_parameters: Vec<BaseParameterResult>,
    pub consistency: Vec<Consistency>,
    /// Every link pseudo-inertia positive definite and friction/motor inertia ≥ 0.
    pub physically_consistent: bool,
    pub solver: SolverInfo,
    /// Row weights per coordinate used by the estimator (1/N·m or 1/N).
    pub weights: Vec<f64>,
    /// Observation rows (samples × coordinates).
    pub rows: usize,
    /// Condition number of the weighted base regressor.
    pub condition_number: f64,
    /// Residual variance of the weighted least-squares fit.
    pub sigma2: f64,
    pub metrics: Metrics,
}

impl FitResult {
    /// The parameter vector in the model's order.
    pub fn params_for(&self, model: &dvrk_model::Model) -> Result<Vec<f64>, IdentError> {
        Ok(model.params_from_named(
            self.parameters.iter().map(|(k, v)| (k.as_str(), *v)),
            "result",
        )?)
    }

    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).expect("serializable")
    }

    pub fn from_json(text: &str, source: &str) -> Result<FitResult, IdentError> {
        serde_json::from_str(text).map_err(|e| IdentError::Io {
            file: source.into(),
            message: format!("not a dvrk-ident result: {e}"),
        })
    }

    /// Reads a result file.
    pub fn read(path: &Path) -> Result<FitResult, IdentError> {
        let text = std::fs::read_to_string(path).map_err(|e| IdentError::Io {
            file: path.display().to_string(),
            message: e.to_string(),
        })?;
        FitResult::from_json(&text, &path.display().to_string())
    }
}

/// Writes `text` to `path` atomically: a temporary file in the same folder, then a
/// rename, so an interrupted run never leaves a half-written output.
pub fn write_atomic(path: &Path, text: &str) -> Result<(), IdentError> {
    let io = |e: std::io::Error| IdentError::Io {
        file: path.display().to_string(),
        message: e.to_string(),
    };
    let dir = path
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().to_string())
        .unwrap_or_default();
    let tmp = dir.join(format!(".{name}.tmp{}", std::process::id()));
    std::fs::write(&tmp, text).map_err(io)?;
    std::fs::rename(&tmp, path).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        io(e)
    })
}
