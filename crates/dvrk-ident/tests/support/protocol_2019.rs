//! The 2019 protocol on the real dVRK measurements (docs/book/src/dvrk.md §5), shared by the
//! acceptance test, the OpenBLAS-reference test of the semidefinite fit and the SDP
//! timing bench, so all three fit exactly the same problems: fit on trajectory "one",
//! test on "two" over the first period, 6th-order zero-phase Butterworth at the cut-offs
//! the 2019 code effectively applied (π·fc: 16.965 Hz PSM, 5.655 Hz MTM) on the motion
//! and the torques, 200 samples trimmed.
#![allow(dead_code)] // each includer uses its own part

use std::path::PathBuf;

use dvrk_ident::log::{self, LogFormat};
use dvrk_ident::signal::{Cutoff, LowPass};
use dvrk_ident::{BoundsSet, FitSettings, JointLog, LinkResult, Method};
use dvrk_model::Model;

/// One robot's protocol.
pub struct Protocol {
    pub robot: &'static str,
    /// Low-pass cut-off (Hz).
    pub cutoff_hz: f64,
    /// Test metrics over the first period of "two" (samples).
    pub window: usize,
}

pub const PSM: Protocol = Protocol {
    robot: "psm",
    cutoff_hz: 16.965,
    window: 1111,
};

pub const MTM: Protocol = Protocol {
    robot: "mtm",
    cutoff_hz: 5.655,
    window: 2000,
};

/// A file of `../shared/data/dvrk`, or `None` after a counted skip when the shared
/// folder is not beside the repository.
pub fn data(rel: &str) -> Option<PathBuf> {
    dvrk_test_support::shared(&format!("data/dvrk/{rel}"))
}

/// The robot and its training ("one") and test ("two") logs, `None` (skipped) without
/// `../shared`.
pub fn load(protocol: &Protocol) -> Option<(Model, JointLog, JointLog)> {
    let one = data(&format!("{}/one_results.csv", protocol.robot))?;
    let two = data(&format!("{}/two_results.csv", protocol.robot))?;
    let model = Model::builtin(protocol.robot).unwrap();
    let train = log::read(&one, Some(LogFormat::Wpi), Some(200.0)).unwrap();
    let test = log::read(&two, Some(LogFormat::Wpi), Some(200.0)).unwrap();
    Some((model, train, test))
}

/// The protocol's processing alone (the 6th-order filter at its cut-off on the motion
/// and the torques, the test window), the rest the defaults: the base the command
/// line's `--cutoff C --filter-torque --test-window N` gives, for `--preset dvrk`.
pub fn processing(protocol: &Protocol) -> FitSettings {
    let mut s = FitSettings {
        test_window: Some(protocol.window),
        ..FitSettings::default()
    };
    s.processing.filter = Some(LowPass {
        cutoff_hz: Cutoff::All(protocol.cutoff_hz),
        ..LowPass::default()
    });
    s.processing.filter_torque = true;
    s
}

/// Whether a fitted link's mass sits on one of its description's mass bounds: within
/// 0.1 % of the bounds' range (looser than `parameter_status`'s 1e-5 of the bound, so
/// that a mass a hair inside a bound counts as held by it).
pub fn mass_on_bound(model: &Model, link: &LinkResult) -> bool {
    let [lo, hi] = model.frame(link.frame).bounds.mass.unwrap();
    [lo, hi]
        .iter()
        .any(|b| (link.mass - b).abs() <= 1e-3 * (hi - lo))
}

/// The fit settings of the protocol for `method`, with the 2019 lower bounds
/// (Fc, Fv, Ia ≥ 0.001) and, as in 2019, without the links' bounding ellipsoids
/// (`--no-ellipsoids`: the MTM's cost its 2019-bounds SDP 0.014 on joint 3).
pub fn settings(protocol: &Protocol, method: Method) -> FitSettings {
    FitSettings {
        method,
        bounds: Some(BoundsSet::Wang2019),
        ellipsoids: false,
        ..processing(protocol)
    }
}

/// What helped beyond the 2019 models: a Stribeck term (vs = 0.3 rad/s or m/s) on every
/// friction element, and the physical lower bounds (Fc, Fv ≥ 0, Ia ≥ 1e-6: the 2019 bounds of
/// 0.001 exceed what the wrist data support), with `method`'s protocol settings.
pub fn stribeck_settings(protocol: &Protocol, method: Method) -> FitSettings {
    let mut s = settings(protocol, method);
    s.stribeck_velocity = Some(0.3);
    s.bounds = Some(BoundsSet::Physical);
    s
}

/// `model` with zero lower bounds on Fc, Fv and Ia: the problem the OpenBLAS reference
/// of the semidefinite fit was recorded on (`tests/sdp_reference.rs`; the physical set
/// keeps `Ia ≥ 1e-6`).
pub fn zero_lower_bounds(model: &Model) -> Model {
    let mut relaxed = model.clone();
    relaxed.bounds.fc_min = 0.0;
    relaxed.bounds.fv_min = 0.0;
    relaxed.bounds.ia_min = 0.0;
    relaxed
}

/// The acceptance fit of issue 14: the semidefinite fit with the description's default
/// (physical) bounds and bounding ellipsoids, a Stribeck term (vs = 0.3) and the
/// torques' measurement delays estimated (`--delay auto`), with the protocol's
/// processing: `--preset dvrk`.
pub fn delay_settings(protocol: &Protocol) -> FitSettings {
    let mut s = settings(protocol, Method::Sdp);
    s.bounds = None;
    s.ellipsoids = true;
    s.stribeck_velocity = Some(0.3);
    s.delay_search_s = Some(dvrk_ident::DEFAULT_MAX_DELAY_S);
    s
}

/// The two semidefinite fits of the protocol: `(label, model, settings)` with the 2019
/// bounds, and with a Stribeck term and zero lower bounds.
pub fn sdp_variants(protocol: &Protocol, model: &Model) -> [(&'static str, Model, FitSettings); 2] {
    [
        ("SDP", model.clone(), settings(protocol, Method::Sdp)),
        (
            "SDP + Stribeck, zero lower bounds",
            zero_lower_bounds(model),
            FitSettings {
                bounds: None,
                ..stribeck_settings(protocol, Method::Sdp)
            },
        ),
    ]
}
