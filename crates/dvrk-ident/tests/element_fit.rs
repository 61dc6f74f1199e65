//! The estimator sees elements only through `dvrk_model::Element` (bounds, clamping,
//! unit classes): an element added in one module of dvrk-model, the quadratic viscous
//! friction `Fq·ṡ·|ṡ|`, is fitted with no change here. Noise-free synthetic torques of a
//! pendulum: least squares and the semidefinite fit recover `Fq`; torques asking for a
//! a negative `Fq` (or one above its `max`) get the bound from the SDP, never beyond.

use dvrk_test_support as support;

use dvrk_ident::estimate::sdp::{solve_sdp, SdpOptions};
use dvrk_model::{inertia, Model, Workspace};
use nalgebra::{DMatrix, DVector};
use support::models::one_link_with;
use support::Rng;

/// The pendulum: one link with friction and quadratic viscous friction of at most 1.
fn pendulum() -> Model {
    let text = one_link_with("friction = true\nquadratic_viscous = { max = 1.0 }\n");
    Model::from_toml_str(&text, "pendulum.toml").unwrap()
}

/// Column of `Fq1` (after the ten link parameters and `Fc1 Fv1 Fo1`).
const FQ: usize = 13;

/// The stacked regressor and torques of `samples` random states for parameters `pi`.
fn observe(model: &Model, pi: &[f64], samples: usize) -> (DMatrix<f64>, DVector<f64>) {
    let p = model.n_params();
    let mut ws = Workspace::new(model);
    let mut rng = Rng::new(7);
    let mut h = DMatrix::zeros(samples, p);
    let mut row = vec![0.0; p];
    for k in 0..samples {
        let (q, dq, ddq) = (
            [rng.uniform(-2.0, 2.0)],
            [rng.uniform(-3.0, 3.0)],
            [rng.uniform(-5.0, 5.0)],
        );
        model.regressor_into(&mut ws, &q, &dq, &ddq, &mut row);
        h.row_mut(k).copy_from_slice(&row);
    }
    let tau = &h * DVector::from_column_slice(pi);
    (h, tau)
}

/// The R factor of `[H | τ]`, as the observation reduces a log.
fn r_factor(h: &DMatrix<f64>, tau: &DVector<f64>) -> DMatrix<f64> {
    let mut ht = DMatrix::zeros(h.nrows(), h.ncols() + 1);
    ht.view_mut((0, 0), (h.nrows(), h.ncols())).copy_from(h);
    ht.set_column(h.ncols(), tau);
    ht.qr().r()
}

fn truth(model: &Model, fq: f64) -> Vec<f64> {
    let mut pi = vec![0.0; model.n_params()];
    let link = inertia::barycentric_from_standard(
        1.2,
        [0.1, 0.02, 0.0],
        [0.01, 0.0, 0.0, 0.012, 0.0, 0.008],
    );
    pi[..10].copy_from_slice(&link);
    pi[10..13].copy_from_slice(&[0.08, 0.03, -0.01]);
    pi[FQ] = fq;
    pi
}

#[test]
fn sdp_recovers_quadratic_viscous_friction() {
    let model = pendulum();
    assert_eq!(model.param_names()[FQ], "Fq1");
    let pi = truth(&model, 0.05);
    let (h, tau) = observe(&model, &pi, 400);
    // Least squares on the identifiable columns sees Fq (its column is independent).
    let base = model.base_parameters().unwrap();
    assert!(base.independent.contains(&FQ));
    let r = r_factor(&h, &tau);
    let sol = solve_sdp(&model, &r, &SdpOptions::default()).unwrap();
    assert!(sol.converged, "status {}", sol.status);
    assert!(
        (sol.params[FQ] - 0.05).abs() < 1e-6,
        "Fq {}",
        sol.params[FQ]
    );
    // The friction too (noise-free data).
    for (k, want) in [(10, 0.08), (11, 0.03), (12, -0.01)] {
        assert!(
            (sol.params[k] - want).abs() < 1e-6,
            "{k}: {}",
            sol.params[k]
        );
    }
}

#[test]
fn sdp_holds_quadratic_viscous_friction_at_its_bounds() {
    let model = pendulum();
    for (fq, bound) in [(-0.05, 0.0), (1.5, 1.0)] {
        let (h, tau) = observe(&model, &truth(&model, fq), 400);
        let r = r_factor(&h, &tau);
        let sol = solve_sdp(&model, &r, &SdpOptions::default()).unwrap();
        assert!(sol.converged, "status {}", sol.status);
        // At the bound, and never beyond it (the element clamps a solver's miss away).
        let got = sol.params[FQ];
        assert!((got - bound).abs() < 1e-6, "data Fq {fq}: {got}");
        assert!((0.0..=1.0).contains(&got), "data Fq {fq}: {got}");
        // Without the frame's bounds only the physical one remains.
        let free = SdpOptions {
            override_bounds: true,
            ..SdpOptions::default()
        };
        let sol = solve_sdp(&model, &r, &free).unwrap();
        assert!(sol.converged, "status {}", sol.status);
        let want = fq.max(0.0);
        assert!(
            (sol.params[FQ] - want).abs() < 1e-6,
            "Fq {} vs {want}",
            sol.params[FQ]
        );
    }
}
