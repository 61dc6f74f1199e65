//! External joint torques from a log: what the identified model does not explain.
//!
//! Per processed sample `τ_ext = τ_measured − τ_model(q, q̇, q̈)`, with the result's own
//! processing (filters, delays, trimming) and its friction, springs and known forces —
//! the prediction `validate` scores, kept sample by sample instead of summed. Beside it,
//! the momentum observer's estimate of the same torque
//! ([`dvrk_model::MomentumObserver`]), which needs no acceleration: a first-order lag of
//! gain `observer_gain` (1/s) over the processed `q`, `q̇` and `τ`.
//!
//! The sign is this crate's one: the torque the joints apply beyond the model, e.g.
//! `+g_payload(q)` for a payload the model does not know (the opposite of the torque the
//! environment applies to the arm). The noise floor of each joint is the fit's own RMS
//! error on its training logs (`metrics.train.rms`): a residual whose RMS stays within
//! it shows nothing the fit did not already leave unexplained.

use dvrk_model::{Model, MomentumObserver, Workspace};
use nalgebra::DMatrix;

use crate::error::IdentError;
use crate::external::ExternalTorque;
use crate::fit::{predict, prepare, JointMap};
use crate::joint_log::{Coordinates, JointLog};
use crate::result::FitResult;
use crate::settings::Joints;

/// Default observer gain, 1/s (a 50 ms time constant).
pub const DEFAULT_OBSERVER_GAIN: f64 = 20.0;

/// How to compute a residual.
#[derive(Clone, Debug, PartialEq)]
pub struct ResidualOptions {
    /// The joints the torques are given in; `None`: the fit's (`settings.joints`), whose
    /// training errors are the noise floor.
    pub joints: Option<Joints>,
    /// The momentum observer's gain, 1/s, every coordinate (positive).
    pub observer_gain: f64,
}

impl Default for ResidualOptions {
    fn default() -> Self {
        ResidualOptions {
            joints: None,
            observer_gain: DEFAULT_OBSERVER_GAIN,
        }
    }
}

/// The external torques of one log (see the module documentation).
#[derive(Clone, Debug)]
pub struct Residual {
    /// The log.
    pub source: String,
    /// The joints' names (model coordinates or measured joints).
    pub joints: Vec<String>,
    /// Time of each processed sample, s.
    pub time: Vec<f64>,
    /// The processed positions (rad or m) and velocities (rad/s or m/s) per sample and
    /// joint, where the torques are.
    pub q: DMatrix<f64>,
    /// See [`Residual::q`].
    pub dq: DMatrix<f64>,
    /// `τ_measured − τ_model` per processed sample (rows) and joint, N·m or N.
    pub external: DMatrix<f64>,
    /// The momentum observer's estimate of the same, N·m or N.
    pub observer: DMatrix<f64>,
    /// RMS of `external` per joint, N·m or N.
    pub rms: Vec<f64>,
    /// The fit's RMS error on its training logs per joint, N·m or N; `None` when the
    /// result's metrics are in other joints than these.
    pub noise_floor: Option<Vec<f64>>,
}

impl Residual {
    /// `external` as a time series (the `simulate --external-torque` layout).
    pub fn external_series(&self) -> ExternalTorque {
        ExternalTorque {
            time: self.time.clone(),
            tau: self.external.clone(),
        }
    }

    /// RMS of the observer's estimate per joint, N·m or N (lower than [`Residual::rms`]
    /// where the noise is faster than the observer's lag).
    pub fn observer_rms(&self) -> Vec<f64> {
        column_rms(&self.observer)
    }

    /// The residual as a log: the processed `q`, `q̇` and the residual (`observer`:
    /// the observer's estimate) as the effort, in these joints (`coordinates`: which
    /// they are), for the log writers (an MCAP `JointState` holds measured joints).
    pub fn to_log(&self, coordinates: Coordinates, observer: bool) -> JointLog {
        JointLog {
            time: self.time.clone(),
            q: self.q.clone(),
            dq: Some(self.dq.clone()),
            tau: if observer {
                self.observer.clone()
            } else {
                self.external.clone()
            },
            joint_names: self.joints.clone(),
            coordinates,
            source: self.source.clone(),
        }
    }

    /// The observer's estimate as a time series.
    pub fn observer_series(&self) -> ExternalTorque {
        ExternalTorque {
            time: self.time.clone(),
            tau: self.observer.clone(),
        }
    }
}

/// RMS of each column of a samples × joints matrix.
fn column_rms(m: &DMatrix<f64>) -> Vec<f64> {
    let count = m.nrows().max(1) as f64;
    (0..m.ncols())
        .map(|j| (m.column(j).norm_squared() / count).sqrt())
        .collect()
}

/// The residual of `log` under `result` (`model` is the result's model, e.g. from
/// [`FitResult::model_for`], and `params` its parameters in that model's order).
pub fn external_torque(
    model: &Model,
    params: &[f64],
    result: &FitResult,
    log: &JointLog,
    options: &ResidualOptions,
) -> Result<Residual, IdentError> {
    let n = model.dof();
    let observer_gains = vec![options.observer_gain; n];
    let mut observer =
        MomentumObserver::new(model, &observer_gains).map_err(|e| IdentError::Setting {
            name: "observer_gain".into(),
            message: e.to_string(),
        })?;
    let data = prepare(model, log, &result.settings.processing)?;
    let predicted = predict(model, params, &data);
    let external = &data.tau - predicted;
    // The observer sees the torque as measured: known forces back in (the model's).
    let mut ws = Workspace::new(model);
    let mut observed = DMatrix::zeros(data.len(), n);
    let (mut q, mut dq, mut tau) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    for k in 0..data.len() {
        for j in 0..n {
            q[j] = data.q[(k, j)];
            dq[j] = data.dq[(k, j)];
            tau[j] = data.tau[(k, j)];
        }
        // Load friction's load: the measured torque, as in the fit.
        model.set_load(&mut ws, &tau);
        model.add_known_forces(&q, &mut tau);
        let dt = if k == 0 {
            1.0 // not used: the first update only starts the observer
        } else {
            data.time[k] - data.time[k - 1]
        };
        if !(dt > 0.0 && dt.is_finite()) {
            return Err(IdentError::Mismatch {
                source_name: data.source.clone(),
                message: format!(
                    "processed sample {k} at {} s does not follow the previous one",
                    data.time[k]
                ),
            });
        }
        model.advance_hysteresis(&mut ws, &q);
        let r = observer.update(model, &mut ws, params, &q, &dq, &tau, dt);
        observed.row_mut(k).copy_from_slice(r);
    }
    let joints = JointMap::new(model, options.joints.unwrap_or(result.settings.joints))?;
    let external = joints.torque(&external).into_owned();
    let observer = joints.torque(&observed).into_owned();
    let (q, dq) = (
        joints.motion(&data.q).into_owned(),
        joints.motion(&data.dq).into_owned(),
    );
    let rms = column_rms(&external);
    let noise_floor =
        (result.metrics.train.joints == joints.names).then(|| result.metrics.train.rms.clone());
    Ok(Residual {
        source: data.source,
        joints: joints.names,
        time: data.time,
        q,
        dq,
        external,
        observer,
        rms,
        noise_floor,
    })
}
