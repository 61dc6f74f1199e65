//! Every recording format, read from small files written by tools this project did not
//! write (`fixtures/bags/gen_bags.py`: rosbags for rosbag2 folders and ROS 1 bags, the
//! official mcap-ros2-support writer), each holding the same 16 PSM samples whose
//! values the generator's formulas give exactly (dyadic fractions).

use std::path::{Path, PathBuf};

use dvrk_logs::log::mcap::{list_topics, read_mcap_log, McapOptions, McapProblem, McapReader};
use dvrk_logs::log::{detect_format, LogError, LogFormat, ReadOptions};
use dvrk_model::Model;
use dvrk_test_support::fixtures::TempDir;

const N: usize = 16;
const T0_NS: i64 = 1_700_000_000 * 1_000_000_000;

fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/bags")
        .join(name)
}

/// The PSM's measured joints (`robots/psm.toml`): the names the generator writes.
fn psm_joints() -> Vec<String> {
    Model::builtin("psm").unwrap().measured.joints
}

fn position(k: usize, j: usize) -> f64 {
    ((k * (j + 1)) % 17) as f64 / 32.0 - 0.25
}
fn velocity(k: usize, j: usize) -> f64 {
    ((k + j) % 5) as f64 / 8.0 - 0.25
}
fn effort(k: usize, j: usize) -> f64 {
    ((3 * k + 2 * j) % 11) as f64 / 16.0 - 5.0 / 16.0
}

/// Every fixture with the format it must be recognized as.
const FIXTURES: [(&str, LogFormat); 11] = [
    ("rosbag2_mcap", LogFormat::Rosbag2),
    ("rosbag2_mcap/metadata.yaml", LogFormat::Rosbag2),
    ("rosbag2_mcap/rosbag2_mcap_0.mcap", LogFormat::Mcap),
    ("rosbag2_sqlite", LogFormat::Rosbag2),
    ("rosbag2_sqlite/rosbag2_sqlite_0.db3", LogFormat::Sqlite3),
    ("split", LogFormat::Rosbag2),
    ("file_zstd", LogFormat::Rosbag2),
    ("message_zstd", LogFormat::Rosbag2),
    ("sqlite_file_zstd", LogFormat::Rosbag2),
    ("noetic.bag", LogFormat::Ros1),
    ("official.mcap", LogFormat::Mcap),
];

/// The other fixtures: compressed single files, a second ROS 1 bag.
const MORE: [(&str, LogFormat); 4] = [
    ("psm.mcap.lz4", LogFormat::Mcap),
    ("file_zstd/file_zstd_0.mcap.zstd", LogFormat::Mcap),
    (
        "sqlite_file_zstd/sqlite_file_zstd_0.db3.zstd",
        LogFormat::Sqlite3,
    ),
    ("noetic_lz4.bag", LogFormat::Ros1),
];

#[test]
fn every_format_reads_the_same_samples_exactly() {
    let options = McapOptions {
        joints: psm_joints(),
        ..Default::default()
    };
    let read_options = ReadOptions {
        joints: psm_joints(),
        ..Default::default()
    };
    for (name, format) in FIXTURES.iter().chain(&MORE) {
        let path = fixture(name);
        assert_eq!(detect_format(&path).unwrap(), *format, "{name}");
        let log = read_mcap_log(&path, &options).unwrap_or_else(|e| panic!("{name}: {e}"));
        // The dVRK 2.x pairing: arm and jaw topics, the arm the clock.
        assert_eq!(
            log.topics,
            ["/PSM1/measured_js", "/PSM1/jaw/measured_js"],
            "{name}"
        );
        assert_eq!(log.start_time_ns, T0_NS, "{name}");
        let t = &log.samples;
        assert_eq!(t.joint_names, psm_joints(), "{name}");
        assert_eq!(t.len(), N, "{name}");
        let dq = t.dq.as_ref().expect("velocities");
        for k in 0..N {
            assert_eq!(t.time[k], (k as i64 * 5_000_000) as f64 / 1e9, "{name} {k}");
            for j in 0..7 {
                assert_eq!(t.q[(k, j)], position(k, j), "{name} q {k} {j}");
                assert_eq!(dq[(k, j)], velocity(k, j), "{name} dq {k} {j}");
                assert_eq!(t.tau[(k, j)], effort(k, j), "{name} tau {k} {j}");
            }
        }
        // The same through the generic reader, format detected.
        let reader = read_options.open(&path).unwrap();
        assert_eq!(reader.format(), *format, "{name}");
        assert_eq!(reader.topics(), log.topics.as_slice());
        let again = read_options.read(&path).unwrap();
        assert_eq!(again.q, t.q, "{name}");
    }
}

