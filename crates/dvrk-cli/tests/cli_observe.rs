//! `dvrk-ident observe` (the map) and `fit --states` (the reduce): states of the logs,
//! merged and fitted, give the document of `fit` of the logs themselves; a streamed
//! observation writes the same state to the byte; states processed differently are
//! refused with the file named and nothing written.

mod support;

use dvrk_ident::log::{self, LogFormat};
use dvrk_ident::JointLog;
use support::{example, files, run, s, temp_dir};

fn part(t: &JointLog, lo: usize, hi: usize) -> JointLog {
    t.select_rows(&(lo..hi).collect::<Vec<_>>())
}

/// A result document without the solver's wall-clock time.
fn document(path: &std::path::Path) -> serde_json::Value {
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    v["solver"]["seconds"] = serde_json::Value::Null;
    v
}

#[test]
fn states_fit_as_their_logs() {
    let dir = temp_dir("observe");
    let whole = log::read(example("psm_excitation.mcap"), None, None).unwrap();
    let n = whole.len();
    let (a, b, c) = (dir.join("a.mcap"), dir.join("b.csv"), dir.join("c.mcap"));
    log::write(&a, &part(&whole, 0, n / 3), LogFormat::Mcap).unwrap();
    log::write(&b, &part(&whole, n / 3, 2 * n / 3), LogFormat::Csv).unwrap();
    log::write(&c, &part(&whole, 2 * n / 3, n), LogFormat::Mcap).unwrap();
    let observe = |log: &std::path::Path, out: &str, extra: &[&str]| {
        let out = dir.join(out);
        let mut args = vec!["observe", &s(log), "--robot", "psm", "--out"]
            .into_iter()
            .map(String::from)
            .collect::<Vec<_>>();
        args.push(s(&out));
        args.extend(extra.iter().map(|x| x.to_string()));
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let (ok, stdout, err) = run(&args);
        assert!(ok, "{err}");
        assert!(stdout.contains("robot psm, 1 log(s)"), "{stdout}");
        out
    };
    let pa = observe(&a, "a.obs", &[]);
    let pb = observe(&b, "b.obs", &[]);
    // Block by block: the same factors to the last bit, so the same file.
    let pa_stream = observe(&a, "a_stream.obs", &["--stream"]);
    assert_eq!(
        std::fs::read(&pa).unwrap(),
        std::fs::read(&pa_stream).unwrap()
    );
    for method in ["wls", "irls", "sdp"] {
        let direct = dir.join(format!("direct_{method}.json"));
        let reduced = dir.join(format!("reduced_{method}.json"));
        let common = ["--method", method, "--test", &s(&c), "--test-window", "150"];
        let (ok, _, err) = run(&[
            &[
                "fit",
                &s(&a),
                &s(&b),
                "--robot",
                "psm",
                "--out",
                &s(&direct),
            ][..],
            &common[..],
        ]
        .concat());
        assert!(ok, "{err}");
        let (ok, stdout, err) = run(&[
            &["fit", "--states", &s(&pa), &s(&pb), "--out", &s(&reduced)][..],
            &common[..],
        ]
        .concat());
        assert!(ok, "{err}");
        assert!(stdout.contains("physically consistent"), "{stdout}");
        let doc = document(&reduced);
        assert_eq!(doc, document(&direct), "{method}");
        let inputs = doc["inputs"].as_array().unwrap();
        assert_eq!(inputs.len(), 3);
        assert_eq!(inputs[0]["path"].as_str().unwrap(), s(&a));
        assert_eq!(inputs[2]["role"].as_str().unwrap(), "test");
    }
    // A state processed with another cut-off: refused, naming it; nothing written.
    let other = observe(&b, "b_cut8.obs", &["--cutoff", "8"]);
    let before = files(&dir);
    // (`--from`: the flag's old spelling, still accepted.)
    let (ok, _, err) = run(&[
        "fit",
        "--from",
        &s(&pa),
        &s(&other),
        "--out",
        &s(&dir.join("never.json")),
    ]);
    assert!(!ok);
    assert!(
        err.contains("b_cut8.obs") && err.contains("processing settings"),
        "{err}"
    );
    assert_eq!(files(&dir), before);
    std::fs::remove_dir_all(&dir).unwrap();
}
