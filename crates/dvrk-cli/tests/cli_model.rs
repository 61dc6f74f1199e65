//! The `model` subcommand end to end: exact flags and JSON keys scripts rely on, the
//! numbers against the library, and errors with a non-zero exit.

mod support;
use support::run;

#[test]
fn model_json_has_the_documented_keys() {
    let (ok, out, err) = run(&["model", "psm", "--json"]);
    assert!(ok, "{err}");
    let doc: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(doc["coordinates"].as_array().unwrap().len(), 7);
    assert_eq!(doc["measured_joints"][6], "jaw");
    assert_eq!(doc["parameters"].as_array().unwrap().len(), 115);
    assert_eq!(doc["base_parameters"].as_array().unwrap().len(), 49);
    assert_eq!(doc["parameters"][0], "L1xx");
    let (ok, out, _) = run(&["model", "mtm", "--json"]);
    assert!(ok);
    let doc: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(doc["base_parameters"].as_array().unwrap().len(), 73);
}

#[test]
fn regressor_and_torque_match_the_library() {
    let q = "0.1,-0.2,0.15,0.3,-0.4,0.5,0.6";
    let dq = "0.5,0.4,-0.1,0.2,0.1,-0.3,0.2";
    let ddq = "-1,0.5,0.2,0.1,0.3,-0.2,0.4";
    let (ok, out, err) = run(&[
        "model",
        "psm",
        "--regressor",
        "--q",
        q,
        "--dq",
        dq,
        "--ddq",
        ddq,
    ]);
    assert!(ok, "{err}");
    let doc: serde_json::Value = serde_json::from_str(&out).unwrap();
    let model = dvrk_model::Model::builtin("psm").unwrap();
    let parse = |s: &str| {
        s.split(',')
            .map(|x| x.parse().unwrap())
            .collect::<Vec<f64>>()
    };
    let mut ws = dvrk_model::Workspace::new(&model);
    let h = model.regressor(&mut ws, &parse(q), &parse(dq), &parse(ddq));
    let rows = doc["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 7);
    for r in 0..7 {
        for c in 0..model.n_params() {
            assert_eq!(rows[r][c].as_f64().unwrap(), h[(r, c)]);
        }
    }
    // Base regressor: one column per base parameter.
    let (ok, out, _) = run(&["model", "psm", "--regressor", "--base", "--q", q]);
    assert!(ok);
    let doc: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(doc["rows"][0].as_array().unwrap().len(), 49);

    // Torque with a parameter file equals H·π.
    let dir = dvrk_test_support::temp_dir("dvrk-cli-test");
    std::fs::create_dir_all(&dir).unwrap();
    let params: serde_json::Map<String, serde_json::Value> = model
        .param_names()
        .iter()
        .enumerate()
        .map(|(k, n)| (n.clone(), serde_json::json!(0.01 * (k % 7) as f64 + 0.001)))
        .collect();
    let file = dir.join("params.json");
    std::fs::write(
        &file,
        serde_json::json!({ "parameters": params }).to_string(),
    )
    .unwrap();
    let (ok, out, err) = run(&[
        "model",
        "psm",
        "--torque",
        "--q",
        q,
        "--dq",
        dq,
        "--ddq",
        ddq,
        "--params",
        file.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    let doc: serde_json::Value = serde_json::from_str(&out).unwrap();
    let pi: Vec<f64> = (0..model.n_params())
        .map(|k| 0.01 * (k % 7) as f64 + 0.001)
        .collect();
    let tau = &h * nalgebra::DVector::from_vec(pi);
    for r in 0..7 {
        let t = doc["tau"][r].as_f64().unwrap();
        assert!((t - tau[r]).abs() < 1e-12 * (1.0 + tau[r].abs()));
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn bad_input_fails_with_a_message() {
    let (ok, _, err) = run(&["model", "no_such_robot"]);
    assert!(!ok);
    assert!(err.contains("unknown robot `no_such_robot`"), "{err}");
    let (ok, _, err) = run(&["model", "psm", "--torque", "--q", "0,0,0"]);
    assert!(!ok);
    assert!(err.contains("expected 7"), "{err}");
    let (ok, _, err) = run(&["model", "psm", "--torque", "--q", "0,0,0,0,0,0,0"]);
    assert!(!ok);
    assert!(err.contains("nominal"), "{err}");
    let (ok, _, err) = run(&["model", "psm", "--torque", "--q", "0,0,0,0,0,0,nan"]);
    assert!(!ok);
    assert!(err.contains("not finite"), "{err}");
}
