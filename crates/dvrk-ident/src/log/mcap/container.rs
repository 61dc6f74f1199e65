//! Streaming over the records of an MCAP file: schemas, channels, messages.
//!
//! The file is read through a buffered reader and the `mcap` crate's sans-io
//! [`LinearReader`] (mcap 0.26: a streaming reader over any `Read`, so no memory map),
//! which decompresses one chunk at a time (zstd or lz4) and checks the chunk,
//! data-section and summary CRCs; memory is bounded by the largest chunk, not the file.
//! A [`Scanner`] hands the messages one at a time, on demand, to a callback as borrowed
//! slices, so messages of topics that are not wanted are never copied, and a log can
//! be read block by block and read again.

use super::{McapProblem, TopicInfo};
use crate::log::LogError;
use ::mcap::records::{op, Record};
use ::mcap::sans_io::{LinearReadEvent, LinearReader, LinearReaderOptions};
use ::mcap::McapError;
use std::collections::BTreeMap;
use std::io::Read;
use std::path::Path;

/// Largest record (or chunk, compressed or not) accepted, bytes: bounds the
/// allocations a corrupted length field can cause (the reader reserves a chunk's
/// uncompressed size before decompressing). rosbag2 writes chunks of under 1 MiB and the
/// `mcap` tool 4 MiB; a camera image is tens of MiB.
const RECORD_LENGTH_LIMIT: usize = 256 << 20;

/// Most bytes handed to the reader per read: it grows its buffer by what it is given,
/// so a record's claimed length is only allocated as its bytes really arrive (a 7 kB
/// file claiming a 539 MB record made it allocate 539 MB at once).
const READ_PIECE: usize = 1 << 16;

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
    let mut scanner = Scanner::open(path)?;
    while scanner.next_message(&mut on_message)?.is_some() {}
    Ok(Scan {
        topics: scanner.topics(),
    })
}

/// A pass over the records of a file, one message at a time, on demand.
pub(crate) struct Scanner {
    path: std::path::PathBuf,
    src: std::io::BufReader<std::fs::File>,
    reader: LinearReader,
    schemas: BTreeMap<u16, String>,
    channels: BTreeMap<u16, ChannelInfo>,
    counts: BTreeMap<u16, u64>,
    past_data_end: bool,
    bytes_read: u64,
}

