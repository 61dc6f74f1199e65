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
    /// The column the messages are read in order of, by batches from an index:
    /// `id` when it is the table's primary key (rosbag2's `INTEGER PRIMARY KEY`), else
    /// the `rowid` (insertion order): a batch on a column without an index would scan
    /// the whole table each time, quadratic in its length.
    order: &'static str,
}

impl SqliteFile {
    pub(crate) fn open(file: &BagFile, channels: &mut Channels) -> Result<SqliteFile, LogError> {
        let path = file.path.clone();
        check_size(file.readable()).map_err(|problem| mcap_error(&path, None, problem))?;
        let fail = |e: rusqlite::Error| sqlite_error(&path, &e);
        let conn =
            open_read_only(file.readable()).map_err(|problem| mcap_error(&path, None, problem))?;
        let order = message_order(&conn).map_err(fail)?;
        // Rows without an id would be skipped by the batches: refused, counted.
        let missing: i64 = conn
            .query_row("SELECT count(*) FROM messages WHERE id IS NULL", [], |r| {
                r.get(0)
            })
            .map_err(fail)?;
        if missing > 0 {
            return Err(mcap_error(
                &path,
                None,
                invalid(format!(
                    "{missing} rows of the messages table have no id (NULL): rosbag2 numbers \
                     every message, so the file was altered"
                )),
            ));
        }
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
            order,
        })
    }

    fn fetch(&mut self) -> Result<(), LogError> {
        let fail = |e: rusqlite::Error| sqlite_error(&self.path, &e);
        let order = self.order;
        let mut stmt = self
            .conn
            .prepare_cached(&format!(
                "SELECT {order}, topic_id, timestamp, data FROM messages WHERE {order} > ?1 \
                 ORDER BY {order} LIMIT ?2"
            ))
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

/// Opens `path` read-only. Without a write-ahead log or rollback journal beside it, as
/// `immutable` (no lock, no `-shm` file: a recording on a read-only medium or folder
/// opens); with a `-wal`, read-only with it (its pages are part of the recording), which
/// needs a writable folder for SQLite's `-shm`; a `-journal` is a transaction that was
/// interrupted, which only a writable copy can roll back.
fn open_read_only(path: &std::path::Path) -> Result<Connection, McapProblem> {
    let beside = |suffix: &str| {
        let mut p = path.as_os_str().to_owned();
        p.push(suffix);
        PathBuf::from(p)
    };
    let (wal, journal) = (beside("-wal"), beside("-journal"));
    if std::fs::metadata(&journal).is_ok_and(|m| m.len() > 0) {
        return Err(invalid(format!(
            "a rollback journal {} beside it: the recording was interrupted inside a \
             transaction; open a copy of both with sqlite3 (which rolls it back) and read \
             the copy",
            journal.display()
        )));
    }
    let flags = OpenFlags::SQLITE_OPEN_READ_ONLY | OpenFlags::SQLITE_OPEN_NO_MUTEX;
    if wal.exists() {
        return Connection::open_with_flags(path, flags).map_err(|e| {
            invalid(format!(
                "{e}: it has a write-ahead log {} beside it, which SQLite reads only from \
                 a folder it may write (for its -shm file); copy the recording with its \
                 -wal to a writable folder",
                wal.display()
            ))
        });
    }
    let uri = format!("file:{}?immutable=1", uri_path(path));
    Connection::open_with_flags(uri, flags | OpenFlags::SQLITE_OPEN_URI)
        .map_err(|e| invalid(e.to_string()))
}

/// `path` for an SQLite URI: every byte but unreserved characters and `/`
/// percent-encoded (a `?` or `#` in a name would end the path).
fn uri_path(path: &std::path::Path) -> String {
    use std::os::unix::ffi::OsStrExt;
    let absolute = std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
    let mut out = String::new();
    for &b in absolute.as_os_str().as_bytes() {
        if b.is_ascii_alphanumeric() || b"/-._~".contains(&b) {
            out.push(b as char);
        } else {
            out.push_str(&format!("%{b:02X}"));
        }
    }
    out
}

/// The column to read the messages in order of (see [`SqliteFile::order`]).
fn message_order(conn: &Connection) -> rusqlite::Result<&'static str> {
    let mut stmt = conn.prepare("SELECT name, pk FROM pragma_table_info('messages')")?;
    let keys: Vec<(String, i64)> = stmt
        .query_map([], |r| Ok((r.get(0)?, r.get(1)?)))?
        .collect::<rusqlite::Result<Vec<(String, i64)>>>()?
        .into_iter()
        .filter(|(_, pk)| *pk > 0)
        .collect();
    Ok(match &keys[..] {
        [(name, _)] if name.eq_ignore_ascii_case("id") => "id",
        _ => "rowid",
    })
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
fn check_size(path: &std::path::Path) -> Result<(), McapProblem> {
    use std::io::Read;
    let mut head = [0u8; 100];
    let io = |e: std::io::Error| invalid(e.to_string());
    let mut f = std::fs::File::open(path).map_err(io)?;
    let len = f.metadata().map_err(io)?.len();
    if f.read_exact(&mut head).is_err() {
        return Err(invalid(
            "truncated sqlite3 file: it ends inside its 100-byte header".into(),
        ));
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
        return Err(invalid(format!(
            "truncated sqlite3 file: its header records {pages} pages of {page} bytes ({} bytes), the file has {len}; was the recording interrupted?",
            pages * page
        )));
    }
    Ok(())
}
