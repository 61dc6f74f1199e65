//! `dvrk-ident compare A.json B.json [--test LOG...]`: two results side by side (see
//! [`dvrk_ident::compare`]).

use std::fmt::Write as _;

use anyhow::Result;
use dvrk_ident::compare::{self, Comparison, Side, TestLog};
use dvrk_ident::log::LogFormat;

use super::args::McapArgs;
use super::{emit, load_result, LoadedResult};

#[derive(clap::Args)]
// A negative number is a value (`--rate -5`), refused by the checks with a message, not
// an unknown flag.
#[command(allow_negative_numbers = true)]
pub struct Args {
    /// First result file (`dvrk-ident fit --out`), A
    pub a: String,
    /// Second result file, B (of the same robot)
    pub b: String,
    /// Logs to evaluate both results on, each with its own model and processing settings
    /// (as `dvrk-ident validate` does)
    #[arg(long = "test", value_name = "LOG", num_args = 1..)]
    pub tests: Vec<String>,
    /// Log format (default: from the file's content); wpi is the 2019 headerless CSV
    #[arg(long, value_parser = super::named::<LogFormat>())]
    pub format: Option<LogFormat>,
    /// Sampling rate of logs without time stamps (Hz)
    #[arg(long)]
    pub rate: Option<f64>,
    #[command(flatten)]
    pub mcap: McapArgs,
    /// Metrics on the first N processed samples of each log only (N ≥ 1)
    #[arg(long, value_parser = super::at_least_one)]
    pub test_window: Option<usize>,
    /// Print the comparison document as JSON
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: Args) -> Result<()> {
    let LoadedResult {
        result: ra,
        model: ma,
        ..
    } = load_result(&args.a, None)?;
    let LoadedResult {
        result: rb,
        model: mb,
        ..
    } = load_result(&args.b, None)?;
    let a = Side {
        name: &args.a,
        result: &ra,
        model: &ma,
    };
    let b = Side {
        name: &args.b,
        result: &rb,
        model: &mb,
    };
    // Refuses results of different robots before any log is read.
    let mut doc = compare::compare(&a, &b, &[], args.test_window)?;
    let base = super::args::read_options(args.format, args.rate, &args.mcap);
    for path in &args.tests {
        // Each result reads the log as `validate` would; once when they read it alike.
        let (oa, ob) = (a.read_options(&base), b.read_options(&base));
        let la = super::args::read(&oa, path)?;
        let lb = if ob == oa {
            None
        } else {
            Some(super::args::read(&ob, path)?)
        };
        let log = TestLog {
            name: path,
            samples: [&la, lb.as_ref().unwrap_or(&la)],
        };
        doc.tests
            .push(compare::test_errors(&a, &b, &log, args.test_window)?);
    }
    if args.json {
        emit(&serde_json::to_string_pretty(&doc)?)
    } else {
        emit(&text(&doc))
    }
}

/// A JSON value in one cell: compact, strings without quotes.
fn cell(v: &serde_json::Value) -> String {
    match v {
        serde_json::Value::String(s) => s.clone(),
        other => other.to_string(),
    }
}

fn num(v: Option<f64>) -> String {
    v.map(|x| format!("{x:.4e}")).unwrap_or_else(|| "-".into())
}

/// The readable comparison: the settings that differ, the errors on each test log, the
/// base parameters with the largest differences first, the link masses.
pub fn text(doc: &Comparison) -> String {
    let mut t = String::new();
    for (tag, s) in [("A", &doc.a), ("B", &doc.b)] {
        let _ = writeln!(
            t,
            "{tag}: {} ({}, {}{}{}, {} rows, condition {:.4e}, sigma2 {:.4e})",
            s.name,
            s.robot,
            s.method,
            if s.converged { "" } else { ", NOT CONVERGED" },
            if s.physically_consistent {
                ", physically consistent"
            } else {
                ""
            },
            s.rows,
            s.condition_number,
            s.sigma2
        );
    }
    let _ = writeln!(t);
    if doc.differences.is_empty() {
        let _ = writeln!(t, "Settings: the same");
    } else {
        let _ = writeln!(t, "Settings that differ ({}):", doc.differences.len());
        let w = doc
            .differences
            .iter()
            .map(|d| d.path.len())
            .max()
            .unwrap_or(0);
        for d in &doc.differences {
            let _ = writeln!(t, "  {:<w$}  A {}  B {}", d.path, cell(&d.a), cell(&d.b));
        }
    }
    for test in &doc.tests {
        let _ = writeln!(t);
        let _ = writeln!(
            t,
            "{} (A {} samples, B {} samples)",
            test.log, test.a.samples, test.b.samples
        );
        let _ = writeln!(
            t,
            "{:<8} {:>10} {:>10} {:>10} {:>10}",
            "joint", "A rel", "A rms", "B rel", "B rms"
        );
        for (j, name) in test.a.joints.iter().enumerate() {
            let _ = writeln!(
                t,
                "{name:<8} {:>10.4} {:>10.4} {:>10.4} {:>10.4}",
                test.a.relative_error[j], test.a.rms[j], test.b.relative_error[j], test.b.rms[j]
            );
        }
    }
    let base = &doc.base_parameters;
    let _ = writeln!(t);
    match &base.reason {
        None => {
            let _ = writeln!(
                t,
                "Base parameters ({}; |A-B| in combined std, largest first):",
                base.parameters.len()
            );
        }
        Some(why) => {
            let _ = writeln!(t, "Base parameters: not comparable one by one: {why}");
        }
    }
    let mut rows: Vec<_> = base.parameters.iter().collect();
    // Largest differences first; those that do not compare last, in document order.
    rows.sort_by(|x, y| {
        let key = |r: &&compare::BaseRow| r.sigmas.unwrap_or(f64::NEG_INFINITY);
        key(y).total_cmp(&key(x))
    });
    let _ = writeln!(
        t,
        "{:<10} {:>11} {:>11} {:>11} {:>11} {:>8}  expression",
        "name", "A value", "A std", "B value", "B std", "sigmas"
    );
    for r in rows {
        let _ = writeln!(
            t,
            "{:<10} {:>11} {:>11} {:>11} {:>11} {:>8}  {}",
            r.name,
            num(r.a.map(|e| e.value)),
            num(r.a.map(|e| e.std)),
            num(r.b.map(|e| e.value)),
            num(r.b.map(|e| e.std)),
            r.sigmas
                .map(|s| format!("{s:.2}"))
                .unwrap_or_else(|| "-".into()),
            r.expression
        );
    }
    let _ = writeln!(t);
    let _ = writeln!(t, "Link masses (kg):");
    let w = doc
        .link_masses
        .iter()
        .map(|m| m.name.len())
        .max()
        .unwrap_or(0)
        .max(4);
    let _ = writeln!(t, "{:<w$} {:>11} {:>11}", "link", "A", "B");
    for m in &doc.link_masses {
        let _ = writeln!(t, "{:<w$} {:>11} {:>11}", m.name, num(m.a), num(m.b));
    }
    let _ = write!(
        t,
        "({} parameters side by side with --json)",
        doc.parameters.len()
    );
    t
}
