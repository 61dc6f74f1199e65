//! `dvrk-ident observe LOG... --robot ROBOT --out part.obs`: the map of a distributed fit.
//! The logs are processed and reduced as `fit` does before its estimator, and the state
//! ([`dvrk_ident::state`]) is written; `fit --from` merges states and fits them.

use std::path::Path;

use anyhow::Result;
use dvrk_ident::fit::stream::BLOCK_SAMPLES;
use dvrk_ident::fit::LogData;
use dvrk_ident::output::Outputs;
use dvrk_ident::request::is_large;
use dvrk_ident::state::ObservationState;
use dvrk_ident::FitSettings;
use dvrk_model::Model;

use super::args::LogArgs;

#[derive(clap::Args)]
#[command(allow_negative_numbers = true)]
pub struct Args {
    /// Training logs (any format `fit` reads), each processed on its own; one state
    /// holds them all
    #[arg(required = true, num_args = 1.., value_name = "LOG")]
    pub logs: Vec<String>,
    /// Built-in robot (psm, psm_simplified, mtm) or a description/URDF path
    #[arg(long)]
    pub robot: String,
    #[command(flatten)]
    pub log_args: LogArgs,
    /// Add a Stribeck friction term with this velocity (rad/s or m/s), as `fit --stribeck`
    #[arg(long, value_name = "VS")]
    pub stribeck: Option<f64>,
    /// The observation state file (written atomically; `-` for stdout)
    #[arg(long)]
    pub out: String,
    /// Read the logs block by block, as `fit --stream` (automatic above 256 MiB)
    #[arg(long)]
    pub stream: bool,
}

pub fn run(args: Args) -> Result<()> {
    let stdout_taken = super::check_outputs(&[("--out", Some(args.out.as_str()))], &[])?;
    let model = Model::load(&args.robot)?;
    let mut settings = args.log_args.settings(FitSettings::default())?;
    settings.stribeck_velocity = args.stribeck;
    let fitted = settings.model(&model)?;
    let read = args.log_args.read_options().for_model(&fitted);
    let readers = args
        .logs
        .iter()
        .map(|p| read.open(p))
        .collect::<Result<Vec<_>, _>>()?;
    let bars = crate::progress::Bars::new();
    let state = if args.stream || args.logs.iter().any(|p| is_large(Path::new(p))) {
        ObservationState::observe_stream(
            &model,
            &readers.iter().collect::<Vec<_>>(),
            &settings,
            BLOCK_SAMPLES,
            &bars,
        )?
    } else {
        let data = readers
            .iter()
            .map(|r| {
                let name = format!("reading {}", r.path().display());
                Ok(bars.spin(&name, || r.read_all())?)
            })
            .collect::<Result<Vec<_>>>()?;
        let logs: Vec<LogData> = data
            .iter()
            .zip(&args.logs)
            .map(|(samples, path)| LogData {
                samples,
                file: Some(Path::new(path)),
            })
            .collect();
        ObservationState::observe(&model, &logs, &settings, &bars)?
    };
    let bytes = state.to_bytes();
    let mut outputs = Outputs::new();
    outputs.add(Path::new(&args.out), &bytes)?;
    outputs.commit()?;
    super::emit_summary(
        &format!(
            "{}: robot {}, {} log(s), {} samples, {} bytes",
            args.out,
            state.robot,
            state.observed.logs.len(),
            state.samples(),
            bytes.len()
        ),
        stdout_taken,
    )
}
