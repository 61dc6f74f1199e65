//! Solve time of the semidefinite fit on the real PSM and MTM data (the 2019 protocol,
//! both SDP variants of `tests/support/protocol_2019.rs`), to compare Clarabel's dense
//! linear algebra providers (the system OpenBLAS before, the crate's Fortran-ABI layer
//! over faer now).
//!
//! `cargo bench -p dvrk-ident --bench sdp [-- RUNS]` (a plain timing binary; default 5
//! runs). The observation (the R factor) is built once per problem; each run times one
//! `solve_sdp` call (building the conic problem and solving it), as `solver.seconds` of
//! a fit does. Prints every run, the median, the status and the iterations; needs
//! `../shared` beside the repository.

#[path = "../tests/support/protocol_2019.rs"]
mod protocol_2019;

use dvrk_ident::estimate::sdp::{solve_sdp, SdpOptions};
use dvrk_ident::fit::{prepare, range_weights};
use dvrk_ident::observation::Observation;
use dvrk_ident::progress::Silent;

fn main() {
    // `cargo bench` passes `--bench`; the first other argument is the number of runs.
    let runs: usize = std::env::args()
        .skip(1)
        .find(|a| !a.starts_with("--"))
        .map_or(5, |a| {
            a.parse()
                .ok()
                .filter(|&r: &usize| r > 0)
                .expect("RUNS: a positive integer")
        });
    for protocol in [&protocol_2019::PSM, &protocol_2019::MTM] {
        let Some((model, train, _)) = protocol_2019::load(protocol) else {
            return;
        };
        for (label, m, settings) in protocol_2019::sdp_variants(protocol, &model) {
            let m = settings.model(&m).expect("model of the settings");
            let data = prepare(&m, &train, &settings.processing).expect("processing");
            let parts = Observation::assemble_per_coordinate(&m, data.samples(), &Silent);
            let obs = Observation::weighted(&parts, &range_weights(&data));
            let options = SdpOptions {
                regularization: settings.sdp_regularization,
                ..SdpOptions::default()
            };
            let mut ms = Vec::with_capacity(runs);
            let mut last = None;
            for _ in 0..runs {
                let sol = solve_sdp(&m, obs.r(), &options).expect("SDP input");
                ms.push(sol.seconds * 1e3);
                last = Some(sol);
            }
            let sol = last.expect("at least one run");
            let mut sorted = ms.clone();
            sorted.sort_by(f64::total_cmp);
            println!(
                "{} {label}: {} in {} iterations; median {:.1} ms, runs {} ms",
                protocol.robot,
                sol.status,
                sol.iterations,
                sorted[sorted.len() / 2],
                ms.iter()
                    .map(|t| format!("{t:.1}"))
                    .collect::<Vec<_>>()
                    .join(" ")
            );
        }
    }
}
