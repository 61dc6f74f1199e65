//! The delay search (`fit::delay`) against the fit itself: the residual it reports at
//! the delays it finds is the residual of the least-squares fit run with those delays
//! fixed (an independent path: the log processed once with them, the R factor, the
//! solve), and moving any one delay by ±1 ms (fractional samples at 200 Hz) only raises
//! that fit's residual. Both hold only if a fractional delay is the affine combination
//! of two whole-sample shifts that the search assumes.

use std::path::PathBuf;

use dvrk_ident::excite::FourierTrajectory;
use dvrk_ident::simulate::{simulate, Simulation};
use dvrk_ident::Silent;
use dvrk_ident::{FitRequest, FitResult, FitSettings, Method};
use dvrk_model::Model;

fn example(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples")
        .join(name)
}

/// `Σ_j (rms_j)²·samples`: the training residual sum of squares (OLS: unit weights).
fn rss(r: &FitResult) -> f64 {
    let m = &r.metrics.train;
    m.rms.iter().map(|e| e * e * m.samples as f64).sum()
}

#[test]
fn search_residual_is_the_fit_residual_and_a_minimum() {
    let model = Model::builtin("psm").unwrap();
    let text = std::fs::read_to_string(example("psm_params.json")).unwrap();
    let doc: serde_json::Value = serde_json::from_str(&text).unwrap();
    let named = doc["parameters"].as_object().unwrap();
    let params = model
        .params_from_named(
            named.iter().map(|(k, v)| (k.as_str(), v.as_f64().unwrap())),
            "params",
        )
        .unwrap();
    let traj = FourierTrajectory::from_json_file(example("psm_trajectory.json")).unwrap();
    let truth = [0.003, 0.0, 0.0211, 0.0, 0.047, 0.012, 0.0];
    let log = simulate(
        &model,
        &params,
        &traj,
        &Simulation {
            duration_s: Some(2.0 * traj.period_s()),
            noise_std: vec![0.002],
            seed: 5,
            delay_s: truth.to_vec(),
            ..Simulation::default()
        },
    )
    .unwrap();
    let searched = FitSettings {
        method: Method::Ols,
        delay_search_s: Some(0.05),
        ..FitSettings::default()
    };
    let r = FitRequest::of_samples([&log], None, searched.clone())
        .run(Some(&model), &Silent)
        .unwrap()
        .result;
    let found = r.delay.clone().unwrap();
    println!(
        "found (ms) {:?}",
        found.delay_s.iter().map(|d| d * 1e3).collect::<Vec<_>>()
    );
    // Recovery to 1 ms is `cli_delay`'s (3 periods); on these 2 periods, within 2 ms.
    for (f, t) in found.delay_s.iter().zip(truth) {
        assert!((f - t).abs() < 2e-3, "{f} vs {t}");
        assert!((0.0..=0.05).contains(f));
    }
    let fixed = |d: Vec<f64>| {
        let mut s = FitSettings {
            method: Method::Ols,
            ..FitSettings::default()
        };
        s.processing.delay_s = d;
        rss(&FitRequest::of_samples([&log], None, s.clone())
            .run(Some(&model), &Silent)
            .unwrap()
            .result)
    };
    let at = fixed(found.delay_s.clone());
    assert!(
        (at - found.residual).abs() <= 1e-8 * at,
        "search {} vs fit {at}",
        found.residual
    );
    assert!((rss(&r) - at).abs() <= 1e-12 * at);
    for j in 0..model.dof() {
        for step in [-1e-3, 1e-3] {
            let mut d = found.delay_s.clone();
            d[j] = (d[j] + step).clamp(0.0, 0.05);
            if d[j] == found.delay_s[j] {
                continue;
            }
            let moved = fixed(d);
            assert!(
                moved >= at * (1.0 - 1e-10),
                "q{} moved by {step} s: residual {moved} < {at}",
                j + 1
            );
        }
    }
}
