//! Measurement delays end to end through the binary: `simulate --delay` writes an MCAP
//! log whose torques lag the motion by known delays (0, 10 and 50 ms on different
//! coordinates), `fit --delay auto` recovers them into the result document, and
//! `validate` applies them from it.

mod support;
use dvrk_test_support::{f64s, read_json};
use support::{fit_example_args, run, run_json, run_ok, s, simulate_example, temp_dir};

const TRUTH_S: [f64; 7] = [0.0, 0.010, 0.050, 0.010, 0.050, 0.0, 0.010];

fn simulate(out: &std::path::Path, seed: &str) {
    let delays: Vec<String> = TRUTH_S.iter().map(|d| d.to_string()).collect();
    simulate_example(
        out,
        &[
            "--periods",
            "3",
            "--noise",
            "0.002",
            "--seed",
            seed,
            "--delay",
            &delays.join(","),
        ],
    );
}

#[test]
fn fit_recovers_simulated_delays_and_validate_applies_them() {
    let dir = temp_dir("delay");
    let (train, test) = (dir.join("train.mcap"), dir.join("test.mcap"));
    simulate(&train, "1");
    simulate(&test, "2");
    let (train, test) = (s(&train), s(&test));
    let result = dir.join("result.json");
    // An OLS fit of `train`, tested on `test`.
    let fit = [
        "fit", &train, "--robot", "psm", "--method", "ols", "--test", &test,
    ];
    let out = run_ok(&[&fit[..], &["--delay", "auto", "--out", &s(&result)]].concat());
    assert!(out.contains("torque delays (estimated, ms)"), "{out}");
    let doc = read_json(&result);
    let found = f64s(&doc["delay"]["delay_s"]);
    let applied = f64s(&doc["settings"]["processing"]["delay_s"]);
    assert_eq!(found, applied);
    println!(
        "delays found (ms): {:?}",
        found.iter().map(|d| d * 1e3).collect::<Vec<_>>()
    );
    for (j, (f, t)) in found.iter().zip(TRUTH_S).enumerate() {
        assert!((f - t).abs() < 1e-3, "q{}: {f} s, simulated {t} s", j + 1);
    }
    for e in doc["delay"]["std_s"].as_array().unwrap() {
        let e = e.as_f64().unwrap();
        assert!(e > 0.0 && e < 1e-3, "std {e}");
    }
    // `validate` processes the test log with the result's delays: the fit's test metrics.
    let v = run_json(&["validate", &s(&result), &test, "--json"]);
    let validated = &v["validations"][0]["metrics"]["relative_error"];
    let tested = &doc["metrics"]["test"]["relative_error"];
    for j in 0..7 {
        let (a, b) = (validated[j].as_f64().unwrap(), tested[j].as_f64().unwrap());
        assert!(
            (a - b).abs() <= 1e-12 * b.abs().max(1e-300),
            "q{}: {a} vs {b}",
            j + 1
        );
    }
    // Fitted without the delays, the same log is explained worse on the delayed joints.
    let plain = run_json(&[&fit[..], &["--json"]].concat());
    let plain = &plain["metrics"]["test"]["relative_error"];
    for j in [2, 4] {
        assert!(
            plain[j].as_f64().unwrap() > 2.0 * tested[j].as_f64().unwrap(),
            "q{}: {} without delays vs {} with",
            j + 1,
            plain[j],
            tested[j]
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn bad_delays_are_refused_with_the_flag_named() {
    for (delay, wanted) in [
        ("-0.01", "within [0, 1] s"),
        ("0.01,0.02", "2 delays for 7 coordinates"),
        ("soon", "`soon` is not a delay"),
        ("2", "within [0, 1] s"),
    ] {
        let (ok, out, err) = run(&fit_example_args(&["--delay", delay]));
        assert!(!ok, "--delay {delay} accepted: {out}");
        assert!(
            err.contains("--delay") && err.contains(wanted),
            "--delay {delay}: {err}"
        );
    }
    let (ok, _, err) = run(&fit_example_args(&["--delay", "auto", "--stream"]));
    assert!(!ok);
    assert!(err.contains("needs the logs in memory"), "{err}");
}
