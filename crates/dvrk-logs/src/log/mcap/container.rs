//! Streaming over the messages of a recording, file after file: MCAP files here,
//! rosbag2's sqlite3 files in [`super::sqlite`], ROS 1 bags in [`super::ros1`], all handed
//! out alike (topic, type, encoding, times, payload), messages compressed on their own
//! decompressed ([`super::bag::Unpacker`]).
//!
//! MCAP files:
//!
//! The file is read through a buffered reader and the `mcap` crate's sans-io
//! [`LinearReader`] (mcap 0.26: a streaming reader over any `Read`, so no memory map),
//! which checks the data-section and summary CRCs. It hands each chunk over whole
//! (`emit_chunks`): the chunk's header states its decompressed size, which is checked
//! against the bounds before a byte is decompressed (at most [`RECORD_LENGTH_LIMIT`] per
//! chunk, and all compressed chunks of a file together at most
//! [`super::bag::unpack_limit`]: 100 times the file, within 64 MiB and 16 GiB, or
//! `--max-unpacked-mib`); a second reader of the same crate then reads the chunk's
//! records, decompressing (zstd or lz4) and checking its CRC, and refuses a chunk that
//! decompresses to more than its header states. Memory is bounded by the largest chunk,
//! not the file; time by the bound: a decompression bomb fails in a fraction of a second
//! instead of expanding for minutes. A file compressed as a whole is bounded the same
//! way.
//! A [`Scanner`] hands the messages one at a time, on demand, to a callback as borrowed
//! slices (each payload copied once out of its chunk), so a log can be read block by
//! block and read again.

use super::channels::{ChannelInfo, Channels, RawMessage};
use super::problem::{mcap_error, UnpackBound};
use super::{McapProblem, TopicInfo};
use crate::log::LogError;
use ::mcap::records::{op, Record};
use ::mcap::sans_io::{LinearReadEvent, LinearReader, LinearReaderOptions};
use ::mcap::McapError;
use std::collections::BTreeMap;
use std::io::Read;
use std::sync::Arc;

use super::bag::{Bag, BagFile, Packing, Storage, Unpacker};
use super::ros1::Ros1File;
use super::sqlite::SqliteFile;

/// Largest record (or chunk, compressed or not) accepted, bytes: bounds the
/// allocations a corrupted length field can cause (the reader reserves a chunk's
/// uncompressed size before decompressing). rosbag2 writes chunks of under 1 MiB and the
/// `mcap` tool 4 MiB; a camera image is tens of MiB.
pub(crate) const RECORD_LENGTH_LIMIT: usize = 256 << 20;

/// Most bytes handed to the reader per read: it grows its buffer by what it is given,
/// so a record's claimed length is only allocated as its bytes really arrive (a 7 kB
/// file claiming a 539 MB record made it allocate 539 MB at once).
const READ_PIECE: usize = 1 << 16;

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

/// Reads the recording from start to end, calling `on_message` for every message in
/// file order. Stops at the first error (of the file or of the callback).
pub(crate) fn scan(
    bag: &Arc<Bag>,
    mut on_message: impl FnMut(MessageRef<'_>) -> Result<(), LogError>,
) -> Result<Scan, LogError> {
    let mut scanner = Scanner::open(bag)?;
    while scanner.next_message(&mut on_message)?.is_some() {}
    Ok(Scan {
        topics: scanner.topics(),
    })
}

/// One file of a recording being read.
enum Backend {
    /// Boxed: it holds two readers, the file's and its current chunk's.
    Mcap(Box<McapFile>),
    Sqlite(SqliteFile),
    Ros1(Ros1File),
}

impl Backend {
    fn open(file: &BagFile, channels: &mut Channels) -> Result<Backend, LogError> {
        Ok(match file.storage {
            Storage::Mcap => Backend::Mcap(Box::new(McapFile::open(file)?)),
            Storage::Sqlite3 => Backend::Sqlite(SqliteFile::open(file, channels)?),
            Storage::Ros1 => Backend::Ros1(Ros1File::open(file, channels)?),
        })
    }

    fn next<'a>(&'a mut self, channels: &mut Channels) -> Result<Option<RawMessage<'a>>, LogError> {
        match self {
            Backend::Mcap(f) => f.next(channels),
            Backend::Sqlite(f) => f.next(),
            Backend::Ros1(f) => f.next(channels),
        }
    }
}

