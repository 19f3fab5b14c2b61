//! The store itself: opening (a new store made whole beside its name; an existing file
//! checked before SQLite reads it), appending records in one transaction, a writer
//! thread that appends in chunks.
use super::fault::{db_error, BUSY_TIMEOUT};
use super::record::{coefficient_columns, Command, Invocation, Record, COEFFS};
use super::schema;
use crate::error::{ErrorKind, HostError, Result};
use rusqlite::{params_from_iter, Connection, OpenFlags, TransactionBehavior};
use std::path::{Path, PathBuf};
use std::time::Duration;

/// An open record store.
pub struct Store {
    conn: Connection,
    path: PathBuf,
}

/// What the bytes of an existing file say before SQLite opens it: an SQLite database of
/// the length its header states, or why not. A store in use by another process (its
/// `-wal` file not empty) may be longer in the log than in the file: only the magic is
/// checked then.
fn check_file(path: &Path) -> Result<()> {
    use std::io::Read;
    let mut f = std::fs::File::open(path).map_err(|e| HostError::io(path, &e))?;
    let len = f.metadata().map_err(|e| HostError::io(path, &e))?.len();
    if len == 0 {
        return Err(HostError::in_file(
            ErrorKind::Store,
            path,
            "is empty (0 bytes): not a record store (a store cut to nothing?); it is left as it is: restore it, or give a path that does not exist yet for a new store",
        ));
    }
    let mut head = [0u8; 100];
    if len < 100 || f.read_exact(&mut head).is_err() {
        return Err(HostError::in_file(
            ErrorKind::Store,
            path,
            format!("is {len} bytes: too short for an SQLite database header (100 bytes), not a record store or one cut short; it is left as it is"),
        ));
    }
    if &head[..16] != b"SQLite format 3\0" {
        return Err(HostError::in_file(
            ErrorKind::Store,
            path,
            "is not a record store (not an SQLite database); it is left as it is",
        ));
    }
    let be = |r: std::ops::Range<usize>| head[r].iter().fold(0u64, |a, b| a << 8 | u64::from(*b));
    let page = match be(16..18) {
        1 => 65_536,
        p => p,
    };
    let pages = be(28..32);
    let valid = head[24..28] == head[92..96];
    let wal = PathBuf::from(format!("{}-wal", path.display()));
    let in_use = std::fs::metadata(&wal).is_ok_and(|m| m.len() > 0);
    if valid && !in_use && len < page * pages {
        return Err(HostError::in_file(
            ErrorKind::Store,
            path,
            format!("the record store is cut short: its header states {pages} pages of {page} bytes ({} bytes), the file has {len}; it is left as it is: restore it from a copy", page * pages),
        ));
    }
    Ok(())
}

/// Make a new store at `path` whole before it has its name: built in a temporary file
/// beside it and linked into place only if no other process made one meanwhile (then
/// that one is used), so that a store is never seen half-made and an empty file is
/// never a store.
fn create_new(path: &Path) -> Result<()> {
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let io = |e: std::io::Error| HostError::io(path, &e);
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = tempfile::Builder::new()
        .prefix(&format!(".{name}."))
        .suffix(".tmp")
        .tempfile_in(dir)
        .map_err(io)?;
    {
        let e = |e| db_error(tmp.path(), e);
        let mut c = Connection::open(tmp.path()).map_err(e)?;
        c.query_row("PRAGMA journal_mode = WAL", [], |r| r.get::<_, String>(0))
            .map_err(e)?;
        schema::prepare(&mut c, tmp.path(), true, &schema::migrations())?;
        // closed here: its log is folded into the file and removed
    }
    match tmp.persist_noclobber(path) {
        Ok(_) => Ok(()),
        Err(e) if e.error.kind() == std::io::ErrorKind::AlreadyExists => Ok(()),
        Err(e) => Err(io(e.error)),
    }
}

