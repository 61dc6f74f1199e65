//! Recordings of `sensor_msgs/msg/JointState` (dVRK 2.x / CRTK `measured_js`): ROS 2
//! MCAP files, rosbag2 folders (`metadata.yaml` and its MCAP or sqlite3 `.db3` files,
//! in order: split recordings are one log), single `.db3` files, and ROS 1 bags of
//! `sensor_msgs/JointState`; files compressed as a whole (zstd, lz4: rosbag2's
//! `compression_mode: file`, e.g. `*.mcap.zstd`) and messages compressed one by one
//! (`compression_mode: message`). All are recognized by content (`bag`), read message by
//! message in file order (`container`, `sqlite`, `ros1`) and decoded to the same
//! JointState (CDR, JSON or ROS 1 serialization), so everything below holds for each.
//!
//! # Reading
//!
//! [`McapReader`] reads a log block by block without holding it: [`McapReader::open`]
//! makes every check below in passes over the file that keep no samples (usually one;
//! see `survey`), and [`McapReader::blocks`] reads the samples, merged and resampled, in
//! blocks. [`read_mcap`] (or [`read_mcap_log`], which also returns the absolute start
//! time, the topics and a timing report) collects every block. An MCAP file is streamed
//! message by message: the `mcap` crate decompresses one chunk at a time (zstd or lz4)
//! and checks the chunk, data and summary CRCs, and only the joint states of the wanted
//! topics are decoded. Messages may be CDR (`cdr` message encoding, what ROS 2 records),
//! JSON (`json`, Foxglove) or ROS 1 (`ros1`).
//!
//! **Topic choice** ([`McapOptions::topics`] empty): among the `sensor_msgs/msg/JointState`
//! topics, the one whose messages have both positions and efforts; if several do, the
//! one whose name ends in `measured_js` (the dVRK/CRTK convention); if that is still not
//! a single topic, an error lists the candidates. When the joints the caller needs are
//! known ([`McapOptions::joints`], a robot's measured joints), a topic that holds them
//! all comes first, then the dVRK 2.x pair `X/measured_js` + `X/jaw/measured_js` (the
//! PSM's jaw on its own topic) that holds them together, merged as below. A topic that is named explicitly must
//! exist, hold JointState messages and not be empty. The choice takes the first pass
//! over the file: every candidate topic is decoded and checked until the end (a
//! JointState topic stops being a candidate at its first message without positions or
//! efforts), keeping only statistics of its stamps.
//!
//! **Several topics** (e.g. dVRK 2.x publishes the PSM jaw on `/PSM1/jaw/measured_js`
//! beside the six arm joints on `/PSM1/measured_js`): the joints are concatenated in the
//! order of the topics, and the *first* topic is the clock. Every other topic is sampled
//! at the first topic's stamps: a sample with the same stamp is taken as it is, otherwise
//! the two neighbouring samples are interpolated linearly. Samples of the first topic
//! outside the time span of another topic (it may start a little later or stop a little
//! earlier) are dropped at either end ([`McapLog::trimmed`]); a gap in another topic is
//! refused like a gap of the clock unless resampling is asked for. Velocities are kept
//! only if every topic has them; joint names must be unique across topics. The topics
//! are merged as their messages come: a clock sample waits for the other topics to
//! reach its stamp, so memory is bounded by how far apart the topics are written in
//! the file (a recorder interleaves them), not by the log.
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

pub(crate) mod bag;
mod blocks;
mod channels;
mod container;
mod joint_state;
mod ros1;
mod sqlite;
mod survey;
mod topic;

pub use self::blocks::McapBlocks;
pub use self::joint_state::{JOINT_STATE_SCHEMA, JOINT_STATE_TYPE};

use self::channels::mcap_error;
use self::joint_state::{Header, JointStateMsg, Time};
use crate::log::LogError;
use crate::trajectory::{Coordinates, Signal, Trajectory, TrajectoryError};
use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;
use std::sync::Arc;
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

impl crate::names::Named for TimeSource {
    const WHAT: &'static str = "time source";
    const NAMES: &'static [(&'static str, Self)] = &[
        ("header", TimeSource::HeaderStamp),
        ("log", TimeSource::LogTime),
        ("publish", TimeSource::PublishTime),
        ("stamp", TimeSource::HeaderStamp),
        ("header_stamp", TimeSource::HeaderStamp),
        ("log_time", TimeSource::LogTime),
        ("publish_time", TimeSource::PublishTime),
    ];
    const CANONICAL: usize = 3;
}

