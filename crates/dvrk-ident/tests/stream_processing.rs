//! Processing a log block by block gives the whole-log processing: every variant of the
//! settings, blocks from one sample to more than the log, a long synthetic signal with
//! friction-like steps, noise and several frequencies.

#[path = "support/logs.rs"]
mod logs;

use dvrk_ident::signal::process_in_blocks;
use dvrk_ident::signal::{
    process, AccelerationSource, Cutoff, LowPass, Processed, Processing, SignalError, Stencil,
};
use dvrk_ident::{Coordinates, JointLog, JointLogError};
use dvrk_logs::uniform_time;
use logs::worst_relative;
use nalgebra::DMatrix;

/// 3 joints, `n` samples at 200 Hz: slow and fast sines, a square wave and noise.
fn synthetic(n: usize, with_dq: bool) -> JointLog {
    let time = uniform_time(n, 200.0);
    let mut rng = dvrk_test_support::Rng::new(0x9E37_79B9_7F4A_7C15);
    let mut noise = move || rng.uniform(-0.5, 0.5);
    let q = DMatrix::from_fn(n, 3, |i, j| {
        let t = time[i];
        (0.4 + 0.3 * j as f64) * (1.1 * t + j as f64).sin() + 0.05 * (13.0 * t).cos()
    });
    let dq = DMatrix::from_fn(n, 3, |i, j| {
        let t = time[i];
        (0.4 + 0.3 * j as f64) * 1.1 * (1.1 * t + j as f64).cos() + 0.01 * noise()
    });
    let tau = DMatrix::from_fn(n, 3, |i, j| {
        let t = time[i];
        let step = if (t * (0.7 + 0.2 * j as f64)).sin() > 0.0 {
            0.3
        } else {
            -0.3
        };
        2.0 * (0.9 * t).cos() + step + 0.02 * noise()
    });
    JointLog {
        time,
        q,
        dq: with_dq.then_some(dq),
        tau,
        joint_names: vec!["a".into(), "b".into(), "c".into()],
        coordinates: Coordinates::Model,
        source: "synthetic".into(),
    }
}

fn block(log: &JointLog, start: usize, len: usize) -> JointLog {
    log.select_rows(&(start..start + len).collect::<Vec<_>>())
}

fn blocks(log: &JointLog, size: usize) -> Vec<JointLog> {
    (0..log.len())
        .step_by(size)
        .map(|s| block(log, s, size.min(log.len() - s)))
        .collect()
}

/// The streamed processing of `log` in blocks of `size`, concatenated.
fn streamed(log: &JointLog, settings: &Processing, size: usize) -> Result<Processed, SignalError> {
    process_in_blocks(&blocks(log, size), settings)
}

fn variants() -> Vec<(&'static str, Processing, bool)> {
    let base = Processing::default();
    vec![
        ("default", base.clone(), true),
        ("no velocity", base.clone(), false),
        (
            "torques filtered, filtered-velocity accelerations, 3-point",
            Processing {
                filter_torque: true,
                acceleration_from: AccelerationSource::FilteredVelocity,
                velocity_stencil: Stencil::ThreePoint,
                acceleration_stencil: Stencil::ThreePoint,
                ..base.clone()
            },
            true,
        ),
        ("2019 (b, a), padlen 20", Processing::wpi(1.8), true),
        (
            "per-joint cut-offs, decimate 7, min speed",
            Processing {
                filter: Some(LowPass {
                    cutoff_hz: Cutoff::PerJoint(vec![2.0, 5.4, 11.0]),
                    ..LowPass::default()
                }),
                decimate: 7,
                min_speed: Some(0.05),
                trim: 33,
                ..base.clone()
            },
            true,
        ),
        (
            "resampled to 150 Hz",
            Processing {
                resample_hz: Some(150.0),
                ..base.clone()
            },
            true,
        ),
        (
            "no filter, no trim",
            Processing {
                filter: None,
                trim: 0,
                ..base
            },
            false,
        ),
    ]
}

#[test]
fn streamed_processing_equals_whole_log_processing() {
    let n = 30_000;
    for (name, settings, with_dq) in variants() {
        let log = synthetic(n, with_dq);
        let whole = process(&log, &settings).unwrap();
        let mut worst: f64 = 0.0;
        for size in [1, 7, 500, 4096, n + 1] {
            let s = streamed(&log, &settings, size).unwrap();
            assert_eq!(s.time, whole.time, "{name}, blocks of {size}: kept samples");
            assert_eq!(s.rate_hz, whole.rate_hz);
            let e = worst_relative(&s, &whole);
            assert!(e < 1e-9, "{name}, blocks of {size}: {e:e}");
            worst = worst.max(e);
        }
        println!("{name}: worst relative difference {worst:.1e}");
    }
}

#[test]
fn streamed_errors_are_the_whole_log_errors() {
    let log = synthetic(1000, true);
    let cases: Vec<(Processing, JointLog)> = vec![
        (
            Processing {
                trim: 500,
                ..Processing::default()
            },
            log.clone(),
        ),
        (
            Processing {
                decimate: 0,
                ..Processing::default()
            },
            log.clone(),
        ),
        (
            Processing {
                filter: Some(LowPass {
                    cutoff_hz: Cutoff::PerJoint(vec![5.0, 150.0, 5.0]),
                    ..LowPass::default()
                }),
                ..Processing::default()
            },
            log.clone(),
        ),
        (
            Processing {
                trim: 5,
                ..Processing::default()
            },
            block(&log, 0, 20),
        ),
        (
            Processing {
                min_speed: Some(100.0),
                ..Processing::default()
            },
            log.clone(),
        ),
    ];
    for (settings, t) in cases {
        let whole = process(&t, &settings).unwrap_err();
        for size in [1, 64, 5000] {
            let s = streamed(&t, &settings, size).unwrap_err();
            assert_eq!(s, whole, "blocks of {size}");
        }
        println!("{whole}");
    }
    // A gap, a NaN: named at the same sample.
    let mut gap = log.clone();
    for t in &mut gap.time[600..] {
        *t += 0.02;
    }
    let mut nan = log.clone();
    nan.tau[(777, 2)] = f64::NAN;
    for t in [gap, nan] {
        let whole = process(&t, &Processing::default()).unwrap_err();
        assert!(matches!(
            whole,
            SignalError::JointLog(
                JointLogError::NonUniform { row: 600, .. }
                    | JointLogError::NonFinite { row: 777, .. }
            )
        ));
        // (Debug text: NaN values are not equal to themselves.)
        for size in [1, 100, 5000] {
            let s = streamed(&t, &Processing::default(), size).unwrap_err();
            assert_eq!(format!("{s:?}"), format!("{whole:?}"));
        }
    }
}
