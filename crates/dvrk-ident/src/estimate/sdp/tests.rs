//! The semidefinite fit's tests ([`super::solve_sdp`] and its LMI rows): closed forms
//! (a Euclidean projection, the Stribeck sum, the projection onto a bounding
//! ellipsoid), synthetic PSM/MTM fits that recover their base parameters, infeasible
//! bounds and bad input; the priors' in `prior`.

use super::constraints::lmi_rows;
use super::*;
use dvrk_model::inertia::{
    barycentric_from_standard, pseudo_inertia, pseudo_inertia_min_eigenvalue, sym6,
};
use dvrk_test_support::models::{one_link_with, ONE_LINK};
use dvrk_test_support::Rng;
use nalgebra::{DVector, Matrix3, Matrix4, Rotation3, Vector3};

mod prior;

/// Upper-triangular (p+1)×(p+1) R of `[h | tau]` by Householder QR (zero rows
/// appended when there are fewer than p+1 rows).
fn r_factor(h: &DMatrix<f64>, tau: &DVector<f64>) -> DMatrix<f64> {
    let np1 = h.ncols() + 1;
    let mut ht = DMatrix::zeros(h.nrows().max(np1), np1);
    ht.view_mut((0, 0), (h.nrows(), h.ncols())).copy_from(h);
    ht.view_mut((0, h.ncols()), (h.nrows(), 1)).copy_from(tau);
    ht.qr().r()
}

/// Friction bounds of [`one_link`]'s frame.
const FRICTION_BOUNDS: &str = "bounds = { fc_max = 0.3, fv_max = 2.0, fo_max = 0.3 }";

/// One link with friction within [`FRICTION_BOUNDS`].
fn one_link() -> String {
    one_link_with(&format!("friction = true\n{FRICTION_BOUNDS}\n"))
}

/// Any symmetric-matrix vectorization that preserves the Frobenius norm
/// (independent of the solver's triangle order): diagonal then √2·(strict upper),
/// row by row.
fn frob_vec(j: &Matrix4<f64>) -> Vec<f64> {
    let mut v = Vec::new();
    for i in 0..4 {
        v.push(j[(i, i)]);
    }
    for i in 0..4 {
        for k in i + 1..4 {
            v.push(std::f64::consts::SQRT_2 * j[(i, k)]);
        }
    }
    v
}

/// Columns 0..10 of `g` (rows 0..10): column k = `frob_vec(J(e_k))`, so that
/// `‖G·π − frob_vec(J_t)‖ = ‖J(π) − J_t‖_F` on a link's 10 parameters (invertible).
fn frobenius_columns(g: &mut DMatrix<f64>) {
    for k in 0..10 {
        let mut e = [0.0; 10];
        e[k] = 1.0;
        for (i, v) in frob_vec(&pseudo_inertia(&e)).into_iter().enumerate() {
            g[(i, k)] = v;
        }
    }
}

