//! Logs read block by block ([`LogReader`]) give the whole log whatever the block size,
//! for the CSV layouts (with and without `--resample`), and name bad rows by their line
//! in the file wherever the block boundaries fall.

#[path = "support/logs.rs"]
mod logs;

use dvrk_logs::log::{write, LogError, LogFormat, LogReader, ReadOptions};
use dvrk_logs::{uniform_time, Coordinates, JointLog};
use logs::concatenate;
use nalgebra::DMatrix;
use std::path::PathBuf;

fn temp(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("dvrk-ident-blocks-{}-{name}", std::process::id()))
}

fn log(n: usize, with_dq: bool, coordinates: Coordinates) -> JointLog {
    let time = uniform_time(n, 200.0);
    JointLog {
        q: DMatrix::from_fn(n, 3, |i, j| (0.01 * i as f64 + j as f64).sin()),
        dq: with_dq.then(|| DMatrix::from_fn(n, 3, |i, j| (0.02 * i as f64 - j as f64).cos())),
        tau: DMatrix::from_fn(n, 3, |i, j| (i % 17) as f64 * 0.1 - j as f64),
        time,
        // A headered CSV tells model coordinates by the names q1..qn.
        joint_names: match coordinates {
            Coordinates::Model => ["q1", "q2", "q3"],
            Coordinates::Measured => ["yaw", "pitch", "insertion"],
        }
        .map(String::from)
        .to_vec(),
        coordinates,
        source: "test".into(),
    }
}

/// The log read by `reader` in blocks of `size`, joined back.
fn read_blocks(reader: &LogReader, size: usize) -> JointLog {
    let blocks: Vec<JointLog> = reader.blocks(size).unwrap().map(|b| b.unwrap()).collect();
    concatenate(&blocks)
}

#[test]
fn blocks_of_any_size_are_the_whole_log() {
    let cases = [
        (
            "wpi.csv",
            LogFormat::Wpi,
            log(3001, true, Coordinates::Model),
        ),
        (
            "csv.csv",
            LogFormat::Csv,
            log(3001, true, Coordinates::Measured),
        ),
        (
            "nodq.csv",
            LogFormat::Csv,
            log(2500, false, Coordinates::Model),
        ),
    ];
    for (name, format, log) in cases {
        let path = temp(name);
        write(&path, &log, format).unwrap();
        for resample_hz in [None, Some(130.0)] {
            let opts = ReadOptions {
                resample_hz,
                ..ReadOptions::default()
            };
            // The rate only for the layout without time stamps: the others refuse it.
            let rate_hz = (format == LogFormat::Wpi).then_some(200.0);
            let whole = ReadOptions {
                rate_hz,
                ..opts.clone()
            }
            .read(&path)
            .unwrap();
            if resample_hz.is_none() {
                assert_eq!((&whole.q, &whole.tau), (&log.q, &log.tau));
            } else {
                whole.check_uniform(1e-9).unwrap();
            }
            let reader = ReadOptions {
                rate_hz,
                ..opts.clone()
            }
            .open(&path)
            .unwrap();
            assert_eq!(reader.format(), format);
            assert_eq!(reader.joint_names(), &whole.joint_names[..]);
            assert_eq!(reader.coordinates(), log.coordinates);
            assert_eq!(reader.has_velocity(), log.dq.is_some());
            for size in [1, 7, 4000] {
                assert_eq!(read_blocks(&reader, size), whole, "{name} blocks of {size}");
            }
        }
        std::fs::remove_file(&path).unwrap();
    }
}

#[test]
fn bad_rows_are_named_by_line_in_any_block() {
    let path = temp("bad.csv");
    // Header on line 1, sample k on line k + 2: sample 56 repeats sample 55's time, and
    // sample 60 is NaN (after it, so the time is the first problem).
    let mut text = String::from("time,position.a,velocity.a,effort.a\n");
    for k in 0..100 {
        let t = if k == 56 { 55 } else { k } as f64 * 0.005;
        let p = if k == 60 {
            "nan".to_string()
        } else {
            format!("{}", k as f64 * 0.1)
        };
        text += &format!("{t},{p},1.0,2.0\n");
    }
    std::fs::write(&path, text).unwrap();
    let opts = ReadOptions::default();
    let whole = opts.read(&path).unwrap_err();
    assert!(
        matches!(whole, LogError::NonMonotonicTime { line: 58, .. }),
        "{whole}"
    );
    let reader = opts.open(&path).unwrap();
    for size in [1, 10, 56, 57, 1000] {
        let e = reader.blocks(size).unwrap().find_map(Result::err).unwrap();
        assert_eq!(e.to_string(), whole.to_string(), "blocks of {size}");
    }
    std::fs::remove_file(&path).unwrap();
    // An empty file and a header without rows.
    let empty = temp("empty.csv");
    std::fs::write(&empty, "# nothing\n").unwrap();
    assert!(matches!(
        opts.open(&empty).unwrap_err(),
        LogError::Empty { .. }
    ));
    std::fs::write(&empty, "time,position.a,effort.a\n").unwrap();
    let reader = opts.open(&empty).unwrap();
    let e = reader.blocks(10).unwrap().next().unwrap().unwrap_err();
    assert!(e.to_string().contains("a header but no data rows"), "{e}");
    std::fs::remove_file(&empty).unwrap();
}
