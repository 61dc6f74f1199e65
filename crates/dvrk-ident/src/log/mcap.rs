//! ROS 2 MCAP logs of `sensor_msgs/msg/JointState` (dVRK 2.x / CRTK `measured_js`).
//!
//! # Reading
//!
//! [`read_mcap`] (or [`read_mcap_log`], which also returns the absolute start time, the
//! topics and a timing report) streams the file message by message: the `mcap` crate
//! decompresses one chunk at a time (zstd or lz4) and checks the chunk, data and summary
//! CRCs, and only the joint states of the wanted topics are decoded and kept. Messages
//! may be CDR (`cdr` message encoding, what ROS 2 records) or JSON (`json`, Foxglove).
//!
//! **Topic choice** ([`McapOptions::topics`] empty): among the `sensor_msgs/msg/JointState`
//! topics, the one whose messages have both positions and efforts; if several do, the
//! one whose name ends in `measured_js` (the dVRK/CRTK convention); if that is still not
//! a single topic, an error lists the candidates. A topic that is named explicitly must
//! exist, hold JointState messages and not be empty. The choice takes the same single
//! pass over the file: every candidate topic is decoded and kept until the end (a
//! JointState topic stops being a candidate at its first message without positions or
//! efforts), so the memory is that of the candidates' samples, not of the file.
//!
//! **Several topics** (e.g. dVRK 2.x publishes the PSM jaw on `/PSM1/jaw/measured_js`
//! beside the six arm joints on `/PSM1/measured_js`): the joints are concatenated in the
//! order of the topics, and the *first* topic is the clock. Every other topic is sampled
//! at the first topic's stamps: a sample with the same stamp is taken as it is, otherwise
//! the two neighbouring samples are interpolated linearly. Samples of the first topic
//! outside the time span of another topic (it may start a little later or stop a little
//! earlier) are dropped at either end ([`McapLog::trimmed`]); a gap in another topic is
//! refused like a gap of the clock unless resampling is asked for. Velocities are kept
//! only if every topic has them; joint names must be unique across topics.
//!
//! **Time**: [`TimeSource::HeaderStamp`] (default, the time the controller measured the
//! joints) or the MCAP log or publish time of each message. [`Trajectory::time`] is in
//! seconds from the first kept sample, computed from integer nanoseconds
//! (`(stamp_k - stamp_0) / 1e9`, so a 200 Hz log gives exactly `k / 200`); the absolute
//! start is [`McapLog::start_time_ns`].
//!
//! **Timing checks** on the clock: stamps must strictly increase (a backward step or a
//! repeated stamp is always an error: the log order cannot be trusted). A step longer
//! than 1.5 median steps is a gap, a step off the median by more than
//! [`JITTER_TOLERANCE`] (the default `uniform_tolerance` of
//! [`crate::signal::Processing`]) is jitter. With [`McapOptions::resample_hz`] the log is
//! resampled onto `k / rate` by linear interpolation ([`crate::signal::resample_linear`];
//! gaps are bridged by straight lines, see [`TimingReport::largest_step_s`]); without it
//! a non-uniform log is refused with the first bad sample and a `--resample HZ` hint.
//!
//! **Checks on the messages** (all errors name the file and topic): arrays whose length
//! differs from the number of joints, velocity or effort arrays empty in some messages
//! and not in others, NaN or infinite values, duplicated joint names, joints that change
//! between messages. Joints that only change *order* are reordered by name to the order
//! of the first message.
//!
//! **Efforts**: [`read_mcap`] returns a [`Trajectory`], which always has efforts, so a
//! topic with empty effort arrays (e.g. `setpoint_js`) is an error saying so: it cannot be
//! fitted. [`read_joint_states`] reads such topics as they are (positions, and velocities
//! and efforts when present) for other uses (e.g. comparing setpoints and measurements).
//!
//! # Writing
//!
//! [`write_mcap`] writes a trajectory as a ROS 2 MCAP (profile `ros2`, schema
//! `sensor_msgs/msg/JointState` in `ros2msg` encoding with the full concatenated message
//! definition, CDR messages, zstd chunks with CRCs, summary and indexes), atomically
//! (temporary file and rename).

mod container;
mod joint_state;

pub use self::joint_state::{JOINT_STATE_SCHEMA, JOINT_STATE_TYPE};

use self::container::{mcap_error, MessageRef};
use self::joint_state::{Header, JointStateMsg, Time};
use crate::log::LogError;
use crate::trajectory::{Coordinates, Signal, Trajectory, TrajectoryError};
use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, HashMap};
use std::fmt::Write as _;
use std::path::Path;
use thiserror::Error;

/// Largest accepted relative deviation of a time step from the median step before a log
/// counts as jittered (equal to the default
/// [`uniform_tolerance`](crate::signal::Processing::uniform_tolerance)).
pub const JITTER_TOLERANCE: f64 = 0.1;

/// A step longer than this many median steps is a gap.
pub const GAP_FACTOR: f64 = 1.5;

/// Topic [`crate::log::write`] uses for MCAP files.
pub const DEFAULT_TOPIC: &str = "/measured_js";

/// Which time of a message becomes the sample time.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TimeSource {
    /// `header.stamp` of the JointState: when the controller measured the joints.
    #[default]
    HeaderStamp,
    /// The MCAP log time: when the recorder received the message.
    LogTime,
    /// The MCAP publish time.
    PublishTime,
}

impl std::fmt::Display for TimeSource {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            TimeSource::HeaderStamp => "header stamps",
            TimeSource::LogTime => "log times",
            TimeSource::PublishTime => "publish times",
        })
    }
}

impl std::str::FromStr for TimeSource {
    type Err = String;

    /// Parses `header` (also `stamp`, `header_stamp`), `log` (`log_time`) or `publish`
    /// (`publish_time`), case-insensitively, `-` or `_` alike.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.to_ascii_lowercase().replace('-', "_").as_str() {
            "header" | "stamp" | "header_stamp" => Ok(TimeSource::HeaderStamp),
            "log" | "log_time" => Ok(TimeSource::LogTime),
            "publish" | "publish_time" => Ok(TimeSource::PublishTime),
            other => Err(format!(
                "unknown time source {other:?}: expected header, log or publish"
            )),
        }
    }
}

