//! A payload's identification record in the result document (`payload.identification`):
//! what the logs determined of it ([`crate::payload`] identifies it).

use indexmap::IndexMap;
use serde::{Deserialize, Serialize};

use super::parameters::{BaseParameterResult, LinkDetermined, ParameterStatus};
use crate::estimate::SolverInfo;

/// Standard deviations of a payload's quantities (the least-squares fit of the same
/// weighted data); `None` for a quantity the logs do not determine.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct PayloadStd {
    /// kg
    pub mass: Option<f64>,
    /// Centre of mass, m, in the payload's frame.
    pub com: Option<[f64; 3]>,
    /// Inertia about the centre of mass, kg·m², `xx yy zz xy xz yz` (the payload's order).
    pub inertia: Option<[f64; 6]>,
}

/// How a payload was identified: a result's `payload.identification`.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct PayloadIdentification {
    /// The logs (their sources).
    pub logs: Vec<String>,
    /// Processed samples over all logs.
    pub samples: usize,
    /// Which of the payload's quantities the logs determine.
    pub determined: LinkDetermined,
    /// Each barycentric parameter's status (named as the frame's link parameters).
    pub parameter_status: IndexMap<String, ParameterStatus>,
    /// Standard deviations of the payload's quantities.
    pub std: PayloadStd,
    /// The body's identifiable combinations with their least-squares values and
    /// standard deviations.
    pub base_parameters: Vec<BaseParameterResult>,
    /// How the semidefinite fit ended.
    pub solver: SolverInfo,
    /// Row weights per model coordinate (the result's), 1/N·m or 1/N.
    pub weights: Vec<f64>,
    /// Model coordinates, one per entry of the RMS lists.
    pub coordinates: Vec<String>,
    /// RMS per coordinate of what the result leaves unexplained, N·m or N.
    pub rms_without: Vec<f64>,
    /// The same with the payload added: what remains, N·m or N.
    pub rms_with: Vec<f64>,
}

impl PayloadIdentification {
    /// Every number with its place, for the result's finiteness checks.
    pub(crate) fn numbers(&self) -> Vec<(String, f64)> {
        let mut out = Vec::new();
        let s = &self.std;
        out.extend(s.mass.map(|m| ("std.mass".to_string(), m)));
        for (what, v) in [
            ("com", s.com.map(|c| c.to_vec())),
            ("inertia", s.inertia.map(|c| c.to_vec())),
        ] {
            for (i, x) in v.into_iter().flatten().enumerate() {
                out.push((format!("std.{what}[{i}]"), x));
            }
        }
        for b in &self.base_parameters {
            out.push((format!("base_parameters.{}.value", b.name), b.value));
            out.push((format!("base_parameters.{}.std", b.name), b.std));
        }
        for (list, name) in [
            (&self.weights, "weights"),
            (&self.rms_without, "rms_without"),
            (&self.rms_with, "rms_with"),
        ] {
            for (i, x) in list.iter().enumerate() {
                out.push((format!("{name}[{i}]"), *x));
            }
        }
        out.push(("solver.seconds".into(), self.solver.seconds));
        out
    }
}
