//! Acceptance on the real dVRK measurements, following the 2019 protocol
//! (docs/book/src/dvrk.md §5, `support/protocol_2019.rs`): fit on trajectory "one", test on "two"
//! over the first period, 6th-order zero-phase Butterworth at the cut-offs the 2019 code
//! effectively applied (π·fc: 16.965 Hz PSM, 5.655 Hz MTM) on the motion and the
//! torques, 200 samples trimmed. Prints the table; skips with a reason when ../shared
//! is absent.

#[path = "support/protocol_2019.rs"]
mod protocol_2019;

use dvrk_ident::Silent;
use dvrk_ident::{FitRequest, FitResult, JointLog, Method};
use dvrk_model::Model;
use protocol_2019::{settings, stribeck_settings, Protocol};
use serde::Deserialize;
use std::collections::HashMap;

/// One robot's protocol and figures.
struct Case {
    protocol: Protocol,
    figures: Figures,
}

/// One robot's figures in `fixtures/acceptance_2019.toml`: test relative errors per
/// joint.
#[derive(Deserialize)]
struct Figures {
    /// Published 2019 test errors (MTM OLS: the 2019 code rerun).
    published: Published,
    /// Our SDP test errors with the 2019 bounds (regression guard, see `run`).
    sdp_guard: [f64; 7],
    /// What helped beyond 2019 (regression guards, see `beyond_2019`): WLS with a
    /// Stribeck term (vs = 0.3), and the SDP with a Stribeck term and zero lower bounds
    /// on Fc, Fv, Ia.
    stribeck_wls_guard: [f64; 7],
    stribeck_sdp_guard: [f64; 7],
}

#[derive(Deserialize)]
struct Published {
    ols: [f64; 7],
    wls: [f64; 7],
    sdp: [f64; 7],
}

impl Published {
    fn by_method(&self) -> [(Method, [f64; 7]); 3] {
        [
            (Method::Ols, self.ols),
            (Method::Wls, self.wls),
            (Method::Sdp, self.sdp),
        ]
    }
}

/// The case of `protocol`'s robot, its figures from the fixture.
fn case(protocol: Protocol) -> Case {
    let text = include_str!("fixtures/acceptance_2019.toml");
    let mut all: HashMap<String, Figures> = toml::from_str(text).expect("the figures' TOML");
    let figures = all
        .remove(protocol.robot)
        .unwrap_or_else(|| panic!("no figures for {}", protocol.robot));
    Case { protocol, figures }
}

fn check_sdp(model: &Model, r: &FitResult) {
    assert!(r.solver.converged, "SDP status {}", r.solver.status);
    // The solve time is printed, never asserted: a test's outcome must not depend on
    // the machine's speed (the bench binaries measure it).
    println!("SDP solve {:.3} s ({})", r.solver.seconds, r.solver.status);
    let eps = model.bounds.pseudo_inertia_eps;
    for c in &r.consistency {
        assert!(
            c.min_eigenvalue >= eps * 0.99,
            "{}: {}",
            c.link,
            c.min_eigenvalue
        );
    }
    let b = &model.bounds;
    for (p, v) in model.params.iter().zip(r.params_for(model).unwrap()) {
        let f = model.frame(p.frame);
        let tol = 1e-6;
        match p.kind {
            dvrk_model::ParamKind::Coulomb => {
                assert!(
                    v >= b.fc_min - tol && v <= f.bounds.fc_max.unwrap_or(f64::INFINITY) + tol,
                    "{} = {v}",
                    p.name
                )
            }
            dvrk_model::ParamKind::Viscous => {
                assert!(
                    v >= b.fv_min - tol && v <= f.bounds.fv_max.unwrap_or(f64::INFINITY) + tol,
                    "{} = {v}",
                    p.name
                )
            }
            dvrk_model::ParamKind::MotorInertia => assert!(v >= b.ia_min - tol, "{} = {v}", p.name),
            _ => {}
        }
    }
}

