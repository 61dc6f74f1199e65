//! End to end without shared data: simulate the PSM and the MTM with known, physically
//! consistent parameters along a Fourier trajectory, add torque noise, fit, and check
//! that the base parameters come back within what the noise allows, and that the
//! semidefinite fit is consistent.

use dvrk_ident::simulate::{model_log, motion_torques};
use dvrk_ident::JointLog;
use dvrk_ident::Silent;
use dvrk_ident::{FitRequest, FitSettings, Method};
use dvrk_logs::uniform_time;
use dvrk_model::{inertia, Model};
use dvrk_test_support::fixtures::assert_recovered;
use nalgebra::DMatrix;

/// Parameters inside the description's bounds: mid-range masses and centres of mass,
/// box-shaped inertias, friction and springs inside their ranges. A link whose
/// mid-range centre of mass lies outside its bounding ellipsoid (the PSM's pitch_front,
/// whose 2019 box reaches its mesh only at x 0.10-0.19 m; the ECM's links, which have no
/// box) gets the ellipsoid's centre moved into its box instead.
fn consistent_params(model: &Model) -> Vec<f64> {
    let mass =
        |bounds: Option<[f64; 2]>| bounds.map_or(1.0, |[a, b]| 0.5 * (a + b).min(2.0 * a + 1.0));
    let mut pi = dvrk_test_support::ParamRule {
        mass: Box::new(mass),
        inertia_com: Box::new(dvrk_test_support::box_inertia),
        friction: Box::new(dvrk_test_support::friction_within_bounds),
        motor_inertia: 0.01,
        spring: Box::new(dvrk_test_support::mid_spring),
    }
    .params(model);
    for &j in model.link_frames() {
        let f = model.frame(j);
        let (Some(p0), Some(e)) = (f.inertia, f.bounds.ellipsoid.as_ref()) else {
            continue;
        };
        if ellipsoid_margin(model, j, &pi).unwrap() > 0.0 {
            continue;
        }
        let mut c = e.center;
        if let Some(b) = f.bounds.com {
            for k in 0..3 {
                c[k] = c[k].clamp(b[k][0], b[k][1]);
            }
        }
        let m = pi[p0 + 9];
        pi[p0..p0 + 10].copy_from_slice(&inertia::barycentric_from_standard(
            m,
            c,
            dvrk_test_support::box_inertia(m),
        ));
    }
    pi
}

/// Sum-of-sines trajectory per coordinate, centred in the description's position limit
/// when the limit is on that coordinate alone (amplitudes small enough to stay inside).
fn simulate(
    model: &Model,
    params: &[f64],
    seconds: f64,
    rate: f64,
    noise: f64,
    seed: u64,
) -> JointLog {
    let n = model.dof();
    let count = (seconds * rate) as usize;
    let time = uniform_time(count, rate);
    let mut rng = dvrk_test_support::Rng::new(seed);
    let mut gauss = dvrk_test_support::Rng::new(seed);
    let mut centre = vec![0.0; n];
    let mut amp = vec![0.5; n];
    for l in &model.limits {
        if let (Some([lo, hi]), [(k, c)]) = (l.position, l.expr.terms.as_slice()) {
            centre[*k] = (0.5 * (lo + hi) - l.expr.offset) / c;
            amp[*k] = 0.25 * (hi - lo) / c.abs();
        }
    }
    let freqs: Vec<[(f64, f64, f64); 3]> = (0..n)
        .map(|_| {
            let mut h = [(0.0, 0.0, 0.0); 3];
            for (i, e) in h.iter_mut().enumerate() {
                *e = (
                    0.2 * (i + 1) as f64 + 0.05 * rng.uniform(0.0, 1.0),
                    rng.uniform(0.0, 6.0),
                    1.0 / (i + 1) as f64,
                );
            }
            h
        })
        .collect();
    let (mut q, mut dq, mut ddq) = (
        DMatrix::zeros(count, n),
        DMatrix::zeros(count, n),
        DMatrix::zeros(count, n),
    );
    for (k, &t) in time.iter().enumerate() {
        for j in 0..n {
            let s: f64 = freqs[j].iter().map(|(_, _, a)| a).sum();
            for &(f, ph, a) in &freqs[j] {
                let w = 2.0 * std::f64::consts::PI * f;
                let a = amp[j] * a / s;
                q[(k, j)] += a * (w * t + ph).sin();
                dq[(k, j)] += a * w * (w * t + ph).cos();
                ddq[(k, j)] -= a * w * w * (w * t + ph).sin();
            }
            q[(k, j)] += centre[j];
        }
    }
    let mut tau = motion_torques(model, params, &q, &dq, &ddq);
    for k in 0..count {
        for j in 0..n {
            tau[(k, j)] += noise * gauss.normal();
        }
    }
    model_log(model, time, q, dq, tau)
}

