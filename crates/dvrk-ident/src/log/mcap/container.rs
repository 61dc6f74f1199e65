//! Streaming over the records of an MCAP file: schemas, channels, messages.
//!
//! The file is read through a buffered reader and the `mcap` crate's sans-io
//! [`LinearReader`], which decompresses one chunk at a time (zstd or lz4) and checks the
//! chunk, data-section and summary CRCs; memory is bounded by the largest chunk, not the
//! file. Messages are handed to a callback as borrowed slices, so messages of topics
//! that are not wanted are never copied.

use super::{McapProblem, TopicInfo};
use crate::log::LogError;
use ::mcap::records::{op, Record};
use ::mcap::sans_io::{LinearReadEvent, LinearReader, LinearReaderOptions};
use ::mcap::McapError;
use std::collections::BTreeMap;
use std::io::Read;
use std::path::Path;

/// Largest record (or chunk) accepted, bytes: bounds the allocations a corrupted length
/// field can cause.
const RECORD_LENGTH_LIMIT: usize = 1 << 30;

/// A channel with its schema's name and encoding.
#[derive(Debug)]
pub(crate) struct ChannelInfo {
    pub topic: String,
    pub schema_name: String,
    pub message_encoding: String,
}

/// A message, its channel and its times.
pub(crate) struct MessageRef<'a> {
    pub channel: &'a ChannelInfo,
    pub log_time: u64,
    pub publish_time: u64,
    pub data: &'a [u8],
}

/// What one pass over a file saw.
pub(crate) struct Scan {
    /// Every topic with its type and message count (channels of the same topic are
    /// merged), sorted by topic.
    pub topics: Vec<TopicInfo>,
}

/// Reads `path` from start to end, calling `on_message` for every message of the data
/// section in file order. Stops at the first error (of the file or of the callback).
pub(crate) fn scan(
    path: &Path,
    mut on_message: impl FnMut(MessageRef<'_>) -> Result<(), LogError>,
) -> Result<Scan, LogError> {
    let file = std::fs::File::open(path).map_err(|source| LogError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let mut src = std::io::BufReader::with_capacity(1 << 16, file);
    let options = LinearReaderOptions::default()
        .with_validate_chunk_crcs(true)
        .with_validate_data_section_crc(true)
        .with_validate_summary_section_crc(true)
        .with_record_length_limit(RECORD_LENGTH_LIMIT);
    let mut reader = LinearReader::new_with_options(options);
    let mut schemas: BTreeMap<u16, String> = BTreeMap::new();
    let mut channels: BTreeMap<u16, ChannelInfo> = BTreeMap::new();
    let mut counts: BTreeMap<u16, u64> = BTreeMap::new();
    let mut past_data_end = false;
    let mut bytes_read: u64 = 0;
    let container =
        |e: McapError, offset: u64| mcap_error(path, None, container_problem(e, offset));
    while let Some(event) = reader.next_event() {
        match event.map_err(|e| container(e, bytes_read))? {
            LinearReadEvent::ReadRequest(need) => {
                let buf = reader.insert(need);
                let n = loop {
                    match src.read(buf) {
                        Ok(n) => break n,
                        Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                        Err(source) => {
                            return Err(LogError::Io {
                                path: path.to_path_buf(),
                                source,
                            })
                        }
                    }
                };
                bytes_read += n as u64;
                reader.notify_read(n);
            }
            LinearReadEvent::Record { opcode, data } => match opcode {
                op::DATA_END => past_data_end = true,
                op::SCHEMA | op::CHANNEL | op::MESSAGE => {
                    let record =
                        ::mcap::parse_record(opcode, data).map_err(|e| container(e, bytes_read))?;
                    match record {
                        Record::Schema { header, .. } => {
                            schemas.entry(header.id).or_insert(header.name);
                        }
                        Record::Channel(c) => {
                            if channels.contains_key(&c.id) {
                                continue;
                            }
                            let schema_name = if c.schema_id == 0 {
                                String::new()
                            } else {
                                schemas.get(&c.schema_id).cloned().ok_or_else(|| {
                                    mcap_error(
                                        path,
                                        Some(&c.topic),
                                        McapProblem::Container {
                                            reason: format!(
                                                "channel {} refers to schema {}, which is not defined before it",
                                                c.id, c.schema_id
                                            ),
                                        },
                                    )
                                })?
                            };
                            channels.insert(
                                c.id,
                                ChannelInfo {
                                    topic: c.topic,
                                    schema_name,
                                    message_encoding: c.message_encoding,
                                },
                            );
                        }
                        Record::Message { header, data } if !past_data_end => {
                            let channel = channels.get(&header.channel_id).ok_or_else(|| {
                                mcap_error(
                                    path,
                                    None,
                                    McapProblem::Container {
                                        reason: format!(
                                            "a message refers to channel {}, which is not defined before it",
                                            header.channel_id
                                        ),
                                    },
                                )
                            })?;
                            *counts.entry(header.channel_id).or_insert(0) += 1;
                            on_message(MessageRef {
                                channel,
                                log_time: header.log_time,
                                publish_time: header.publish_time,
                                data: &data,
                            })?;
                        }
                        _ => {}
                    }
                }
                _ => {}
            },
        }
    }
    // Topics: merge the channels of one topic.
    let mut topics: BTreeMap<String, TopicInfo> = BTreeMap::new();
    for (id, c) in &channels {
        let n = counts.get(id).copied().unwrap_or(0);
        let t = topics.entry(c.topic.clone()).or_insert_with(|| TopicInfo {
            topic: c.topic.clone(),
            schema_name: c.schema_name.clone(),
            message_encoding: c.message_encoding.clone(),
            messages: 0,
        });
        t.messages += n;
    }
    Ok(Scan {
        topics: topics.into_values().collect(),
    })
}

pub(crate) fn mcap_error(path: &Path, topic: Option<&str>, problem: McapProblem) -> LogError {
    LogError::Mcap {
        path: path.to_path_buf(),
        topic: topic.map(str::to_owned),
        problem: Box::new(problem),
    }
}

/// Says what a container error means for a user.
fn container_problem(e: McapError, offset: u64) -> McapProblem {
    match e {
        McapError::BadMagic => McapProblem::NotMcap,
        McapError::UnexpectedEof | McapError::BadFooter => {
            McapProblem::Truncated { bytes_read: offset }
        }
        McapError::BadChunkCrc { .. }
        | McapError::BadDataCrc { .. }
        | McapError::BadSummaryCrc { .. } => McapProblem::Container {
            reason: format!("corrupted file: {e}"),
        },
        other => McapProblem::Container {
            reason: format!("{other} (about byte {offset})"),
        },
    }
}
