//! The command line and the Python call that repeat a fit: a result's settings, inputs
//! and robot (and the options its logs were read with, which the result does not record)
//! rendered as `dvrk-ident fit ...` flags and as `di.fit(...)` keyword arguments.
//!
//! Both renderings read the same [`FitSettings`], and every setting is either rendered or
//! named in [`Rendered::unrendered`]: a setting the command line has no flag for (the
//! filter's order, form or convention, the differentiation stencils, ...) is listed, never
//! invented. The command-line tests parse [`FitCall::cli_command`]'s text with the real
//! binary and compare the settings of the document it writes with the original ones.
//!
//! ```
//! use dvrk_ident::log::ReadOptions;
//! use dvrk_ident::reproduce::FitCall;
//! use dvrk_ident::{FitSettings, InputInfo, Method};
//! let mut settings = FitSettings { method: Method::Ols, ..FitSettings::default() };
//! settings.stribeck_velocity = Some(0.3);
//! let train = InputInfo { role: "train".into(), path: "one.csv".into(), sha256: String::new(),
//!     bytes: 0, source: String::new(), metrics: None, offset: None };
//! let read = ReadOptions { rate_hz: Some(200.0), ..ReadOptions::default() };
//! let inputs = [train];
//! let call = FitCall { robot: "psm", settings: &settings, inputs: &inputs, read: Some(&read) };
//! let r = call.cli_command();
//! assert_eq!(r.text, "dvrk-ident fit one.csv --robot psm --rate 200 --method ols --stribeck 0.3");
//! assert!(r.unrendered.is_empty());
//! ```

use std::fmt::Write as _;

use crate::fit::delay::DEFAULT_MAX_DELAY_S;
use crate::log::ReadOptions;
use crate::names::Named;
use crate::result::{loadable_robot, InputInfo};
use crate::settings::{FitSettings, Prior, PriorMetric};
use crate::signal::{Cutoff, LowPass, Processing};

/// A rendered command line or Python call, and what it cannot express.
#[derive(Clone, Debug, PartialEq)]
pub struct Rendered {
    /// The text to copy: a shell command line (words quoted for a POSIX shell) or Python
    /// statements.
    pub text: String,
    /// For the command line, its words unquoted (`dvrk-ident` first); empty for Python.
    pub args: Vec<String>,
    /// Settings or inputs the text does not reproduce, each with the reason (empty: the
    /// text repeats the fit's settings exactly).
    pub unrendered: Vec<String>,
}

/// A number as a flag or Python value: Rust's shortest text that reads back to the same
/// `f64`, in exponent form when that is shorter.
fn num(v: f64) -> String {
    let plain = format!("{v}");
    let exp = format!("{v:e}");
    if exp.len() < plain.len() {
        exp
    } else {
        plain
    }
}

/// `word` quoted for a POSIX shell when it needs it.
pub(crate) fn shell_quote(word: &str) -> String {
    let safe = !word.is_empty()
        && word
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "_-./:=,@%+".contains(c));
    if safe {
        word.to_string()
    } else {
        format!("'{}'", word.replace('\'', r"'\''"))
    }
}

/// A Python string literal.
fn py_str(text: &str) -> String {
    serde_json::to_string(text).unwrap_or_else(|_| format!("{text:?}"))
}

