//! `dvrk-ident export RESULT --urdf OUT.urdf [--template ROBOT.urdf] [--wpi-json OUT.json]
//! [--dvrk-gc gc-MTML.json] [--dvrk-kinematic-gc GC.json [--endoscope TYPE]]`: an
//! identified model for the tools that read URDF, the 2019 params.json, or the dVRK
//! controller's gravity compensation (the MTM's file, the ECM's and Si arms' kinematic
//! file). Each output flag is one
//! variant of [`dvrk_ident::export::Export`], which Python's methods map onto too.

use std::path::Path;

use anyhow::{Context, Result};
use dvrk_ident::export::{dvrk_gc, Export, UrdfTemplate};
use dvrk_logs::output::Outputs;
use dvrk_model::Model;

use super::args::{INPUT, MODEL, OUTPUT};
use super::{emit_summary, load_result, LoadedResult};

#[derive(clap::Args)]
// A negative number is a value (`--f0 -1`, `--rate -5`), refused by the checks with a
// message, not an unknown flag.
#[command(allow_negative_numbers = true)]
#[command(group(
    clap::ArgGroup::new("outputs")
        .args(["urdf", "wpi_json", "dvrk_gc", "dvrk_kinematic_gc"])
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
    /// Write the dVRK controller's kinematic gravity-compensation file (the physical DH
    /// its `kinematic_gc` key names) of an ecm, psm_si (psm_si_tool) or ecm_si result here
    /// (atomically)
    #[arg(long, value_name = "GC.json", help_heading = OUTPUT)]
    pub dvrk_kinematic_gc: Option<String>,
    /// The ECM's endoscope type, as its configuration's `endoscope` (Classic_SD_STRAIGHT,
    /// Classic_HD_UP, Si_HD_STRAIGHT, Custom_DOWN, NONE, ...): the controller sets the
    /// insertion link's mass from it
    #[arg(long, value_name = "TYPE", requires = "dvrk_kinematic_gc", help_heading = OUTPUT)]
    pub endoscope: Option<String>,
}

/// The files the export reads, which no output may replace.
fn inputs(args: &Args) -> super::Inputs {
    super::inputs(
        &[],
        &[
            ("the result", Some(&args.result)),
            ("the template", args.template.as_deref()),
            ("the robot", args.robot.as_deref()),
        ],
    )
}

pub fn run(args: Args) -> Result<()> {
    let stdout_taken = super::check_outputs(
        &[
            ("--urdf", args.urdf.as_deref()),
            ("--wpi-json", args.wpi_json.as_deref()),
            ("--dvrk-gc", args.dvrk_gc.as_deref()),
            ("--dvrk-kinematic-gc", args.dvrk_kinematic_gc.as_deref()),
        ],
        &[],
        &inputs(&args),
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
    // The template first: an unreadable one is the first error, before any export is
    // computed.
    let template = match &args.urdf {
        Some(_) => urdf_template(args.template.as_deref(), &loaded.robot)?,
        None => None,
    };
    let mut wanted = Vec::new();
    if let Some(out) = &args.urdf {
        let template = template
            .as_ref()
            .map(|(file, text)| UrdfTemplate { text, file });
        wanted.push((out, Export::Urdf { template }));
    }
    if let Some(out) = &args.wpi_json {
        wanted.push((out, Export::WpiParams));
    }
    if let Some(out) = &args.dvrk_gc {
        let points = args.gc_points;
        wanted.push((out, Export::DvrkGc { points }));
    }
    if let Some(out) = &args.dvrk_kinematic_gc {
        let endoscope = args.endoscope.as_deref();
        wanted.push((out, Export::DvrkKinematicGc { endoscope }));
    }
    // Everything is built before anything is written: an error leaves no output.
    let mut built = Vec::new();
    for (out, export) in wanted {
        let exported = export
            .build_for(&loaded.model, &loaded.params, &loaded.result)
            .with_context(|| failure(&export, &loaded, &args.result))?;
        built.push((out, exported));
    }
    let mut report = String::new();
    let mut outputs = Outputs::protecting(inputs(&args));
    for (out, e) in &built {
        outputs.add(Path::new(out), e.document.to_text())?;
        report += &format!("wrote {out}: {}\n{}", e.what, e.details);
    }
    outputs.commit()?;
    for (out, e) in &built {
        for line in &e.undetermined {
            super::warn(format_args!("{out}: {line}"));
        }
    }
    emit_summary(&report, stdout_taken)
}

/// The template URDF and its text: `--template`, else the robot's own URDF when it was
/// loaded from one; `None` to generate one.
fn urdf_template(template: Option<&str>, robot: &str) -> Result<Option<(String, String)>> {
    let Some(path) = template.map(str::to_string).or_else(|| robot_urdf(robot)) else {
        return Ok(None);
    };
    let text = dvrk_model::input::read_text(Path::new(&path))
        .with_context(|| format!("{path}: cannot read"))?;
    Ok(Some((path, text)))
}

/// What a failed export says: the result file, the format, and for a URDF of a
/// least-squares fit why its links are no rigid bodies and what would be.
fn failure(export: &Export, loaded: &LoadedResult, result: &str) -> String {
    let method = &loaded.result.method;
    // Both hold rigid bodies, which a least-squares fit's link parameters are not.
    let hint = if method == "sdp" {
        String::new()
    } else {
        format!(
            " (this {method} fit identifies the base parameters only, its link \
             parameters are a representative, not rigid bodies; `dvrk-ident fit \
             --method sdp` gives physically consistent ones)"
        )
    };
    match export {
        Export::Urdf { .. } => format!("{result}: cannot export to URDF{hint}"),
        Export::WpiParams => format!("{result}: cannot export the 2019 params.json"),
        Export::DvrkGc { .. } => {
            format!("{result}: cannot export the dVRK gravity compensation{hint}")
        }
        Export::DvrkKinematicGc { .. } => {
            format!("{result}: cannot export the dVRK kinematic gravity compensation")
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