#[test]
fn topics_of_every_format_are_listed() {
    for (name, _) in FIXTURES.iter().chain(&MORE) {
        let topics = list_topics(fixture(name)).unwrap();
        let mut names: Vec<(&str, u64)> = topics
            .iter()
            .map(|t| (t.topic.as_str(), t.messages))
            .collect();
        names.sort();
        assert_eq!(
            names,
            [
                ("/PSM1/jaw/measured_js", N as u64),
                ("/PSM1/measured_cp", N as u64 / 2),
                ("/PSM1/measured_js", N as u64),
                ("/PSM1/setpoint_js", N as u64 / 2),
                ("/PSM1/status", N as u64 / 8),
            ],
            "{name}"
        );
        let js = topics
            .iter()
            .find(|t| t.topic == "/PSM1/measured_js")
            .unwrap();
        if name.ends_with(".bag") {
            assert_eq!(
                (js.schema_name.as_str(), js.message_encoding.as_str()),
                ("sensor_msgs/JointState", "ros1")
            );
        } else {
            assert_eq!(
                (js.schema_name.as_str(), js.message_encoding.as_str()),
                ("sensor_msgs/msg/JointState", "cdr")
            );
        }
    }
}

#[test]
fn without_the_robot_the_single_measured_topic_is_read() {
    // Not knowing the robot's joints, the arm topic alone (the measured_js candidate
    // ending: both arm and jaw end in measured_js, so that is ambiguous).
    let e = read_mcap_log(fixture("split"), &McapOptions::default()).unwrap_err();
    let msg = e.to_string();
    assert!(
        matches!(&e, LogError::Mcap { problem, .. } if matches!(**problem, McapProblem::Ambiguous { .. })),
        "{msg}"
    );
    assert!(
        msg.contains("/PSM1/jaw/measured_js, /PSM1/measured_js"),
        "{msg}"
    );
    // Joints on one topic only: that topic.
    let arm_only = McapOptions {
        joints: psm_joints()[..6].to_vec(),
        ..Default::default()
    };
    let log = read_mcap_log(fixture("noetic.bag"), &arm_only).unwrap();
    assert_eq!(log.topics, ["/PSM1/measured_js"]);
    assert_eq!(log.samples.dof(), 6);
    // Explicit topics are read as given.
    let explicit = McapOptions {
        topics: vec!["/PSM1/jaw/measured_js".into()],
        ..Default::default()
    };
    let log = read_mcap_log(fixture("rosbag2_sqlite"), &explicit).unwrap();
    assert_eq!(log.samples.joint_names, ["jaw"]);
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        std::fs::copy(e.path(), to.join(e.file_name())).unwrap();
    }
}

fn problem(e: &LogError) -> &McapProblem {
    match e {
        LogError::Mcap { problem, .. } => problem,
        other => panic!("not a recording error: {other}"),
    }
}