/// How to read an MCAP log.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct McapOptions {
    /// JointState topics to read; empty: automatic choice (see the module docs). Several
    /// topics are merged, the first one being the clock.
    pub topics: Vec<String>,
    /// Which time of each message is its sample time.
    pub time_source: TimeSource,
    /// Resample to this uniform rate, Hz, by linear interpolation; `None`: a log with
    /// gaps or jitter is refused.
    pub resample_hz: Option<f64>,
}

/// A topic of an MCAP file.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct TopicInfo {
    /// Topic name.
    pub topic: String,
    /// Schema name (message type, e.g. `sensor_msgs/msg/JointState`; empty: no schema).
    pub schema_name: String,
    /// Message encoding (e.g. `cdr`).
    pub message_encoding: String,
    /// Number of messages.
    pub messages: u64,
}

impl std::fmt::Display for TopicInfo {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let schema = if self.schema_name.is_empty() {
            "no schema"
        } else {
            &self.schema_name
        };
        write!(
            f,
            "{} ({schema}, {}, {} messages)",
            self.topic, self.message_encoding, self.messages
        )
    }
}

/// The joint states of one topic as recorded: one row per message, columns in the
/// joint order of the first message.
#[derive(Clone, Debug, PartialEq)]
pub struct JointStateSeries {
    /// Topic name.
    pub topic: String,
    /// Joint names (the first message's order). Messages without names get
    /// `joint_1`, `joint_2`, ...
    pub joint_names: Vec<String>,
    /// `header.frame_id` of the first message.
    pub frame_id: String,
    /// Sample times, ns since the epoch, from the chosen [`TimeSource`].
    pub stamps_ns: Vec<i64>,
    /// Positions, rad or m.
    pub position: DMatrix<f64>,
    /// Velocities; `None` when the messages' velocity arrays are empty.
    pub velocity: Option<DMatrix<f64>>,
    /// Efforts; `None` when the messages' effort arrays are empty.
    pub effort: Option<DMatrix<f64>>,
}

/// What the timing checks found on the clock topic (before any resampling).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TimingReport {
    /// Number of samples checked.
    pub samples: usize,
    /// Median time step, s.
    pub median_step_s: f64,
    /// Steps longer than [`GAP_FACTOR`] median steps.
    pub gaps: usize,
    /// Other steps off the median by more than [`JITTER_TOLERANCE`] (relative).
    pub jittered: usize,
    /// Longest step, s.
    pub largest_step_s: f64,
    /// Index of the second sample of the first gap or jittered step.
    pub first_irregular: Option<usize>,
    /// The rate the log was resampled to, Hz, if it was.
    pub resampled_hz: Option<f64>,
}

/// A log read by [`read_mcap_log`]: the trajectory and what is known about it.
#[derive(Clone, Debug, PartialEq)]
pub struct McapLog {
    /// Measured joints; time from 0 s at the first kept sample.
    pub trajectory: Trajectory,
    /// The absolute time of `trajectory.time[0]`, ns since the epoch, in the chosen
    /// [`TimeSource`].
    pub start_time_ns: i64,
    /// The topics read, the clock first.
    pub topics: Vec<String>,
    /// The time source used.
    pub time_source: TimeSource,
    /// Timing of the clock topic.
    pub timing: TimingReport,
    /// Samples of the clock topic dropped at the start and at the end because another
    /// topic had not started or had already stopped (merging only).
    pub trimmed: (usize, usize),
}