impl std::str::FromStr for TimeSource {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        <Self as crate::names::Named>::parse_name(s)
    }
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
    /// The joints the caller needs (e.g. a robot's measured joints), for the automatic
    /// topic choice: a topic holding them all, else a dVRK arm topic and its jaw topic
    /// (`X/measured_js` + `X/jaw/measured_js`) holding them together. Empty: unknown.
    pub joints: Vec<String>,
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
    /// A file (or folder) that is no recording of a supported format.
    #[error("not a supported log: it looks like {looks_like}; {}", bag::SUPPORTED)]
    NotARecording {
        /// What it looks like.
        looks_like: String,
    },
    /// A rosbag2 metadata.yaml that cannot be used.
    #[error("invalid rosbag2 metadata.yaml: {reason}")]
    Metadata {
        /// What is wrong.
        reason: String,
    },
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
    #[error("the topic holds {} messages in {message_encoding:?} encoding, not {JOINT_STATE_TYPE} in cdr or json encoding (or sensor_msgs/JointState in ros1 encoding)", if schema_name.is_empty() { "schemaless" } else { schema_name })]
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
    #[error("several {JOINT_STATE_TYPE} topics (or arm and jaw topic pairs) have positions and efforts: {}; choose one with --topic (repeat --topic to merge the joints of several topics, e.g. an arm and its jaw)", candidates.join(", "))]
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
    let bag = Arc::new(bag::Bag::open(path.as_ref())?);
    Ok(container::scan(&bag, |_| Ok(()))?.topics)
}

/// Reads an MCAP log into a [`Trajectory`] in measured coordinates (see the module docs
/// for topic choice, merging, time and checks).
pub fn read_mcap(path: impl AsRef<Path>, options: &McapOptions) -> Result<Trajectory, LogError> {
    read_mcap_log(path, options).map(|log| log.trajectory)
}

/// [`read_mcap`], also returning the absolute start time, the topics read and the timing
/// report: every block of an [`McapReader`], collected.
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
    let reader = McapReader::open(path, options)?;
    let mut all = crate::log::TrajectoryBuilder::default();
    for block in reader.blocks(crate::log::BLOCK_SAMPLES)? {
        all.push(&block?);
    }
    Ok(McapLog {
        trajectory: all.build(),
        start_time_ns: reader.plan.start_time_ns,
        topics: reader.plan.topics.clone(),
        time_source: reader.plan.time_source,
        timing: reader.plan.timing.clone(),
        trimmed: reader.plan.trimmed,
    })
}

/// An MCAP log read block by block: [`McapReader::open`] chooses the topics and makes
/// every check of [`read_mcap`] (messages, stamps, gaps, overlap) in passes that keep no
/// samples; [`McapReader::blocks`] then reads the samples in blocks, as many times as
/// needed. Memory is bounded by the block, the largest chunk of the file and how far
/// merged topics are apart in it, not by the log's length.
#[derive(Clone, Debug)]
pub struct McapReader {
    bag: Arc<bag::Bag>,
    plan: survey::Plan,
}

impl McapReader {
    /// Opens `path` (a file or a rosbag2 folder, see the module docs) and checks it
    /// (see the type docs); errors are those of [`read_mcap`].
    pub fn open(path: impl AsRef<Path>, options: &McapOptions) -> Result<McapReader, LogError> {
        let bag = Arc::new(bag::Bag::open(path.as_ref())?);
        Ok(McapReader {
            plan: survey::plan(&bag, options)?,
            bag,
        })
    }

    /// The samples in blocks of at most `block_samples`, in order, each validated like
    /// the whole trajectory (rows numbered from the log's start); one pass over the file.
    pub fn blocks(&self, block_samples: usize) -> Result<McapBlocks<'_>, LogError> {
        McapBlocks::new(&self.bag, &self.plan, block_samples)
    }

    /// The recording's format: [`LogFormat::Mcap`], [`LogFormat::Rosbag2`] (a folder),
    /// [`LogFormat::Sqlite3`] or [`LogFormat::Ros1`].
    pub fn format(&self) -> crate::log::LogFormat {
        self.bag.format
    }

    /// The files read, in order (one, or those of a rosbag2 folder).
    pub fn files(&self) -> Vec<std::path::PathBuf> {
        self.bag.files.iter().map(|f| f.path.clone()).collect()
    }

    /// The topics read, the clock first.
    pub fn topics(&self) -> &[String] {
        &self.plan.topics
    }

    /// The joints of the samples: every topic's, in topic order.
    pub fn joint_names(&self) -> Vec<String> {
        self.plan.joints.concat()
    }

    /// Whether the samples have velocities (every topic has them).
    pub fn has_velocity(&self) -> bool {
        self.plan.with_velocity
    }

    /// Number of samples the blocks hold.
    pub fn samples(&self) -> usize {
        self.plan.samples
    }

    /// The absolute time of the first sample, ns since the epoch.
    pub fn start_time_ns(&self) -> i64 {
        self.plan.start_time_ns
    }

    /// Timing of the clock topic.
    pub fn timing(&self) -> &TimingReport {
        &self.plan.timing
    }
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
    let bag = Arc::new(bag::Bag::open(path.as_ref())?);
    Ok(survey::survey(&bag, topics, &[], time_source, true)?
        .into_iter()
        .map(survey::TopicSurvey::into_series)
        .collect())
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
}
