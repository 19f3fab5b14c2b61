//! The store itself, on either backend: opening (as [`Mode`] allows), appending records
//! in one transaction, reading them by a typed [`Filter`], a writer thread that appends
//! in chunks. Every statement is parameterised: no value ever becomes SQL text.
use super::columns::{columns, record_select, Column, Row, SqlType, Value};
use super::location::Location;
use super::record::{Command, Invocation, Record, RunId, Trace};
use super::schema::{Dialect, Mode, CALIBRATION};
use super::{pg, sqlite};
use crate::error::{ErrorKind, HostError, Result};
use std::path::{Path, PathBuf};
use std::time::Duration;

/// The connection of a store.
enum Conn {
    Sqlite(rusqlite::Connection),
    Postgres(Box<postgres::Client>),
}

/// An open record store.
pub struct Store {
    conn: Conn,
    location: Location,
    /// The name errors give (the SQLite file, or the URL without its password).
    at: PathBuf,
}

/// The order of the records read.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Order {
    /// The order of writing (`id`).
    #[default]
    Written,
    /// None (an aggregate).
    None,
    /// Calibration time, then input file, then writing (a batch's units share its start
    /// time: in the order of their files, not of which job finished first).
    Time,
}

/// Which records to read: every field given must match (typed values, bound as
/// parameters).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Filter {
    /// The unit's serial, exactly.
    pub serial: Option<String>,
    /// The run id.
    pub run: Option<RunId>,
    /// Run ids starting with these hex digits (lowercase).
    pub run_prefix: Option<String>,
    /// The lot.
    pub lot: Option<String>,
    /// The command.
    pub command: Option<Command>,
    /// Only calibrations (see [`CALIBRATION`]).
    pub calibrations: bool,
    /// Only records written after the record of this id.
    pub after_id: Option<i64>,
    /// The order.
    pub order: Order,
    /// At most this many records.
    pub limit: Option<i64>,
}

impl Filter {
    /// The records of unit `serial`.
    pub fn serial(serial: &str) -> Filter {
        Filter {
            serial: Some(serial.to_string()),
            ..Filter::default()
        }
    }

    /// The `WHERE ... ORDER BY ...` of the filter in dialect `d`, and its parameters.
    fn sql(&self, d: Dialect) -> (String, Vec<Value>) {
        let mut cond: Vec<String> = Vec::new();
        let mut params: Vec<Value> = Vec::new();
        let mut bind = |c: &mut Vec<String>, sql: &str, v: Value| {
            params.push(v);
            c.push(sql.replace('#', &d.placeholder(params.len())));
        };
        if let Some(s) = &self.serial {
            bind(&mut cond, "serial = #", Value::Text(s.clone()));
        }
        if let Some(r) = &self.run {
            bind(&mut cond, "run_id = #", Value::Text(r.to_string()));
        }
        if let Some(p) = &self.run_prefix {
            // every id starting with the prefix lies in [prefix, prefix + "g")
            bind(&mut cond, "run_id >= #", Value::Text(p.clone()));
            bind(&mut cond, "run_id < #", Value::Text(format!("{p}g")));
        }
        if let Some(l) = &self.lot {
            bind(&mut cond, "lot = #", Value::Text(l.clone()));
        }
        if let Some(c) = self.command {
            bind(&mut cond, "command = #", Value::Text(c.name().to_string()));
        }
        if let Some(id) = self.after_id {
            bind(&mut cond, "id > #", Value::Integer(id));
        }
        if self.calibrations {
            cond.push(format!("({CALIBRATION})"));
        }
        let mut sql = String::new();
        if !cond.is_empty() {
            sql.push_str(" WHERE ");
            sql.push_str(&cond.join(" AND "));
        }
        sql.push_str(match self.order {
            Order::None => "",
            Order::Written => " ORDER BY id",
            Order::Time => " ORDER BY time_utc, input, id",
        });
        if let Some(n) = self.limit {
            params.push(Value::Integer(n));
            sql.push_str(&format!(" LIMIT {}", d.placeholder(params.len())));
        }
        (sql, params)
    }
}

