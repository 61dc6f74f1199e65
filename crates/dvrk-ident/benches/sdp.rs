//! Solve time of the semidefinite fit on the real PSM and MTM data (the 2019 protocol,
//! both SDP variants of `tests/support/protocol_2019.rs`), to compare Clarabel's dense
//! linear algebra providers (the system OpenBLAS before, the crate's Fortran-ABI layer
//! over faer now).
//!
//! `cargo bench -p dvrk-ident --bench sdp [-- RUNS]` (a plain timing binary; default 5
//! runs). Each run is a whole fit through the public request ([`FitRequest`]) and prints
//! the solver's own time (`solver.seconds` of the result: building the conic problem and
//! solving it, with the options the fit derives from its settings), so the processing
//! and the reduction of the log, repeated every run, are not counted. Prints every run,
//! the median, the status and the iterations; needs `../shared` beside the repository.
//! (Until 2026-11-28 the bench called the solver on an R factor of its own with default
//! options but the regularization; its figures are not comparable with these.)

#[path = "../tests/support/protocol_2019.rs"]
mod protocol_2019;

use dvrk_ident::{FitRequest, Silent};

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
            let request = FitRequest::of_samples([&train], None, settings);
            let mut ms = Vec::with_capacity(runs);
            let mut last = None;
            for _ in 0..runs {
                let fit = request.run(Some(&m), &Silent).expect("the fit");
                let sol = fit.result.solver;
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
