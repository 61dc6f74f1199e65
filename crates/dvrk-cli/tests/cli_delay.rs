//! Measurement delays end to end through the binary: `simulate --delay` writes an MCAP
//! log whose torques lag the motion by known delays (0, 10 and 50 ms on different
//! coordinates), `fit --delay auto` recovers them into the result document, and
//! `validate` applies them from it.

mod support;
use support::{example, run, s, temp_dir};

const TRUTH_S: [f64; 7] = [0.0, 0.010, 0.050, 0.010, 0.050, 0.0, 0.010];

fn simulate(out: &std::path::Path, seed: &str) {
    let delays: Vec<String> = TRUTH_S.iter().map(|d| d.to_string()).collect();
    let (ok, _, err) = run(&[
        "simulate",
        "psm",
        "--params",
        &example("psm_params.json"),
        "--trajectory",
        &example("psm_trajectory.json"),
        "--periods",
        "3",
        "--noise",
        "0.002",
        "--seed",
        seed,
        "--delay",
        &delays.join(","),
        "--out",
        &s(out),
    ]);
    assert!(ok, "{err}");
}

#[test]
fn fit_recovers_simulated_delays_and_validate_applies_them() {
    let dir = temp_dir("delay");
    let (train, test) = (dir.join("train.mcap"), dir.join("test.mcap"));
    simulate(&train, "1");
    simulate(&test, "2");
    let result = dir.join("result.json");
    let (ok, out, err) = run(&[
        "fit",
        &s(&train),
        "--robot",
        "psm",
        "--method",
        "ols",
        "--delay",
        "auto",
        "--test",
        &s(&test),
        "--out",
        &s(&result),
    ]);
    assert!(ok, "{err}");
    assert!(out.contains("torque delays (estimated, ms)"), "{out}");
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&result).unwrap()).unwrap();
    let found: Vec<f64> = doc["delay"]["delay_s"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    let applied: Vec<f64> = doc["settings"]["processing"]["delay_s"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
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
    let (ok, out, err) = run(&["validate", &s(&result), &s(&test), "--json"]);
    assert!(ok, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
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
    let (ok, out, err) = run(&[
        "fit",
        &s(&train),
        "--robot",
        "psm",
        "--method",
        "ols",
        "--test",
        &s(&test),
        "--json",
    ]);
    assert!(ok, "{err}");
    let plain: serde_json::Value = serde_json::from_str(&out).unwrap();
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
    let log = example("psm_excitation.mcap");
    for (delay, wanted) in [
        ("-0.01", "within [0, 1] s"),
        ("0.01,0.02", "2 delays for 7 coordinates"),
        ("soon", "`soon` is not a delay"),
        ("2", "within [0, 1] s"),
    ] {
        let (ok, out, err) = run(&["fit", &log, "--robot", "psm", "--delay", delay]);
        assert!(!ok, "--delay {delay} accepted: {out}");
        assert!(
            err.contains("--delay") && err.contains(wanted),
            "--delay {delay}: {err}"
        );
    }
    let (ok, _, err) = run(&["fit", &log, "--robot", "psm", "--delay", "auto", "--stream"]);
    assert!(!ok);
    assert!(err.contains("needs the logs in memory"), "{err}");
}