/// Every column of a record but `id`.
pub fn record_columns() -> Vec<String> {
    columns().into_iter().map(|c| c.name).collect()
}

impl Store {
    /// Open the store at `location`, making it when the file does not exist (SQLite) or
    /// the database is empty (PostgreSQL); an existing store must be of this version.
    pub fn open(location: impl Into<Location>) -> Result<Store> {
        Self::open_as(location.into(), Mode::Create)
    }

    /// Open an existing store (`history`, `trend`): a missing file is an error.
    pub fn open_existing(location: impl Into<Location>) -> Result<Store> {
        Self::open_as(location.into(), Mode::Existing)
    }

    /// Open the store as `mode` allows (`store migrate`: [`Mode::Migrate`]).
    pub fn open_as(location: Location, mode: Mode) -> Result<Store> {
        let at = location.error_path();
        let conn = match &location {
            Location::Sqlite(p) => Conn::Sqlite(sqlite::open(p, mode)?),
            Location::Postgres(u) => Conn::Postgres(Box::new(pg::open(u, mode)?)),
        };
        Ok(Store { conn, location, at })
    }

    /// Where the store is.
    pub fn location(&self) -> &Location {
        &self.location
    }

    /// The store's name in messages (the SQLite file, or the URL without password).
    pub fn path(&self) -> &Path {
        &self.at
    }

    fn dialect(&self) -> Dialect {
        match self.conn {
            Conn::Sqlite(_) => Dialect::Sqlite,
            Conn::Postgres(_) => Dialect::Postgres,
        }
    }

    /// Append `records` in one transaction: all of them are written, or none (and the
    /// error names the store). Their `id`s are set.
    pub fn append(&mut self, records: &mut [Record]) -> Result<()> {
        if records.is_empty() {
            return Ok(());
        }
        // the columns by the names the record gives them (every column of `columns`)
        let cols: Vec<Column> = columns();
        let d = self.dialect();
        let mut rows: Vec<Vec<Value>> = Vec::with_capacity(records.len());
        for r in records.iter() {
            let mut named: std::collections::HashMap<String, Value> =
                r.to_row().into_iter().collect();
            rows.push(
                cols.iter()
                    .map(|c| named.remove(&c.name).unwrap_or(Value::Null))
                    .collect(),
            );
        }
        let names: Vec<&str> = cols.iter().map(|c| c.name.as_str()).collect();
        let ids = match &mut self.conn {
            Conn::Sqlite(c) => {
                let sql = format!(
                    "INSERT INTO runs ({}) VALUES ({})",
                    names.join(", "),
                    (1..=cols.len())
                        .map(|i| d.placeholder(i))
                        .collect::<Vec<_>>()
                        .join(", ")
                );
                sqlite::insert(c, &self.at, &sql, &rows)?
            }
            Conn::Postgres(c) => {
                let types: Vec<SqlType> = cols.iter().map(|c| c.ty).collect();
                pg::insert(c, &self.at, &names, &types, &rows)?
            }
        };
        for (r, id) in records.iter_mut().zip(ids) {
            r.id = id;
        }
        Ok(())
    }

    /// The columns `names` of the records `filter` selects.
    pub fn select(&mut self, names: &[String], filter: &Filter) -> Result<Vec<Row>> {
        let (cond, params) = filter.sql(self.dialect());
        let sql = format!("SELECT {} FROM runs{cond}", names.join(", "));
        match &mut self.conn {
            Conn::Sqlite(c) => sqlite::select(c, &self.at, &sql, names, &params),
            Conn::Postgres(c) => pg::select(c, &self.at, &sql, names, &params),
        }
    }

    /// The whole records `filter` selects.
    pub fn records(&mut self, filter: &Filter) -> Result<Vec<Record>> {
        let rows = self.select(&record_select(), filter)?;
        rows.iter()
            .map(|r| {
                Record::from_row(r).map_err(|m| {
                    HostError::in_file(
                        ErrorKind::Store,
                        &self.at,
                        format!("record #{}: {m}", r.integer("id").unwrap_or(0)),
                    )
                })
            })
            .collect()
    }