/// A pass over the messages of a recording, one message at a time, on demand, file
/// after file.
pub(crate) struct Scanner {
    bag: Arc<Bag>,
    next_file: usize,
    backend: Option<Backend>,
    channels: Channels,
    /// Messages compressed on their own, decompressed.
    unpacker: Unpacker,
    /// What the current file's messages decompressed to so far, bytes.
    unpacked: u64,
}

impl Scanner {
    pub(crate) fn open(bag: &Arc<Bag>) -> Result<Scanner, LogError> {
        Ok(Scanner {
            bag: bag.clone(),
            next_file: 0,
            backend: None,
            channels: Channels::default(),
            unpacker: Unpacker::default(),
            unpacked: 0,
        })
    }

    /// Reads on to the next message and hands it to `f`; `None` at the end of the last
    /// file (each file then checked to its end, e.g. an MCAP's last CRC).
    pub(crate) fn next_message<T>(
        &mut self,
        mut f: impl FnMut(MessageRef<'_>) -> Result<T, LogError>,
    ) -> Result<Option<T>, LogError> {
        loop {
            if self.backend.is_none() {
                let Some(file) = self.bag.files.get(self.next_file) else {
                    return Ok(None);
                };
                self.backend = Some(Backend::open(file, &mut self.channels)?);
                self.next_file += 1;
                self.unpacked = 0;
            }
            let Scanner {
                bag,
                next_file,
                backend,
                channels,
                unpacker,
                unpacked,
            } = self;
            let raw = backend.as_mut().expect("opened above").next(channels)?;
            let Some(raw) = raw else {
                *backend = None;
                continue;
            };
            channels.counts[raw.channel] += 1;
            let channel = &channels.list[raw.channel];
            let mut data = raw.data;
            // ROS 1 messages carry no encapsulation header: never compressed alone.
            if channel.message_encoding != "ros1" {
                let file = &bag.files[*next_file - 1];
                let budget = file.unpack_limit.saturating_sub(*unpacked);
                if let Some(r) = unpacker.unpack(data, budget) {
                    r.map_err(|e| mcap_error(&file.path, Some(&channel.topic), e))?;
                    data = unpacker.out.as_slice();
                    *unpacked += data.len() as u64;
                }
            }
            return f(MessageRef {
                channel,
                log_time: raw.log_time,
                publish_time: raw.publish_time,
                data,
            })
            .map(Some);
        }
    }

    /// Every topic seen so far with its type and message count (channels of the same
    /// topic merged), sorted by topic: the whole recording's after the last message.
    pub(crate) fn topics(&self) -> Vec<TopicInfo> {
        let mut topics: BTreeMap<String, TopicInfo> = BTreeMap::new();
        for (c, &n) in self.channels.list.iter().zip(&self.channels.counts) {
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

/// An MCAP file, read through the `mcap` crate's sans-io reader (decompressed on the
/// fly when the whole file is zstd or lz4 compressed).
struct McapFile {
    path: std::path::PathBuf,
    packed: bool,
    src: Box<dyn Read>,
    reader: LinearReader,
    records: Records,
    /// Bytes handed to the reader: the file's, or what it decompressed to when it is
    /// compressed as a whole.
    bytes_read: u64,
    /// Most bytes the file (compressed as a whole) and, separately, its compressed
    /// chunks together may decompress to ([`super::bag::unpack_limit`]).
    unpack_limit: u64,
    /// The decompressed sizes of the compressed chunks so far, as their headers state.
    chunks_unpacked: u64,
    /// The reader of the current chunk's records, fed the chunk record alone.
    chunk: Option<LinearReader>,
    /// The file's size on disk, bytes.
    compressed_len: u64,
}

impl McapFile {
    fn open(file: &BagFile) -> Result<McapFile, LogError> {
        let path = file.readable();
        let io = |source| LogError::Io {
            path: path.to_path_buf(),
            source,
        };
        let raw = std::fs::File::open(path).map_err(io)?;
        let compressed_len = raw.metadata().map_err(io)?.len();
        let raw = std::io::BufReader::with_capacity(1 << 16, raw);
        let src: Box<dyn Read> = match file.packing {
            Packing::None => Box::new(raw),
            Packing::Zstd => Box::new(zstd::stream::read::Decoder::with_buffer(raw).map_err(io)?),
            Packing::Lz4 => Box::new(lz4::Decoder::new(raw).map_err(io)?),
        };
        let options = LinearReaderOptions::default()
            .with_validate_chunk_crcs(true)
            .with_validate_data_section_crc(true)
            .with_validate_summary_section_crc(true)
            .with_record_length_limit(RECORD_LENGTH_LIMIT)
            .with_emit_chunks(true);
        Ok(McapFile {
            path: file.path.clone(),
            packed: file.packing != Packing::None,
            src,
            reader: LinearReader::new_with_options(options),
            records: Records {
                path: file.path.clone(),
                ..Records::default()
            },
            bytes_read: 0,
            unpack_limit: file.unpack_limit,
            chunks_unpacked: 0,
            chunk: None,
            compressed_len,
        })
    }

    /// Reads up to `need` bytes (at most [`READ_PIECE`]) of the file into the reader.
    fn read_more(&mut self, need: usize) -> Result<(), LogError> {
        let path = self.path.as_path();
        let buf = self.reader.insert(need.min(READ_PIECE));
        let n = loop {
            match self.src.read(buf) {
                Ok(n) => break n,
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                // A compressed file that stops decompressing is corrupted.
                Err(e) if self.packed && e.kind() != std::io::ErrorKind::NotFound => {
                    return Err(mcap_error(
                        path,
                        None,
                        McapProblem::Container {
                            reason: format!("the compressed file does not decompress: {e}"),
                        },
                    ))
                }
                Err(source) => {
                    return Err(LogError::Io {
                        path: path.to_path_buf(),
                        source,
                    })
                }
            }
        };
        self.bytes_read += n as u64;
        if self.packed && self.bytes_read > self.unpack_limit {
            return Err(mcap_error(
                path,
                None,
                McapProblem::Unpacked {
                    kind: "compressed file",
                    bound: UnpackBound::File {
                        what: "it",
                        limit: self.unpack_limit,
                        compressed: self.compressed_len,
                    },
                },
            ));
        }
        self.reader.notify_read(n);
        Ok(())
    }

    fn next(&mut self, registry: &mut Channels) -> Result<Option<RawMessage<'_>>, LogError> {
        let found = loop {
            // The current chunk's records first.
            if let Some(chunk) = self.chunk.as_mut() {
                match chunk.next_event() {
                    None => self.chunk = None,
                    // The chunk record is all the reader gets: the end of its input.
                    Some(Ok(LinearReadEvent::ReadRequest(_))) => chunk.notify_read(0),
                    Some(Ok(LinearReadEvent::Record { opcode, data })) => {
                        if let Some(found) =
                            self.records
                                .record(opcode, data, self.bytes_read, registry)?
                        {
                            break found;
                        }
                    }
                    Some(Err(e)) => {
                        return Err(mcap_error(
                            &self.path,
                            None,
                            container_problem(e, self.bytes_read),
                        ))
                    }
                }
                continue;
            }
            let Some(event) = self.reader.next_event() else {
                return Ok(None);
            };
            match event
                .map_err(|e| mcap_error(&self.path, None, container_problem(e, self.bytes_read)))?
            {
                LinearReadEvent::ReadRequest(need) => self.read_more(need)?,
                LinearReadEvent::Record {
                    opcode: op::CHUNK,
                    data,
                } => {
                    if let Some((size, compression)) = chunk_header(data) {
                        if !compression.is_empty() {
                            let problem = if size > RECORD_LENGTH_LIMIT as u64 {
                                Some(McapProblem::Container {
                                    reason: format!(
                                        "a chunk (about byte {}) states {size} bytes \
                                         decompressed, more than the {} MiB a chunk may hold",
                                        self.bytes_read,
                                        RECORD_LENGTH_LIMIT >> 20
                                    ),
                                })
                            } else {
                                self.chunks_unpacked += size;
                                (self.chunks_unpacked > self.unpack_limit).then_some(
                                    McapProblem::Unpacked {
                                        kind: "MCAP file",
                                        bound: UnpackBound::File {
                                            what: "its compressed chunks",
                                            limit: self.unpack_limit,
                                            compressed: self.compressed_len,
                                        },
                                    },
                                )
                            };
                            if let Some(problem) = problem {
                                return Err(mcap_error(&self.path, None, problem));
                            }
                        }
                    }
                    self.chunk = Some(chunk_reader(data));
                }
                LinearReadEvent::Record { opcode, data } => {
                    if let Some(found) =
                        self.records
                            .record(opcode, data, self.bytes_read, registry)?
                    {
                        break found;
                    }
                }
            }
        };
        let (channel, log_time, publish_time) = found;
        Ok(Some(RawMessage {
            channel,
            log_time,
            publish_time,
            data: &self.records.current,
        }))
    }
}

/// A reader of one chunk's records: the chunk record (`data`, without its opcode and
/// length) is its whole input. It decompresses the chunk (its sizes and its CRC
/// checked by the `mcap` crate, which refuses output beyond the stated size).
fn chunk_reader(data: &[u8]) -> LinearReader {
    let options = LinearReaderOptions::default()
        .with_skip_start_magic(true)
        .with_skip_end_magic(true)
        .with_validate_chunk_crcs(true)
        .with_record_length_limit(RECORD_LENGTH_LIMIT);
    let mut reader = LinearReader::new_with_options(options);
    let buf = reader.insert(9 + data.len());
    buf[0] = op::CHUNK;
    buf[1..9].copy_from_slice(&(data.len() as u64).to_le_bytes());
    buf[9..].copy_from_slice(data);
    reader.notify_read(9 + data.len());
    reader
}

/// A chunk record's stated decompressed size and compression (empty: none), read
/// without allocating; `None` for a header too short to hold them (the chunk's reader
/// then reports it).
fn chunk_header(data: &[u8]) -> Option<(u64, &[u8])> {
    // start time, end time (8 bytes each), uncompressed size, CRC (4), compression
    let size = u64::from_le_bytes(data.get(16..24)?.try_into().ok()?);
    let n = u32::from_le_bytes(data.get(28..32)?.try_into().ok()?) as usize;
    Some((size, data.get(32..32usize.checked_add(n)?)?))
}

/// What the records of a file define and the last message, as they are read.
#[derive(Default)]
struct Records {
    path: std::path::PathBuf,
    schemas: BTreeMap<u16, String>,
    /// Channel id to the index in [`Channels`].
    channels: BTreeMap<u16, usize>,
    past_data_end: bool,
    /// The last message's payload.
    current: Vec<u8>,
}

impl Records {
    /// Takes in one record (of the file or of a chunk); a message's channel and times
    /// when it is one (its payload in [`Records::current`]). `offset` (bytes read)
    /// places errors.
    fn record(
        &mut self,
        opcode: u8,
        data: &[u8],
        offset: u64,
        registry: &mut Channels,
    ) -> Result<Option<(usize, u64, u64)>, LogError> {
        match opcode {
            op::DATA_END => self.past_data_end = true,
            op::SCHEMA | op::CHANNEL | op::MESSAGE => {
                if !lengths_fit(opcode, data) {
                    return Err(mcap_error(
                        &self.path,
                        None,
                        McapProblem::Container {
                            reason: format!(
                                "corrupted file: a length inside a {} record runs past its \
                                 end (about byte {offset})",
                                if opcode == op::SCHEMA {
                                    "schema"
                                } else {
                                    "channel"
                                },
                            ),
                        },
                    ));
                }
                let record = ::mcap::parse_record(opcode, data)
                    .map_err(|e| mcap_error(&self.path, None, container_problem(e, offset)))?;
                match record {
                    Record::Schema { header, .. } => {
                        self.schemas.entry(header.id).or_insert(header.name);
                    }
                    Record::Channel(c) => {
                        if self.channels.contains_key(&c.id) {
                            return Ok(None);
                        }
                        let schema_name = if c.schema_id == 0 {
                            String::new()
                        } else {
                            self.schemas.get(&c.schema_id).cloned().ok_or_else(|| {
                                mcap_error(
                                    &self.path,
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
                        let k = registry.index(&c.topic, &schema_name, &c.message_encoding);
                        self.channels.insert(c.id, k);
                    }
                    Record::Message { header, data } if !self.past_data_end => {
                        let &channel = self.channels.get(&header.channel_id).ok_or_else(|| {
                            mcap_error(
                                &self.path,
                                None,
                                McapProblem::Container {
                                    reason: format!(
                                        "a message refers to channel {}, which is not defined before it",
                                        header.channel_id
                                    ),
                                },
                            )
                        })?;
                        self.current.clear();
                        self.current.extend_from_slice(&data);
                        return Ok(Some((channel, header.log_time, header.publish_time)));
                    }
                    _ => {}
                }
            }
            _ => {}
        }
        Ok(None)
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