/// Why an MCAP log could not be read or written. [`LogError::Mcap`] adds the file and,
/// where it matters, the topic.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum McapProblem {
    /// The file does not start with the MCAP magic.
    #[error("not an MCAP file (it does not start with the MCAP magic bytes)")]
    NotMcap,
    /// The file ends in the middle of a record or lacks its footer.
    #[error("truncated MCAP file: it ends in the middle of a record or before its footer ({bytes_read} bytes read); was the recording interrupted? (`mcap recover` can salvage the complete chunks)")]
    Truncated {
        /// Bytes read before the end.
        bytes_read: u64,
    },
    /// A malformed or corrupted MCAP container.
    #[error("invalid MCAP file: {reason}")]
    Container {
        /// What is wrong.
        reason: String,
    },
    /// A requested topic is not in the file.
    #[error(
        "no such topic in the file; its topics: {}",
        list_topics_text(available)
    )]
    TopicNotFound {
        /// The file's topics.
        available: Vec<TopicInfo>,
    },
    /// A requested topic has no messages.
    #[error("the topic has no messages")]
    EmptyTopic,
    /// A requested topic is not a JointState topic.
    #[error("the topic holds {} messages in {message_encoding:?} encoding, not {JOINT_STATE_TYPE} in cdr or json encoding", if schema_name.is_empty() { "schemaless" } else { schema_name })]
    WrongType {
        /// Its schema name.
        schema_name: String,
        /// Its message encoding.
        message_encoding: String,
    },
    /// Automatic choice: no JointState topic with positions and efforts.
    #[error("no {JOINT_STATE_TYPE} topic with both positions and efforts{}; the file's topics: {}", if rejected.is_empty() { String::new() } else { format!(" ({})", rejected.join(", ")) }, list_topics_text(available))]
    NoJointStates {
        /// The file's topics.
        available: Vec<TopicInfo>,
        /// JointState topics that were not candidates, and why.
        rejected: Vec<String>,
    },
    /// Automatic choice: several candidate topics.
    #[error("several {JOINT_STATE_TYPE} topics have positions and efforts: {}; choose one with --topic (repeat --topic to merge the joints of several topics, e.g. an arm and its jaw)", candidates.join(", "))]
    Ambiguous {
        /// The candidate topics.
        candidates: Vec<String>,
    },
    /// A message that does not decode as a JointState.
    #[error("message {index}: cannot decode it as {JOINT_STATE_TYPE}: {reason}")]
    Decode {
        /// Message index on the topic, 0-based.
        index: usize,
        /// What is wrong.
        reason: String,
    },
    /// A first message without joint names and positions.
    #[error("message {index} has no joints (empty name and position arrays)")]
    NoJoints {
        /// Message index on the topic, 0-based.
        index: usize,
    },
    /// An array whose length is not the number of joints.
    #[error("message {index}: {field} has {len} values for {joints} joints")]
    ArrayLength {
        /// Message index on the topic, 0-based.
        index: usize,
        /// `position`, `velocity` or `effort`.
        field: &'static str,
        /// Its length.
        len: usize,
        /// Number of joints (names).
        joints: usize,
    },
    /// Velocity or effort arrays empty in some messages and not in others.
    #[error("message {index}: the {field} array is {} but it was {} in message 0: all messages must have {field} values or none", if *empty { "empty" } else { "not empty" }, if *empty { "not empty" } else { "empty" })]
    Inconsistent {
        /// Message index on the topic, 0-based.
        index: usize,
        /// `velocity` or `effort`.
        field: &'static str,
        /// Whether it is empty in this message.
        empty: bool,
    },
    /// NaN or infinite value.
    #[error(
        "message {index} (t = {time_s} s): non-finite {signal} value {value} for joint {joint:?}"
    )]
    NonFinite {
        /// Message index on the topic, 0-based.
        index: usize,
        /// Time from the topic's first message, s.
        time_s: f64,
        /// Which signal.
        signal: Signal,
        /// Joint name.
        joint: String,
        /// The value.
        value: f64,
    },
    /// The set of joints changed between messages.
    #[error("message {index}: the joints changed from {first:?} (message 0) to {found:?}")]
    JointsChanged {
        /// Message index on the topic, 0-based.
        index: usize,
        /// Joints of the first message.
        first: Vec<String>,
        /// Joints of this message.
        found: Vec<String>,
    },
    /// The same joint name twice (in one message, or in two merged topics).
    #[error("joint {joint:?} appears twice ({context})")]
    DuplicateJoint {
        /// Joint name.
        joint: String,
        /// Where.
        context: String,
    },
    /// The same topic requested twice.
    #[error("the topic is requested twice")]
    RepeatedTopic,
    /// A topic without efforts where efforts are needed.
    #[error("the topic has no efforts (its effort arrays are empty, as on a setpoint topic): identification needs measured joint efforts, e.g. from a measured_js topic")]
    NoEffort,
    /// A message time that does not fit in 64-bit nanoseconds.
    #[error("message {index}: {time_source} value {value} ns is out of range")]
    TimeOutOfRange {
        /// Message index on the topic, 0-based.
        index: usize,
        /// The time source.
        time_source: TimeSource,
        /// The raw value, ns.
        value: u64,
    },
    /// Time stamps that go backwards or repeat.
    #[error("{time_source} do not strictly increase: sample {index} (t = {time_s} s) {} sample {} (t = {previous_s} s); {backwards} backward step(s) and {duplicates} repeated stamp(s) in {samples} samples. The sample order cannot be trusted: check the recording{}", if time_s == previous_s { "repeats the stamp of" } else { "comes before" }, index - 1, if *time_source == TimeSource::HeaderStamp { ", or read with log times (TimeSource::LogTime)" } else { "" })]
    NotIncreasing {
        /// Index of the offending sample, 0-based.
        index: usize,
        /// Its time from the first sample, s.
        time_s: f64,
        /// The previous sample's time, s.
        previous_s: f64,
        /// Number of backward steps.
        backwards: usize,
        /// Number of repeated stamps.
        duplicates: usize,
        /// Number of samples.
        samples: usize,
        /// The time source.
        time_source: TimeSource,
    },
    /// Gaps or jitter without resampling.
    #[error("non-uniform sampling ({time_source}): first at sample {index} (t = {time_s} s), a step of {} ms against a median of {} ms; {gaps} gap(s) (> {GAP_FACTOR} median steps, the longest {} ms) and {jittered} jittered step(s) (> {}% off the median) in {samples} samples. Filtering and differentiation need a uniform clock: resample with --resample HZ (McapOptions::resample_hz), e.g. --resample {suggested_hz}", fmt_ms(*step_s), fmt_ms(*median_step_s), fmt_ms(*largest_step_s), JITTER_TOLERANCE * 100.0)]
    NonUniform {
        /// Index of the second sample of the first irregular step, 0-based.
        index: usize,
        /// Its time, s.
        time_s: f64,
        /// The irregular step, s.
        step_s: f64,
        /// The median step, s.
        median_step_s: f64,
        /// Number of gaps.
        gaps: usize,
        /// Number of jittered steps.
        jittered: usize,
        /// Longest step, s.
        largest_step_s: f64,
        /// Number of samples.
        samples: usize,
        /// The time source.
        time_source: TimeSource,
        /// A rate to suggest (the inverse median step, rounded), Hz.
        suggested_hz: f64,
    },
    /// Merged topics whose time spans do not overlap.
    #[error("the topics do not overlap in time: {detail}")]
    NoOverlap {
        /// The topics' time spans.
        detail: String,
    },
    /// Resampling failed.
    #[error("cannot resample: {reason}")]
    Resample {
        /// Why.
        reason: String,
    },
    /// The resulting trajectory is invalid.
    #[error("{0}")]
    Invalid(TrajectoryError),
    /// Writing a model-coordinate trajectory.
    #[error("a JointState log holds measured joints but the trajectory is in model coordinates: map it to measured joints first")]
    WrongCoordinates,
    /// A sample time that cannot be a ROS 2 time stamp.
    #[error("sample {index}: t = {time_s} s (plus the start time) is not a valid stamp: ROS 2 stamps are int32 seconds, MCAP log times non-negative ns, and stamps must strictly increase at 1 ns resolution")]
    BadStamp {
        /// Sample index, 0-based.
        index: usize,
        /// Its time, s.
        time_s: f64,
    },
    /// A topic name that cannot be written.
    #[error("invalid topic name {0:?}")]
    BadTopic(String),
    /// The MCAP writer failed.
    #[error("cannot write the MCAP file: {reason}")]
    Write {
        /// Why.
        reason: String,
    },
}

fn list_topics_text(topics: &[TopicInfo]) -> String {
    if topics.is_empty() {
        return "none".into();
    }
    topics
        .iter()
        .map(ToString::to_string)
        .collect::<Vec<_>>()
        .join(", ")
}

fn fmt_ms(s: f64) -> String {
    format!("{:.3}", s * 1e3)
}

/// Lists the topics of an MCAP file with their types and message counts (one pass over
/// the file).
pub fn list_topics(path: impl AsRef<Path>) -> Result<Vec<TopicInfo>, LogError> {
    Ok(container::scan(path.as_ref(), |_| Ok(()))?.topics)
}