    /// The record of run `run`.
    pub fn record(&mut self, run: RunId) -> Result<Option<Record>> {
        let f = Filter {
            run: Some(run),
            ..Filter::default()
        };
        self.records(&f).map(|mut v| v.pop())
    }

    /// Every record, in the order written (for tools; a large store is read whole).
    pub fn all(&mut self) -> Result<Vec<Record>> {
        self.records(&Filter::default())
    }

    /// How many records the store holds.
    pub fn count(&mut self) -> Result<i64> {
        let f = Filter {
            order: Order::None,
            ..Filter::default()
        };
        let rows = self.select(&["count(*)".to_string()], &f)?;
        Ok(rows
            .first()
            .and_then(|r| r.integer("count(*)"))
            .unwrap_or(0))
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

/// What a command was asked to record into: the store, the lot, where and by whom, and
/// how the tool was run (filled by the command line).
#[derive(Debug, Clone)]
pub struct Target {
    /// The store.
    pub db: Location,
    /// The lot, if given.
    pub lot: Option<String>,
    /// Station, chamber, tilter, operator.
    pub trace: Trace,
    /// How the tool was run.
    pub invocation: Option<Invocation>,
}

impl Target {
    /// A target of the store at `db`, nothing else given.
    pub fn new(db: impl Into<Location>) -> Target {
        Target {
            db: db.into(),
            lot: None,
            trace: Trace::default(),
            invocation: None,
        }
    }

    /// A record of `command` on `serial` from `input`, with this target's lot and trace
    /// and the invocation's options.
    pub fn record(&self, command: Command, serial: &str, input: &Path) -> Result<Record> {
        let mut r = Record::new(command, self.invocation.as_ref(), serial, input)?;
        r.lot.clone_from(&self.lot);
        r.trace = self.trace.clone();
        Ok(r)
    }
}

impl From<&Path> for Location {
    fn from(p: &Path) -> Location {
        Location::Sqlite(p.to_path_buf())
    }
}

impl From<PathBuf> for Location {
    fn from(p: PathBuf) -> Location {
        Location::Sqlite(p)
    }
}

impl From<&PathBuf> for Location {
    fn from(p: &PathBuf) -> Location {
        Location::Sqlite(p.clone())
    }
}

impl From<&Location> for Location {
    fn from(l: &Location) -> Location {
        l.clone()
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
        assert_eq!(back, ok[1]);
    }

    #[test]
    fn filters_are_parameters_never_sql() {
        let f = Filter {
            serial: Some("X'); DROP TABLE runs;--".into()),
            lot: Some("L1".into()),
            command: Some(Command::Batch),
            calibrations: true,
            ..Filter::default()
        };
        let (sql, params) = f.sql(Dialect::Postgres);
        assert_eq!(
            sql,
            format!(
                " WHERE serial = $1 AND lot = $2 AND command = $3 AND ({CALIBRATION}) ORDER BY id"
            )
        );
        assert_eq!(params[0], Value::Text("X'); DROP TABLE runs;--".into()));
        let (sql, _) = f.sql(Dialect::Sqlite);
        assert!(sql.starts_with(" WHERE serial = ?1 AND lot = ?2"), "{sql}");
    }

    #[test]
    fn bad_files_are_named_and_left_alone() {
        let dir = tempfile::tempdir().unwrap();
        let text = dir.path().join("notes.txt");
        std::fs::write(&text, "x".repeat(500)).unwrap();
        let e = Store::open(&text).err().unwrap();
        assert!(
            e.to_string().contains("notes.txt") && e.message.contains("not an SQLite database"),
            "{e}"
        );
        assert_eq!(std::fs::read(&text).unwrap(), "x".repeat(500).as_bytes());
        let empty = dir.path().join("empty.sqlite");
        std::fs::write(&empty, "").unwrap();
        let e = Store::open(&empty).err().unwrap();
        assert!(e.message.contains("is empty"), "{e}");
        assert_eq!(std::fs::metadata(&empty).unwrap().len(), 0);
        let missing = dir.path().join("none.sqlite");
        let e = Store::open_existing(&missing).err().unwrap();
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
        assert!(e.message.contains("cut short"), "{e}");
        assert_eq!(std::fs::read(&p).unwrap().len(), full.len() / 2);
    }
}
