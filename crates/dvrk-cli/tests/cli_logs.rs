//! Logs in and out, end to end through the binary: the bundled simulated PSM log is
//! fitted back to its generating parameters, `simulate` and `convert` round-trip values
//! between MCAP, headered CSV and the 2019 layout, and bad inputs fail with a message
//! naming the problem, a non-zero exit and no output file.

mod support;
use std::ffi::OsStr;
use std::fmt::Debug;
use std::path::Path;
use support::{
    example, fit_example_args, run, run_json, run_ok, s, simulate_args, simulate_example, temp_dir,
};

use dvrk_ident::log;
use dvrk_model::Model;

/// Noise of the bundled log, N·m or N per model coordinate (see examples/README.md).
const NOISE: f64 = 0.002;

/// The generating parameters of the bundled log, projected on the base parameters.
fn true_base_parameters(model: &Model) -> Vec<f64> {
    let pi = dvrk_test_support::fixtures::example_params(model);
    model.base_parameters().unwrap().project(&pi)
}

/// The README's main command with the flags `extra` and JSON output: the result
/// document.
fn fit_example(extra: &[&str]) -> serde_json::Value {
    let mut args = fit_example_args(extra);
    args.push("--json".into());
    run_json(&args)
}

#[test]
fn ols_fit_of_the_example_recovers_the_generating_base_parameters() {
    let model = Model::builtin("psm").unwrap();
    let truth = true_base_parameters(&model);
    let r = fit_example(&["--method", "ols"]);
    assert_eq!(r["solver"]["converged"], true);
    assert_eq!(r["rows"], 7 * (2222 - 2 * 200));
    let base = r["base_parameters"].as_array().unwrap();
    assert_eq!(base.len(), truth.len());
    let mut worst: f64 = 0.0;
    for (b, t) in base.iter().zip(&truth) {
        let (v, std) = (b["value"].as_f64().unwrap(), b["std"].as_f64().unwrap());
        worst = worst.max((v - t).abs() / std);
        assert!(
            (v - t).abs() <= 6.0 * std + 1e-9,
            "{}: {v} vs {t} (std {std})",
            b["expression"]
        );
    }
    // What is left is the noise.
    for rms in r["metrics"]["train"]["rms"].as_array().unwrap() {
        let rms = rms.as_f64().unwrap();
        assert!(rms < 1.2 * NOISE && rms > 0.8 * NOISE, "rms {rms}");
    }
    println!(
        "ols: worst |error|/std {worst:.2}, condition number {:.1}",
        r["condition_number"]
    );
    // The README's main command is this fit with the default processing.
    let readme = std::fs::read_to_string(example("../README.md")).unwrap();
    assert!(readme.contains(
        "cargo run --release -p dvrk-cli -- fit examples/psm_excitation.mcap --robot psm\n"
    ));
}

#[test]
fn filtering_the_torques_biases_the_example_fit() {
    // Why the default processing leaves the torques alone: the low-pass smooths the
    // Coulomb friction steps in the measured torques but not in the regressor.
    let model = Model::builtin("psm").unwrap();
    let truth = true_base_parameters(&model);
    let r = fit_example(&["--method", "ols", "--filter-torque"]);
    assert_eq!(r["settings"]["processing"]["filter_torque"], true);
    let worst = r["base_parameters"]
        .as_array()
        .unwrap()
        .iter()
        .zip(&truth)
        .map(|(b, t)| (b["value"].as_f64().unwrap() - t).abs() / b["std"].as_f64().unwrap())
        .fold(0.0, f64::max);
    assert!(worst > 20.0, "worst |error|/std {worst}");
    for rms in r["metrics"]["train"]["rms"].as_array().unwrap() {
        assert!(rms.as_f64().unwrap() > 5.0 * NOISE, "{rms}");
    }
}