#[test]
fn split_folder_without_metadata_and_bad_metadata() {
    let dir = TempDir::new("bags-split");
    let bag = dir.path("rec");
    copy_dir(&fixture("split"), &bag);
    let options = McapOptions {
        joints: psm_joints(),
        ..Default::default()
    };
    let whole = read_mcap_log(&bag, &options).unwrap();
    // An interrupted recording has no metadata.yaml: the files by their split index.
    std::fs::remove_file(bag.join("metadata.yaml")).unwrap();
    let found = read_mcap_log(&bag, &options).unwrap();
    assert_eq!(found.samples.q, whole.samples.q);
    // metadata.yaml naming a missing file, or not rosbag2's.
    std::fs::write(
        bag.join("metadata.yaml"),
        "rosbag2_bagfile_information:\n  relative_file_paths: [split_0.mcap, gone_1.mcap]\n",
    )
    .unwrap();
    let e = read_mcap_log(&bag, &options).unwrap_err();
    assert!(matches!(problem(&e), McapProblem::Metadata { .. }), "{e}");
    assert!(e.to_string().contains("gone_1.mcap"), "{e}");
    std::fs::write(
        bag.join("metadata.yaml"),
        "rosbag2_bagfile_information: [1, 2\n",
    )
    .unwrap();
    let e = read_mcap_log(&bag, &options).unwrap_err();
    assert!(
        e.to_string()
            .contains("metadata.yaml: invalid rosbag2 metadata.yaml"),
        "{e}"
    );
    // One file of a split recording is a log of its own, its first half.
    let first = read_mcap_log(bag.join("split_0.mcap"), &options).unwrap();
    assert!(first.samples.len() < N && !first.samples.is_empty());
    assert_eq!(
        first.samples.q,
        whole.samples.q.rows(0, first.samples.len())
    );
}

#[test]
fn what_is_not_a_log_says_what_it_looks_like() {
    let dir = TempDir::new("bags-foreign");
    let cases: [(&str, &[u8], &str); 5] = [
        (
            "a.mcap",
            b"\x1f\x8b\x08\x00\x00\x00\x00\x00",
            "gzip-compressed data",
        ),
        ("b.bag", b"#ROSRECORD V1.2\n\x00\x00", "old 1.2 format"),
        (
            "c.db3",
            b"\x00\x01\x02\x03\xff\xfe\x00\x00binary",
            "binary data of no known log format",
        ),
        ("d.zip", b"PK\x03\x04\x14\x00", "zip archive"),
        (
            "e.mcap.zstd",
            &[0x28, 0xb5, 0x2f, 0xfd, 0x00, 0x01],
            "does not decompress",
        ),
    ];
    for (name, bytes, expect) in cases {
        let p = dir.path(name);
        std::fs::write(&p, bytes).unwrap();
        let e = ReadOptions::default().read(&p).unwrap_err();
        let msg = e.to_string();
        assert!(msg.contains(name), "{msg}");
        assert!(msg.contains(expect), "{name}: {msg}");
        assert!(!msg.contains("CSV parse"), "{name}: {msg}");
        if !name.ends_with(".zstd") {
            assert!(msg.contains("supported: a rosbag2 folder"), "{msg}");
        }
    }
    // A zstd-compressed CSV is no recording.
    let csv = dir.path("log.csv.zst");
    std::fs::write(&csv, zstd_of(b"time,position.a,effort.a\n0,1,2\n")).unwrap();
    let e = detect_format(&csv).unwrap_err();
    assert!(
        e.to_string()
            .contains("zstd-compressed data that is not a recording"),
        "{e}"
    );
    // A text file is a CSV whatever its name.
    let named = dir.path("log.mcap");
    std::fs::write(&named, "time,position.q1,effort.q1\n0,1,2\n0.005,1,2\n").unwrap();
    assert_eq!(detect_format(&named).unwrap(), LogFormat::Csv);
    // Asked to read it as a recording: it says so.
    let e = McapReader::open(&named, &McapOptions::default()).unwrap_err();
    assert!(
        matches!(problem(&e), McapProblem::NotARecording { .. }),
        "{e}"
    );
    // An empty folder.
    let empty = dir.path("empty");
    std::fs::create_dir(&empty).unwrap();
    let e = ReadOptions::default().read(&empty).unwrap_err();
    assert!(
        e.to_string()
            .contains("neither a metadata.yaml nor a recording file"),
        "{e}"
    );
}

fn zstd_of(bytes: &[u8]) -> Vec<u8> {
    zstd::bulk::compress(bytes, 3).unwrap()
}