/// Reads an MCAP log into a [`Trajectory`] in measured coordinates (see the module docs
/// for topic choice, merging, time and checks).
pub fn read_mcap(path: impl AsRef<Path>, options: &McapOptions) -> Result<Trajectory, LogError> {
    read_mcap_log(path, options).map(|log| log.trajectory)
}

/// [`read_mcap`], also returning the absolute start time, the topics read and the timing
/// report.
///
/// ```rust
/// use dvrk_ident::log::mcap::{read_mcap_log, write_mcap, McapOptions, McapWriteOptions};
/// use dvrk_ident::trajectory::{Coordinates, Trajectory, uniform_time};
/// use nalgebra::DMatrix;
/// let path = std::env::temp_dir().join(format!("dvrk-ident-doc-{}.mcap", std::process::id()));
/// let n = 50;
/// let traj = Trajectory {
///     time: uniform_time(n, 200.0),
///     q: DMatrix::from_fn(n, 2, |i, j| (i * (j + 1)) as f64 * 1e-3),
///     dq: None,
///     tau: DMatrix::from_element(n, 2, 0.25),
///     joint_names: vec!["outer_yaw".into(), "outer_pitch".into()],
///     coordinates: Coordinates::Measured,
///     source: "doc".into(),
/// };
/// let start = 1_700_000_000_000_000_000;
/// let write = McapWriteOptions { start_time_ns: start, ..Default::default() };
/// write_mcap(&path, &traj, "/PSM1/measured_js", &write).unwrap();
/// let log = read_mcap_log(&path, &McapOptions::default()).unwrap();
/// assert_eq!(log.topics, ["/PSM1/measured_js"]);
/// assert_eq!(log.start_time_ns, start);
/// assert_eq!(log.trajectory.time, traj.time);
/// assert_eq!(log.trajectory.q, traj.q);
/// assert!(log.trajectory.dq.is_none());
/// std::fs::remove_file(&path).unwrap();
/// ```
pub fn read_mcap_log(path: impl AsRef<Path>, options: &McapOptions) -> Result<McapLog, LogError> {
    let path = path.as_ref();
    if let Some(rate) = options.resample_hz {
        if !(rate.is_finite() && rate > 0.0) {
            return Err(LogError::InvalidRate {
                path: path.to_path_buf(),
                rate_hz: rate,
            });
        }
    }
    let series = collect(path, &options.topics, options.time_source)?;
    for s in &series {
        if s.effort.is_none() {
            return Err(mcap_error(path, Some(&s.topic), McapProblem::NoEffort));
        }
    }
    merge(path, series, options)
}

/// Reads the JointState messages of `topics` as they are, one [`JointStateSeries`] per
/// topic, with the message checks of [`read_mcap`] but without the timing checks,
/// merging and effort requirement: e.g. a setpoint topic, whose velocity and effort
/// arrays are empty. `topics` empty: the automatic choice of [`read_mcap`].
pub fn read_joint_states(
    path: impl AsRef<Path>,
    topics: &[String],
    time_source: TimeSource,
) -> Result<Vec<JointStateSeries>, LogError> {
    collect(path.as_ref(), topics, time_source)
}

/// Per-topic accumulation of decoded messages.
struct Acc {
    topic: String,
    /// Automatic mode: not a candidate (no positions or no efforts in message 0), why.
    rejected: Option<&'static str>,
    /// Automatic mode: the first problem, reported only if the topic is chosen.
    error: Option<LogError>,
    count: usize,
    names: Vec<String>,
    index_of: HashMap<String, usize>,
    /// Last message order that differed from `names`, and its permutation:
    /// `perm[j]` = index in the message of `names[j]`.
    reorder: Option<(Vec<String>, Vec<usize>)>,
    frame_id: String,
    has_velocity: bool,
    has_effort: bool,
    stamps: Vec<i64>,
    position: Vec<f64>,
    velocity: Vec<f64>,
    effort: Vec<f64>,
}

impl Acc {
    fn new(topic: &str) -> Acc {
        Acc {
            topic: topic.to_owned(),
            rejected: None,
            error: None,
            count: 0,
            names: Vec::new(),
            index_of: HashMap::new(),
            reorder: None,
            frame_id: String::new(),
            has_velocity: false,
            has_effort: false,
            stamps: Vec::new(),
            position: Vec::new(),
            velocity: Vec::new(),
            effort: Vec::new(),
        }
    }

