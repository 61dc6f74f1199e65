//! The generalized-momentum observer (De Luca & Mattone, ICRA 2003; Haddadin, De Luca &
//! Albu-Schäffer, "Robot collisions", T-RO 2017): the external joint torque a controller
//! sees in every cycle from `q`, `q̇` and the applied torque `τ`, without an acceleration.
//!
//! **Sign: the torque the model does not explain.** This crate's external torque is
//! `τ_ext = τ − τ_model(q, q̇, q̈)`, the applied (measured) torque minus the model's, as
//! the residual of a log (`dvrk-ident residual`) and a simulation's added torque: what
//! the joints push with beyond the model, e.g. `+g_payload(q)` under a payload. It is the
//! opposite of the torque the environment applies to the robot (the `τ_ext` of De Luca's
//! equations); a collision shows with the other sign here.
//!
//! With `p = M(q)·q̇` the generalized momentum, the equation of motion
//! `M·q̈ + C·q̇ + g + τ_el + τ_known = τ − τ_ext` gives `ṗ = τ + Cᵀ·q̇ − g − τ_el −
//! τ_known − τ_ext` (`Ṁ = C + Cᵀ`), and the observer
//! `r = K·(∫(τ + Cᵀ·q̇ − g − τ_el − τ_known − r) dt − p(t) + p(0))` obeys
//! `ṙ = K·(τ_ext − r)`: each coordinate's estimate follows the external torque through a
//! first-order lag of time constant `1/K` (s).
//!
//! **The model's known torque.** `τ_el` are the elements' torques at zero acceleration
//! (friction, springs, any element that is not an acceleration term) and `τ_known` the
//! known forces (the MTM's cable), exactly as [`Model::forward_dynamics_into`] subtracts
//! them from the applied torque; motor inertias are acceleration terms and sit in `M`
//! (constant, so they add to `p` and not to `Ṁ`). Whatever the identified model does not
//! explain — contact, a payload, unmodelled friction — is `τ_ext`.
//!
//! **Discrete time, from the crate's own `M` and `h`.** Over a step the only term that is
//! not a plain integral of the sampled torques is `∫Ṁ·q̇ dt` (inside `Cᵀ·q̇ = Ṁ·q̇ − C·q̇`).
//! The trapezoid rule on it, `(M_k − M_{k−1})·(q̇_k + q̇_{k−1})/2`, makes the momentum
//! change `Δp − ∫Ṁ·q̇ dt` equal `M̄·Δq̇` with `M̄ = (M_k + M_{k−1})/2`, so one update needs
//! the mass matrix and `h = C·q̇ + g + τ_el + τ_known` (both from one kinematics pass, the
//! pair forward dynamics uses), never `C` itself:
//! `Δy = dt·((τ − h)_k + (τ − h)_{k−1})/2 − M̄·(q̇_k − q̇_{k−1})` is the integral of the
//! external torque over the step (second order in `dt`), and the lag is discretized
//! exactly for a torque constant over the step, `r_k = α·r_{k−1} + (1 − α)·Δy/dt` with
//! `α = e^{−K·dt}`. An external torque step between two samples is therefore followed by
//! `r = τ_ext·(1 − e^{−K·(t − t_step)})` at the samples, to the trapezoid's half-sample
//! rounding of the step's instant. A real joint's Coulomb friction switches sign
//! between two samples while the model's switches at a sample: the step of a velocity
//! reversal is off by at most the friction jump over that step, a kick of at most
//! `(1 − α)·|jump|` in the estimate that decays with the lag.

use crate::model::Model;
use crate::workspace::Workspace;

/// A momentum-observer gain that is not positive and finite, or a gain vector of the
/// wrong length.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("momentum observer: {0}")]
pub struct InvalidGain(String);

/// The generalized-momentum observer of one model (see the module documentation): its
/// gains and the previous sample. One [`MomentumObserver::update`] per control cycle;
/// nothing allocates after [`MomentumObserver::new`].
///
/// ```
/// # use dvrk_model::{Model, Workspace, MomentumObserver};
/// let model = Model::builtin("psm").unwrap();
/// let mut ws = Workspace::new(&model);
/// let params = vec![0.01; model.n_params()];
/// // 50 /s per coordinate: a 20 ms time constant.
/// let mut observer = MomentumObserver::new(&model, &[50.0; 7]).unwrap();
/// let (q, dq, tau) = ([0.1; 7], [0.0; 7], [0.0; 7]);
/// let first = observer.update(&model, &mut ws, &params, &q, &dq, &tau, 0.001);
/// assert_eq!(first, &[0.0; 7]); // the first sample only starts the observer
/// ```
#[derive(Clone, Debug)]
pub struct MomentumObserver {
    /// K per coordinate, 1/s.
    gains: Vec<f64>,
    /// `e^{−K·dt}` for `alpha_dt` (s), recomputed when the step changes.
    alpha: Vec<f64>,
    alpha_dt: f64,
    /// The estimate of the external torque, N·m or N per coordinate.
    estimate: Vec<f64>,
    /// Whether a previous sample is stored.
    started: bool,
    /// The previous sample's `q̇`, `τ − h` and mass matrix (n×n column-major).
    dq_prev: Vec<f64>,
    net_prev: Vec<f64>,
    mass_prev: Vec<f64>,
    /// This sample's `τ − h` and mass matrix (swapped with the previous ones).
    net: Vec<f64>,
    mass: Vec<f64>,
}

