//! The MCAP reader and writer on fixtures made here, in a temporary directory: files from
//! `write_mcap`, and hand-made files (several topics, odd stamps, broken messages)
//! written with the `mcap` and `cdr` crates directly, independently of the code tested.

#[path = "support/logs.rs"]
mod logs;

use dvrk_logs::log::mcap::{
    list_topics, read_joint_states, read_mcap, read_mcap_log, write_mcap, McapCompression,
    McapOptions, McapProblem, McapReader, McapWriteOptions, TimeSource, JOINT_STATE_SCHEMA,
    JOINT_STATE_TYPE,
};
use dvrk_logs::log::{detect_format, read, write, LogError, LogFormat};
use dvrk_logs::{uniform_time, Coordinates, JointLog};
use dvrk_model::Model;
use dvrk_test_support::fixtures::TempDir;
use logs::concatenate;
use nalgebra::DMatrix;
use serde::Serialize;
use std::collections::{BTreeMap, HashMap};
use std::path::Path;
use std::sync::LazyLock;

const T0: i64 = 1_700_000_000_000_000_000;
const STEP: i64 = 5_000_000; // 200 Hz

#[derive(Serialize)]
struct RosTime {
    sec: i32,
    nanosec: u32,
}

#[derive(Serialize)]
struct RosHeader {
    stamp: RosTime,
    frame_id: String,
}

#[derive(Serialize)]
struct JointState {
    header: RosHeader,
    name: Vec<String>,
    position: Vec<f64>,
    velocity: Vec<f64>,
    effort: Vec<f64>,
}

fn joint_state(stamp: i64, names: &[&str], p: &[f64], v: &[f64], e: &[f64]) -> JointState {
    JointState {
        header: RosHeader {
            stamp: RosTime {
                sec: stamp.div_euclid(1_000_000_000) as i32,
                nanosec: stamp.rem_euclid(1_000_000_000) as u32,
            },
            frame_id: String::new(),
        },
        name: names.iter().map(|s| s.to_string()).collect(),
        position: p.to_vec(),
        velocity: v.to_vec(),
        effort: e.to_vec(),
    }
}

/// Hand-made MCAP files: any topics, stamps and payloads.
struct Fixture {
    w: mcap::Writer<std::io::BufWriter<std::fs::File>>,
    schemas: HashMap<String, u16>,
    channels: HashMap<String, u16>,
    seq: u32,
}

impl Fixture {
    fn new(path: &Path) -> Fixture {
        let file = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
        let w = mcap::WriteOptions::new()
            .profile("ros2")
            .chunk_size(Some(4096)) // several chunks
            .create(file)
            .unwrap();
        Fixture {
            w,
            schemas: HashMap::new(),
            channels: HashMap::new(),
            seq: 0,
        }
    }

    fn channel(&mut self, topic: &str, schema: &str, encoding: &str) -> u16 {
        if let Some(&c) = self.channels.get(topic) {
            return c;
        }
        let schema_id = match self.schemas.get(schema) {
            Some(&s) => s,
            None => {
                let text = if schema == JOINT_STATE_TYPE {
                    JOINT_STATE_SCHEMA
                } else {
                    "string data\n"
                };
                let s = self
                    .w
                    .add_schema(schema, "ros2msg", text.as_bytes())
                    .unwrap();
                self.schemas.insert(schema.to_owned(), s);
                s
            }
        };
        let c = self
            .w
            .add_channel(schema_id, topic, encoding, &BTreeMap::new())
            .unwrap();
        self.channels.insert(topic.to_owned(), c);
        c
    }

    fn raw(&mut self, topic: &str, schema: &str, encoding: &str, log_time: i64, data: &[u8]) {
        let channel_id = self.channel(topic, schema, encoding);
        self.seq += 1;
        let header = mcap::records::MessageHeader {
            channel_id,
            sequence: self.seq,
            log_time: log_time as u64,
            publish_time: log_time as u64,
        };
        self.w.write_to_known_channel(&header, data).unwrap();
    }

    fn js(&mut self, topic: &str, msg: &JointState) {
        let data = cdr::serialize::<_, _, cdr::CdrLe>(msg, cdr::Infinite).unwrap();
        let stamp =
            i64::from(msg.header.stamp.sec) * 1_000_000_000 + i64::from(msg.header.stamp.nanosec);
        self.raw(topic, JOINT_STATE_TYPE, "cdr", stamp, &data);
    }

    fn finish(mut self) {
        self.w.finish().unwrap();
    }
}

/// The PSM's measured joints as its logs name them (`robots/psm.toml`), the jaw last.
static PSM_JOINTS: LazyLock<Vec<String>> =
    LazyLock::new(|| Model::builtin("psm").unwrap().measured.joints);
/// The PSM's arm joints: all but the jaw.
static ARM: LazyLock<Vec<&str>> =
    LazyLock::new(|| PSM_JOINTS[..6].iter().map(String::as_str).collect());

fn arm_values(t: f64) -> ([f64; 6], [f64; 6], [f64; 6]) {
    let mut p = [0.0; 6];
    let mut v = [0.0; 6];
    let mut e = [0.0; 6];
    for j in 0..6 {
        let w = 1.0 + j as f64;
        p[j] = 0.1 * j as f64 + 0.5 * (w * t).sin();
        v[j] = 0.5 * w * (w * t).cos();
        e[j] = -0.2 + 0.3 * (w * t + 0.5).sin();
    }
    (p, v, e)
}