    /// Checks and appends one message.
    fn push(&mut self, msg: JointStateMsg, stamp: i64, auto: bool) -> Result<(), Box<McapProblem>> {
        let index = self.count;
        self.count += 1;
        let names = if msg.name.is_empty() {
            (1..=msg.position.len())
                .map(|k| format!("joint_{k}"))
                .collect()
        } else {
            msg.name
        };
        if index == 0 {
            if auto && msg.position.is_empty() {
                self.rejected = Some("no positions");
                return Ok(());
            }
            if auto && msg.effort.is_empty() {
                self.rejected = Some("no efforts");
                return Ok(());
            }
            if names.is_empty() {
                return Err(Box::new(McapProblem::NoJoints { index }));
            }
            for (k, n) in names.iter().enumerate() {
                if self.index_of.insert(n.clone(), k).is_some() {
                    return Err(Box::new(McapProblem::DuplicateJoint {
                        joint: n.clone(),
                        context: "in message 0".into(),
                    }));
                }
            }
            self.names = names.clone();
            self.frame_id = msg.header.frame_id;
            self.has_velocity = !msg.velocity.is_empty();
            self.has_effort = !msg.effort.is_empty();
        }
        let joints = self.names.len();
        // The permutation from this message's order to the first message's.
        let perm: Option<&[usize]> = if names == self.names {
            None
        } else {
            let cached = matches!(&self.reorder, Some((order, _)) if *order == names);
            if !cached {
                let changed = || {
                    Box::new(McapProblem::JointsChanged {
                        index,
                        first: self.names.clone(),
                        found: names.clone(),
                    })
                };
                if names.len() != joints {
                    return Err(changed());
                }
                let mut perm = vec![usize::MAX; joints];
                for (k, n) in names.iter().enumerate() {
                    match self.index_of.get(n) {
                        Some(&j) if perm[j] == usize::MAX => perm[j] = k,
                        _ => return Err(changed()),
                    }
                }
                self.reorder = Some((names.clone(), perm));
            }
            self.reorder.as_ref().map(|(_, p)| p.as_slice())
        };
        let arrays = [
            ("position", Signal::Position, &msg.position, true),
            (
                "velocity",
                Signal::Velocity,
                &msg.velocity,
                self.has_velocity,
            ),
            ("effort", Signal::Effort, &msg.effort, self.has_effort),
        ];
        for (field, signal, values, expected) in arrays {
            if values.is_empty() && field != "position" {
                if expected {
                    return Err(Box::new(McapProblem::Inconsistent {
                        index,
                        field,
                        empty: true,
                    }));
                }
                continue;
            }
            if !expected {
                return Err(Box::new(McapProblem::Inconsistent {
                    index,
                    field,
                    empty: false,
                }));
            }
            if values.len() != joints {
                return Err(Box::new(McapProblem::ArrayLength {
                    index,
                    field,
                    len: values.len(),
                    joints,
                }));
            }
            if let Some(k) = values.iter().position(|v| !v.is_finite()) {
                let time_s = self
                    .stamps
                    .first()
                    .map_or(0.0, |&s0| (i128::from(stamp) - i128::from(s0)) as f64 / 1e9);
                return Err(Box::new(McapProblem::NonFinite {
                    index,
                    time_s,
                    signal,
                    joint: names[k].clone(),
                    value: values[k],
                }));
            }
        }
        let append = |out: &mut Vec<f64>, values: &[f64]| match perm {
            None => out.extend_from_slice(values),
            Some(p) => out.extend(p.iter().map(|&k| values[k])),
        };
        append(&mut self.position, &msg.position);
        if self.has_velocity {
            append(&mut self.velocity, &msg.velocity);
        }
        if self.has_effort {
            append(&mut self.effort, &msg.effort);
        }
        self.stamps.push(stamp);
        Ok(())
    }

    fn into_series(self) -> JointStateSeries {
        let (n, dof) = (self.stamps.len(), self.names.len());
        let matrix = |v: Vec<f64>| DMatrix::from_row_slice(n, dof, &v);
        JointStateSeries {
            topic: self.topic,
            joint_names: self.names,
            frame_id: self.frame_id,
            stamps_ns: self.stamps,
            position: matrix(self.position),
            velocity: self.has_velocity.then(|| matrix(self.velocity)),
            effort: self.has_effort.then(|| matrix(self.effort)),
        }
    }
}

fn is_joint_state(c: &container::ChannelInfo) -> bool {
    let enc = c.message_encoding.as_str();
    (c.schema_name == JOINT_STATE_TYPE && (enc == "cdr" || enc == "json"))
        || (c.schema_name == "sensor_msgs/JointState" && enc == "json")
}

fn decode(c: &container::ChannelInfo, data: &[u8]) -> Result<JointStateMsg, String> {
    if c.message_encoding == "json" {
        joint_state::decode_json(data)
    } else {
        joint_state::decode_cdr(data)
    }
}

/// One pass over the file: decodes and checks the JointStates of the requested topics
/// (or of every candidate topic in automatic mode), then picks the topics.
fn collect(
    path: &Path,
    topics: &[String],
    time_source: TimeSource,
) -> Result<Vec<JointStateSeries>, LogError> {
    let auto = topics.is_empty();
    let mut accs: BTreeMap<String, Acc> = BTreeMap::new();
    if !auto {
        for (k, t) in topics.iter().enumerate() {
            if topics[..k].contains(t) {
                return Err(mcap_error(path, Some(t), McapProblem::RepeatedTopic));
            }
            accs.insert(t.clone(), Acc::new(t));
        }
    }
    let on_message = |m: MessageRef<'_>| -> Result<(), LogError> {
        let topic = m.channel.topic.as_str();
        if !is_joint_state(m.channel) {
            if !auto && accs.contains_key(topic) {
                return Err(mcap_error(
                    path,
                    Some(topic),
                    McapProblem::WrongType {
                        schema_name: m.channel.schema_name.clone(),
                        message_encoding: m.channel.message_encoding.clone(),
                    },
                ));
            }
            return Ok(());
        }
        let acc = match accs.get_mut(topic) {
            Some(a) => a,
            None if auto => accs
                .entry(topic.to_owned())
                .or_insert_with(|| Acc::new(topic)),
            None => return Ok(()),
        };
        if acc.rejected.is_some() || acc.error.is_some() {
            return Ok(());
        }
        let index = acc.count;
        let result = (|| {
            let msg = decode(m.channel, m.data)
                .map_err(|reason| Box::new(McapProblem::Decode { index, reason }))?;
            let stamp = match time_source {
                TimeSource::HeaderStamp => Ok(msg.header.stamp.as_nanos()),
                TimeSource::LogTime => i64::try_from(m.log_time).map_err(|_| m.log_time),
                TimeSource::PublishTime => {
                    i64::try_from(m.publish_time).map_err(|_| m.publish_time)
                }
            }
            .map_err(|value| {
                Box::new(McapProblem::TimeOutOfRange {
                    index,
                    time_source,
                    value,
                })
            })?;
            acc.push(msg, stamp, auto)
        })();
        match result {
            Ok(()) => Ok(()),
            Err(problem) => {
                let e = LogError::Mcap {
                    path: path.to_path_buf(),
                    topic: Some(topic.to_owned()),
                    problem,
                };
                if auto {
                    acc.error = Some(e);
                    Ok(())
                } else {
                    Err(e)
                }
            }
        }
    };
    let scan = container::scan(path, on_message)?;
    let info = |t: &str| scan.topics.iter().find(|i| i.topic == t);
    let chosen: Vec<Acc> = if auto {
        let candidates: Vec<&Acc> = accs.values().filter(|a| a.rejected.is_none()).collect();
        let pick = match candidates.len() {
            0 => {
                let rejected = accs
                    .values()
                    .filter_map(|a| a.rejected.map(|why| format!("{}: {why}", a.topic)))
                    .collect();
                return Err(mcap_error(
                    path,
                    None,
                    McapProblem::NoJointStates {
                        available: scan.topics,
                        rejected,
                    },
                ));
            }
            1 => candidates[0].topic.clone(),
            _ => {
                let measured: Vec<&&Acc> = candidates
                    .iter()
                    .filter(|a| a.topic.ends_with("measured_js"))
                    .collect();
                if measured.len() == 1 {
                    measured[0].topic.clone()
                } else {
                    return Err(mcap_error(
                        path,
                        None,
                        McapProblem::Ambiguous {
                            candidates: candidates.iter().map(|a| a.topic.clone()).collect(),
                        },
                    ));
                }
            }
        };
        vec![accs.remove(&pick).expect("picked from accs")]
    } else {
        topics
            .iter()
            .map(|t| accs.remove(t).expect("one accumulator per topic"))
            .collect()
    };
    let mut out = Vec::with_capacity(chosen.len());
    for acc in chosen {
        if let Some(e) = acc.error {
            return Err(e);
        }
        if acc.count == 0 {
            let problem = match info(&acc.topic) {
                None => McapProblem::TopicNotFound {
                    available: scan.topics.clone(),
                },
                Some(_) => McapProblem::EmptyTopic,
            };
            return Err(mcap_error(path, Some(&acc.topic), problem));
        }
        out.push(acc.into_series());
    }
    Ok(out)
}