/// The record's values in the order of [`INSERT`]'s columns.
fn values(r: &Record) -> Vec<rusqlite::types::Value> {
    use rusqlite::types::Value as V;
    let text = |s: &str| V::Text(s.to_string());
    let opt_text = |s: Option<&str>| s.map_or(V::Null, text);
    let real = |v: Option<f64>| v.filter(|v| v.is_finite()).map_or(V::Null, V::Real);
    let mut v = vec![
        text(&r.run_id.to_string()),
        text(&r.serial),
        text(&r.time_utc),
        text(&r.version),
        text(&r.commit),
        text(r.command.name()),
        text(&r.options.to_string()),
        opt_text(r.lot.as_deref()),
        text(&r.input),
        opt_text(r.input_sha256.as_deref()),
        opt_text(r.output_unit.as_deref()),
        opt_text(r.model.as_deref()),
        real(r.at_t0.map(|a| a.t0_c)),
    ];
    for c in 0..COEFFS {
        v.push(real(r.at_t0.map(|a| a.values[c])));
    }
    for c in 0..COEFFS {
        v.push(real(r.at_t0.and_then(|a| a.sigma).map(|s| s[c])));
    }
    v.push(r.blob.clone().map_or(V::Null, V::Blob));
    v.push(r.blob_crc().map_or(V::Null, |c| V::Integer(i64::from(c))));
    v.push(opt_text(
        r.judged
            .as_ref()
            .map(|j| j.verdict.as_str())
            .filter(|v| *v != super::record::NOT_JUDGED),
    ));
    v.push(opt_text(r.judged.as_ref().map(|j| j.reason.as_str())));
    v.push(real(r.worst_dg_mg));
    v.push(opt_text(r.diagnosis_verdict.as_deref()));
    v.push(
        r.findings
            .as_ref()
            .map_or(V::Null, |f| V::Text(f.to_string())),
    );
    v
}

/// Every column of a record but `id`, in the order [`values`] gives them.
pub fn record_columns() -> Vec<String> {
    [
        "run_id",
        "serial",
        "time_utc",
        "host_fit_version",
        "host_fit_commit",
        "command",
        "options",
        "lot",
        "input",
        "input_sha256",
        "output_unit",
        "model",
        "t0_c",
    ]
    .iter()
    .map(|s| s.to_string())
    .chain(coefficient_columns())
    .chain(
        [
            "blob",
            "blob_crc",
            "acceptance",
            "reason",
            "worst_dg_mg",
            "diagnosis_verdict",
            "findings",
        ]
        .iter()
        .map(|s| s.to_string()),
    )
    .collect()
}

impl Store {
    /// Open the store at `path`, creating it (and its schema) when the file does not
    /// exist; an existing file must be a record store this host-fit can read.
    pub fn open(path: &Path) -> Result<Store> {
        Self::open_with(path, true)
    }

    /// Open an existing store (`history`, `trend`): a missing file is an error.
    pub fn open_existing(path: &Path) -> Result<Store> {
        Self::open_with(path, false)
    }

    fn open_with(path: &Path, create: bool) -> Result<Store> {
        if path.is_dir() {
            return Err(HostError::in_file(
                ErrorKind::Invalid,
                path,
                "is a folder: give the record store's file (e.g. this folder/records.sqlite)",
            ));
        }
        let exists = path.exists();
        if !exists && !create {
            return Err(HostError::in_file(
                ErrorKind::Store,
                path,
                "no record store here: give the --db of a fit, verify, diagnose or batch (a batch writes records.sqlite in its output folder)",
            ));
        }
        if !exists {
            create_new(path)?;
        }
        check_file(path)?;
        // never SQLite's own create: a store that vanished is not quietly made anew
        let flags = OpenFlags::SQLITE_OPEN_READ_WRITE | OpenFlags::SQLITE_OPEN_NO_MUTEX;
        let mut conn = Connection::open_with_flags(path, flags).map_err(|e| db_error(path, e))?;
        conn.busy_timeout(BUSY_TIMEOUT)
            .map_err(|e| db_error(path, e))?;
        let mode: String = conn
            .query_row("PRAGMA journal_mode", [], |r| r.get(0))
            .map_err(|e| db_error(path, e))?;
        if !mode.eq_ignore_ascii_case("wal") {
            conn.query_row("PRAGMA journal_mode = WAL", [], |r| r.get::<_, String>(0))
                .map_err(|e| db_error(path, e))?;
        }
        conn.execute_batch("PRAGMA synchronous = FULL;")
            .map_err(|e| db_error(path, e))?;
        schema::prepare(&mut conn, path, create, &schema::migrations())?;
        Ok(Store {
            conn,
            path: path.to_path_buf(),
        })
    }