/// A single-topic arm log with the given stamps (ns).
fn arm_file(path: &Path, topic: &str, stamps: &[i64]) {
    let mut f = Fixture::new(path);
    for &s in stamps {
        let (p, v, e) = arm_values((s - T0) as f64 / 1e9);
        f.js(topic, &joint_state(s, &ARM, &p, &v, &e));
    }
    f.finish();
}

/// The error of reading `path` with the default options, and its message (printed: what
/// the user would read).
fn refusal(path: &Path) -> (LogError, String) {
    let e = read_mcap(path, &McapOptions::default()).unwrap_err();
    let msg = e.to_string();
    println!("{msg}");
    (e, msg)
}

/// The file `path` written from the 7-joint trajectory of `samples` samples on
/// `/PSM1/measured_js` with `opts`, and its bytes.
fn written(path: &Path, samples: usize, opts: &McapWriteOptions) -> Vec<u8> {
    write_mcap(path, &trajectory(samples, true), "/PSM1/measured_js", opts).unwrap();
    std::fs::read(path).unwrap()
}

fn problem(e: &LogError) -> &McapProblem {
    match e {
        LogError::Mcap { problem, .. } => problem,
        other => panic!("expected an MCAP problem, got {other:?}"),
    }
}

fn trajectory(n: usize, with_dq: bool) -> JointLog {
    let dof = 7;
    JointLog {
        time: uniform_time(n, 200.0),
        q: DMatrix::from_fn(n, dof, |i, j| {
            ((i * 7 + j) as f64 * 0.37).sin() * if j == 2 { 0.05 } else { 1.3 }
        }),
        dq: with_dq.then(|| DMatrix::from_fn(n, dof, |i, j| ((i + 3 * j) as f64 * 0.11).cos())),
        tau: DMatrix::from_fn(n, dof, |i, j| match (i, j) {
            (0, 0) => 1e-300,
            (1, 0) => -0.0,
            // The largest effort a log may hold (Signal::max_magnitude), to the bit.
            (2, 0) => -1e6,
            (3, 0) => f64::MIN_POSITIVE / 2.0, // subnormal
            _ => (i as f64 - 3.0 * j as f64) / 7.0,
        }),
        joint_names: PSM_JOINTS.clone(),
        coordinates: Coordinates::Measured,
        source: "test".into(),
    }
}

#[test]
fn mcap_round_trip_is_exact() {
    let dir = TempDir::new("mcap-round-trip");
    for (k, compression) in [
        McapCompression::Zstd,
        McapCompression::Lz4,
        McapCompression::None,
    ]
    .into_iter()
    .enumerate()
    {
        for with_dq in [true, false] {
            let written = trajectory(1500, with_dq);
            let path = dir.path(format!("rt-{k}-{with_dq}.mcap"));
            let opts = McapWriteOptions {
                start_time_ns: T0,
                frame_id: "PSM1_base".into(),
                compression,
            };
            write_mcap(&path, &written, "/PSM1/measured_js", &opts).unwrap();
            let log = read_mcap_log(&path, &McapOptions::default()).unwrap();
            assert_eq!(log.start_time_ns, T0);
            assert_eq!(log.topics, ["/PSM1/measured_js"]);
            let back = &log.samples;
            assert_eq!(back.time, written.time, "time is exactly k / 200");
            assert_eq!(back.joint_names, written.joint_names);
            assert_eq!(back.coordinates, Coordinates::Measured);
            // Bit for bit (assert_eq would let -0.0 == 0.0 pass).
            let bits = |m: &DMatrix<f64>| m.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&back.q), bits(&written.q));
            assert_eq!(bits(&back.tau), bits(&written.tau));
            assert_eq!(back.dq.as_ref().map(bits), written.dq.as_ref().map(bits));
            // The header stamps, log and publish times agree.
            for ts in [TimeSource::LogTime, TimeSource::PublishTime] {
                let o = McapOptions {
                    time_source: ts,
                    ..Default::default()
                };
                let l = read_mcap_log(&path, &o).unwrap();
                assert_eq!(l.start_time_ns, T0);
                assert_eq!(l.samples.time, written.time);
            }
            let series = read_joint_states(
                &path,
                &["/PSM1/measured_js".into()],
                TimeSource::HeaderStamp,
            )
            .unwrap();
            assert_eq!(series[0].frame_id, "PSM1_base");
            assert_eq!(series[0].stamps_ns[1499], T0 + 1499 * STEP);
        }
    }
    // The generic entry points: extension detection, default topic.
    let written = trajectory(10, true);
    let path = dir.path("generic.mcap");
    write(&path, &written, LogFormat::Mcap).unwrap();
    assert_eq!(detect_format(&path).unwrap(), LogFormat::Mcap);
    let back = read(&path, None, None).unwrap();
    assert_eq!(
        (back.q, back.dq, back.tau),
        (written.q, written.dq, written.tau)
    );
    // Only the finished files are left (the temporary files were renamed).
    let names: Vec<String> = std::fs::read_dir(dir.dir())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert!(
        names
            .iter()
            .all(|n| n.ends_with(".mcap") && !n.starts_with('.')),
        "{names:?}"
    );
}

