//! What a result says the data identified (`parameter_status`, `LinkResult::determined`)
//! on a robot whose null space is known analytically: a planar two-link arm in a
//! vertical plane (modified DH, parallel z axes, gravity along −y, link 2 at `a = 0.3`
//! m along x₁).
//!
//! Joint torques about z see a link only through `Lzz`, `lx`, `ly` and `m`, and link 2
//! folds into link 1 through the joint at `(a, 0, 0)`: the classical base parameters
//! (Khalil & Dombre, "Modeling, Identification and Control of Robots", §12.3) are
//! `ZZR1 = L1zz + a²·m2`, `MXR1 = l1x + a·m2`, `MY1 = l1y`, `ZZ2 = L2zz`, `MX2 = l2x`,
//! `MY2 = l2y`, and friction `Fc, Fv, Fo` of each joint by itself. So exactly `l1y`,
//! `L2zz`, `l2x`, `l2y` and the six friction parameters are identifiable one by one;
//! every other link parameter (`L1zz`, `l1x`, `m2` lumped; `m1`, `Lxx … Lyz`, `lz`
//! unseen) is not.

use dvrk_ident::simulate::{model_log, motion_torques};
use dvrk_ident::ParameterStatus;
use dvrk_ident::Silent;
use dvrk_ident::{FitRequest, FitResult, FitSettings, JointLog, Method};
use dvrk_logs::uniform_time;
use dvrk_model::{inertia, Model};
use nalgebra::DMatrix;

/// `fo_max` bounds the offsets at 0.2 N·m; the truth below puts `Fo1 = +0.3` and
/// `Fo2 = −0.3` outside them.
const ARM: &str = include_str!("../../../tests/fixtures/planar_2r_offset_bounds.toml");

/// The parameters identifiable one by one (see the module documentation).
const IDENTIFIABLE: [&str; 10] = [
    "l1y", "L2zz", "l2x", "l2y", "Fc1", "Fv1", "Fo1", "Fc2", "Fv2", "Fo2",
];

fn arm() -> Model {
    Model::from_toml_str(ARM, "planar2r.toml").unwrap()
}

/// Box-like links with off-axis centres of mass, friction, offsets ±0.3 N·m.
fn truth(model: &Model) -> Vec<f64> {
    let mut pi = vec![0.0; model.n_params()];
    let links = [
        (
            1.5,
            [0.15, 0.02, 0.01],
            [0.004, 0.0, 0.0, 0.012, 0.0, 0.013],
        ),
        (
            1.0,
            [0.12, -0.01, 0.0],
            [0.002, 0.0, 0.0, 0.006, 0.0, 0.007],
        ),
    ];
    for (&j, (m, com, i)) in model.link_frames().iter().zip(links) {
        let p0 = model.frame(j).inertia.unwrap();
        pi[p0..p0 + 10].copy_from_slice(&inertia::barycentric_from_standard(m, com, i));
    }
    for (name, v) in [
        ("Fc1", 0.1),
        ("Fv1", 0.05),
        ("Fo1", 0.3),
        ("Fc2", 0.08),
        ("Fv2", 0.03),
        ("Fo2", -0.3),
    ] {
        pi[model.param_index(name).unwrap()] = v;
    }
    pi
}

/// Two sines per joint, `seconds` at `rate` Hz, Gaussian torque noise of std `noise`
/// (N·m).
fn simulate(model: &Model, params: &[f64], seconds: f64, rate: f64, noise: f64) -> JointLog {
    let count = (seconds * rate) as usize;
    let time = uniform_time(count, rate);
    let mut gauss = dvrk_test_support::Rng::new(7);
    let (mut q, mut dq, mut ddq) = (
        DMatrix::zeros(count, 2),
        DMatrix::zeros(count, 2),
        DMatrix::zeros(count, 2),
    );
    let waves = [
        [(0.9, 0.7, 0.0), (2.3, 0.3, 1.0)],
        [(1.3, 0.9, 0.5), (3.1, 0.4, 2.0)],
    ];
    for (k, &t) in time.iter().enumerate() {
        for (j, w) in waves.iter().enumerate() {
            for &(f, a, ph) in w {
                let om = std::f64::consts::TAU * f / 2.0;
                q[(k, j)] += a * (om * t + ph).sin();
                dq[(k, j)] += a * om * (om * t + ph).cos();
                ddq[(k, j)] -= a * om * om * (om * t + ph).sin();
            }
        }
    }
    let mut tau = motion_torques(model, params, &q, &dq, &ddq);
    for v in tau.iter_mut() {
        *v += noise * gauss.normal();
    }
    model_log(model, time, q, dq, tau)
}