    /// The store's file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The connection (for the queries of [`history`] and [`trend`]).
    pub fn conn(&self) -> &Connection {
        &self.conn
    }

    /// Append `records` in one transaction: all of them are written, or none (and the
    /// error names the store). Their `id`s are set.
    pub fn append(&mut self, records: &mut [Record]) -> Result<()> {
        let path = self.path.clone();
        let e = |e| db_error(&path, e);
        let cols = record_columns();
        let sql = format!(
            "INSERT INTO runs ({}) VALUES ({})",
            cols.join(", "),
            (1..=cols.len())
                .map(|i| format!("?{i}"))
                .collect::<Vec<_>>()
                .join(", ")
        );
        let tx = self
            .conn
            .transaction_with_behavior(TransactionBehavior::Immediate)
            .map_err(e)?;
        {
            let mut st = tx.prepare_cached(&sql).map_err(e)?;
            for r in records.iter_mut() {
                st.execute(params_from_iter(values(r))).map_err(e)?;
                r.id = tx.last_insert_rowid();
            }
        }
        tx.commit().map_err(e)
    }

    /// How many records the store holds.
    pub fn count(&self) -> Result<i64> {
        self.conn
            .query_row("SELECT count(*) FROM runs", [], |r| r.get(0))
            .map_err(|e| db_error(&self.path, e))
    }
}

/// A store written from another thread: records sent from any number of threads are
/// appended in chunks, one transaction each (a chunk is written when it is full, or a
/// second after its first record came), so a long batch keeps its records even if it is
/// stopped mid-way.
pub struct Writer {
    tx: std::sync::mpsc::Sender<Record>,
    handle: std::thread::JoinHandle<Result<usize>>,
}

/// The longest a record waits in a writer's chunk before the chunk is written.
pub const FLUSH_AFTER: Duration = Duration::from_secs(1);

impl Writer {
    /// Append `r` (in the writer's next chunk). A writer that failed takes no more; its
    /// error comes from [`Writer::finish`].
    pub fn send(&self, r: Record) {
        let _ = self.tx.send(r);
    }

    /// Write what is left and return how many records were written, or the first error.
    pub fn finish(self) -> Result<usize> {
        drop(self.tx);
        self.handle.join().map_err(|_| {
            HostError::new(
                ErrorKind::Internal,
                "the record store's writer stopped unexpectedly",
            )
        })?
    }
}

impl Store {
    /// Hand the store to a writer thread that appends in chunks of `chunk` records.
    pub fn writer(mut self, chunk: usize) -> Writer {
        let (tx, rx) = std::sync::mpsc::channel::<Record>();
        let handle = std::thread::spawn(move || {
            use std::sync::mpsc::RecvTimeoutError;
            let mut buf = Vec::with_capacity(chunk);
            let (mut written, mut since) = (0, std::time::Instant::now());
            loop {
                let wait = if buf.is_empty() {
                    Duration::from_secs(3600)
                } else {
                    FLUSH_AFTER.saturating_sub(since.elapsed())
                };
                let last = match rx.recv_timeout(wait) {
                    Ok(r) => {
                        if buf.is_empty() {
                            since = std::time::Instant::now();
                        }
                        buf.push(r);
                        if buf.len() < chunk && since.elapsed() < FLUSH_AFTER {
                            continue;
                        }
                        false
                    }
                    Err(RecvTimeoutError::Timeout) => false,
                    Err(RecvTimeoutError::Disconnected) => true,
                };
                if !buf.is_empty() {
                    self.append(&mut buf)?;
                    written += buf.len();
                    buf.clear();
                }
                if last {
                    return Ok(written);
                }
            }
        });
        Writer { tx, handle }
    }
}

