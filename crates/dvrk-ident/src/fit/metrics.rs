//! The errors of parameters on processed samples: predictions, per-joint relative and
//! RMS errors (in the model coordinates or the measured joints, [`JointMap`]) summed
//! block by block or read off the observation's factors, and the torque ranges of the
//! WLS weights.

use dvrk_model::{Model, Workspace};
use nalgebra::DMatrix;

use super::joints::JointMap;
use super::prepare::Prepared;
use crate::error::IdentError;
use crate::observation::{Observation, Samples};
use crate::result::JointMetrics;

/// Predicted torques `H(q, q̇, q̈)·π` for every sample (known forces excluded, as the
/// prepared torques); load friction's load is the predicted torque, not the measured one
/// ([`Model::loaded_inverse_dynamics`]).
pub fn predict(model: &Model, params: &[f64], data: &Prepared) -> DMatrix<f64> {
    let n = model.dof();
    let mut ws = Workspace::new(model);
    let mut out = DMatrix::zeros(data.len(), n);
    let (mut q, mut dq, mut ddq, mut tau) =
        (vec![0.0; n], vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let s = data.samples();
    for k in 0..data.len() {
        s.read(k, &mut q, &mut dq, &mut ddq);
        model.advance_hysteresis(&mut ws, &q);
        model.loaded_inverse_dynamics(&mut ws, params, &q, &dq, &ddq, &mut tau);
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
    /// The workspace of the passes, which carries the hysteresis (Dahl) states from one
    /// block of the log to the next (`None` before the first).
    ws: Option<Workspace>,
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
            ws: None,
        }
    }

    /// One set of sums per prepared log, in order: the training pass of an
    /// in-memory fit and of a cross-validation fold.
    pub(crate) fn of_logs(model: &Model, params: &[f64], logs: &[Prepared]) -> Vec<MetricSums> {
        logs.iter()
            .map(|log| MetricSums::of_samples(model, params, log.samples(), None))
            .collect()
    }

    /// The sums of one log's samples on their own (its Dahl states starting at zero),
    /// up to `window` samples ([`MetricSums::add`]).
    pub(crate) fn of_samples(
        model: &Model,
        params: &[f64],
        samples: Samples<'_>,
        window: Option<usize>,
    ) -> MetricSums {
        let mut sums = MetricSums::new(model);
        sums.add(model, params, samples, window);
        sums
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
        let p = params.len();
        MetricSums {
            e2: DMatrix::from_diagonal(&nalgebra::DVector::from_iterator(
                parts.len(),
                parts.iter().map(|o| o.residual_sum_of_squares(params)),
            )),
            t2: DMatrix::from_diagonal(&nalgebra::DVector::from_iterator(
                parts.len(),
                parts.iter().map(|o| o.r().column(p).norm_squared()),
            )),
            cross: false,
            samples: parts.first().map_or(0, Observation::rows),
            ws: None,
        }
    }

    /// The sums of [`MetricSums::from_factors`] with the errors of `fitted`, the same
    /// rows' factors with some columns projected out ([`Observation::project_out`]: the
    /// log's own torque offsets eliminated), and the torques of `parts`, the rows as
    /// measured: the relative error stays relative to the measured torques.
    pub(crate) fn from_fitted_factors(
        parts: &[Observation],
        fitted: &[Observation],
        params: &[f64],
    ) -> MetricSums {
        let mut sums = MetricSums::from_factors(parts, params);
        sums.e2 = MetricSums::from_factors(fitted, params).e2;
        sums
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
        let ws = self.ws.get_or_insert_with(|| Workspace::new(model));
        let (mut q, mut dq, mut ddq) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        let mut err = DMatrix::zeros(rows, n);
        let mut tau = vec![0.0; n];
        for k in 0..rows {
            samples.read(k, &mut q, &mut dq, &mut ddq);
            model.advance_hysteresis(ws, &q);
            model.loaded_inverse_dynamics(ws, params, &q, &dq, &ddq, &mut tau);
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
                name: crate::options::Setting::Joints.into(),
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
