//! The estimator sees elements only through `dvrk_model::Element` (bounds, clamping,
//! unit classes): an element added in one module of dvrk-model, the quadratic viscous
//! friction `Fq·ṡ·|ṡ|`, is fitted with no change here. Noise-free synthetic torques of a
//! pendulum: least squares and the semidefinite fit recover `Fq`; torques asking for a
//! a negative `Fq` (or one above its `max`) get the bound from the SDP, never beyond. The
//! monotone friction of issue 28 likewise: weights recovered, and held at 0; Dahl
//! friction and the position-dependent torque recovered within noise (the latter through
//! the fit's `position_torque` setting).

use dvrk_test_support as support;

use crate::estimate::sdp::{solve_sdp, SdpOptions, SdpSolution};
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
    let sol = solved(&model, &r, &SdpOptions::default());
    assert!(
        (sol.params[FQ] - 0.05).abs() < 1e-6,
        "Fq {}",
        sol.params[FQ]
    );
    // The friction too (noise-free data).
    assert_friction_of_truth(&sol.params);
}

#[test]
fn sdp_holds_quadratic_viscous_friction_at_its_bounds() {
    let model = pendulum();
    for (fq, bound) in [(-0.05, 0.0), (1.5, 1.0)] {
        let (h, tau) = observe(&model, &truth(&model, fq), 400);
        let r = r_factor(&h, &tau);
        let sol = solved(&model, &r, &SdpOptions::default());
        // At the bound, and never beyond it (the element clamps a solver's miss away).
        let got = sol.params[FQ];
        assert!((got - bound).abs() < 1e-6, "data Fq {fq}: {got}");
        assert!((0.0..=1.0).contains(&got), "data Fq {fq}: {got}");
        // Without the frame's bounds only the physical one remains.
        let free = SdpOptions {
            override_bounds: true,
            ..SdpOptions::default()
        };
        let sol = solved(&model, &r, &free);
        let want = fq.max(0.0);
        assert!(
            (sol.params[FQ] - want).abs() < 1e-6,
            "Fq {} vs {want}",
            sol.params[FQ]
        );
    }
}

/// The semidefinite fit of `r`, which must converge.
fn solved(model: &Model, r: &DMatrix<f64>, options: &SdpOptions) -> SdpSolution {
    let sol = solve_sdp(model, r, options).unwrap();
    assert!(sol.converged, "status {}", sol.status);
    sol
}

/// The friction of [`truth`] recovered from noise-free data: `Fc1 Fv1 Fo1`.
fn assert_friction_of_truth(params: &[f64]) {
    for (k, want) in [(10, 0.08), (11, 0.03), (12, -0.01)] {
        assert!((params[k] - want).abs() < 1e-6, "{k}: {}", params[k]);
    }
}

/// The pendulum with friction and monotone friction of steps 0.1 and 0.5 rad/s
/// (weights `Fpa1 Fna1 Fpb1 Fnb1` after `Fc1 Fv1 Fo1`).
fn monotone_pendulum() -> Model {
    let text = one_link_with("friction = true\nmonotone_friction = { velocities = [0.1, 0.5] }\n");
    Model::from_toml_str(&text, "monotone.toml").unwrap()
}

/// Column of `Fpa1`.
const FM: usize = 13;

/// The link and friction of [`truth`], then the monotone friction's `weights`.
fn monotone_truth(model: &Model, weights: [f64; 4]) -> Vec<f64> {
    let mut pi = truth(&pendulum(), 0.0)[..FM].to_vec();
    pi.extend(weights);
    assert_eq!(pi.len(), model.n_params());
    pi
}

#[test]
fn sdp_recovers_monotone_friction() {
    let model = monotone_pendulum();
    assert_eq!(&model.param_names()[FM..], ["Fpa1", "Fna1", "Fpb1", "Fnb1"]);
    let weights = [0.2, 0.05, 0.1, 0.3];
    let pi = monotone_truth(&model, weights);
    let (h, tau) = observe(&model, &pi, 600);
    let base = model.base_parameters().unwrap();
    assert!((FM..FM + 4).all(|c| base.independent.contains(&c)));
    let sol = solved(&model, &r_factor(&h, &tau), &SdpOptions::default());
    for (k, want) in weights.iter().enumerate() {
        let got = sol.params[FM + k];
        assert!((got - want).abs() < 1e-6, "weight {k}: {got} vs {want}");
    }
    assert_friction_of_truth(&sol.params);
}

