//! rosbag2's sqlite3 storage (`.db3`, the default of ROS 2 before Iron): a `topics`
//! table (`id`, `name`, `type`, `serialization_format`) and a `messages` table (`id`,
//! `topic_id`, `timestamp` in ns, `data`: the serialized message, CDR). Read through
//! SQLite itself (rusqlite, compiled in), read-only, in batches of rows in insertion
//! (recording) order, so memory is bounded by a batch, not the file.

use std::collections::{HashMap, VecDeque};
use std::path::PathBuf;

use rusqlite::{Connection, OpenFlags};

use super::bag::BagFile;
use super::channels::{Channels, RawMessage};
use super::problem::mcap_error;
use super::McapProblem;
use crate::log::LogError;

/// Rows fetched per query.
const BATCH_ROWS: i64 = 512;

/// A rosbag2 sqlite3 file being read.
pub(crate) struct SqliteFile {
    path: PathBuf,
    conn: Connection,
    /// `topics.id` to the index in [`Channels`].
    topics: HashMap<i64, usize>,
    last_id: i64,
    batch: VecDeque<(usize, i64, Vec<u8>)>,
    done: bool,
    current: Vec<u8>,
}

impl SqliteFile {
    pub(crate) fn open(file: &BagFile, channels: &mut Channels) -> Result<SqliteFile, LogError> {
        let path = file.path.clone();
        check_size(file.readable()).map_err(|reason| mcap_error(&path, None, invalid(reason)))?;
        let fail = |e: rusqlite::Error| sqlite_error(&path, &e);
        let conn = Connection::open_with_flags(
            file.readable(),
            OpenFlags::SQLITE_OPEN_READ_ONLY | OpenFlags::SQLITE_OPEN_NO_MUTEX,
        )
        .map_err(fail)?;
        let mut topics = HashMap::new();
        {
            let mut stmt = conn
                .prepare("SELECT id, name, type, serialization_format FROM topics ORDER BY id")
                .map_err(fail)?;
            let rows = stmt
                .query_map([], |r| {
                    Ok((
                        r.get::<_, i64>(0)?,
                        r.get::<_, String>(1)?,
                        r.get::<_, String>(2)?,
                        r.get::<_, String>(3)?,
                    ))
                })
                .map_err(fail)?;
            for row in rows {
                let (id, name, kind, encoding) = row.map_err(fail)?;
                topics.insert(id, channels.index(&name, &kind, &encoding));
            }
        }
        Ok(SqliteFile {
            path,
            conn,
            topics,
            last_id: i64::MIN,
            batch: VecDeque::new(),
            done: false,
            current: Vec::new(),
        })
    }

    fn fetch(&mut self) -> Result<(), LogError> {
        let fail = |e: rusqlite::Error| sqlite_error(&self.path, &e);
        let mut stmt = self
            .conn
            .prepare_cached(
                "SELECT id, topic_id, timestamp, data FROM messages WHERE id > ?1 ORDER BY id LIMIT ?2",
            )
            .map_err(fail)?;
        let rows = stmt
            .query_map([self.last_id, BATCH_ROWS], |r| {
                Ok((
                    r.get::<_, i64>(0)?,
                    r.get::<_, i64>(1)?,
                    r.get::<_, i64>(2)?,
                    r.get::<_, Vec<u8>>(3)?,
                ))
            })
            .map_err(fail)?;
        let mut n = 0;
        for row in rows {
            let (id, topic, stamp, data) = row.map_err(fail)?;
            let &channel = self.topics.get(&topic).ok_or_else(|| {
                mcap_error(
                    &self.path,
                    None,
                    invalid(format!(
                        "message {id} refers to topic id {topic}, which the topics table does not define"
                    )),
                )
            })?;
            self.last_id = id;
            self.batch.push_back((channel, stamp, data));
            n += 1;
        }
        self.done = n < BATCH_ROWS;
        Ok(())
    }

    pub(crate) fn next(&mut self) -> Result<Option<RawMessage<'_>>, LogError> {
        if self.batch.is_empty() && !self.done {
            self.fetch()?;
        }
        let Some((channel, stamp, data)) = self.batch.pop_front() else {
            return Ok(None);
        };
        self.current = data;
        // A negative receive time cannot be a log time: it becomes one out of range.
        let time = stamp as u64;
        Ok(Some(RawMessage {
            channel,
            log_time: time,
            publish_time: time,
            data: &self.current,
        }))
    }
}

fn sqlite_error(path: &std::path::Path, e: &rusqlite::Error) -> LogError {
    let text = e.to_string();
    let reason = if text.contains("no such table") || text.contains("no such column") {
        format!("an SQLite database but not rosbag2's sqlite3 storage ({text}; expected the tables topics and messages)")
    } else {
        text
    };
    mcap_error(path, None, invalid(reason))
}

/// The problem of a rosbag2 sqlite3 file that cannot be read.
fn invalid(reason: String) -> McapProblem {
    McapProblem::Damaged {
        kind: "rosbag2 sqlite3 file",
        reason,
    }
}

/// SQLite reads the missing end of a truncated file as zeros, so a cut file would give
/// wrong values without an error: the size the header records (page count × page
/// size, when the header's count is valid) must be in the file. (A write-ahead log
/// beside the file may hold the last pages: then the file may be shorter.)
fn check_size(path: &std::path::Path) -> Result<(), String> {
    use std::io::Read;
    let mut head = [0u8; 100];
    let mut f = std::fs::File::open(path).map_err(|e| e.to_string())?;
    let len = f.metadata().map_err(|e| e.to_string())?.len();
    if f.read_exact(&mut head).is_err() {
        return Err("truncated sqlite3 file: it ends inside its 100-byte header".into());
    }
    let page = match u16::from_be_bytes([head[16], head[17]]) {
        1 => 65536,
        p => u64::from(p),
    };
    let pages = u64::from(u32::from_be_bytes(
        head[28..32].try_into().expect("4 bytes"),
    ));
    let count_valid = head[92..96] == head[24..28];
    let mut wal = path.as_os_str().to_owned();
    wal.push("-wal");
    if count_valid && pages * page > len && !std::path::Path::new(&wal).exists() {
        return Err(format!(
            "truncated sqlite3 file: its header records {pages} pages of {page} bytes ({} bytes), the file has {len}; was the recording interrupted?",
            pages * page
        ));
    }
    Ok(())
}