/// With `‖R11·π − r1‖ = ‖J(π) − J_t‖_F` (link) and `R11 = I` (friction), the SDP is
/// a Euclidean projection with a closed form: clip J_t's eigenvalues at eps, clip the
/// friction parameters into their bounds.
#[test]
fn sdp_tiny_projection_has_closed_form() {
    let model = Model::from_toml_str(&one_link(), "one_link.toml").unwrap();
    assert_eq!(model.n_params(), 13);
    let eps = model.bounds.pseudo_inertia_eps;
    // Target: a "link" whose inertia violates the triangle inequality and whose
    // pseudo-inertia has a clearly negative eigenvalue.
    let target_link =
        barycentric_from_standard(0.8, [0.05, -0.02, 0.1], [0.001, 0.0, 0.0, 0.001, 0.0, 0.01]);
    let jt = pseudo_inertia(&target_link);
    assert!(pseudo_inertia_min_eigenvalue(&target_link) < -1e-3);
    // Fc < fc_min, Fv > fv_max, Fo < -fo_max, by about the link's distance to
    // consistency (a residual much larger than the link's would hide the link's
    // part below the solver's tolerance).
    let target_friction = [-0.002, 2.003, -0.304];
    // G: column k = frob_vec(J(e_k)) (10×10, invertible), friction block identity.
    let mut g = DMatrix::zeros(13, 13);
    frobenius_columns(&mut g);
    for k in 10..13 {
        g[(k, k)] = 1.0;
    }
    let mut rhs = DVector::zeros(13);
    for (i, v) in frob_vec(&jt).into_iter().enumerate() {
        rhs[i] = v;
    }
    for k in 0..3 {
        rhs[10 + k] = target_friction[k];
    }
    let r = r_factor(&g, &rhs);
    let options = SdpOptions {
        regularization: 0.0,
        tolerance: 1e-10,
        ..SdpOptions::default()
    };
    let sol = solve_sdp(&model, &r, &options).unwrap();
    assert!(sol.converged, "status {}", sol.status);
    assert_eq!(sol.status, crate::estimate::SolverStatus::Solved);

    // Closed form of the link part: eigenvalues of J_t clipped at eps.
    let eig = jt.symmetric_eigen();
    let clipped = eig.eigenvalues.map(|l| l.max(eps));
    let j_star = eig.eigenvectors * Matrix4::from_diagonal(&clipped) * eig.eigenvectors.transpose();
    let j_sol = pseudo_inertia(&sol.params[0..10]);
    let err = (j_sol - j_star).norm();
    assert!(err < 1e-6 * jt.norm(), "J error {err:e}\n{j_sol}\n{j_star}");
    assert!(pseudo_inertia_min_eigenvalue(&sol.params[0..10]) >= eps * (1.0 - 1e-3));
    // Friction: projection onto [fc_min, fc_max] × [fv_min, fv_max] × [-fo, fo].
    let expected = [model.bounds.fc_min, 2.0, -0.3];
    for (k, want) in expected.into_iter().enumerate() {
        let got = sol.params[10 + k];
        assert!((got - want).abs() < 1e-7, "friction {k}: {got} vs {want}");
    }
    // The reported objective is the data term at the solution.
    let want = (j_sol - jt).norm_squared()
        + (0..3)
            .map(|k| (sol.params[10 + k] - target_friction[k]).powi(2))
            .sum::<f64>();
    assert!((sol.objective - want).abs() < 1e-8 * want.max(1.0));
}

/// With `R11 = I` on the friction block, `(Fc, Fs)` is the Euclidean projection of
/// the target onto `Fc + Fs ≥ 0`: `(Fc, Fs) − min(0, Fc + Fs)/2·(1, 1)`. The solver
/// meets the constraint only to its tolerance, a hair on either side; the solution
/// returned meets it exactly (the verdict of a fit checks the sign with no slack
/// beyond 1e-9, and a converged fit once failed it at −3e-9).
#[test]
fn sdp_stribeck_sum_holds_exactly() {
    let model = Model::from_toml_str(&one_link(), "one_link.toml")
        .unwrap()
        .with_stribeck(0.3)
        .unwrap();
    let p = model.n_params();
    let (fc, fs) = (
        model.frames[0].friction().unwrap().param,
        model.frames[0].stribeck().unwrap().param,
    );
    let mut rng = Rng::new(0x5eed_1234);
    for _ in 0..12 {
        // A consistent link (identity rows: its target is feasible), Fc and Fs with
        // a negative sum of a few hundredths.
        let link = barycentric_from_standard(
            0.5,
            [0.01, 0.02, 0.03],
            [0.002, 0.0, 0.0, 0.002, 0.0, 0.001],
        );
        let target_fc = rng.uniform(0.01, 0.2);
        let target_fs = -target_fc - rng.uniform(0.001, 0.1);
        let mut rhs = DVector::zeros(p);
        for k in 0..10 {
            rhs[k] = link[k];
        }
        rhs[fc] = target_fc;
        rhs[fc + 1] = 0.5;
        rhs[fs] = target_fs;
        let r = r_factor(&DMatrix::identity(p, p), &rhs);
        let sol = solve_sdp(&model, &r, &SdpOptions::default()).unwrap();
        assert!(sol.converged, "status {}", sol.status);
        let sum = sol.params[fc] + sol.params[fs];
        assert!(sum >= 0.0, "Fc + Fs = {sum:e}");
        let shift = (target_fc + target_fs) / 2.0;
        assert!((sol.params[fc] - (target_fc - shift)).abs() < 1e-6);
        assert!((sol.params[fs] - (target_fs - shift)).abs() < 1e-6);
    }
}

