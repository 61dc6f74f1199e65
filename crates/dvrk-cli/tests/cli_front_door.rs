//! The front door (issue 25): a result evaluated with its own model (Stribeck terms),
//! a result of another robot refused in one line wherever a result is read, a log of
//! another arm refused before fitting with the joint and the ranges named, and
//! `--preset dvrk` recorded as the settings it expands to.

mod support;
use support::{example, fit_wpi_args, run, run_json, run_ok, s, temp_dir};

use dvrk_model::{Model, Workspace};

/// Fits the bundled example with `extra` into `out` (a result document).
fn fit_example_to(out: &std::path::Path, extra: &[&str]) {
    let mut args = vec![
        "fit".to_string(),
        example("psm_excitation.mcap"),
        "--robot".into(),
        "psm".into(),
        "--out".into(),
        s(out),
    ];
    args.extend(extra.iter().map(|a| a.to_string()));
    run_ok(&args);
}

/// A result document of the MTM: a PSM result relabelled (what a result records of its
/// robot is what the check reads; its parameters are never reached).
fn mtm_result(dir: &std::path::Path) -> std::path::PathBuf {
    let psm = dir.join("for_mtm.json");
    fit_example_to(&psm, &["--method", "ols"]);
    let mut doc = dvrk_test_support::read_json(&psm);
    doc["robot"] = "mtm".into();
    doc["robot_source"] = "builtin:mtm".into();
    let out = dir.join("mtm.json");
    std::fs::write(&out, serde_json::to_string_pretty(&doc).unwrap()).unwrap();
    out
}

#[test]
fn a_stribeck_result_is_evaluated_with_its_own_model() {
    let dir = temp_dir("front-door-stribeck");
    let out = dir.join("stribeck.json");
    fit_example_to(&out, &["--method", "ols", "--stribeck", "0.3"]);
    let (q, dq, ddq) = (
        [0.1, -0.2, 0.12, 0.3, -0.1, 0.2, 0.4],
        [0.2, 0.1, -0.05, -0.3, 0.5, 0.1, -0.2],
        [1.0, -0.5, 0.1, 0.0, 0.3, -0.7, 0.2],
    );
    let list = |v: &[f64]| {
        v.iter()
            .map(|x| format!("{x:?}"))
            .collect::<Vec<_>>()
            .join(",")
    };
    let doc = run_json(&[
        "model",
        "psm",
        "--torque",
        "--params",
        &s(&out),
        "--q",
        &list(&q),
        "--dq",
        &list(&dq),
        "--ddq",
        &list(&ddq),
    ]);
    let tau: Vec<f64> = dvrk_test_support::f64s(&doc["tau"]);
    // The reference: the library's model with the result's Stribeck terms, H·π.
    let result = dvrk_ident::FitResult::read(&out).unwrap();
    let model = Model::builtin("psm").unwrap().with_stribeck(0.3).unwrap();
    let params = result.params_for(&model).unwrap();
    assert_eq!(params.len(), 125);
    let mut ws = Workspace::new(&model);
    let expected = dvrk_test_support::regressor_times(&model, &mut ws, &q, &dq, &ddq, &params);
    dvrk_test_support::assert_close("tau", &tau, &expected, 1e-12);
    // The Stribeck terms matter at this velocity: without them the torque differs.
    let mut plain = vec![0.0; 7];
    let base = Model::builtin("psm").unwrap();
    base.inverse_dynamics(
        &mut Workspace::new(&base),
        &params[..115],
        &q,
        &dq,
        &ddq,
        &mut plain,
    );
    assert!(tau.iter().zip(&plain).any(|(a, b)| (a - b).abs() > 1e-6));
}

#[test]
fn a_result_of_another_robot_is_refused_in_one_line() {
    let dir = temp_dir("front-door-robot");
    let mtm = mtm_result(&dir);
    let psm_out = dir.join("psm.json");
    fit_example_to(&psm_out, &["--method", "ols"]);
    let expected = format!("dvrk-ident: error: {} was fitted for mtm, not psm", s(&mtm));
    let cases: Vec<Vec<String>> = vec![
        vec![
            "validate".into(),
            s(&mtm),
            example("psm_excitation.mcap"),
            "--robot".into(),
            "psm".into(),
        ],
        vec![
            "export".into(),
            s(&mtm),
            "--robot".into(),
            "psm".into(),
            "--urdf".into(),
            s(&dir.join("x.urdf")),
        ],
        vec![
            "model".into(),
            "psm".into(),
            "--torque".into(),
            "--params".into(),
            s(&mtm),
            "--q".into(),
            "0,0,0.1,0,0,0,0.3".into(),
        ],
        vec![
            "fit".into(),
            example("psm_excitation.mcap"),
            "--robot".into(),
            "psm".into(),
            "--prior".into(),
            s(&mtm),
        ],
    ];
    for args in cases {
        let (ok, _, err) = run(&args);
        assert!(!ok, "{args:?} succeeded");
        assert_eq!(err.trim(), expected, "{args:?}");
    }
    assert!(!dir.join("x.urdf").exists());
}

