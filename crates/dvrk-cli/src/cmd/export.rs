//! `dvrk-ident export RESULT --urdf OUT.urdf [--template ROBOT.urdf] [--wpi-json OUT.json]
//! [--dvrk-gc gc-MTML.json]`: an identified model for the tools that read URDF, the 2019
//! params.json, or the dVRK controller's MTM gravity compensation.

use std::path::Path;

use anyhow::{Context, Result};
use dvrk_ident::export::dvrk_gc::{self, dvrk_gc};
use dvrk_ident::export::wpi_params::wpi_params_json;
use dvrk_ident::output::Outputs;
use dvrk_model::Model;

use super::args::{INPUT, MODEL, OUTPUT};
use super::{emit_summary, load_result, LoadedResult};

#[derive(clap::Args)]
// A negative number is a value (`--f0 -1`, `--rate -5`), refused by the checks with a
// message, not an unknown flag.
#[command(allow_negative_numbers = true)]
#[command(group(
    clap::ArgGroup::new("outputs")
        .args(["urdf", "wpi_json", "dvrk_gc"])
        .required(true)
        .multiple(true)
))]
pub struct Args {
    /// Result file written by `dvrk-ident fit --out`
    pub result: String,
    /// URDF whose <inertial> elements are replaced, everything else kept [default: the
    /// robot's own file when the robot is a URDF; for a description, a URDF is generated]
    #[arg(long, alias = "from", value_name = "ROBOT.urdf", requires = "urdf", help_heading = INPUT)]
    pub template: Option<String>,
    /// Robot [default: the one the result was fitted for]
    #[arg(long, help_heading = MODEL)]
    pub robot: Option<String>,
    /// Write a URDF with the identified inertials here (atomically)
    #[arg(long, value_name = "OUT.urdf", help_heading = OUTPUT)]
    pub urdf: Option<String>,
    /// Write the parameters in the 2019 package's params.json layout here (atomically)
    #[arg(long, value_name = "OUT.json", help_heading = OUTPUT)]
    pub wpi_json: Option<String>,
    /// Write the dVRK controller's MTM gravity-compensation file (version 2.0, as
    /// sawIntuitiveResearchKit's robGravityCompensationMTM reads it) here (atomically)
    #[arg(long, value_name = "gc-MTML.json", help_heading = OUTPUT)]
    pub dvrk_gc: Option<String>,
    /// Grid points per joint of the gravity-compensation fit (joints 1-6), 6 to 10
    #[arg(long, value_name = "N", default_value_t = dvrk_gc::DEFAULT_POINTS, requires = "dvrk_gc", help_heading = OUTPUT)]
    pub gc_points: usize,
}

pub fn run(args: Args) -> Result<()> {
    let stdout_taken = super::check_outputs(
        &[
            ("--urdf", args.urdf.as_deref()),
            ("--wpi-json", args.wpi_json.as_deref()),
            ("--dvrk-gc", args.dvrk_gc.as_deref()),
        ],
        &[],
    )?;
    let loaded = load_result(&args.result, args.robot.as_deref())?;
    // None of the formats has a place for the torques' measurement delays: a controller
    // that compares these torques with its measurements must apply them itself.
    let delays = &loaded.result.settings.processing.delay_s;
    if !delays.is_empty() {
        let ms: Vec<String> = delays.iter().map(|d| format!("{:.1}", d * 1e3)).collect();
        eprintln!(
            "note: the fit's torque measurement delays ({} ms, per coordinate) are not part \
             of the exported files: compare measured torques that much later with the \
             model's",
            ms.join(" ")
        );
    }
    // Everything is built before anything is written: an error leaves no output.
    let urdf = match &args.urdf {
        Some(out) => Some((
            out,
            urdf_text(&loaded, args.template.as_deref(), &args.result)?,
        )),
        None => None,
    };
    let wpi = match &args.wpi_json {
        Some(out) => {
            let doc = wpi_params_json(&loaded.model, &loaded.params);
            Some((out, serde_json::to_string_pretty(&doc)?))
        }
        None => None,
    };
    let gc = match &args.dvrk_gc {
        Some(out) => {
            let gc = dvrk_gc(&loaded.model, &loaded.params, args.gc_points).with_context(|| {
                format!(
                    "{}: cannot export the dVRK gravity compensation",
                    args.result
                )
            })?;
            Some((
                out,
                serde_json::to_string_pretty(&gc.to_json())?,
                gc.summary(),
            ))
        }
        None => None,
    };
    let mut report = String::new();
    let mut outputs = Outputs::new();
    if let Some((out, (text, how))) = &urdf {
        outputs.add(Path::new(out), text)?;
        report += &format!("wrote {out}: {how}\n");
    }
    if let Some((out, text)) = &wpi {
        outputs.add(Path::new(out), text)?;
        report += &format!("wrote {out}: 2019 params.json layout\n");
    }
    if let Some((out, text, summary)) = &gc {
        outputs.add(Path::new(out), text)?;
        report += &format!("wrote {out}: dVRK MTM gravity compensation\n{summary}");
    }
    outputs.commit()?;
    emit_summary(&report, stdout_taken)
}

/// The URDF text and how it was made: the inertials replaced in `from` (or the robot's own
/// URDF), else generated from the description.
fn urdf_text(loaded: &LoadedResult, from: Option<&str>, result: &str) -> Result<(String, String)> {
    let LoadedResult {
        result: fit,
        robot,
        model,
        params,
    } = loaded;
    let hint = || {
        if fit.method == "sdp" {
            String::new()
        } else {
            format!(
                " (this {} fit identifies the base parameters only, its link parameters \
                 are a representative, not rigid bodies; `dvrk-ident fit --method sdp` \
                 gives physically consistent ones)",
                fit.method
            )
        }
    };
    let context = || format!("{result}: cannot export to URDF{}", hint());
    let source = from.map(str::to_string).or_else(|| robot_urdf(robot));
    match source {
        Some(path) => {
            let text = dvrk_model::input::read_text(Path::new(&path))
                .with_context(|| format!("{path}: cannot read"))?;
            let out = model
                .urdf_with_inertials(params, &text, &path)
                .with_context(context)?;
            Ok((
                out,
                format!(
                    "{path} with the identified inertials of robot `{}`",
                    model.name
                ),
            ))
        }
        None => {
            let out = model.to_urdf(params).with_context(context)?;
            Ok((
                out,
                format!(
                    "URDF generated from robot `{}` (what URDF cannot hold is listed in its header)",
                    model.name
                ),
            ))
        }
    }
}

/// The robot's own URDF file, when it was loaded from one.
fn robot_urdf(robot: &str) -> Option<String> {
    if Model::builtin_names().contains(&robot) {
        return None;
    }
    let text = dvrk_model::input::read_text(Path::new(robot)).ok()?;
    dvrk_model::is_urdf_document(Path::new(robot), &text).then(|| robot.to_string())
}
