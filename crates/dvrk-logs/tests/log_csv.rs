//! CSV log readers and writers: round trips, format detection and every error case.

use dvrk_logs::columns::ColumnError;
use dvrk_logs::log::{
    detect_format, read, read_headered, read_wpi, write, write_headered, write_wpi, LogError,
    LogFormat,
};
use dvrk_logs::{uniform_time, Coordinates, JointLog};
use nalgebra::DMatrix;
use std::path::{Path, PathBuf};

/// A fresh directory for one test under cargo's per-target temporary directory.
fn test_dir(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("log_csv-{name}"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn write_file(dir: &Path, name: &str, content: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, content).unwrap();
    p
}

/// Values that stress number formatting: tiny, huge, negative zero, inexact decimals.
fn awkward(i: usize, j: usize) -> f64 {
    let v = [
        0.1 + 0.2,
        -0.0,
        1e-300,
        -2.5e-7,
        123456.789,
        -0.43909142302978293,
        9.99e5, // near the largest magnitude a logged value may have (1e6)
        std::f64::consts::PI,
    ];
    v[(i * 3 + j) % v.len()] * if (i + j) % 2 == 0 { 1.0 } else { -1.0 }
}

fn sample(n: usize, dof: usize, coordinates: Coordinates, with_dq: bool) -> JointLog {
    JointLog {
        time: uniform_time(n, 200.0),
        q: DMatrix::from_fn(n, dof, awkward),
        dq: with_dq.then(|| DMatrix::from_fn(n, dof, |i, j| awkward(i + 1, j))),
        tau: DMatrix::from_fn(n, dof, |i, j| awkward(i + 2, j)),
        joint_names: (1..=dof).map(|j| format!("q{j}")).collect(),
        coordinates,
        source: "test".into(),
    }
}

fn assert_bits_eq(a: &DMatrix<f64>, b: &DMatrix<f64>) {
    assert_eq!(a.shape(), b.shape());
    for (x, y) in a.iter().zip(b.iter()) {
        assert_eq!(x.to_bits(), y.to_bits(), "{x} vs {y}");
    }
}

#[test]
fn wpi_round_trip_is_exact() {
    let dir = test_dir("wpi_round_trip");
    let path = dir.join("traj.csv");
    let t = sample(17, 3, Coordinates::Model, true);
    write_wpi(&path, &t).unwrap();
    let back = read_wpi(&path, 200.0, None).unwrap();
    assert_bits_eq(&back.q, &t.q);
    assert_bits_eq(back.dq.as_ref().unwrap(), t.dq.as_ref().unwrap());
    assert_bits_eq(&back.tau, &t.tau);
    assert_eq!(back.time, t.time);
    assert_eq!(back.joint_names, vec!["q1", "q2", "q3"]);
    assert_eq!(back.coordinates, Coordinates::Model);
    assert_eq!(back.source, path.display().to_string());
    back.validate().unwrap();
    // Forced dof, and format detection through `read`.
    assert_eq!(read_wpi(&path, 200.0, Some(3)).unwrap().dof(), 3);
    assert_eq!(detect_format(&path).unwrap(), LogFormat::Wpi);
    assert_eq!(read(&path, None, Some(200.0)).unwrap(), back);
    // No temporary files left behind.
    let files: Vec<_> = std::fs::read_dir(&dir).unwrap().collect();
    assert_eq!(files.len(), 1);
}

#[test]
fn headered_round_trip_is_exact() {
    let dir = test_dir("headered_round_trip");
    for (coords, with_dq) in [
        (Coordinates::Measured, true),
        (Coordinates::Model, true),
        (Coordinates::Measured, false),
    ] {
        let path = dir.join(format!("{coords}-{with_dq}.csv"));
        let mut t = sample(11, 2, coords, with_dq);
        t.joint_names = vec!["outer.yaw".into(), "jaw, left".into()]; // dots and commas
        t.time = (0..11).map(|k| 1.7e9 + k as f64 * 0.005).collect(); // ROS-like stamps
        write_headered(&path, &t).unwrap();
        // The header is the first line (every CSV reader takes it as the header).
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(text.starts_with("time,position."), "{text}");
        let back = read_headered(&path).unwrap();
        // Model coordinates are told by their names.
        let names = match coords {
            Coordinates::Model => vec!["q1".to_string(), "q2".to_string()],
            Coordinates::Measured => t.joint_names.clone(),
        };
        assert_eq!(back.joint_names, names);
        assert_eq!(back.coordinates, coords);
        assert_eq!(back.time, t.time);
        assert_bits_eq(&back.q, &t.q);
        assert_bits_eq(&back.tau, &t.tau);
        assert_eq!(back.dq.is_some(), with_dq);
        if with_dq {
            assert_bits_eq(back.dq.as_ref().unwrap(), t.dq.as_ref().unwrap());
        }
        assert_eq!(detect_format(&path).unwrap(), LogFormat::Csv);
        assert_eq!(read(&path, None, None).unwrap(), back);
        // `write` dispatches by format.
        write(&path, &t, LogFormat::Csv).unwrap();
        assert_eq!(read_headered(&path).unwrap(), back);
    }
}

#[test]
fn headered_files_of_earlier_versions_still_read() {
    // The development builds before 0.1.0 put the coordinates in a comment line above
    // the header.
    let dir = test_dir("earlier_versions");
    let header = "time,position.a,position.b,effort.a,effort.b\n0,1,2,3,4\n0.005,1,2,3,4\n";
    for (stated, expected) in [
        ("model", Coordinates::Model),
        ("measured", Coordinates::Measured),
    ] {
        let comment = format!(
            "# dvrk-ident joint log; coordinates: {stated}; time s, position rad|m, velocity \
             rad/s|m/s, effort N*m|N\n"
        );
        let path = write_file(&dir, &format!("{stated}.csv"), &(comment + header));
        let t = read_headered(&path).unwrap();
        assert_eq!(t.coordinates, expected);
        assert_eq!(t.joint_names, vec!["a", "b"]);
        assert_eq!(t.tau[(1, 1)], 4.0);
    }
    // Without the comment, `q1..qn` in order are model coordinates; anything else, or the
    // same names out of order, measured joints.
    for (names, expected) in [
        (["q1", "q2"], Coordinates::Model),
        (["q2", "q1"], Coordinates::Measured),
        (["q1", "yaw"], Coordinates::Measured),
    ] {
        let text = format!(
            "time,position.{0},position.{1},effort.{0},effort.{1}\n0,1,2,3,4\n",
            names[0], names[1]
        );
        let path = write_file(&dir, "inferred.csv", &text);
        assert_eq!(
            read_headered(&path).unwrap().coordinates,
            expected,
            "{names:?}"
        );
    }
}

#[test]
fn headered_any_column_order_joint_order_from_positions() {
    let dir = test_dir("column_order");
    let path = write_file(
        &dir,
        "log.csv",
        "effort.b, velocity.a, position.b, time, effort.a, position.a, velocity.b\n\
         10, 1, 2, 0.0, 20, 3, 4\n\
         11, 5, 6, 0.1, 21, 7, 8\n",
    );
    let t = read_headered(&path).unwrap();
    assert_eq!(t.joint_names, vec!["b", "a"]);
    assert_eq!(t.time, vec![0.0, 0.1]);
    assert_eq!(t.q, DMatrix::from_row_slice(2, 2, &[2.0, 3.0, 6.0, 7.0]));
    assert_eq!(
        t.dq.unwrap(),
        DMatrix::from_row_slice(2, 2, &[4.0, 1.0, 8.0, 5.0])
    );
    assert_eq!(
        t.tau,
        DMatrix::from_row_slice(2, 2, &[10.0, 20.0, 11.0, 21.0])
    );
    assert_eq!(t.coordinates, Coordinates::Measured);
}

#[test]
fn comments_blank_lines_crlf_and_bom() {
    let dir = test_dir("comments");
    let path = write_file(
        &dir,
        "c.csv",
        "\u{feff}# a comment\r\n\r\n1,2,3\r\n# another\r\n4,5,6\r\n",
    );
    let t = read_wpi(&path, 100.0, None).unwrap();
    assert_eq!(t.len(), 2);
    assert_eq!(t.tau[(1, 0)], 6.0);
    assert_eq!(detect_format(&path).unwrap(), LogFormat::Wpi);
    // Line numbers count comment and blank lines.
    let path = write_file(&dir, "d.csv", "# c\n\n1,2,3\n1,x,3\n");
    let e = read_wpi(&path, 100.0, None).unwrap_err();
    assert!(e.to_string().contains("d.csv:4:"), "{e}");
}

fn expect_err(path: &Path, e: LogError, line: Option<u64>, needles: &[&str]) -> LogError {
    let msg = e.to_string();
    assert!(
        msg.contains(&path.display().to_string()),
        "message does not name the file: {msg}"
    );
    if let Some(l) = line {
        assert!(
            msg.contains(&format!(":{l}:")),
            "message does not name line {l}: {msg}"
        );
    }
    for n in needles {
        assert!(msg.contains(n), "message lacks {n:?}: {msg}");
    }
    e
}

#[test]
fn malformed_number_names_file_line_column() {
    let dir = test_dir("malformed");
    let path = write_file(&dir, "w.csv", "1,2,3,4,5,6\n1,2,3,4,abc,6\n");
    let e = read_wpi(&path, 200.0, None).unwrap_err();
    let e = expect_err(&path, e, Some(2), &["abc", "column 5", "tau1"]);
    assert!(matches!(
        e,
        LogError::MalformedNumber {
            line: 2,
            column: 5,
            ..
        }
    ));

    let path = write_file(
        &dir,
        "h.csv",
        "time,position.j,effort.j\n0,1,2\n0.1,1..5,2\n",
    );
    let e = read_headered(&path).unwrap_err();
    expect_err(&path, e, Some(3), &["1..5", "position.j"]);
}

#[test]
fn wrong_column_count() {
    let dir = test_dir("column_count");
    let path = write_file(&dir, "w.csv", "1,2,3\n1,2,3\n1,2\n");
    let e = read_wpi(&path, 200.0, None).unwrap_err();
    let e = expect_err(&path, e, Some(3), &["2 columns, expected 3"]);
    assert!(matches!(
        e,
        LogError::ColumnCount {
            line: 3,
            expected: 3,
            found: 2,
            ..
        }
    ));
    let path = write_file(&dir, "h.csv", "time,position.j,effort.j\n0,1,2,3\n");
    let e = read_headered(&path).unwrap_err();
    expect_err(&path, e, Some(2), &["4 columns, expected 3"]);
}

#[test]
fn wpi_dof_must_divide_columns() {
    let dir = test_dir("dof");
    let path = write_file(&dir, "w.csv", "1,2,3,4\n");
    let e = read_wpi(&path, 200.0, None).unwrap_err();
    assert!(matches!(
        e,
        LogError::DofMismatch {
            columns: 4,
            dof: None,
            ..
        }
    ));
    expect_err(&path, e, Some(1), &["not divisible by 3"]);
    let path = write_file(&dir, "w9.csv", "1,2,3,4,5,6,7,8,9\n");
    let e = read_wpi(&path, 200.0, Some(2)).unwrap_err();
    expect_err(&path, e, Some(1), &["2 joints", "expected 6 columns"]);
    assert!(read_wpi(&path, 200.0, Some(0)).is_err());
    assert_eq!(read_wpi(&path, 200.0, Some(3)).unwrap().dof(), 3);
}

#[test]
fn missing_columns() {
    let dir = test_dir("missing");
    let path = write_file(
        &dir,
        "effort.csv",
        "time,position.a,position.b,effort.a\n0,1,2,3\n",
    );
    let e = read_headered(&path).unwrap_err();
    let e = expect_err(
        &path,
        e,
        None,
        &["missing effort column for joint \"b\"", "effort.b"],
    );
    assert!(matches!(
        e,
        LogError::Columns { source: ColumnError::MissingEffort { ref joint }, .. } if joint == "b"
    ));

    let path = write_file(
        &dir,
        "velocity.csv",
        "time,position.a,position.b,velocity.a,effort.a,effort.b\n0,1,2,3,4,5\n",
    );
    let e = read_headered(&path).unwrap_err();
    expect_err(&path, e, None, &["velocity", "\"b\"", "all joints or none"]);

    let path = write_file(&dir, "time.csv", "position.a,effort.a\n1,2\n");
    let e = read_headered(&path).unwrap_err();
    assert!(matches!(e, LogError::MissingTime { .. }));
    expect_err(&path, e, None, &["time"]);

    let path = write_file(&dir, "nojoint.csv", "time\n0\n");
    assert!(matches!(
        read_headered(&path).unwrap_err(),
        LogError::Columns {
            source: ColumnError::NoJoints,
            ..
        }
    ));

    let path = write_file(
        &dir,
        "orphan.csv",
        "time,position.a,effort.a,effort.c\n0,1,2,3\n",
    );
    let e = read_headered(&path).unwrap_err();
    expect_err(&path, e, None, &["effort.c", "position.c"]);

    let path = write_file(&dir, "unknown.csv", "time,postion.a,effort.a\n0,1,2\n");
    let e = read_headered(&path).unwrap_err();
    expect_err(&path, e, Some(1), &["unknown column \"postion.a\""]);

    let path = write_file(&dir, "nodot.csv", "time,position,effort.a\n0,1,2\n");
    assert!(matches!(
        read_headered(&path).unwrap_err(),
        LogError::Columns {
            source: ColumnError::Unknown { .. },
            ..
        }
    ));

    let path = write_file(
        &dir,
        "dup.csv",
        "time,position.a,effort.a,position.a\n0,1,2,1\n",
    );
    let e = read_headered(&path).unwrap_err();
    expect_err(&path, e, Some(1), &["duplicate column \"position.a\""]);
}

#[test]
fn non_finite_values_are_rejected_with_line() {
    let dir = test_dir("nonfinite");
    for (i, bad) in ["NaN", "nan", "inf", "-Infinity"].iter().enumerate() {
        let path = write_file(&dir, &format!("w{i}.csv"), &format!("1,2,3\n4,{bad},6\n"));
        let e = read_wpi(&path, 200.0, None).unwrap_err();
        let e = expect_err(&path, e, Some(2), &["non-finite", bad, "dq1"]);
        assert!(matches!(
            e,
            LogError::NonFinite {
                line: 2,
                column: 2,
                ..
            }
        ));
    }
    let path = write_file(
        &dir,
        "h.csv",
        "time,position.a,effort.a\n0,1,2\n0.1,1,NaN\n",
    );
    let e = read_headered(&path).unwrap_err();
    expect_err(&path, e, Some(3), &["non-finite", "effort.a"]);
}

#[test]
fn empty_inputs() {
    let dir = test_dir("empty");
    for (name, content) in [
        ("zero.csv", ""),
        ("blank.csv", "\n\n  \n"),
        ("comment.csv", "# nothing here\n"),
    ] {
        let path = write_file(&dir, name, content);
        let e = read_wpi(&path, 200.0, None).unwrap_err();
        assert!(matches!(e, LogError::Empty { .. }), "{name}: {e}");
        expect_err(&path, e, None, &["empty"]);
        assert!(matches!(
            read_headered(&path).unwrap_err(),
            LogError::Empty { .. }
        ));
        assert!(matches!(
            read(&path, None, Some(200.0)).unwrap_err(),
            LogError::Empty { .. }
        ));
    }
    let path = write_file(&dir, "header.csv", "time,position.a,effort.a\n");
    let e = read_headered(&path).unwrap_err();
    expect_err(&path, e, None, &["no data rows"]);
}

#[test]
fn time_must_increase() {
    let dir = test_dir("time");
    let path = write_file(
        &dir,
        "t.csv",
        "time,position.a,effort.a\n0,1,2\n0.1,1,2\n0.1,1,2\n",
    );
    let e = read_headered(&path).unwrap_err();
    expect_err(&path, e, Some(4), &["not after"]);
}

#[test]
fn rate_and_format_errors() {
    let dir = test_dir("rate");
    let path = write_file(&dir, "w.csv", "1,2,3\n");
    let e = read(&path, None, None).unwrap_err();
    assert!(matches!(e, LogError::MissingRate { .. }));
    expect_err(&path, e, None, &["Hz"]);
    assert!(matches!(
        read_wpi(&path, 0.0, None).unwrap_err(),
        LogError::InvalidRate { .. }
    ));
    assert!(matches!(
        read_wpi(&path, f64::NAN, None).unwrap_err(),
        LogError::InvalidRate { .. }
    ));
    // Forcing the headered reader on a headerless file: numbers are unknown columns.
    assert!(matches!(
        read(&path, Some(LogFormat::Csv), None).unwrap_err(),
        LogError::Columns {
            source: ColumnError::Unknown { .. },
            ..
        }
    ));
    // By content, not by extension: a text file named .mcap is a CSV.
    let mcap = write_file(&dir, "x.mcap", "not really");
    assert_eq!(detect_format(&mcap).unwrap(), LogFormat::Csv);
    let e = read(&mcap, Some(LogFormat::Mcap), None).unwrap_err();
    if cfg!(feature = "recordings") {
        assert!(matches!(e, LogError::Mcap { .. }), "{e}");
        assert!(e.to_string().contains("x.mcap: not a supported log"), "{e}");
    } else {
        assert!(matches!(e, LogError::RecordingsNotBuilt { .. }), "{e}");
    }
    let missing = dir.join("missing.csv");
    let e = read(&missing, None, Some(200.0)).unwrap_err();
    assert!(matches!(e, LogError::Io { .. }));
    expect_err(&missing, e, None, &[]);
}

#[test]
fn invalid_utf8_is_an_error_not_a_panic() {
    let dir = test_dir("utf8");
    let path = dir.join("bad.csv");
    std::fs::write(&path, b"time,position.a,effort.a\n0,\xff\xfe,2\n").unwrap();
    let e = read_headered(&path).unwrap_err();
    expect_err(&path, e, None, &[]);
    assert!(read(&path, None, Some(200.0)).is_err());
}

#[test]
fn writer_errors_leave_no_file() {
    let dir = test_dir("writer_errors");
    let path = dir.join("out.csv");
    let e = write_wpi(&path, &sample(3, 2, Coordinates::Measured, true)).unwrap_err();
    assert!(matches!(e, LogError::WrongCoordinates { .. }));
    let e = write_wpi(&path, &sample(3, 2, Coordinates::Model, false)).unwrap_err();
    assert!(matches!(e, LogError::MissingVelocity { .. }));
    let mut bad = sample(3, 2, Coordinates::Model, true);
    bad.q[(1, 1)] = f64::NAN;
    let e = write_headered(&path, &bad).unwrap_err();
    let e = expect_err(&path, e, None, &["invalid trajectory", "\"q2\""]);
    assert!(matches!(e, LogError::Invalid { .. }));
    assert!(matches!(
        write(
            &path,
            &sample(3, 2, Coordinates::Model, true),
            LogFormat::Mcap
        )
        .unwrap_err(),
        LogError::Mcap { .. }
    ));
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0);
    // A missing directory is an I/O error naming the target.
    let nowhere = dir.join("no/such/dir/out.csv");
    let e = write_wpi(&nowhere, &sample(3, 2, Coordinates::Model, true)).unwrap_err();
    assert!(matches!(e, LogError::Io { .. }));
    expect_err(&nowhere, e, None, &[]);
}

#[test]
fn atomic_write_replaces_existing_file() {
    let dir = test_dir("atomic");
    let path = write_file(
        &dir,
        "out.csv",
        "old content that is longer than the new one\n"
            .repeat(100)
            .as_str(),
    );
    let t = sample(2, 1, Coordinates::Model, true);
    write_wpi(&path, &t).unwrap();
    let back = read_wpi(&path, 200.0, None).unwrap();
    assert_eq!(back.len(), 2);
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1);
    // A failed write (invalid trajectory) leaves the previous file untouched.
    let before = std::fs::read(&path).unwrap();
    let mut bad = t.clone();
    bad.tau[(0, 0)] = f64::INFINITY;
    assert!(write_wpi(&path, &bad).is_err());
    assert_eq!(std::fs::read(&path).unwrap(), before);
}