#[test]
fn a_log_of_another_arm_is_refused_naming_the_joint_and_the_ranges() {
    let Some(mtm_log) = dvrk_test_support::shared("data/dvrk/mtm/one_results.csv") else {
        return;
    };
    let dir = temp_dir("front-door-range");
    let out = dir.join("r.json");
    let (ok, stdout, err) = run(&fit_wpi_args(&mtm_log, "psm", &["--out", &s(&out)]));
    assert!(!ok && stdout.is_empty());
    assert_eq!(
        err.trim(),
        format!(
            "dvrk-ident: error: {}: joint outer_insertion runs from -0.151 to 0.585 m, outside \
             robot psm's range 0 to 0.24 m: is this a log of another arm, or in other units?",
            s(&mtm_log)
        )
    );
    assert!(!out.exists());
    // The same log with its own robot is within every range.
    run_ok(&fit_wpi_args(&mtm_log, "mtm", &["--method", "ols"]));
}

#[test]
fn preset_dvrk_records_what_it_expands_to() {
    let dir = temp_dir("front-door-preset");
    let preset = dir.join("preset.json");
    let spelled = dir.join("spelled.json");
    fit_example_to(&preset, &["--preset", "dvrk"]);
    fit_example_to(
        &spelled,
        &["--method", "sdp", "--delay", "auto", "--stribeck", "0.3"],
    );
    let a = dvrk_test_support::read_json(&preset);
    let b = dvrk_test_support::read_json(&spelled);
    assert_eq!(a["settings"], b["settings"]);
    assert_eq!(a["parameters"], b["parameters"]);
    assert_eq!(a["settings"]["method"], "sdp");
    assert_eq!(a["settings"]["stribeck_velocity"], 0.3);
    assert!(a["delay"].is_object(), "the delays were estimated");
    // A flag given beside the preset wins over it.
    let ols = dir.join("ols.json");
    fit_example_to(&ols, &["--preset", "dvrk", "--method", "ols"]);
    let c = dvrk_test_support::read_json(&ols);
    assert_eq!(c["settings"]["method"], "ols");
    assert_eq!(c["settings"]["stribeck_velocity"], 0.3);
    let (ok, _, err) = run(&[
        "fit",
        &example("psm_excitation.mcap"),
        "--robot",
        "psm",
        "--preset",
        "ur5",
    ]);
    assert!(!ok);
    assert!(
        err.contains("unknown preset \"ur5\": expected dvrk"),
        "{err}"
    );
}

#[test]
fn validate_and_report_name_the_settings_their_flags_change() {
    let dir = temp_dir("front-door-settings");
    let out = dir.join("ols.json");
    fit_example_to(&out, &["--method", "ols"]);
    let log = example("psm_excitation.mcap");
    // With the result's own settings: no note.
    let same = run_ok(&["validate", &s(&out), &log]);
    assert!(!same.contains("note:"), "{same}");
    let changed = run_ok(&["validate", &s(&out), &log, "--trim", "20", "--cutoff", "8"]);
    let first = changed.lines().next().unwrap();
    assert_eq!(
        first,
        "note: these logs are processed with settings that differ from the fit's, so their \
         errors compare with the fit's only in part: processing.filter.cutoff_hz 8.0 (fit: \
         5.4); processing.trim 20 (fit: 200)"
    );
    let doc = run_json(&["validate", &s(&out), &log, "--trim", "20", "--json"]);
    assert_eq!(
        doc["settings_differences"],
        serde_json::json!([{"path": "processing.trim", "a": 20, "b": 200}])
    );
    let (ok, _, err) = run(&[
        "report",
        &s(&out),
        &log,
        "--out",
        &s(&dir.join("rep")),
        "--trim",
        "20",
    ]);
    assert!(ok, "{err}");
    assert!(
        err.contains("differ from the fit's, so their errors compare with the fit's only in part: processing.trim 20 (fit: 200)"),
        "{err}"
    );
}