/// What a command was asked to record into: the store's path, the lot, and how the
/// tool was run (filled by the command line).
#[derive(Debug, Clone, Default)]
pub struct Target {
    /// The store's file.
    pub db: PathBuf,
    /// The lot, if given.
    pub lot: Option<String>,
    /// How the tool was run.
    pub invocation: Option<Invocation>,
}

impl Target {
    /// A record of `command` on `serial` from `input`, with this target's lot and the
    /// invocation's options.
    pub fn record(&self, command: Command, serial: &str, input: &Path) -> Result<Record> {
        let mut r = Record::new(command, self.invocation.as_ref(), serial, input)?;
        r.lot.clone_from(&self.lot);
        Ok(r)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(serial: &str) -> Record {
        let mut r = Record::new(Command::Fit, None, serial, Path::new("r.csv")).unwrap();
        r.input_sha256 = Some("a".repeat(64));
        r.blob = Some(vec![1, 2, 3, 4, 5, 6, 7, 8]);
        r
    }

    #[test]
    fn a_chunk_is_written_whole_or_not_at_all() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("s.sqlite");
        let mut s = Store::open(&p).unwrap();
        let mut ok = vec![sample("A"), sample("B")];
        s.append(&mut ok).unwrap();
        assert_eq!((ok[0].id, ok[1].id), (1, 2));
        // the third record of a chunk fails (a run id already stored): none of the
        // chunk stays
        let mut bad = vec![sample("C"), sample("D"), sample("E")];
        bad[2].run_id = ok[0].run_id;
        let e = s.append(&mut bad).unwrap_err();
        assert_eq!(e.file.as_deref(), Some(p.as_path()));
        assert_eq!(s.count().unwrap(), 2);
        // a bad sha (not 64 digits) is refused by the schema, the record not written
        let mut odd = vec![sample("F")];
        odd[0].input_sha256 = Some("abc".into());
        assert!(s.append(&mut odd).is_err());
        assert_eq!(s.count().unwrap(), 2);
        let back = s.record(ok[1].run_id).unwrap().unwrap();
        assert_eq!(back.serial, "B");
        assert_eq!(back.blob, ok[1].blob);
        assert_eq!(back.time_utc, ok[1].time_utc);
    }

    #[test]
    fn bad_files_are_named_and_left_alone() {
        let dir = tempfile::tempdir().unwrap();
        let text = dir.path().join("notes.txt");
        std::fs::write(&text, "x".repeat(500)).unwrap();
        let e = Store::open(&text).err().unwrap();
        assert_eq!(e.kind(), ErrorKind::Store);
        assert!(
            e.to_string().contains("notes.txt") && e.message.contains("not an SQLite database"),
            "{e}"
        );
        assert_eq!(std::fs::read(&text).unwrap(), "x".repeat(500).as_bytes());
        let empty = dir.path().join("empty.sqlite");
        std::fs::write(&empty, "").unwrap();
        let e = Store::open(&empty).err().unwrap();
        assert_eq!(e.kind(), ErrorKind::Store);
        assert!(e.message.contains("is empty"), "{e}");
        assert_eq!(std::fs::metadata(&empty).unwrap().len(), 0);
        let missing = dir.path().join("none.sqlite");
        let e = Store::open_existing(&missing).err().unwrap();
        assert_eq!(e.kind(), ErrorKind::Store);
        assert!(e.message.contains("no record store"), "{e}");
        assert!(!missing.exists());
        // a store cut to half its length
        let p = dir.path().join("s.sqlite");
        {
            let mut s = Store::open(&p).unwrap();
            let mut many: Vec<Record> = (0..200).map(|i| sample(&format!("U{i}"))).collect();
            s.append(&mut many).unwrap();
        }
        let full = std::fs::read(&p).unwrap();
        std::fs::write(&p, &full[..full.len() / 2]).unwrap();
        let e = Store::open(&p).err().unwrap();
        assert_eq!(e.kind(), ErrorKind::Store);
        assert!(e.message.contains("cut short"), "{e}");
        assert_eq!(std::fs::read(&p).unwrap().len(), full.len() / 2);
    }
}
