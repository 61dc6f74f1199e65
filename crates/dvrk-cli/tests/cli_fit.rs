//! `fit`, `validate` and `cable-fit` end to end on logs written by the test itself: the
//! flags scripts rely on, the result document, atomic outputs and errors.

mod support;
use std::path::Path;
use support::{run, run_json, run_ok, temp_dir, write_model_log};

use dvrk_model::{Model, ParamKind};
use dvrk_test_support::fixtures::assert_recovered;
use dvrk_test_support::read_json;

/// A noise-free MTM log in model coordinates (the 2019 CSV layout) from consistent
/// parameters; `phase` changes the motion so train and test differ.
fn write_mtm_log(path: &Path, phase: f64) -> Vec<f64> {
    let model = Model::builtin("mtm").unwrap();
    // Coulomb too: the default processing filters the motion only, so the measured
    // torques keep their sign steps, as the regressor does.
    let pi = dvrk_test_support::mtm_rule(0.03).params(&model);
    write_model_log(&model, &pi, 3000, path, |j, tk| {
        let (w1, w2) = (0.6 + 0.13 * j as f64, 1.7 + 0.11 * j as f64);
        let p = phase + j as f64;
        (
            0.4 * (w1 * tk + p).sin()
                + 0.2 * (w2 * tk + 2.0 * p).sin()
                + if j == 1 { 0.5 } else { 0.0 },
            0.4 * w1 * (w1 * tk + p).cos() + 0.2 * w2 * (w2 * tk + 2.0 * p).cos(),
            -0.4 * w1 * w1 * (w1 * tk + p).sin() - 0.2 * w2 * w2 * (w2 * tk + 2.0 * p).sin(),
        )
    });
    pi
}

