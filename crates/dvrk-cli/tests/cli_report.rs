//! `fit --report`, `report` and `model --draw` end to end on the bundled example log:
//! the files a user opens, their content, and errors that leave nothing behind.

mod support;
use dvrk_test_support::read_json;
use std::path::{Path, PathBuf};
use support::{example, files, fit_example_args, run, run_json, run_ok, s, temp_dir};

#[test]
fn fit_report_then_report_command_show_the_result() {
    let dir = temp_dir("fit");
    let out = dir.join("result.json");
    let rep = dir.join("fit-report");
    let log = example("psm_excitation.mcap");
    run_ok(&fit_example_args(&[
        "--method",
        "wls",
        "--cutoff",
        "none",
        "--test",
        &log,
        "--test-window",
        "500",
        "--out",
        out.to_str().unwrap(),
        "--report",
        rep.to_str().unwrap(),
    ]));
    let names = files(&rep);
    for stem in [
        "torque_1_training",
        "torque_2_test",
        "processing_1_training",
        "base_parameters",
        "kinematics",
    ] {
        assert!(names.contains(&format!("{stem}.svg")), "{names:?}");
        assert!(names.contains(&format!("{stem}.png")), "{names:?}");
    }
    let html = std::fs::read_to_string(rep.join("report.html")).unwrap();
    let result = read_json(&out);
    for key in ["train", "test"] {
        for v in result["metrics"][key]["relative_error"].as_array().unwrap() {
            let cell = format!("<td>{:.4}</td>", v.as_f64().unwrap());
            assert!(html.contains(&cell), "{key} {cell}");
        }
    }
    assert!(html.contains(result["inputs"][0]["sha256"].as_str().unwrap()));

    // `report` on the same result: its recorded logs by default, plus an excitation.
    let rep2 = dir.join("report");
    let traj = PathBuf::from(example("psm_trajectory.json"));
    let stdout = run_ok(&[
        "report",
        out.to_str().unwrap(),
        "--out",
        rep2.to_str().unwrap(),
        "--excitation",
        traj.to_str().unwrap(),
    ]);
    assert_eq!(
        stdout.trim(),
        rep2.join("report.html").display().to_string()
    );
    let names2 = files(&rep2);
    assert!(names2.contains(&"excitation.svg".to_string()));
    assert!(names2.contains(&"torque_2_test.png".to_string()));
    // The test metrics of the page come from the same 500-sample window.
    let html2 = std::fs::read_to_string(rep2.join("report.html")).unwrap();
    assert!(html2.contains("(500 samples)"));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn draw_writes_svg_and_png_of_the_tree() {
    let dir = temp_dir("draw");
    let svg = dir.join("tree.svg");
    let png = dir.join("tree.png");
    let (ok, _, err) = run(&[
        "model",
        "mtm",
        "--draw",
        "--q",
        "0.1,0.2,-0.3,0,0,0,0",
        "--out",
        svg.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    let text = std::fs::read_to_string(&svg).unwrap();
    assert!(text.starts_with("<svg") && text.trim_end().ends_with("</svg>"));
    assert!(text.contains("q3=-0.300"));
    let (ok, _, err) = run(&["model", "psm", "--draw", "--out", png.to_str().unwrap()]);
    assert!(ok, "{err}");
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn bad_requests_fail_cleanly_and_write_nothing() {
    let dir = temp_dir("errors");
    let bad_ext = dir.join("tree.pdf");
    let (ok, _, err) = run(&["model", "psm", "--draw", "--out", bad_ext.to_str().unwrap()]);
    assert!(!ok);
    assert!(
        err.contains("tree.pdf") && err.contains(".svg or .png"),
        "{err}"
    );
    let (ok, _, err) = run(&[
        "model",
        "psm",
        "--draw",
        "--q",
        "0,0",
        "--out",
        dir.join("t.svg").to_str().unwrap(),
    ]);
    assert!(!ok && err.contains("--q"), "{err}");
    let missing = dir.join("missing.json");
    let (ok, _, err) = run(&[
        "report",
        missing.to_str().unwrap(),
        "--out",
        dir.join("rep").to_str().unwrap(),
    ]);
    assert!(!ok && err.contains("missing.json"), "{err}");
    // A result file that is not one.
    let junk = dir.join("junk.json");
    std::fs::write(&junk, "{\"method\": 3}").unwrap();
    let (ok, _, err) = run(&[
        "report",
        junk.to_str().unwrap(),
        "--out",
        dir.join("rep").to_str().unwrap(),
    ]);
    assert!(!ok && err.contains("junk.json"), "{err}");
    assert_eq!(files(&dir), ["junk.json"]);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn progress_bars_stay_off_pipes_and_quiet_is_global() {
    for extra in [&[][..], &["--quiet"][..]] {
        let args = [&["--cutoff", "none", "--method", "ols"], extra].concat();
        let (ok, stdout, err) = run(&fit_example_args(&args));
        assert!(ok, "{err}");
        assert!(stdout.contains("physically consistent"));
        // stderr is a pipe here: no bar, no spinner, nothing at all.
        assert_eq!(err, "", "{extra:?}");
    }
}

/// A fit with `--stribeck` records it in its settings, so `validate` and `report`
/// rebuild the same extended model and reproduce its metrics.
#[test]
fn stribeck_fit_is_read_back_by_validate_and_report() {
    let dir = temp_dir("stribeck");
    let out = dir.join("r.json");
    let log = example("psm_excitation.mcap");
    run_ok(&fit_example_args(&[
        "--cutoff",
        "none",
        "--method",
        "sdp",
        "--stribeck",
        "0.2",
        "--out",
        out.to_str().unwrap(),
    ]));
    let result = read_json(&out);
    assert_eq!(result["settings"]["stribeck_velocity"], 0.2);
    let params = result["parameters"].as_object().unwrap();
    assert!(params.contains_key("Fs1") && params.contains_key("Fs16"));
    let validate = ["validate", out.to_str().unwrap(), &log, "--cutoff", "none"];
    let v = run_json(&[&validate[..], &["--json"]].concat());
    let again = v["validations"][0]["metrics"]["relative_error"]
        .as_array()
        .unwrap();
    let train = result["metrics"]["train"]["relative_error"]
        .as_array()
        .unwrap();
    for (a, b) in again.iter().zip(train) {
        assert!((a.as_f64().unwrap() - b.as_f64().unwrap()).abs() < 1e-12);
    }
    // The fit's own metrics beside the log's: in the document and side by side in the
    // table.
    assert_eq!(v["fit"]["train"], result["metrics"]["train"]);
    let table = run_ok(&validate);
    let header = table.lines().nth(1).unwrap();
    assert!(
        header.contains("fit train rel") && header.contains("this log rel"),
        "{table}"
    );
    let q1: Vec<f64> = table
        .lines()
        .nth(2)
        .unwrap()
        .split_whitespace()
        .skip(1)
        .map(|x| x.parse().unwrap())
        .collect();
    assert_eq!(q1.len(), 4, "{table}");
    assert!(
        (q1[0] - q1[2]).abs() < 1e-4,
        "the same log: the same error, {table}"
    );
    run_ok(&[
        "report",
        out.to_str().unwrap(),
        &log,
        "--cutoff",
        "none",
        "--out",
        dir.join("rep").to_str().unwrap(),
    ]);
    let html = std::fs::read_to_string(dir.join("rep/report.html")).unwrap();
    assert!(html.contains("<td class=l>Fs16</td>"));
    // One metrics table, each column once: this log's errors are the fit's training
    // errors (same log, same settings), so the fit's column names it instead of a copy.
    assert!(
        html.contains("<th colspan=2>fit: training, shown as log 1 ("),
        "one column"
    );
    assert_eq!(html.matches("<th colspan=2>").count(), 1);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `fit --excitation`: the trajectory is drawn in the report, and the test metrics cover
/// its first period (int(200 Hz / 0.18 Hz) = 1111 samples, the 2019 protocol).
#[test]
fn fit_with_excitation_uses_its_period_and_draws_it() {
    let dir = temp_dir("excitation");
    let log = example("psm_excitation.mcap");
    let traj = PathBuf::from(example("psm_trajectory.json"));
    let rep = dir.join("rep");
    // An OLS fit of the log tested on itself, with the excitation and JSON output.
    let fit = [
        "--cutoff",
        "none",
        "--method",
        "ols",
        "--test",
        &log,
        "--excitation",
        traj.to_str().unwrap(),
        "--json",
    ];
    let r = run_json(&fit_example_args(
        &[&fit[..], &["--report", rep.to_str().unwrap()]].concat(),
    ));
    assert_eq!(r["settings"]["test_window"], 1111);
    assert_eq!(r["metrics"]["test"]["samples"], 1111);
    assert!(files(&rep).contains(&"excitation.svg".to_string()));
    // An explicit --test-window wins.
    let r = run_json(&fit_example_args(
        &[&fit[..], &["--test-window", "300"]].concat(),
    ));
    assert_eq!(r["metrics"]["test"]["samples"], 300);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The words of a command line as a POSIX shell splits it: blanks separate words, single
/// quotes keep everything up to the next one (the quoting `reproduce::shell_quote` uses).
/// The bundled example fitted by OLS into `out`: a result document to report on.
fn fit_ols_example(out: &Path) {
    run_ok(&fit_example_args(&["--method", "ols", "--out", &s(out)]));
}

fn shell_words(text: &str) -> Vec<String> {
    let mut words = Vec::new();
    let mut word: Option<String> = None;
    let mut quoted = false;
    for c in text.chars() {
        match (quoted, c) {
            (true, '\'') => quoted = false,
            (true, c) => word.get_or_insert_with(String::new).push(c),
            (false, '\'') => {
                quoted = true;
                word.get_or_insert_with(String::new);
            }
            (false, c) if c.is_whitespace() => words.extend(word.take()),
            (false, '\\') => panic!("no backslash outside quotes expected: {text}"),
            (false, c) => word.get_or_insert_with(String::new).push(c),
        }
    }
    assert!(!quoted, "unbalanced quote: {text}");
    words.extend(word);
    words
}

/// The command line a report shows is the fit's: run as the shell would split it, the
/// real command line writes a document with the same settings and inputs (so the
/// rendering cannot drift from the flags). Non-default settings of several kinds: a
/// per-coordinate cut-off, trimming, decimation, a minimum speed, fixed delays, a
/// Stribeck term, a test window, the measured joints; a log path with a space.
#[test]
fn the_reports_command_line_repeats_the_fit() {
    use dvrk_ident::log::ReadOptions;
    use dvrk_ident::reproduce::FitCall;

    let dir = temp_dir("reproduce");
    let log = dir.join("psm excitation.mcap");
    std::fs::copy(example("psm_excitation.mcap"), &log).unwrap();
    let first = dir.join("first.json");
    let rep = dir.join("rep");
    run_ok(&[
        "fit",
        log.to_str().unwrap(),
        "--robot",
        "psm",
        "--method",
        "ols",
        "--cutoff",
        "4,4,4,3.5,3.5,3.5,3.5",
        "--trim",
        "150",
        "--decimate",
        "2",
        "--min-speed",
        "0.001",
        "--delay",
        "0.005,0,0,0.01,0,0,0",
        "--stribeck",
        "0.2",
        "--test",
        &example("psm_excitation.mcap"),
        "--test-window",
        "300",
        "--joints",
        "measured",
        "--out",
        first.to_str().unwrap(),
        "--report",
        rep.to_str().unwrap(),
    ]);
    let result = dvrk_ident::FitResult::read(&first).unwrap();
    let read = ReadOptions::default();
    let rendered = FitCall::of_result(&result, Some(&read)).cli_command();
    assert!(rendered.unrendered.is_empty(), "{:?}", rendered.unrendered);
    let words = shell_words(&rendered.text);
    assert_eq!(words, rendered.args);
    assert_eq!(words[..2], ["dvrk-ident", "fit"]);
    assert!(
        rendered.text.contains("'"),
        "the path with a space is quoted"
    );

    let again = dir.join("again.json");
    let mut args = words[1..].to_vec();
    args.extend(["--out".to_string(), again.display().to_string()]);
    run_ok(&args);
    let (a, b) = (read_json(&first), read_json(&again));
    assert_eq!(a["settings"], b["settings"]);
    assert_eq!(a["inputs"], b["inputs"]);
    assert_eq!(a["parameters"], b["parameters"]);

    // The report shows that command line (HTML-escaped), and the Python call.
    let html = std::fs::read_to_string(rep.join("report.html")).unwrap();
    let escaped = dvrk_ident::report::html::escape(&rendered.text);
    assert!(
        html.contains(&format!("<pre id=command-line>{escaped}</pre>")),
        "{escaped}"
    );
    assert!(html.contains("result = di.fit(robot, train, method=&quot;ols&quot;"));
    assert!(!html.contains("id=not-reproduced"));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A setting without a flag is named in the page, not rendered as an invented flag: a
/// result whose filter is the 2019 one (transfer-function form, the 2019 cut-off
/// convention) reported again.
#[test]
fn a_setting_without_a_flag_is_named_in_the_report() {
    let dir = temp_dir("noflag");
    let out = dir.join("result.json");
    fit_ols_example(&out);
    let mut doc = read_json(&out);
    doc["settings"]["processing"]["filter"]["form"] = "ba".into();
    doc["settings"]["processing"]["filter"]["convention"] = "wpi".into();
    doc["settings"]["processing"]["filter"]["padlen"] = 20.into();
    std::fs::write(&out, serde_json::to_string_pretty(&doc).unwrap()).unwrap();
    let rep = dir.join("rep");
    run_ok(&[
        "report",
        out.to_str().unwrap(),
        "--out",
        rep.to_str().unwrap(),
    ]);
    let html = std::fs::read_to_string(rep.join("report.html")).unwrap();
    let start = html
        .find("<ul id=not-reproduced>")
        .expect("the list of what is not repeated");
    let list = &html[start..start + html[start..].find("</ul>").unwrap()];
    assert!(list.contains("the low-pass filter"), "{list}");
    assert!(
        list.contains("&quot;convention&quot;:&quot;wpi&quot;"),
        "{list}"
    );
    let command = &html[html.find("<pre id=command-line>").unwrap()..];
    let command = &command[..command.find("</pre>").unwrap()];
    assert!(
        !command.contains("wpi") && !command.contains("--cutoff"),
        "{command}"
    );
    // Python carries it in settings=.
    assert!(html.contains("settings={&quot;processing&quot;: {&quot;filter&quot;:"));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A report whose flags change the logs' processing or joints keeps the result's own
/// settings where they are the fit's (its command line, its metrics columns) and lists
/// what differs for the logs drawn; nothing of the result document changes.
#[test]
fn a_reports_own_settings_are_listed_not_passed_off_as_the_fits() {
    let dir = temp_dir("report-shown");
    let out = dir.join("result.json");
    fit_ols_example(&out);
    let before = std::fs::read(&out).unwrap();
    let rep = dir.join("rep");
    let (ok, _, err) = run(&[
        "report",
        out.to_str().unwrap(),
        &example("psm_excitation.mcap"),
        "--cutoff",
        "5",
        "--joints",
        "measured",
        "--out",
        rep.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    assert!(err.contains("cutoff"), "the terminal note: {err}");
    let html = std::fs::read_to_string(rep.join("report.html")).unwrap();
    let listed = html
        .split("differ from the fit's")
        .nth(1)
        .expect("the differing settings are listed");
    let table = &listed[..listed.find("</table>").unwrap()];
    assert!(table.contains("processing.filter.cutoff_hz"), "{table}");
    assert!(
        table.contains("<td class=l>joints</td><td class=l>measured</td><td class=l>none</td>"),
        "{table}"
    );
    // The fit's command line is the fit's: no cut-off of 5 Hz, no --joints.
    let command = html.split("<pre id=command-line>").nth(1).unwrap();
    let command = &command[..command.find("</pre>").unwrap()];
    assert!(
        !command.contains("--cutoff") && !command.contains("--joints"),
        "{command}"
    );
    // The logs' metrics in the measured joints, in their own table beside the fit's.
    assert!(html.contains("outer_wrist_pitch"));
    assert_eq!(std::fs::read(&out).unwrap(), before);
    std::fs::remove_dir_all(&dir).unwrap();
}
