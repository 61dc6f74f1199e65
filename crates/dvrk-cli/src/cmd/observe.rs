//! `dvrk-ident observe LOG... --robot ROBOT --out part.obs`: the map of a distributed fit.
//! The logs are processed and reduced as `fit` does before its estimator, and the state
//! ([`dvrk_ident::ObservationState`]) is written; `fit --states` merges states and fits them.

use std::path::Path;

use anyhow::Result;
use dvrk_ident::{LogSource, ObserveRequest, Streaming};
use dvrk_logs::output::Outputs;
use dvrk_model::Model;

use super::args::{LogArgs, INPUT, MODEL, OUTPUT};
use super::settings::{Observe, SettingFlags};

#[derive(clap::Args)]
#[command(allow_negative_numbers = true, mut_args = super::args::library_defaults)]
pub struct Args {
    /// Training logs (any format `fit` reads), each processed on its own; one state
    /// holds them all
    #[arg(required = true, num_args = 1.., value_name = "LOG")]
    pub logs: Vec<String>,
    /// Read the logs block by block, as `fit --stream` (automatic above 256 MiB)
    #[arg(long, help_heading = INPUT)]
    pub stream: bool,
    /// Built-in robot (psm, psm_simplified, mtm, ecm, psm_si, psm_si_tool, ecm_si) or a description/URDF path
    #[arg(long, help_heading = MODEL)]
    pub robot: String,
    // The fit options (`--method`, `--cutoff`, ...: every library `Setting`), before
    // `log_args`: they read `--resample`, which `log_args` declares and takes.
    #[command(flatten)]
    pub settings: SettingFlags<Observe>,
    #[command(flatten)]
    pub log_args: LogArgs,
    /// The observation state file (written atomically; `-` for stdout)
    #[arg(long, value_name = "STATE", help_heading = OUTPUT)]
    pub out: String,
}

pub fn run(args: Args) -> Result<()> {
    let logs: Vec<&str> = args.logs.iter().map(String::as_str).collect();
    let inputs = super::inputs(&logs, &[("the robot", Some(&args.robot))]);
    let stdout_taken = super::check_outputs(&[("--out", Some(args.out.as_str()))], &[], &inputs)?;
    let model = Model::load(&args.robot)?;
    let request = ObserveRequest {
        read: args.log_args.read_options(),
        overrides: args.settings.overrides()?,
        streaming: if args.stream {
            Streaming::Always
        } else {
            Streaming::Auto
        },
        ..ObserveRequest::new(
            args.logs
                .iter()
                .map(|p| LogSource::File(p.into()))
                .collect(),
        )
    };
    let state = request.run(&model, &crate::progress::Bars::new())?;
    let bytes = state.to_bytes();
    let mut outputs = Outputs::protecting(inputs);
    outputs.add(Path::new(&args.out), &bytes)?;
    outputs.commit()?;
    super::emit_summary(
        &format!(
            "{}: robot {}, {} log(s), {} samples, {} bytes",
            args.out,
            state.robot,
            state.logs().len(),
            state.samples(),
            bytes.len()
        ),
        stdout_taken,
    )
}