#[test]
fn cut_or_corrupted_bags_are_errors_not_panics() {
    let dir = TempDir::new("bags-cut");
    let options = McapOptions {
        joints: psm_joints(),
        ..Default::default()
    };
    for name in [
        "noetic.bag",
        "noetic_lz4.bag",
        "rosbag2_sqlite/rosbag2_sqlite_0.db3",
        "official.mcap",
        "psm.mcap.lz4",
        "file_zstd/file_zstd_0.mcap.zstd",
    ] {
        let bytes = std::fs::read(fixture(name)).unwrap();
        let cut = dir.path(Path::new(name).file_name().unwrap());
        for len in [20, bytes.len() / 3, bytes.len() / 2, bytes.len() - 7] {
            std::fs::write(&cut, &bytes[..len]).unwrap();
            let e = read_mcap_log(&cut, &options)
                .expect_err(&format!("{name} cut at {len} bytes read"));
            assert!(
                e.to_string()
                    .contains(cut.file_name().unwrap().to_str().unwrap()),
                "{e}"
            );
        }
        for at in [bytes.len() / 4, bytes.len() / 2, 3 * bytes.len() / 4] {
            let mut bad = bytes.clone();
            bad[at] ^= 0x5a;
            std::fs::write(&cut, &bad).unwrap();
            // Either an error or the log (a flipped byte in a payload can decode);
            // never a panic.
            let _ = read_mcap_log(&cut, &options);
        }
    }
}

/// A `metadata.yaml` names files inside its folder, each once, in plain YAML: anchors
/// and aliases (an alias bomb), entries leaving the folder (absolute, `..`, a symbolic
/// link out, a loop of links), the same file twice (100 000 times) and more files than
/// accepted are each an error naming the entry, before any recording is read.
#[test]
fn metadata_names_files_inside_its_folder_once() {
    let dir = TempDir::new("bags-metadata-hostile");
    let bag = dir.path("rec");
    copy_dir(&fixture("split"), &bag);
    let outside = dir.path("other.mcap");
    std::fs::copy(bag.join("split_0.mcap"), &outside).unwrap();
    let options = McapOptions {
        joints: psm_joints(),
        ..Default::default()
    };
    let refused = |yaml: &str, words: &[&str]| {
        std::fs::write(bag.join("metadata.yaml"), yaml).unwrap();
        let e = read_mcap_log(&bag, &options).unwrap_err();
        assert!(matches!(problem(&e), McapProblem::Metadata { .. }), "{e}");
        let text = e.to_string();
        assert!(
            text.contains("metadata.yaml: invalid rosbag2 metadata.yaml"),
            "{text}"
        );
        for w in words {
            assert!(text.contains(w), "{w:?} not in {text}");
        }
    };
    let list = |entries: &str| {
        format!("rosbag2_bagfile_information:\n  relative_file_paths: [{entries}]\n")
    };
    // The alias bomb: nine levels of nine aliases are 9^9 strings once expanded.
    let mut bomb = String::from("a0: &a0 [x, x, x, x, x, x, x, x, x]\n");
    for k in 1..10 {
        let p = k - 1;
        bomb += &format!(
            "a{k}: &a{k} [*a{p}, *a{p}, *a{p}, *a{p}, *a{p}, *a{p}, *a{p}, *a{p}, *a{p}]\n"
        );
    }
    bomb += &list("split_0.mcap");
    refused(&bomb, &["line 1", "anchor", "rosbag2 never writes"]);
    refused(
        &format!("{}  x: *a\n", list("split_0.mcap")),
        &["unknown anchor"],
    );
    refused(
        &format!(
            "rosbag2_bagfile_information:\n  relative_file_paths: {}{}\n",
            "[".repeat(40),
            "]".repeat(40)
        ),
        &["nested more than 32 levels"],
    );
    refused(
        &list(&outside.display().to_string()),
        &["an absolute path", "other.mcap"],
    );
    refused(
        &list("../other.mcap"),
        &["`../other.mcap`", "leading out of the folder"],
    );
    std::os::unix::fs::symlink("../other.mcap", bag.join("out.mcap")).unwrap();
    refused(&list("out.mcap"), &["`out.mcap`", "outside the folder"]);
    std::os::unix::fs::symlink("loop_b", bag.join("loop_a")).unwrap();
    std::os::unix::fs::symlink("loop_a", bag.join("loop_b")).unwrap();
    refused(&list("loop_a"), &["`loop_a`", "loop of symbolic links"]);
    refused(
        &list("split_0.mcap, ./split_0.mcap"),
        &["`split_0.mcap` and `./split_0.mcap` are the same file"],
    );
    let many = vec!["split_0.mcap"; 100_000].join(", ");
    refused(&list(&many), &["lists 100000 files, more than the 10000"]);
    let twice = vec!["split_0.mcap"; 5_000].join(", ");
    refused(&list(&twice), &["are the same file"]);
    // A link inside the folder is a member; the recording reads.
    std::os::unix::fs::symlink("split_1.mcap", bag.join("inside.mcap")).unwrap();
    std::fs::write(bag.join("metadata.yaml"), list("split_0.mcap, inside.mcap")).unwrap();
    assert!(read_mcap_log(&bag, &options).is_ok());
    // Without metadata.yaml, a link out of the folder is refused too, naming it.
    std::fs::remove_file(bag.join("metadata.yaml")).unwrap();
    for l in ["loop_a", "loop_b", "inside.mcap"] {
        std::fs::remove_file(bag.join(l)).unwrap();
    }
    let e = read_mcap_log(&bag, &options).unwrap_err().to_string();
    assert!(
        e.contains("invalid rosbag2 folder: entry `out.mcap`"),
        "{e}"
    );
}