#[test]
fn mcap_written_file_is_a_ros2_mcap() {
    let dir = TempDir::new("mcap-ros2");
    let path = dir.path("ros2.mcap");
    let bytes = written(&path, 20, &McapWriteOptions::default());
    let summary = mcap::Summary::read(&bytes).unwrap().expect("a summary");
    let schemas: Vec<_> = summary.schemas.values().collect();
    assert_eq!(schemas.len(), 1);
    assert_eq!(schemas[0].name, "sensor_msgs/msg/JointState");
    assert_eq!(schemas[0].encoding, "ros2msg");
    let text = std::str::from_utf8(&schemas[0].data).unwrap();
    assert!(text.contains("\nfloat64[] effort\n"));
    assert!(text.contains(&format!("{}\nMSG: std_msgs/Header\n", "=".repeat(80))));
    assert!(text.contains(&format!(
        "{}\nMSG: builtin_interfaces/Time\n",
        "=".repeat(80)
    )));
    let channel = summary.channels.values().next().unwrap();
    assert_eq!(channel.topic, "/PSM1/measured_js");
    assert_eq!(channel.message_encoding, "cdr");
    assert_eq!(summary.stats.as_ref().unwrap().message_count, 20);
    assert!(!summary.chunk_indexes.is_empty());
    // Profile "ros2" in the header record.
    let mut reader = mcap::read::LinearReader::new(&bytes).unwrap();
    match reader.next().unwrap().unwrap() {
        mcap::records::Record::Header(h) => {
            assert_eq!(h.profile, "ros2");
            assert!(h.library.starts_with("dvrk-ident/"), "{}", h.library);
        }
        other => panic!("first record: {other:?}"),
    }
    // Messages: CDR little-endian, sequence = sample index, times = stamps.
    let msgs: Vec<_> = mcap::MessageStream::new(&bytes)
        .unwrap()
        .map(Result::unwrap)
        .collect();
    assert_eq!(msgs.len(), 20);
    assert_eq!(&msgs[3].data[..4], &[0, 1, 0, 0]);
    assert_eq!(msgs[3].sequence, 3);
    assert_eq!(msgs[3].log_time, 3 * STEP as u64);
    assert_eq!(msgs[3].publish_time, 3 * STEP as u64);
}

#[test]
fn mcap_writer_refuses_bad_input_and_leaves_nothing() {
    let dir = TempDir::new("mcap-write-errors");
    let path = dir.path("bad.mcap");
    let mut model = trajectory(5, true);
    model.coordinates = Coordinates::Model;
    let e = write_mcap(&path, &model, "/x", &McapWriteOptions::default()).unwrap_err();
    assert!(matches!(problem(&e), McapProblem::WrongCoordinates), "{e}");
    let mut nan = trajectory(5, true);
    nan.q[(2, 1)] = f64::NAN;
    let e = write_mcap(&path, &nan, "/x", &McapWriteOptions::default()).unwrap_err();
    assert!(matches!(e, LogError::Invalid { .. }), "{e}");
    let early = McapWriteOptions {
        start_time_ns: -1,
        ..Default::default()
    };
    let e = write_mcap(&path, &trajectory(5, true), "/x", &early).unwrap_err();
    assert!(
        matches!(problem(&e), McapProblem::BadStamp { index: 0, .. }),
        "{e}"
    );
    let e = write_mcap(
        &path,
        &trajectory(5, true),
        "",
        &McapWriteOptions::default(),
    )
    .unwrap_err();
    assert!(matches!(problem(&e), McapProblem::BadTopic(_)), "{e}");
    assert_eq!(std::fs::read_dir(dir.dir()).unwrap().count(), 0);
    // A directory that does not exist: an I/O error naming the file.
    let e = write_mcap(
        dir.path("missing/x.mcap"),
        &trajectory(5, true),
        "/x",
        &McapWriteOptions::default(),
    )
    .unwrap_err();
    assert!(
        matches!(e, LogError::Io { .. }) && e.to_string().contains("x.mcap"),
        "{e}"
    );
}

