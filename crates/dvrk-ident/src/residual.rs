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
//!
//! With a frame ([`ResidualOptions::wrench`], e.g. the PSM's `tool_tip`), the external
//! torques become a Cartesian wrench at that frame ([`tip_wrench`]): the least-squares
//! `F` of `τ_ext = J(q)ᵀ·F` with `J` the frame's Jacobian in the model coordinates,
//! the directions the joints cannot sense at that pose reported, not estimated.

use dvrk_model::{Model, MomentumObserver, Workspace};
use nalgebra::{DMatrix, Vector3};

use crate::error::IdentError;
use crate::external::ExternalTorque;
use crate::fit::{predict, prepare, JointMap};
use crate::result::FitResult;
use crate::settings::Joints;
use crate::{Coordinates, JointLog};

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
    /// The frame (a name of the robot's frames, e.g. `tool_tip`) at whose origin to
    /// express the external torques as a wrench ([`tip_wrench`]); `None`: no wrench.
    pub wrench: Option<String>,
    /// The relative threshold of [`tip_wrench`] (see [`DEFAULT_WRENCH_RCOND`]).
    pub wrench_rcond: f64,
}

impl Default for ResidualOptions {
    fn default() -> Self {
        ResidualOptions {
            joints: None,
            observer_gain: DEFAULT_OBSERVER_GAIN,
            wrench: None,
            wrench_rcond: DEFAULT_WRENCH_RCOND,
        }
    }
}

/// Default relative threshold of [`tip_wrench`]: a wrench direction whose joint
/// torques are below `1e-6` times those of the best-sensed direction (singular values
/// of `Jᵀ`) is unsensed. It only separates the directions no joint senses (a
/// kinematic singularity, fewer coordinates than six) from the rest; directions sensed
/// weakly (near a singularity) stay and amplify the torque noise by `1/σ`: raise it to
/// drop them.
pub const DEFAULT_WRENCH_RCOND: f64 = 1e-6;

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
    /// `external` as a wrench at [`ResidualOptions::wrench`]'s frame, when asked.
    pub wrench: Option<TipWrench>,
}

/// External torques as a Cartesian wrench at a frame's origin, per sample (rows): the
/// least-squares, minimum-norm `F` of `τ_ext = J(q)ᵀ·F`, `J` the frame's 6×n Jacobian
/// in the model coordinates ([`Model::frame_jacobian`]: the origin's linear velocity,
/// then the angular velocity, in the base frame's axes).
///
/// Each row is `[fx, fy, fz, mx, my, mz]`: the force (N) the arm applies at the frame's
/// origin and the moment (N·m) about that origin — the sign of the residual, the
/// opposite of the contact wrench on the tool (a payload held at the tip gives an
/// upward force of its weight). The minimum norm counts 1 N and 1 N·m alike. A
/// coordinate's torque that no wrench at the frame makes (the PSM's jaw grip) is left
/// out of `F`.
#[derive(Clone, Debug)]
pub struct TipWrench {
    /// The frame, by its name in the robot's description ("the tip").
    pub frame: String,
    /// The relative threshold on the singular values of `Jᵀ` (see
    /// [`DEFAULT_WRENCH_RCOND`]).
    pub rcond: f64,
    /// The wrench in the base frame's axes, samples × 6 (N, N·m).
    pub in_base: DMatrix<f64>,
    /// The same wrench in the tip frame's own axes (`R_tipᵀ` times each half of
    /// `in_base`, `R_tip` the frame's orientation in the base frame), samples × 6.
    pub in_tip: DMatrix<f64>,
    /// Per sample, how many independent wrench directions the joints sense (0 to 6).
    pub rank: Vec<usize>,
    /// Per sample, the `6 − rank` unsensed directions (unit `[f, m]` vectors, base
    /// frame axes): a wrench along them moves no joint, so `in_base` has no component
    /// along them (minimum norm) and says nothing about the wrench there.
    pub unsensed_in_base: Vec<Vec<[f64; 6]>>,
    /// The same directions in the tip frame's axes.
    pub unsensed_in_tip: Vec<Vec<[f64; 6]>>,
}

