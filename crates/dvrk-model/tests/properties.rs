//! Property tests (proptest, stable Rust): `H(q, q̇, q̈)·π` equals the inverse dynamics
//! for any state and any parameter vector (not only physical ones), on every built-in
//! robot and the MTM with Stribeck friction terms. The seed is fixed, so a run is
//! reproducible.

// Reads descriptions (TOML, URDF): needs the default `description` feature.
#![cfg(feature = "description")]

use dvrk_test_support as support;

use dvrk_model::{Model, Workspace};
use dvrk_test_support::fixed_seed_config;
use proptest::prelude::*;
use support::id;

/// The built-in robots (parallelograms, tendon couplings, springs, the MTM cable) and
/// the MTM with a Stribeck term on every friction element.
fn models() -> Vec<Model> {
    let mut v: Vec<Model> = Model::builtin_names()
        .iter()
        .map(|n| Model::builtin(n).unwrap())
        .collect();
    v.push(Model::builtin("mtm").unwrap().with_stribeck(0.3).unwrap());
    v
}

proptest! {
    #![proptest_config(fixed_seed_config(64))]

    #[test]
    fn regressor_times_params_is_inverse_dynamics(
        robot in 0usize..4,
        // Coordinates within ±4 rad or m, rates up to 20 rad/s and 200 rad/s².
        state in proptest::collection::vec((-4.0f64..4.0, -20.0f64..20.0, -200.0f64..200.0), 7),
        params in proptest::collection::vec(-10.0f64..10.0, 160),
    ) {
        let models = models();
        let model = &models[robot];
        let (n, p) = (model.dof(), model.n_params());
        prop_assert!(n <= state.len() && p <= params.len());
        let q: Vec<f64> = state[..n].iter().map(|s| s.0).collect();
        let dq: Vec<f64> = state[..n].iter().map(|s| s.1).collect();
        let ddq: Vec<f64> = state[..n].iter().map(|s| s.2).collect();
        let pi = &params[..p];
        let mut ws = Workspace::new(model);
        let tau = id(model, &mut ws, pi, &q, &dq, &ddq);
        let h = model.regressor(&mut ws, &q, &dq, &ddq);
        for row in 0..n {
            let terms: Vec<f64> = (0..p).map(|c| h[(row, c)] * pi[c]).collect();
            let hp: f64 = terms.iter().sum();
            // Round-off of a sum is relative to the sum of magnitudes.
            let scale = terms.iter().map(|t| t.abs()).sum::<f64>().max(1e-300);
            prop_assert!(
                (hp - tau[row]).abs() <= 1e-10 * scale,
                "{}: row {row}: H·π = {hp}, inverse dynamics {}", model.name, tau[row]
            );
        }
    }
}
