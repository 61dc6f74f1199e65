//! The fit options' flags, made from the library's list of options
//! ([`Setting`], declared once with [`Overrides`]): each flag's name, help and default
//! come from there; this file adds only what is the command line's own (heading, value
//! name, parser) in one exhaustive `match`, so an option without a flag does not
//! compile. [`SettingFlags`] declares a command's options and maps what was given onto
//! [`Overrides`] through the library's one conversion ([`Overrides::from_values`]).

use std::marker::PhantomData;

use anyhow::Result;
use clap::parser::ValueSource;
use clap::{Arg, ArgAction, ArgMatches, Command};
use dvrk_ident::SettingName;
use dvrk_ident::{BoundsSet, IdentError, Method};
use dvrk_ident::{FitSettings, Joints, PriorMetric};
use dvrk_ident::{Overrides, Preset, Setting, SettingError};

use super::args::{ESTIMATOR, INPUT, MODEL, OUTPUT, PROCESSING};
use super::{at_least_one, named};

/// How the command line spells an option: its flag (`--cutoff`, `--no-ellipsoids`).
pub fn flag(s: Setting) -> String {
    match s {
        Setting::Ellipsoids => "--no-ellipsoids".into(),
        s => format!("--{}", s.name().replace('_', "-")),
    }
}

/// How the command line spells a setting the library refuses
/// ([`IdentError::Setting`]): each fit option as its flag, another argument as the flag
/// of that name (`--wrench`), or by its name where the command line has no such flag.
pub fn spelled(name: &SettingName) -> String {
    match name {
        SettingName::Options(settings) => settings
            .iter()
            .map(|s| flag(*s))
            .collect::<Vec<_>>()
            .join(", "),
        // Python's `points=` of the gravity-compensation export.
        SettingName::Argument("points") => "--gc-points".into(),
        // The payload's result and logs are positional arguments.
        SettingName::Argument(n @ ("payload" | "logs")) => format!("invalid setting {n}"),
        SettingName::Argument(n) => format!("--{}", n.replace('_', "-")),
    }
}

