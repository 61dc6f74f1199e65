//! One module per subcommand, plus the few conversions they share.

pub mod args;
pub mod cable_fit;
pub mod compare;
pub mod convert;
pub mod excite;
pub mod export;
pub mod fit;
pub mod model;
pub mod observe;
pub mod payload;
pub mod report;
pub mod residual;
pub mod settings;
pub mod shell;
pub mod simulate;
pub mod validate;

use anyhow::{bail, Context, Result};
use dvrk_ident::FitResult;
use dvrk_ident::Named;
use dvrk_logs::output::Inputs;
use dvrk_model::Model;

/// The clap parser of a flag whose values are a library option enum's names
/// ([`Named`]): the command line lists and parses exactly what Python accepts.
#[derive(Clone)]
pub struct NamedParser<T> {
    /// Why the flag refuses a value (`None`: it takes it); the help lists only the
    /// values it takes.
    refuse: fn(T) -> Option<String>,
}

/// [`NamedParser`] for `T`, in `#[arg(value_parser = named::<T>())]`.
pub fn named<T>() -> NamedParser<T> {
    NamedParser { refuse: |_| None }
}

/// [`NamedParser`] of an output's log format: only the formats that are written, so
/// the help offers no format that is then refused.
pub fn writable() -> NamedParser<dvrk_ident::log::LogFormat> {
    NamedParser {
        refuse: |f| {
            (!f.is_writable())
                .then(|| format!("logs are written as wpi, csv or mcap ({f} is read only)"))
        },
    }
}

impl<T: Named + PartialEq + Send + Sync> clap::builder::TypedValueParser for NamedParser<T> {
    type Value = T;

    fn parse_ref(
        &self,
        cmd: &clap::Command,
        arg: Option<&clap::Arg>,
        value: &std::ffi::OsStr,
    ) -> Result<T, clap::Error> {
        let flag = arg.map(|a| format!("{a}: ")).unwrap_or_default();
        let message = match value.to_str() {
            Some(text) => match T::parse_name(text) {
                Ok(v) => match (self.refuse)(v) {
                    None => return Ok(v),
                    Some(m) => m,
                },
                Err(e) => e.to_string(),
            },
            None => format!("{} is not valid UTF-8", T::WHAT),
        };
        Err(clap::Error::raw(
            clap::error::ErrorKind::InvalidValue,
            format!("{flag}{message}\n"),
        )
        .with_cmd(cmd))
    }

    fn possible_values(
        &self,
    ) -> Option<Box<dyn Iterator<Item = clap::builder::PossibleValue> + '_>> {
        Some(Box::new(
            T::NAMES[..T::CANONICAL]
                .iter()
                .filter(|(_, v)| (self.refuse)(*v).is_none())
                .map(|(n, _)| clap::builder::PossibleValue::new(*n)),
        ))
    }
}

/// Writes `text` and a newline to stdout. A closed pipe (`dvrk-ident ... | head`) is
/// reported as an I/O error that `main` treats as a normal end, not a panic.
pub fn emit(text: &str) -> Result<()> {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    out.write_all(text.as_bytes())?;
    if !text.ends_with('\n') {
        out.write_all(b"\n")?;
    }
    out.flush()?;
    Ok(())
}

/// The width of a table's joint column: its longest name, at least 8 characters (the
/// tables of `fit`, `validate` and `residual`).
pub fn joint_width(names: &[String]) -> usize {
    names
        .iter()
        .map(|n| n.chars().count())
        .max()
        .unwrap_or(0)
        .max(8)
}

/// Prints a warning on stderr: every command's warnings with the one prefix, as its
/// errors have theirs (`dvrk-ident: error:`).
pub fn warn(text: impl std::fmt::Display) {
    eprintln!("dvrk-ident: warning: {text}");
}

/// The summary of a command: on stdout, or on stderr when an output (`-`) has stdout.
pub fn emit_summary(text: &str, stdout_taken: bool) -> Result<()> {
    if stdout_taken {
        eprintln!("{}", text.trim_end());
        Ok(())
    } else {
        emit(text)
    }
}

