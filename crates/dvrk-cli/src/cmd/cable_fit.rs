//! `dvrk-ident cable-fit SWEEP.csv --degree 7`: a known-force polynomial from a slow
//! sweep in both directions (the MTM joint-4 cable).

use anyhow::{Context, Result};
use dvrk_ident::Signal;
use dvrk_ident::{fit_cable, CableSettings};

use super::args::{MODEL, OUTPUT, PROCESSING};
use super::emit;

#[derive(clap::Args)]
// A negative number is a value (`--f0 -1`, `--rate -5`), refused by the checks with a
// message, not an unknown flag.
#[command(allow_negative_numbers = true)]
pub struct Args {
    /// Sweep file: rows of `position, velocity, effort` (no header), one way then back
    pub sweep: String,
    /// Polynomial degree
    #[arg(long, default_value_t = 7, help_heading = MODEL)]
    pub degree: usize,
    /// Samples dropped at the start and end of each half
    #[arg(long, default_value_t = 100, help_heading = PROCESSING)]
    pub drop: usize,
    /// Print JSON
    #[arg(long, help_heading = OUTPUT)]
    pub json: bool,
}

pub fn run(args: Args) -> Result<()> {
    let text = dvrk_model::input::read_text(std::path::Path::new(&args.sweep))
        .with_context(|| format!("{}: cannot read", args.sweep))?;
    let (mut q, mut dq, mut tau) = (Vec::new(), Vec::new(), Vec::new());
    for (i, line) in text.lines().enumerate() {
        if line.trim().is_empty() {
            continue;
        }
        let cols: Vec<&str> = line.split(',').collect();
        if cols.len() < 3 {
            anyhow::bail!(
                "{}:{}: expected 3 columns (position, velocity, effort)",
                args.sweep,
                i + 1
            );
        }
        let num = |s: &str, signal: Signal| -> Result<f64> {
            let x = s.trim().parse::<f64>().with_context(|| {
                format!("{}:{}: `{}` is not a number", args.sweep, i + 1, s.trim())
            })?;
            dvrk_model::input::check_magnitude(x, signal.max_magnitude(), signal.unit())
                .map_err(|m| anyhow::anyhow!("{}:{}: {signal}: {m}", args.sweep, i + 1))
        };
        q.push(num(cols[0], Signal::Position)?);
        dq.push(num(cols[1], Signal::Velocity)?);
        tau.push(num(cols[2], Signal::Effort)?);
    }
    let fit = fit_cable(
        &q,
        &dq,
        &tau,
        &CableSettings {
            degree: args.degree,
            drop: args.drop,
        },
        &args.sweep,
    )?;
    if args.json {
        return emit(&serde_json::to_string_pretty(&fit)?);
    }
    let coefs: Vec<String> = fit.polynomial.iter().map(|c| format!("{c:.7e}")).collect();
    emit(&format!(
        "cable torque polynomial (degree {}, highest first), rms residual {:.4} N·m over [{:.3}, {:.3}] rad\n\
         # for the robot description, on the frame whose joint value is the swept coordinate:\n\
         known_force = {{ polynomial = [{}] }}",
        args.degree,
        fit.rms,
        fit.range[0],
        fit.range[1],
        coefs.join(", ")
    ))
}