/// Order statistics of a stamp sequence.
struct Order {
    /// First offending index.
    first: Option<usize>,
    backwards: usize,
    duplicates: usize,
}

fn order(stamps: &[i64]) -> Order {
    let mut o = Order {
        first: None,
        backwards: 0,
        duplicates: 0,
    };
    for (k, w) in stamps.windows(2).enumerate() {
        if w[1] <= w[0] {
            if w[1] == w[0] {
                o.duplicates += 1;
            } else {
                o.backwards += 1;
            }
            o.first.get_or_insert(k + 1);
        }
    }
    o
}

fn seconds_between(a: i64, b: i64) -> f64 {
    (i128::from(b) - i128::from(a)) as f64 / 1e9
}

fn check_increasing(
    path: &Path,
    topic: &str,
    stamps: &[i64],
    time_source: TimeSource,
) -> Result<(), LogError> {
    let o = order(stamps);
    if let Some(index) = o.first {
        return Err(mcap_error(
            path,
            Some(topic),
            McapProblem::NotIncreasing {
                index,
                time_s: seconds_between(stamps[0], stamps[index]),
                previous_s: seconds_between(stamps[0], stamps[index - 1]),
                backwards: o.backwards,
                duplicates: o.duplicates,
                samples: stamps.len(),
                time_source,
            },
        ));
    }
    Ok(())
}

/// Gaps and jitter of strictly increasing stamps (integer arithmetic on ns steps).
fn timing(stamps: &[i64]) -> TimingReport {
    let steps: Vec<i128> = stamps
        .windows(2)
        .map(|w| i128::from(w[1]) - i128::from(w[0]))
        .collect();
    let mut report = TimingReport {
        samples: stamps.len(),
        median_step_s: 0.0,
        gaps: 0,
        jittered: 0,
        largest_step_s: 0.0,
        first_irregular: None,
        resampled_hz: None,
    };
    if steps.is_empty() {
        return report;
    }
    let mut sorted = steps.clone();
    sorted.sort_unstable();
    let m = sorted.len();
    // Median in half-nanoseconds, to stay in integers for an even count.
    let median2 = if m % 2 == 1 {
        2 * sorted[m / 2]
    } else {
        sorted[m / 2 - 1] + sorted[m / 2]
    };
    report.median_step_s = median2 as f64 / 2e9;
    report.largest_step_s = sorted[m - 1] as f64 / 1e9;
    for (k, &s) in steps.iter().enumerate() {
        let s2 = 2 * s;
        let irregular = if s2 as f64 > GAP_FACTOR * median2 as f64 {
            report.gaps += 1;
            true
        } else if ((s2 - median2).abs() as f64) > JITTER_TOLERANCE * median2 as f64 {
            report.jittered += 1;
            true
        } else {
            false
        };
        if irregular && report.first_irregular.is_none() {
            report.first_irregular = Some(k + 1);
        }
    }
    report
}

fn non_uniform(
    path: &Path,
    topic: &str,
    stamps: &[i64],
    report: &TimingReport,
    time_source: TimeSource,
) -> LogError {
    let index = report.first_irregular.unwrap_or(1);
    let suggested = if report.median_step_s > 0.0 {
        (1.0 / report.median_step_s).round().max(1.0)
    } else {
        1.0
    };
    mcap_error(
        path,
        Some(topic),
        McapProblem::NonUniform {
            index,
            time_s: seconds_between(stamps[0], stamps[index]),
            step_s: seconds_between(stamps[index - 1], stamps[index]),
            median_step_s: report.median_step_s,
            gaps: report.gaps,
            jittered: report.jittered,
            largest_step_s: report.largest_step_s,
            samples: report.samples,
            time_source,
            suggested_hz: suggested,
        },
    )
}

/// Values of `m` (rows at the strictly increasing `stamps`) at the clock stamps `at`
/// (within `stamps[0]..=stamps[last]`): exact rows where a stamp matches, linear
/// interpolation between the two neighbours otherwise.
fn sample_at(stamps: &[i64], m: &DMatrix<f64>, at: &[i64]) -> DMatrix<f64> {
    let mut out = DMatrix::zeros(at.len(), m.ncols());
    let mut seg = 0;
    for (i, &t) in at.iter().enumerate() {
        while seg + 1 < stamps.len() && stamps[seg + 1] <= t {
            seg += 1;
        }
        if stamps[seg] == t || seg + 1 == stamps.len() {
            out.row_mut(i).copy_from(&m.row(seg));
        } else {
            let w = seconds_between(stamps[seg], t) / seconds_between(stamps[seg], stamps[seg + 1]);
            for j in 0..m.ncols() {
                out[(i, j)] = (1.0 - w) * m[(seg, j)] + w * m[(seg + 1, j)];
            }
        }
    }
    out
}

