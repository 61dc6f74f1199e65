//! `dvrk-ident fit a b --test c`: several logs of mixed formats (an MCAP, a rosbag2
//! folder written by hand around an MCAP, a headered CSV), the same document as the
//! library's fit of the same logs, in memory and streamed; a file that is no log is an
//! error saying what it is, with nothing written.

mod support;

use std::path::Path;
use std::sync::Arc;

use dvrk_ident::log::{self, LogFormat};
use dvrk_ident::Silent;
use dvrk_ident::{FitRequest, FitSettings, JointLog, LogSource, Method, Training};
use dvrk_model::Model;
use dvrk_test_support::read_json;
use support::{example, files, run, run_ok, s, temp_dir};

fn part(t: &JointLog, lo: usize, hi: usize) -> JointLog {
    t.select_rows(&(lo..hi).collect::<Vec<_>>())
}

#[test]
fn several_logs_of_mixed_formats() {
    let dir = temp_dir("several");
    let whole = log::read(example("psm_excitation.mcap"), None, None).unwrap();
    let a = dir.join("a.mcap");
    log::write(&a, &part(&whole, 0, 900), LogFormat::Mcap).unwrap();
    // A rosbag2 folder: metadata.yaml listing its one MCAP file.
    let bag = dir.join("b_bag");
    std::fs::create_dir(&bag).unwrap();
    log::write(
        bag.join("b_bag_0.mcap"),
        &part(&whole, 900, 1700),
        LogFormat::Mcap,
    )
    .unwrap();
    std::fs::write(
        bag.join("metadata.yaml"),
        "rosbag2_bagfile_information:\n  version: 9\n  storage_identifier: mcap\n  relative_file_paths:\n  - b_bag_0.mcap\n",
    )
    .unwrap();
    let c = dir.join("c.csv");
    log::write(&c, &part(&whole, 1700, whole.len()), LogFormat::Csv).unwrap();

    let out = dir.join("r.json");
    // The WLS fit of a and b tested on c, into `out`, with the flags `extra`.
    let fit = |out: &Path, extra: &[&str]| {
        let (a, bag, c, out) = (s(&a), s(&bag), s(&c), s(out));
        let args = [
            "fit",
            &a,
            &bag,
            "--robot",
            "psm",
            "--method",
            "wls",
            "--test",
            &c,
            "--test-window",
            "100",
            "--out",
            &out,
        ];
        run_ok(&[&args[..], extra].concat())
    };
    let stdout = fit(&out, &[]);
    assert!(
        stdout.contains("logs (samples after processing, sha256)"),
        "{stdout}"
    );
    assert!(stdout.contains("b_bag (/measured_js)"), "{stdout}");
    let doc = read_json(&out);
    let inputs = doc["inputs"].as_array().unwrap();
    let roles: Vec<&str> = inputs.iter().map(|i| i["role"].as_str().unwrap()).collect();
    assert_eq!(roles, ["train", "train", "test"]);
    // The folder's hash covers metadata.yaml and the MCAP file.
    let folder_bytes = std::fs::metadata(bag.join("metadata.yaml")).unwrap().len()
        + std::fs::metadata(bag.join("b_bag_0.mcap")).unwrap().len();
    assert_eq!(inputs[1]["bytes"].as_u64().unwrap(), folder_bytes);
    assert_eq!(inputs[2]["metrics"]["samples"].as_u64().unwrap(), 100);
    assert_eq!(
        doc["metrics"]["train"]["samples"].as_u64().unwrap(),
        inputs[0]["metrics"]["samples"].as_u64().unwrap()
            + inputs[1]["metrics"]["samples"].as_u64().unwrap()
    );

    // The library on the same logs: the same parameters and metrics.
    let model = Model::builtin("psm").unwrap();
    // Each log read here, handed to the library as samples with their file.
    let mut data: Vec<LogSource> = [&a, &bag, &c]
        .iter()
        .map(|p| LogSource::Samples {
            samples: Arc::new(log::read(p, None, None).unwrap()),
            file: Some(p.to_path_buf()),
        })
        .collect();
    let test = data.split_off(2);
    let request = FitRequest {
        test,
        settings: FitSettings {
            method: Method::Wls,
            test_window: Some(100),
            ..FitSettings::default()
        },
        ..FitRequest::new(Training::Logs(data))
    };
    let lib = request.run(Some(&model), &Silent).unwrap().result;
    let lib: serde_json::Value = serde_json::from_str(&lib.to_json()).unwrap();
    assert_eq!(doc["parameters"], lib["parameters"]);
    assert_eq!(doc["metrics"], lib["metrics"]);
    assert_eq!(doc["inputs"], lib["inputs"]);

    // Streamed: the same document but for the solver's time.
    let streamed = dir.join("s.json");
    fit(&streamed, &["--stream"]);
    let sdoc = read_json(&streamed);
    for key in [
        "parameters",
        "metrics",
        "inputs",
        "weights",
        "base_parameters",
    ] {
        assert_eq!(sdoc[key], doc[key], "{key}");
    }

    // Each log's own offset (--log-offsets): the same in memory and streamed, the
    // first log's zero; validate on another log says which offsets it applies.
    let (own, own_streamed) = (dir.join("o.json"), dir.join("os.json"));
    let stdout = fit(&own, &["--log-offsets"]);
    assert!(
        stdout.contains("own torque offset over the model's"),
        "{stdout}"
    );
    fit(&own_streamed, &["--log-offsets", "--stream"]);
    let (odoc, osdoc) = (read_json(&own), read_json(&own_streamed));
    assert_eq!(odoc["inputs"], osdoc["inputs"]);
    assert_eq!(odoc["parameters"], osdoc["parameters"]);
    let offsets = |i: usize| dvrk_test_support::f64s(&odoc["inputs"][i]["offset"]);
    assert_eq!(offsets(0), [0.0; 7]);
    assert!(offsets(1).iter().any(|v| *v != 0.0));
    assert!(
        odoc["inputs"][2].get("offset").is_none(),
        "a test log has none"
    );
    let stdout = run_ok(&["validate", &s(&own), &s(&c)]);
    assert!(
        stdout.contains("torque offsets: the model's Fo, fitted on the first training log"),
        "{stdout}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_file_that_is_no_log_is_named_and_nothing_is_written() {
    let dir = temp_dir("no-log");
    let junk = dir.join("run_0.db3");
    std::fs::write(&junk, b"PK\x03\x04\x14\x00\x00\x00zipped").unwrap();
    let out = dir.join("r.json");
    let (ok, _, err) = run(&[
        "fit",
        &example("psm_excitation.mcap"),
        &s(&junk),
        "--robot",
        "psm",
        "--out",
        &s(&out),
    ]);
    assert!(!ok);
    assert!(
        err.contains("run_0.db3: not a supported log: it looks like a zip archive"),
        "{err}"
    );
    assert!(err.contains("supported: a rosbag2 folder"), "{err}");
    assert!(!err.contains("CSV parse"), "{err}");
    assert_eq!(files(&dir), ["run_0.db3"]);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The same data given twice (a training log repeated, a test log equal to a training
/// log) is fitted, with a warning naming both on stderr; distinct logs give none.
#[test]
fn the_same_data_twice_is_named_in_a_warning() {
    let dir = support::temp_dir("same-data-twice");
    let copy = dir.join("copy.mcap");
    std::fs::copy(support::example("psm_excitation.mcap"), &copy).unwrap();
    let log = support::example("psm_excitation.mcap");
    let (ok, _, err) = support::run(&[
        "fit",
        &log,
        &support::s(&copy),
        "--robot",
        "psm",
        "--method",
        "ols",
        "--test",
        &log,
    ]);
    assert!(ok, "{err}");
    let warnings: Vec<&str> = err
        .lines()
        .filter(|l| l.starts_with("dvrk-ident: warning:"))
        .collect();
    assert_eq!(warnings.len(), 2, "{err}");
    assert!(
        warnings[0].contains("train log")
            && warnings[0].contains("copy.mcap")
            && warnings[0].contains("√2"),
        "{}",
        warnings[0]
    );
    assert!(
        warnings[1].starts_with("dvrk-ident: warning: test log")
            && warnings[1].contains("not a test of generalization"),
        "{}",
        warnings[1]
    );
    let (ok, _, err) = support::run(&["fit", &log, "--robot", "psm", "--method", "ols"]);
    assert!(ok && !err.contains("warning:"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}