/// `tr(Q·J)` of frame `j`'s link at `params` (kg; ≥ 0: its mass can lie inside its
/// bounding ellipsoid), `None` without an ellipsoid.
fn ellipsoid_margin(model: &Model, j: usize, params: &[f64]) -> Option<f64> {
    let f = model.frame(j);
    let p0 = f.inertia?;
    let e = f.bounds.ellipsoid.as_ref()?;
    Some((e.q_matrix() * inertia::pseudo_inertia(&params[p0..p0 + 10])).trace())
}

fn settings(method: Method) -> FitSettings {
    let mut s = FitSettings {
        method,
        ..FitSettings::default()
    };
    // Exact signals: no filter; derivatives of the analytic velocity are accurate.
    s.processing.filter = None;
    s.processing.trim = 10;
    s
}

fn check(robot: &str) {
    check_at(robot, None);
}

/// `robot` mounted at `pitch_deg` (simulated with that gravity; the fit is given the
/// description as loaded and the pitch in its settings, which it must apply).
fn check_at(robot: &str, pitch_deg: Option<f64>) {
    let loaded = Model::builtin(robot).unwrap();
    let mut model = loaded.clone();
    if let Some(p) = pitch_deg {
        model.set_mounting_pitch(p).unwrap();
    }
    let truth = consistent_params(&model);
    // The dVRK's nominal centres of mass (the Classic ECM's endoscope) lie inside the
    // ellipsoids of the dVRK's meshes: the two sources agree.
    let mut nominal_inside = 0;
    for &j in model.link_frames() {
        let f = model.frame(j);
        if let (Some(e), Some(c)) = (f.bounds.ellipsoid.as_ref(), f.nominal.com) {
            assert!(
                e.contains(c),
                "{robot} {}: nominal centre of mass {c:?} outside",
                f.name
            );
            nominal_inside += 1;
        }
    }
    assert_eq!(nominal_inside, usize::from(robot == "ecm"), "{robot}");
    for &j in model.link_frames() {
        let p0 = model.frame(j).inertia.unwrap();
        assert!(inertia::pseudo_inertia_min_eigenvalue(&truth[p0..p0 + 10]) > 0.0);
        // The truth lies inside the description's bounding ellipsoids (the MTM's).
        if let Some(t) = ellipsoid_margin(&model, j, &truth) {
            assert!(
                t > 0.0,
                "{robot} {}: truth outside its ellipsoid",
                model.frame(j).name
            );
        }
    }
    let noise = 0.005; // N·m
    let train = simulate(&model, &truth, 60.0, 200.0, noise, 1);
    let test = simulate(&model, &truth, 20.0, 200.0, noise, 2);
    let base = model.base_parameters().unwrap();
    let beta_true = base.project(&truth);
    for method in [Method::Ols, Method::Sdp] {
        let s = FitSettings {
            mounting_pitch_deg: pitch_deg,
            ..settings(method)
        };
        let r = FitRequest::of_samples([&train], Some(&test), s.clone())
            .run(Some(&loaded), &Silent)
            .unwrap()
            .result;
        assert_eq!(
            r.settings.mounting_pitch_deg, pitch_deg,
            "{robot}: recorded pitch"
        );
        assert!(
            r.solver.converged,
            "{robot} {method:?}: {}",
            r.solver.status
        );
        // OLS: within 6 standard deviations (the std comes from the noise level); SDP
        // (true parameters inside the feasible set): the same bound, plus 1e-6.
        let worst = assert_recovered(
            &format!("{robot} {method:?}"),
            r.base_parameters
                .iter()
                .map(|b| (b.expression.as_str(), b.value, b.std)),
            &beta_true,
        );
        let rel = &r.metrics.test.as_ref().unwrap().relative_error;
        println!(
            "{robot} {method:?}: worst |error|/std {worst:.2}, test relative errors {rel:.4?}"
        );
        if method == Method::Sdp {
            assert!(
                r.physically_consistent,
                "{robot}: SDP result not consistent"
            );
            for c in &r.consistency {
                assert!(c.min_eigenvalue > 0.0, "{}: {}", c.link, c.min_eigenvalue);
            }
            // The fit stays inside every bounding ellipsoid (to the solver's tolerance).
            let fitted = model
                .params_from_named(r.parameters.iter().map(|(k, v)| (k.as_str(), *v)), "fit")
                .unwrap();
            let mut checked = 0;
            for &j in model.link_frames() {
                if let Some(t) = ellipsoid_margin(&model, j, &fitted) {
                    // tr(Q·J) = m·(1 − E[d²]), to the solver's tolerance (see the
                    // semidefinite fit's unit tests).
                    let m = fitted[model.frame(j).inertia.unwrap() + 9];
                    assert!(
                        t > -1e-5 * m,
                        "{robot} {}: tr(QJ) = {t:e}",
                        model.frame(j).name
                    );
                    checked += 1;
                }
            }
            // The ellipsoids of the dVRK's meshes (robots/*.toml say which links have
            // none and why).
            let expected = match robot {
                "mtm" => 7,
                "psm" => 1,
                "ecm" => 3,
                _ => 0,
            };
            assert_eq!(checked, expected, "{robot}: the links with an ellipsoid");
        }
        // The residual left is the noise: RMS error close to the noise level.
        for &e in &r.metrics.test.as_ref().unwrap().rms {
            assert!(e < 2.0 * noise, "{robot} {method:?}: test rms {e}");
        }
    }
}