/// Checks timing, merges the topics on the first one's clock, resamples if asked.
fn merge(
    path: &Path,
    series: Vec<JointStateSeries>,
    options: &McapOptions,
) -> Result<McapLog, LogError> {
    let ts = options.time_source;
    // Joint names unique across topics.
    let mut owner: HashMap<&str, &str> = HashMap::new();
    for s in &series {
        for n in &s.joint_names {
            if let Some(first) = owner.insert(n.as_str(), s.topic.as_str()) {
                return Err(mcap_error(
                    path,
                    Some(&s.topic),
                    McapProblem::DuplicateJoint {
                        joint: n.clone(),
                        context: format!(
                            "also on topic {first}; merged topics need distinct joint names"
                        ),
                    },
                ));
            }
        }
    }
    for s in &series {
        check_increasing(path, &s.topic, &s.stamps_ns, ts)?;
    }
    // Gaps in the other topics would be bridged by interpolation: refuse them too.
    if options.resample_hz.is_none() {
        for s in &series[1..] {
            let r = timing(&s.stamps_ns);
            if r.gaps > 0 {
                return Err(non_uniform(path, &s.topic, &s.stamps_ns, &r, ts));
            }
        }
    }
    let clock = &series[0];
    let (mut lo, mut hi) = (i64::MIN, i64::MAX);
    for s in &series[1..] {
        lo = lo.max(s.stamps_ns[0]);
        hi = hi.min(*s.stamps_ns.last().expect("non-empty"));
    }
    let first = clock.stamps_ns.partition_point(|&t| t < lo);
    let end = clock.stamps_ns.partition_point(|&t| t <= hi);
    if first >= end {
        let mut detail = String::new();
        let t0 = clock.stamps_ns[0];
        for s in &series {
            let _ = write!(
                detail,
                "{}{} from {} s to {} s",
                if detail.is_empty() { "" } else { ", " },
                s.topic,
                seconds_between(t0, s.stamps_ns[0]),
                seconds_between(t0, *s.stamps_ns.last().expect("non-empty"))
            );
        }
        return Err(mcap_error(path, None, McapProblem::NoOverlap { detail }));
    }
    let trimmed = (first, clock.stamps_ns.len() - end);
    let stamps = &clock.stamps_ns[first..end];
    let mut timing_report = timing(stamps);
    if options.resample_hz.is_none() && timing_report.first_irregular.is_some() {
        return Err(non_uniform(path, &clock.topic, stamps, &timing_report, ts));
    }
    let n = stamps.len();
    let dof: usize = series.iter().map(|s| s.joint_names.len()).sum();
    let with_velocity = series.iter().all(|s| s.velocity.is_some());
    let mut q = DMatrix::zeros(n, dof);
    let mut dq = DMatrix::zeros(n, if with_velocity { dof } else { 0 });
    let mut tau = DMatrix::zeros(n, dof);
    let mut col = 0;
    for (k, s) in series.iter().enumerate() {
        let w = s.joint_names.len();
        let take = |m: &DMatrix<f64>| {
            if k == 0 {
                m.rows(first, n).into_owned()
            } else {
                sample_at(&s.stamps_ns, m, stamps)
            }
        };
        q.columns_mut(col, w).copy_from(&take(&s.position));
        if let Some(v) = &s.velocity {
            if with_velocity {
                dq.columns_mut(col, w).copy_from(&take(v));
            }
        }
        let e = s.effort.as_ref().expect("checked by the caller");
        tau.columns_mut(col, w).copy_from(&take(e));
        col += w;
    }
    let mut time: Vec<f64> = stamps
        .iter()
        .map(|&t| seconds_between(stamps[0], t))
        .collect();
    let mut dq = with_velocity.then_some(dq);
    let topics: Vec<String> = series.iter().map(|s| s.topic.clone()).collect();
    if let Some(rate) = options.resample_hz {
        let resample = |m: &DMatrix<f64>| {
            crate::signal::resample_linear(&time, m, rate).map_err(|e| {
                mcap_error(
                    path,
                    Some(&clock.topic),
                    McapProblem::Resample {
                        reason: e.to_string(),
                    },
                )
            })
        };
        let (t, q2) = resample(&q)?;
        let (_, tau2) = resample(&tau)?;
        let dq2 = match &dq {
            Some(d) => Some(resample(d)?.1),
            None => None,
        };
        time = t;
        q = q2;
        tau = tau2;
        dq = dq2;
        timing_report.resampled_hz = Some(rate);
    }
    let trajectory = Trajectory {
        time,
        q,
        dq,
        tau,
        joint_names: series.iter().flat_map(|s| s.joint_names.clone()).collect(),
        coordinates: Coordinates::Measured,
        source: format!("{} ({})", path.display(), topics.join(" + ")),
    };
    trajectory
        .validate()
        .map_err(|e| mcap_error(path, Some(&clock.topic), McapProblem::Invalid(e)))?;
    Ok(McapLog {
        trajectory,
        start_time_ns: stamps[0],
        topics,
        time_source: ts,
        timing: timing_report,
        trimmed,
    })
}

/// Chunk compression of written files.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum McapCompression {
    /// No compression.
    None,
    /// zstd (what ROS 2 tools use).
    #[default]
    Zstd,
    /// lz4.
    Lz4,
}

/// How [`write_mcap`] writes.
#[derive(Clone, Debug, PartialEq)]
pub struct McapWriteOptions {
    /// Absolute time of `t = 0`, ns since the epoch: `header.stamp` of sample `k` is
    /// `start_time_ns + round(time[k] * 1e9)`, and so are its log and publish times.
    pub start_time_ns: i64,
    /// `header.frame_id` of every message.
    pub frame_id: String,
    /// Chunk compression.
    pub compression: McapCompression,
}

impl Default for McapWriteOptions {
    /// Start at 0 ns (the epoch), empty frame id, zstd.
    fn default() -> Self {
        McapWriteOptions {
            start_time_ns: 0,
            frame_id: String::new(),
            compression: McapCompression::Zstd,
        }
    }
}

