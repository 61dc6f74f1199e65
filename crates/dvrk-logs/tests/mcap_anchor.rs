//! The MCAP reader against `shared/anchors/psm_joint_states_sample.mcap`, written by the
//! official Python writer (mcap 1.6 + mcap-ros2-support 0.6: chunked, zstd, CRCs). Every
//! value is checked against the formulas of the companion JSON.

use dvrk_logs::log::mcap::{
    list_topics, read_joint_states, read_mcap, read_mcap_log, McapOptions, McapProblem, TimeSource,
};
use dvrk_logs::log::{read, LogError};
use std::f64::consts::PI;
use std::path::PathBuf;

fn anchor(name: &str) -> Option<PathBuf> {
    dvrk_test_support::shared(&format!("anchors/{name}"))
}

struct Formulas {
    a: Vec<f64>,
    off: Vec<f64>,
    f_hz: Vec<f64>,
    phi: Vec<f64>,
    b: Vec<f64>,
    c: Vec<f64>,
    names: Vec<String>,
    t0_ns: i64,
}

fn formulas() -> Option<Formulas> {
    let path = anchor("psm_joint_states_sample.json")?;
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    let v = |k: &str| -> Vec<f64> {
        json["formulas"][k]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect()
    };
    Some(Formulas {
        a: v("A"),
        off: v("OFF"),
        f_hz: v("F_hz"),
        phi: v("PHI"),
        b: v("B"),
        c: v("C"),
        names: json["joint_names"]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_str().unwrap().to_owned())
            .collect(),
        t0_ns: json["timing"]["T0_NS"].as_i64().unwrap(),
    })
}

impl Formulas {
    fn arg(&self, j: usize, t: f64) -> f64 {
        2.0 * PI * self.f_hz[j] * t + self.phi[j]
    }
    fn position(&self, j: usize, t: f64) -> f64 {
        self.off[j] + self.a[j] * self.arg(j, t).sin()
    }
    fn velocity(&self, j: usize, t: f64) -> f64 {
        self.a[j] * 2.0 * PI * self.f_hz[j] * self.arg(j, t).cos()
    }
    fn effort(&self, j: usize, t: f64) -> f64 {
        self.c[j] + self.b[j] * (self.arg(j, t) + 0.5).sin()
    }
    fn setpoint(&self, j: usize, t: f64) -> f64 {
        self.off[j] + self.a[j] * (2.0 * PI * self.f_hz[j] * (t + 0.010) + self.phi[j]).sin()
    }
}

#[test]
fn mcap_anchor_auto_topic_values_and_time() {
    let (Some(path), Some(f)) = (anchor("psm_joint_states_sample.mcap"), formulas()) else {
        return;
    };
    let log = read_mcap_log(&path, &McapOptions::default()).unwrap();
    assert_eq!(log.topics, ["/PSM1/measured_js"]);
    assert_eq!(log.start_time_ns, f.t0_ns);
    assert_eq!(log.trimmed, (0, 0));
    assert_eq!(log.timing.gaps + log.timing.jittered, 0);
    assert_eq!(log.timing.resampled_hz, None);
    let tr = &log.samples;
    assert_eq!(tr.len(), 2000);
    assert_eq!(tr.joint_names, f.names);
    assert_eq!(tr.coordinates, dvrk_logs::Coordinates::Measured);
    assert!(tr.source.contains("/PSM1/measured_js"), "{}", tr.source);
    let dq = tr.dq.as_ref().expect("measured_js has velocities");
    let mut worst: f64 = 0.0;
    for k in 0..2000 {
        let t = k as f64 / 200.0;
        assert!((tr.time[k] - t).abs() <= 1e-9, "time {k}: {}", tr.time[k]);
        for j in 0..7 {
            for (got, want) in [
                (tr.q[(k, j)], f.position(j, t)),
                (dq[(k, j)], f.velocity(j, t)),
                (tr.tau[(k, j)], f.effort(j, t)),
            ] {
                let e = (got - want).abs();
                worst = worst.max(e);
                assert!(e <= 1e-12, "sample {k} joint {j}: {got} vs {want}");
            }
        }
    }
    println!("largest deviation from the formulas: {worst:e}");
    // Time is exactly k / 200 (integer nanoseconds divided once).
    assert!(tr
        .time
        .iter()
        .enumerate()
        .all(|(k, &t)| t == k as f64 / 200.0));
    assert!((tr.rate_hz().unwrap() - 200.0).abs() < 1e-9);
    // log::read detects the format from the extension and gives the same.
    let via_read = read(&path, None, None).unwrap();
    assert_eq!(&via_read, tr);
}

