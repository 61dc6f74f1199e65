//! Simulated logs: a robot model with known parameters runs an excitation trajectory and
//! "measures" its joints, as the real robot would log them.
//!
//! [`simulate`] samples the trajectory (model coordinates) at a fixed rate, computes the
//! torques `τ = H(q, q̇, q̈)·π + known forces(q) + τ_ext(t) + noise` with independent
//! Gaussian noise per model coordinate (`π` with the payload's parameters added, if any;
//! `τ_ext` the external torque file's, if any), then maps everything to the robot's measured joints
//! ([`to_measured_coordinates`]): `q_meas = M q`, `q̇_meas = M q̇`, `τ_meas = M⁻ᵀ τ`
//! with `M` = `model.measured.coupling`. The result is a [`JointLog`] in
//! [`Coordinates::Measured`] with the model's measured joint names and the exact
//! velocities, ready for [`crate::log::write`] (e.g. a ROS 2 MCAP log).
//!
//! The noise comes from a small built-in generator (SplitMix64 and Box–Muller), so a
//! seed gives the same log on every platform and with every dependency version.

use std::borrow::Cow;

use dvrk_model::{Model, Payload, Workspace};
use nalgebra::DMatrix;

use crate::error::IdentError;
use crate::excite::FourierTrajectory;
/// External torques a simulation adds ([`Simulation`]'s `external`).
pub use crate::external::ExternalTorque;
/// The other way: a log in the robot's measured coordinates (joint positions, motor
/// torques of the coupled joints) turned into the model's, as the fit reads it.
pub use crate::fit::to_model_coordinates;
use crate::{Coordinates, JointLog};
use dvrk_logs::uniform_time;

/// Most samples [`simulate`] produces (a guard against a mistyped duration or rate).
pub const MAX_SAMPLES: usize = 10_000_000;

/// How to sample and perturb a simulated log.
#[derive(Clone, Debug, PartialEq)]
pub struct Simulation {
    /// Length of the log, s; `None`: one period of the trajectory.
    pub duration_s: Option<f64>,
    /// Sampling rate, Hz (sample `k` at `k / rate`).
    pub rate_hz: f64,
    /// Standard deviation of the torque noise, N·m or N, added in model coordinates
    /// before the mapping to measured joints: empty for none, one value for every
    /// coordinate or one per coordinate.
    pub noise_std: Vec<f64>,
    /// Seed of the noise generator.
    pub seed: u64,
    /// Measurement delay of each coordinate's torque, s: the torque logged at `t` is the
    /// one of the motion at `t − d_j` (what `fit --delay` estimates). Empty for none,
    /// one value for every coordinate or one per coordinate.
    pub delay_s: Vec<f64>,
    /// A rigid payload fixed to a frame, added to the parameters: the arm carries it.
    pub payload: Option<Payload>,
    /// An external torque per model coordinate over time (N·m or N), added to the
    /// simulated torques (the torque the model does not explain: what `residual`
    /// estimates); delayed with each coordinate's torque.
    pub external_torque: Option<ExternalTorque>,
}

impl Default for Simulation {
    /// One period at 200 Hz (the dVRK logging rate), no noise, seed 0.
    fn default() -> Self {
        Simulation {
            duration_s: None,
            rate_hz: 200.0,
            noise_std: Vec::new(),
            seed: 0,
            delay_s: Vec::new(),
            payload: None,
            external_torque: None,
        }
    }
}

impl Simulation {
    /// Number of samples for a trajectory: `round(duration · rate)`.
    pub fn samples(&self, traj: &FourierTrajectory) -> usize {
        let d = self.duration_s.unwrap_or_else(|| traj.period_s());
        let n = (d * self.rate_hz).round();
        if n.is_finite() && n >= 0.0 {
            n.min(usize::MAX as f64) as usize
        } else {
            0
        }
    }
}

/// Deterministic normal deviates: SplitMix64 uniforms and the Box–Muller transform.
#[derive(Clone, Debug)]
pub struct Gaussian {
    state: u64,
}

impl Gaussian {
    /// A generator for `seed` (any value, including 0).
    pub fn new(seed: u64) -> Self {
        Gaussian { state: seed }
    }

    fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in (0, 1].
    fn uniform(&mut self) -> f64 {
        ((self.next_u64() >> 11) + 1) as f64 / (1u64 << 53) as f64
    }

    /// A standard normal deviate.
    pub fn sample(&mut self) -> f64 {
        let (u, v) = (self.uniform(), self.uniform());
        (-2.0 * u.ln()).sqrt() * (2.0 * std::f64::consts::PI * v).cos()
    }
}

fn setting(name: &'static str, message: String) -> IdentError {
    IdentError::Setting {
        name: crate::error::SettingName::Argument(name),
        message,
    }
}

/// Simulates a log of `model` with parameters `params` (the model's order) along
/// `traj` (model coordinates): see the module docs. Returns measured coordinates with
/// velocities. Errors name the setting or the mismatch (trajectory size or coordinate
/// names against the model, parameter count, non-finite values, singular coupling).
pub fn simulate(
    model: &Model,
    params: &[f64],
    traj: &FourierTrajectory,
    sim: &Simulation,
) -> Result<JointLog, IdentError> {
    check_inputs(model, params, traj)?;
    let (noise, delay, count) = check_simulation(model.dof(), traj, sim)?;
    let params = match &sim.payload {
        None => Cow::Borrowed(params),
        Some(payload) => {
            let mut with = params.to_vec();
            payload.add_to(model, &mut with, "payload")?;
            Cow::Owned(with)
        }
    };
    let time = uniform_time(count, sim.rate_hz);
    let (q, dq, ddq) = traj.sample(&time);
    let mut tau = torques(model, &params, traj, &time, (&q, &dq, &ddq), &delay);
    if let Some(external) = &sim.external_torque {
        add_external(&mut tau, external, &time, &delay);
    }
    add_noise(&mut tau, &noise, sim.seed);
    let in_model = model_log(model, time, q, dq, tau);
    let measured = to_measured_coordinates(model, &in_model)?;
    measured.validate()?;
    Ok(measured)
}

/// Refuses a trajectory or parameters that do not fit `model`.
fn check_inputs(model: &Model, params: &[f64], traj: &FourierTrajectory) -> Result<(), IdentError> {
    let n = model.dof();
    let mismatch = |message: String| IdentError::Mismatch {
        source_name: "simulation".into(),
        message,
    };
    traj.validate("excitation trajectory")
        .map_err(|e| mismatch(e.to_string()))?;
    if traj.dof() != n {
        return Err(mismatch(format!(
            "the trajectory has {} coordinates but robot {} has {n}",
            traj.dof(),
            model.name
        )));
    }
    if !traj.coordinates.is_empty() && traj.coordinates != model.coordinates {
        return Err(mismatch(format!(
            "the trajectory's coordinates ({}) are not robot {}'s ({})",
            traj.coordinates.join(", "),
            model.name,
            model.coordinates.join(", ")
        )));
    }
    if params.len() != model.n_params() {
        return Err(mismatch(format!(
            "{} parameter values for robot {}'s {} parameters",
            params.len(),
            model.name,
            model.n_params()
        )));
    }
    if let Some(k) = params.iter().position(|v| !v.is_finite()) {
        return Err(mismatch(format!(
            "parameter {} = {} is not finite",
            model.params[k].name, params[k]
        )));
    }
    Ok(())
}

