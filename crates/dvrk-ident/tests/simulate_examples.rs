//! The bundled example inputs (`examples/` at the workspace root) are what their README
//! says: `psm_trajectory.json` is the 2019 `psm_one` trajectory, `psm_params.json` the
//! rule below (physically consistent, inside `robots/psm.toml`'s bounds).
//!
//! Regenerate both with `DVRK_WRITE_EXAMPLES=1 cargo test -p dvrk-ident --test
//! simulate_examples` (the trajectory needs `shared/anchors`), then the log with the
//! command in `examples/README.md`.

use std::path::PathBuf;

use dvrk_ident::excite::FourierTrajectory;
use dvrk_model::{inertia, Model};

fn examples() -> PathBuf {
    dvrk_test_support::repo().join("examples")
}

fn anchor(name: &str) -> Option<PathBuf> {
    dvrk_test_support::shared(&format!("anchors/{name}"))
}

fn write_examples() -> bool {
    std::env::var_os("DVRK_WRITE_EXAMPLES").is_some()
}

/// The example parameters: per link a mass at mid-range of its bounds but at most
/// 0.5 kg above the lower bound, the centre of mass at the middle of its box, the
/// inertia of a 6 x 5 x 4 cm box about it; Coulomb 0.5, viscous 0.3 and offset 0.2 of
/// their maxima; motor inertias 0.002; springs at mid-range.
fn example_params(model: &Model) -> Vec<f64> {
    let mass = |bounds: Option<[f64; 2]>| {
        let [lo, hi] = bounds.unwrap_or([0.5, 1.5]);
        (0.5 * (lo + hi)).min(lo + 0.5)
    };
    dvrk_test_support::ParamRule {
        mass: Box::new(mass),
        inertia_com: Box::new(dvrk_test_support::box_inertia),
        friction: Box::new(dvrk_test_support::friction_within_bounds),
        motor_inertia: 0.002,
        spring: Box::new(dvrk_test_support::mid_spring),
    }
    .params(model)
}

#[test]
fn example_params_are_the_documented_rule_and_consistent() {
    let model = Model::builtin("psm").unwrap();
    let truth = example_params(&model);
    let path = examples().join("psm_params.json");
    if write_examples() {
        // In the model's order (serde_json's own map would sort the names).
        let params: indexmap::IndexMap<String, f64> = model
            .param_names()
            .into_iter()
            .zip(truth.iter().copied())
            .collect();
        #[derive(serde::Serialize)]
        struct Doc {
            description: &'static str,
            robot: &'static str,
            parameters: indexmap::IndexMap<String, f64>,
        }
        let doc = Doc {
            description: "Example PSM parameters (robot psm; per link barycentric: inertia about the frame origin kg*m^2, first moment kg*m, mass kg; friction; motor inertia; spring). Rule: example_params in crates/dvrk-ident/tests/simulate_examples.rs.",
            robot: "psm",
            parameters: params,
        };
        std::fs::write(&path, serde_json::to_string_pretty(&doc).unwrap() + "\n").unwrap();
    }
    let text = std::fs::read_to_string(&path).unwrap();
    let doc: serde_json::Value = serde_json::from_str(&text).unwrap();
    let map = doc["parameters"].as_object().unwrap();
    let file = model
        .params_from_named(
            map.iter().map(|(k, v)| (k.as_str(), v.as_f64().unwrap())),
            "file",
        )
        .unwrap();
    for (k, (a, b)) in file.iter().zip(&truth).enumerate() {
        assert!(
            (a - b).abs() <= 1e-15 * b.abs().max(1.0),
            "{}: file {a} vs rule {b}",
            model.params[k].name
        );
    }
    // Physically consistent, with a margin above the SDP's pseudo-inertia epsilon, and
    // inside every bound of the description.
    for &j in model.link_frames() {
        let f = model.frame(j);
        let p0 = f.inertia.unwrap();
        let e = inertia::pseudo_inertia_min_eigenvalue(&file[p0..p0 + 10]);
        assert!(
            e > 10.0 * model.bounds.pseudo_inertia_eps,
            "{}: {e}",
            f.name
        );
        let s = inertia::standard_from_barycentric(&file[p0..p0 + 10]);
        if let Some([lo, hi]) = f.bounds.mass {
            assert!(lo < s.mass && s.mass < hi, "{}", f.name);
        }
        if let Some(b) = f.bounds.com {
            for ([lo, hi], c) in b.iter().zip(s.com) {
                assert!(*lo <= c && c <= *hi, "{}", f.name);
            }
        }
    }
    for f in &model.frames {
        if let Some(fr) = f.friction() {
            let (fc, fv, fo) = (file[fr.param], file[fr.param + 1], file[fr.param + 2]);
            assert!(fc >= model.bounds.fc_min && fc <= f.bounds.fc_max.unwrap());
            assert!(fv >= model.bounds.fv_min && fv <= f.bounds.fv_max.unwrap());
            assert!(fo.abs() <= f.bounds.fo_max.unwrap());
        }
        if let Some(mi) = f.motor_inertia() {
            assert!(file[mi.param] >= model.bounds.ia_min);
        }
        if let (Some(sp), Some([lo, hi])) = (f.spring(), f.bounds.spring) {
            assert!(lo <= file[sp.param] && file[sp.param] <= hi);
        }
    }
}

#[test]
fn example_trajectory_is_the_2019_psm_one() {
    let path = examples().join("psm_trajectory.json");
    let Some(anchor) = anchor("wpi2019_excitation_trajectories.json") else {
        // Without the anchor, at least check that the example reads.
        FourierTrajectory::from_json_file(&path).unwrap();
        return;
    };
    let expected = FourierTrajectory::from_wpi_file(&anchor, "psm_one").unwrap();
    if write_examples() {
        std::fs::write(&path, expected.to_json() + "\n").unwrap();
    }
    let file = FourierTrajectory::from_json_file(&path).unwrap();
    assert_eq!(file, expected);
    assert_eq!(file.coordinates, Model::builtin("psm").unwrap().coordinates);
}