#[test]
fn psm_synthetic_fit_recovers_base_parameters() {
    check("psm");
}

#[test]
fn mtm_synthetic_fit_recovers_base_parameters() {
    check("mtm");
}

/// The arms the dVRK controller's kinematic gravity compensation is for, mounted as the
/// dVRK mounts them (PSM1 −45°, ECM Si −70°, Classic ECM −45°), and the PSM Si with its
/// instrument (its motor inertias, friction and roll spring identified with the arm).
#[test]
fn ecm_and_si_arms_mounted_synthetic_fit_recovers_base_parameters() {
    check_at("psm_si", Some(-45.0));
    check_at("psm_si_tool", Some(-45.0));
    check_at("ecm_si", Some(-70.0));
    check_at("ecm", Some(-45.0));
}

/// `--preset dvrk` on the MTM adds the position torque of its description's `[preset]`
/// (upper arm and forearm, order 1) and records it; `position_torque: 0` leaves it out.
/// On a log without such a torque the forearm's terms (in the elbow's relative angle,
/// which no link's gravity depends on) come back small: measured 0.003 and 0.001 N·m,
/// where the upper arm's, which the links' gravity spans, take 0.30 and −0.18 N·m of the
/// gravity that the prior moves off the masses (this log's are not the nominal ones).
#[test]
fn mtm_preset_adds_the_descriptions_position_torque() {
    use dvrk_ident::{Overrides, Preset};
    let model = Model::builtin("mtm").unwrap();
    let truth = consistent_params(&model);
    let train = simulate(&model, &truth, 30.0, 200.0, 0.005, 3);
    let fit = |extra: Overrides| {
        FitRequest {
            overrides: Overrides {
                preset: Some(Preset::Dvrk),
                ..extra
            },
            ..FitRequest::of_samples([&train], None, settings(Method::Sdp))
        }
        .run(Some(&model), &Silent)
        .unwrap()
        .result
    };
    let r = fit(Overrides::default());
    let torques: Vec<(&str, f64)> = r
        .parameters
        .iter()
        .filter(|(k, _)| k.starts_with("Pc") || k.starts_with("Ps"))
        .map(|(k, v)| (k.as_str(), *v))
        .collect();
    println!("mtm --preset dvrk position torques (N·m): {torques:?}");
    let names: Vec<&str> = torques.iter().map(|t| t.0).collect();
    assert_eq!(names, ["Pca2", "Psa2", "Pca3", "Psa3"]);
    for (name, v) in &torques[2..] {
        assert!(v.abs() < 1e-2, "{name} = {v}");
    }
    assert_eq!(r.settings.position_torque_order, Some(1));
    assert_eq!(r.settings.position_torque_frames, ["upper_arm", "forearm"]);
    let none = fit(Overrides {
        position_torque_order: Some(0),
        ..Overrides::default()
    });
    assert_eq!(none.parameters.len(), r.parameters.len() - 4);
    assert_eq!(none.settings.position_torque_order, None);
}