/// Checks the simulation's settings against `n` coordinates; returns the noise standard
/// deviation (N·m or N) and the torque delay (s) of each coordinate, and the number of
/// samples.
fn check_simulation(
    n: usize,
    traj: &FourierTrajectory,
    sim: &Simulation,
) -> Result<(Vec<f64>, Vec<f64>, usize), IdentError> {
    if !(sim.rate_hz.is_finite() && sim.rate_hz > 0.0) {
        return Err(setting(
            "rate",
            format!("must be positive and finite, got {} Hz", sim.rate_hz),
        ));
    }
    if let Some(d) = sim.duration_s {
        if !(d.is_finite() && d > 0.0) {
            return Err(setting(
                "duration",
                format!("must be positive and finite, got {d} s"),
            ));
        }
    }
    let noise = per_coordinate("noise", &sim.noise_std, n)?;
    if let Some(v) = noise.iter().find(|v| !(v.is_finite() && **v >= 0.0)) {
        return Err(setting(
            "noise",
            format!("standard deviations must be finite and non-negative, got {v}"),
        ));
    }
    let delay = per_coordinate("delay", &sim.delay_s, n)?;
    let max_delay = crate::signal::advance::MAX_DELAY_S;
    if let Some(v) = delay
        .iter()
        .find(|v| !(v.is_finite() && **v >= 0.0 && **v <= max_delay))
    {
        return Err(setting(
            "delay",
            format!("delays must be within [0, {max_delay}] s, got {v}"),
        ));
    }
    if let Some(e) = &sim.external_torque {
        if e.tau.ncols() != n || e.time.is_empty() {
            return Err(setting(
                "external_torque",
                format!("{} columns of torques for {n} coordinates", e.tau.ncols()),
            ));
        }
    }
    let count = sim.samples(traj);
    if count < 2 {
        return Err(setting(
            "duration",
            format!("the log would have {count} samples; at least 2 are needed"),
        ));
    }
    if count > MAX_SAMPLES {
        return Err(setting(
            "duration",
            format!(
                "the log would have {count} samples, {} s at {} Hz (more than {MAX_SAMPLES}): \
                 lower the rate or the duration",
                dvrk_model::input::show_approx(sim.duration_s.unwrap_or_else(|| traj.period_s())),
                dvrk_model::input::show(sim.rate_hz)
            ),
        ));
    }
    Ok((noise, delay, count))
}

/// One value per coordinate of `n` from the setting `name`'s `values`: none gives 0 to
/// every coordinate, else [`crate::signal::per_coordinate`]'s rule.
fn per_coordinate(name: &'static str, values: &[f64], n: usize) -> Result<Vec<f64>, IdentError> {
    if values.is_empty() {
        return Ok(vec![0.0; n]);
    }
    crate::signal::per_coordinate(values, n).ok_or_else(|| {
        setting(
            name,
            format!(
                "expected one value or {n} (one per coordinate), got {}",
                values.len()
            ),
        )
    })
}

/// The torques `τ = H(q, q̇, q̈)·π + known forces(q)` at the samples `motion` = `(q, q̇,
/// q̈)` of `traj` at `time`, each coordinate's from the motion `delay[j]` s earlier.
fn torques(
    model: &Model,
    params: &[f64],
    traj: &FourierTrajectory,
    time: &[f64],
    motion: (&DMatrix<f64>, &DMatrix<f64>, &DMatrix<f64>),
    delay: &[f64],
) -> DMatrix<f64> {
    let (q, dq, ddq) = motion;
    let mut tau = DMatrix::zeros(time.len(), model.dof());
    // The torques of each distinct delay from the motion that much earlier (the
    // trajectory is periodic, so before its start too).
    let mut distinct = delay.to_vec();
    distinct.sort_by(f64::total_cmp);
    distinct.dedup();
    for &d in &distinct {
        let t = if d == 0.0 {
            motion_torques(model, params, q, dq, ddq)
        } else {
            let shifted: Vec<f64> = time.iter().map(|t| t - d).collect();
            let (sq, sdq, sddq) = traj.sample(&shifted);
            motion_torques(model, params, &sq, &sdq, &sddq)
        };
        for j in (0..model.dof()).filter(|&j| delay[j] == d) {
            tau.set_column(j, &t.column(j));
        }
    }
    tau
}

