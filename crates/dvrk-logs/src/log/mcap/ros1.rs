//! ROS 1 bags (format 2.0, what `rosbag record` writes on Noetic and earlier), read
//! through the `rosbag` crate: connections from the index section, then the chunks in
//! file order, one at a time (bz2 or lz4 chunks decompressed by the crate), their
//! messages handed out in record order. Messages are in ROS 1 serialization
//! (`ros1` encoding), their time the record's (when the recorder received them).
//!
//! The crate decompresses a chunk into memory sized by the chunk's `size` field (a 7 kB
//! bag whose bz2 chunk claimed 4 GB took 3.8 GB), and an lz4 chunk without any bound.
//! So every chunk's header is read first, when the bag is opened: a compressed chunk
//! may state at most 256 MiB, and all of them together at most the file's bound
//! ([`super::bag::unpack_limit`], `--max-unpacked-mib`); bz2 output stops at the stated
//! size, and an lz4 chunk is decoded once, output discarded, to check that it does not
//! exceed it before the crate decodes it.

use std::collections::{HashMap, VecDeque};
use std::io::Read;
use std::path::{Path, PathBuf};

use rosbag::{ChunkRecord, IndexRecord, MessageRecord, RosBag};

use super::bag::BagFile;
use super::channels::{Channels, RawMessage};
use super::problem::{mcap_error, UnpackBound};
use super::McapProblem;
use crate::log::LogError;

/// A ROS 1 bag being read.
pub(crate) struct Ros1File {
    path: PathBuf,
    /// The file read (the decompressed copy of a compressed bag).
    bag_path: PathBuf,
    bag: RosBag,
    /// Chunk record positions, in file order.
    chunks: Vec<u64>,
    /// The lz4 chunks' data (position, length) and stated size, by chunk position.
    lz4: HashMap<u64, (u64, u64, u64)>,
    next_chunk: usize,
    /// Connection id to the index in [`Channels`].
    connections: HashMap<u32, usize>,
    /// The current chunk's messages: channel, time (ns), payload.
    queue: VecDeque<(usize, u64, Vec<u8>)>,
    current: Vec<u8>,
}

fn container(path: &Path, reason: String) -> LogError {
    mcap_error(path, None, damaged(reason))
}

/// A ROS 1 bag that cannot be read, and why.
fn damaged(reason: String) -> McapProblem {
    McapProblem::Damaged {
        kind: "ROS 1 bag",
        reason,
    }
}

impl Ros1File {
    pub(crate) fn open(file: &BagFile, channels: &mut Channels) -> Result<Ros1File, LogError> {
        let path = file.path.clone();
        let readable = file.readable();
        // The crate slices its memory map at the header's index position without
        // checking it: check it first, so a bag that was never closed is an error.
        check_header(readable).map_err(|problem| mcap_error(&path, None, problem))?;
        let bag = RosBag::new(readable).map_err(|e| container(&path, e.to_string()))?;
        let fail = |e: rosbag::Error| container(&path, format!("its index: {e}"));
        let mut connections = HashMap::new();
        let mut chunks = Vec::new();
        for record in bag.index_records() {
            match record.map_err(fail)? {
                IndexRecord::Connection(c) => {
                    connections
                        .entry(c.id)
                        .or_insert_with(|| channels.index(c.topic, c.tp, "ros1"));
                }
                IndexRecord::ChunkInfo(info) => chunks.push(info.chunk_pos),
                IndexRecord::IndexData(_) => {}
            }
        }
        chunks.sort_unstable();
        let lz4 = check_chunk_sizes(readable, &chunks, file.unpack_limit)
            .map_err(|problem| mcap_error(&path, None, problem))?;
        Ok(Ros1File {
            path,
            bag_path: readable.to_path_buf(),
            bag,
            chunks,
            lz4,
            next_chunk: 0,
            connections,
            queue: VecDeque::new(),
            current: Vec::new(),
        })
    }