/// Checks every output of a command before any work is done (see
/// [`dvrk_logs::output`]): files `(flag, path)` and folders `(flag, path)` must be
/// writable destinations whose folder exists, no two the same, at most one `-`
/// (standard output), none of them one of the command's `inputs`. Returns whether one of
/// them is standard output.
pub fn check_outputs(
    files: &[(&str, Option<&str>)],
    dirs: &[(&str, Option<&str>)],
    inputs: &Inputs,
) -> Result<bool> {
    use dvrk_logs::output::{check_dir, Destination};
    let mut seen: Vec<(Option<std::path::PathBuf>, &str)> = Vec::new();
    for &(flag, path) in files.iter().chain(dirs) {
        let Some(path) = path else { continue };
        inputs
            .check(std::path::Path::new(path))
            .with_context(|| format!("{flag} {path}"))?;
    }
    for &(flag, path) in files {
        let Some(path) = path else { continue };
        let key = match Destination::of(std::path::Path::new(path))
            .with_context(|| format!("{flag} {path}"))?
        {
            Destination::Stdout => None,
            Destination::File(p) | Destination::Special(p) => Some(p),
        };
        if let Some((_, other)) = seen.iter().find(|(k, _)| *k == key) {
            bail!("{flag} {path}: the same destination as {other}");
        }
        seen.push((key, flag));
    }
    for &(flag, path) in dirs {
        let Some(path) = path else { continue };
        let (resolved, _) =
            check_dir(std::path::Path::new(path)).with_context(|| format!("{flag} {path}"))?;
        if let Some((_, other)) = seen.iter().find(|(k, _)| k.as_ref() == Some(&resolved)) {
            bail!("{flag} {path}: the same destination as {other}");
        }
        seen.push((Some(resolved), flag));
    }
    Ok(seen.iter().any(|(k, _)| k.is_none()))
}

/// The inputs of a command, which no output may replace (see [`check_outputs`]): `logs`
/// (with the members of rosbag2 folders), and `files` `(what, path)` such as `("the
/// result", Some("r.json"))`. A robot given by a built-in name is no file.
pub fn inputs(logs: &[&str], files: &[(&str, Option<&str>)]) -> Inputs {
    let mut inputs = Inputs::new();
    for log in logs {
        inputs.add_log(std::path::Path::new(log));
    }
    for &(what, path) in files {
        let Some(path) = path else { continue };
        if what == "the robot" && dvrk_model::Model::builtin_names().contains(&path) {
            continue;
        }
        inputs.add(format!("{what} {path}"), std::path::Path::new(path));
    }
    inputs
}

/// A count flag that must be at least 1 (e.g. `--test-window`: 0 samples have no
/// metrics).
pub fn at_least_one(
    text: &str,
) -> std::result::Result<usize, Box<dyn std::error::Error + Send + Sync>> {
    match text.parse::<usize>()? {
        0 => Err("must be at least 1".into()),
        n => Ok(n),
    }
}

/// Parses a comma-separated list of numbers such as `0.1,-0.2,0.3` of length `n`.
pub fn parse_vector(text: &str, n: usize, flag: &str) -> Result<Vec<f64>> {
    let v: Vec<f64> = text
        .split(',')
        .map(|t| {
            t.trim()
                .parse::<f64>()
                .with_context(|| format!("{flag}: `{t}` is not a number"))
        })
        .collect::<Result<_>>()?;
    if v.len() != n {
        bail!(
            "{flag}: expected {n} comma-separated values, got {}",
            v.len()
        );
    }
    if let Some(x) = v.iter().find(|x| !x.is_finite()) {
        bail!("{flag}: value {x} is not finite");
    }
    // The range of logged values (positions, velocities; accelerations alike).
    let max = dvrk_ident::Signal::Position.max_magnitude();
    if let Some(x) = v.iter().find(|x| x.abs() > max) {
        bail!(
            "{flag}: value {} is beyond the accepted ±{max:e}",
            dvrk_model::input::show(*x)
        );
    }
    Ok(v)
}

