//! Why a recording could not be read or written: [`McapProblem`], which
//! [`LogError::Mcap`] wraps with the file and the topic.

use serde::{Deserialize, Serialize};
#[cfg(feature = "recordings")]
use std::path::Path;

use thiserror::Error;

use super::options::{TimeSource, GAP_FACTOR, JITTER_TOLERANCE};
use super::schema::JOINT_STATE_TYPE;
use crate::hint::Hint;
use crate::joint_log::{JointLogError, Signal};
#[cfg_attr(not(feature = "recordings"), allow(unused_imports))] // the docs' link
use crate::log::LogError;

/// Why a message does not decode as a `sensor_msgs/msg/JointState`
/// ([`McapProblem::Decode`]).
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum DecodeError {
    /// A CDR message shorter than its encapsulation header.
    #[error("{bytes} bytes: too short for the 4-byte CDR encapsulation header")]
    TooShort {
        /// The message's length, bytes.
        bytes: usize,
    },
    /// A CDR representation other than plain CDR.
    #[error("CDR encapsulation {kind:#06x} is {what}; only plain CDR (0x0000 big-endian, 0x0001 little-endian) is supported")]
    Encapsulation {
        /// The representation identifier (the header's first two bytes, big-endian).
        kind: u16,
        /// What it is (`XCDR2 (CDR2)`).
        what: &'static str,
    },
    /// A message that ends inside a field.
    #[error(
        "message ends in field {field}: {needed} bytes needed at offset {offset}, {left} left"
    )]
    Truncated {
        /// The field (`header.frame_id`).
        field: &'static str,
        /// The bytes it needs.
        needed: usize,
        /// Where, counted from the message's start (its encapsulation header included).
        offset: usize,
        /// The bytes left.
        left: usize,
    },
    /// A string field that is not UTF-8.
    #[error("field {field}: invalid UTF-8: {error}")]
    Utf8 {
        /// The field.
        field: &'static str,
        /// Where the bytes stop being UTF-8.
        error: std::str::Utf8Error,
    },
    /// A sequence length larger than the bytes left could hold.
    #[error("field {field}: sequence of {count} elements does not fit in the {left} bytes left")]
    Sequence {
        /// The field.
        field: &'static str,
        /// The length the message gives.
        count: usize,
        /// The bytes left.
        left: usize,
    },
    /// A ROS 1 stamp beyond the `int32` seconds of ROS 2's time.
    #[error("stamp {sec}.{nanosec:09} s is beyond the year 2038")]
    Beyond2038 {
        /// Seconds.
        sec: u32,
        /// Nanoseconds.
        nanosec: u32,
    },
    /// A JSON message that does not parse as a joint state.
    #[error("JSON: {0}")]
    Json(serde_json::Error),
    /// A JSON message without `header.stamp`.
    #[error("JSON: no header.stamp")]
    NoStamp,
    /// A JSON stamp outside the `int32` seconds of ROS 2's time.
    #[error("JSON: stamp {sec}.{nanosec} s out of range")]
    StampRange {
        /// Seconds.
        sec: i64,
        /// Nanoseconds.
        nanosec: i64,
    },
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

/// The text of errors about files that are no log, after what the file looks like.
const SUPPORTED: &str = "supported: a rosbag2 folder (metadata.yaml with MCAP or \
    sqlite3 files, split recordings, zstd or lz4 compressed files or messages), an MCAP \
    file, a rosbag2 sqlite3 .db3 file, a ROS 1 .bag (format 2.0), each possibly \
    zstd/lz4-compressed, the 2019 headerless CSV layout and the headered CSV";

