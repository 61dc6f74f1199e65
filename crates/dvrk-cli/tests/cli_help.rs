//! The help that guides: options grouped under headings, every default shown (and the
//! library's defaults shown as the library has them), one name per idea with the old
//! spellings still accepted, and the generated shell completions and manual pages.

mod support;

use std::path::Path;

use dvrk_ident::excite::optimize::ExciteOptions;
use dvrk_ident::signal::Cutoff;
use dvrk_ident::{FitSettings, Prior, PriorMetric};
use support::{example, files, run, run_ok, s, temp_dir};

/// The headings of a help text with the long flags listed under each, in order.
fn sections(help: &str) -> Vec<(String, Vec<String>)> {
    let mut out: Vec<(String, Vec<String>)> = Vec::new();
    for line in help.lines() {
        if !line.starts_with(' ') && line.ends_with(':') {
            out.push((line.trim_end_matches(':').to_string(), Vec::new()));
        } else if let (Some(flag), Some((_, flags))) = (long_flag(line), out.last_mut()) {
            flags.push(flag);
        }
    }
    out
}

/// The long flag an option line of a help text describes (`      --trim <N>  ...`).
fn long_flag(line: &str) -> Option<String> {
    let t = line.trim_start();
    let t = t
        .strip_prefix("-h, ")
        .or(t.strip_prefix("-V, "))
        .unwrap_or(t);
    let flag = t.strip_prefix("--")?;
    let end = flag.find([' ', '<']).unwrap_or(flag.len());
    Some(format!("--{}", &flag[..end]))
}

/// The entry of `flag` in a help text: its line, and the lines of its help when clap
/// puts them below it (the layout of a heading with long flags).
#[track_caller]
fn line_of(help: &str, flag: &str) -> String {
    let lines: Vec<&str> = help.lines().collect();
    let at = lines
        .iter()
        .position(|l| long_flag(l).as_deref() == Some(flag))
        .unwrap_or_else(|| panic!("no {flag} in\n{help}"));
    let mut entry = lines[at].to_string();
    for l in &lines[at + 1..] {
        if l.trim().is_empty() || l.trim_start().starts_with('-') || !l.starts_with(' ') {
            break;
        }
        entry.push(' ');
        entry.push_str(l.trim());
    }
    entry
}

/// The `[default: ...]` text of `flag`'s help line.
#[track_caller]
fn default_of(help: &str, flag: &str) -> String {
    let line = line_of(help, flag);
    let start = line
        .find("[default: ")
        .unwrap_or_else(|| panic!("{flag} shows no default: {line}"))
        + "[default: ".len();
    let end = start + line[start..].find(']').unwrap();
    line[start..end].to_string()
}

fn help(command: &str) -> String {
    run_ok(&[command, "--help"])
}

#[test]
fn fit_help_groups_its_options_under_headings() {
    let h = help("fit");
    let fit_sections = sections(&h);
    let names: Vec<&str> = fit_sections.iter().map(|(n, _)| n.as_str()).collect();
    for heading in ["Input", "Model", "Processing", "Estimator", "Output"] {
        assert!(names.contains(&heading), "{heading} missing: {names:?}");
    }
    let under = |heading: &str| -> &Vec<String> {
        &fit_sections.iter().find(|(n, _)| n == heading).unwrap().1
    };
    for (heading, flag) in [
        ("Input", "--states"),
        ("Input", "--topic"),
        ("Input", "--format"),
        ("Model", "--robot"),
        ("Model", "--bounds"),
        ("Processing", "--cutoff"),
        ("Processing", "--trim"),
        ("Processing", "--resample"),
        ("Estimator", "--method"),
        ("Estimator", "--irls-iterations"),
        ("Output", "--out"),
        ("Output", "--json"),
    ] {
        assert!(
            under(heading).contains(&flag.to_string()),
            "{flag} not under {heading}: {fit_sections:?}"
        );
    }
    // The long list of the flat help is gone: only --quiet and --help are left
    // ungrouped.
    assert_eq!(
        under("Options"),
        &["--quiet".to_string(), "--help".to_string()]
    );
    // Every subcommand that has options groups them the same way.
    for command in [
        "observe",
        "validate",
        "residual",
        "payload",
        "report",
        "convert",
        "simulate",
        "export",
        "excite",
        "model",
        "cable-fit",
        "man",
    ] {
        let h = help(command);
        let ungrouped = &sections(&h)
            .into_iter()
            .find(|(n, _)| n == "Options")
            .unwrap()
            .1;
        assert_eq!(
            ungrouped,
            &["--quiet".to_string(), "--help".to_string()],
            "{command}: {h}"
        );
    }
}