/// Torques asking for a negative weight (a friction curve that falls with speed): least
/// squares follows them, the semidefinite fit keeps every weight at or above 0 and the
/// result physically consistent.
#[test]
fn sdp_keeps_monotone_friction_weights_nonnegative() {
    let model = monotone_pendulum();
    let pi = monotone_truth(&model, [-0.1, 0.05, 0.3, 0.1]);
    let (h, tau) = observe(&model, &pi, 600);
    let ls = h.clone().svd(true, true).solve(&tau, 1e-12).unwrap();
    assert!((ls[FM] + 0.1).abs() < 1e-6, "least squares Fpa1 {}", ls[FM]);
    let sol = solved(&model, &r_factor(&h, &tau), &SdpOptions::default());
    for k in FM..FM + 4 {
        assert!(
            sol.params[k] >= 0.0,
            "{}: {}",
            model.param_names()[k],
            sol.params[k]
        );
    }
    assert!(
        sol.params[FM] < 1e-6,
        "Fpa1 {} held at its bound",
        sol.params[FM]
    );
    assert!(model
        .frame(1)
        .elements
        .iter()
        .all(|e| e.consistent(&sol.params, -1e-9)));
}

/// The pendulum with friction and Dahl friction of stiffness 20 /rad (`Fd1` after
/// `Fc1 Fv1 Fo1`).
fn dahl_pendulum() -> Model {
    let text = one_link_with("friction = true\ndahl = { sigma = 20 }\n");
    Model::from_toml_str(&text, "dahl.toml").unwrap()
}

/// Column of `Fd1`.
const FD: usize = 13;

/// The regressor along a path of reversals of several amplitudes (the Dahl state needs a
/// path, not random states), and its torques for `pi` plus Gaussian-like noise of
/// standard deviation `noise` (N·m).
fn observe_path(model: &Model, pi: &[f64], noise: f64) -> (DMatrix<f64>, DVector<f64>) {
    let (p, count, dt) = (model.n_params(), 2000, 0.005);
    let mut ws = Workspace::new(model);
    let mut rng = Rng::new(11);
    let mut h = DMatrix::zeros(count, p);
    let mut row = vec![0.0; p];
    for k in 0..count {
        let t = k as f64 * dt;
        // Two incommensurate harmonics: reversals of 0.01 to 0.5 rad.
        let q = [0.3 * (1.1 * t).sin() + 0.05 * (7.3 * t).sin()];
        let dq = [0.33 * (1.1 * t).cos() + 0.365 * (7.3 * t).cos()];
        let ddq = [-0.363 * (1.1 * t).sin() - 2.6645 * (7.3 * t).sin()];
        model.advance_hysteresis(&mut ws, &q);
        model.regressor_into(&mut ws, &q, &dq, &ddq, &mut row);
        h.row_mut(k).copy_from_slice(&row);
    }
    let clean = &h * DVector::from_column_slice(pi);
    // A sum of uniforms: zero mean, standard deviation `noise`.
    let tau = clean.map(|x| x + noise * (0..12).map(|_| rng.uniform(-0.5, 0.5)).sum::<f64>());
    (h, tau)
}

fn dahl_truth(fd: f64) -> Vec<f64> {
    let mut pi = truth(&pendulum(), 0.0)[..FD].to_vec();
    pi.push(fd);
    pi
}

/// Synthetic recovery: torques with Dahl friction `Fd = 0.06` N·m and noise of 2 mN·m;
/// the semidefinite fit recovers `Fd` within a few standard errors of the noise.
#[test]
fn sdp_recovers_dahl_friction_within_noise() {
    let model = dahl_pendulum();
    assert_eq!(model.param_names()[FD], "Fd1");
    let base = model.base_parameters().unwrap();
    assert!(base.independent.contains(&FD), "Fd1 is identifiable");
    let pi = dahl_truth(0.06);
    let (h, tau) = observe_path(&model, &pi, 0.002);
    let sol = solved(&model, &r_factor(&h, &tau), &SdpOptions::default());
    let got = sol.params[FD];
    assert!((got - 0.06).abs() < 0.003, "Fd1 {got} vs 0.06");
    // Coulomb friction and Dahl friction are told apart (Fc1 = 0.08).
    assert!(
        (sol.params[10] - 0.08).abs() < 0.005,
        "Fc1 {}",
        sol.params[10]
    );
}