#[test]
fn mcap_two_topics_are_merged_on_the_first_clock() {
    let dir = TempDir::new("mcap-merge");
    let path = dir.path("merge.mcap");
    let n = 400;
    let jaw = |t: f64| (0.3 + 0.2 * t, -0.1 + 0.05 * t); // linear: interpolation is exact
    let mut f = Fixture::new(&path);
    for k in 0..n as i64 {
        let s = T0 + k * STEP;
        let (p, v, e) = arm_values((s - T0) as f64 / 1e9);
        f.js("/PSM1/measured_js", &joint_state(s, &ARM, &p, &v, &e));
        // The jaw publishes 1.5 ms later, without velocities, and stops 3 samples early.
        if k < n as i64 - 3 {
            let sj = s + 1_500_000;
            let (pj, ej) = jaw((sj - T0) as f64 / 1e9);
            f.js(
                "/PSM1/jaw/measured_js",
                &joint_state(sj, &["jaw"], &[pj], &[], &[ej]),
            );
        }
    }
    f.raw(
        "/rosout",
        "rcl_interfaces/msg/Log",
        "cdr",
        T0,
        b"\0\x01\0\0",
    );
    f.finish();
    let opts = McapOptions {
        topics: vec!["/PSM1/measured_js".into(), "/PSM1/jaw/measured_js".into()],
        ..Default::default()
    };
    let log = read_mcap_log(&path, &opts).unwrap();
    let tr = &log.samples;
    let mut names: Vec<&str> = ARM.to_vec();
    names.push("jaw");
    assert_eq!(tr.joint_names, names);
    // The arm's first sample is before the jaw's first; its last 3 after the jaw's last.
    assert_eq!(log.trimmed, (1, 3));
    assert_eq!(tr.len(), n - 4);
    assert_eq!(log.start_time_ns, T0 + STEP);
    assert!(tr.dq.is_none(), "the jaw has no velocities");
    assert!(
        tr.source
            .contains("/PSM1/measured_js + /PSM1/jaw/measured_js"),
        "{}",
        tr.source
    );
    for k in 0..tr.len() {
        let abs_t = ((T0 + (k as i64 + 1) * STEP) - T0) as f64 / 1e9;
        assert_eq!(tr.time[k], k as f64 / 200.0);
        let (p, _, e) = arm_values(abs_t);
        for j in 0..6 {
            assert_eq!(tr.q[(k, j)], p[j]);
            assert_eq!(tr.tau[(k, j)], e[j]);
        }
        let (pj, ej) = jaw(abs_t);
        assert!(
            (tr.q[(k, 6)] - pj).abs() < 1e-12,
            "{k}: {} vs {pj}",
            tr.q[(k, 6)]
        );
        assert!((tr.tau[(k, 6)] - ej).abs() < 1e-12);
    }
    // Same stamps: taken as they are.
    let path2 = dir.path("same-stamps.mcap");
    let mut f = Fixture::new(&path2);
    for k in 0..50 {
        let s = T0 + k * STEP;
        let (p, v, e) = arm_values((s - T0) as f64 / 1e9);
        f.js(
            "/a/measured_js",
            &joint_state(s, &ARM[..3], &p[..3], &v[..3], &e[..3]),
        );
        f.js(
            "/b/measured_js",
            &joint_state(s, &ARM[3..], &p[3..], &v[3..], &e[3..]),
        );
    }
    f.finish();
    let opts = McapOptions {
        topics: vec!["/a/measured_js".into(), "/b/measured_js".into()],
        ..Default::default()
    };
    let tr = read_mcap(&path2, &opts).unwrap();
    assert_eq!(tr.len(), 50);
    let dq = tr.dq.as_ref().unwrap();
    for k in 0..50usize {
        let (p, v, e) = arm_values((k as i64 * STEP) as f64 / 1e9);
        for j in 0..6 {
            assert_eq!(
                (tr.q[(k, j)], dq[(k, j)], tr.tau[(k, j)]),
                (p[j], v[j], e[j])
            );
        }
    }
    // The same topic twice is refused.
    let opts = McapOptions {
        topics: vec!["/a/measured_js".into(), "/a/measured_js".into()],
        ..Default::default()
    };
    let e = read_mcap(&path2, &opts).unwrap_err();
    assert!(matches!(problem(&e), McapProblem::RepeatedTopic), "{e}");
    // Two topics with a joint of the same name are refused.
    let path3 = dir.path("same-joint.mcap");
    let mut f = Fixture::new(&path3);
    for k in 0..10 {
        let s = T0 + k * STEP;
        f.js(
            "/a/measured_js",
            &joint_state(s, &["jaw"], &[0.1], &[], &[0.2]),
        );
        f.js(
            "/b/measured_js",
            &joint_state(s, &["jaw"], &[0.1], &[], &[0.2]),
        );
    }
    f.finish();
    let opts = McapOptions {
        topics: vec!["/a/measured_js".into(), "/b/measured_js".into()],
        ..Default::default()
    };
    let e = read_mcap(&path3, &opts).unwrap_err();
    assert!(
        matches!(problem(&e), McapProblem::DuplicateJoint { .. }),
        "{e}"
    );
    assert!(
        e.to_string().contains("also on topic /a/measured_js"),
        "{e}"
    );
}

#[test]
fn mcap_automatic_topic_choice() {
    let dir = TempDir::new("mcap-auto");
    let stamps: Vec<i64> = (0..20).map(|k| T0 + k * STEP).collect();
    let write = |path: &Path, topics: &[(&str, bool)]| {
        let mut f = Fixture::new(path);
        for &s in &stamps {
            let (p, v, e) = arm_values((s - T0) as f64 / 1e9);
            for &(topic, with_effort) in topics {
                let e: &[f64] = if with_effort { &e } else { &[] };
                f.js(topic, &joint_state(s, &ARM, &p, &v, e));
            }
        }
        f.finish();
    };
    // One candidate with efforts besides a setpoint topic: no ambiguity.
    let p1 = dir.path("one.mcap");
    write(
        &p1,
        &[("/PSM1/setpoint_js", false), ("/PSM1/servo_js", true)],
    );
    let log = read_mcap_log(&p1, &McapOptions::default()).unwrap();
    assert_eq!(log.topics, ["/PSM1/servo_js"]);
    // Two candidates, one measured_js: it wins.
    let p2 = dir.path("two.mcap");
    write(
        &p2,
        &[("/PSM1/measured_js", true), ("/PSM1/servo_js", true)],
    );
    assert_eq!(
        read_mcap_log(&p2, &McapOptions::default()).unwrap().topics,
        ["/PSM1/measured_js"]
    );
    // Two measured_js: an error listing both.
    let p3 = dir.path("three.mcap");
    write(
        &p3,
        &[("/PSM1/measured_js", true), ("/PSM2/measured_js", true)],
    );
    let (e, msg) = refusal(&p3);
    assert!(matches!(problem(&e), McapProblem::Ambiguous { candidates } if candidates.len() == 2));
    assert!(
        msg.contains("/PSM1/measured_js") && msg.contains("/PSM2/measured_js"),
        "{msg}"
    );
    assert!(
        msg.contains("three.mcap") && msg.contains("--topic"),
        "{msg}"
    );
    // No candidate: says why the JointState topics were not.
    let p4 = dir.path("four.mcap");
    write(&p4, &[("/PSM1/setpoint_js", false)]);
    let (e, msg) = refusal(&p4);
    assert!(
        matches!(problem(&e), McapProblem::NoJointStates { .. }),
        "{msg}"
    );
    assert!(msg.contains("/PSM1/setpoint_js: no efforts"), "{msg}");
}

