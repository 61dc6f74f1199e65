//! What a recording is read with: the time source, the reader's options and the timing
//! tolerances (no dependency on the recording crates: `ReadOptions` and the command line
//! name them in every build).

use serde::{Deserialize, Serialize};

/// Largest accepted relative deviation of a time step from the median step before a log
/// counts as jittered (equal to the default
/// dvrk-ident's `signal::Processing::uniform_tolerance`).
pub const JITTER_TOLERANCE: f64 = 0.1;

/// A step longer than this many median steps is a gap.
pub const GAP_FACTOR: f64 = 1.5;

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
    type Err = crate::names::UnknownName;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
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
    /// Largest size a compressed sqlite3 or ROS 1 file may decompress to, MiB; `None`:
    /// the default (100 times the compressed size, at least
    /// 64 MiB and at most 16 GiB).
    pub max_unpacked_mib: Option<u64>,
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