#[test]
fn fit_help_shows_the_library_defaults() {
    let h = help("fit");
    let fit = FitSettings::default();
    let Cutoff::All(cutoff) = fit.processing.filter.as_ref().unwrap().cutoff_hz else {
        panic!("the default cut-off is one for all joints");
    };
    assert_eq!(default_of(&h, "--cutoff"), cutoff.to_string());
    assert_eq!(default_of(&h, "--trim"), fit.processing.trim.to_string());
    assert_eq!(
        default_of(&h, "--decimate"),
        fit.processing.decimate.to_string()
    );
    assert_eq!(
        default_of(&h, "--irls-iterations"),
        fit.irls_iterations.to_string()
    );
    assert_eq!(
        default_of(&h, "--sdp-regularization").parse::<f64>(),
        Ok(fit.sdp_regularization)
    );
    assert_eq!(
        default_of(&h, "--prior-weight").parse::<f64>(),
        Ok(Prior::DEFAULT_WEIGHT)
    );
    assert_eq!(default_of(&h, "--method"), fit.method.name());
    assert_eq!(
        default_of(&h, "--prior-metric"),
        PriorMetric::default().name()
    );
    // The defaults that are computed say so.
    for flag in [
        "--format",
        "--topic",
        "--time",
        "--bounds",
        "--delay",
        "--test-window",
        "--stribeck",
        "--prior",
        "--min-speed",
        "--resample",
    ] {
        assert!(!default_of(&h, flag).is_empty(), "{flag}");
    }
    // --topic serves every recording, not only MCAP.
    let topic = line_of(&h, "--topic");
    for kind in ["MCAP", "rosbag2", ".db3", ".bag"] {
        assert!(topic.contains(kind), "{topic}");
    }
}

#[test]
fn validate_and_report_default_to_the_results_processing() {
    for command in ["validate", "report"] {
        let h = help(command);
        for flag in [
            "--cutoff",
            "--trim",
            "--decimate",
            "--min-speed",
            "--resample",
        ] {
            assert_eq!(default_of(&h, flag), "the result's", "{command} {flag}");
        }
        assert_eq!(default_of(&h, "--time"), "header", "{command}");
    }
    // observe processes as fit does: the library's defaults.
    let h = help("observe");
    assert_eq!(
        default_of(&h, "--trim"),
        FitSettings::default().processing.trim.to_string()
    );
}

#[test]
fn excite_help_shows_the_library_defaults() {
    let h = help("excite");
    let o = ExciteOptions::default();
    assert_eq!(default_of(&h, "--order"), o.order.to_string());
    assert_eq!(default_of(&h, "--f0"), o.base_frequency_hz.to_string());
    assert_eq!(default_of(&h, "--starts"), o.starts.to_string());
    assert_eq!(default_of(&h, "--refine"), o.refine.to_string());
    assert_eq!(
        default_of(&h, "--iterations"),
        o.iterations_per_stage.to_string()
    );
    assert_eq!(
        default_of(&h, "--refine-iterations"),
        o.refine_iterations_per_stage.to_string()
    );
    assert_eq!(
        default_of(&h, "--samples-per-harmonic"),
        o.samples_per_harmonic.to_string()
    );
    assert_eq!(default_of(&h, "--check-rate"), o.check_rate_hz.to_string());
    use dvrk_ident::Named;
    assert_eq!(default_of(&h, "--criterion"), o.criterion.name());
}

#[test]
fn output_formats_offered_are_the_writable_ones() {
    for command in ["convert", "simulate"] {
        let line = line_of(&help(command), "--out-format");
        assert!(line.contains("[possible values: wpi, csv, mcap]"), "{line}");
        for read_only in ["sqlite3", "rosbag2", "ros1"] {
            assert!(!line.contains(read_only), "{command}: {line}");
        }
    }
    // The input's format is any readable one.
    let line = line_of(&help("convert"), "--in-format");
    assert!(line.contains("sqlite3") && line.contains("ros1"), "{line}");
}