#[test]
fn mcap_truncated_and_foreign_files_are_errors() {
    let dir = TempDir::new("mcap-truncated");
    let path = dir.path("full.mcap");
    let bytes = written(&path, 3000, &McapWriteOptions::default());
    let cut = dir.path("cut.mcap");
    for len in [
        0,
        5,
        8,
        20,
        bytes.len() / 3,
        bytes.len() / 2,
        bytes.len() - 30,
        bytes.len() - 1,
    ] {
        std::fs::write(&cut, &bytes[..len]).unwrap();
        let (e, msg) = refusal(&cut);
        assert!(msg.contains("cut.mcap"), "{len}: {msg}");
        assert!(
            matches!(problem(&e), McapProblem::Truncated { .. }),
            "{len} bytes: {msg}"
        );
    }
    // A flipped byte inside a compressed chunk: CRC or decompression error, not a panic.
    let mut corrupt = bytes.clone();
    let mid = bytes.len() / 2;
    corrupt[mid] ^= 0x55;
    std::fs::write(&cut, &corrupt).unwrap();
    let (e, _) = refusal(&cut);
    assert!(matches!(problem(&e), McapProblem::Container { .. }), "{e}");
    // Not an MCAP at all: by content a CSV, whatever its name; read as a recording, an
    // error saying what it is.
    let csv = dir.path("log.mcap");
    std::fs::write(&csv, "time,position.q1,effort.q1\n0,1,2\n").unwrap();
    assert_eq!(read(&csv, None, None).unwrap().len(), 1);
    let (e, _) = refusal(&csv);
    assert!(
        matches!(problem(&e), McapProblem::NotARecording { .. }),
        "{e}"
    );
    assert!(
        e.to_string()
            .contains("log.mcap: not a supported log: it looks like a text file"),
        "{e}"
    );
    // Missing file.
    let (e, _) = refusal(&dir.path("nope.mcap"));
    assert!(matches!(e, LogError::Io { .. }), "{e}");
}

#[test]
fn mcap_wrong_type_missing_and_empty_topics() {
    let dir = TempDir::new("mcap-types");
    let path = dir.path("types.mcap");
    let mut f = Fixture::new(&path);
    for k in 0..10 {
        let s = T0 + k * STEP;
        let (p, v, e) = arm_values(k as f64 * 0.005);
        f.js("/PSM1/measured_js", &joint_state(s, &ARM, &p, &v, &e));
        f.raw(
            "/PSM1/measured_cp",
            "geometry_msgs/msg/PoseStamped",
            "cdr",
            s,
            &[0, 1, 0, 0],
        );
    }
    f.channel("/PSM1/quiet_js", JOINT_STATE_TYPE, "cdr");
    f.finish();
    let read_topic = |t: &str| {
        let opts = McapOptions {
            topics: vec![t.to_owned()],
            ..Default::default()
        };
        read_mcap(&path, &opts).unwrap_err()
    };
    let e = read_topic("/PSM1/measured_cp");
    let msg = e.to_string();
    println!("{msg}");
    assert!(
        matches!(problem(&e), McapProblem::WrongType { .. }),
        "{msg}"
    );
    assert!(msg.contains("types.mcap: topic /PSM1/measured_cp"), "{msg}");
    assert!(msg.contains("geometry_msgs/msg/PoseStamped"), "{msg}");
    let e = read_topic("/PSM1/quiet_js");
    assert!(matches!(problem(&e), McapProblem::EmptyTopic), "{e}");
    assert!(e.to_string().contains("/PSM1/quiet_js"), "{e}");
    let e = read_topic("/PSM3/measured_js");
    assert!(
        matches!(problem(&e), McapProblem::TopicNotFound { .. }),
        "{e}"
    );
    let topics = list_topics(&path).unwrap();
    let quiet = topics.iter().find(|t| t.topic == "/PSM1/quiet_js").unwrap();
    assert_eq!(quiet.messages, 0);
}