impl TipWrench {
    /// RMS per component of `m` (`in_base` or `in_tip`), N and N·m.
    pub fn rms(m: &DMatrix<f64>) -> Vec<f64> {
        column_rms(m)
    }

    /// The fewest sensed directions over the samples (6 when every sample senses all;
    /// 6 for no sample).
    pub fn min_rank(&self) -> usize {
        self.rank.iter().copied().min().unwrap_or(6)
    }

    /// The samples where some direction is unsensed.
    pub fn rank_deficient_samples(&self) -> usize {
        self.rank.iter().filter(|&&r| r < 6).count()
    }

    /// The wrench as CSV, one row per sample at `time` (s): `time`, the six components
    /// in the base frame's axes (`fx_base` … `mz_base`, N and N·m), the same in the tip
    /// frame's (`fx_tip` … `mz_tip`), and `rank` (the directions sensed).
    pub fn to_csv(&self, time: &[f64]) -> String {
        assert_eq!(time.len(), self.rank.len(), "one time per sample");
        let mut out = String::from("time");
        for frame in ["base", "tip"] {
            for c in WRENCH_COMPONENTS {
                out.push_str(&format!(",{c}_{frame}"));
            }
        }
        out.push_str(",rank\n");
        for (k, t) in time.iter().enumerate() {
            out.push_str(&t.to_string());
            for v in self.in_base.row(k).iter().chain(self.in_tip.row(k).iter()) {
                out.push(',');
                out.push_str(&v.to_string());
            }
            out.push_str(&format!(",{}\n", self.rank[k]));
        }
        out
    }
}

/// The wrench's components in the order of a [`TipWrench`] row: force (N), then moment
/// (N·m).
pub const WRENCH_COMPONENTS: [&str; 6] = ["fx", "fy", "fz", "mx", "my", "mz"];

/// The index (base 0, as [`Model::frame_names`]) of the frame `frame` a wrench can be
/// at; the error names the robot's frames. The base does not move and senses nothing.
pub fn wrench_frame(model: &Model, frame: &str) -> Result<usize, IdentError> {
    let names = model.frame_names();
    let error = |message: String| IdentError::Setting {
        name: crate::error::SettingName::Argument("wrench"),
        message,
    };
    match names.iter().position(|n| n == frame) {
        Some(0) => Err(error(format!(
            "the base frame does not move: choose a frame of robot {} ({})",
            model.name,
            names[1..].join(", ")
        ))),
        Some(i) => Ok(i),
        None => Err(error(format!(
            "robot {} has no frame `{frame}` (frames: {})",
            model.name,
            names[1..].join(", ")
        ))),
    }
}

/// [`wrench_frame`], and `rcond` in `[0, 1)`.
fn check_wrench(model: &Model, frame: &str, rcond: f64) -> Result<usize, IdentError> {
    if !(rcond.is_finite() && (0.0..1.0).contains(&rcond)) {
        return Err(IdentError::Setting {
            name: crate::error::SettingName::Argument("wrench_rcond"),
            message: format!("must be in [0, 1), got {rcond}"),
        });
    }
    wrench_frame(model, frame)
}