fn settings(method: Method) -> FitSettings {
    let mut s = FitSettings {
        method,
        ..FitSettings::default()
    };
    // Exact signals: no filter, the analytic velocity.
    s.processing.filter = None;
    s.processing.trim = 0;
    s
}

/// Every parameter not listed in `at_bounds` is identified exactly when it is one of
/// [`IDENTIFIABLE`].
fn check_classification(r: &FitResult, at_bounds: &[(&str, ParameterStatus)]) {
    assert_eq!(r.parameter_status.len(), r.parameters.len());
    for (name, s) in &r.parameter_status {
        let expected = match at_bounds.iter().find(|(n, _)| n == name) {
            Some(&(_, s)) => s,
            None if IDENTIFIABLE.contains(&name.as_str()) => ParameterStatus::Identified,
            None => ParameterStatus::Unidentified,
        };
        assert_eq!(*s, expected, "{} {name} = {}", r.method, r.parameters[name]);
    }
}

#[test]
fn least_squares_identifies_exactly_the_analytic_base_parameters_that_stand_alone() {
    let model = arm();
    let log = simulate(&model, &truth(&model), 30.0, 100.0, 0.001);
    for method in [Method::Ols, Method::Wls] {
        let r = FitRequest::of_samples([&log], None, settings(method))
            .run(Some(&model), &Silent)
            .unwrap()
            .result;
        // No bounds in least squares: the offsets outside fo_max are identified.
        check_classification(&r, &[]);
        for l in &r.links {
            let d = l.determined.unwrap();
            assert!(!d.mass && !d.inertia, "{}: {d:?}", l.link);
            assert!(
                !d.first_moment,
                "{}: l1x (link 1) and l2z are not identifiable",
                l.link
            );
        }
    }
}

#[test]
fn a_parameter_on_a_bound_of_the_semidefinite_fit_is_reported_at_it() {
    let model = arm();
    let log = simulate(&model, &truth(&model), 30.0, 100.0, 0.001);
    let r = FitRequest::of_samples([&log], None, settings(Method::Sdp))
        .run(Some(&model), &Silent)
        .unwrap()
        .result;
    assert!(r.solver.converged, "{}", r.solver.status);
    // On their bounds to the solver's tolerance (the data ask for ±0.3 N·m).
    assert!(
        (r.parameters["Fo1"] - 0.2).abs() < 1e-6,
        "{}",
        r.parameters["Fo1"]
    );
    assert!(
        (r.parameters["Fo2"] + 0.2).abs() < 1e-6,
        "{}",
        r.parameters["Fo2"]
    );
    check_classification(
        &r,
        &[
            ("Fo1", ParameterStatus::AtUpperBound),
            ("Fo2", ParameterStatus::AtLowerBound),
        ],
    );
    // The document keeps them through JSON.
    let back = FitResult::from_json(&r.to_json(), "test").unwrap();
    assert_eq!(back.parameter_status, r.parameter_status);
    assert_eq!(back.links, r.links);
}

#[test]
fn data_drowned_in_noise_identify_nothing() {
    // The same structure, but 40 rows of torques whose noise (30 N·m) is about a hundred
    // times the signal: a standard deviation of each parameter is far above a tenth of
    // its plausible magnitude, so even the structurally identifiable ones are not
    // determined.
    let model = arm();
    let log = simulate(&model, &truth(&model), 0.5, 40.0, 30.0);
    let r = FitRequest::of_samples([&log], None, settings(Method::Ols))
        .run(Some(&model), &Silent)
        .unwrap()
        .result;
    let identified: Vec<&String> = r
        .parameter_status
        .iter()
        .filter(|(_, s)| s.identified())
        .map(|(k, _)| k)
        .collect();
    assert!(identified.is_empty(), "{identified:?}");
}