    /// The messages of the next chunk into the queue.
    fn read_chunk(&mut self, channels: &mut Channels) -> Result<(), LogError> {
        let pos = self.chunks[self.next_chunk];
        self.next_chunk += 1;
        let path = &self.path;
        let fail = |e: rosbag::Error| container(path, format!("chunk at byte {pos}: {e}"));
        if let Some(&(data_pos, data_len, size)) = self.lz4.get(&pos) {
            check_lz4_size(&self.bag_path, pos, (data_pos, data_len), size)
                .map_err(|problem| mcap_error(path, None, problem))?;
        }
        let mut records = self.bag.chunk_records();
        records.seek(pos).map_err(fail)?;
        let chunk = match records.next() {
            Some(Ok(ChunkRecord::Chunk(c))) => c,
            Some(Ok(ChunkRecord::IndexData(_))) | None => {
                return Err(container(
                    path,
                    format!("the index points to byte {pos}, where there is no chunk"),
                ))
            }
            Some(Err(e)) => return Err(fail(e)),
        };
        for record in chunk.messages() {
            match record.map_err(fail)? {
                MessageRecord::Connection(c) => {
                    self.connections
                        .entry(c.id)
                        .or_insert_with(|| channels.index(c.topic, c.tp, "ros1"));
                }
                MessageRecord::MessageData(m) => {
                    let &channel = self.connections.get(&m.conn_id).ok_or_else(|| {
                        container(
                            path,
                            format!(
                                "a message refers to connection {}, which the bag does not define",
                                m.conn_id
                            ),
                        )
                    })?;
                    self.queue.push_back((channel, m.time, m.data.to_vec()));
                }
            }
        }
        Ok(())
    }

    pub(crate) fn next(
        &mut self,
        channels: &mut Channels,
    ) -> Result<Option<RawMessage<'_>>, LogError> {
        while self.queue.is_empty() && self.next_chunk < self.chunks.len() {
            self.read_chunk(channels)?;
        }
        let Some((channel, time, data)) = self.queue.pop_front() else {
            return Ok(None);
        };
        self.current = data;
        Ok(Some(RawMessage {
            channel,
            log_time: time,
            publish_time: time,
            data: &self.current,
        }))
    }
}

/// Checks the bag header record: its index position must lie after the header and
/// within the file (0 while `rosbag record` is still writing, or was killed).
fn check_header(path: &Path) -> Result<(), McapProblem> {
    let io = |e: std::io::Error| damaged(e.to_string());
    let mut file = std::fs::File::open(path).map_err(io)?;
    let len = file.metadata().map_err(io)?.len();
    let mut head = [0u8; 13 + 4];
    file.read_exact(&mut head)
        .map_err(|_| damaged("the file ends inside its header (truncated)".into()))?;
    let header_len = u32::from_le_bytes(head[13..17].try_into().expect("4 bytes")) as u64;
    if header_len > 1 << 20 || 17 + header_len + 4 > len {
        return Err(damaged("invalid or truncated header record".into()));
    }
    let mut header = vec![0u8; header_len as usize];
    let mut data_len = [0u8; 4];
    file.read_exact(&mut header).map_err(io)?;
    file.read_exact(&mut data_len).map_err(io)?;
    let start = 17 + header_len + 4 + u64::from(u32::from_le_bytes(data_len));
    let mut fields = header.as_slice();
    let mut index_pos = None;
    while fields.len() >= 4 {
        let n = u32::from_le_bytes(fields[..4].try_into().expect("4 bytes")) as usize;
        let Some(field) = fields.get(4..4 + n) else {
            break;
        };
        if let Some(v) = field.strip_prefix(b"index_pos=") {
            if let Ok(b) = <[u8; 8]>::try_from(v) {
                index_pos = Some(u64::from_le_bytes(b));
            }
        }
        fields = &fields[4 + n..];
    }
    match index_pos {
        None => Err(damaged("the header has no index position".into())),
        Some(0) => Err(damaged(
            "no index: the recording was not closed (`rosbag reindex` rebuilds it)".into(),
        )),
        Some(p) if p < start || p > len => Err(damaged(format!(
            "the header's index position {p} is outside the file ({len} bytes): truncated? (`rosbag reindex` may rebuild it)"
        ))),
        Some(_) => Ok(()),
    }
}

/// Largest decompressed size a compressed chunk may state, bytes (`rosbag record` writes
/// chunks of 768 KiB).
const MAX_CHUNK_BYTES: u64 = 256 << 20;