#[test]
fn mcap_gaps_are_refused_or_resampled() {
    let dir = TempDir::new("mcap-gap");
    let path = dir.path("gap.mcap");
    // 200 Hz with a 4-sample hole after sample 99 (the next stamp is 25 ms later).
    let stamps: Vec<i64> = (0..300)
        .map(|k| T0 + k * STEP + if k >= 100 { 4 * STEP } else { 0 })
        .collect();
    arm_file(&path, "/PSM1/measured_js", &stamps);
    let (e, msg) = refusal(&path);
    assert!(
        matches!(
            problem(&e),
            McapProblem::NonUniform {
                index: 100,
                gaps: 1,
                jittered: 0,
                ..
            }
        ),
        "{msg}"
    );
    assert!(msg.contains("gap.mcap: topic /PSM1/measured_js"), "{msg}");
    assert!(msg.contains("sample 100 (t = 0.52 s)"), "{msg}");
    assert!(
        msg.contains("--resample HZ") && msg.contains("--resample 200"),
        "{msg}"
    );
    let opts = McapOptions {
        resample_hz: Some(200.0),
        ..Default::default()
    };
    let log = read_mcap_log(&path, &opts).unwrap();
    let tr = &log.samples;
    assert_eq!(tr.len(), 304, "1.515 s at 200 Hz");
    assert_eq!(log.timing.gaps, 1);
    assert_eq!(log.timing.resampled_hz, Some(200.0));
    assert!((log.timing.largest_step_s - 0.025).abs() < 1e-12);
    tr.check_uniform(1e-9).unwrap();
    // On the recorded samples, the values are the recorded ones; in the hole, a line.
    let (p99, _, _) = arm_values(99.0 * 0.005);
    let (p100, _, _) = arm_values(104.0 * 0.005);
    for j in 0..6 {
        assert!((tr.q[(99, j)] - p99[j]).abs() < 1e-12);
        assert!((tr.q[(104, j)] - p100[j]).abs() < 1e-12);
        let mid = 0.4 * p99[j] + 0.6 * p100[j]; // t = 102 * 5 ms: 3/5 of the way
        assert!(
            (tr.q[(102, j)] - mid).abs() < 1e-12,
            "{} vs {mid}",
            tr.q[(102, j)]
        );
    }
    // Jitter: one stamp 1 ms late.
    let jitter = dir.path("jitter.mcap");
    let mut stamps: Vec<i64> = (0..100).map(|k| T0 + k * STEP).collect();
    stamps[40] += 1_000_000;
    arm_file(&jitter, "/PSM1/measured_js", &stamps);
    let (e, _) = refusal(&jitter);
    assert!(
        matches!(
            problem(&e),
            McapProblem::NonUniform {
                index: 40,
                gaps: 0,
                jittered: 2,
                ..
            }
        ),
        "{e}"
    );
    let tr = read_mcap(&jitter, &opts).unwrap();
    assert_eq!(tr.len(), 100);
    // A bad resampling rate.
    let bad = McapOptions {
        resample_hz: Some(0.0),
        ..Default::default()
    };
    assert!(matches!(
        read_mcap(&jitter, &bad).unwrap_err(),
        LogError::InvalidRate { .. }
    ));
}

#[test]
fn mcap_stamps_that_go_back_or_repeat() {
    let dir = TempDir::new("mcap-order");
    let path = dir.path("back.mcap");
    let mut stamps: Vec<i64> = (0..50).map(|k| T0 + k * STEP).collect();
    stamps.swap(20, 21);
    arm_file(&path, "/PSM1/measured_js", &stamps);
    let (e, msg) = refusal(&path);
    assert!(
        matches!(
            problem(&e),
            McapProblem::NotIncreasing {
                index: 21,
                backwards: 1,
                duplicates: 0,
                ..
            }
        ),
        "{msg}"
    );
    assert!(
        msg.contains("sample 21") && msg.contains("log times"),
        "{msg}"
    );
    // Resampling does not hide it.
    let opts = McapOptions {
        resample_hz: Some(200.0),
        ..Default::default()
    };
    assert!(read_mcap(&path, &opts).is_err());
    let path = dir.path("dup.mcap");
    let mut stamps: Vec<i64> = (0..50).map(|k| T0 + k * STEP).collect();
    stamps[31] = stamps[30];
    arm_file(&path, "/PSM1/measured_js", &stamps);
    let (e, _) = refusal(&path);
    assert!(
        matches!(
            problem(&e),
            McapProblem::NotIncreasing {
                index: 31,
                backwards: 0,
                duplicates: 1,
                ..
            }
        ),
        "{e}"
    );
    assert!(e.to_string().contains("repeats the stamp"), "{e}");
}