#[test]
fn a_result_written_before_parameter_statuses_still_loads() {
    let model = arm();
    let log = simulate(&model, &truth(&model), 5.0, 100.0, 0.001);
    let r = FitRequest::of_samples([&log], None, settings(Method::Ols))
        .run(Some(&model), &Silent)
        .unwrap()
        .result;
    let mut doc: serde_json::Value = serde_json::from_str(&r.to_json()).unwrap();
    doc.as_object_mut().unwrap().remove("parameter_status");
    for l in doc["links"].as_array_mut().unwrap() {
        l.as_object_mut().unwrap().remove("determined");
    }
    let old = FitResult::from_json(&doc.to_string(), "old.json").unwrap();
    assert!(old.parameter_status.is_empty());
    assert!(old.links.iter().all(|l| l.determined.is_none()));
    assert!(old.link_status(&old.links[0]).is_none());
    // Nothing is known, so no export warns.
    let params = old.params_for(&model).unwrap();
    let exported = dvrk_ident::export::Export::WpiParams
        .build_for(&model, &params, &old)
        .unwrap();
    assert!(exported.undetermined.is_empty());
}

/// A partial prior (`--prior nominal` on a description that gives a nominal mass to
/// link 1 only, as the dVRK's publishes link masses and nothing else) moves the mass the
/// data cannot see (`m1`: link 1's origin is on the fixed joint axis) to its nominal
/// value and leaves the base parameters where the data put them.
#[test]
fn a_partial_prior_moves_an_unidentified_mass_and_not_the_base_parameters() {
    use dvrk_ident::Overrides;
    use dvrk_ident::PriorSource;
    let truth_model = arm();
    let log = simulate(&truth_model, &truth(&truth_model), 30.0, 100.0, 0.001);
    // The truth has m1 = 1.5 kg; the nominal says 3 kg.
    let described = ARM.replacen(
        "theta = \"q1\"\n",
        "theta = \"q1\"\nnominal = { mass = 3.0 }\n",
        1,
    );
    let model = Model::from_toml_str(&described, "planar2r_nominal.toml").unwrap();
    let plain = FitRequest::of_samples([&log], None, settings(Method::Sdp))
        .run(Some(&model), &Silent)
        .unwrap()
        .result;
    let with_prior = Overrides {
        prior: Some(PriorSource::Nominal),
        prior_weight: Some(1e-2),
        ..Overrides::default()
    }
    .settings_for(settings(Method::Sdp), &model)
    .unwrap();
    let prior = with_prior.prior.as_ref().unwrap();
    // Partial: link 1's mass and nothing else (link 2 has no nominal mass, and the
    // friction's zero defaults are no published value).
    assert_eq!(prior.parameters.keys().collect::<Vec<_>>(), ["m1"]);
    assert!(
        prior.source.starts_with("nominal (partial"),
        "{}",
        prior.source
    );
    let r = FitRequest::of_samples([&log], None, with_prior.clone())
        .run(Some(&model), &Silent)
        .unwrap()
        .result;
    assert!(r.solver.converged, "{}", r.solver.status);
    let (m0, m) = (plain.parameters["m1"], r.parameters["m1"]);
    println!("m1: {m0} kg without the prior, {m} kg with it (nominal 3)");
    assert!((m0 - 3.0).abs() > 0.5, "without the prior m1 = {m0}");
    assert!((m - 3.0).abs() < 0.03, "with the prior m1 = {m}");
    // The base parameters (module documentation), with and without the prior.
    let a = 0.3;
    let base = |p: &indexmap::IndexMap<String, f64>| {
        vec![
            p["L1zz"] + a * a * p["m2"],
            p["l1x"] + a * p["m2"],
            p["l1y"],
            p["L2zz"],
            p["l2x"],
            p["l2y"],
        ]
    };
    for (k, (b0, b)) in base(&plain.parameters)
        .into_iter()
        .zip(base(&r.parameters))
        .enumerate()
    {
        // 1e-4 kg·m or kg·m²: the noise (1 mN·m on 3000 samples) moves them by ~1e-5.
        assert!((b - b0).abs() < 1e-4, "base parameter {k}: {b0} -> {b}");
    }
    let (e0, e) = (
        plain.metrics.train.relative_error.clone(),
        r.metrics.train.relative_error.clone(),
    );
    for (x0, x) in e0.iter().zip(&e) {
        assert!((x - x0).abs() <= 0.01 * x0 + 1e-6, "{e0:?} -> {e:?}");
    }
}