/// A JSON value as a Python literal (`true` → `True`, `null` → `None`), dictionary keys
/// in sorted order.
fn py_value(v: &serde_json::Value) -> String {
    use serde_json::Value;
    match v {
        Value::Null => "None".into(),
        Value::Bool(b) => if *b { "True" } else { "False" }.into(),
        Value::Number(n) => n.to_string(),
        Value::String(s) => py_str(s),
        Value::Array(a) => format!(
            "[{}]",
            a.iter().map(py_value).collect::<Vec<_>>().join(", ")
        ),
        Value::Object(o) => {
            // Keys sorted, whatever order the map keeps (serde_json's depends on its
            // features, which the workspace's crates unify differently per build).
            let mut entries: Vec<(&String, &serde_json::Value)> = o.iter().collect();
            entries.sort_by(|a, b| a.0.cmp(b.0));
            format!(
                "{{{}}}",
                entries
                    .iter()
                    .map(|(k, v)| format!("{}: {}", py_str(k), py_value(v)))
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        }
    }
}

/// One option of a fit, in the two front ends' spellings.
#[derive(Clone, Debug)]
enum Value {
    /// A switch (`--filter-torque`, `filter_torque=True`).
    Switch,
    /// A switch that turns a default off (`--no-ellipsoids`, `ellipsoids=False`).
    SwitchOff,
    /// A number.
    Num(f64),
    /// An integer.
    Int(usize),
    /// A name (`--method ols`, `method="ols"`).
    Name(String),
    /// A list of numbers (`--cutoff 5,5,3`, `cutoff=[5, 5, 3]`).
    List(Vec<f64>),
}

impl Value {
    fn flag(&self) -> Option<String> {
        match self {
            Value::Switch | Value::SwitchOff => None,
            Value::Num(v) => Some(num(*v)),
            Value::Int(v) => Some(v.to_string()),
            Value::Name(n) => Some(n.clone()),
            Value::List(v) => Some(v.iter().map(|x| num(*x)).collect::<Vec<_>>().join(",")),
        }
    }

    fn python(&self) -> String {
        match self {
            Value::Switch => "True".into(),
            Value::SwitchOff => "False".into(),
            Value::Num(v) => num(*v),
            Value::Int(v) => v.to_string(),
            Value::Name(n) => py_str(n),
            Value::List(v) => format!(
                "[{}]",
                v.iter().map(|x| num(*x)).collect::<Vec<_>>().join(", ")
            ),
        }
    }
}

/// What the settings say, option by option (name in snake case as Python spells it; the
/// flag is `--` and the name with dashes), and what has no option.
struct Options {
    /// `(name, value)` in the order the command line lists them.
    given: Vec<(&'static str, Value)>,
    /// The settings without an option, as a partial settings document (the layout of a
    /// result's `settings`; Python's `settings=` takes it).
    without_option: serde_json::Map<String, serde_json::Value>,
    /// The same settings named for the reader, with their values.
    without_flag: Vec<String>,
}

/// The options of `settings`: every setting that differs from its default, the method
/// always.
fn options(settings: &FitSettings) -> Options {
    let d = FitSettings::default();
    let p = &settings.processing;
    let dp = Processing::default();
    let mut given: Vec<(&'static str, Value)> =
        vec![("method", Value::Name(settings.method.name().into()))];
    let mut without_option = serde_json::Map::new();
    let mut processing_extra = serde_json::Map::new();
    let mut without_flag = Vec::new();
    let mut note = |what: String, key: &str, value: serde_json::Value, processing: bool| {
        without_flag.push(what);
        if processing {
            processing_extra.insert(key.into(), value);
        } else {
            without_option.insert(key.into(), value);
        }
    };

    // The low-pass filter: `--cutoff` and `--filter-order` set the cut-off and the order
    // of a filter of the default form and convention.
    match &p.filter {
        None => given.push(("cutoff", Value::Name("none".into()))),
        Some(lp) => {
            let default = LowPass::default();
            let default_shape = LowPass {
                cutoff_hz: lp.cutoff_hz.clone(),
                order: lp.order,
                ..LowPass::default()
            };
            if *lp == default_shape {
                if lp.cutoff_hz != default.cutoff_hz {
                    given.push((
                        "cutoff",
                        match &lp.cutoff_hz {
                            Cutoff::All(v) => Value::Num(*v),
                            Cutoff::PerJoint(v) => Value::List(v.clone()),
                        },
                    ));
                }
                if lp.order != default.order {
                    given.push(("filter_order", Value::Int(lp.order)));
                }
            } else {
                let json = serde_json::to_value(lp).unwrap_or_default();
                note(
                    format!(
                        "the low-pass filter {} (only its cut-off and order have flags, \
                         --cutoff and --filter-order, for a filter of second-order sections, \
                         standard convention, default padding)",
                        serde_json::to_string(lp).unwrap_or_default()
                    ),
                    "filter",
                    json,
                    true,
                );
            }
        }
    }
    if p.filter_torque {
        given.push(("filter_torque", Value::Switch));
    }
    if p.trim != dp.trim {
        given.push(("trim", Value::Int(p.trim)));
    }
    if p.decimate != dp.decimate {
        given.push(("decimate", Value::Int(p.decimate)));
    }
    if let Some(v) = p.min_speed {
        given.push(("min_speed", Value::Num(v)));
    }
    if let Some(v) = p.resample_hz {
        given.push(("resample", Value::Num(v)));
    }
    let processing_fields: [(&str, bool); 4] = [
        (
            "velocity_stencil",
            p.velocity_stencil != dp.velocity_stencil,
        ),
        (
            "acceleration_stencil",
            p.acceleration_stencil != dp.acceleration_stencil,
        ),
        (
            "acceleration_from",
            p.acceleration_from != dp.acceleration_from,
        ),
        (
            "uniform_tolerance",
            p.uniform_tolerance != dp.uniform_tolerance,
        ),
    ];
    let processing_json = serde_json::to_value(p).unwrap_or_default();
    for (key, differs) in processing_fields {
        if differs {
            let value = processing_json.get(key).cloned().unwrap_or_default();
            note(
                format!("processing.{key} = {value} (no flag)"),
                key,
                value,
                true,
            );
        }
    }
    match settings.delay_search_s {
        Some(max) if max == DEFAULT_MAX_DELAY_S => {
            given.push(("delay", Value::Name("auto".into())));
        }
        Some(max) => note(
            format!(
                "the delay search over [0, {max}] s (--delay auto searches [0, \
                 {DEFAULT_MAX_DELAY_S}] s)"
            ),
            "delay_search_s",
            serde_json::json!(max),
            false,
        ),
        None => {
            let delays = &p.delay_s;
            if !delays.is_empty() {
                if delays.iter().all(|&v| v == delays[0]) {
                    given.push(("delay", Value::Num(delays[0])));
                } else {
                    given.push(("delay", Value::List(delays.clone())));
                }
            }
        }
    }
    if let Some(w) = settings.test_window {
        given.push(("test_window", Value::Int(w)));
    }
    if settings.irls_iterations != d.irls_iterations {
        given.push(("irls_iterations", Value::Int(settings.irls_iterations)));
    }
    if settings.sdp_regularization != d.sdp_regularization {
        given.push((
            "sdp_regularization",
            Value::Num(settings.sdp_regularization),
        ));
    }
    match &settings.select {
        // The selection repeats itself and chooses the same friction terms.
        Some(candidates) => given.push(("select", Value::Name(candidates.to_string()))),
        None => {
            if let Some(v) = settings.stribeck_velocity {
                given.push(("stribeck", Value::Num(v)));
            }
            if let Some(v) = settings.dahl_sigma {
                given.push(("dahl", Value::Num(v)));
            }
        }
    }
    if settings.log_offsets {
        given.push(("log_offsets", Value::Switch));
    }
    if let Some(k) = settings.position_torque_order {
        given.push(("position_torque", Value::Int(k)));
        if !settings.position_torque_frames.is_empty() {
            let frames = settings.position_torque_frames.join(",");
            given.push(("position_torque_frames", Value::Name(frames)));
        }
    }
    if settings.load_friction {
        given.push(("load_friction", Value::Switch));
    }
    if let Some(b) = settings.bounds {
        given.push(("bounds", Value::Name(b.name().into())));
    }
    if !settings.ellipsoids {
        given.push(("ellipsoids", Value::SwitchOff));
    }
    if let Some(prior) = &settings.prior {
        prior_options(prior, &mut given, &mut without_flag);
    }
    if !settings.joints.is_model() {
        given.push(("joints", Value::Name(settings.joints.name().into())));
    }
    if !processing_extra.is_empty() {
        without_option.insert(
            "processing".into(),
            serde_json::Value::Object(processing_extra),
        );
    }
    Options {
        given,
        without_option,
        without_flag,
    }
}

/// The prior's options: `nominal` or the result file it was read from, its weight and
/// metric when not the defaults.
fn prior_options(
    prior: &Prior,
    given: &mut Vec<(&'static str, Value)>,
    without_flag: &mut Vec<String>,
) {
    if prior.source.starts_with("a result in memory") {
        without_flag.push(format!(
            "the prior, {} (write that result to a file and give it as --prior FILE)",
            prior.source
        ));
    } else {
        given.push(("prior", Value::Name(prior.source.clone())));
    }
    if prior.weight != Prior::DEFAULT_WEIGHT {
        given.push(("prior_weight", Value::Num(prior.weight)));
    }
    if prior.metric != PriorMetric::default() {
        given.push(("prior_metric", Value::Name(prior.metric.name().into())));
    }
}

/// The reading options as `(name, value)`; Python's `read_log` keyword for the time source
/// is `time_source`, the flag `--time`.
fn read_options(read: &ReadOptions) -> Vec<(&'static str, Value)> {
    let mut out = Vec::new();
    if let Some(f) = read.format {
        out.push(("format", Value::Name(f.name().into())));
    }
    if let Some(r) = read.rate_hz {
        out.push(("rate", Value::Num(r)));
    }
    for t in &read.topics {
        out.push(("topic", Value::Name(t.clone())));
    }
    if let Some(t) = read.time_source {
        out.push(("time", Value::Name(t.name().into())));
    }
    if let Some(m) = read.max_unpacked_mib {
        out.push(("max_unpacked_mib", Value::Int(m as usize)));
    }
    out
}

fn flag(name: &str) -> String {
    format!("--{}", name.replace('_', "-"))
}

/// What cannot be repeated of the inputs: logs without a file (built in Python).
fn input_notes(inputs: &[InputInfo], read: Option<&ReadOptions>, out: &mut Vec<String>) {
    for i in inputs
        .iter()
        .filter(|i| i.role != "prior" && i.path.is_empty())
    {
        out.push(format!(
            "a {} log without a file (samples built in Python, SHA-256 {}): save it to a \
             file first",
            i.role, i.sha256
        ));
    }
    if read.is_none() {
        out.push(
            "how the logs were read (--format, --rate, --topic, --time) is not recorded in \
             the result: add the flags the fit was run with"
                .into(),
        );
    }
}

/// The logs of `role` (`train`, `test`) as their paths, a log without a file as a
/// marked name.
fn paths<'a>(inputs: &'a [InputInfo], role: &'a str) -> impl Iterator<Item = String> + 'a {
    inputs.iter().filter(move |i| i.role == role).map(|i| {
        if i.path.is_empty() {
            format!("<{} samples without a file>", i.role)
        } else {
            i.path.clone()
        }
    })
}

/// A fit to repeat: of `robot` (a built-in name, a description path, or a result's
/// `robot_source`) with `settings` on `inputs` (the result's: training logs, test logs, a
/// prior's file), its logs read with `read` (`None`: not known; the renderings then say
/// so in [`Rendered::unrendered`]).
#[derive(Clone, Copy, Debug)]
pub struct FitCall<'a> {
    /// The robot as the fit loaded it.
    pub robot: &'a str,
    /// The fit's settings.
    pub settings: &'a FitSettings,
    /// The fit's inputs, in the result's order.
    pub inputs: &'a [InputInfo],
    /// How the logs were read, when known.
    pub read: Option<&'a ReadOptions>,
}

impl<'a> FitCall<'a> {
    /// The fit that made `result`, its logs read with `read`.
    pub fn of_result(result: &'a crate::FitResult, read: Option<&'a ReadOptions>) -> Self {
        FitCall {
            robot: &result.robot_source,
            settings: &result.settings,
            inputs: &result.inputs,
            read,
        }
    }
}

impl FitCall<'_> {
    /// The `dvrk-ident fit` command line.
    ///
    /// Every setting that differs from its default is a flag (the method always); a
    /// setting without a flag is listed in [`Rendered::unrendered`], not rendered.
    pub fn cli_command(&self) -> Rendered {
        let (robot, settings, inputs, read) = (self.robot, self.settings, self.inputs, self.read);
        let options = options(settings);
        let mut args: Vec<String> = vec!["dvrk-ident".into(), "fit".into()];
        args.extend(paths(inputs, "train"));
        args.push("--robot".into());
        args.push(loadable_robot(robot).into());
        let push = |args: &mut Vec<String>, name: &str, v: &Value| {
            args.push(match v {
                Value::SwitchOff => flag(&format!("no_{name}")),
                _ => flag(name),
            });
            if let Some(text) = v.flag() {
                args.push(text);
            }
        };
        if let Some(read) = read {
            for (name, v) in read_options(read) {
                push(&mut args, name, &v);
            }
        }
        let tests: Vec<String> = paths(inputs, "test").collect();
        for (name, v) in &options.given {
            push(&mut args, name, v);
            if *name == "method" && !tests.is_empty() {
                args.push("--test".into());
                args.extend(tests.iter().cloned());
            }
        }
        let mut unrendered = options.without_flag;
        input_notes(inputs, read, &mut unrendered);
        Rendered {
            text: args
                .iter()
                .map(|a| shell_quote(a))
                .collect::<Vec<_>>()
                .join(" "),
            args,
            unrendered,
        }
    }

    /// The Python statements that repeat the fit of [`FitCall::cli_command`]: `di.read_log` of each
    /// log with the reading options, then `di.fit(robot, train, ...)` with the settings as
    /// keyword arguments, and the settings without a keyword in `settings={...}` (the
    /// result document's `settings` layout), so everything but logs without a file and a
    /// prior held in memory is repeated.
    /// The Python statements: `di.read_log` of each log with the reading options, then
    /// `di.fit(robot, train, ...)` with the settings as keyword arguments, and the
    /// settings without a keyword in `settings={...}` (the result document's `settings`
    /// layout), so everything but logs without a file and a prior held in memory is
    /// repeated.
    pub fn python_call(&self) -> Rendered {
        let (robot, settings, inputs, read) = (self.robot, self.settings, self.inputs, self.read);
        let options = options(settings);
        let mut o = String::new();
        let _ = writeln!(o, "import dvrk_ident as di");
        let _ = writeln!(
            o,
            "robot = di.Model.load({})",
            py_str(loadable_robot(robot))
        );
        let mut read_kw = String::new();
        if let Some(read) = read {
            let mut topics = Vec::new();
            for (name, v) in read_options(read) {
                match name {
                    "topic" => topics.push(v.python()),
                    "time" => {
                        let _ = write!(read_kw, ", time_source={}", v.python());
                    }
                    _ => {
                        let _ = write!(read_kw, ", {name}={}", v.python());
                    }
                }
            }
            match topics.len() {
                0 => {}
                1 => {
                    let _ = write!(read_kw, ", topic={}", topics[0]);
                }
                _ => {
                    let _ = write!(read_kw, ", topic=[{}]", topics.join(", "));
                }
            }
        }
        if let Some(r) = settings.processing.resample_hz {
            // The command line reads its files at the processing rate too.
            let _ = write!(read_kw, ", resample={}", num(r));
        }
        let list = |role: &str| -> String {
            let items: Vec<String> = paths(inputs, role)
                .map(|p| format!("di.read_log({}, robot{read_kw})", py_str(&p)))
                .collect();
            format!("[{}]", items.join(", "))
        };
        let _ = writeln!(o, "train = {}", list("train"));
        let has_test = inputs.iter().any(|i| i.role == "test");
        if has_test {
            let _ = writeln!(o, "test = {}", list("test"));
        }
        let mut kw: Vec<String> = Vec::new();
        for (name, v) in &options.given {
            kw.push(format!("{name}={}", v.python()));
            if *name == "method" && has_test {
                kw.push("test=test".into());
            }
        }
        if !options.without_option.is_empty() {
            kw.push(format!(
                "settings={}",
                py_value(&serde_json::Value::Object(options.without_option.clone()))
            ));
        }
        let _ = writeln!(o, "result = di.fit(robot, train, {})", kw.join(", "));
        let mut unrendered: Vec<String> = options
            .without_flag
            .into_iter()
            .filter(|w| w.starts_with("the prior, a result in memory"))
            .collect();
        input_notes(inputs, read, &mut unrendered);
        Rendered {
            text: o,
            args: Vec::new(),
            unrendered,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::signal::Stencil;

    fn call<'a>(
        robot: &'a str,
        settings: &'a FitSettings,
        inputs: &'a [InputInfo],
        read: Option<&'a ReadOptions>,
    ) -> FitCall<'a> {
        FitCall {
            robot,
            settings,
            inputs,
            read,
        }
    }

    fn input(role: &str, path: &str) -> InputInfo {
        InputInfo {
            role: role.into(),
            path: path.into(),
            sha256: "ab".into(),
            bytes: 1,
            source: String::new(),
            metrics: None,
            offset: None,
        }
    }

    #[test]
    fn numbers_read_back_exactly() {
        for v in [16.965, 1e-12, 0.3, 200.0, 0.0010677878481615147, 5e7, -2.5] {
            assert_eq!(num(v).parse::<f64>().unwrap(), v, "{}", num(v));
        }
        assert_eq!(num(1e-12), "1e-12");
        assert_eq!(num(200.0), "200");
    }

    #[test]
    fn quoting_keeps_plain_words_and_quotes_the_rest() {
        assert_eq!(shell_quote("/a/b-c_d.csv"), "/a/b-c_d.csv");
        assert_eq!(shell_quote("my log.csv"), "'my log.csv'");
        assert_eq!(shell_quote("it's"), r"'it'\''s'");
        assert_eq!(shell_quote(""), "''");
    }

    #[test]
    fn settings_without_a_flag_are_listed_and_go_to_python_settings() {
        let mut s = FitSettings::default();
        s.processing.filter = Some(LowPass::wpi(5.4));
        s.processing.velocity_stencil = Stencil::ThreePoint;
        s.delay_search_s = Some(0.05);
        let inputs = [input("train", "one.csv"), input("test", "two.csv")];
        let cli = call("builtin:psm", &s, &inputs, Some(&ReadOptions::default())).cli_command();
        assert_eq!(
            cli.text,
            "dvrk-ident fit one.csv --robot psm --method sdp --test two.csv"
        );
        assert_eq!(cli.unrendered.len(), 3, "{:?}", cli.unrendered);
        assert!(cli.unrendered[0].contains("\"convention\":\"wpi\""));
        assert!(cli.unrendered[1].contains("velocity_stencil"));
        assert!(cli.unrendered[2].contains("[0, 0.05] s"));
        let py = call("builtin:psm", &s, &inputs, Some(&ReadOptions::default())).python_call();
        assert!(py.unrendered.is_empty(), "{:?}", py.unrendered);
        assert!(
            py.text.contains(
                "result = di.fit(robot, train, method=\"sdp\", test=test, settings={\"delay_search_s\": 0.05, \
                 \"processing\": {\"filter\": {\"convention\": \"wpi\", \"cutoff_hz\": 5.4, \"form\": \"ba\", \
                 \"order\": 6, \"padlen\": 20}, \"velocity_stencil\": \"three_point\"}})"
            ),
            "{}",
            py.text
        );
    }

    #[test]
    fn every_flag_of_a_full_fit_and_its_python_keywords() {
        let mut s = FitSettings::default();
        s.processing
            .set_cutoff(Some(Cutoff::PerJoint(vec![5.0, 3.5])));
        s.processing.filter_torque = true;
        if let Some(f) = s.processing.filter.as_mut() {
            f.order = 4;
        }
        s.processing.trim = 150;
        s.processing.decimate = 2;
        s.processing.min_speed = Some(0.01);
        s.processing.delay_s = vec![0.01, 0.02];
        s.test_window = Some(300);
        s.stribeck_velocity = Some(0.3);
        s.bounds = Some(crate::BoundsSet::Wang2019);
        s.ellipsoids = false;
        s.sdp_regularization = 1e-9;
        let read = ReadOptions {
            format: Some(crate::log::LogFormat::Wpi),
            rate_hz: Some(200.0),
            ..ReadOptions::default()
        };
        let inputs = [input("train", "my one.csv"), input("test", "two.csv")];
        let cli = call("psm", &s, &inputs, Some(&read)).cli_command();
        assert_eq!(
            cli.text,
            "dvrk-ident fit 'my one.csv' --robot psm --format wpi --rate 200 --method sdp \
             --test two.csv --cutoff 5,3.5 --filter-order 4 --filter-torque --trim 150 --decimate 2 \
             --min-speed 0.01 --delay 0.01,0.02 --test-window 300 --sdp-regularization 1e-9 \
             --stribeck 0.3 --bounds 2019 --no-ellipsoids"
        );
        assert!(cli.unrendered.is_empty(), "{:?}", cli.unrendered);
        let py = call("psm", &s, &inputs, Some(&read)).python_call();
        assert_eq!(
            py.text,
            "import dvrk_ident as di\nrobot = di.Model.load(\"psm\")\n\
             train = [di.read_log(\"my one.csv\", robot, format=\"wpi\", rate=200)]\n\
             test = [di.read_log(\"two.csv\", robot, format=\"wpi\", rate=200)]\n\
             result = di.fit(robot, train, method=\"sdp\", test=test, cutoff=[5, 3.5], \
             filter_order=4, filter_torque=True, trim=150, decimate=2, min_speed=0.01, delay=[0.01, 0.02], \
             test_window=300, sdp_regularization=1e-9, stribeck=0.3, bounds=\"2019\", \
             ellipsoids=False)\n"
        );
        // Unknown reading options are said, not guessed.
        let unknown = call("psm", &s, &inputs, None).cli_command();
        assert!(unknown.unrendered[0].contains("--format, --rate"));
    }

    /// A selection's result repeats the selection (which chooses the same terms), not
    /// the winner's terms; per-log offsets are a switch.
    #[test]
    fn a_selection_is_repeated_not_its_winner() {
        let s = FitSettings {
            method: crate::Method::Ols,
            stribeck_velocity: Some(0.3),
            select: Some(crate::settings::Candidates::builtin()),
            log_offsets: true,
            ..FitSettings::default()
        };
        let inputs = [input("train", "a.csv"), input("train", "b.csv")];
        let cli = call("psm", &s, &inputs, Some(&ReadOptions::default())).cli_command();
        assert_eq!(
            cli.text,
            "dvrk-ident fit a.csv b.csv --robot psm --method ols \
             --select coulomb,stribeck,dahl,stribeck+dahl --log-offsets"
        );
        let py = call("psm", &s, &inputs, Some(&ReadOptions::default())).python_call();
        assert!(
            py.text.contains(
                "method=\"ols\", select=\"coulomb,stribeck,dahl,stribeck+dahl\", log_offsets=True)"
            ),
            "{}",
            py.text
        );
    }

    /// A raised decompression bound is part of how the logs were read: a compressed
    /// recording larger than the default bound needs it again.
    #[test]
    fn the_decompression_bound_is_repeated() {
        let s = FitSettings::default();
        let read = ReadOptions {
            max_unpacked_mib: Some(40_000),
            ..ReadOptions::default()
        };
        let inputs = [input("train", "big.mcap.zst")];
        let cli = call("psm", &s, &inputs, Some(&read)).cli_command();
        assert_eq!(
            cli.text,
            "dvrk-ident fit big.mcap.zst --robot psm --max-unpacked-mib 40000 --method sdp"
        );
        let py = call("psm", &s, &inputs, Some(&read)).python_call();
        assert!(
            py.text
                .contains("train = [di.read_log(\"big.mcap.zst\", robot, max_unpacked_mib=40000)]"),
            "{}",
            py.text
        );
    }
}