impl MomentumObserver {
    /// An observer for `model` with gain `gains[k]` (1/s, positive and finite; the time
    /// constant of coordinate `k` is `1/gains[k]`): one per coordinate.
    pub fn new(model: &Model, gains: &[f64]) -> Result<Self, InvalidGain> {
        let n = model.dof();
        if gains.len() != n {
            return Err(InvalidGain(format!(
                "{} gains for {} coordinates ({})",
                gains.len(),
                n,
                model.coordinates.join(", ")
            )));
        }
        if let Some((k, g)) = gains
            .iter()
            .enumerate()
            .find(|(_, g)| !(g.is_finite() && **g > 0.0))
        {
            return Err(InvalidGain(format!(
                "the gain of {} must be positive and finite (1/s), got {g}",
                model.coordinates[k]
            )));
        }
        Ok(MomentumObserver {
            gains: gains.to_vec(),
            alpha: vec![0.0; n],
            alpha_dt: f64::NAN,
            estimate: vec![0.0; n],
            started: false,
            dq_prev: vec![0.0; n],
            net_prev: vec![0.0; n],
            mass_prev: vec![0.0; n * n],
            net: vec![0.0; n],
            mass: vec![0.0; n * n],
        })
    }

    /// The gains, 1/s per coordinate.
    pub fn gains(&self) -> &[f64] {
        &self.gains
    }

    /// The current estimate of the external torque (N·m or N per coordinate; zeros
    /// before the second update).
    pub fn estimate(&self) -> &[f64] {
        &self.estimate
    }

    /// Forgets the previous sample and the estimate: the next update starts again (at
    /// zero), as after a jump in time or a change of tool.
    pub fn reset(&mut self) {
        self.started = false;
        self.estimate.fill(0.0);
    }

    /// One control cycle: the sample `q` (rad or m), `q̇` (rad/s or m/s) and applied
    /// torque `tau` (N·m or N, as measured: the known forces are the model's), `dt` (s)
    /// after the previous update. Returns the estimate of the external torque `τ −
    /// τ_model` (see the module documentation for the sign), N·m or N per coordinate. The first update (and the first after [`MomentumObserver::reset`])
    /// only stores the sample and returns zeros. Allocates nothing.
    ///
    /// # Panics
    /// If `dt` is not positive and finite, a vector's length is not the model's, or the
    /// workspace or observer was made for another model.
    #[allow(clippy::too_many_arguments)]
    pub fn update(
        &mut self,
        model: &Model,
        ws: &mut Workspace,
        params: &[f64],
        q: &[f64],
        dq: &[f64],
        tau: &[f64],
        dt: f64,
    ) -> &[f64] {
        let n = model.dof();
        model.check_state(ws, params, &[q, dq, tau]);
        assert_eq!(
            self.gains.len(),
            n,
            "observer was created for another model"
        );
        assert!(dt > 0.0 && dt.is_finite(), "observer step dt = {dt} s");
        model.bias_and_mass(ws, params, q, dq, &mut self.net, &mut self.mass);
        for (h, t) in self.net.iter_mut().zip(tau) {
            *h = t - *h;
        }
        if self.started {
            if dt != self.alpha_dt {
                for (a, k) in self.alpha.iter_mut().zip(&self.gains) {
                    *a = (-k * dt).exp();
                }
                self.alpha_dt = dt;
            }
            // Δq̇ once (into the previous velocity, replaced below), not per row.
            for (d, v) in self.dq_prev.iter_mut().zip(dq) {
                *d = v - *d;
            }
            let change = &self.dq_prev[..n];
            for i in 0..n {
                // Row i of 2·M̄·Δq̇ (both matrices symmetric: column i).
                let (now, before) = (&self.mass[i * n..][..n], &self.mass_prev[i * n..][..n]);
                let mut momentum = 0.0;
                for ((a, b), d) in now.iter().zip(before).zip(change) {
                    momentum += (a + b) * d;
                }
                // Δy/dt: the mean of τ − h over the step minus M̄·Δq̇/dt.
                let mean = 0.5 * (self.net[i] + self.net_prev[i]) - 0.5 * momentum / dt;
                let a = self.alpha[i];
                self.estimate[i] = a * self.estimate[i] + (1.0 - a) * mean;
            }
        } else {
            self.estimate.fill(0.0);
            self.started = true;
        }
        std::mem::swap(&mut self.mass, &mut self.mass_prev);
        std::mem::swap(&mut self.net, &mut self.net_prev);
        self.dq_prev.copy_from_slice(dq);
        &self.estimate
    }
}