/// What decompresses past its bound ([`McapProblem::Unpacked`]): a decompression bomb,
/// or a recording larger than the bound. Kept as a value until shown, so that the
/// setting that raises the bound ([`Hint::MaxUnpackedMib`]) is spelled by the front end.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum UnpackBound {
    /// `what` (`it`: the file; `its compressed chunks`) decompresses to more than `limit`
    /// bytes, the file being `compressed` bytes.
    #[error("{what} decompress{} to more than {} MiB ({} times its {compressed} bytes): a decompression bomb, or a recording larger than the bound; raise it with {}", if *what == "it" { "es" } else { "" }, limit >> 20, limit / (*compressed).max(1), Hint::MaxUnpackedMib)]
    File {
        /// `it` or `its compressed chunks`.
        what: &'static str,
        /// The bound, bytes.
        limit: u64,
        /// The file's size, bytes.
        compressed: u64,
    },
    /// A message compressed on its own whose frame states more than `limit` bytes.
    #[error("a compressed message of {size} bytes is larger than the {limit} bytes it may decompress to (256 MiB a message, and what is left of the file's bound, which {} raises)", Hint::MaxUnpackedMib)]
    MessageStated {
        /// The size the frame states, bytes.
        size: u64,
        /// The bound, bytes.
        limit: u64,
    },
    /// A message compressed on its own that decompresses to more than `limit` bytes.
    #[error("a compressed message is larger than the {limit} bytes it may decompress to (256 MiB a message, and what is left of the file's bound, which {} raises)", Hint::MaxUnpackedMib)]
    Message {
        /// The bound, bytes.
        limit: u64,
    },
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
    #[error("not a supported log: it looks like {looks_like}; {}", SUPPORTED)]
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
    /// A malformed or corrupted recording of another kind than MCAP, or a rosbag2 folder
    /// that cannot be used as one.
    #[error("invalid {kind}: {reason}")]
    Damaged {
        /// What the file is: `rosbag2 sqlite3 file`, `ROS 1 bag`, `compressed file`,
        /// `rosbag2 folder`.
        kind: &'static str,
        /// What is wrong.
        reason: String,
    },
    /// A compressed file, or its compressed chunks or messages, that decompress past
    /// their bound.
    #[error("invalid {kind}: {bound}")]
    Unpacked {
        /// What the file is: `compressed file`, `MCAP file`, `ROS 1 bag`.
        kind: &'static str,
        /// What decompresses past which bound.
        bound: UnpackBound,
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
    #[error("several {JOINT_STATE_TYPE} topics (or arm and jaw topic pairs) have positions and efforts: {}; choose one with {}", candidates.join(", "), Hint::Topics)]
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
        reason: DecodeError,
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
    #[error("{time_source} do not strictly increase: sample {index} (t = {time_s} s) {} sample {} (t = {previous_s} s); {backwards} backward step(s) and {duplicates} repeated stamp(s) in {samples} samples. The sample order cannot be trusted: check the recording{}", if time_s == previous_s { "repeats the stamp of" } else { "comes before" }, index - 1, if *time_source == TimeSource::HeaderStamp { format!(", or read with log times ({})", Hint::LogTimes) } else { String::new() })]
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
    #[error("non-uniform sampling ({time_source}): first at sample {index} (t = {time_s} s), a step of {} ms against a median of {} ms; {gaps} gap(s) (> {GAP_FACTOR} median steps, the longest {} ms) and {jittered} jittered step(s) (> {}% off the median) in {samples} samples. Filtering and differentiation need a uniform clock: resample with {}, e.g. {}", fmt_ms(*step_s), fmt_ms(*median_step_s), fmt_ms(*largest_step_s), JITTER_TOLERANCE * 100.0, Hint::ResampleHz, Hint::ResampleAt(*suggested_hz))]
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
    Invalid(JointLogError),
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

#[cfg(feature = "recordings")]
/// The error of a recording's file (and topic).
pub(crate) fn mcap_error(path: &Path, topic: Option<&str>, problem: McapProblem) -> LogError {
    LogError::Mcap {
        path: path.to_path_buf(),
        topic: topic.map(str::to_owned),
        problem: Box::new(problem),
    }
}