/// The torques `τ = H(q, q̇, q̈)·π + known forces(q)` (N·m or N) of `model` with
/// parameters `params` at each sample (row) of the motion `q`, `q̇`, `q̈` (model
/// coordinates: rad or m, per s, per s²): what the joints feel, without noise.
pub fn motion_torques(
    model: &Model,
    params: &[f64],
    q: &DMatrix<f64>,
    dq: &DMatrix<f64>,
    ddq: &DMatrix<f64>,
) -> DMatrix<f64> {
    let (count, n) = (q.nrows(), model.dof());
    let mut ws = Workspace::new(model);
    let mut tau = DMatrix::zeros(count, n);
    let (mut qk, mut dqk, mut ddqk, mut tk) =
        (vec![0.0; n], vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    for k in 0..count {
        for j in 0..n {
            qk[j] = q[(k, j)];
            dqk[j] = dq[(k, j)];
            ddqk[j] = ddq[(k, j)];
        }
        model.advance_hysteresis(&mut ws, &qk);
        model.loaded_inverse_dynamics(&mut ws, params, &qk, &dqk, &ddqk, &mut tk);
        model.add_known_forces(&qk, &mut tk);
        tau.row_mut(k).copy_from_slice(&tk);
    }
    tau
}

/// A simulated log of `model` in its own coordinates (exact velocities), before
/// [`to_measured_coordinates`]: samples at `time` (s), `q`, `q̇`, `τ` one row a sample.
pub fn model_log(
    model: &Model,
    time: Vec<f64>,
    q: DMatrix<f64>,
    dq: DMatrix<f64>,
    tau: DMatrix<f64>,
) -> JointLog {
    JointLog {
        time,
        q,
        dq: Some(dq),
        tau,
        joint_names: model.coordinates.clone(),
        coordinates: Coordinates::Model,
        source: format!("simulated {}", model.name),
    }
}

/// Adds the external torque at each sample's time (coordinate `j` at `t − delay[j]`).
fn add_external(tau: &mut DMatrix<f64>, external: &ExternalTorque, time: &[f64], delay: &[f64]) {
    let n = tau.ncols();
    let mut at = vec![0.0; n];
    for (k, t) in time.iter().enumerate() {
        for j in 0..n {
            external.at(t - delay[j], &mut at);
            tau[(k, j)] += at[j];
        }
    }
}

/// Independent Gaussian noise of standard deviation `noise[j]` added to coordinate `j`
/// of every sample, in sample order (the generator's stream is the same for a seed).
fn add_noise(tau: &mut DMatrix<f64>, noise: &[f64], seed: u64) {
    let (count, n) = tau.shape();
    let mut rng = Gaussian::new(seed);
    for k in 0..count {
        for j in 0..n {
            if noise[j] > 0.0 {
                tau[(k, j)] += noise[j] * rng.sample();
            }
        }
    }
}

/// The inverse of [`crate::fit::to_model_coordinates`]: a model-coordinate trajectory
/// mapped to the robot's measured joints, `q_meas = M q`, `q̇_meas = M q̇`,
/// `τ_meas = M⁻ᵀ τ` (`M` = `model.measured.coupling`), named by the measured joint
/// names. A trajectory already in measured coordinates is returned as it is.
pub fn to_measured_coordinates(model: &Model, log: &JointLog) -> Result<JointLog, IdentError> {
    if log.coordinates == Coordinates::Measured {
        return Ok(log.clone());
    }
    let n = model.dof();
    let mismatch = |message: String| IdentError::Mismatch {
        source_name: log.source.clone(),
        message,
    };
    if log.dof() != n {
        return Err(mismatch(format!(
            "the log has {} joints in model coordinates but robot {} has {n} coordinates",
            log.dof(),
            model.name
        )));
    }
    let m = &model.measured.coupling;
    let minv = model
        .measured_to_model_matrix()
        .ok_or_else(|| mismatch("the robot's coupling matrix is singular".into()))?;
    let mt = m.transpose();
    Ok(JointLog {
        time: log.time.clone(),
        q: &log.q * &mt,
        dq: log.dq.as_ref().map(|d| d * &mt),
        tau: &log.tau * minv,
        joint_names: model.measured.joints.clone(),
        coordinates: Coordinates::Measured,
        source: log.source.clone(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gaussian_moments() {
        let mut g = Gaussian::new(0);
        let n = 200_000;
        let xs: Vec<f64> = (0..n).map(|_| g.sample()).collect();
        let mean = xs.iter().sum::<f64>() / n as f64;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n as f64;
        assert!(mean.abs() < 0.01, "{mean}");
        assert!((var - 1.0).abs() < 0.01, "{var}");
        let mut a = Gaussian::new(7);
        let mut b = Gaussian::new(7);
        assert_eq!(a.sample(), b.sample());
    }
}