fn run(case: &Case) {
    let Some((model, train, test)) = protocol_2019::load(&case.protocol) else {
        return;
    };
    println!(
        "{} test errors (first period), ours vs 2019:",
        case.protocol.robot
    );
    for (method, published) in &case.figures.published.by_method() {
        let s = settings(&case.protocol, *method);
        let r = FitRequest::of_samples([&train], Some(&test), s.clone())
            .run(Some(&model), &Silent)
            .unwrap()
            .result;
        let ours = &r.metrics.test.as_ref().unwrap().relative_error;
        let row: Vec<String> = ours
            .iter()
            .zip(published)
            .map(|(o, p)| format!("{o:.4}/{p:.4}"))
            .collect();
        println!(
            "  {:<4} {}  ({:.3} s)",
            r.method,
            row.join(" "),
            r.solver.seconds
        );
        // Least squares: every joint within 0.005 of 2019. The semidefinite fit cannot
        // reach the published SDP numbers on every joint with the 2019 lower bounds
        // (Fc, Fv, Ia >= 0.001): the published 2019 parameters (WPI params.json)
        // themselves violate those bounds (negative motor inertias, viscous friction
        // below 0.001, negative link inertias) — the 2019 SCS solve stopped at an
        // infeasible point. For the SDP the bound is therefore our own current result
        // (a regression guard), and the comparison with 2019 is printed above.
        let limit: [f64; 7] = if *method == Method::Sdp {
            case.figures.sdp_guard
        } else {
            *published
        };
        for (j, (o, p)) in ours.iter().zip(limit).enumerate() {
            assert!(
                *o <= p + 0.005,
                "{} {} joint {}: {o:.4} > {p:.4} + 0.005",
                case.protocol.robot,
                r.method,
                j + 1
            );
        }
        if *method == Method::Sdp {
            check_sdp(&s.model(&model).unwrap(), &r);
        }
    }
    beyond_2019(case, &model, &train, &test);
}

/// What helped beyond the 2019 models, printed and guarded as regressions:
/// a Stribeck friction term (vs = 0.3 rad/s or m/s) on every friction element, and
/// for the physically consistent fit also zero lower bounds on Fc, Fv and Ia (the 2019
/// bounds of 0.001 exceed what the wrist data support, see `run`).
fn beyond_2019(case: &Case, model: &Model, train: &JointLog, test: &JointLog) {
    let sdp_published = case.figures.published.sdp;
    for (label, m, method, guard) in [
        (
            "WLS + Stribeck",
            model,
            Method::Wls,
            case.figures.stribeck_wls_guard,
        ),
        (
            "SDP + Stribeck, physical bounds",
            model,
            Method::Sdp,
            case.figures.stribeck_sdp_guard,
        ),
    ] {
        let s = stribeck_settings(&case.protocol, method);
        let r = FitRequest::of_samples([train], Some(test), s.clone())
            .run(Some(m), &Silent)
            .unwrap()
            .result;
        let ours = &r.metrics.test.as_ref().unwrap().relative_error;
        let better = ours
            .iter()
            .zip(sdp_published)
            .filter(|(o, p)| *o < p)
            .count();
        println!(
            "  {label}: {}  (better than the 2019 SDP on {better} of 7 joints)",
            ours.iter()
                .map(|o| format!("{o:.4}"))
                .collect::<Vec<_>>()
                .join(" ")
        );
        for (j, (o, g)) in ours.iter().zip(guard).enumerate() {
            assert!(
                *o <= g + 0.002,
                "{} {label} joint {}: {o:.4} > {g:.4}",
                case.protocol.robot,
                j + 1
            );
        }
        if method == Method::Sdp {
            let m = s.model(m).unwrap();
            check_sdp(&m, &r);
            assert!(r.physically_consistent);
            // On the MTM this beats the published 2019 SDP on every joint.
            if case.protocol.robot == "mtm" {
                assert_eq!(better, 7, "{ours:?}");
            }
        }
    }
}

/// Issue 14's acceptance: `fit --method sdp --delay auto --stribeck 0.3` with the
/// robot's default (physical) bounds is converged and physically consistent, and on
/// every joint at most the published 2019 SDP test error, the mean lower by
/// `mean_gain` (0.20 PSM, 0.10 MTM). Prints the delays and the solve time (never
/// asserted: see `check_sdp`).
fn delays_beat_2019(case: &Case, mean_gain: f64) {
    let Some((model, train, test)) = protocol_2019::load(&case.protocol) else {
        return;
    };
    let s = protocol_2019::delay_settings(&case.protocol);
    let r = FitRequest::of_samples([&train], Some(&test), s.clone())
        .run(Some(&model), &Silent)
        .unwrap()
        .result;
    let m = s.model(&model).unwrap();
    check_sdp(&m, &r);
    assert!(r.physically_consistent, "{}", case.protocol.robot);
    let d = r.delay.as_ref().expect("delays estimated");
    println!(
        "{} delays (ms): {}",
        case.protocol.robot,
        d.delay_s
            .iter()
            .zip(&d.std_s)
            .map(|(v, e)| format!("{:.1}±{:.1}", v * 1e3, e * 1e3))
            .collect::<Vec<_>>()
            .join(" ")
    );
    assert_eq!(r.settings.processing.delay_s, d.delay_s);
    let ours = &r.metrics.test.as_ref().unwrap().relative_error;
    let published = case.figures.published.sdp;
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let gain = 1.0 - mean(ours) / mean(&published);
    println!(
        "{} SDP + delays + Stribeck, physical bounds: {}  (mean {:.4} vs 2019 SDP {:.4}: {:.1} % lower)",
        case.protocol.robot,
        ours.iter()
            .map(|o| format!("{o:.4}"))
            .collect::<Vec<_>>()
            .join(" "),
        mean(ours),
        mean(&published),
        100.0 * gain
    );
    for (j, (o, p)) in ours.iter().zip(published).enumerate() {
        assert!(
            *o <= p,
            "{} joint {}: {o:.4} > 2019 SDP {p:.4}",
            case.protocol.robot,
            j + 1
        );
    }
    assert!(
        gain >= mean_gain,
        "{}: mean {:.1} % lower than 2019, wanted {:.0} %",
        case.protocol.robot,
        100.0 * gain,
        100.0 * mean_gain
    );
}