/// The arguments of `fit` on a log of [`write_mtm_log`] (the 2019 CSV layout at
/// 200 Hz), then `extra`.
fn fit_mtm_args<'a>(log: &'a Path, extra: &[&'a str]) -> Vec<&'a str> {
    let mut args = vec![
        "fit",
        log.to_str().unwrap(),
        "--robot",
        "mtm",
        "--format",
        "wpi-csv",
        "--rate",
        "200",
    ];
    args.extend_from_slice(extra);
    args
}

#[test]
fn fit_validate_and_exports() {
    let dir = temp_dir("fit");
    let (one, two) = (dir.join("one.csv"), dir.join("two.csv"));
    let truth = write_mtm_log(&one, 0.0);
    write_mtm_log(&two, 1.0);
    let out = dir.join("result.json");
    let wpi = dir.join("params.json");
    let stdout = run_ok(&fit_mtm_args(
        &one,
        &[
            "--method",
            "wls",
            "--test",
            two.to_str().unwrap(),
            "--test-window",
            "1000",
            "--trim",
            "20",
            "--cutoff",
            "20",
            "--out",
            out.to_str().unwrap(),
            "--wpi-json",
            wpi.to_str().unwrap(),
        ],
    ));
    assert!(stdout.contains("test rel"), "{stdout}");
    let doc = read_json(&out);
    for key in [
        "method",
        "parameters",
        "base_parameters",
        "consistency",
        "solver",
        "metrics",
    ] {
        assert!(doc.get(key).is_some(), "missing key {key}");
    }
    assert_eq!(doc["method"], "wls");
    assert_eq!(doc["solver"]["converged"], true);
    assert!(doc["consistency"][0]["min_eigenvalue"].is_number());
    assert_eq!(
        doc["metrics"]["test"]["relative_error"]
            .as_array()
            .unwrap()
            .len(),
        7
    );
    assert_eq!(doc["metrics"]["test"]["samples"], 1000);
    assert_eq!(doc["inputs"][0]["sha256"].as_str().unwrap().len(), 64);
    // The base parameters of noise-free data come back.
    let model = Model::builtin("mtm").unwrap();
    let beta = model.base_parameters().unwrap().project(&truth);
    for (b, t) in doc["base_parameters"].as_array().unwrap().iter().zip(&beta) {
        let v = b["value"].as_f64().unwrap();
        assert!(
            (v - t).abs() < 1e-3 * (1.0 + t.abs()),
            "{}: {v} vs {t}",
            b["expression"]
        );
    }
    assert_eq!(read_json(&wpi).as_object().unwrap().len(), 10);
    // validate reproduces the fit's test metrics.
    let v = run_json(&[
        "validate",
        out.to_str().unwrap(),
        two.to_str().unwrap(),
        "--format",
        "wpi-csv",
        "--rate",
        "200",
        "--test-window",
        "1000",
        "--json",
    ]);
    let a = &v["validations"][0]["metrics"]["relative_error"];
    let b = &doc["metrics"]["test"]["relative_error"];
    for j in 0..7 {
        assert!((a[j].as_f64().unwrap() - b[j].as_f64().unwrap()).abs() < 1e-12);
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn fit_errors_exit_non_zero_and_write_nothing() {
    let dir = temp_dir("errors");
    let out = dir.join("result.json");
    // Missing file.
    let (ok, _, err) = run(&[
        "fit",
        dir.join("nope.csv").to_str().unwrap(),
        "--robot",
        "psm",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(!ok);
    assert!(err.contains("nope.csv"), "{err}");
    // Malformed number.
    let bad = dir.join("bad.csv");
    std::fs::write(&bad, "1,2,3\n4,x,6\n").unwrap();
    let (ok, _, err) = run(&[
        "fit",
        bad.to_str().unwrap(),
        "--robot",
        "psm",
        "--format",
        "wpi-csv",
        "--rate",
        "200",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(!ok);
    assert!(err.contains("bad.csv"), "{err}");
    // A headered log that lacks one of the robot's joints: the PSM's measured joints
    // but the last, the jaw.
    let csv = dir.join("missing_joint.csv");
    let mut text = String::from("time");
    let psm = Model::builtin("psm").unwrap();
    let (jaw, joints) = psm.measured.joints.split_last().unwrap();
    assert_eq!(jaw, "jaw");
    for j in joints {
        text += &format!(",position.{j},effort.{j}");
    }
    text += "\n";
    for k in 0..500 {
        text += &format!("{}", k as f64 / 200.0);
        for _ in joints {
            text += ",0.1,0.2";
        }
        text += "\n";
    }
    std::fs::write(&csv, text).unwrap();
    let (ok, _, err) = run(&[
        "fit",
        csv.to_str().unwrap(),
        "--robot",
        "psm",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(!ok);
    assert!(err.contains("`jaw`"), "{err}");
    // Too short to determine the parameters after trimming.
    let short = dir.join("short.csv");
    write_mtm_log(&short, 0.0);
    let text = std::fs::read_to_string(&short).unwrap();
    let few: String = text.lines().take(450).map(|l| format!("{l}\n")).collect();
    std::fs::write(&short, few).unwrap();
    let (ok, _, err) = run(&fit_mtm_args(
        &short,
        &["--method", "ols", "--out", out.to_str().unwrap()],
    ));
    assert!(!ok);
    assert!(
        err.contains("short.csv") && err.contains("do not determine"),
        "{err}"
    );
    assert!(!out.exists(), "a failed fit must not write its output");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn cable_fit_prints_a_description_line() {
    let dir = temp_dir("cable");
    let sweep = dir.join("sweep.csv");
    let poly = [0.02, -0.01, 0.05];
    let mut text = String::new();
    for i in 0..1000 {
        let (x, dir) = if i < 500 {
            (-1.0 + i as f64 / 250.0, 1.0)
        } else {
            (1.0 - (i - 500) as f64 / 250.0, -1.0)
        };
        let tau = poly[0] * x * x + poly[1] * x + poly[2] + 0.03 * dir;
        // Position, velocity (the sweep's direction: cable-fit checks it reverses), torque.
        text += &format!("{x},{},{tau}\n", 0.1 * dir);
    }
    std::fs::write(&sweep, text).unwrap();
    let args = [
        "cable-fit",
        sweep.to_str().unwrap(),
        "--degree",
        "2",
        "--drop",
        "20",
    ];
    let doc = run_json(&[&args[..], &["--json"]].concat());
    for (c, p) in doc["polynomial"].as_array().unwrap().iter().zip(poly) {
        assert!((c.as_f64().unwrap() - p).abs() < 1e-9, "{doc}");
    }
    let stdout = run_ok(&args);
    assert!(
        stdout.contains("known_force = { polynomial = ["),
        "{stdout}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// The columns `{kind}.{joint}` of a headered simulated CSV (e.g. `position.yaw`), one
/// row per sample, in the order of `joints`.
fn csv_columns(path: &Path, kind: &str, joints: &[String]) -> Vec<Vec<f64>> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let cols: Vec<usize> = joints
        .iter()
        .map(|j| {
            let name = format!("{kind}.{j}");
            header.iter().position(|h| *h == name).unwrap()
        })
        .collect();
    lines
        .map(|l| {
            let v: Vec<f64> = l.split(',').map(|x| x.parse().unwrap()).collect();
            cols.iter().map(|&c| v[c]).collect()
        })
        .collect()
}

/// The parameters `psm_si_tool` is simulated with, by name: its instrument has no nominal
/// values, so psm_si's nominal arm (the same frames and parameters come first) and
/// instrument values inside psm.toml's instrument bounds (friction 0.5, 0.3 and 0.2 of
/// the maxima, motor inertias 1e-3 kg·m², the roll spring mid-range).
fn psm_si_tool_truth() -> Vec<(String, f64)> {
    let tool = Model::builtin("psm_si_tool").unwrap();
    let arm = Model::builtin("psm_si")
        .unwrap()
        .nominal_parameters()
        .unwrap();
    let instrument = dvrk_test_support::ParamRule {
        mass: Box::new(|_| 1.0),
        inertia_com: Box::new(dvrk_test_support::box_inertia),
        friction: Box::new(dvrk_test_support::friction_within_bounds),
        motor_inertia: 1e-3,
        spring: Box::new(dvrk_test_support::mid_spring),
    }
    .params(&tool);
    assert_eq!(
        tool.link_frames(),
        Model::builtin("psm_si").unwrap().link_frames(),
        "the instrument carries no link"
    );
    tool.params
        .iter()
        .enumerate()
        .map(|(k, p)| (p.name.clone(), arm.get(k).copied().unwrap_or(instrument[k])))
        .collect()
}

/// Issue 29, item 4: the identification round trip of each arm the dVRK added, mounted
/// as the dVRK mounts it, through the commands a user runs: `excite` designs a trajectory
/// inside the description's limits (checked here on every simulated sample, in model
/// coordinates), `simulate --params nominal` adds torque noise, `fit --preset dvrk`
/// (semidefinite, Stribeck and Dahl friction on the joints that have friction) recovers
/// the nominal base parameters within 6 standard deviations, and `report` draws the fit
/// with the arm's coordinates. Small optimizer settings and 11 s logs keep it cheap. The
/// PSM Si with its instrument ([`psm_si_tool_truth`]) goes through the same commands: its
/// limits are on the instrument's joints, its log holds them (the file's coupling of the
/// actuators) and the fit reads them back.
#[test]
fn new_arms_round_trip_through_excite_simulate_fit_preset_and_report() {
    let dir = temp_dir("arms-round-trip");
    let s = |p: &Path| p.display().to_string();
    let tool_truth = psm_si_tool_truth();
    let tool_params = dir.join("psm_si_tool_params.json");
    let entries: Vec<String> = tool_truth
        .iter()
        .map(|(k, v)| format!("\"{k}\": {v:?}"))
        .collect();
    std::fs::write(&tool_params, format!("{{{}}}", entries.join(", "))).unwrap();
    for (robot, pitch) in [
        ("ecm", -45.0),
        ("psm_si", -45.0),
        ("ecm_si", -70.0),
        ("psm_si_tool", -45.0),
    ] {
        let params = if robot == "psm_si_tool" {
            s(&tool_params)
        } else {
            "nominal".to_string()
        };
        let pitch_flag = format!("--mounting-pitch={pitch}");
        let (traj, log, fit, rep) = (
            dir.join(format!("{robot}.json")),
            dir.join(format!("{robot}.csv")),
            dir.join(format!("{robot}_fit.json")),
            dir.join(format!("{robot}_report")),
        );
        run_ok(&[
            "excite",
            "--robot",
            robot,
            &pitch_flag,
            "--order",
            "4",
            "--starts",
            "1",
            "--refine",
            "1",
            "--iterations",
            "10",
            "--refine-iterations",
            "20",
            "--samples-per-harmonic",
            "6",
            "--quiet",
            "--out",
            &s(&traj),
        ]);
        run_ok(&[
            "simulate",
            robot,
            "--params",
            &params,
            &pitch_flag,
            "--excitation",
            &s(&traj),
            "--periods",
            "2",
            "--noise",
            "0.01",
            "--seed",
            "3",
            "--quiet",
            "--out",
            &s(&log),
        ]);
        // Every sample inside every position and velocity limit of the description.
        let model = Model::builtin(robot).unwrap();
        assert_eq!(
            model.limits.len(),
            model.dof(),
            "{robot}: one limit per coordinate"
        );
        let to_model = model.measured_to_model_matrix().unwrap();
        let joints = &model.measured.joints;
        let in_model = |rows: Vec<Vec<f64>>| -> Vec<Vec<f64>> {
            rows.iter()
                .map(|m| {
                    (&to_model * nalgebra::DVector::from_column_slice(m))
                        .as_slice()
                        .to_vec()
                })
                .collect()
        };
        let q = in_model(csv_columns(&log, "position", joints));
        let dq = in_model(csv_columns(&log, "velocity", joints));
        assert_eq!(q.len(), 2222, "{robot}: two periods at 200 Hz");
        for l in &model.limits {
            let ([p0, p1], [v0, v1]) = (l.position.unwrap(), l.velocity.unwrap());
            let p: Vec<f64> = q.iter().map(|q| l.expr.eval(q)).collect();
            let v: Vec<f64> = dq.iter().map(|dq| l.expr.dot(dq)).collect();
            let (pmin, pmax) = p
                .iter()
                .fold((f64::MAX, f64::MIN), |(a, b), &x| (a.min(x), b.max(x)));
            assert!(
                p0 <= pmin && pmax <= p1,
                "{robot} {}: {pmin}..{pmax}",
                l.label
            );
            assert!(
                v.iter().all(|&x| v0 <= x && x <= v1),
                "{robot} {} velocity",
                l.label
            );
            // The coordinate moves (is excited), not parked at a limit.
            assert!(
                pmax - pmin > 0.1 * (p1 - p0),
                "{robot} {}: {pmin}..{pmax}",
                l.label
            );
        }
        run_ok(&[
            "fit",
            &s(&log),
            "--robot",
            robot,
            "--preset",
            "dvrk",
            &pitch_flag,
            "--quiet",
            "--out",
            &s(&fit),
        ]);
        let result = dvrk_ident::FitResult::read(&fit).unwrap();
        assert_eq!(result.settings.mounting_pitch_deg, Some(pitch));
        assert!(result.physically_consistent, "{robot}");
        // The preset's prior toward the nominal masses (the simulated truth) holds the
        // masses the data do not determine near them: without it the Si ECM's yaw link
        // came out at 1002 kg (nominal 1.003) and its pitch3 at 161 kg (1.845).
        assert!(
            result.settings.prior.is_some(),
            "{robot}: the preset's prior"
        );
        for l in &result.links {
            if let Some(m0) = model.frame(l.frame).nominal.mass.filter(|m| *m > 0.0) {
                let ratio = l.mass / m0;
                assert!((0.5..=2.0).contains(&ratio), "{robot} {}: {ratio}", l.link);
            }
        }
        // The fitted model: the description with Stribeck and Dahl terms on each joint
        // with friction; their true values (nominal) are zero.
        let fitted = result.model(None).unwrap();
        let friction_joints = model
            .params
            .iter()
            .filter(|p| p.kind == ParamKind::Coulomb)
            .count();
        assert!(friction_joints >= 3, "{robot}");
        for kind in [ParamKind::Stribeck, ParamKind::Dahl] {
            let count = fitted.params.iter().filter(|p| p.kind == kind).count();
            assert_eq!(
                count, friction_joints,
                "{robot}: {kind:?} on each joint with friction"
            );
        }
        let truth = if robot == "psm_si_tool" {
            // The simulated values; the Stribeck and Dahl terms the fit adds, zero.
            let named = tool_truth.iter().map(|(k, v)| (k.as_str(), *v));
            let added = fitted
                .params
                .iter()
                .filter(|p| matches!(p.kind, ParamKind::Stribeck | ParamKind::Dahl))
                .map(|p| (p.name.as_str(), 0.0));
            fitted
                .params_from_named(named.chain(added), "truth")
                .unwrap()
        } else {
            fitted.nominal_parameters().unwrap()
        };
        let beta_true = fitted.base_parameters().unwrap().project(&truth);
        let worst = assert_recovered(
            robot,
            result
                .base_parameters
                .iter()
                .map(|b| (b.expression.as_str(), b.value, b.std)),
            &beta_true,
        );
        println!("{robot}: worst |error|/std {worst:.2}");
        run_ok(&["report", &s(&fit), &s(&log), "--quiet", "--out", &s(&rep)]);
        let html = std::fs::read_to_string(rep.join("report.html")).unwrap();
        assert!(html.contains(robot), "{robot}: the report names its robot");
        let torque = support::files(&rep)
            .into_iter()
            .find(|f| f.starts_with("torque_") && f.ends_with(".svg"))
            .unwrap();
        let torque = std::fs::read_to_string(rep.join(torque)).unwrap();
        for c in &model.coordinates {
            assert!(torque.contains(&format!("{c} ")), "{robot}: {c} drawn");
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The position torque's frames: `--preset dvrk` takes them from the MTM's description
/// (the reproduce line repeats them), `--position-torque 0` leaves them out, and
/// `--position-torque-frames` puts the torque on the named frames only; a name that is
/// not a revolute frame with friction, or frames without an order, are refused naming
/// the flag, writing nothing.
#[test]
fn position_torque_frames_from_the_preset_and_the_flag() {
    let dir = temp_dir("position-torque-frames");
    let log = dir.join("mtm.csv");
    write_mtm_log(&log, 0.0);
    let torques = |doc: &serde_json::Value| -> Vec<String> {
        let params = doc["parameters"].as_object().unwrap();
        params
            .keys()
            .filter(|k| k.starts_with("Pc") || k.starts_with("Ps"))
            .cloned()
            .collect()
    };
    let two = dir.join("mtm_two.csv");
    write_mtm_log(&two, 1.0);
    let fitted = dir.join("preset.json");
    let (t, f) = (two.to_str().unwrap(), fitted.to_str().unwrap());
    let preset = run_json(&fit_mtm_args(
        &log,
        &["--preset", "dvrk", "--test", t, "--out", f, "--json"],
    ));
    // validate rebuilds the model with the preset's frames: the fit's test metrics.
    let v = run_json(&[
        "validate", f, t, "--format", "wpi-csv", "--rate", "200", "--json",
    ]);
    let a = &v["validations"][0]["metrics"]["relative_error"];
    let b = &preset["metrics"]["test"]["relative_error"];
    for j in 0..7 {
        assert!((a[j].as_f64().unwrap() - b[j].as_f64().unwrap()).abs() < 1e-12);
    }
    // (serde_json's map sorts the names)
    assert_eq!(torques(&preset), ["Pca2", "Pca3", "Psa2", "Psa3"]);
    assert_eq!(
        preset["settings"]["position_torque_frames"],
        serde_json::json!(["upper_arm", "forearm"])
    );
    let result: dvrk_ident::FitResult = serde_json::from_value(preset.clone()).unwrap();
    let call = dvrk_ident::reproduce::FitCall::of_result(&result, None);
    let line = call.cli_command().text;
    assert!(
        line.contains("--position-torque 1 --position-torque-frames upper_arm,forearm"),
        "{line}"
    );
    let py = call.python_call().text;
    assert!(
        py.contains("position_torque_frames=\"upper_arm,forearm\""),
        "{py}"
    );
    let off = run_json(&fit_mtm_args(
        &log,
        &["--preset", "dvrk", "--position-torque", "0", "--json"],
    ));
    assert!(torques(&off).is_empty());
    let one = run_json(&fit_mtm_args(
        &log,
        &[
            "--method",
            "ols",
            "--position-torque",
            "1",
            "--position-torque-frames",
            "top_panel",
            "--json",
        ],
    ));
    assert_eq!(torques(&one), ["Pca1", "Psa1"]);
    let out = dir.join("out.json");
    let o = out.to_str().unwrap();
    for (extra, want) in [
        (
            &["--position-torque-frames", "upper_arm"][..],
            "--position-torque-frames: needs the position torque's order (position_torque)",
        ),
        (
            &[
                "--position-torque",
                "1",
                "--position-torque-frames",
                "elbow",
            ][..],
            "--position-torque-frames: elbow: no frame is named elbow",
        ),
        (
            &[
                "--position-torque",
                "1",
                "--position-torque-frames",
                "upper_arm,,forearm",
            ][..],
            "expected frame names separated by commas",
        ),
    ] {
        let mut args = fit_mtm_args(&log, &["--method", "ols", "--out", o]);
        args.extend_from_slice(extra);
        let (ok, _, err) = run(&args);
        assert!(!ok && err.contains(want), "{extra:?}: {err}");
        assert!(!out.exists(), "{extra:?} wrote a result");
    }
    std::fs::remove_dir_all(&dir).ok();
}