#[test]
fn sdp_fit_of_the_example_converges_and_is_physically_consistent() {
    let model = Model::builtin("psm").unwrap();
    let truth = true_base_parameters(&model);
    let r = fit_example(&["--method", "sdp"]);
    assert_eq!(r["solver"]["converged"], true, "{}", r["solver"]);
    assert_eq!(r["physically_consistent"], true);
    for c in r["consistency"].as_array().unwrap() {
        assert!(c["min_eigenvalue"].as_f64().unwrap() > 0.0, "{c}");
    }
    let mut worst: f64 = 0.0;
    for (b, t) in r["base_parameters"].as_array().unwrap().iter().zip(&truth) {
        let (v, std) = (b["value"].as_f64().unwrap(), b["std"].as_f64().unwrap());
        worst = worst.max((v - t).abs() / std);
        // The generating parameters are feasible, so the constraints cost little: the
        // same bound as least squares (std from the WLS fit of the same data).
        assert!(
            (v - t).abs() <= 6.0 * std + 1e-6,
            "{}: {v} vs {t} (std {std})",
            b["expression"]
        );
    }
    for rms in r["metrics"]["train"]["rms"].as_array().unwrap() {
        assert!(rms.as_f64().unwrap() < 1.5 * NOISE, "{rms}");
    }
    println!("sdp: worst |error|/std {worst:.2}");
}