/// The LMI rows (A, b of `s = b − A·π`, triangle order, √2) unpack to `J(π) − eps·I`.
#[test]
fn sdp_lmi_rows_reproduce_pseudo_inertia() {
    let mut rng = Rng::new(0x1234_5678_9abc_def1);
    for trial in 0..20 {
        let p0 = trial % 3;
        let pi: Vec<f64> = (0..p0 + 10).map(|_| rng.uniform(-2.0, 2.0)).collect();
        let eps = rng.uniform(0.0, 0.1);
        let tau = if trial % 2 == 0 {
            1.0
        } else {
            rng.uniform(0.05, 2.0)
        };
        let rows = lmi_rows(p0, eps, tau);
        assert_eq!(rows.len(), 10);
        // Unpack svec (upper triangle, column-major, off-diagonals ×√2).
        let mut s = Matrix4::zeros();
        let mut k = 0;
        for col in 0..4 {
            for row in 0..=col {
                let (a, b) = &rows[k];
                let ax: f64 = a.iter().map(|&(c, v)| v * pi[c]).sum();
                let mut v = b - ax;
                if row != col {
                    v /= std::f64::consts::SQRT_2;
                }
                s[(row, col)] = v;
                s[(col, row)] = v;
                k += 1;
            }
        }
        let t = Matrix4::from_diagonal(&nalgebra::Vector4::new(1.0, 1.0, 1.0, tau));
        let want = t * (pseudo_inertia(&pi[p0..p0 + 10]) - eps * Matrix4::identity()) * t;
        assert!((s - want).norm() < 1e-12, "trial {trial}\n{s}\n{want}");
    }
}

/// Random physically consistent parameters inside the model's bounds.
fn random_consistent(model: &Model, rng: &mut Rng) -> Vec<f64> {
    let g = &model.bounds;
    let mut pi = vec![0.0; model.n_params()];
    for f in &model.frames {
        let b = &f.bounds;
        if let Some(p0) = f.inertia {
            let inner = |lo: f64, hi: f64, rng: &mut Rng| {
                let w = hi - lo;
                rng.uniform(lo + 0.05 * w, hi - 0.05 * w)
            };
            let [mlo, mhi] = b.mass.unwrap_or([0.1, 2.0]);
            let com = b.com.unwrap_or([[-0.1, 0.1]; 3]);
            let bary = loop {
                let m = inner(mlo, mhi, rng);
                let c = [
                    inner(com[0][0], com[0][1], rng),
                    inner(com[1][0], com[1][1], rng),
                    inner(com[2][0], com[2][1], rng),
                ];
                // Solid box a×b×c, randomly rotated (smaller inside a bounding ellipsoid).
                let side = if b.ellipsoid.is_some() { 0.1 } else { 0.4 };
                let (x, y, z) = (
                    rng.uniform(0.03, side),
                    rng.uniform(0.03, side),
                    rng.uniform(0.03, side),
                );
                let d = Matrix3::from_diagonal(&Vector3::new(
                    m * (y * y + z * z) / 12.0,
                    m * (x * x + z * z) / 12.0,
                    m * (x * x + y * y) / 12.0,
                ));
                let rot = Rotation3::from_euler_angles(
                    rng.uniform(-3.0, 3.0),
                    rng.uniform(-3.0, 3.0),
                    rng.uniform(-3.0, 3.0),
                );
                let ic = rot.matrix() * d * rot.matrix().transpose();
                let bary = barycentric_from_standard(m, c, sym6(&ic));
                // Strictly inside the link's bounding ellipsoid, if it has one.
                let inside = b
                    .ellipsoid
                    .as_ref()
                    .is_none_or(|e| (e.q_matrix() * pseudo_inertia(&bary)).trace() > 0.05 * m);
                if inside && pseudo_inertia_min_eigenvalue(&bary) > 20.0 * g.pseudo_inertia_eps {
                    break bary;
                }
            };
            pi[p0..p0 + 10].copy_from_slice(&bary);
        }
        if let Some(fr) = f.friction() {
            pi[fr.param] = rng.uniform(g.fc_min, b.fc_max.unwrap_or(0.5));
            pi[fr.param + 1] = rng.uniform(g.fv_min, b.fv_max.unwrap_or(0.5));
            let fo = b.fo_max.unwrap_or(0.3);
            pi[fr.param + 2] = rng.uniform(-fo, fo);
        }
        if let Some(mi) = f.motor_inertia() {
            pi[mi.param] = rng.uniform(g.ia_min, b.ia_max.unwrap_or(0.01));
        }
        if let Some(sp) = f.spring() {
            let [lo, hi] = b.spring.unwrap_or([0.0, 1.0]);
            pi[sp.param] = rng.uniform(lo, hi);
        }
    }
    pi
}