/// rosbag2 sqlite3 details: a messages table without the integer primary key reads the
/// same samples in insertion order (in batches from the rowid, not a scan per batch), a
/// row without an id is refused and counted instead of skipped, a hot rollback journal is
/// named, and the file is never written (its bytes unchanged, no `-shm` or `-wal` made).
#[test]
fn sqlite3_without_primary_key_null_ids_and_journals() {
    let dir = TempDir::new("bags-sqlite3-details");
    let options = McapOptions {
        joints: psm_joints(),
        ..Default::default()
    };
    let original = fixture("rosbag2_sqlite").join("rosbag2_sqlite_0.db3");
    let reference = read_mcap_log(&original, &options).unwrap();
    let copy = |name: &str, nulls: usize| {
        let path = dir.path(name);
        let conn = rusqlite::Connection::open(&path).unwrap();
        conn.execute_batch(&format!(
            "ATTACH '{}' AS o;
             CREATE TABLE topics AS SELECT * FROM o.topics;
             CREATE TABLE messages(id INTEGER, topic_id INTEGER, timestamp INTEGER, data BLOB);
             INSERT INTO messages SELECT id, topic_id, timestamp, data FROM o.messages ORDER BY id;
             UPDATE messages SET id = NULL WHERE rowid IN (SELECT rowid FROM messages LIMIT {nulls});
             DETACH o;",
            original.display()
        ))
        .unwrap();
        drop(conn);
        path
    };
    let plain = copy("plain.db3", 0);
    let bytes = std::fs::read(&plain).unwrap();
    let log = read_mcap_log(&plain, &options).unwrap();
    assert_eq!(log.samples.q, reference.samples.q);
    assert_eq!(log.samples.tau, reference.samples.tau);
    assert_eq!(
        std::fs::read(&plain).unwrap(),
        bytes,
        "the recording was written"
    );
    let mut names: Vec<String> = std::fs::read_dir(dir.path(""))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(names, ["plain.db3"]);

    let holes = copy("holes.db3", 3);
    let e = read_mcap_log(&holes, &options).unwrap_err().to_string();
    assert!(
        e.contains(
            "holes.db3: invalid rosbag2 sqlite3 file: 3 rows of the messages table have no id"
        ),
        "{e}"
    );

    let journal = dir.path("plain.db3-journal");
    std::fs::write(&journal, b"\xd9\xd5\x05\xf9\x20\xa1\x63\xd7 a hot journal").unwrap();
    let e = read_mcap_log(&plain, &options).unwrap_err().to_string();
    assert!(
        e.contains("invalid rosbag2 sqlite3 file: a rollback journal")
            && e.contains("plain.db3-journal"),
        "{e}"
    );
}