/// Writes `traj` (measured coordinates) as `sensor_msgs/msg/JointState` messages on
/// `topic` of a ROS 2 MCAP file, one message per sample: `name` = joint names,
/// `position` = q, `velocity` = dq (empty arrays when `dq` is `None`), `effort` = tau,
/// `header.stamp` = log time = publish time = `start_time_ns + round(time * 1e9)` ns,
/// sequence = sample index. The file is written to a temporary file in the same
/// directory and renamed, so a failure never leaves a partial file under `path`.
///
/// Reading it back with [`read_mcap`] gives the same values and joint names, and the
/// times relative to the first sample at 1 ns resolution (exactly `time` when
/// `time[0] == 0` and the times are whole nanoseconds or `k / rate` for a rate dividing
/// 1e9).
pub fn write_mcap(
    path: impl AsRef<Path>,
    traj: &Trajectory,
    topic: &str,
    options: &McapWriteOptions,
) -> Result<(), LogError> {
    let path = path.as_ref();
    traj.validate().map_err(|source| LogError::Invalid {
        path: path.to_path_buf(),
        source,
    })?;
    let err = |p: McapProblem| mcap_error(path, Some(topic), p);
    if traj.coordinates != Coordinates::Measured {
        return Err(err(McapProblem::WrongCoordinates));
    }
    if topic.is_empty() || topic.chars().any(char::is_whitespace) {
        return Err(err(McapProblem::BadTopic(topic.to_owned())));
    }
    // Stamps first, so that a bad one leaves nothing behind.
    let mut stamps: Vec<(i64, Time)> = Vec::with_capacity(traj.len());
    for (index, &t) in traj.time.iter().enumerate() {
        let bad = || err(McapProblem::BadStamp { index, time_s: t });
        let offset = (t * 1e9).round();
        if !offset.is_finite() || offset.abs() >= 9.2e18 {
            return Err(bad());
        }
        let ns = options
            .start_time_ns
            .checked_add(offset as i64)
            .filter(|&ns| ns >= 0 && stamps.last().is_none_or(|&(p, _)| ns > p))
            .ok_or_else(bad)?;
        let stamp = Time::from_nanos(ns).ok_or_else(bad)?;
        stamps.push((ns, stamp));
    }
    let compression = match options.compression {
        McapCompression::None => None,
        McapCompression::Zstd => Some(::mcap::Compression::Zstd),
        McapCompression::Lz4 => Some(::mcap::Compression::Lz4),
    };
    let write_options = ::mcap::WriteOptions::new()
        .profile("ros2")
        .library(format!(
            "dvrk-ident/{} {}",
            env!("CARGO_PKG_VERSION"),
            ::mcap::LIBRARY_IDENTIFIER
        ))
        .compression(compression)
        .compression_threads(0);
    write_atomic_seek(path, |file| {
        let mut w = write_options.create(file)?;
        let schema = w.add_schema(JOINT_STATE_TYPE, "ros2msg", JOINT_STATE_SCHEMA.as_bytes())?;
        let channel = w.add_channel(schema, topic, "cdr", &BTreeMap::new())?;
        let mut msg = JointStateMsg {
            header: Header {
                stamp: Time::default(),
                frame_id: options.frame_id.clone(),
            },
            name: traj.joint_names.clone(),
            position: Vec::new(),
            velocity: Vec::new(),
            effort: Vec::new(),
        };
        for (k, &(ns, stamp)) in stamps.iter().enumerate() {
            msg.header.stamp = stamp;
            msg.position.clear();
            msg.position.extend(traj.q.row(k).iter());
            msg.velocity.clear();
            if let Some(dq) = &traj.dq {
                msg.velocity.extend(dq.row(k).iter());
            }
            msg.effort.clear();
            msg.effort.extend(traj.tau.row(k).iter());
            let data = joint_state::encode_cdr(&msg).map_err(|reason| {
                ::mcap::McapError::Io(std::io::Error::other(format!("CDR encoding: {reason}")))
            })?;
            let header = ::mcap::records::MessageHeader {
                channel_id: channel,
                sequence: k as u32,
                log_time: ns as u64,
                publish_time: ns as u64,
            };
            w.write_to_known_channel(&header, &data)?;
        }
        w.finish()?;
        Ok(w.into_inner())
    })
}

/// [`crate::log::write_atomic_file`] with the MCAP writer's errors named.
fn write_atomic_seek(
    path: &Path,
    fill: impl FnOnce(
        std::io::BufWriter<std::fs::File>,
    ) -> Result<std::io::BufWriter<std::fs::File>, ::mcap::McapError>,
) -> Result<(), LogError> {
    crate::log::write_atomic_file(path, |w| {
        fill(w).map_err(|e| match e {
            ::mcap::McapError::Io(source) => LogError::Io {
                path: path.to_path_buf(),
                source,
            },
            other => mcap_error(
                path,
                None,
                McapProblem::Write {
                    reason: other.to_string(),
                },
            ),
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn time_source_names() {
        for s in [
            TimeSource::HeaderStamp,
            TimeSource::LogTime,
            TimeSource::PublishTime,
        ] {
            let name = serde_json::to_string(&s).unwrap();
            assert_eq!(name.trim_matches('"').parse::<TimeSource>().unwrap(), s);
        }
        assert_eq!(
            "log-time".parse::<TimeSource>().unwrap(),
            TimeSource::LogTime
        );
        assert_eq!(
            "Header".parse::<TimeSource>().unwrap(),
            TimeSource::HeaderStamp
        );
        assert!("wall".parse::<TimeSource>().is_err());
    }

    #[test]
    fn timing_counts_gaps_and_jitter() {
        let mut s: Vec<i64> = (0..100).map(|k| k * 5_000_000).collect();
        let r = timing(&s);
        assert_eq!((r.gaps, r.jittered, r.first_irregular), (0, 0, None));
        assert_eq!(r.median_step_s, 0.005);
        s[50] += 1_000_000; // one step 6 ms, the next 4 ms: both jitter (20 %)
        for t in &mut s[80..] {
            *t += 10_000_000; // a 15 ms step: a gap
        }
        let r = timing(&s);
        assert_eq!((r.gaps, r.jittered, r.first_irregular), (1, 2, Some(50)));
        assert!((r.largest_step_s - 0.015).abs() < 1e-15);
        let o = order(&[0, 1, 1, 0, 2]);
        assert_eq!((o.first, o.duplicates, o.backwards), (Some(2), 1, 1));
    }

    #[test]
    fn sample_at_exact_and_interpolated() {
        let stamps = [0, 10, 20];
        let m = DMatrix::from_column_slice(3, 1, &[0.0, 1.0, 3.0]);
        let r = sample_at(&stamps, &m, &[0, 5, 10, 15, 20]);
        assert_eq!(r.as_slice(), &[0.0, 0.5, 1.0, 2.0, 3.0]);
    }
}
