//! `dvrk-ident cable-fit SWEEP.csv --degree 7`: a known-force polynomial from a slow
//! sweep in both directions (the MTM joint-4 cable).

use anyhow::{Context, Result};
use dvrk_ident::cable::{fit_cable, CableSettings};

use super::emit;

#[derive(clap::Args)]
pub struct Args {
    /// Sweep file: rows of `position, velocity, effort` (no header), one way then back
    pub sweep: String,
    /// Polynomial degree
    #[arg(long, default_value_t = 7)]
    pub degree: usize,
    /// Samples dropped at the start and end of each half
    #[arg(long, default_value_t = 100)]
    pub drop: usize,
    /// Print JSON
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: Args) -> Result<()> {
    let text = std::fs::read_to_string(&args.sweep)
        .with_context(|| format!("{}: cannot read", args.sweep))?;
    let (mut q, mut tau) = (Vec::new(), Vec::new());
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
        let num = |s: &str| {
            s.trim().parse::<f64>().with_context(|| {
                format!("{}:{}: `{}` is not a number", args.sweep, i + 1, s.trim())
            })
        };
        q.push(num(cols[0])?);
        tau.push(num(cols[2])?);
    }
    let fit = fit_cable(
        &q,
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
