//! Runtime of `excite` on the acceptance problems: PSM (psm_simplified) and MTM with the
//! 2019 limits, order 6, the 2019 base frequencies (0.18 Hz, 0.1 Hz), default options,
//! seed 0. The goal is under 2 minutes each on a 2-core machine.
//!
//! `cargo bench -p dvrk-ident --bench excite` (a plain timing binary: one optimization
//! takes tens of seconds, too long for criterion's repeated sampling). Prints the wall
//! time, the criterion and the dense check of each run, and the 2019 trajectory's
//! criterion when `../shared` is beside the repository.

use std::time::Instant;

use dvrk_ident::excite::optimize::{self, Criterion, ExciteOptions, Limits};
use dvrk_ident::excite::FourierTrajectory;
use dvrk_ident::Silent;
use dvrk_model::Model;

const WPI2019: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../../shared/anchors/wpi2019_excitation_trajectories.json"
);

fn main() {
    // `cargo bench` passes `--bench`; a name filter may follow.
    let filter: Option<String> = std::env::args().skip(1).find(|a| !a.starts_with("--"));
    for (robot, pick, f0) in [("psm_simplified", "psm_one", 0.18), ("mtm", "mtm_one", 0.1)] {
        if filter.as_deref().is_some_and(|f| !robot.contains(f)) {
            continue;
        }
        let model = Model::builtin(robot).expect("built-in robot");
        let base = model.base_parameters().expect("base parameters");
        let limits = Limits::of_model(&model);
        let opts = ExciteOptions {
            order: 6,
            base_frequency_hz: f0,
            ..ExciteOptions::default()
        };
        let started = Instant::now();
        let result = optimize::optimize(&model, &base, &limits, &opts, &Silent);
        let seconds = started.elapsed().as_secs_f64();
        let reference = FourierTrajectory::from_wpi_file(WPI2019, pick)
            .ok()
            .and_then(|old| {
                optimize::evaluate(
                    &model,
                    &base,
                    &old,
                    &limits,
                    Criterion::Condition,
                    opts.samples_per_harmonic,
                    opts.check_rate_hz,
                )
                .ok()
            })
            .map_or("../shared absent".to_string(), |ev| {
                format!(
                    "{pick} {:.3} (feasible {})",
                    ev.criterion.value, ev.feasibility.feasible
                )
            });
        match result {
            Ok(r) => println!(
                "excite {robot:<15} {seconds:7.1} s  condition {:.3}  feasible {} on {} samples  \
                 (goal < 120 s: {}); 2019: {reference}",
                r.evaluation.criterion.value,
                r.evaluation.feasibility.feasible,
                r.evaluation.feasibility.samples,
                if seconds < 120.0 { "met" } else { "MISSED" },
            ),
            Err(e) => println!("excite {robot:<15} {seconds:7.1} s  failed: {e}"),
        }
    }
}