/// Every constraint of the model at π, to `tol` (absolute, model units).
fn assert_feasible(model: &Model, pi: &[f64], tol: f64) {
    let g = &model.bounds;
    for f in &model.frames {
        let b = &f.bounds;
        let name = &f.name;
        if let Some(p0) = f.inertia {
            let ev = pseudo_inertia_min_eigenvalue(&pi[p0..p0 + 10]);
            assert!(
                ev >= g.pseudo_inertia_eps * (1.0 - 1e-3),
                "{name}: pseudo-inertia eigenvalue {ev:e}"
            );
            let m = pi[p0 + 9];
            if let Some([lo, hi]) = b.mass {
                assert!(m >= lo - tol && m <= hi + tol, "{name}: mass {m}");
            }
            if let Some(e) = &b.ellipsoid {
                // tr(Q·J) = m·(1 − E[d²]): the mass's mean squared ellipsoid radius at
                // most 1 + 1e-5. The solver meets the row, scaled to a unit largest
                // coefficient (1/a² on the inertia, up to 1300 m⁻² on the MTM's wrist),
                // to its tolerance: on the noisy MTM fit the wrist yaw missed by 8e-7 kg.
                let t = (e.q_matrix() * pseudo_inertia(&pi[p0..p0 + 10])).trace();
                assert!(
                    t >= -(tol.max(1e-5)) * m,
                    "{name}: tr(QJ) = {t:e}, mass outside its ellipsoid"
                );
            }
            if let Some(com) = b.com {
                for k in 0..3 {
                    let l = pi[p0 + 6 + k];
                    assert!(
                        l >= m * com[k][0] - tol && l <= m * com[k][1] + tol,
                        "{name}: l[{k}] = {l} outside m·[{}, {}]",
                        com[k][0],
                        com[k][1]
                    );
                }
            }
        }
        if let Some(fr) = f.friction() {
            let (fc, fv, fo) = (pi[fr.param], pi[fr.param + 1], pi[fr.param + 2]);
            assert!(fc >= g.fc_min - tol, "{name}: Fc {fc}");
            assert!(fv >= g.fv_min - tol, "{name}: Fv {fv}");
            if let Some(v) = b.fc_max {
                assert!(fc <= v + tol, "{name}: Fc {fc}");
            }
            if let Some(v) = b.fv_max {
                assert!(fv <= v + tol, "{name}: Fv {fv}");
            }
            if let Some(v) = b.fo_max {
                assert!(fo.abs() <= v + tol, "{name}: Fo {fo}");
            }
        }
        if let Some(mi) = f.motor_inertia() {
            let ia = pi[mi.param];
            assert!(ia >= g.ia_min - tol, "{name}: Ia {ia}");
            if let Some(v) = b.ia_max {
                assert!(ia <= v + tol, "{name}: Ia {ia}");
            }
        }
        if let Some(sp) = f.spring() {
            if let Some([lo, hi]) = b.spring {
                let k = pi[sp.param];
                assert!(k >= lo - tol && k <= hi + tol, "{name}: K {k}");
            }
        }
    }
}

struct Report {
    sol: SdpSolution,
    /// ‖H_b·(β − β_true)‖ / ‖H_b·β_true‖.
    torque_rel: f64,
    /// max_i |β_i − β_true,i|·‖H_b[:, i]‖ / ‖H_b·β_true‖.
    component_rel: f64,
    /// max_i |β_i − β_true,i| / max(|β_true,i|, 1e-3).
    worst_rel: f64,
    min_eigenvalue: f64,
}

