//! The semidefinite fit's priors: the Euclidean one against ridge regression, the
//! entropic one against Newton's method, and the errors of a prior that does not fit.

use super::*;

/// A well-conditioned random upper-triangular (n+1)×(n+1) R whose torque column
/// is `R11·truth` plus a little noise.
fn random_r(truth: &[f64], rng: &mut Rng) -> DMatrix<f64> {
    let n = truth.len();
    let mut r = DMatrix::zeros(n + 1, n + 1);
    for i in 0..n {
        for j in i..n {
            r[(i, j)] = if i == j {
                rng.uniform(1.0, 3.0)
            } else {
                rng.uniform(-0.5, 0.5)
            };
        }
    }
    for i in 0..n {
        let v: f64 = (i..n).map(|j| r[(i, j)] * truth[j]).sum();
        r[(i, n)] = v + 0.02 * rng.uniform(-1.0, 1.0);
    }
    r[(n, n)] = 0.01;
    r
}

fn consistent_link(m: f64, c: [f64; 3], i: [f64; 3]) -> Vec<f64> {
    barycentric_from_standard(m, c, [i[0], 0.0, 0.0, i[1], 0.0, i[2]]).to_vec()
}

/// Euclidean prior on a small robot: with no constraint active the fit is the
/// ridge regression `(RᵀR + (λ+w)·D²)·π = Rᵀr + (λ+w)·D²·π₀`, `D = diag(‖R[:, i]‖)`
/// (closed form, solved here by nalgebra's LU). The solver's x approaches it as its
/// tolerance shrinks.
#[test]
fn sdp_euclidean_prior_is_ridge_regression() {
    let model = Model::from_toml_str(&one_link(), "one_link.toml").unwrap();
    let p = model.n_params();
    // A seed whose R leaves the closed form inside the constraints (checked below; 17 of
    // seeds 1-60 do, 2 is the first).
    let mut rng = Rng::new(2);
    let mut truth = consistent_link(1.2, [0.05, 0.02, -0.03], [0.02, 0.03, 0.025]);
    truth.extend([0.1, 0.5, 0.05]);
    let mut prior = consistent_link(0.9, [0.03, 0.0, -0.01], [0.015, 0.02, 0.02]);
    prior.extend([0.15, 0.8, 0.0]);
    let r = random_r(&truth, &mut rng);
    let mut last_distance = f64::INFINITY;
    for weight in [0.003, 0.01, 0.03] {
        let options = SdpOptions {
            prior: Some(prior.clone()),
            prior_weight: weight,
            prior_metric: PriorMetric::Euclidean,
            tolerance: 1e-11,
            ..SdpOptions::default()
        };
        let sol = solve_sdp(&model, &r, &options).unwrap();
        assert!(sol.converged, "status {}", sol.status);
        assert_eq!(sol.divergence, None);
        let r11 = r.view((0, 0), (p + 1, p)).into_owned();
        let rhs = r.column(p).into_owned();
        let lw = weight + options.regularization;
        let d2 = DMatrix::from_diagonal(&DVector::from_iterator(
            p,
            (0..p).map(|i| r11.column(i).norm_squared()),
        ));
        let lhs = r11.transpose() * &r11 + lw * &d2;
        let want = lhs
            .lu()
            .solve(&(r11.transpose() * &rhs + lw * &d2 * DVector::from_column_slice(&prior)))
            .unwrap();
        // The closed form is the answer only where no constraint is active.
        assert_feasible(&model, want.as_slice(), 0.0);
        assert!(pseudo_inertia_min_eigenvalue(&want.as_slice()[0..10]) > 1e-4);
        // Distance in the data's own metric, relative to the torque: ‖R·(π − π*)‖/γ.
        let diff = DVector::from_column_slice(&sol.params) - &want;
        let err = (&r11 * diff).norm() / rhs.norm();
        println!("euclidean w {weight}: ‖R·(π − π*)‖/γ = {err:e}");
        assert!(err < 1e-6, "w {weight}: {:?} vs {want}", sol.params);
        // The prior pulls: a heavier weight lands closer to it.
        let dist = |v: &[f64]| -> f64 { v.iter().zip(&prior).map(|(a, b)| (a - b).powi(2)).sum() };
        let d = dist(&sol.params);
        println!("euclidean w {weight}: distance² to the prior {d:e}");
        assert!(d < last_distance);
        last_distance = d;
    }
}