#[test]
fn psm_delays_beat_2019() {
    delays_beat_2019(&case(protocol_2019::PSM), 0.20);
}

#[test]
fn mtm_delays_beat_2019() {
    delays_beat_2019(&case(protocol_2019::MTM), 0.10);
}

#[test]
fn psm_2019_protocol() {
    run(&case(protocol_2019::PSM));
}

#[test]
fn mtm_2019_protocol() {
    run(&case(protocol_2019::MTM));
}

/// The mean over the joints of a result's test relative errors.
fn mean_test_error(r: &FitResult) -> f64 {
    let e = &r.metrics.test.as_ref().unwrap().relative_error;
    e.iter().sum::<f64>() / e.len() as f64
}

/// Rows `a..b` of a log.
fn rows(t: &JointLog, a: usize, b: usize) -> JointLog {
    JointLog {
        time: t.time[a..b].to_vec(),
        q: t.q.rows(a, b - a).into_owned(),
        dq: t.dq.as_ref().map(|d| d.rows(a, b - a).into_owned()),
        tau: t.tau.rows(a, b - a).into_owned(),
        source: format!("{} rows {}..{}", t.source, a + 1, b),
        ..t.clone()
    }
}

/// Issue 14's priors on real data (the table of docs/book/src/fit.md, in part): the prior
/// is the fit of trajectory "one" (SDP, delays, Stribeck); the fit is periods 2–3 of "two"
/// with those delays; the test is the first period of "two", which neither saw. Every fit converges
/// and is physically consistent; a heavier weight stays closer to the prior; at the
/// default weight the held-out error is within 3 % of the fit without a prior (measured:
/// +0.6/−0.0 % PSM, +2.0/+0.1 % MTM, entropic/Euclidean).
fn priors_on_a_short_log(case: &Case) {
    use dvrk_ident::{Prior, PriorMetric};
    let Some((model, one, two)) = protocol_2019::load(&case.protocol) else {
        return;
    };
    let w = case.protocol.window;
    let prior_fit =
        FitRequest::of_samples([&one], None, protocol_2019::delay_settings(&case.protocol))
            .run(Some(&model), &Silent)
            .unwrap()
            .result;
    assert!(prior_fit.solver.converged);
    let short = rows(&two, w, (3 * w).min(two.len()));
    let mut s = protocol_2019::delay_settings(&case.protocol);
    s.delay_search_s = None;
    s.processing.delay_s = prior_fit.settings.processing.delay_s.clone();
    let mean = mean_test_error;
    let none = FitRequest::of_samples([&short], Some(&two), s.clone())
        .run(Some(&model), &Silent)
        .unwrap()
        .result;
    assert!(none.solver.converged && none.physically_consistent);
    println!(
        "{} prior \"one\" → periods 2-3 of \"two\": no prior {:.4}",
        case.protocol.robot,
        mean(&none)
    );
    for metric in [PriorMetric::Entropic, PriorMetric::Euclidean] {
        let mut last_divergence = f64::INFINITY;
        for weight in [Prior::DEFAULT_WEIGHT, 1.0] {
            let mut sp = s.clone();
            sp.prior = Some(Prior {
                source: "fit of one".into(),
                metric,
                weight,
                parameters: prior_fit.parameters.clone(),
            });
            let r = FitRequest::of_samples([&short], Some(&two), sp.clone())
                .run(Some(&model), &Silent)
                .unwrap()
                .result;
            assert!(
                r.solver.converged,
                "{metric:?} {weight}: {}",
                r.solver.status
            );
            assert!(r.physically_consistent, "{metric:?} {weight}");
            println!(
                "  {} {weight}: {:.4} ({:+.1} %), divergence {:?}",
                metric.name(),
                mean(&r),
                100.0 * (mean(&r) / mean(&none) - 1.0),
                r.prior_divergence
            );
            if let Some(d) = r.prior_divergence {
                assert!(d < last_divergence);
                last_divergence = d;
            }
            if weight == Prior::DEFAULT_WEIGHT {
                assert!(mean(&r) <= 1.03 * mean(&none), "{metric:?}");
            }
        }
    }
}