/// Random consistent parameters, 300 random samples, τ = H·π (+ uniform noise of
/// `noise`·max|τ|), solve, compare the base parameters.
fn synthetic(name: &str, seed: u64, noise: f64, options: &SdpOptions) -> Report {
    let model = Model::builtin(name).unwrap();
    let mut rng = Rng::new(seed);
    let truth = random_consistent(&model, &mut rng);
    assert_feasible(&model, &truth, 0.0);
    let h = model.random_regressor(300, seed ^ 0xabcdef);
    let mut tau = &h * DVector::from_column_slice(&truth);
    let scale = tau.amax();
    for v in tau.iter_mut() {
        *v += noise * scale * rng.uniform(-1.0, 1.0);
    }
    let r = r_factor(&h, &tau);
    let sol = solve_sdp(&model, &r, options).unwrap();
    let base = model.base_parameters().unwrap();
    let (beta, bt) = (base.project(&sol.params), base.project(&truth));
    let hb = h.select_columns(&base.independent);
    let pred_true = &hb * DVector::from_column_slice(&bt);
    let pred = &hb * DVector::from_column_slice(&beta);
    let torque_rel = (&pred - &pred_true).norm() / pred_true.norm();
    let component_rel = (0..beta.len())
        .map(|i| (beta[i] - bt[i]).abs() * hb.column(i).norm() / pred_true.norm())
        .fold(0.0, f64::max);
    let worst_rel = beta
        .iter()
        .zip(&bt)
        .map(|(a, b)| (a - b).abs() / b.abs().max(1e-3))
        .fold(0.0, f64::max);
    let min_eigenvalue = model
        .link_frames()
        .iter()
        .map(|&f| {
            let p0 = model.frame(f).inertia.unwrap();
            pseudo_inertia_min_eigenvalue(&sol.params[p0..p0 + 10])
        })
        .fold(f64::INFINITY, f64::min);
    println!(
        "{name} (noise {noise}, regularization {:e}): {} params, status {}, {} iterations, \
         {:.3} s, objective {:e}; base parameter error: torque-relative {torque_rel:e}, \
         per component {component_rel:e}, worst relative {worst_rel:e}; min pseudo-inertia \
         eigenvalue {min_eigenvalue:e}",
        options.regularization,
        model.n_params(),
        sol.status,
        sol.iterations,
        sol.seconds,
        sol.objective
    );
    if sol.converged {
        assert_feasible(&model, &sol.params, 1e-7);
    }
    Report {
        sol,
        torque_rel,
        component_rel,
        worst_rel,
        min_eigenvalue,
    }
}

/// Noise-free: the base parameters come back up to the regularization's bias
/// (≈ 700·λ torque-relative, see the module documentation), with the default λ and
/// with a 100 times smaller one.
fn check_noise_free(name: &str, seed: u64) {
    let rep = synthetic(name, seed, 0.0, &SdpOptions::default());
    assert!(rep.sol.converged, "{name}: status {}", rep.sol.status);
    assert!(rep.min_eigenvalue > 0.0);
    let default_bounds = [
        ("torque-relative error", rep.torque_rel, 1e-8),
        ("per-component error", rep.component_rel, 1e-6),
        ("worst relative error", rep.worst_rel, 1e-2),
    ];
    let tight = SdpOptions {
        regularization: 1e-14,
        ..SdpOptions::default()
    };
    let rep = synthetic(name, seed, 0.0, &tight);
    assert!(rep.sol.converged, "{name}: status {}", rep.sol.status);
    let tight_bounds = [
        ("torque-relative error", rep.torque_rel, 1e-10),
        ("worst relative error", rep.worst_rel, 1e-4),
    ];
    for (what, error, bound) in default_bounds.into_iter().chain(tight_bounds) {
        assert!(
            error < bound,
            "{name}: {what} {error:e} (at most {bound:e})"
        );
    }
}

#[test]
fn sdp_synthetic_psm_recovers_base_parameters() {
    check_noise_free("psm", 0x9e37_79b9_7f4a_7c15);
}

#[test]
fn sdp_synthetic_mtm_recovers_base_parameters() {
    check_noise_free("mtm", 0xd1b5_4a32_d192_ed03);
}

