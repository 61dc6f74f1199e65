//! `compare`: two fits of the bundled example side by side, against what `validate` and
//! the result files themselves say.

mod support;
use std::path::Path;
use std::process::Command;

use serde_json::Value;
use support::{
    example, fit_example_args, fit_wpi_args, run_json, run_ok, s, simulate_example, temp_dir,
};

use dvrk_model::Model;
use dvrk_test_support::read_json;

/// `compare A B --test LOGS... --json`.
fn compare_json(a: &Path, b: &Path, logs: &[&str]) -> Value {
    let mut args = vec!["compare".to_string(), s(a), s(b), "--json".into()];
    if !logs.is_empty() {
        args.push("--test".into());
        args.extend(logs.iter().map(|l| l.to_string()));
    }
    run_json(&args)
}

fn f64s(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap_or_else(|| panic!("not an array: {v}"))
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

fn close(what: &str, a: &[f64], b: &[f64], tol: f64) {
    assert_eq!(a.len(), b.len(), "{what}");
    for (i, (x, y)) in a.iter().zip(b).enumerate() {
        assert!((x - y).abs() <= tol, "{what}[{i}]: {x} vs {y}");
    }
}

/// The `{name: value}` of a result's base parameter `field` (`value` or `std`).
fn base(result: &Value, name: &str, field: &str) -> f64 {
    result["base_parameters"]
        .as_array()
        .unwrap()
        .iter()
        .find(|p| p["name"] == name)
        .unwrap_or_else(|| panic!("no base parameter {name}"))[field]
        .as_f64()
        .unwrap()
}

#[test]
fn two_fits_of_the_example_side_by_side() {
    let dir = temp_dir("compare");
    let (a, b) = (dir.join("ols.json"), dir.join("wls.json"));
    run_ok(&fit_example_args(&["--method", "ols", "--out", &s(&a)]));
    run_ok(&fit_example_args(&[
        "--method",
        "wls",
        "--cutoff",
        "8",
        "--out",
        &s(&b),
    ]));
    // A held-out log: the example's parameters along its trajectory, other noise.
    let test = dir.join("test.mcap");
    simulate_example(
        &test,
        &["--duration", "20", "--noise", "0.02", "--seed", "7"],
    );
    let logs = [s(&test), example("psm_excitation.mcap")];
    let logs: Vec<&str> = logs.iter().map(String::as_str).collect();
    let doc = compare_json(&a, &b, &logs);

    // Exactly the two settings changed, with their values.
    let mut diffs: Vec<(String, Value, Value)> = doc["differences"]
        .as_array()
        .unwrap()
        .iter()
        .map(|d| {
            (
                d["path"].as_str().unwrap().to_string(),
                d["a"].clone(),
                d["b"].clone(),
            )
        })
        .collect();
    diffs.sort_by(|x, y| x.0.cmp(&y.0));
    assert_eq!(
        diffs,
        vec![
            ("settings.method".into(), "ols".into(), "wls".into()),
            (
                "settings.processing.filter.cutoff_hz".into(),
                5.4.into(),
                8.0.into()
            ),
        ]
    );
    assert_eq!(doc["a"]["name"], s(&a).as_str());
    assert_eq!(
        (doc["a"]["method"].as_str(), doc["b"]["method"].as_str()),
        (Some("ols"), Some("wls"))
    );

    // Each result's errors on each log are those `validate` gives it there.
    let tests = doc["tests"].as_array().unwrap();
    assert_eq!(tests.len(), 2);
    for (side, file) in [("a", &a), ("b", &b)] {
        let mut args = vec!["validate".to_string(), s(file)];
        args.extend(logs.iter().map(|l| l.to_string()));
        args.push("--json".into());
        let v = run_json(&args);
        for (k, t) in tests.iter().enumerate() {
            let m = &v["validations"][k]["metrics"];
            assert_eq!(t["log"], logs[k]);
            assert_eq!(t[side]["samples"], m["samples"], "{side} on {}", logs[k]);
            assert_eq!(t[side]["joints"], m["joints"]);
            let what = format!("{side} on {}", logs[k]);
            close(
                &what,
                &f64s(&t[side]["relative_error"]),
                &f64s(&m["relative_error"]),
                1e-12,
            );
            close(&what, &f64s(&t[side]["rms"]), &f64s(&m["rms"]), 1e-12);
        }
    }
    // The two processings differ, so the two results' errors do too.
    assert_ne!(tests[0]["a"]["rms"], tests[0]["b"]["rms"]);

    // The base parameters: the same combinations, each row the files' values, the
    // difference in combined standard deviations.
    let (ra, rb) = (read_json(&a), read_json(&b));
    let bp = &doc["base_parameters"];
    assert_eq!(bp["comparable"], true);
    assert!(bp["reason"].is_null());
    let rows = bp["parameters"].as_array().unwrap();
    assert_eq!(rows.len(), ra["base_parameters"].as_array().unwrap().len());
    let mut largest: f64 = 0.0;
    for r in rows {
        let name = r["name"].as_str().unwrap();
        let (va, sa) = (base(&ra, name, "value"), base(&ra, name, "std"));
        let (vb, sb) = (base(&rb, name, "value"), base(&rb, name, "std"));
        assert_eq!(r["a"]["value"].as_f64(), Some(va));
        assert_eq!(r["b"]["std"].as_f64(), Some(sb));
        assert_eq!(r["difference"].as_f64(), Some(vb - va));
        let z = r["sigmas"].as_f64().unwrap();
        assert!((z - (va - vb).abs() / (sa * sa + sb * sb).sqrt()).abs() <= 1e-12 * z.max(1.0));
        largest = largest.max(z);
    }
    assert!(
        largest > 0.1,
        "the two fits differ by {largest} sigma at most"
    );

    // Every parameter and link mass as the files have them.
    let params = doc["parameters"].as_array().unwrap();
    assert_eq!(params.len(), ra["parameters"].as_object().unwrap().len());
    for p in params {
        let name = p["name"].as_str().unwrap();
        assert_eq!(p["a"], ra["parameters"][name], "{name}");
        assert_eq!(p["b"], rb["parameters"][name], "{name}");
    }
    let links = ra["links"].as_array().unwrap();
    assert_eq!(doc["link_masses"].as_array().unwrap().len(), links.len());
    for (m, (la, lb)) in doc["link_masses"]
        .as_array()
        .unwrap()
        .iter()
        .zip(links.iter().zip(rb["links"].as_array().unwrap()))
    {
        assert_eq!(
            (&m["name"], &m["a"], &m["b"]),
            (&la["link"], &la["mass"], &lb["mass"])
        );
    }

    // The table: the settings first, then the errors, then the base parameters with the
    // largest difference first.
    let text = run_ok(&["compare", &s(&a), &s(&b), "--test", logs[0]]);
    let at = |needle: &str| {
        text.find(needle)
            .unwrap_or_else(|| panic!("no `{needle}` in:\n{text}"))
    };
    assert!(at("Settings that differ (2):") < at(logs[0]));
    assert!(at(logs[0]) < at("Base parameters (49;"));
    let top = rows
        .iter()
        .max_by(|x, y| {
            x["sigmas"]
                .as_f64()
                .unwrap()
                .total_cmp(&y["sigmas"].as_f64().unwrap())
        })
        .unwrap();
    let first_row = text[at("Base parameters (49;")..].lines().nth(2).unwrap();
    assert!(
        first_row.starts_with(&format!("{} ", top["name"].as_str().unwrap())),
        "{first_row}"
    );
    assert!(
        text.contains("settings.processing.filter.cutoff_hz  A 5.4  B 8.0"),
        "{text}"
    );

    // A result against itself: nothing differs.
    let same = compare_json(&a, &a, &logs[..1]);
    assert_eq!(same["differences"], Value::Array(vec![]));
    for r in same["base_parameters"]["parameters"].as_array().unwrap() {
        assert_eq!(
            (r["difference"].as_f64(), r["sigmas"].as_f64()),
            (Some(0.0), Some(0.0)),
            "{r}"
        );
    }
    assert_eq!(same["tests"][0]["a"], same["tests"][0]["b"]);
    assert_eq!(same["tests"][0]["a"], tests[0]["a"]);
    assert!(run_ok(&["compare", &s(&a), &s(&a)]).contains("Settings: the same"));

    // A model option changes the base parameters: the common ones still compare, and
    // the document says why the rest do not.
    let c = dir.join("stribeck.json");
    run_ok(&fit_example_args(&[
        "--method",
        "ols",
        "--stribeck",
        "0.05",
        "--out",
        &s(&c),
    ]));
    let doc = compare_json(&a, &c, &[]);
    assert_eq!(doc["base_parameters"]["comparable"], false);
    let why = doc["base_parameters"]["reason"].as_str().unwrap();
    assert!(
        why.contains("Stribeck") && why.contains("49 base parameters"),
        "{why}"
    );
    let rows = doc["base_parameters"]["parameters"].as_array().unwrap();
    let only_c = rows.iter().filter(|r| r["a"].is_null()).count();
    let rc = read_json(&c);
    assert_eq!(only_c, rc["base_parameters"].as_array().unwrap().len() - 49);
    assert!(rows
        .iter()
        .filter(|r| r["a"].is_null())
        .all(|r| r["sigmas"].is_null()));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A noise-free MTM log in model coordinates (the 2019 CSV layout).
fn write_mtm_log(path: &Path) {
    let model = Model::builtin("mtm").unwrap();
    let pi = dvrk_test_support::mtm_rule(0.03).params(&model);
    support::write_model_log(&model, &pi, 3000, path, |j, tk| {
        let (w1, w2) = (0.6 + 0.13 * j as f64, 1.7 + 0.11 * j as f64);
        let p = j as f64;
        (
            0.4 * (w1 * tk + p).sin() + 0.2 * (w2 * tk + 2.0 * p).sin(),
            0.4 * w1 * (w1 * tk + p).cos() + 0.2 * w2 * (w2 * tk + 2.0 * p).cos(),
            -0.4 * w1 * w1 * (w1 * tk + p).sin() - 0.2 * w2 * w2 * (w2 * tk + 2.0 * p).sin(),
        )
    });
}

#[test]
fn results_of_two_robots_are_refused_in_one_line() {
    let dir = temp_dir("compare-robots");
    let (mtm_log, mtm, psm) = (
        dir.join("mtm.csv"),
        dir.join("mtm.json"),
        dir.join("psm.json"),
    );
    write_mtm_log(&mtm_log);
    run_ok(&fit_wpi_args(
        &mtm_log,
        "mtm",
        &["--method", "ols", "--out", &s(&mtm)],
    ));
    run_ok(&fit_example_args(&["--method", "ols", "--out", &s(&psm)]));
    // Refused before any log is read: the missing test log is not what is reported.
    let missing = dir.join("missing.mcap");
    let out = Command::new(env!("CARGO_BIN_EXE_dvrk-ident"))
        .args(["compare", &s(&mtm), &s(&psm), "--test", &s(&missing)])
        .output()
        .unwrap();
    let err = String::from_utf8(out.stderr).unwrap();
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(out.stdout.is_empty());
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(
        err.contains(&format!(
            "{} was fitted for mtm, {} for psm",
            s(&mtm),
            s(&psm)
        )),
        "{err}"
    );
    // A missing result is named.
    let (ok, _, err) = support::run(&["compare", &s(&psm), &s(&dir.join("nope.json"))]);
    assert!(!ok && err.contains("nope.json"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}