/// Reads the header of every chunk at `chunks` (positions in `path`): a compressed
/// chunk's stated `size` at most [`MAX_CHUNK_BYTES`], all of them together at most
/// `limit`. Returns the lz4 chunks' data position, length and stated size. A header
/// that cannot be read is left to the crate, which reports it.
fn check_chunk_sizes(
    path: &Path,
    chunks: &[u64],
    limit: u64,
) -> Result<HashMap<u64, (u64, u64, u64)>, McapProblem> {
    use std::io::{Seek, SeekFrom};
    let io = |e: std::io::Error| damaged(e.to_string());
    let mut file = std::fs::File::open(path).map_err(io)?;
    let len = file.metadata().map_err(io)?.len();
    let mut total = 0u64;
    let mut lz4 = HashMap::new();
    for &pos in chunks {
        let mut n = [0u8; 4];
        if pos.checked_add(4).is_none_or(|end| end > len)
            || file.seek(SeekFrom::Start(pos)).is_err()
            || file.read_exact(&mut n).is_err()
        {
            continue;
        }
        let header_len = u64::from(u32::from_le_bytes(n));
        if header_len > 1 << 20 || pos + 4 + header_len + 4 > len {
            continue;
        }
        let mut header = vec![0u8; header_len as usize];
        file.read_exact(&mut header).map_err(io)?;
        file.read_exact(&mut n).map_err(io)?;
        let data_len = u64::from(u32::from_le_bytes(n));
        let (mut op, mut compression, mut size) = (None, None, None);
        let mut fields = header.as_slice();
        while fields.len() >= 4 {
            let n = u32::from_le_bytes(fields[..4].try_into().expect("4 bytes")) as usize;
            let Some(field) = fields.get(4..4 + n) else {
                break;
            };
            if let Some(v) = field.strip_prefix(b"op=") {
                op = v.first().copied();
            } else if let Some(v) = field.strip_prefix(b"compression=") {
                compression = Some(v);
            } else if let Some(v) = field.strip_prefix(b"size=") {
                size = <[u8; 4]>::try_from(v).ok().map(u32::from_le_bytes);
            }
            fields = &fields[4 + n..];
        }
        let (Some(0x05), Some(compression), Some(size)) = (op, compression, size) else {
            continue;
        };
        if compression == b"none" {
            continue;
        }
        let size = u64::from(size);
        if size > MAX_CHUNK_BYTES {
            return Err(damaged(format!(
                "the chunk at byte {pos} states {size} bytes decompressed, more than the {} \
                 MiB a chunk may hold",
                MAX_CHUNK_BYTES >> 20
            )));
        }
        total += size;
        if total > limit {
            return Err(McapProblem::Unpacked {
                kind: "ROS 1 bag",
                bound: UnpackBound::File {
                    what: "its compressed chunks",
                    limit,
                    compressed: len,
                },
            });
        }
        if compression == b"lz4" {
            lz4.insert(pos, (pos + 4 + header_len + 4, data_len, size));
        }
    }
    Ok(lz4)
}

/// Decodes the lz4 data of the chunk at byte `chunk` of `path` (`data_len` bytes at
/// `data_pos`), output discarded, refusing more than its stated `size`.
fn check_lz4_size(
    path: &Path,
    chunk: u64,
    (data_pos, data_len): (u64, u64),
    size: u64,
) -> Result<(), McapProblem> {
    use std::io::{Seek, SeekFrom};
    let fail = |reason: String| damaged(format!("chunk at byte {chunk}: {reason}"));
    let io = |e: std::io::Error| fail(e.to_string());
    let mut file = std::fs::File::open(path).map_err(io)?;
    file.seek(SeekFrom::Start(data_pos)).map_err(io)?;
    let unpack = |e: std::io::Error| fail(format!("its lz4 data does not decompress: {e}"));
    let decoder = lz4::Decoder::new(file.take(data_len)).map_err(unpack)?;
    let n = std::io::copy(&mut decoder.take(size + 1), &mut std::io::sink()).map_err(unpack)?;
    if n > size {
        return Err(fail(format!(
            "its lz4 data decompresses to more than the {size} bytes its header states"
        )));
    }
    Ok(())
}
