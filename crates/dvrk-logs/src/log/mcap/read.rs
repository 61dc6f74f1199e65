//! The reader facades: a recording listed, read whole, read block by block, or read as
//! the joint states it holds.

use std::path::Path;
use std::sync::Arc;

use super::blocks::McapBlocks;
use super::options::{McapOptions, TimeSource};
use super::problem::TopicInfo;
use super::survey::{JointStateSeries, TimingReport};
use super::{bag, container, survey};
use crate::joint_log::JointLog;
use crate::log::LogError;
#[allow(unused_imports)] // the docs' links
use crate::log::LogFormat;

/// A log read by [`read_mcap_log`]: the samples and what is known about it.
#[derive(Clone, Debug, PartialEq)]
pub struct McapLog {
    /// Measured joints; time from 0 s at the first kept sample.
    pub samples: JointLog,
    /// The absolute time of `samples.time[0]`, ns since the epoch, in the chosen
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

/// Lists the topics of an MCAP file with their types and message counts (one pass over
/// the file).
pub fn list_topics(path: impl AsRef<Path>) -> Result<Vec<TopicInfo>, LogError> {
    let bag = Arc::new(bag::Bag::open(path.as_ref(), None)?);
    Ok(container::scan(&bag, |_| Ok(()))?.topics)
}

/// Reads an MCAP log into a [`JointLog`] in measured coordinates (see the module docs
/// for topic choice, merging, time and checks).
pub fn read_mcap(path: impl AsRef<Path>, options: &McapOptions) -> Result<JointLog, LogError> {
    read_mcap_log(path, options).map(|log| log.samples)
}

/// [`read_mcap`], also returning the absolute start time, the topics read and the timing
/// report: every block of an [`McapReader`], collected.
///
/// ```rust
/// use dvrk_logs::log::mcap::{read_mcap_log, write_mcap, McapOptions, McapWriteOptions};
/// use dvrk_logs::{Coordinates, JointLog, uniform_time};
/// use nalgebra::DMatrix;
/// let path = std::env::temp_dir().join(format!("dvrk-ident-doc-{}.mcap", std::process::id()));
/// let n = 50;
/// let written = JointLog {
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
/// write_mcap(&path, &written, "/PSM1/measured_js", &write).unwrap();
/// let log = read_mcap_log(&path, &McapOptions::default()).unwrap();
/// assert_eq!(log.topics, ["/PSM1/measured_js"]);
/// assert_eq!(log.start_time_ns, start);
/// assert_eq!(log.samples.time, written.time);
/// assert_eq!(log.samples.q, written.q);
/// assert!(log.samples.dq.is_none());
/// std::fs::remove_file(&path).unwrap();
/// ```
pub fn read_mcap_log(path: impl AsRef<Path>, options: &McapOptions) -> Result<McapLog, LogError> {
    let reader = McapReader::open(path, options)?;
    let mut all = crate::log::JointLogBuilder::default();
    for block in reader.blocks(crate::log::BLOCK_SAMPLES)? {
        all.push(&block?);
    }
    Ok(McapLog {
        samples: all.build(),
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
        let bag = Arc::new(bag::Bag::open(path.as_ref(), options.max_unpacked_mib)?);
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
    let bag = Arc::new(bag::Bag::open(path.as_ref(), None)?);
    Ok(survey::survey(&bag, topics, &[], time_source, true)?
        .into_iter()
        .map(survey::TopicSurvey::into_series)
        .collect())
}
