//! The state and parameters every benchmark uses (`dynamics.rs`, `count.rs`).

use dvrk_model::inertia::barycentric_from_standard;
use dvrk_model::Model;

/// The Panda URDF of `../shared/anchors` beside the repository.
pub const PANDA: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../../shared/anchors/panda_arm_7dof.urdf"
);

/// A fixed state vector of length `n` (rad, m or their rates), `k` telling them apart.
pub fn sample(n: usize, k: f64) -> Vec<f64> {
    (0..n).map(|i| 0.1 * k + 0.07 * i as f64).collect()
}

/// Physical parameters (forward dynamics needs a positive definite mass matrix): the
/// description's nominal values when it has them all (the Panda URDF), else every link
/// 1 kg with a box-like inertia, friction, motor inertias and springs.
pub fn physical(model: &Model) -> Vec<f64> {
    if let Some(p) = model.nominal_parameters() {
        return p;
    }
    let mut pi = vec![0.0; model.n_params()];
    for (i, f) in model.frames.iter().enumerate() {
        let k = i as f64;
        if let Some(p0) = f.inertia {
            let link = barycentric_from_standard(
                1.0 + 0.1 * k,
                [0.01 * k, -0.02, 0.03],
                [0.004, 0.0005, 0.0, 0.005, -0.0003, 0.003],
            );
            pi[p0..p0 + 10].copy_from_slice(&link);
        }
        if let Some(fr) = f.friction() {
            pi[fr.param..fr.param + 3].copy_from_slice(&[0.1, 0.05, 0.01]);
        }
        if let Some(mi) = f.motor_inertia() {
            pi[mi.param] = 0.01;
        }
        if let Some(sp) = f.spring() {
            pi[sp.param] = 0.2;
        }
    }
    pi
}
