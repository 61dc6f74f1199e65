//! The MCAP writer: a trajectory as `sensor_msgs/msg/JointState` messages.

use std::collections::BTreeMap;
use std::path::Path;

use serde::{Deserialize, Serialize};

use super::joint_state::{self, Header, JointStateMsg, Time};
use super::problem::mcap_error;
use super::problem::McapProblem;
#[allow(unused_imports)] // the docs' links
use super::read::read_mcap;
use super::schema::{JOINT_STATE_SCHEMA, JOINT_STATE_TYPE};
use crate::joint_log::{Coordinates, JointLog};
use crate::log::LogError;

/// Topic [`crate::log::write`] uses for MCAP files.
pub const DEFAULT_TOPIC: &str = "/measured_js";

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

/// Writes `log` (measured coordinates) as `sensor_msgs/msg/JointState` messages on
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
    log: &JointLog,
    topic: &str,
    options: &McapWriteOptions,
) -> Result<(), LogError> {
    let path = path.as_ref();
    log.validate().map_err(|source| LogError::Invalid {
        path: path.to_path_buf(),
        source,
    })?;
    let err = |p: McapProblem| mcap_error(path, Some(topic), p);
    if log.coordinates != Coordinates::Measured {
        return Err(err(McapProblem::WrongCoordinates));
    }
    if topic.is_empty() || topic.chars().any(char::is_whitespace) {
        return Err(err(McapProblem::BadTopic(topic.to_owned())));
    }
    // Stamps first, so that a bad one leaves nothing behind.
    let mut stamps: Vec<(i64, Time)> = Vec::with_capacity(log.len());
    for (index, &t) in log.time.iter().enumerate() {
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
            name: log.joint_names.clone(),
            position: Vec::new(),
            velocity: Vec::new(),
            effort: Vec::new(),
        };
        for (k, &(ns, stamp)) in stamps.iter().enumerate() {
            msg.header.stamp = stamp;
            msg.position.clear();
            msg.position.extend(log.q.row(k).iter());
            msg.velocity.clear();
            if let Some(dq) = &log.dq {
                msg.velocity.extend(dq.row(k).iter());
            }
            msg.effort.clear();
            msg.effort.extend(log.tau.row(k).iter());
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

/// [`crate::output::write_seekable`] (where every output is written atomically) with the
/// MCAP writer's errors named.
fn write_atomic_seek(
    path: &Path,
    fill: impl FnOnce(
        std::io::BufWriter<std::fs::File>,
    ) -> Result<std::io::BufWriter<std::fs::File>, ::mcap::McapError>,
) -> Result<(), LogError> {
    let io = |source| LogError::Io {
        path: path.to_path_buf(),
        source,
    };
    crate::output::write_seekable(
        path,
        |w| {
            fill(w).map_err(|e| match e {
                ::mcap::McapError::Io(source) => io(source),
                other => mcap_error(
                    path,
                    None,
                    McapProblem::Write {
                        reason: other.to_string(),
                    },
                ),
            })
        },
        io,
    )
}
