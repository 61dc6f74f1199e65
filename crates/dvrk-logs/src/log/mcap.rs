//! Recordings of `sensor_msgs/msg/JointState` (dVRK 2.x / CRTK `measured_js`): ROS 2
//! MCAP files, rosbag2 folders (`metadata.yaml` and its MCAP or sqlite3 `.db3` files,
//! in order: split recordings are one log), single `.db3` files, and ROS 1 bags of
//! `sensor_msgs/JointState`; files compressed as a whole (zstd, lz4: rosbag2's
//! `compression_mode: file`, e.g. `*.mcap.zstd`) and messages compressed one by one
//! (`compression_mode: message`). All are recognized by content (`bag`), read message by
//! message in file order (`container`, `sqlite`, `ros1`) and decoded to the same
//! JointState (CDR, JSON or ROS 1 serialization), so everything below holds for each.
//!
//! The readers and the writer need the default feature `recordings` (the MCAP, CDR,
//! SQLite, ROS 1 bag, YAML, zstd and lz4 crates). Without it, [`McapOptions`],
//! [`TimeSource`] and [`McapProblem`] remain, and a recording is still recognized by its
//! content: reading or writing one is a [`LogError::RecordingsNotBuilt`].
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
//! joints) or the MCAP log or publish time of each message. [`JointLog::time`] is in
//! seconds from the first kept sample, computed from integer nanoseconds
//! (`(stamp_k - stamp_0) / 1e9`, so a 200 Hz log gives exactly `k / 200`); the absolute
//! start is [`McapLog::start_time_ns`].
//!
//! **Timing checks** on the clock: stamps must strictly increase (a backward step or a
//! repeated stamp is always an error: the log order cannot be trusted). A step longer
//! than 1.5 median steps is a gap, a step off the median by more than
//! [`JITTER_TOLERANCE`] (the default `uniform_tolerance` of
//! dvrk-ident's `signal::Processing`) is jitter. With [`McapOptions::resample_hz`] the log is
//! resampled onto `k / rate` by linear interpolation ([`crate::resample`];
//! gaps are bridged by straight lines, see [`TimingReport::largest_step_s`]); without it
//! a non-uniform log is refused with the first bad sample and a `--resample HZ` hint.
//!
//! **Checks on the messages** (all errors name the file and topic): arrays whose length
//! differs from the number of joints, velocity or effort arrays empty in some messages
//! and not in others, NaN or infinite values, duplicated joint names, joints that change
//! between messages. Joints that only change *order* are reordered by name to the order
//! of the first message.
//!
//! **Efforts**: [`read_mcap`] returns a [`JointLog`], which always has efforts, so a
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

// Always built: what the rest of the crate names (options, time source, the error) and
// the recognition of a recording by its content.
mod options;
mod problem;
mod schema;
pub(crate) mod sniff;

// The readers and the writer (feature `recordings`).
#[cfg(feature = "recordings")]
pub(crate) mod bag;
#[cfg(feature = "recordings")]
mod blocks;
#[cfg(feature = "recordings")]
mod channels;
#[cfg(feature = "recordings")]
mod container;
#[cfg(feature = "recordings")]
mod joint_state;
#[cfg(feature = "recordings")]
mod read;
#[cfg(feature = "recordings")]
mod ros1;
#[cfg(feature = "recordings")]
mod sqlite;
#[cfg(feature = "recordings")]
mod survey;
#[cfg(feature = "recordings")]
mod topic;
#[cfg(feature = "recordings")]
mod write;

pub use self::options::{McapOptions, TimeSource, GAP_FACTOR, JITTER_TOLERANCE};
pub use self::problem::{DecodeError, McapProblem, TopicInfo, UnpackBound};
pub use self::schema::{JOINT_STATE_SCHEMA, JOINT_STATE_TYPE};

#[cfg(feature = "recordings")]
pub use self::blocks::McapBlocks;
#[cfg(feature = "recordings")]
pub use self::read::{
    list_topics, read_joint_states, read_mcap, read_mcap_log, McapLog, McapReader,
};
#[cfg(feature = "recordings")]
pub use self::survey::{JointStateSeries, TimingReport};
#[cfg(feature = "recordings")]
pub use self::write::{write_mcap, McapCompression, McapWriteOptions, DEFAULT_TOPIC};

#[allow(unused_imports)] // the docs' links
use crate::{joint_log::JointLog, log::LogError};
