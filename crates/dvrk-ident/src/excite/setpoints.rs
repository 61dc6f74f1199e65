//! Setpoints of an excitation trajectory for playback on the robot: one period in the
//! measured joint space, as numbers or as the CSV `dvrk-ident excite --setpoints` writes.

use dvrk_model::Model;
use nalgebra::DMatrix;

use super::{ExciteError, FourierTrajectory};

/// The setpoints' rate when none is given (`excite --rate`, Python's
/// `FourierTrajectory.setpoints(rate=)`), Hz: the dVRK's 2019 logs' rate.
pub const DEFAULT_RATE_HZ: f64 = 200.0;

/// Setpoints of one period at `rate_hz` in the MEASURED joint space (`q_meas = M q`,
/// what a dVRK script plays back): the times (s, from 0, `round(period · rate)` of
/// them) and one row of measured joint positions (rad or m) per time, columns in
/// `model.measured.joints` order.
pub fn setpoints(
    model: &Model,
    traj: &FourierTrajectory,
    rate_hz: f64,
) -> Result<(Vec<f64>, DMatrix<f64>), ExciteError> {
    check_dof(model, traj)?;
    if !(rate_hz > 0.0 && rate_hz.is_finite()) {
        return Err(ExciteError::Invalid(format!(
            "rate must be positive, got {rate_hz}"
        )));
    }
    let count = (traj.period_s() * rate_hz).round().max(1.0) as usize;
    let times: Vec<f64> = (0..count).map(|k| k as f64 / rate_hz).collect();
    let (q, _, _) = traj.sample(&times);
    Ok((times, q * model.measured.coupling.transpose()))
}

/// [`setpoints`] as a CSV with header `time,<measured joint names>` (s; rad or m).
pub fn setpoints_csv(
    model: &Model,
    traj: &FourierTrajectory,
    rate_hz: f64,
) -> Result<String, ExciteError> {
    let (times, q) = setpoints(model, traj, rate_hz)?;
    let mut out = String::from("time");
    for name in &model.measured.joints {
        out.push(',');
        out.push_str(name);
    }
    out.push('\n');
    for (k, t) in times.iter().enumerate() {
        out.push_str(&format!("{t:.6}"));
        for v in q.row(k).iter() {
            out.push_str(&format!(",{v:.9}"));
        }
        out.push('\n');
    }
    Ok(out)
}

/// `traj` is a valid trajectory with one coordinate per coordinate of `model`: the
/// check every entry point of the optimizer and the setpoints start with.
pub(crate) fn check_dof(model: &Model, traj: &FourierTrajectory) -> Result<(), ExciteError> {
    traj.validate("trajectory")?;
    if traj.dof() != model.dof() {
        return Err(ExciteError::Invalid(format!(
            "the trajectory has {} coordinates, model {} has {}",
            traj.dof(),
            model.name,
            model.dof()
        )));
    }
    Ok(())
}