#[test]
fn mcap_anchor_log_time_has_the_250_us_offset() {
    let (Some(path), Some(f)) = (anchor("psm_joint_states_sample.mcap"), formulas()) else {
        return;
    };
    let opts = McapOptions {
        time_source: TimeSource::LogTime,
        ..Default::default()
    };
    let log = read_mcap_log(&path, &opts).unwrap();
    assert_eq!(log.start_time_ns, f.t0_ns + 250_000);
    assert_eq!(log.time_source, TimeSource::LogTime);
    // The offset is constant, so relative times are still k / 200.
    assert!(log
        .samples
        .time
        .iter()
        .enumerate()
        .all(|(k, &t)| (t - k as f64 / 200.0).abs() <= 1e-9));
    let opts = McapOptions {
        time_source: TimeSource::PublishTime,
        ..Default::default()
    };
    assert_eq!(read_mcap_log(&path, &opts).unwrap().start_time_ns, f.t0_ns);
}

#[test]
fn mcap_anchor_setpoint_topic() {
    let (Some(path), Some(f)) = (anchor("psm_joint_states_sample.mcap"), formulas()) else {
        return;
    };
    let topic = "/PSM1/setpoint_js".to_string();
    // As a series: positions only.
    let series =
        read_joint_states(&path, std::slice::from_ref(&topic), TimeSource::HeaderStamp).unwrap();
    assert_eq!(series.len(), 1);
    let s = &series[0];
    assert_eq!(s.topic, topic);
    assert_eq!(s.joint_names, f.names);
    assert_eq!(s.stamps_ns.len(), 2000);
    assert_eq!(s.stamps_ns[0], f.t0_ns);
    assert_eq!(s.stamps_ns[1999], f.t0_ns + 1999 * 5_000_000);
    assert!(s.velocity.is_none() && s.effort.is_none());
    for k in 0..2000 {
        let t = k as f64 / 200.0;
        for j in 0..7 {
            let (got, want) = (s.position[(k, j)], f.setpoint(j, t));
            assert!(
                (got - want).abs() <= 1e-12,
                "sample {k} joint {j}: {got} vs {want}"
            );
        }
    }
    // As a trajectory to fit: refused, it has no efforts.
    let opts = McapOptions {
        topics: vec![topic.clone()],
        ..Default::default()
    };
    let e = read_mcap(&path, &opts).unwrap_err();
    let msg = e.to_string();
    println!("{msg}");
    assert!(
        matches!(&e, LogError::Mcap { problem, topic: Some(t), .. } if matches!(**problem, McapProblem::NoEffort) && *t == topic),
        "{msg}"
    );
    assert!(msg.contains("psm_joint_states_sample.mcap"), "{msg}");
    assert!(
        msg.contains("/PSM1/setpoint_js") && msg.contains("no efforts"),
        "{msg}"
    );
}

#[test]
fn mcap_anchor_topics_and_wrong_type() {
    let Some(path) = anchor("psm_joint_states_sample.mcap") else {
        return;
    };
    let topics = list_topics(&path).unwrap();
    let summary: Vec<(&str, &str, u64)> = topics
        .iter()
        .map(|t| (t.topic.as_str(), t.schema_name.as_str(), t.messages))
        .collect();
    assert_eq!(
        summary,
        [
            ("/PSM1/measured_js", "sensor_msgs/msg/JointState", 2000),
            ("/PSM1/setpoint_js", "sensor_msgs/msg/JointState", 2000),
            ("/rosout", "rcl_interfaces/msg/Log", 10),
        ]
    );
    let opts = McapOptions {
        topics: vec!["/rosout".into()],
        ..Default::default()
    };
    let msg = read_mcap(&path, &opts).unwrap_err().to_string();
    println!("{msg}");
    assert!(
        msg.contains("/rosout") && msg.contains("rcl_interfaces/msg/Log"),
        "{msg}"
    );
    let opts = McapOptions {
        topics: vec!["/PSM2/measured_js".into()],
        ..Default::default()
    };
    let msg = read_mcap(&path, &opts).unwrap_err().to_string();
    println!("{msg}");
    assert!(
        msg.contains("/PSM2/measured_js") && msg.contains("no such topic"),
        "{msg}"
    );
    assert!(
        msg.contains("/PSM1/measured_js (sensor_msgs/msg/JointState"),
        "{msg}"
    );
}