#[test]
fn the_example_log_is_what_its_readme_command_writes() {
    let dir = temp_dir("logs-regenerate");
    let out = dir.join("again.mcap");
    simulate_example(
        &out,
        &[
            "--periods",
            "2",
            "--rate",
            "200",
            "--noise",
            "0.002",
            "--seed",
            "1",
            "--out-topic",
            "/PSM1/measured_js",
        ],
    );
    let a = log::read(example("psm_excitation.mcap"), None, None).unwrap();
    let b = log::read(&out, None, None).unwrap();
    assert_eq!(a.len(), 2222);
    assert_eq!(a.time, b.time);
    assert_eq!(a.joint_names, b.joint_names);
    assert_eq!(a.q, b.q);
    assert_eq!(a.dq, b.dq);
    assert_eq!(a.tau, b.tau);
    // The same trajectory taken from the 2019 coefficient file.
    if let Some(anchor) = dvrk_test_support::shared("anchors/wpi2019_excitation_trajectories.json")
    {
        let picked = dir.join("picked.mcap");
        run_ok(&simulate_args(
            "psm",
            &s(&anchor),
            &picked,
            &[
                "--pick",
                "psm_one",
                "--periods",
                "2",
                "--noise",
                "0.002",
                "--seed",
                "1",
            ],
        ));
        let c = log::read(&picked, None, None).unwrap();
        assert_eq!((&c.q, &c.tau), (&a.q, &a.tau));
    }
    let readme = std::fs::read_to_string(example("README.md")).unwrap();
    assert!(readme.contains("--periods 2 --rate 200 --noise 0.002 --seed 1"));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn simulate_then_convert_round_trips_values() {
    let dir = temp_dir("logs-roundtrip");
    let mcap = dir.join("sim.mcap");
    let out = simulate_example(
        &mcap,
        &["--duration", "1.5", "--noise", "0.01", "--seed", "9"],
    );
    assert!(out.contains("300 samples"), "{out}");
    let original = log::read(&mcap, None, None).unwrap();
    assert_eq!(original.len(), 300);

    // MCAP -> headered CSV (measured joints, exact values).
    let csv = dir.join("sim.csv");
    let (ok, _, err) = run(&["convert", &s(&mcap), &s(&csv)]);
    assert!(ok, "{err}");
    let c = log::read(&csv, None, None).unwrap();
    assert_eq!(c.coordinates, dvrk_ident::Coordinates::Measured);
    assert_eq!(
        (&c.time, &c.q, &c.dq, &c.tau),
        (&original.time, &original.q, &original.dq, &original.tau)
    );

    // CSV -> 2019 layout (model coordinates).
    let wpi = dir.join("sim_wpi.csv");
    let (ok, _, err) = run(&[
        "convert",
        &s(&csv),
        &s(&wpi),
        "--robot",
        "psm",
        "--out-format",
        "wpi-csv",
    ]);
    assert!(ok, "{err}");
    let w = log::read(&wpi, None, Some(200.0)).unwrap();
    let model = Model::builtin("psm").unwrap();
    let expected = dvrk_ident::simulate::to_model_coordinates(&model, &original).unwrap();
    assert_eq!(w.coordinates, dvrk_ident::Coordinates::Model);
    assert!((&w.q - &expected.q).abs().max() == 0.0);
    assert!((&w.tau - &expected.tau).abs().max() == 0.0);
    assert_eq!(w.time, original.time);

    // 2019 layout -> MCAP (back to measured joints through the coupling).
    let back = dir.join("back.mcap");
    let (ok, _, err) = run(&[
        "convert",
        &s(&wpi),
        &s(&back),
        "--robot",
        "psm",
        "--rate",
        "200",
    ]);
    assert!(ok, "{err}");
    let b = log::read(&back, None, None).unwrap();
    assert_eq!(b.joint_names, original.joint_names);
    assert_eq!(b.time, original.time);
    assert!((&b.q - &original.q).abs().max() < 1e-14);
    assert!(
        (b.dq.as_ref().unwrap() - original.dq.as_ref().unwrap())
            .abs()
            .max()
            < 1e-13
    );
    assert!((&b.tau - &original.tau).abs().max() < 1e-13);

    // Model-coordinate headered CSV and the MCAP reading flags.
    let model_csv = dir.join("model.csv");
    let (ok, _, err) = run(&[
        "convert",
        &s(&mcap),
        &s(&model_csv),
        "--robot",
        "psm",
        "--coordinates",
        "model",
        "--topic",
        "/measured_js",
        "--time",
        "log",
    ]);
    assert!(ok, "{err}");
    let m = log::read(&model_csv, None, None).unwrap();
    assert_eq!(m.coordinates, dvrk_ident::Coordinates::Model);
    assert_eq!(m.joint_names, model.coordinates);
    assert_eq!(m.q, expected.q);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn fit_reads_mcap_with_topic_time_and_resample_flags() {
    let r = fit_example(&[
        "--method",
        "ols",
        "--cutoff",
        "none",
        "--topic",
        "/PSM1/measured_js",
        "--time",
        "log",
        "--resample",
        "100",
        "--trim",
        "50",
    ]);
    // 1111 samples at 100 Hz (11.105 s), 50 trimmed at each end.
    assert_eq!(r["rows"], 7 * (1111 - 100));
    // A processing setting, recorded as Python's `fit(resample=)` records it.
    assert_eq!(r["settings"]["processing"]["resample_hz"], 100.0);
    let (ok, _, err) = run(&fit_example_args(&["--topic", "/PSM2/measured_js"]));
    assert!(!ok);
    assert!(err.contains("/PSM2/measured_js"), "{err}");
}

/// Asserts a failure: non-zero exit, the message contains every word, no output file.
fn assert_fails<A: AsRef<OsStr> + Debug>(args: &[A], words: &[&str], output: Option<&Path>) {
    let (ok, _, err) = run(args);
    assert!(!ok, "{args:?} succeeded");
    for w in words {
        assert!(err.contains(w), "{args:?}: `{w}` not in: {err}");
    }
    if let Some(o) = output {
        assert!(!o.exists(), "{} was written", o.display());
        let dir = o.parent().unwrap();
        for e in std::fs::read_dir(dir).unwrap() {
            let name = e.unwrap().file_name().to_string_lossy().to_string();
            assert!(!name.contains(".tmp"), "temporary file {name} left behind");
        }
    }
}

#[test]
fn bad_logs_fail_naming_the_problem_and_write_nothing() {
    let dir = temp_dir("logs-errors");
    let mcap = dir.join("sim.mcap");
    simulate_example(&mcap, &["--duration", "1"]);
    let csv = dir.join("sim.csv");
    assert!(run(&["convert", &s(&mcap), &s(&csv)]).0);
    let text = std::fs::read_to_string(&csv).unwrap();
    let out = dir.join("out.csv");

    // A CSV without the jaw: the robot's joint is named.
    let keep: Vec<usize> = {
        let header = text.lines().next().unwrap();
        header
            .split(',')
            .enumerate()
            .filter(|(_, h)| !h.ends_with(".jaw"))
            .map(|(i, _)| i)
            .collect()
    };
    let no_jaw: String = text
        .lines()
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            keep.iter().map(|&i| f[i]).collect::<Vec<_>>().join(",")
        })
        .collect::<Vec<_>>()
        .join("\n");
    let no_jaw_path = dir.join("no_jaw.csv");
    std::fs::write(&no_jaw_path, no_jaw).unwrap();
    let model_out = dir.join("model.csv");
    assert_fails(
        &[
            "convert",
            &s(&no_jaw_path),
            &s(&model_out),
            "--robot",
            "psm",
            "--coordinates",
            "model",
        ],
        &["no_jaw.csv", "`jaw`", "missing"],
        Some(&model_out),
    );
    assert_fails(
        &["fit", &s(&no_jaw_path), "--robot", "psm", "--method", "ols"],
        &["`jaw`", "missing"],
        None,
    );
    // A CSV missing one effort column.
    let header = text.lines().next().unwrap();
    let k = header
        .split(',')
        .position(|h| h == "effort.outer_roll")
        .unwrap();
    let no_effort: String = text
        .lines()
        .map(|l| {
            let mut f: Vec<&str> = l.split(',').collect();
            f.remove(k);
            f.join(",")
        })
        .collect::<Vec<_>>()
        .join("\n");
    let p = dir.join("no_effort.csv");
    std::fs::write(&p, no_effort).unwrap();
    assert_fails(
        &["convert", &s(&p), &s(&out)],
        &["effort", "outer_roll"],
        Some(&out),
    );

    // NaN in a CSV: file, line and column.
    let lines: Vec<&str> = text.lines().collect();
    let mut f: Vec<String> = lines[10].split(',').map(String::from).collect();
    f[3] = "NaN".into();
    let mut nan = lines.clone();
    let row = f.join(",");
    nan[10] = &row;
    let p = dir.join("nan.csv");
    std::fs::write(&p, nan.join("\n")).unwrap();
    assert_fails(
        &["convert", &s(&p), &s(&out)],
        &["nan.csv:11", "non-finite"],
        Some(&out),
    );
    let mcap_out = dir.join("out.mcap");
    assert_fails(
        &["convert", &s(&p), &s(&mcap_out)],
        &["nan.csv"],
        Some(&mcap_out),
    );

    // A truncated MCAP.
    let bytes = std::fs::read(&mcap).unwrap();
    let p = dir.join("truncated.mcap");
    std::fs::write(&p, &bytes[..bytes.len() / 2]).unwrap();
    assert_fails(
        &["convert", &s(&p), &s(&out)],
        &["truncated.mcap"],
        Some(&out),
    );
    assert_fails(
        &["fit", &s(&p), "--robot", "psm", "--method", "ols"],
        &["truncated.mcap"],
        None,
    );

    // Simulation inputs: NaN noise, a trajectory for another robot, bad parameters.
    let sim_out = dir.join("sim_out.mcap");
    let short = dir.join("traj6.json");
    std::fs::write(
        &short,
        r#"{"order": 1, "base_frequency_hz": 0.2, "q0": [0,0,0,0,0,0], "a": [[0],[0],[0],[0],[0],[0]], "b": [[0],[0],[0],[0],[0],[0]]}"#,
    )
    .unwrap();
    let (trajectory, short) = (example("psm_trajectory.json"), s(&short));
    for (robot, trajectory, extra, word) in [
        ("psm", &trajectory, &["--noise", "nan"][..], "noise"),
        ("psm", &trajectory, &["--rate", "0"], "rate"),
        ("mtm", &trajectory, &[], "psm_params.json"),
        ("psm", &short, &[], "6 coordinates"),
    ] {
        assert_fails(
            &simulate_args(robot, trajectory, &sim_out, extra),
            &[word],
            Some(&sim_out),
        );
    }
    // Coordinates the target format cannot hold.
    assert_fails(
        &[
            "convert",
            &s(&mcap),
            &s(&mcap_out),
            "--coordinates",
            "model",
            "--robot",
            "psm",
        ],
        &["measured"],
        Some(&mcap_out),
    );
    let wpi_out = dir.join("w.csv");
    // (`--format`: the old spelling of `--out-format`, still accepted.)
    assert_fails(
        &["convert", &s(&mcap), &s(&wpi_out), "--format", "wpi-csv"],
        &["--robot"],
        Some(&wpi_out),
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn stream_gives_the_same_result_document_and_table() {
    let log = example("psm_excitation.mcap");
    let variants: [&[&str]; 3] = [
        &["--method", "sdp", "--test", &log, "--test-window", "500"],
        &["--method", "irls", "--resample", "150", "--trim", "50"],
        &["--method", "wls", "--filter-torque", "--cutoff", "8"],
    ];
    for extra in variants {
        let args = fit_example_args(extra);
        let outputs: Vec<(serde_json::Value, String)> = [false, true]
            .iter()
            .map(|&stream| {
                let mut a = args.clone();
                if stream {
                    a.push("--stream".into());
                }
                let (ok, table, err) = run(&a);
                assert!(ok, "{a:?}: {err}");
                a.push("--json".into());
                let (ok, out, err) = run(&a);
                assert!(ok, "{a:?}: {err}");
                let mut doc: serde_json::Value = serde_json::from_str(&out).unwrap();
                // Wall-clock time is the only difference.
                doc["solver"]["seconds"] = serde_json::Value::Null;
                let table: String = table
                    .lines()
                    .filter(|l| !l.starts_with("solver "))
                    .collect::<Vec<_>>()
                    .join("\n");
                (doc, table)
            })
            .collect();
        assert_eq!(outputs[0].0, outputs[1].0, "{extra:?}: documents differ");
        assert_eq!(outputs[0].1, outputs[1].1, "{extra:?}: tables differ");
        assert_eq!(outputs[0].0["solver"]["converged"], true);
    }
    // Errors name the file when streamed too.
    let (ok, _, err) = run(&["fit", "missing.mcap", "--robot", "psm", "--stream"]);
    assert!(!ok && err.contains("missing.mcap"), "{err}");
}

/// An interrupted run (Ctrl-C: SIGINT) removes its temporary files: the decompressed
/// copy of a compressed sqlite3 file (`tests/fixtures/hostile/bomb.db3.zst`, 300 MB once
/// decompressed, read with the bound raised past it) is gone once the process has exited
/// with status 130. The signal is sent once the copy exists (it is created before the
/// first byte is decompressed), without timing: a run that finished by itself before the
/// signal (it fails on the file, which is no database) must have removed it too, and is
/// tried again; after five such runs the interruption is reported as not tested.
#[cfg(unix)]
#[test]
fn an_interrupted_run_leaves_no_temporary_file() {
    use std::process::{Command, Stdio};
    use std::time::{Duration, Instant};
    let bomb =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/fixtures/hostile/bomb.db3.zst");
    let left = |dir: &Path| -> Vec<String> {
        std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect()
    };
    for attempt in 0..5 {
        let tmp = temp_dir(&format!("interrupted-{attempt}"));
        let mut child = Command::new(env!("CARGO_BIN_EXE_dvrk-ident"))
            .args([
                OsStr::new("fit"),
                bomb.as_os_str(),
                OsStr::new("--robot"),
                OsStr::new("psm"),
                OsStr::new("--max-unpacked-mib"),
                OsStr::new("400"),
            ])
            .env("TMPDIR", &tmp)
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        // A safety net only: the copy appears at once unless something is broken.
        let deadline = Instant::now() + Duration::from_secs(300);
        let copy_exists = loop {
            if !left(&tmp).is_empty() {
                break true;
            }
            if child.try_wait().unwrap().is_some() || Instant::now() > deadline {
                break false;
            }
            std::thread::sleep(Duration::from_millis(1));
        };
        if copy_exists {
            let killed = Command::new("kill")
                .args(["-INT", &child.id().to_string()])
                .status()
                .unwrap();
            assert!(killed.success() || child.try_wait().unwrap().is_some());
        }
        let out = child.wait_with_output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
        assert!(
            left(&tmp).is_empty(),
            "left behind: {:?} (status {:?}, {stderr})",
            left(&tmp),
            out.status
        );
        std::fs::remove_dir_all(&tmp).unwrap();
        if copy_exists && out.status.code() == Some(130) {
            assert!(stderr.contains("interrupted"), "{stderr}");
            return;
        }
        // Finished by itself before the signal: an error naming the file.
        assert_eq!(out.status.code(), Some(1), "{stderr}");
        assert!(stderr.contains("bomb.db3.zst"), "{stderr}");
    }
    dvrk_test_support::skip("every run finished before it could be interrupted");
}
