//! `dvrk-ident payload RESULT LOG... --frame NAME`: a rigid payload fixed to a frame,
//! estimated from logs of the arm carrying it with the rest of the model held at the
//! result; the computation is `dvrk_ident::payload`.

use std::fmt::Write as _;
use std::path::Path;

use anyhow::Result;
use dvrk_ident::payload::identify_payload;
use dvrk_logs::output::Outputs;
use serde_json::json;

use super::args::{MODEL, OUTPUT};
use super::settings::ResultOnLogs;
use super::{emit_summary, LoadedResult};

#[derive(clap::Args)]
#[command(
    allow_negative_numbers = true,
    mut_args = super::args::result_defaults,
    mut_arg("result", |a| a.help(
        "Result file written by `dvrk-ident fit --out`, of the arm without the payload"
    )),
    mut_arg("logs", |a| a.help("Logs of the arm carrying the payload"))
)]
pub struct Args {
    /// The frame the payload is fixed to (a frame with link parameters)
    #[arg(long, value_name = "NAME", help_heading = MODEL)]
    pub frame: String,
    #[command(flatten)]
    pub on_logs: ResultOnLogs,
    /// Write the result with the payload added (a `payload` section: validate, residual,
    /// report and export then use the arm with its load)
    #[arg(long, value_name = "FILE.json", help_heading = OUTPUT)]
    pub out: Option<String>,
    /// Print JSON
    #[arg(long, help_heading = OUTPUT)]
    pub json: bool,
}

pub fn run(args: Args) -> Result<()> {
    let stdout_taken = super::check_outputs(
        &[("--out", args.out.as_deref())],
        &[],
        &args.on_logs.inputs(&[]),
    )?;
    let LoadedResult {
        result,
        model,
        params,
        ..
    } = args.on_logs.load_with_settings()?;
    // The frame before the logs: a wrong name is told without reading them.
    model.payload_model(&args.frame, "--frame")?;
    let read = args
        .on_logs
        .read_options(&model, &result.settings.processing);
    let logs = args
        .on_logs
        .logs
        .iter()
        .map(|path| super::args::read(&read, path))
        .collect::<Result<Vec<_>>>()?;
    let estimate = identify_payload(&model, &params, &result, &logs, &args.frame)?;
    let (p, id) = (&estimate.payload, &estimate.identification);
    let mut outputs = Outputs::new();
    if let Some(out) = &args.out {
        outputs.add(Path::new(out), estimate.applied_to(&result).to_json())?;
    }
    outputs.commit()?;
    if args.json {
        return emit_summary(
            &serde_json::to_string_pretty(&json!({
                "result": args.on_logs.result,
                "payload": p,
                "identification": id,
            }))?,
            stdout_taken,
        );
    }
    let mut text = String::new();
    let d = id.determined;
    let shown = |ok: bool, value: String, std: Option<String>| match (ok, std) {
        (true, Some(s)) => format!("{value} ± {s}"),
        _ => format!("{value} (not determined by these logs)"),
    };
    let v3 = |v: &[f64]| {
        v.iter()
            .map(|x| format!("{x:.5}"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let _ = writeln!(
        text,
        "payload on frame {} from {} samples of {} log(s)",
        p.frame,
        id.samples,
        id.logs.len()
    );
    let _ = writeln!(
        text,
        "  mass            {}",
        shown(
            d.mass,
            format!("{:.5} kg", p.mass),
            id.std.mass.map(|s| format!("{s:.5} kg"))
        )
    );
    let _ = writeln!(
        text,
        "  centre of mass  {}",
        shown(
            d.com(),
            format!("[{}] m", v3(&p.com)),
            id.std.com.map(|s| format!("[{}] m", v3(&s)))
        )
    );
    let _ = writeln!(
        text,
        "  inertia (com)   {}",
        shown(
            d.inertia_com(),
            format!("[{}] kg·m² (xx yy zz xy xz yz)", v3(&p.inertia)),
            id.std.inertia.map(|s| format!("[{}]", v3(&s)))
        )
    );
    if !(d.mass && d.first_moment && d.inertia) {
        let (yes, no): (Vec<_>, Vec<_>) = id
            .parameter_status
            .iter()
            .partition(|(_, s)| s.identified());
        let names = |v: Vec<(&String, _)>| {
            v.into_iter()
                .map(|(k, _)| k.as_str())
                .collect::<Vec<_>>()
                .join(" ")
        };
        let _ = writeln!(
            text,
            "  these logs determine {}; not {} (set by physical consistency, not by the data)",
            names(yes),
            names(no)
        );
    }
    let width = super::joint_width(&id.coordinates);
    let _ = writeln!(
        text,
        "{:<width$} {:>14} {:>14}",
        "RMS", "without", "with payload"
    );
    for (j, name) in id.coordinates.iter().enumerate() {
        let _ = writeln!(
            text,
            "{name:<width$} {:>14.5} {:>14.5}",
            id.rms_without[j], id.rms_with[j]
        );
    }
    emit_summary(&text, stdout_taken)
}
