//! `dvrk-ident model ROBOT`: summary, regressor and inverse dynamics of a model.

use anyhow::{bail, Context, Result};
use dvrk_ident::report::draw::kinematic_drawing;
use dvrk_ident::report::write_figure;
use dvrk_model::{Model, Workspace};
use serde_json::json;

use std::fmt::Write as _;

use super::args::{MountingArgs, OUTPUT};
use super::{emit, parse_vector, read_params};

/// The heading of the regressor and torque evaluation's flags.
const EVALUATION: &str = "Evaluation";

#[derive(clap::Args)]
// A negative number is a value (`--f0 -1`, `--rate -5`), refused by the checks with a
// message, not an unknown flag.
#[command(allow_negative_numbers = true)]
pub struct Args {
    /// Built-in robot (psm, psm_simplified, mtm, ecm, psm_si, psm_si_tool, ecm_si) or a path to a .toml description or .urdf
    pub robot: String,
    #[command(flatten)]
    pub mounting: MountingArgs,
    /// Print JSON instead of text
    #[arg(long, help_heading = OUTPUT)]
    pub json: bool,
    /// Print the regressor at --q/--dq/--ddq as JSON {"parameters": [...], "rows": [...]}
    #[arg(long, conflicts_with = "torque", help_heading = EVALUATION)]
    pub regressor: bool,
    /// With --regressor: the base regressor (columns = base parameters)
    #[arg(long, requires = "regressor", help_heading = EVALUATION)]
    pub base: bool,
    /// Print the inverse-dynamics torque at --q/--dq/--ddq as JSON {"tau": [...]}
    #[arg(long, help_heading = EVALUATION)]
    pub torque: bool,
    /// Coordinates (rad, m), comma-separated, model order
    #[arg(long, allow_hyphen_values = true, help_heading = EVALUATION)]
    pub q: Option<String>,
    /// Velocities (rad/s, m/s), comma-separated, model order [default: zeros]
    #[arg(long, allow_hyphen_values = true, help_heading = EVALUATION)]
    pub dq: Option<String>,
    /// Accelerations (rad/s², m/s²), comma-separated, model order [default: zeros]
    #[arg(long, allow_hyphen_values = true, help_heading = EVALUATION)]
    pub ddq: Option<String>,
    /// Draw the kinematic tree at --q (at zeros without it) into --out (.svg or .png)
    #[arg(long, requires = "out", conflicts_with_all = ["regressor", "torque", "json"], help_heading = OUTPUT)]
    pub draw: bool,
    /// Output figure of --draw
    #[arg(long, requires = "draw", help_heading = OUTPUT)]
    pub out: Option<String>,
    /// Parameter file for --torque (JSON {name: value} or a result file) [default: the
    /// description's nominal parameters]
    #[arg(long, help_heading = EVALUATION)]
    pub params: Option<String>,
}

pub fn run(args: Args) -> Result<()> {
    let mut model = Model::load(&args.robot)?;
    args.mounting.apply(&mut model)?;
    if args.draw {
        return draw(&model, &args);
    }
    if args.regressor || args.torque {
        return evaluate(&model, &args);
    }
    let base = model
        .base_parameters()
        .with_context(|| format!("{}: base parameters", args.robot))?;
    let summary = model.summary(&base);
    if args.json {
        return emit(&serde_json::to_string_pretty(&summary)?);
    }
    let mut out = String::new();
    writeln!(out, "robot {} ({})", summary.name, summary.source)?;
    writeln!(
        out,
        "{} coordinates: {}",
        summary.coordinates.len(),
        summary.coordinates.join(" ")
    )?;
    writeln!(
        out,
        "measured joints: {}",
        summary.measured_joints.join(" ")
    )?;
    let [gx, gy, gz] = summary.gravity;
    writeln!(out, "gravity (base frame): {gx} {gy} {gz} m/s²")?;
    writeln!(out, "{} frames:", summary.frames.len())?;
    for f in &summary.frames {
        writeln!(
            out,
            "  {:>2} {:<28} parent {:>2}  {:<9} {:<36} {}",
            f.index,
            f.name,
            f.parent,
            f.joint,
            f.value,
            f.elements.join(",")
        )?;
    }
    writeln!(
        out,
        "{} parameters: {}",
        summary.parameters.len(),
        summary.parameters.join(" ")
    )?;
    writeln!(out, "{} base parameters:", summary.base_parameters.len())?;
    for (i, e) in summary.base_parameters.iter().enumerate() {
        writeln!(out, "  {:>3} {e}", i + 1)?;
    }
    emit(&out)
}

fn draw(model: &Model, args: &Args) -> Result<()> {
    let q = match &args.q {
        Some(q) => parse_vector(q, model.dof(), "--q")?,
        None => vec![0.0; model.dof()],
    };
    let out = args.out.as_deref().context("--draw needs --out")?;
    let inputs = super::inputs(&[], &[("the robot", Some(&args.robot))]);
    let stdout_taken = super::check_outputs(&[("--out", Some(out))], &[], &inputs)?;
    let drawing = kinematic_drawing(model, &q)?;
    write_figure(&drawing, std::path::Path::new(out))?;
    super::emit_summary(out, stdout_taken)
}

fn evaluate(model: &Model, args: &Args) -> Result<()> {
    let n = model.dof();
    let Some(q) = &args.q else {
        bail!("--regressor and --torque need --q");
    };
    let q = parse_vector(q, n, "--q")?;
    let optional = |text: &Option<String>, flag: &str| match text {
        Some(t) => parse_vector(t, n, flag),
        None => Ok(vec![0.0; n]),
    };
    let dq = optional(&args.dq, "--dq")?;
    let ddq = optional(&args.ddq, "--ddq")?;
    if args.regressor {
        let h = model.regressor(&mut Workspace::new(model), &q, &dq, &ddq);
        let (names, h) = if args.base {
            let base = model.base_parameters()?;
            (
                base.expressions.clone(),
                h.select_columns(&base.independent),
            )
        } else {
            (model.param_names(), h)
        };
        if h.iter().any(|x| !x.is_finite()) {
            bail!("the regressor at these coordinates overflows (not finite): smaller --q, --dq, --ddq");
        }
        let rows: Vec<Vec<f64>> = (0..h.nrows())
            .map(|r| h.row(r).iter().copied().collect())
            .collect();
        return emit(&json!({"parameters": names, "rows": rows}).to_string());
    }
    let (model, params) = read_params(model, args.params.as_deref().unwrap_or("nominal"))?;
    // A result with Stribeck terms has more parameters, and its own workspace.
    let mut ws = Workspace::new(&model);
    let mut tau = vec![0.0; n];
    // Load friction (a result fitted with --load-friction) with its load predicted, as
    // the fit's metrics and the C library do.
    model.loaded_inverse_dynamics(&mut ws, &params, &q, &dq, &ddq, &mut tau);
    if let Some(t) = tau.iter().find(|t| !t.is_finite()) {
        bail!("the torque at these coordinates is {t}: the parameters and motion overflow");
    }
    emit(&json!({ "tau": tau }).to_string())
}