/// The wrench at frame `frame`'s origin whose joint torques are `tau_ext` (samples ×
/// dof, model coordinates, N·m or N) at the positions `q` (samples × dof, model
/// coordinates): per sample the SVD `Jᵀ = U·Σ·Vᵀ` of the frame's Jacobian, and
/// `F = Σᵢ vᵢ·(uᵢᵀ·τ)/σᵢ` over the singular values `σᵢ > rcond·σ_max`; the other
/// `vᵢ` are the unsensed directions (all six where `σ_max = 0`). See [`TipWrench`].
pub fn tip_wrench(
    model: &Model,
    frame: &str,
    q: &DMatrix<f64>,
    tau_ext: &DMatrix<f64>,
    rcond: f64,
) -> Result<TipWrench, IdentError> {
    let index = check_wrench(model, frame, rcond)?;
    let n = model.dof();
    if q.ncols() != n || tau_ext.shape() != q.shape() {
        return Err(IdentError::Setting {
            name: crate::error::SettingName::Argument("wrench"),
            message: format!(
                "q is {}×{} and the external torque {}×{}: both need one row per sample and \
                 one column per coordinate of robot {} ({n})",
                q.nrows(),
                q.ncols(),
                tau_ext.nrows(),
                tau_ext.ncols(),
                model.name
            ),
        });
    }
    let samples = q.nrows();
    let mut ws = Workspace::new(model);
    let (mut in_base, mut in_tip) = (DMatrix::zeros(samples, 6), DMatrix::zeros(samples, 6));
    let mut rank = Vec::with_capacity(samples);
    let (mut unsensed_in_base, mut unsensed_in_tip) =
        (Vec::with_capacity(samples), Vec::with_capacity(samples));
    let mut qk = vec![0.0; n];
    // Jᵀ with zero rows below it up to six: the thin SVD then has six singular values
    // and all of V, so the unsensed directions of an arm with fewer coordinates too.
    let mut jt = DMatrix::zeros(n.max(6), 6);
    for k in 0..samples {
        for (j, v) in qk.iter_mut().enumerate() {
            *v = q[(k, j)];
        }
        model.forward_kinematics(&mut ws, &qk);
        let jac = model.frame_jacobian(&ws, index);
        jt.view_mut((0, 0), (n, 6)).tr_copy_from(&jac);
        let svd = jt.clone().svd(true, true);
        let (u, v_t) = (
            svd.u.as_ref().expect("asked for U"),
            svd.v_t.as_ref().expect("asked for V"),
        );
        let s_max = svd.singular_values.max();
        let tau = tau_ext.row(k);
        let rotation = ws.pose(index).rotation;
        let to_tip = |w: [f64; 6]| {
            let f = rotation.tr_mul(&Vector3::new(w[0], w[1], w[2]));
            let m = rotation.tr_mul(&Vector3::new(w[3], w[4], w[5]));
            [f.x, f.y, f.z, m.x, m.y, m.z]
        };
        let mut f = [0.0; 6];
        let (mut sensed, mut lost) = (0, Vec::new());
        for (i, &s) in svd.singular_values.iter().enumerate() {
            let direction: [f64; 6] = std::array::from_fn(|c| v_t[(i, c)]);
            if s_max > 0.0 && s > rcond * s_max {
                let along = (0..n).map(|j| u[(j, i)] * tau[j]).sum::<f64>() / s;
                for (fc, d) in f.iter_mut().zip(direction) {
                    *fc += along * d;
                }
                sensed += 1;
            } else {
                lost.push(direction);
            }
        }
        if let Some(c) = f.iter().position(|x| !x.is_finite()) {
            return Err(IdentError::Setting {
                name: crate::error::SettingName::Argument("wrench"),
                message: format!(
                    "sample {k}: wrench component {c} is not finite (external torque {:?})",
                    tau.iter().collect::<Vec<_>>()
                ),
            });
        }
        in_base.row_mut(k).copy_from_slice(&f);
        in_tip.row_mut(k).copy_from_slice(&to_tip(f));
        rank.push(sensed);
        unsensed_in_tip.push(lost.iter().map(|&d| to_tip(d)).collect());
        unsensed_in_base.push(lost);
    }
    Ok(TipWrench {
        frame: frame.to_string(),
        rcond,
        in_base,
        in_tip,
        rank,
        unsensed_in_base,
        unsensed_in_tip,
    })
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
    if let Some(frame) = &options.wrench {
        // A wrong frame is told before the log is processed.
        check_wrench(model, frame, options.wrench_rcond)?;
    }
    let observer_gains = vec![options.observer_gain; n];
    let mut observer =
        MomentumObserver::new(model, &observer_gains).map_err(|e| IdentError::Setting {
            name: crate::error::SettingName::Argument("observer_gain"),
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
    // In the model coordinates, where `J` is.
    let wrench = match &options.wrench {
        Some(frame) => Some(tip_wrench(
            model,
            frame,
            &data.q,
            &external,
            options.wrench_rcond,
        )?),
        None => None,
    };
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
        wrench,
    })
}
