//! The generalized-momentum observer against its closed-form response: on a simulated
//! PSM whose applied torque is the inverse dynamics (links, friction, springs, motor
//! inertias, from Newton–Euler, independent of the observer's mass matrix) plus an
//! external torque step (the crate's sign: measured minus model), each coordinate's estimate must follow `τ_ext·(1 − e^{−K·(t − t_step)})`,
//! the first-order response of time constant `1/K`.

// Reads the built-in description (TOML): needs the default `description` feature.
#![cfg(feature = "description")]

use dvrk_model::{Model, MomentumObserver, Workspace};
use dvrk_test_support as support;

/// A smooth motion of every coordinate (rad or m): a drift plus two harmonics, with
/// velocities and accelerations that give the Coriolis terms some weight.
fn motion(k: usize, t: f64) -> [f64; 3] {
    let (amp, w, phase) = (
        0.3 / (1.0 + 0.2 * k as f64),
        2.0 + 0.7 * k as f64,
        0.4 * k as f64,
    );
    let scale = if k == 2 { 0.05 } else { 1.0 }; // the insertion is in m
    let (s1, c1) = (w * t + phase).sin_cos();
    let (s2, c2) = (2.3 * w * t).sin_cos();
    let q = 0.2 + 0.5 * t + amp * s1 + 0.3 * amp * s2;
    let dq = 0.5 + amp * w * c1 + 0.3 * amp * 2.3 * w * c2;
    let ddq = -amp * w * w * s1 - 0.3 * amp * (2.3 * w).powi(2) * s2;
    [scale * q, scale * dq, scale * ddq]
}

/// Runs the observer over `duration` s at step `dt` with an external torque `step`
/// applied from `t_step` on, and returns the largest error after three time constants
/// of the slowest coordinate, relative to the step, per coordinate, and the same
/// before the step (absolute, N·m or N).
fn step_response(params: &[f64], gains: &[f64], step: &[f64], dt: f64) -> (Vec<f64>, Vec<f64>) {
    let model = Model::builtin("psm").unwrap();
    let n = model.dof();
    let mut ws = Workspace::new(&model);
    let mut observer = MomentumObserver::new(&model, gains).unwrap();
    let steps = (1.5 / dt).round() as usize;
    let j_step = steps / 3;
    // The trapezoid sees a step applied from sample j_step on as one half a step earlier.
    let t_step = (j_step as f64 - 0.5) * dt;
    let settle = 3.0 / gains.iter().cloned().fold(f64::INFINITY, f64::min);
    let (mut after, mut before) = (vec![0.0f64; n], vec![0.0f64; n]);
    let mut tau = vec![0.0; n];
    for j in 0..steps {
        let t = j as f64 * dt;
        let (mut q, mut dq, mut ddq) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        for k in 0..n {
            [q[k], dq[k], ddq[k]] = motion(k, t);
        }
        model.inverse_dynamics(&mut ws, params, &q, &dq, &ddq, &mut tau);
        model.add_known_forces(&q, &mut tau);
        let applied = j >= j_step;
        if applied {
            for (t, s) in tau.iter_mut().zip(step) {
                *t += s;
            }
        }
        let r = observer.update(&model, &mut ws, params, &q, &dq, &tau, dt);
        for k in 0..n {
            if !applied {
                before[k] = before[k].max(r[k].abs());
            } else if t - t_step >= settle {
                let expected = step[k] * (1.0 - (-gains[k] * (t - t_step)).exp());
                after[k] = after[k].max((r[k] - expected).abs() / step[k].abs());
            }
        }
    }
    (after, before)
}

/// `v` in scientific notation, for the record.
fn sci(v: &[f64]) -> String {
    v.iter()
        .map(|x| format!("{x:.2e}"))
        .collect::<Vec<_>>()
        .join(" ")
}

fn psm_params(coulomb: bool) -> Vec<f64> {
    let model = Model::builtin("psm").unwrap();
    let mut params = support::physical_params(&model, &mut support::Rng::new(31));
    if !coulomb {
        for f in &model.frames {
            if let Some(fr) = f.friction() {
                params[fr.param] = 0.0;
            }
        }
    }
    params
}

/// Viscous and offset friction, springs and motor inertias: every torque is smooth, and
/// the estimate is the first-order response within 1 % of the step after three time
/// constants (1 kHz, gains 20–80 /s).
#[test]
fn psm_observer_follows_the_first_order_response_to_a_torque_step() {
    let gains = [20.0, 30.0, 40.0, 50.0, 60.0, 70.0, 80.0];
    let step = [0.4, -0.3, 2.0, 0.05, -0.04, 0.03, 0.02];
    let (after, before) = step_response(&psm_params(false), &gains, &step, 1e-3);
    eprintln!("relative error after 3 time constants: {}", sci(&after));
    eprintln!("|estimate| before the step (N·m, N): {}", sci(&before));
    for k in 0..7 {
        assert!(after[k] < 0.01, "q{}: {:.3e} of the step", k + 1, after[k]);
        assert!(
            before[k] < 0.01 * step[k].abs(),
            "q{}: {:.3e} before the step",
            k + 1,
            before[k]
        );
    }
}

/// The same at 5 kHz: the discretization's error (second order in `dt`) shrinks.
#[test]
fn psm_observer_error_shrinks_with_the_step() {
    let gains = [20.0, 30.0, 40.0, 50.0, 60.0, 70.0, 80.0];
    let step = [0.4, -0.3, 2.0, 0.05, -0.04, 0.03, 0.02];
    let params = psm_params(false);
    let (coarse, _) = step_response(&params, &gains, &step, 1e-3);
    let (fine, _) = step_response(&params, &gains, &step, 2e-4);
    eprintln!("1 kHz: {}\n5 kHz: {}", sci(&coarse), sci(&fine));
    let worst = |v: &[f64]| v.iter().cloned().fold(0.0, f64::max);
    assert!(worst(&fine) < worst(&coarse) / 4.0);
}

/// With Coulomb friction too (the PSM's velocities reverse during the run): the model's
/// own friction is in `h`, subtracted sample by sample, and the estimate is still the
/// first-order response within 1 %.
#[test]
fn coulomb_friction_is_the_models_known_torque() {
    let gains = [20.0, 30.0, 40.0, 50.0, 60.0, 70.0, 80.0];
    let step = [0.4, -0.3, 2.0, 0.05, -0.04, 0.03, 0.02];
    let params = psm_params(true);
    // The run has reversals: some coordinate's velocity changes sign.
    let reverses = (0..7).any(|k| {
        (1..1500).any(|j| motion(k, j as f64 * 1e-3)[1] * motion(k, (j - 1) as f64 * 1e-3)[1] < 0.0)
    });
    assert!(reverses);
    let (after, _) = step_response(&params, &gains, &step, 1e-3);
    eprintln!(
        "with Coulomb friction, relative error after 3 time constants: {}",
        sci(&after)
    );
    assert!(after.iter().all(|e| *e < 0.01));
}

#[test]
fn observer_gains_are_checked() {
    let model = Model::builtin("psm").unwrap();
    let e = MomentumObserver::new(&model, &[1.0; 6]).unwrap_err();
    assert!(e.to_string().contains("6 gains for 7 coordinates"), "{e}");
    let e = MomentumObserver::new(&model, &[1.0, 1.0, -2.0, 1.0, 1.0, 1.0, 1.0]).unwrap_err();
    assert!(e.to_string().contains("must be positive and finite"), "{e}");
    let e = MomentumObserver::new(&model, &[f64::NAN; 7]).unwrap_err();
    assert!(e.to_string().contains("got NaN"), "{e}");
}