#[test]
fn mcap_message_contents_are_checked() {
    let dir = TempDir::new("mcap-contents");
    let topic = "/PSM1/measured_js";
    let opts = McapOptions::default();
    // Builds a 30-message file where message 12 is made by `odd`.
    let file = |name: &str, odd: &dyn Fn(i64) -> JointState| {
        let path = dir.path(name);
        let mut f = Fixture::new(&path);
        for k in 0..30 {
            let s = T0 + k * STEP;
            let msg = if k == 12 {
                odd(s)
            } else {
                let (p, v, e) = arm_values(k as f64 * 0.005);
                joint_state(s, &ARM, &p, &v, &e)
            };
            f.js(topic, &msg);
        }
        f.finish();
        path
    };
    let (p, v, e) = arm_values(12.0 * 0.005);
    // NaN.
    let path = file("nan.mcap", &|s| {
        let mut e = e;
        e[4] = f64::NAN;
        joint_state(s, &ARM, &p, &v, &e)
    });
    let err = read_mcap(&path, &opts).unwrap_err();
    let msg = err.to_string();
    println!("{msg}");
    assert!(
        matches!(problem(&err), McapProblem::NonFinite { index: 12, .. }),
        "{msg}"
    );
    assert!(msg.contains("nan.mcap: topic /PSM1/measured_js"), "{msg}");
    assert!(
        msg.contains("effort") && msg.contains("outer_wrist_pitch"),
        "{msg}"
    );
    assert!(msg.contains("t = 0.06 s"), "{msg}");
    // Reordered joints: reordered by name.
    let path = file("reordered.mcap", &|s| {
        let order = [5, 0, 4, 1, 3, 2];
        let names: Vec<&str> = order.iter().map(|&j| ARM[j]).collect();
        let pick = |x: &[f64; 6]| order.iter().map(|&j| x[j]).collect::<Vec<_>>();
        joint_state(s, &names, &pick(&p), &pick(&v), &pick(&e))
    });
    let tr = read_mcap(&path, &opts).unwrap();
    assert_eq!(tr.joint_names, *ARM);
    for j in 0..6 {
        assert_eq!(tr.q[(12, j)], p[j]);
        assert_eq!(tr.dq.as_ref().unwrap()[(12, j)], v[j]);
        assert_eq!(tr.tau[(12, j)], e[j]);
    }
    // A joint replaced by another: an error.
    let path = file("changed.mcap", &|s| {
        let mut names = ARM.clone();
        names[5] = "jaw";
        joint_state(s, &names, &p, &v, &e)
    });
    let err = read_mcap(&path, &opts).unwrap_err();
    assert!(
        matches!(problem(&err), McapProblem::JointsChanged { index: 12, .. }),
        "{err}"
    );
    assert!(err.to_string().contains("\"jaw\""), "{err}");
    // Arrays of the wrong length.
    let path = file("short.mcap", &|s| joint_state(s, &ARM, &p, &v[..5], &e));
    let err = read_mcap(&path, &opts).unwrap_err();
    assert!(
        matches!(
            problem(&err),
            McapProblem::ArrayLength {
                index: 12,
                field: "velocity",
                len: 5,
                joints: 6
            }
        ),
        "{err}"
    );
    // Velocities missing in one message only.
    let path = file("novel.mcap", &|s| joint_state(s, &ARM, &p, &[], &e));
    let err = read_mcap(&path, &opts).unwrap_err();
    assert!(
        matches!(
            problem(&err),
            McapProblem::Inconsistent {
                index: 12,
                field: "velocity",
                empty: true
            }
        ),
        "{err}"
    );
    // Duplicate joint names.
    let path = file("dup.mcap", &|s| {
        let mut names = ARM.clone();
        names[1] = "outer_yaw";
        joint_state(s, &names, &p, &v, &e)
    });
    let err = read_mcap(&path, &opts).unwrap_err();
    assert!(
        matches!(problem(&err), McapProblem::JointsChanged { .. }),
        "{err}"
    );
    // Undecodable payload.
    let path = dir.path("garbage.mcap");
    let mut f = Fixture::new(&path);
    f.raw(topic, JOINT_STATE_TYPE, "cdr", T0, &[0, 1, 0, 0, 1, 2]);
    f.finish();
    let err = read_mcap(&path, &opts).unwrap_err();
    assert!(
        matches!(problem(&err), McapProblem::Decode { index: 0, .. }),
        "{err}"
    );
}

#[test]
fn mcap_big_endian_and_json_messages() {
    let dir = TempDir::new("mcap-encodings");
    let path = dir.path("enc.mcap");
    let mut f = Fixture::new(&path);
    for k in 0..20 {
        let s = T0 + k * STEP;
        let (p, v, e) = arm_values(k as f64 * 0.005);
        let be =
            cdr::serialize::<_, _, cdr::CdrBe>(&joint_state(s, &ARM, &p, &v, &e), cdr::Infinite)
                .unwrap();
        f.raw("/be/measured_js", JOINT_STATE_TYPE, "cdr", s, &be);
        let json = serde_json::json!({
            "header": {"stamp": {"sec": s / 1_000_000_000, "nanosec": s % 1_000_000_000}, "frame_id": ""},
            "name": *ARM, "position": p, "velocity": [], "effort": e,
        });
        f.raw(
            "/json/js",
            JOINT_STATE_TYPE,
            "json",
            s,
            json.to_string().as_bytes(),
        );
    }
    f.finish();
    for topic in ["/be/measured_js", "/json/js"] {
        let opts = McapOptions {
            topics: vec![topic.into()],
            ..Default::default()
        };
        let tr = read_mcap(&path, &opts).unwrap();
        assert_eq!(tr.len(), 20);
        assert_eq!(tr.dq.is_some(), topic.starts_with("/be"));
        for k in 0..20 {
            let (p, _, e) = arm_values(k as f64 * 0.005);
            for j in 0..6 {
                assert_eq!(
                    (tr.q[(k, j)], tr.tau[(k, j)]),
                    (p[j], e[j]),
                    "{topic} {k} {j}"
                );
            }
        }
    }
}