/// A library error as the command line shows it: a refused setting named as its flag
/// ([`spelled`]), any other as the library's message.
pub fn error_text(e: &(dyn std::error::Error + 'static)) -> String {
    match e.downcast_ref::<IdentError>() {
        Some(IdentError::Setting { name, message }) => format!("{}: {message}", spelled(name)),
        _ => e.to_string(),
    }
}

/// An option's value refused, named as its flag.
pub fn setting_error(e: SettingError) -> anyhow::Error {
    anyhow::anyhow!("{}: {}", flag(e.setting), e.message)
}

/// The value of flag `id` if the command line gave it (not a default): `switch`'s value
/// for a switch (`Some(on)`: the value the flag stands for), else the flag's last text,
/// which the library's one conversion reads. Shared by the fit's and `excite`'s option
/// flags.
pub fn given(m: &ArgMatches, id: &str, switch: Option<bool>) -> Option<serde_json::Value> {
    if m.value_source(id) != Some(ValueSource::CommandLine) {
        return None;
    }
    match switch {
        Some(on) => Some(serde_json::Value::Bool(on)),
        None => {
            let text = m.try_get_raw(id).ok().flatten()?.next_back()?;
            Some(serde_json::Value::String(text.to_string_lossy().into()))
        }
    }
}

/// Whether the flag is a switch (given or not), and the value it gives.
fn switch(s: Setting) -> Option<bool> {
    match s {
        Setting::FilterTorque | Setting::LogOffsets | Setting::LoadFriction => Some(true),
        Setting::Ellipsoids => Some(false),
        _ => None,
    }
}

/// The flag of an option: name and help from the library, the rest here.
pub fn arg(s: Setting) -> Arg {
    // clap takes a flag's name as a `&'static str`; the command is built once per
    // process (twenty-odd short names).
    let long: &'static str = Box::leak(flag(s)[2..].to_string().into_boxed_str());
    let a = Arg::new(s.name()).long(long).help(s.doc());
    let a = match switch(s) {
        Some(_) => a.action(ArgAction::SetTrue),
        None => a.action(ArgAction::Set),
    };
    let usize = clap::value_parser!(usize);
    let f64 = clap::value_parser!(f64);
    match s {
        Setting::Method => a
            .value_parser(named::<Method>())
            .value_name("METHOD")
            .help_heading(ESTIMATOR),
        Setting::Cutoff => a.value_name("HZ|HZ1,HZ2,...|none").help_heading(PROCESSING),
        Setting::FilterOrder => a
            .value_parser(at_least_one)
            .value_name("N")
            .help_heading(PROCESSING),
        Setting::FilterTorque => a.help_heading(PROCESSING),
        Setting::Trim => a
            .value_parser(usize)
            .value_name("N")
            .help_heading(PROCESSING),
        Setting::Decimate => a
            .value_parser(at_least_one)
            .value_name("N")
            .help_heading(PROCESSING),
        Setting::MinSpeed => a
            .value_parser(f64)
            .value_name("SPEED")
            .help_heading(PROCESSING),
        Setting::Resample => a
            .value_parser(f64)
            .value_name("HZ")
            .help_heading(PROCESSING),
        Setting::TestWindow => a
            .value_parser(at_least_one)
            .value_name("N")
            .help_heading(INPUT),
        Setting::IrlsIterations => a
            .value_parser(usize)
            .value_name("N")
            .help_heading(ESTIMATOR),
        Setting::SdpRegularization => a.value_parser(f64).value_name("W").help_heading(ESTIMATOR),
        Setting::Stribeck => a.value_parser(f64).value_name("VS").help_heading(MODEL),
        Setting::Dahl => a.value_parser(f64).value_name("SIGMA").help_heading(MODEL),
        Setting::LoadFriction => a.help_heading(MODEL),
        Setting::PositionTorque => a
            .value_parser(usize)
            .value_name("ORDER")
            .help_heading(MODEL),
        Setting::PositionTorqueFrames => a.value_name("FRAME,...").help_heading(MODEL),
        Setting::MountingPitch => a
            .value_parser(f64)
            .value_name("DEG")
            .allow_hyphen_values(true)
            .help_heading(MODEL),
        Setting::Bounds => a
            .value_parser(named::<BoundsSet>())
            .value_name("SET")
            .help_heading(MODEL),
        Setting::Ellipsoids => a.help_heading(MODEL),
        Setting::Delay => a.value_name("auto|D|D1,D2,...").help_heading(PROCESSING),
        Setting::Prior => a.value_name("FILE|nominal").help_heading(ESTIMATOR),
        Setting::PriorWeight => a.value_parser(f64).value_name("W").help_heading(ESTIMATOR),
        Setting::PriorMetric => a
            .value_parser(named::<PriorMetric>())
            .value_name("METRIC")
            .help_heading(ESTIMATOR),
        Setting::Preset => a
            .value_parser(named::<Preset>())
            .value_name("PRESET")
            .help_heading(ESTIMATOR),
        Setting::LogOffsets => a.help_heading(MODEL),
        Setting::Select => a
            .num_args(0..=1)
            .default_missing_value("builtin")
            .value_name("builtin|CANDIDATE,...")
            .help_heading(MODEL),
        Setting::Joints => a
            .value_parser(named::<Joints>())
            .value_name("model|measured")
            .help_heading(OUTPUT),
    }
}

/// The options a command takes. `--resample` is a reading flag every command that
/// reads logs has ([`super::args::McapArgs`], with [`arg`]'s help): read as an option
/// here, declared there.
pub trait Scope {
    /// The options the command takes.
    const SETTINGS: &'static [Setting];
}

/// `fit`: every option.
#[derive(Clone, Debug, Default)]
pub struct Fit;
impl Scope for Fit {
    const SETTINGS: &'static [Setting] = Setting::ALL;
}

/// `observe`: the options an observation state carries.
#[derive(Clone, Debug, Default)]
pub struct Observe;
impl Scope for Observe {
    const SETTINGS: &'static [Setting] = Setting::OBSERVE;
}

/// `validate`, `report`, `residual`: the processing of the logs.
#[derive(Clone, Debug, Default)]
pub struct Processing;
impl Scope for Processing {
    const SETTINGS: &'static [Setting] = Setting::PROCESSING;
}

/// A command's option flags (`#[command(flatten)]`), and the values given.
#[derive(Clone, Debug, Default)]
pub struct SettingFlags<S> {
    values: Vec<(Setting, serde_json::Value)>,
    scope: PhantomData<S>,
}

impl<S: Scope> SettingFlags<S> {
    /// The options given, as overrides (an error names the flag).
    pub fn overrides(&self) -> Result<Overrides> {
        Overrides::from_values(self.values.iter().cloned()).map_err(setting_error)
    }

    /// `base` with the options given applied.
    pub fn settings(&self, base: FitSettings) -> Result<FitSettings> {
        Ok(self.overrides()?.apply(base))
    }
}

impl<S: Scope> clap::FromArgMatches for SettingFlags<S> {
    fn from_arg_matches(m: &ArgMatches) -> Result<Self, clap::Error> {
        let values = S::SETTINGS
            .iter()
            .filter_map(|&s| given(m, s.name(), switch(s)).map(|v| (s, v)))
            .collect();
        Ok(SettingFlags {
            values,
            scope: PhantomData,
        })
    }

    fn update_from_arg_matches(&mut self, m: &ArgMatches) -> Result<(), clap::Error> {
        *self = Self::from_arg_matches(m)?;
        Ok(())
    }
}

impl<S: Scope> clap::Args for SettingFlags<S> {
    fn augment_args(cmd: Command) -> Command {
        cmd.args(
            S::SETTINGS
                .iter()
                .filter(|s| **s != Setting::Resample)
                .map(|s| arg(*s)),
        )
    }

    fn augment_args_for_update(cmd: Command) -> Command {
        Self::augment_args(cmd)
    }
}

/// The arguments of every command that uses a result on logs (validate, report,
/// residual, payload): the result file and the logs, the robot, the processing (the
/// result's own unless given) and how the logs are read. Declared once so the four
/// commands read and default them alike; each words the two files' help for what it does
/// (`mut_arg`).
#[derive(clap::Args, Clone)]
pub struct ResultOnLogs {
    /// Result file written by `dvrk-ident fit --out`
    pub result: String,
    /// Logs to use the result on
    #[arg(required = true, value_name = "LOG")]
    pub logs: Vec<String>,
    /// Robot [default: the one the result was fitted for]
    #[arg(long, help_heading = super::args::MODEL)]
    pub robot: Option<String>,
    // The fit options (`--cutoff`, ...: every processing `Setting`), before `log_args`:
    // they read `--resample`, which `log_args` declares and takes.
    #[command(flatten)]
    pub settings: SettingFlags<Processing>,
    #[command(flatten)]
    pub log_args: super::args::LogArgs,
}

impl ResultOnLogs {
    /// The result file with its model (the robot given, or the result's), and the
    /// settings to use it with: the result's, with those given on the command line.
    pub fn load(&self) -> Result<(super::LoadedResult, dvrk_ident::FitSettings)> {
        let loaded = super::load_result(&self.result, self.robot.as_deref())?;
        let settings = self.settings.settings(loaded.result.settings.clone())?;
        Ok((loaded, settings))
    }

    /// [`ResultOnLogs::load`] with those settings put in the result: for the commands
    /// whose computation reads them from the result (`residual`, `payload`).
    pub fn load_with_settings(&self) -> Result<super::LoadedResult> {
        let (mut loaded, settings) = self.load()?;
        loaded.result.settings = settings;
        Ok(loaded)
    }

    /// How the command reads its logs ([`super::args::LogArgs::read_options_for`] on
    /// them: these flags, `model`'s measured joints, `processing`'s resampling and the
    /// checks across the logs); report, whose logs may be the result's own, calls that.
    pub fn read_options(
        &self,
        model: &dvrk_model::Model,
        processing: &dvrk_ident::signal::Processing,
    ) -> dvrk_ident::log::ReadOptions {
        self.log_args
            .read_options_for(model, processing, self.logs.iter().map(String::as_str))
    }

    /// What the command reads ([`super::inputs`]: the logs, the result, the robot's
    /// description and `others`), so that no output overwrites it.
    pub fn inputs(&self, others: &[(&str, Option<&str>)]) -> super::Inputs {
        let logs: Vec<&str> = self.logs.iter().map(String::as_str).collect();
        let mut files = vec![
            ("the result", Some(self.result.as_str())),
            ("the robot", self.robot.as_deref()),
        ];
        files.extend_from_slice(others);
        super::inputs(&logs, &files)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    /// Every option of a command's scope has its flag there, named and documented as
    /// the library's list says (the help adds only the shown default).
    #[test]
    fn every_option_has_its_flag() {
        let cli = crate::Cli::command();
        for (command, scope) in [
            ("fit", Setting::ALL),
            ("observe", Setting::OBSERVE),
            ("validate", Setting::PROCESSING),
            ("report", Setting::PROCESSING),
            ("residual", Setting::PROCESSING),
            ("payload", Setting::PROCESSING),
        ] {
            let cmd = cli.find_subcommand(command).unwrap();
            for s in scope {
                let a = cmd
                    .get_arguments()
                    .find(|a| a.get_id() == s.name())
                    .unwrap_or_else(|| panic!("{command}: no flag for {s:?}"));
                assert_eq!(
                    format!("--{}", a.get_long().unwrap()),
                    flag(*s),
                    "{command}"
                );
                let help = a.get_help().unwrap().to_string();
                assert!(help.starts_with(&s.doc()), "{command} {}: {help}", flag(*s));
            }
        }
        assert_eq!(Setting::ALL.len(), 27);
    }

    /// A setting the library refuses is named as the command line's flag: the fit
    /// options by [`flag`] (`--no-ellipsoids`, not `--ellipsoids`), several together,
    /// and the other arguments as their flags.
    #[test]
    fn refused_settings_are_named_as_flags() {
        let e = IdentError::Setting {
            name: SettingName::Options(vec![Setting::Ellipsoids, Setting::FilterOrder]),
            message: "m".into(),
        };
        assert_eq!(error_text(&e), "--no-ellipsoids, --filter-order: m");
        assert_eq!(
            spelled(&SettingName::Argument("wrench_rcond")),
            "--wrench-rcond"
        );
        assert_eq!(spelled(&SettingName::Argument("points")), "--gc-points");
        // Through anyhow, as a command returns it.
        let e = anyhow::Error::from(IdentError::Setting {
            name: Setting::Delay.into(),
            message: "m".into(),
        });
        assert_eq!(crate::message(&e), "--delay: m");
    }

    /// A setting a library message suggests ([`Hint`]) is the command line's flag, in a
    /// nested error too: the library's default spelling is the flags [`flag`] declares.
    #[test]
    fn suggested_settings_are_named_as_flags() {
        use dvrk_logs::hint::Hint;
        for (hint, setting) in [
            (Hint::Cutoff, Setting::Cutoff),
            (Hint::Trim, Setting::Trim),
            (Hint::TestWindow, Setting::TestWindow),
        ] {
            assert_eq!(hint.to_string(), flag(setting));
        }
        let e = anyhow::Error::from(IdentError::Evaluated {
            result: "a.json".into(),
            error: Box::new(IdentError::NoSampleLeft {
                source_name: "t.csv".into(),
            }),
        });
        assert_eq!(
            crate::message(&e),
            "a.json: evaluated on t.csv: no processed sample is left (a longer log or a \
             smaller --trim)"
        );
    }

    /// `--resample`, declared with the reading flags, is read as the fit option in
    /// every command that takes it (the reading flags take their values afterwards).
    #[test]
    fn commands_read_resample_as_an_option() {
        use clap::Parser;
        for command in ["fit", "observe", "validate"] {
            let mut argv = vec![
                "dvrk-ident",
                command,
                "a.json",
                "b.csv",
                "--resample",
                "250",
            ];
            argv.extend(["--trim", "5", "--robot", "psm", "--out", "s"]);
            let argv: Vec<&str> = match command {
                "fit" => argv
                    .into_iter()
                    .filter(|a| *a != "--out" && *a != "s")
                    .collect(),
                "validate" => argv[..8].to_vec(),
                _ => argv,
            };
            let cli = crate::Cli::try_parse_from(&argv).unwrap();
            let o = match cli.command {
                crate::Command::Fit(a) => a.settings.overrides(),
                crate::Command::Observe(a) => a.settings.overrides(),
                crate::Command::Validate(a) => a.on_logs.settings.overrides(),
                _ => unreachable!(),
            }
            .unwrap();
            assert_eq!((o.resample_hz, o.trim), (Some(250.0), Some(5)), "{command}");
        }
    }

    /// Text given on the command line and mapped through [`SettingFlags`] is the
    /// library's overrides, and a refused value names the flag.
    #[test]
    fn flags_map_onto_overrides() {
        use clap::FromArgMatches;
        let cmd = <SettingFlags<Fit> as clap::Args>::augment_args(Command::new("t"))
            .arg(Arg::new("resample").long("resample"));
        let m = cmd
            .clone()
            .try_get_matches_from([
                "t",
                "--cutoff",
                "5,3",
                "--no-ellipsoids",
                "--filter-order",
                "4",
                "--resample",
                "250",
                "--delay",
                "auto",
            ])
            .unwrap();
        let o = SettingFlags::<Fit>::from_arg_matches(&m)
            .unwrap()
            .overrides()
            .unwrap();
        assert_eq!(
            o.given(),
            [
                Setting::Cutoff,
                Setting::FilterOrder,
                Setting::Resample,
                Setting::Ellipsoids,
                Setting::Delay
            ]
        );
        assert_eq!(
            (o.ellipsoids, o.filter_order, o.resample_hz),
            (Some(false), Some(4), Some(250.0))
        );
        let m = cmd.try_get_matches_from(["t", "--delay", "soon"]).unwrap();
        let e = SettingFlags::<Fit>::from_arg_matches(&m)
            .unwrap()
            .overrides()
            .unwrap_err();
        assert_eq!(
            e.to_string(),
            "--delay: `soon` is not a delay: expected auto or seconds d1,d2,..."
        );
    }
}