/// The minimizer of `f(π) = ‖R11·π − r‖²/ρ² + λ‖D(π − π₀)‖²/ρ² + w·d(J(π)‖J₀)` for
/// one link by Newton's method with the closed-form derivatives of the divergence,
/// `∂ₖd = tr((J₀⁻¹ − J⁻¹)·Pₖ)`, `∂ₖ∂ₗd = tr(J⁻¹·Pₖ·J⁻¹·Pₗ)` (`Pₖ = J(eₖ)`), with
/// inverses and no whitening: a reference independent of the cones.
fn entropic_newton(
    r: &DMatrix<f64>,
    rho: f64,
    lambda: f64,
    weight: f64,
    prior: &[f64],
) -> Vec<f64> {
    let r11 = r.view((0, 0), (11, 10)).into_owned();
    let rhs = r.column(10).into_owned();
    let j0_inv = pseudo_inertia(prior).try_inverse().unwrap();
    let basis: Vec<Matrix4<f64>> = (0..10)
        .map(|k| {
            let mut e = [0.0; 10];
            e[k] = 1.0;
            pseudo_inertia(&e)
        })
        .collect();
    let d2: Vec<f64> = (0..10).map(|k| r11.column(k).norm_squared()).collect();
    let f = |x: &DVector<f64>| -> f64 {
        let j = pseudo_inertia(x.as_slice());
        let Some(c) = j.cholesky() else {
            return f64::INFINITY;
        };
        let log_det: f64 = (0..4).map(|i| 2.0 * c.l()[(i, i)].ln()).sum();
        let tik: f64 = (0..10).map(|k| d2[k] * (x[k] - prior[k]).powi(2)).sum();
        ((&r11 * x - &rhs).norm_squared() + lambda * tik) / (rho * rho)
            + weight * ((j0_inv * j).trace() - log_det)
    };
    let mut x = DVector::from_column_slice(prior);
    for _ in 0..100 {
        let j_inv = pseudo_inertia(x.as_slice()).try_inverse().unwrap();
        let mut g = r11.transpose() * (&r11 * &x - &rhs) * (2.0 / (rho * rho));
        let mut h = r11.transpose() * &r11 * (2.0 / (rho * rho));
        for k in 0..10 {
            g[k] += 2.0 * lambda * d2[k] * (x[k] - prior[k]) / (rho * rho)
                + weight * ((j0_inv - j_inv) * basis[k]).trace();
            h[(k, k)] += 2.0 * lambda * d2[k] / (rho * rho);
            for l in 0..10 {
                h[(k, l)] += weight * (j_inv * basis[k] * j_inv * basis[l]).trace();
            }
        }
        let step = h.cholesky().unwrap().solve(&g);
        // Backtracking keeps J positive definite and f decreasing.
        let mut t = 1.0;
        while f(&(&x - t * &step)) > f(&x) && t > 1e-12 {
            t *= 0.5;
        }
        x -= t * &step;
        if step.norm() * t < 1e-15 * x.norm() {
            break;
        }
    }
    x.as_slice().to_vec()
}

