//! `export` end to end: a fit of the bundled PSM log exported as a generated URDF, a fit
//! of a URDF robot exported into its own URDF, both read back with the importer and
//! compared torque for torque with the result's model; the params.json layout equal to
//! `fit --wpi-json`'s; errors naming the file, exiting non-zero and writing nothing.

mod support;
use dvrk_test_support::{rigid_only, torque_difference};
use std::path::{Path, PathBuf};
use support::{fit_example_args, run, s, temp_dir, write_arm_log, ARM};

use dvrk_ident::FitResult;
use dvrk_model::Model;

/// Fits the bundled PSM log (noise-free processing, quick) and writes the result and the
/// params.json of `fit --wpi-json`.
fn fit_example(dir: &Path, method: &str) -> (PathBuf, PathBuf) {
    let (out, wpi) = (
        dir.join(format!("{method}.json")),
        dir.join(format!("{method}_params.json")),
    );
    let (ok, _, err) = run(&fit_example_args(&[
        "--cutoff",
        "none",
        "--method",
        method,
        "--out",
        &s(&out),
        "--wpi-json",
        &s(&wpi),
    ]));
    assert!(ok, "{err}");
    (out, wpi)
}

#[test]
fn psm_fit_exports_a_generated_urdf_and_the_2019_layout() {
    let dir = temp_dir("export-psm");
    let (result, fit_wpi) = fit_example(&dir, "sdp");
    let (urdf, wpi) = (dir.join("psm.urdf"), dir.join("params.json"));
    let (ok, stdout, err) = run(&[
        "export",
        &s(&result),
        "--urdf",
        &s(&urdf),
        "--wpi-json",
        &s(&wpi),
    ]);
    assert!(ok, "{err}");
    assert!(stdout.contains("generated from robot `psm`"), "{stdout}");
    assert_eq!(
        std::fs::read(&wpi).unwrap(),
        std::fs::read(&fit_wpi).unwrap(),
        "export --wpi-json writes what fit --wpi-json wrote"
    );
    // The URDF's rigid-body dynamics are the result's.
    let model = Model::builtin("psm").unwrap();
    let fit = FitResult::read(&result).unwrap();
    let params = rigid_only(&model, &fit.params_for(&model).unwrap());
    let back = Model::load(&s(&urdf)).unwrap();
    let worst = torque_difference(
        &model,
        &params,
        &back,
        &back.nominal_parameters().unwrap(),
        1,
    );
    eprintln!("psm sdp result → generated URDF: max |Δτ| = {worst:e}");
    assert!(worst < 1e-9, "torques differ by {worst:e}");
    let text = std::fs::read_to_string(&urdf).unwrap();
    assert!(
        text.contains("motor inertia Ia11"),
        "header notes motor inertia"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn urdf_robot_fit_exports_into_its_own_urdf() {
    let dir = temp_dir("export-arm");
    let urdf = dir.join("arm.urdf");
    std::fs::write(&urdf, ARM).unwrap();
    let log = dir.join("arm.csv");
    write_arm_log(&urdf, &log);
    let result = dir.join("result.json");
    let (ok, _, err) = run(&[
        "fit",
        &s(&log),
        "--robot",
        &s(&urdf),
        "--format",
        "wpi-csv",
        "--rate",
        "200",
        "--cutoff",
        "none",
        "--trim",
        "10",
        "--out",
        &s(&result),
    ]);
    assert!(ok, "{err}");
    let model = Model::load(&s(&urdf)).unwrap();
    let fit = FitResult::read(&result).unwrap();
    let params = fit.params_for(&model).unwrap();
    // Without --template: the robot's own URDF; with --template: a copy elsewhere.
    let copy = dir.join("copy_of_arm.urdf");
    std::fs::copy(&urdf, &copy).unwrap();
    for (out, from) in [("own.urdf", None), ("from.urdf", Some(&copy))] {
        let out = dir.join(out);
        let mut args = vec!["export".to_string(), s(&result), "--urdf".into(), s(&out)];
        if let Some(f) = from {
            args.extend(["--template".to_string(), s(f)]);
        }
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let (ok, stdout, err) = run(&args);
        assert!(ok, "{err}");
        assert!(stdout.contains("with the identified inertials"), "{stdout}");
        let text = std::fs::read_to_string(&out).unwrap();
        assert!(text.contains("<!-- a three-joint arm for the export test -->"));
        assert!(text.contains(r#"<cylinder radius="0.05" length="0.2"/>"#));
        let back = Model::load(&s(&out)).unwrap();
        let nominal = back.nominal_parameters().unwrap();
        let worst_param = nominal
            .iter()
            .zip(&params)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        let worst = torque_difference(&model, &params, &back, &nominal, 2);
        eprintln!(
            "arm sdp result → {}: max |Δπ| = {worst_param:e}, max |Δτ| = {worst:e}",
            out.display()
        );
        assert!(worst_param < 1e-12 && worst < 1e-9);
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Runs a failing command: non-zero exit, every word in stderr, no output files (nor
/// temporaries) in `dir` besides `keep`.
#[track_caller]
fn assert_fails(args: &[&str], words: &[&str], dir: &Path) {
    let (ok, _, err) = run(args);
    assert!(!ok, "{args:?} succeeded");
    assert!(!err.contains("panicked"), "{args:?} panicked: {err}");
    for w in words {
        assert!(err.contains(w), "{args:?}: `{w}` not in: {err}");
    }
    if let Some(e) = std::fs::read_dir(dir).unwrap().next() {
        panic!("{} was written", e.unwrap().path().display());
    }
}

#[test]
fn export_errors_name_the_file_and_write_nothing() {
    let dir = temp_dir("export-errors");
    let inputs = temp_dir("export-errors-inputs");
    let (ols, ols_wpi) = fit_example(&inputs, "ols");
    let (urdf, wpi) = (s(&dir.join("out.urdf")), s(&dir.join("out.json")));
    let fails = |args: &[&str], words: &[&str]| assert_fails(args, words, &dir);

    // A least-squares representative is not a set of rigid bodies: no URDF, a hint, and
    // not the params.json either (nothing is written when any output fails).
    let r = s(&ols);
    fails(
        &["export", &r, "--urdf", &urdf, "--wpi-json", &wpi],
        &[
            &r,
            "cannot export to URDF",
            "mass 0 with first moment",
            "--method sdp",
        ],
    );
    // Its params.json alone is what fit wrote.
    let (ok, _, err) = run(&["export", &r, "--wpi-json", &wpi]);
    assert!(ok, "{err}");
    assert_eq!(
        std::fs::read(&wpi).unwrap(),
        std::fs::read(&ols_wpi).unwrap()
    );
    std::fs::remove_file(&wpi).unwrap();

    // Missing result file.
    let missing = s(&inputs.join("nope.json"));
    fails(&["export", &missing, "--urdf", &urdf], &[&missing]);
    // Not a result.
    let garbage = inputs.join("garbage.json");
    std::fs::write(&garbage, "{\"parameters\": [1, 2").unwrap();
    fails(
        &["export", &s(&garbage), "--urdf", &urdf],
        &[&s(&garbage), "not a dvrk-ident result"],
    );
    // A parameter that is not a number (NaN is written as null by JSON writers).
    let sdp = fit_example(&inputs, "sdp").0;
    let text = std::fs::read_to_string(&sdp).unwrap();
    let mut doc: serde_json::Value = serde_json::from_str(&text).unwrap();
    doc["parameters"]["m2"] = serde_json::Value::Null;
    let nan = inputs.join("nan.json");
    std::fs::write(&nan, serde_json::to_string(&doc).unwrap()).unwrap();
    fails(&["export", &s(&nan), "--urdf", &urdf], &[&s(&nan)]);
    // A parameter of another robot.
    let mut doc: serde_json::Value = serde_json::from_str(&text).unwrap();
    doc["parameters"].as_object_mut().unwrap().remove("m2");
    let short = inputs.join("short.json");
    std::fs::write(&short, serde_json::to_string(&doc).unwrap()).unwrap();
    fails(
        &["export", &s(&short), "--urdf", &urdf],
        &[&s(&short), "missing parameters: m2"],
    );
    // The dVRK gravity-compensation file is for the MTM: refused for the PSM, and the
    // URDF that could have been written is not.
    let gc = s(&dir.join("gc-MTML.json"));
    fails(
        &["export", &s(&sdp), "--urdf", &urdf, "--dvrk-gc", &gc],
        &[
            &s(&sdp),
            "dVRK gravity compensation",
            "for the MTM",
            "outer_pitch",
        ],
    );
    // --gc-points out of range.
    fails(
        &["export", &s(&sdp), "--dvrk-gc", &gc, "--gc-points", "3"],
        &["grid points per joint must be 6 to 10"],
    );
    // --from (the old spelling of --template, still accepted) a URDF that is not the
    // robot.
    let other = inputs.join("other.urdf");
    std::fs::write(&other, ARM).unwrap();
    fails(
        &["export", &s(&sdp), "--urdf", &urdf, "--from", &s(&other)],
        &[&s(&other), "do not match robot `psm`"],
    );
    // --template a file that does not exist.
    let absent = s(&inputs.join("absent.urdf"));
    fails(
        &["export", &s(&sdp), "--urdf", &urdf, "--template", &absent],
        &[&absent, "cannot read"],
    );
    // No output asked for: a usage error.
    fails(&["export", &s(&sdp)], &["--urdf", "--wpi-json"]);
    // --template without --urdf.
    fails(
        &[
            "export",
            &s(&sdp),
            "--wpi-json",
            &wpi,
            "--template",
            &s(&other),
        ],
        &["--urdf"],
    );
    std::fs::remove_dir_all(&dir).unwrap();
    std::fs::remove_dir_all(&inputs).unwrap();
}

/// The fit's summary marks what the data determined, and `export` warns about every
/// link whose mass, centre of mass or inertia it writes without the data having
/// determined them (on stderr, and in an XML comment of the URDF, which stays a URDF the
/// importer reads), and about the parameters the semidefinite fit left on a bound.
#[test]
fn summary_and_export_say_what_the_data_did_not_determine() {
    let dir = temp_dir("export-status");
    let out = dir.join("sdp.json");
    let (ok, summary, err) = run(&fit_example_args(&["--cutoff", "none", "--out", &s(&out)]));
    assert!(ok, "{err}");
    let result = FitResult::read(&out).unwrap();
    let model = Model::builtin("psm").unwrap();
    assert_eq!(result.parameter_status.len(), model.n_params());
    let identified = result
        .parameter_status
        .values()
        .filter(|s| s.identified())
        .count();
    assert!(
        summary.contains(&format!(
            "parameters identified by the data: {identified} of {}",
            model.n_params()
        )),
        "{summary}"
    );
    // No PSM link has its mass, centre of mass and inertia all determined (revolute
    // joints fold what they carry into the parents' moments and inertias), so every URDF
    // link gets a warning.
    let urdf = dir.join("psm.urdf");
    let (ok, _, warnings) = run(&["export", &s(&out), "--urdf", &s(&urdf)]);
    assert!(ok, "{warnings}");
    let text = std::fs::read_to_string(&urdf).unwrap();
    for l in &result.links {
        let d = l.determined.unwrap();
        assert!(!d.inertia_com(), "{}", l.link);
        let line = format!("link {}: ", l.link);
        assert!(
            warnings.contains(&format!("dvrk-ident: warning: {}: {line}", s(&urdf))),
            "{warnings}"
        );
        assert!(text.contains(&line), "{text}");
        // The summary's mass column says the same as the document.
        let mark = match result.parameter_status[&format!("m{}", l.frame)] {
            dvrk_ident::ParameterStatus::Identified => "yes",
            dvrk_ident::ParameterStatus::AtLowerBound => "lower",
            dvrk_ident::ParameterStatus::AtUpperBound => "upper",
            dvrk_ident::ParameterStatus::Unidentified => "no",
        };
        let row = summary
            .lines()
            .find(|r| r.split_whitespace().nth(1) == Some(l.link.as_str()))
            .unwrap();
        let marks = row.split(']').nth(1).unwrap();
        assert_eq!(marks.split_whitespace().next(), Some(mark), "{row}");
    }
    for (name, st) in &result.parameter_status {
        if matches!(
            st,
            dvrk_ident::ParameterStatus::AtLowerBound | dvrk_ident::ParameterStatus::AtUpperBound
        ) {
            assert!(warnings.contains(&format!("{name} ")), "{name}: {warnings}");
        }
    }
    assert!(text.starts_with("<?xml"), "the declaration stays first");
    Model::from_urdf_str(&text, "psm.urdf").expect("still a URDF");
}