/// The parameters of a `--params` file for `model`, with the model that evaluates them:
/// a result document (`dvrk-ident fit --out`) is evaluated with the model it was fitted
/// with (its Stribeck terms, its bounds) and refused for another robot in one line; a
/// plain `{name: value}` object (or `{"parameters": {...}}`) must name exactly `model`'s
/// parameters; `nominal` stands for the description's nominal parameters.
pub fn read_params<'m>(
    model: &'m dvrk_model::Model,
    path: &str,
) -> Result<(std::borrow::Cow<'m, dvrk_model::Model>, Vec<f64>)> {
    if path == "nominal" {
        let nominal = model.nominal_parameters().with_context(|| {
            format!(
                "{}: the description has no nominal value for every parameter (every link \
                 needs a nominal mass, every motor inertia and spring a nominal value); give a \
                 parameter file",
                model.source
            )
        })?;
        return Ok((std::borrow::Cow::Borrowed(model), nominal));
    }
    let text = dvrk_model::input::read_text(std::path::Path::new(path))
        .with_context(|| format!("{path}: cannot read"))?;
    let doc: serde_json::Value =
        serde_json::from_str(&text).with_context(|| format!("{path}: not valid JSON"))?;
    // A result document records its robot and settings beside its parameters.
    if doc.get("robot").is_some() && doc.get("settings").is_some() {
        let result = FitResult::from_json(&text, path)?;
        let fitted = result.model_for(model, path)?;
        let params = result.params_for(&fitted)?;
        return Ok((fitted, params));
    }
    let map = doc
        .get("parameters")
        .unwrap_or(&doc)
        .as_object()
        .with_context(|| format!("{path}: expected an object of parameter values"))?;
    let mut values = Vec::with_capacity(map.len());
    for (k, v) in map {
        let x = v
            .as_f64()
            .with_context(|| format!("{path}: parameter {k} is not a number"))?;
        let x = dvrk_model::input::check_magnitude(x, dvrk_model::input::MAX_VALUE, "")
            .map_err(|m| anyhow::anyhow!("{path}: parameter {k}: {m}"))?;
        values.push((k.as_str(), x));
    }
    let params = model.params_from_named(values, path)?;
    Ok((std::borrow::Cow::Borrowed(model), params))
}

/// The note `validate` and `report` print when their processing flags change the fit's
/// settings (`changed`: [`dvrk_ident::FitSettings::differences`] from the fit's), so a
/// log's numbers are not read as the fit's; `None` when nothing changed.
pub fn settings_note(changed: &[dvrk_ident::Difference]) -> Option<String> {
    if changed.is_empty() {
        return None;
    }
    let list: Vec<String> = changed
        .iter()
        .map(|d| {
            let (here, fit) = d.shown();
            format!("{} {here} (fit: {fit})", d.path)
        })
        .collect();
    Some(format!(
        "note: these logs are processed with settings that differ from the fit's, so \
         their errors compare with the fit's only in part: {}",
        list.join("; ")
    ))
}

/// A fit result with the model it was fitted for and its parameter vector.
pub struct LoadedResult {
    pub result: FitResult,
    /// The robot as given to [`Model::load`]: a built-in name or a path.
    pub robot: String,
    pub model: Model,
    pub params: Vec<f64>,
}

/// Reads a result file and rebuilds its model: `robot` if given, else the robot the
/// result records (built-in name or description path), with the fit's model options.
pub fn load_result(path: &str, robot: Option<&str>) -> Result<LoadedResult> {
    let result = FitResult::read(std::path::Path::new(path))?;
    let robot = robot.unwrap_or_else(|| result.robot()).to_string();
    let given = Model::load(&robot).with_context(|| format!("{path}: robot of the result"))?;
    // Through the result, so the fit's model options (Stribeck terms) are applied.
    let model = result.model_for(&given, path)?.into_owned();
    let params = result
        .params_for(&model)
        .with_context(|| format!("{path}: parameters for robot `{robot}`"))?;
    Ok(LoadedResult {
        result,
        robot,
        model,
        params,
    })
}