/// With 1% noise the fit stays consistent and within bounds (checked in
/// `synthetic`), and the base parameters are off by about the noise.
#[test]
fn sdp_synthetic_noisy_is_feasible() {
    for (name, seed) in [
        ("psm", 0x2545_f491_4f6c_dd1d),
        ("mtm", 0x94d0_49bb_1331_11eb),
    ] {
        let rep = synthetic(name, seed, 0.01, &SdpOptions::default());
        assert!(rep.sol.converged, "{name}: status {}", rep.sol.status);
        assert!(
            rep.torque_rel < 0.05,
            "{name}: torque-relative {:e}",
            rep.torque_rel
        );
    }
}

#[test]
#[ignore = "exploration: bias of the regularization"]
fn sdp_regularization_sweep() {
    for reg in [0.0, 1e-14, 1e-12, 1e-11, 1e-10, 1e-8, 1e-6] {
        let options = SdpOptions {
            regularization: reg,
            ..SdpOptions::default()
        };
        for noise in [0.0, 0.01] {
            synthetic("psm", 0x9e37_79b9_7f4a_7c15, noise, &options);
            synthetic("mtm", 0xd1b5_4a32_d192_ed03, noise, &options);
        }
    }
}

/// Contradictory bounds are reported as infeasible, not as a result.
#[test]
fn sdp_infeasible_bounds_are_not_converged() {
    // Needs the LMI: J ⪰ eps·I forces m ≥ eps = 1 kg, but the bounds say m ≤ 0.5 kg.
    let text = one_link().replace(
        FRICTION_BOUNDS,
        "bounds = { mass = [0.1, 0.5] }\n\n[bounds]\npseudo_inertia_eps = 1.0",
    );
    let model = Model::from_toml_str(&text, "infeasible.toml").unwrap();
    let r = DMatrix::identity(14, 14);
    let sol = solve_sdp(&model, &r, &SdpOptions::default()).unwrap();
    assert!(!sol.converged);
    assert!(sol.status.infeasible(), "status {}", sol.status);
    // Plain contradictory bounds (m ≥ 5, m ≤ 4) on the built-in PSM.
    let mut psm = Model::builtin("psm").unwrap();
    let p0 = psm.frames[0].inertia.unwrap();
    psm.frames[0].bounds.mass = Some([5.0, 4.0]);
    let h = psm.random_regressor(50, 7);
    let truth = vec![0.0; psm.n_params()];
    let tau = &h * DVector::from_column_slice(&truth);
    let r = r_factor(&h, &tau);
    let sol = solve_sdp(&psm, &r, &SdpOptions::default()).unwrap();
    assert!(!sol.converged);
    assert_eq!(
        sol.status,
        crate::estimate::SolverStatus::PrimalInfeasible,
        "m1 = {}",
        sol.params[p0 + 9]
    );
    // The same model with override_bounds ignores the frame bounds and solves.
    let options = SdpOptions {
        override_bounds: true,
        ..SdpOptions::default()
    };
    let sol = solve_sdp(&psm, &r, &options).unwrap();
    assert!(sol.converged, "status {}", sol.status);
}

#[test]
fn sdp_rejects_bad_input() {
    let model = Model::from_toml_str(&one_link(), "one_link.toml").unwrap();
    let mut r = DMatrix::identity(14, 14);
    r[(2, 5)] = f64::NAN;
    assert!(matches!(
        solve_sdp(&model, &r, &SdpOptions::default()),
        Err(SdpError::NonFinite { .. })
    ));
    let r = DMatrix::identity(13, 13);
    assert!(matches!(
        solve_sdp(&model, &r, &SdpOptions::default()),
        Err(SdpError::Dimension { .. })
    ));
    let r = DMatrix::identity(14, 14);
    let bad_prior = SdpOptions {
        prior: Some(vec![f64::INFINITY; 13]),
        ..SdpOptions::default()
    };
    assert!(matches!(
        solve_sdp(&model, &r, &bad_prior),
        Err(SdpError::NonFinite { .. })
    ));
    let bad_reg = SdpOptions {
        regularization: f64::NAN,
        ..SdpOptions::default()
    };
    assert!(matches!(
        solve_sdp(&model, &r, &bad_reg),
        Err(SdpError::Option { .. })
    ));
}