#[test]
fn psm_priors_on_a_short_log() {
    priors_on_a_short_log(&case(protocol_2019::PSM));
}

#[test]
fn mtm_priors_on_a_short_log() {
    priors_on_a_short_log(&case(protocol_2019::MTM));
}

/// Project issue 27 on real data: `--preset dvrk` (with the 2019 protocol's processing)
/// against the same preset without the bounding ellipsoids and the prior toward the
/// nominal masses (`--no-ellipsoids --prior none`). The price in prediction is at most
/// 2 % of the mean test error (measured: PSM 0.1257 against 0.1265, −0.6 %, with the CAD
/// masses of `psm.toml`; MTM 0.1726 against 0.1729, −0.2 %, with the position torque of
/// `mtm.toml`'s `[preset]` in both); every link with a nominal mass ends within 0.25–4
/// times it (measured: MTM 0.77–1.00, PSM 0.28–1.72; without the prior the MTM's upper
/// arm is 11.5 times its mass and the PSM's pitch_intermediate 10 times), and no link
/// mass of either arm on a bound (without the prior the PSM's pitch_intermediate,
/// pitch_bottom and pitch_top sit on theirs; without the `[preset]` position torque the
/// MTM's back parallelogram link sits on its 10 kg upper bound and the front one on its
/// 0.05 kg lower bound).
fn preset_is_plausible(case: &Case, preset_mean: f64) {
    use dvrk_ident::{Overrides, Preset};
    let Some((model, train, test)) = protocol_2019::load(&case.protocol) else {
        return;
    };
    let base = protocol_2019::processing(&case.protocol);
    let fit = |extra: Overrides| {
        let overrides = Overrides {
            preset: Some(Preset::Dvrk),
            ..extra
        };
        FitRequest {
            overrides,
            ..FitRequest::of_samples([&train], Some(&test), base.clone())
        }
        .run(Some(&model), &Silent)
        .unwrap()
        .result
    };
    let mean = mean_test_error;
    let preset = fit(Overrides::default());
    let plain = fit(Overrides {
        ellipsoids: Some(false),
        prior: Some(dvrk_ident::PriorSource::None),
        ..Overrides::default()
    });
    let robot = case.protocol.robot;
    assert!(preset.physically_consistent && plain.physically_consistent);
    // Both descriptions have nominal masses, so the preset brings its prior.
    assert!(preset.settings.prior.is_some(), "{robot}");
    let (m, p) = (mean(&preset), mean(&plain));
    println!(
        "{robot} --preset dvrk: mean test error {m:.4}, without ellipsoids and prior {p:.4} ({:+.1} %)",
        100.0 * (m / p - 1.0)
    );
    assert!((m - preset_mean).abs() < 5e-4, "{robot}: {m:.4}");
    assert!(m <= 1.02 * p, "{robot}: {m:.4} vs {p:.4}");
    for l in &preset.links {
        if let Some(m0) = model.frame(l.frame).nominal.mass {
            let ratio = l.mass / m0;
            println!("  {} {:.3} kg, {ratio:.2} x nominal", l.link, l.mass);
            assert!(
                (0.25..=4.0).contains(&ratio),
                "{robot} {}: {ratio:.2}",
                l.link
            );
        }
        assert!(
            !protocol_2019::mass_on_bound(&model, l),
            "{robot} {}: {:.4} kg on its mass bound {:?}",
            l.link,
            l.mass,
            model.frame(l.frame).bounds.mass
        );
    }
    // The MTM's description adds its cable torques to the preset's model.
    let torques: Vec<&str> = preset
        .parameters
        .keys()
        .filter(|k| k.starts_with("Pc") || k.starts_with("Ps"))
        .map(String::as_str)
        .collect();
    let want: &[&str] = if robot == "mtm" {
        &["Pca2", "Psa2", "Pca3", "Psa3"]
    } else {
        &[]
    };
    assert_eq!(torques, want, "{robot}");
}

#[test]
fn psm_preset_is_plausible() {
    preset_is_plausible(&case(protocol_2019::PSM), 0.1257);
}

#[test]
fn mtm_preset_is_plausible() {
    preset_is_plausible(&case(protocol_2019::MTM), 0.1726);
}
