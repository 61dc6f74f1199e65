//! What every storage backend of a recording (MCAP files in [`super::container`],
//! rosbag2's sqlite3 in [`super::sqlite`], ROS 1 bags in [`super::ros1`]) shares: the
//! channel registry and the raw message they hand out.
//! A leaf: the backends and the container that dispatches over them depend on it, and
//! not on each other.

/// A channel with its schema's name and encoding.
#[derive(Debug)]
pub(crate) struct ChannelInfo {
    pub topic: String,
    pub schema_name: String,
    pub message_encoding: String,
}

/// The channels of every file of a recording, merged by topic, type and encoding (a
/// split recording repeats them in each file, under ids of that file).
#[derive(Default)]
pub(crate) struct Channels {
    pub(super) list: Vec<ChannelInfo>,
    pub(super) counts: Vec<u64>,
}

impl Channels {
    /// The index of a channel, added if new.
    pub(crate) fn index(
        &mut self,
        topic: &str,
        schema_name: &str,
        message_encoding: &str,
    ) -> usize {
        if let Some(k) = self.list.iter().position(|c| {
            c.topic == topic
                && c.schema_name == schema_name
                && c.message_encoding == message_encoding
        }) {
            return k;
        }
        self.list.push(ChannelInfo {
            topic: topic.to_owned(),
            schema_name: schema_name.to_owned(),
            message_encoding: message_encoding.to_owned(),
        });
        self.counts.push(0);
        self.list.len() - 1
    }
}

/// A message as a storage backend gives it: its channel's index in [`Channels`].
pub(crate) struct RawMessage<'a> {
    pub channel: usize,
    pub log_time: u64,
    pub publish_time: u64,
    pub data: &'a [u8],
}