impl Scanner {
    pub(crate) fn open(path: &Path) -> Result<Scanner, LogError> {
        let file = std::fs::File::open(path).map_err(|source| LogError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        let options = LinearReaderOptions::default()
            .with_validate_chunk_crcs(true)
            .with_validate_data_section_crc(true)
            .with_validate_summary_section_crc(true)
            .with_record_length_limit(RECORD_LENGTH_LIMIT);
        Ok(Scanner {
            path: path.to_path_buf(),
            src: std::io::BufReader::with_capacity(1 << 16, file),
            reader: LinearReader::new_with_options(options),
            schemas: BTreeMap::new(),
            channels: BTreeMap::new(),
            counts: BTreeMap::new(),
            past_data_end: false,
            bytes_read: 0,
        })
    }

    /// Reads on to the next message of the data section and hands it to `f`; `None`
    /// at the end of the file (which is then checked to the last CRC).
    pub(crate) fn next_message<T>(
        &mut self,
        mut f: impl FnMut(MessageRef<'_>) -> Result<T, LogError>,
    ) -> Result<Option<T>, LogError> {
        let path = self.path.as_path();
        let container =
            |e: McapError, offset: u64| mcap_error(path, None, container_problem(e, offset));
        while let Some(event) = self.reader.next_event() {
            match event.map_err(|e| container(e, self.bytes_read))? {
                LinearReadEvent::ReadRequest(need) => {
                    let buf = self.reader.insert(need.min(READ_PIECE));
                    let n = loop {
                        match self.src.read(buf) {
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
                    self.bytes_read += n as u64;
                    self.reader.notify_read(n);
                }
                LinearReadEvent::Record { opcode, data } => match opcode {
                    op::DATA_END => self.past_data_end = true,
                    op::SCHEMA | op::CHANNEL | op::MESSAGE => {
                        if !lengths_fit(opcode, data) {
                            return Err(mcap_error(
                                path,
                                None,
                                McapProblem::Container {
                                    reason: format!(
                                        "corrupted file: a length inside a {} record runs \
                                         past its end (about byte {})",
                                        if opcode == op::SCHEMA {
                                            "schema"
                                        } else {
                                            "channel"
                                        },
                                        self.bytes_read
                                    ),
                                },
                            ));
                        }
                        let record = ::mcap::parse_record(opcode, data)
                            .map_err(|e| container(e, self.bytes_read))?;
                        match record {
                            Record::Schema { header, .. } => {
                                self.schemas.entry(header.id).or_insert(header.name);
                            }
                            Record::Channel(c) => {
                                if self.channels.contains_key(&c.id) {
                                    continue;
                                }
                                let schema_name = if c.schema_id == 0 {
                                    String::new()
                                } else {
                                    self.schemas.get(&c.schema_id).cloned().ok_or_else(|| {
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
                                self.channels.insert(
                                    c.id,
                                    ChannelInfo {
                                        topic: c.topic,
                                        schema_name,
                                        message_encoding: c.message_encoding,
                                    },
                                );
                            }
                            Record::Message { header, data } if !self.past_data_end => {
                                let channel =
                                    self.channels.get(&header.channel_id).ok_or_else(|| {
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
                                *self.counts.entry(header.channel_id).or_insert(0) += 1;
                                return f(MessageRef {
                                    channel,
                                    log_time: header.log_time,
                                    publish_time: header.publish_time,
                                    data: &data,
                                })
                                .map(Some);
                            }
                            _ => {}
                        }
                    }
                    _ => {}
                },
            }
        }
        Ok(None)
    }

    /// Every topic seen so far with its type and message count (channels of the same
    /// topic merged), sorted by topic: the whole file's after the last message.
    pub(crate) fn topics(&self) -> Vec<TopicInfo> {
        let mut topics: BTreeMap<String, TopicInfo> = BTreeMap::new();
        for (id, c) in &self.channels {
            let n = self.counts.get(id).copied().unwrap_or(0);
            let t = topics.entry(c.topic.clone()).or_insert_with(|| TopicInfo {
                topic: c.topic.clone(),
                schema_name: c.schema_name.clone(),
                message_encoding: c.message_encoding.clone(),
                messages: 0,
            });
            t.messages += n;
        }
        topics.into_values().collect()
    }
}

pub(crate) fn mcap_error(path: &Path, topic: Option<&str>, problem: McapProblem) -> LogError {
    LogError::Mcap {
        path: path.to_path_buf(),
        topic: topic.map(str::to_owned),
        problem: Box::new(problem),
    }
}

/// Whether every length-prefixed string, map and byte array of a schema or channel
/// record fits in the record. The `mcap` crate (0.26) reserves a string's claimed length
/// before reading it, so a corrupted length inside a small record allocated gigabytes
/// (found by fuzzing, `fuzz/seeds/mcap/oom-string-length-3GB.mcap`). Other records have
/// no such field.
fn lengths_fit(opcode: u8, data: &[u8]) -> bool {
    struct Cursor<'a>(&'a [u8]);
    impl Cursor<'_> {
        fn skip(&mut self, n: usize) -> Option<()> {
            self.0 = self.0.get(n..)?;
            Some(())
        }
        /// A u32 length and that many bytes.
        fn prefixed(&mut self) -> Option<&[u8]> {
            let len = u32::from_le_bytes(self.0.get(..4)?.try_into().ok()?) as usize;
            let rest = self.0.get(4..)?;
            let (inner, after) = (rest.get(..len)?, rest.get(len..)?);
            self.0 = after;
            Some(inner)
        }
    }
    let mut c = Cursor(data);
    let fits = match opcode {
        // id; name; encoding; data
        op::SCHEMA => (|| {
            c.skip(2)?;
            c.prefixed()?;
            c.prefixed()?;
            c.prefixed().map(|_| ())
        })(),
        // id, schema id; topic; message encoding; metadata map of strings
        op::CHANNEL => (|| {
            c.skip(4)?;
            c.prefixed()?;
            c.prefixed()?;
            let mut map = Cursor(c.prefixed()?);
            while !map.0.is_empty() {
                map.prefixed()?;
                map.prefixed()?;
            }
            Some(())
        })(),
        _ => Some(()),
    };
    fits.is_some()
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