/// Torques asking for a negative `Fd` (a force along the motion): least squares follows
/// them, the semidefinite fit holds `Fd` at 0 and stays consistent.
#[test]
fn sdp_keeps_dahl_friction_nonnegative() {
    let model = dahl_pendulum();
    let (h, tau) = observe_path(&model, &dahl_truth(-0.05), 0.0);
    let ls = h.clone().svd(true, true).solve(&tau, 1e-12).unwrap();
    assert!((ls[FD] + 0.05).abs() < 1e-6, "least squares Fd1 {}", ls[FD]);
    let sol = solved(&model, &r_factor(&h, &tau), &SdpOptions::default());
    assert!(
        sol.params[FD] >= 0.0 && sol.params[FD] < 1e-6,
        "Fd1 {}",
        sol.params[FD]
    );
    assert!(model
        .frame(1)
        .elements
        .iter()
        .all(|e| e.consistent(&sol.params, -1e-9)));
}

/// A link turning about the vertical (no gravity torque, so no first-order alias of the
/// series) with friction: `Pca1 Psa1 Pcb1 Psb1` come from the fit's setting.
const VERTICAL_LINK: &str = "name = \"vertical\"\nconvention = \"modified\"\n\
    coordinates = [\"q1\"]\ngravity = [0.0, 0.0, -9.81]\n[[frames]]\nname = \"link\"\n\
    parent = \"base\"\ntheta = \"q1\"\ninertia = true\nfriction = true\n";

/// A log of `model` with parameters `pi` swinging over most of a turn, 20 s at 100 Hz,
/// `q = 2.5·sin(0.5t) + 0.5·sin(1.7t)`, its torques simulated (`simulate::motion_torques`,
/// load friction with its load solved for) plus noise of standard deviation `noise`
/// (N·m).
fn swing_log(model: &Model, pi: &[f64], noise: f64) -> crate::JointLog {
    use crate::simulate::{model_log, motion_torques};
    use dvrk_logs::uniform_time;
    let (count, rate) = (2000, 100.0);
    let time = uniform_time(count, rate);
    let wave = |t: f64| {
        let (a, b) = ((0.5 * t).sin_cos(), (1.7 * t).sin_cos());
        (
            2.5 * a.0 + 0.5 * b.0,
            1.25 * a.1 + 0.85 * b.1,
            -0.625 * a.0 - 1.445 * b.0,
        )
    };
    let col = |f: &dyn Fn((f64, f64, f64)) -> f64| {
        DMatrix::from_iterator(count, 1, time.iter().map(|&t| f(wave(t))))
    };
    let (q, dq, ddq) = (col(&|w| w.0), col(&|w| w.1), col(&|w| w.2));
    let mut tau = motion_torques(model, pi, &q, &dq, &ddq);
    let mut rng = Rng::new(5);
    for v in tau.iter_mut() {
        *v += noise * (0..12).map(|_| rng.uniform(-0.5, 0.5)).sum::<f64>();
    }
    model_log(model, time, q, dq, tau)
}

/// The fit of `log` from the description `plain` through the fit's request, exact
/// signals (no filter, no trim), `method` and the setting `set` applied.
fn fit_swing(
    plain: &Model,
    log: &crate::JointLog,
    method: crate::Method,
    set: impl FnOnce(&mut crate::FitSettings),
) -> crate::FitResult {
    let mut settings = crate::FitSettings {
        method,
        ..crate::FitSettings::default()
    };
    settings.processing.filter = None;
    settings.processing.trim = 0;
    set(&mut settings);
    crate::FitRequest::of_samples([log], None, settings)
        .run(Some(plain), &crate::progress::Silent)
        .unwrap()
        .result
}