#[test]
fn mcap_cut_or_corrupted_files_never_panic() {
    let dir = TempDir::new("mcap-fuzz");
    let path = dir.path("full.mcap");
    let opts = McapWriteOptions {
        start_time_ns: T0,
        compression: McapCompression::None, // flips reach the records, not only zstd
        ..Default::default()
    };
    let bytes = written(&path, 400, &opts);
    let bad = dir.path("bad.mcap");
    // Every cut is an error.
    let cuts = (0..bytes.len())
        .step_by(389)
        .chain(bytes.len() - 100..bytes.len());
    for len in cuts {
        std::fs::write(&bad, &bytes[..len]).unwrap();
        assert!(
            read_mcap(&bad, &McapOptions::default()).is_err(),
            "cut at {len}"
        );
    }
    // Flipped bytes: an error or (where the byte does not matter) a result, never a panic.
    let mut rng = dvrk_test_support::Rng::new(0x2545_f491_4f6c_dd1d);
    let mut errors = 0;
    for _ in 0..300 {
        let state = rng.next_u64();
        let mut b = bytes.clone();
        let at = (state % b.len() as u64) as usize;
        b[at] ^= 1 << (state >> 61);
        std::fs::write(&bad, &b).unwrap();
        if read_mcap(&bad, &McapOptions::default()).is_err() {
            errors += 1;
        }
    }
    assert!(errors > 250, "{errors} of 300 flips detected");
}

/// Every block of `reader` in blocks of `size`, concatenated.
fn concatenated(reader: &McapReader, size: usize) -> JointLog {
    let blocks: Vec<JointLog> = reader.blocks(size).unwrap().map(|b| b.unwrap()).collect();
    assert!(blocks.iter().all(|b| b.len() <= size));
    concatenate(&blocks)
}

#[test]
fn mcap_blocks_of_any_size_are_the_whole_log() {
    // A long jittered clock (more distinct steps than the median's exact first pass
    // counts) and a jaw topic that starts late, stops early and is written behind the
    // arm in the file: the blocks, merged on the fly, must give the whole log.
    let dir = TempDir::new("mcap-blocks");
    let path = dir.path("blocks.mcap");
    let n: i64 = 20_000;
    let mut rng = dvrk_test_support::Rng::new(12345);
    let mut jitter = move || (rng.next_u64() % 400_001) as i64 - 200_000;
    let stamps: Vec<i64> = (0..n)
        .map(|k| T0 + k * STEP + if k == 0 { 0 } else { jitter() })
        .collect();
    let mut f = Fixture::new(&path);
    let mut jaw_backlog = Vec::new();
    for (k, &s) in stamps.iter().enumerate() {
        let (p, v, e) = arm_values((s - T0) as f64 / 1e9);
        f.js("/PSM1/measured_js", &joint_state(s, &ARM, &p, &v, &e));
        if (2..stamps.len() - 5).contains(&k) {
            let sj = s + 1_500_000;
            let t = (sj - T0) as f64 / 1e9;
            jaw_backlog.push(joint_state(
                sj,
                &["jaw"],
                &[0.3 + 0.2 * t],
                &[0.2],
                &[-0.1 + t],
            ));
        }
        if k % 37 == 36 {
            for m in jaw_backlog.drain(..) {
                f.js("/PSM1/jaw/measured_js", &m);
            }
        }
    }
    for m in jaw_backlog.drain(..) {
        f.js("/PSM1/jaw/measured_js", &m);
    }
    f.finish();
    let merged = McapOptions {
        topics: vec!["/PSM1/measured_js".into(), "/PSM1/jaw/measured_js".into()],
        ..Default::default()
    };
    let resampled = McapOptions {
        resample_hz: Some(150.0),
        ..merged.clone()
    };
    let bits = |m: &DMatrix<f64>| m.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
    let arm = McapOptions {
        topics: vec!["/PSM1/measured_js".into()],
        ..Default::default()
    };
    for opts in [arm, merged, resampled] {
        let whole = read_mcap_log(&path, &opts).unwrap();
        let reader = McapReader::open(&path, &opts).unwrap();
        assert_eq!(reader.samples(), whole.samples.len());
        assert_eq!(reader.timing(), &whole.timing);
        for size in [1, 777, 100_000] {
            let b = concatenated(&reader, size);
            let w = &whole.samples;
            assert_eq!(b.time, w.time, "blocks of {size}");
            assert_eq!(bits(&b.q), bits(&w.q));
            assert_eq!(b.dq.as_ref().map(bits), w.dq.as_ref().map(bits));
            assert_eq!(bits(&b.tau), bits(&w.tau));
            assert_eq!((&b.joint_names, &b.source), (&w.joint_names, &w.source));
        }
        // The median step is exact: the clock's steps over the kept span, sorted.
        let first = whole.trimmed.0;
        let kept = &stamps[first..first + whole.timing.samples];
        let mut steps: Vec<i64> = kept.windows(2).map(|w| w[1] - w[0]).collect();
        steps.sort_unstable();
        let m = steps.len();
        let median2 = if m % 2 == 1 {
            2 * steps[m / 2]
        } else {
            steps[m / 2 - 1] + steps[m / 2]
        };
        assert_eq!(whole.timing.median_step_s, median2 as f64 / 2e9);
        assert_eq!(whole.timing.largest_step_s, steps[m - 1] as f64 / 1e9);
        println!(
            "{:?}: {} samples, trimmed {:?}, median step {} s",
            opts.topics,
            whole.samples.len(),
            whole.trimmed,
            whole.timing.median_step_s
        );
    }
}
