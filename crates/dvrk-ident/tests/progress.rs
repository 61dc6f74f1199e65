//! The fit and the excitation optimizer announce their stages and count all their work,
//! so the CLI's bars end at 100 %.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;

use dvrk_ident::excite::optimize::{optimize, ExciteOptions, Limits};
use dvrk_ident::validate::prepare;
use dvrk_ident::Progress;
use dvrk_ident::{FitRequest, FitSettings, Method};
use dvrk_model::Model;

#[derive(Default)]
struct Recorder {
    stages: Mutex<Vec<(String, Option<u64>)>>,
    units: AtomicU64,
    finished: AtomicU64,
}

impl Progress for Recorder {
    fn stage(&self, name: &str, total: Option<u64>) {
        self.stages.lock().unwrap().push((name.into(), total));
    }
    fn advance(&self, units: u64) {
        self.units.fetch_add(units, Ordering::Relaxed);
    }
    fn finish(&self) {
        self.finished.fetch_add(1, Ordering::Relaxed);
    }
}

fn example() -> dvrk_ident::JointLog {
    let path = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples/psm_excitation.mcap");
    dvrk_ident::log::read(path, None, None).unwrap()
}

#[test]
fn fit_counts_every_sample() {
    let model = Model::builtin("psm").unwrap();
    let log = example();
    // One assembly pass for every method: IRLS re-weights the per-coordinate factors.
    for method in [Method::Ols, Method::Irls, Method::Sdp] {
        let mut settings = FitSettings {
            method,
            irls_iterations: 3,
            ..FitSettings::default()
        };
        settings.processing.filter = None;
        let samples = prepare(&model, &log, &settings.processing).unwrap().len() as u64;
        let rec = Recorder::default();
        FitRequest::of_samples([&log], None, settings)
            .run(Some(&model), &rec)
            .unwrap();
        let stages = rec.stages.lock().unwrap().clone();
        let assembling = stages
            .iter()
            .find(|(n, _)| n.starts_with("assembling"))
            .unwrap();
        assert_eq!(assembling.1, Some(samples), "{method:?}");
        assert_eq!(rec.units.load(Ordering::Relaxed), samples);
        assert_eq!(
            stages.iter().any(|(n, _)| n.contains("semidefinite")),
            method == Method::Sdp
        );
        // Every stage ends.
        assert_eq!(rec.finished.load(Ordering::Relaxed), stages.len() as u64);
    }
}

#[test]
fn optimizer_counts_its_starts() {
    let model = Model::builtin("psm_simplified").unwrap();
    let base = model.base_parameters().unwrap();
    let opts = ExciteOptions {
        order: 2,
        base_frequency_hz: 0.2,
        starts: 3,
        refine: 2,
        iterations_per_stage: 5,
        refine_iterations_per_stage: 5,
        ..ExciteOptions::default()
    };
    let rec = Recorder::default();
    optimize(&model, &base, &Limits::of_model(&model), &opts, &rec).unwrap();
    assert_eq!(
        *rec.stages.lock().unwrap(),
        [
            ("exploring starts".to_string(), Some(3)),
            ("refining the best starts".to_string(), Some(2)),
            ("hopping from the best".to_string(), Some(4))
        ]
    );
    assert_eq!(rec.units.load(Ordering::Relaxed), 3 + 2 + 4);
    assert_eq!(rec.finished.load(Ordering::Relaxed), 3);
}