/// Synthetic recovery through the fit's request: a log simulated with a position torque
/// of order 2 (known coefficients, N·m) and noise of 2 mN·m, fitted from the description
/// without it and `position_torque_order = 2` (`--position-torque 2`): the semidefinite
/// fit recovers every coefficient within a few standard errors of the noise, and the
/// offset `Fo1` apart from them.
#[test]
fn fit_recovers_a_position_torque_within_noise() {
    let plain = Model::from_toml_str(VERTICAL_LINK, "vertical.toml").unwrap();
    let model = plain.with_position_torque(2).unwrap();
    let names = model.param_names();
    assert_eq!(&names[13..], ["Pca1", "Psa1", "Pcb1", "Psb1"]);
    let mut pi = truth(&pendulum(), 0.0)[..10].to_vec();
    let want = [0.08, 0.03, -0.05, 0.04, -0.03, 0.02, 0.01];
    pi.extend(want);
    let log = swing_log(&model, &pi, 0.002);
    let r = fit_swing(&plain, &log, crate::Method::Sdp, |s| {
        s.position_torque_order = Some(2)
    });
    for (name, want) in names[10..].iter().zip(want) {
        let got = r.parameters[name.as_str()];
        assert!((got - want).abs() < 0.002, "{name} {got} vs {want}");
    }
}

/// The pendulum with friction, whose gravity torque (about 1.2 N·m) loads its joint,
/// and its truth with load friction `Fl1 = fl` after `Fc1 Fv1 Fo1`.
fn loaded_pendulum(fl: f64) -> (Model, Model, Vec<f64>) {
    let plain = Model::from_toml_str(&one_link_with("friction = true\n"), "one.toml").unwrap();
    let model = plain.with_load_friction();
    assert_eq!(model.param_names()[13], "Fl1");
    let mut pi = truth(&pendulum(), 0.0)[..13].to_vec();
    pi.push(fl);
    (plain, model, pi)
}

/// Synthetic recovery: a log whose Coulomb friction grows with the joint's torque,
/// `Fl1 = 0.08` (the torque solved for, `Model::loaded_inverse_dynamics`), noise of
/// 2 mN·m, fitted with `load_friction` (`--load-friction`, the load the measured
/// torque): `Fl1` within noise (the errors in variables of a 2 mN·m noise on a torque of
/// about 1 N·m bias it by far less), and the constant Coulomb `Fc1` told apart from it.
#[test]
fn fit_recovers_load_friction_within_noise() {
    let (plain, model, pi) = loaded_pendulum(0.08);
    let log = swing_log(&model, &pi, 0.002);
    let r = fit_swing(&plain, &log, crate::Method::Sdp, |s| s.load_friction = true);
    let (fl, fc) = (r.parameters["Fl1"], r.parameters["Fc1"]);
    assert!((fl - 0.08).abs() < 0.003, "Fl1 {fl} vs 0.08");
    assert!((fc - 0.08).abs() < 0.003, "Fc1 {fc} vs 0.08");
    // The metrics predict the load (no measured torque in the prediction): the
    // training error is the noise's.
    let err = r.metrics.train.relative_error[0];
    assert!(err < 0.01, "relative training error {err}");
}

/// Torques whose friction falls as the load grows (`Fl1 = −0.05`, noise-free): least
/// squares follows them, the semidefinite fit holds `Fl1` at its bound 0 and stays
/// consistent.
#[test]
fn sdp_keeps_load_friction_nonnegative() {
    let (plain, _, pi) = loaded_pendulum(-0.05);
    let model = plain.with_load_friction();
    let log = swing_log(&model, &pi, 0.0);
    let ols = fit_swing(&plain, &log, crate::Method::Ols, |s| s.load_friction = true);
    let fl = ols.parameters["Fl1"];
    assert!((fl + 0.05).abs() < 1e-6, "least squares Fl1 {fl}");
    let sdp = fit_swing(&plain, &log, crate::Method::Sdp, |s| s.load_friction = true);
    let fl = sdp.parameters["Fl1"];
    assert!((0.0..1e-6).contains(&fl), "semidefinite Fl1 {fl}");
    let values: Vec<f64> = sdp.parameters.values().copied().collect();
    assert!(model
        .frame(1)
        .elements
        .iter()
        .all(|e| e.consistent(&values, -1e-9)));
}
