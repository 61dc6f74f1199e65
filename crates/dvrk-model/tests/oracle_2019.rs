//! The regressor against the 2019 package's symbolic (sympy, Lagrangian) models, column by
//! column by parameter name, and base-parameter spans.

// Reads descriptions (TOML, URDF): needs the default `description` feature.
#![cfg(feature = "description")]

use dvrk_model::{Model, Workspace};
use dvrk_test_support::*;
use nalgebra::DMatrix;

/// Compares every regressor column by name. Conventions shared with 2019: the motor
/// inertia of a frame with joint value `c·q_k + const` has column `c·q̈_k` (so the PSM
/// frame-11 column is 1.0186·q̈5), and Coulomb columns use sign(0) = 0.
fn check_regressor(robot: &str) {
    let Some(path) = shared(&format!("oracle/{robot}.json")) else {
        return;
    };
    let oracle = read_json(&path);
    let model = Model::builtin(robot).unwrap();
    let names: Vec<String> = oracle["bary_params"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s.as_str().unwrap().to_string())
        .collect();
    assert_eq!(model.param_names(), names, "parameter names and order");
    let mut ws = Workspace::new(&model);
    let (n, p) = (model.dof(), model.n_params());
    let mut worst = (0.0f64, String::new());
    for sample in oracle["samples"].as_array().unwrap() {
        let q = f64s(&sample["q"]);
        let dq = f64s(&sample["dq"]);
        let ddq = f64s(&sample["ddq"]);
        let h = model.regressor(&mut ws, &q, &dq, &ddq);
        let rows = sample["H"].as_array().unwrap();
        for r in 0..n {
            let row = f64s(&rows[r]);
            for c in 0..p {
                let d = (h[(r, c)] - row[c]).abs();
                if d > worst.0 {
                    worst = (
                        d,
                        format!(
                            "row {r} column {} ({}): ours {} 2019 {}",
                            c,
                            names[c],
                            h[(r, c)],
                            row[c]
                        ),
                    );
                }
            }
        }
    }
    eprintln!("{robot}: worst difference {:e} at {}", worst.0, worst.1);
    assert!(
        worst.0 < 1e-8,
        "{robot}: worst difference {:e} at {}",
        worst.0,
        worst.1
    );
}

#[test]
fn psm_regressor_matches_2019() {
    check_regressor("psm");
}

#[test]
fn psm_simplified_regressor_matches_2019() {
    check_regressor("psm_simplified");
}

#[test]
fn mtm_regressor_matches_2019() {
    check_regressor("mtm");
}

/// Parses a 2019 base-parameter string such as `0.5*l2y - 0.5*l6y + 1.0*l9z` into a
/// coefficient row over the parameter names.
fn parse_combination(text: &str, names: &[String]) -> Vec<f64> {
    let mut row = vec![0.0; names.len()];
    let normalized = text.replace(" - ", " + -").replace("- ", "-");
    for term in normalized.split(" + ") {
        let term = term.trim();
        let (coef, name) = match term.split_once('*') {
            Some((c, n)) => (c.parse::<f64>().unwrap(), n),
            None if term.starts_with('-') => (-1.0, &term[1..]),
            None => (1.0, term),
        };
        let k = names
            .iter()
            .position(|n| n == name)
            .unwrap_or_else(|| panic!("unknown {name}"));
        row[k] += coef;
    }
    row
}

fn rank(m: &DMatrix<f64>) -> usize {
    let sv = m.clone().svd(false, false).singular_values;
    let max = sv.max();
    sv.iter().filter(|&&s| s > 1e-7 * max).count()
}

fn check_base_span(robot: &str) {
    let Some(path) = shared(&format!("oracle/{robot}.json")) else {
        return;
    };
    let oracle = read_json(&path);
    let model = Model::builtin(robot).unwrap();
    let base = model.base_parameters().unwrap();
    let expected = oracle["base_num"].as_u64().unwrap() as usize;
    assert_eq!(base.rank(), expected, "{robot}: base parameter count");
    let names = model.param_names();
    let theirs: Vec<Vec<f64>> = oracle["base_params"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| parse_combination(s.as_str().unwrap(), &names))
        .collect();
    let p = names.len();
    let k2019 = DMatrix::from_fn(theirs.len(), p, |r, c| theirs[r][c]);
    assert_eq!(rank(&k2019), expected);
    // Same span: stacking both sets of combinations adds no dimension.
    let stacked = DMatrix::from_fn(2 * expected, p, |r, c| {
        if r < expected {
            base.combination[(r, c)]
        } else {
            k2019[(r - expected, c)]
        }
    });
    assert_eq!(
        rank(&stacked),
        expected,
        "{robot}: base parameter spans differ"
    );
    // And our base regressor reproduces the oracle's torques through β = K·π.
    let mut ws = Workspace::new(&model);
    let pi: Vec<f64> = (0..p)
        .map(|k| ((k * 37 % 11) as f64 - 5.0) * 0.01)
        .collect();
    let beta = base.project(&pi);
    for sample in oracle["samples"].as_array().unwrap() {
        let (q, dq, ddq) = (
            f64s(&sample["q"]),
            f64s(&sample["dq"]),
            f64s(&sample["ddq"]),
        );
        let h = model.regressor(&mut ws, &q, &dq, &ddq);
        let hb = h.select_columns(&base.independent);
        let lhs = &h * nalgebra::DVector::from_vec(pi.clone());
        let rhs = hb * nalgebra::DVector::from_vec(beta.clone());
        assert!((lhs - rhs).amax() < 1e-9);
    }
}

#[test]
fn psm_base_parameters_span_2019() {
    check_base_span("psm");
}

#[test]
fn psm_simplified_base_parameters_span_2019() {
    check_base_span("psm_simplified");
}

#[test]
fn mtm_base_parameters_span_2019() {
    check_base_span("mtm");
}