/// One link whose bounding ellipsoid excludes the data's link: with `R11` the
/// Frobenius-norm map of `J` (as in [`sdp_tiny_projection_has_closed_form`]), the fit is
/// the projection of `J_t` onto `{J ⪰ eps·I, tr(Q·J) ≥ 0}`: it ends on the ellipsoid's
/// boundary, and no mass distribution inside the ellipsoid (brute force: random clouds
/// of point masses) is closer to `J_t`. Without the ellipsoid, `J_t` itself.
#[test]
fn sdp_ellipsoid_projection_is_optimal_on_the_boundary() {
    let ellipsoid =
        "center = [0.05, 0.0, 0.0], semi_axes = [0.1, 0.05, 0.04], rpy = [0.0, 0.0, 0.3]";
    let model = Model::from_toml_str(
        &one_link_with(&format!("bounds = {{ ellipsoid = {{ {ellipsoid} }} }}\n")),
        "one_link.toml",
    )
    .unwrap();
    assert_eq!(model.n_params(), 10);
    let e = model.frame(1).bounds.ellipsoid.clone().unwrap();
    let q = e.q_matrix();
    // 1 kg around x = 0.25 m: consistent, but outside the ellipsoid.
    let target =
        barycentric_from_standard(1.0, [0.25, 0.02, 0.0], [1e-3, 0.0, 0.0, 2e-3, 0.0, 2e-3]);
    let jt = pseudo_inertia(&target);
    assert!(pseudo_inertia_min_eigenvalue(&target) > 0.0);
    assert!((q * jt).trace() < -0.5);
    let mut g = DMatrix::zeros(10, 10);
    frobenius_columns(&mut g);
    let rhs = DVector::from_vec(frob_vec(&jt));
    let r = r_factor(&g, &rhs);
    let options = SdpOptions {
        regularization: 0.0,
        ..SdpOptions::default()
    };
    let sol = solve_sdp(&model, &r, &options).unwrap();
    assert!(sol.converged, "status {}", sol.status);
    let j = pseudo_inertia(&sol.params);
    let on_boundary = (q * j).trace();
    assert!(on_boundary.abs() < 1e-6, "tr(QJ) = {on_boundary:e}");
    assert!(pseudo_inertia_min_eigenvalue(&sol.params) > 0.0);
    let distance = (j - jt).norm();
    // Brute force: clouds of 1–12 point masses inside the ellipsoid.
    let mut rng = Rng::new(0xe111);
    let r_e = dvrk_model::inertia::rotation_rpy(&e.rpy);
    for trial in 0..5000 {
        let n = 1 + (rng.next_u64() % 12) as usize;
        let mut cand = Matrix4::zeros();
        for _ in 0..n {
            let u = Vector3::new(rng.normal(), rng.normal(), rng.normal()).normalize()
                * rng.uniform(0.0, 1.0).cbrt();
            let x = r_e * Vector3::from(e.semi_axes).component_mul(&u) + Vector3::from(e.center);
            let m = rng.uniform(0.0, 2.0) / n as f64;
            cand += pseudo_inertia(&barycentric_from_standard(m, x.into(), [0.0; 6]));
        }
        assert!((q * cand).trace() >= 0.0);
        let d = (cand - jt).norm();
        assert!(
            d >= distance * (1.0 - 1e-6),
            "trial {trial}: a distribution inside is closer, {d} < {distance}"
        );
    }
    // Without the ellipsoid the target is feasible: the fit returns it.
    let free = solve_sdp(
        &model,
        &r,
        &SdpOptions {
            ellipsoids: false,
            ..options.clone()
        },
    )
    .unwrap();
    assert!(free.converged);
    let jf = pseudo_inertia(&free.params);
    assert!((jf - jt).norm() < 1e-6 * jt.norm(), "{}", (jf - jt).norm());
    assert!((q * jf).trace() < -0.5);
    // The same with the frame bounds overridden.
    let over = solve_sdp(
        &model,
        &r,
        &SdpOptions {
            override_bounds: true,
            ..options
        },
    )
    .unwrap();
    assert!((pseudo_inertia(&over.params) - jt).norm() < 1e-6 * jt.norm());
}