#[test]
fn renamed_flags_keep_their_old_spelling_hidden() {
    // The old spellings are not offered...
    for (command, old) in [
        ("fit", "--from"),
        ("convert", "--from"),
        ("convert", "--format"),
        ("export", "--from"),
        ("simulate", "--trajectory"),
        ("simulate", "--format"),
        ("simulate", "--topic"),
    ] {
        let h = help(command);
        assert!(
            !h.lines().any(|l| long_flag(l).as_deref() == Some(old)),
            "{command} still lists {old}"
        );
    }
    // ... but still work: a simulation and a conversion with only old spellings give
    // what the new ones give.
    let dir = temp_dir("help-old-flags");
    let traj = example("psm_trajectory.json");
    let params = example("psm_params.json");
    let simulate = |out: &Path, names: [&str; 3]| {
        run_ok(&[
            "simulate",
            "psm",
            "--params",
            &params,
            names[0],
            &traj,
            names[1],
            "mcap",
            names[2],
            "/OLD/measured_js",
            "--out",
            &s(out),
        ]);
    };
    let (old, new) = (dir.join("old.log"), dir.join("new.log"));
    simulate(&old, ["--trajectory", "--format", "--topic"]);
    simulate(&new, ["--excitation", "--out-format", "--out-topic"]);
    assert_eq!(std::fs::read(&old).unwrap(), std::fs::read(&new).unwrap());
    let convert = |out: &Path, names: [&str; 2]| {
        run_ok(&[
            "convert",
            &s(&old),
            &s(out),
            names[0],
            "mcap",
            names[1],
            "wpi",
            "--topic",
            "/OLD/measured_js",
            "--robot",
            "psm",
        ]);
    };
    let (old_wpi, new_wpi) = (dir.join("old.csv"), dir.join("new.csv"));
    convert(&old_wpi, ["--from", "--format"]);
    convert(&new_wpi, ["--in-format", "--out-format"]);
    let text = std::fs::read_to_string(&new_wpi).unwrap();
    assert!(!text.is_empty() && !text.starts_with("time"), "not wpi");
    assert_eq!(text, std::fs::read_to_string(&old_wpi).unwrap());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn completions_list_the_subcommands_and_flags() {
    let bash = run_ok(&["completions", "bash"]);
    for word in [
        "fit",
        "observe",
        "convert",
        "completions",
        "man",
        "--states",
        "--cutoff",
        "--out-topic",
        "--in-format",
    ] {
        assert!(bash.contains(word), "bash completion lacks {word}");
    }
    // bash itself accepts the script, when there is a bash to ask.
    match std::process::Command::new("bash")
        .args(["-n", "-c", &bash])
        .output()
    {
        Ok(out) => assert!(
            out.status.success(),
            "bash -n: {}",
            String::from_utf8_lossy(&out.stderr)
        ),
        Err(e) => dvrk_test_support::skip(format!("bash -n not run: {e}")),
    }
    for shell in ["zsh", "fish", "powershell", "elvish"] {
        let script = run_ok(&["completions", shell]);
        assert!(
            script.contains("dvrk-ident") && script.contains("--states"),
            "{shell}"
        );
    }
    let (ok, _, err) = run(&["completions", "tcsh"]);
    assert!(!ok && err.contains("possible values"), "{err}");
}

#[test]
fn man_prints_a_page_and_writes_them_all() {
    let main = run_ok(&["man"]);
    assert!(main.contains(".TH dvrk-ident 1"), "{main}");
    for sub in [
        "fit",
        "observe",
        "validate",
        "convert",
        "export",
        "completions",
    ] {
        assert!(main.contains(&format!("dvrk\\-ident\\-{sub}(1)")), "{sub}");
    }
    let fit = run_ok(&["man", "fit"]);
    assert!(fit.contains(".TH dvrk-ident-fit 1"), "{fit}");
    assert!(fit.contains("\\-\\-states"), "{fit}");
    let (ok, out, err) = run(&["man", "nosuch"]);
    assert!(!ok && out.is_empty(), "{out}");
    assert!(err.contains("man nosuch: no such subcommand"), "{err}");

    // Every page into a new folder, listed on stdout.
    let dir = temp_dir("help-man");
    let pages = dir.join("man1");
    let listed = run_ok(&["man", "--out", &s(&pages)]);
    let written = files(&pages);
    assert!(written.contains(&"dvrk-ident.1".to_string()), "{written:?}");
    assert!(written.contains(&"dvrk-ident-fit.1".to_string()));
    assert!(written.contains(&"dvrk-ident-man.1".to_string()));
    assert_eq!(listed.lines().count(), written.len(), "{listed}");
    assert_eq!(
        std::fs::read_to_string(pages.join("dvrk-ident-fit.1")).unwrap(),
        fit
    );
    // Into a folder whose parent is missing: an error, nothing written.
    let (ok, _, err) = run(&["man", "--out", &s(&dir.join("no/man1"))]);
    assert!(!ok && err.contains("--out"), "{err}");
    assert_eq!(files(&dir), ["man1"]);
    std::fs::remove_dir_all(&dir).unwrap();
}