/// Decompression bombs (`tests/fixtures/hostile/make_bombs.py`) fail before they
/// expand, naming the file and the bound: MCAP chunks stating 120 MiB in all, 100 MiB
/// or 1 TiB in one, a chunk holding far more than it states (never decompressed
/// beyond what it states), an MCAP compressed as a whole into
/// 300 MB of zeros, ROS 1 bz2 chunks stating 4 GB in one or 120 MiB in all, an lz4
/// chunk holding more than it states. `max_unpacked_mib` sets the bound of the whole
/// file (not the 256 MiB of a chunk). A real recording with compressed chunks reads
/// within the default bound and is refused below its size.
#[test]
fn decompression_bombs_fail_naming_the_file_and_the_bound() {
    let hostile = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../tests/fixtures/hostile");
    let read = |name: &str, bound: Option<u64>| {
        let options = McapOptions {
            max_unpacked_mib: bound,
            ..Default::default()
        };
        read_mcap_log(hostile.join(name), &options).expect_err(name)
    };
    let chunks = "its compressed chunks decompress to more than";
    for (name, bound, expected) in [
        ("chunks_total.mcap", Some(1), format!("{chunks} 1 MiB")),
        ("chunk_100mib.mcap", None, format!("chunk_100mib.mcap: invalid MCAP file: {chunks} 64 MiB")),
        ("chunk_100mib.mcap", Some(50), format!("{chunks} 50 MiB")),
        ("chunk_huge.mcap", Some(1 << 30), "states 1099511627776 bytes decompressed, more than the 256 MiB a chunk may hold".into()),
        // Decompressed no further than the 900 bytes it states: no message in them.
        ("chunk_lying.mcap", None, "chunk_lying.mcap: no sensor_msgs/msg/JointState topic".into()),
        ("whole.mcap.zst", None, "whole.mcap.zst: invalid compressed file: it decompresses to more than 64 MiB".into()),
        ("whole.mcap.zst", Some(2), "it decompresses to more than 2 MiB".into()),
        ("bz2_4gb.bag", Some(1 << 20), "bz2_4gb.bag: invalid ROS 1 bag: the chunk at byte 4109 states 4294967295 bytes decompressed, more than the 256 MiB a chunk may hold".into()),
        ("bz2_total.bag", None, format!("bz2_total.bag: invalid ROS 1 bag: {chunks} 64 MiB")),
        ("bz2_total.bag", Some(100), format!("{chunks} 100 MiB")),
        ("lz4_lying.bag", None, "chunk at byte 4109: its lz4 data decompresses to more than the 1000 bytes its header states".into()),
    ] {
        let error = read(name, bound);
        let e = error.to_string();
        assert!(e.contains(&expected), "{name} {bound:?}: {e}");
        if expected.contains("MiB (") || e.contains("decompression bomb") {
            assert!(e.ends_with("raise it with --max-unpacked-mib"), "{e}");
            // The error keeps the setting as a hint until shown: Python's spelling.
            let python = dvrk_logs::hint::spelled(&error, |h| match h {
                dvrk_logs::hint::Hint::MaxUnpackedMib => "max_unpacked_mib=".into(),
                h => h.flag(),
            });
            assert!(
                python.ends_with("raise it with max_unpacked_mib=") && !python.contains("--"),
                "{python}"
            );
        }
    }
    // official.mcap has zstd chunks: read within the default bound, refused below.
    let options = McapOptions {
        joints: psm_joints(),
        ..Default::default()
    };
    read_mcap_log(fixture("official.mcap"), &options).unwrap();
    let e = read_mcap_log(
        fixture("official.mcap"),
        &McapOptions {
            max_unpacked_mib: Some(0),
            ..options
        },
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains(&format!("{chunks} 0 MiB")), "{e}");
}