/// Entropic prior on a one-link robot: the solution is the minimizer of the smooth
/// objective found by Newton's method (no constraint is active), and the reported
/// divergence is `tr(J₀⁻¹J) − log det(J₀⁻¹J) − 4` (by determinants).
#[test]
fn sdp_entropic_prior_matches_newton() {
    // The link alone: no friction bounds to hit.
    let model = Model::from_toml_str(ONE_LINK, "one_link.toml").unwrap();
    assert_eq!(model.n_params(), 10);
    // A seed whose R leaves Newton's minimizer inside the constraints (checked below; 25
    // of seeds 1-60 do, 2 is the first).
    let mut rng = Rng::new(2);
    let truth = consistent_link(1.2, [0.05, 0.02, -0.03], [0.02, 0.03, 0.025]);
    let prior = consistent_link(0.8, [0.02, 0.0, -0.01], [0.01, 0.02, 0.015]);
    let j0 = pseudo_inertia(&prior);
    let r = random_r(&truth, &mut rng);
    // R11 has full rank: the least-squares residual is the last diagonal entry, and
    // the data term is measured against it.
    let rho = r[(10, 10)].abs();
    assert!(rho > 1e-3 * r.column(10).norm());
    let r11 = r.view((0, 0), (11, 10)).into_owned();
    let mut last_divergence = f64::INFINITY;
    for weight in [1e-3, 1e-2, 1e-1, 1.0] {
        let options = SdpOptions {
            prior: Some(prior.clone()),
            prior_weight: weight,
            prior_metric: PriorMetric::Entropic,
            ..SdpOptions::default()
        };
        let sol = solve_sdp(&model, &r, &options).unwrap();
        assert!(sol.converged, "status {}", sol.status);
        let pi = &sol.params;
        let want = entropic_newton(&r, rho, options.regularization, weight, &prior);
        assert!(
            pseudo_inertia_min_eigenvalue(&want) > 1e-4,
            "no bound active"
        );
        // The distance in the data's metric, relative to the residual, and in the
        // prior's.
        let diff = DVector::from_column_slice(pi) - DVector::from_column_slice(&want);
        let data = (&r11 * &diff).norm() / rho;
        let j = pseudo_inertia(pi);
        let a = j0.try_inverse().unwrap() * j;
        let want_div = a.trace() - a.determinant().ln() - 4.0;
        let div = sol.divergence.unwrap();
        println!("entropic w {weight}: divergence {div:.6}, ‖R11·(π − π_newton)‖/ρ = {data:e}");
        assert!(data < 1e-4, "w {weight}: {pi:?} vs {want:?}");
        assert!(
            (div - want_div).abs() < 1e-9 * want_div.max(1.0),
            "{div} vs {want_div}"
        );
        assert!(
            div > 0.0 && div < last_divergence,
            "heavier weight, closer prior"
        );
        last_divergence = div;
    }
}

/// The entropic metric refuses a prior that is not physically consistent, naming the
/// link; the Euclidean metric takes it; a weight without values is refused.
#[test]
fn sdp_prior_errors() {
    let model = Model::from_toml_str(ONE_LINK, "one_link.toml").unwrap();
    let truth = consistent_link(1.2, [0.05, 0.02, -0.03], [0.02, 0.03, 0.025]);
    let r = random_r(&truth, &mut Rng::new(7));
    let mut bad = truth.clone();
    bad[9] = -1.0; // negative mass
    let entropic = SdpOptions {
        prior: Some(bad.clone()),
        prior_weight: 0.01,
        ..SdpOptions::default()
    };
    match solve_sdp(&model, &r, &entropic) {
        Err(e @ SdpError::PriorInconsistent { .. }) => {
            assert!(e.to_string().contains("link link (frame 1)"), "{e}")
        }
        other => panic!("expected PriorInconsistent, got {other:?}"),
    }
    let euclidean = SdpOptions {
        prior_metric: PriorMetric::Euclidean,
        ..entropic
    };
    assert!(solve_sdp(&model, &r, &euclidean).unwrap().converged);
    for (weight, prior) in [
        (f64::NAN, Some(truth.clone())),
        (-1.0, Some(truth.clone())),
        (0.1, None),
    ] {
        let options = SdpOptions {
            prior,
            prior_weight: weight,
            ..SdpOptions::default()
        };
        assert!(matches!(
            solve_sdp(&model, &r, &options),
            Err(SdpError::Option {
                name: "prior_weight",
                ..
            })
        ));
    }
}

/// A prior weight is 0 (no pull) or within [1e-9, 1e6]; the message names the range and
/// the weight given.
#[test]
fn prior_weights_are_zero_or_in_range() {
    assert!(prior_weight_problem(0.0).is_none() && prior_weight_problem(10.0).is_none());
    assert_eq!(
        prior_weight_problem(1e-300).unwrap(),
        "must be 0 or in [1e-9, 1e6], got 1e-300"
    );
}
