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
        &[
            "--method",
            "sdp",
            "--stribeck",
            "0.3",
            "--dahl",
            "20",
            "--prior",
            "nominal",
            "--prior-weight",
            "0.05",
        ],
    );
    let a = dvrk_test_support::read_json(&preset);
    let b = dvrk_test_support::read_json(&spelled);
    assert_eq!(a["settings"], b["settings"]);
    assert_eq!(a["parameters"], b["parameters"]);
    assert_eq!(a["settings"]["method"], "sdp");
    assert_eq!(a["settings"]["stribeck_velocity"], 0.3);
    assert_eq!(a["settings"]["dahl_sigma"], 20.0);
    assert!(
        a["parameters"]["Fd1"].as_f64().unwrap() >= 0.0,
        "Dahl friction fitted"
    );
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

/// The PSM's measured joints, as robots/psm.toml's `[measured]` names them (the dVRK 2.x
/// ROS names), read from the file rather than through the model the CLI also uses.
fn psm_measured() -> serde_json::Value {
    let path = dvrk_test_support::repo().join("robots/psm.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let description: toml::Table = text.parse().unwrap();
    let joints = description["measured"]["joints"].as_array().unwrap();
    assert_eq!(joints.len(), 7, "{}", path.display());
    joints.iter().map(|j| j.as_str().unwrap()).collect()
}

fn numbers(v: &serde_json::Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

fn assert_close_all(a: &[f64], b: &[f64], rel: f64, what: &str) {
    assert_eq!(a.len(), b.len(), "{what}");
    for (j, (x, y)) in a.iter().zip(b).enumerate() {
        assert!(
            (x - y).abs() <= rel * x.abs().max(y.abs()),
            "{what}[{j}]: {x} vs {y}"
        );
    }
}

/// `--joints measured` changes what is shown, not the fit: the same parameters; the
/// metrics named by the arm's joints; the first four (uncoupled) joints' errors those of
/// the model coordinates; the wrist's different (q5..q7 are motor angles). The fit in
/// memory, the streamed fit and `validate` agree, and the result's setting is
/// validate's and report's default.
#[test]
fn measured_joints_show_the_same_fit_by_the_arms_joint_names() {
    let dir = temp_dir("front-door-joints");
    let (model_doc, measured_doc) = (dir.join("model.json"), dir.join("measured.json"));
    let test = [
        "--test",
        &example("psm_excitation.mcap"),
        "--test-window",
        "500",
    ];
    fit_example_to(&model_doc, &test);
    fit_example_to(
        &measured_doc,
        &[&test[..], &["--joints", "measured"]].concat(),
    );
    let (a, b) = (
        dvrk_test_support::read_json(&model_doc),
        dvrk_test_support::read_json(&measured_doc),
    );
    assert_eq!(a["parameters"], b["parameters"]);
    assert_eq!(b["settings"]["joints"], "measured");
    assert!(
        a["settings"].get("joints").is_none(),
        "the default is left out"
    );
    for set in ["train", "test"] {
        let (ma, mb) = (&a["metrics"][set], &b["metrics"][set]);
        assert_eq!(mb["joints"], psm_measured());
        assert_eq!(ma["samples"], mb["samples"]);
        for key in ["relative_error", "rms"] {
            let (x, y) = (numbers(&ma[key]), numbers(&mb[key]));
            assert_close_all(&x[..4], &y[..4], 1e-9, &format!("{set} {key}"));
            for j in 4..7 {
                assert!(
                    (x[j] - y[j]).abs() > 1e-3 * x[j],
                    "{set} {key}[{j}]: the wrist's joints are not its coordinates"
                );
            }
        }
    }
    // Streamed: the training metrics from one more pass, the same numbers.
    let streamed = dir.join("streamed.json");
    fit_example_to(
        &streamed,
        &[&test[..], &["--joints", "measured", "--stream"]].concat(),
    );
    let c = dvrk_test_support::read_json(&streamed);
    for set in ["train", "test"] {
        for key in ["relative_error", "rms"] {
            assert_close_all(
                &numbers(&b["metrics"][set][key]),
                &numbers(&c["metrics"][set][key]),
                1e-9,
                &format!("streamed {set} {key}"),
            );
        }
    }
    // validate: in the result's joints by default, or as asked; the same numbers as
    // the fit's training metrics on the training log.
    let validated = |doc: &std::path::Path, extra: &[&str]| {
        let mut args = vec![
            "validate".to_string(),
            s(doc),
            example("psm_excitation.mcap"),
            "--json".into(),
        ];
        args.extend(extra.iter().map(|x| x.to_string()));
        run_json(&args)["validations"][0]["metrics"].clone()
    };
    for v in [
        validated(&measured_doc, &[]),
        validated(&model_doc, &["--joints", "measured"]),
    ] {
        assert_eq!(v["joints"], psm_measured());
        for key in ["relative_error", "rms"] {
            assert_close_all(
                &numbers(&b["metrics"]["train"][key]),
                &numbers(&v[key]),
                1e-9,
                &format!("validate {key}"),
            );
        }
    }
    let back = validated(&measured_doc, &["--joints", "model"]);
    assert_eq!(back["joints"][4], "q5");
    // The report draws the wrist by its names.
    let rep = dir.join("report");
    run_ok(&[
        "report",
        &s(&measured_doc),
        &example("psm_excitation.mcap"),
        "--out",
        &s(&rep),
    ]);
    let name = support::files(&rep)
        .into_iter()
        .find(|f| f.starts_with("torque_") && f.ends_with(".svg"))
        .unwrap();
    let torque = std::fs::read_to_string(rep.join(name)).unwrap();
    assert!(torque.contains("outer_wrist_pitch"), "names in the figure");
    assert!(!torque.contains(">q5 "), "no model coordinate titles");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Observation states hold no samples, so a fit of states cannot show coupled measured
/// joints' training errors: refused before anything is written, naming the setting.
#[test]
fn measured_joints_of_a_fit_of_states_are_refused() {
    let dir = temp_dir("front-door-joints-states");
    let state = dir.join("psm.obs");
    run_ok(&[
        "observe",
        &example("psm_excitation.mcap"),
        "--robot",
        "psm",
        "--out",
        &s(&state),
    ]);
    let out = dir.join("fit.json");
    let (ok, _, err) = run(&[
        "fit",
        "--states",
        &s(&state),
        "--joints",
        "measured",
        "--out",
        &s(&out),
    ]);
    assert!(!ok);
    assert!(
        err.contains("joints") && err.contains("observation states"),
        "{err}"
    );
    assert!(!out.exists());
    std::fs::remove_dir_all(&dir).unwrap();
}
