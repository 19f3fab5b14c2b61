//! The SQLite backend: a store in one file, the SQLite compiled into host-fit. A new
//! store is made whole beside its name (readable by the group and others as the umask
//! allows, like any file the tool writes); an existing file is checked before SQLite
//! reads it; WAL mode, `synchronous = FULL`, and every write one `BEGIN IMMEDIATE`
//! transaction (a writer waits for another up to [`BUSY_TIMEOUT`]).
use super::columns::{index_of, Row, Value};
use super::fault::{db_error, BUSY_TIMEOUT};
use super::schema::{self, Dialect, Mode, APPLICATION_ID};
use crate::error::{ErrorKind, HostError, Result};
use rusqlite::{params_from_iter, Connection, OpenFlags, TransactionBehavior};
use std::path::{Path, PathBuf};

/// What the bytes of an existing file say before SQLite opens it: an SQLite database of
/// the length its header states, or why not. A store in use by another process (its
/// `-wal` file not empty) may be longer in the log than in the file: only the magic is
/// checked then.
fn check_file(path: &Path) -> Result<()> {
    use std::io::Read;
    let mut f = std::fs::File::open(path).map_err(|e| HostError::io(path, &e))?;
    let len = f.metadata().map_err(|e| HostError::io(path, &e))?.len();
    if len == 0 {
        return Err(HostError::in_file(ErrorKind::Store, path,
            "is empty (0 bytes): not a record store (a store cut to nothing?); it is left as it is: restore it, or give a path that does not exist yet for a new store",
        ));
    }
    let mut head = [0u8; 100];
    if len < 100 || f.read_exact(&mut head).is_err() {
        return Err(HostError::in_file(ErrorKind::Store, path,
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
        return Err(HostError::in_file(ErrorKind::Store, path,
            format!("the record store is cut short: its header states {pages} pages of {page} bytes ({} bytes), the file has {len}; it is left as it is: restore it from a copy", page * pages),
        ));
    }
    Ok(())
}

/// The mode a new store's file is made with (the umask is applied to it, as to every
/// file the tool writes: 0644 under the usual 022, 0664 under 002).
const NEW_FILE_MODE: u32 = 0o666;

/// Make a new store at `path` whole before it has its name: built in a temporary file
/// beside it and linked into place only if no other process made one meanwhile (then
/// that one is used), so that a store is never seen half-made and an empty file is
/// never a store.
fn create_new(path: &Path) -> Result<()> {
    use std::os::unix::fs::PermissionsExt;
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
        .permissions(std::fs::Permissions::from_mode(NEW_FILE_MODE))
        .tempfile_in(dir)
        .map_err(io)?;
    {
        let e = |e| db_error(tmp.path(), e);
        let mut c = Connection::open(tmp.path()).map_err(e)?;
        c.query_row("PRAGMA journal_mode = WAL", [], |r| r.get::<_, String>(0))
            .map_err(e)?;
        prepare(
            &mut c,
            tmp.path(),
            Mode::Create,
            &schema::migrations(Dialect::Sqlite),
        )?;
        // closed here: its log is folded into the file and removed
    }
    match tmp.persist_noclobber(path) {
        Ok(_) => Ok(()),
        Err(e) if e.error.kind() == std::io::ErrorKind::AlreadyExists => Ok(()),
        Err(e) => Err(io(e.error)),
    }
}

/// The store's version (0 for an empty database) and whether it is empty, checked to be
/// a record store.
fn version(conn: &Connection, path: &Path) -> Result<(i64, bool)> {
    let q = |sql: &str| -> Result<i64> {
        conn.query_row(sql, [], |r| r.get(0))
            .map_err(|e| db_error(path, e))
    };
    let app = q("PRAGMA application_id")?;
    let version = q("PRAGMA user_version")?;
    let objects = q("SELECT count(*) FROM sqlite_schema")?;
    let empty = app == 0 && version == 0 && objects == 0;
    if !empty && app != APPLICATION_ID {
        return Err(HostError::in_file(ErrorKind::Store, path,
            format!("is an SQLite database but not a host-fit record store (application id {app:#x}, {objects} tables and indexes): left as it is; give the path of a record store, or of a new file"),
        ));
    }
    Ok((version, empty))
}

/// Bring the store at `conn` to the version of `steps` (see [`schema::migrations`]) as
/// `mode` allows.
pub fn prepare(conn: &mut Connection, path: &Path, mode: Mode, steps: &[String]) -> Result<()> {
    let target = steps.len() as i64;
    let shown = path.display().to_string();
    let (v, empty) = version(conn, path)?;
    if !schema::decide(v, empty, target, mode, &shown)
        .map_err(|m| HostError::in_file(ErrorKind::Store, path, m))?
    {
        return Ok(());
    }
    // another process may be migrating at the same moment: decide inside the write lock
    let tx = conn
        .transaction_with_behavior(TransactionBehavior::Immediate)
        .map_err(|e| db_error(path, e))?;
    let (v, empty) = version(&tx, path)?;
    if !schema::decide(v, empty, target, mode, &shown)
        .map_err(|m| HostError::in_file(ErrorKind::Store, path, m))?
    {
        return Ok(());
    }
    for (i, step) in steps.iter().enumerate().skip(v as usize) {
        tx.execute_batch(step).map_err(|e| {
            HostError::in_file(
                ErrorKind::Store,
                path,
                format!(
                    "migration of the record store to version {} failed (nothing changed): {e}",
                    i + 1
                ),
            )
        })?;
    }
    tx.execute_batch(&format!(
        "PRAGMA application_id = {APPLICATION_ID}; PRAGMA user_version = {target};"
    ))
    .map_err(|e| db_error(path, e))?;
    tx.commit().map_err(|e| db_error(path, e))
}

/// Open the store at `path` as `mode` allows (a missing file is made a new store unless
/// `mode` is [`Mode::Existing`]).
pub fn open(path: &Path, mode: Mode) -> Result<Connection> {
    if path.is_dir() {
        return Err(HostError::in_file(
            ErrorKind::Store,
            path,
            "is a folder: give the record store's file (e.g. this folder/records.sqlite)",
        ));
    }
    let exists = path.exists();
    if !exists && mode == Mode::Existing {
        return Err(HostError::in_file(ErrorKind::Store, path,
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
    let mode_now: String = conn
        .query_row("PRAGMA journal_mode", [], |r| r.get(0))
        .map_err(|e| db_error(path, e))?;
    if !mode_now.eq_ignore_ascii_case("wal") {
        conn.query_row("PRAGMA journal_mode = WAL", [], |r| r.get::<_, String>(0))
            .map_err(|e| db_error(path, e))?;
    }
    conn.execute_batch("PRAGMA synchronous = FULL;")
        .map_err(|e| db_error(path, e))?;
    prepare(&mut conn, path, mode, &schema::migrations(Dialect::Sqlite))?;
    Ok(conn)
}

fn param(v: &Value) -> rusqlite::types::Value {
    use rusqlite::types::Value as V;
    match v {
        Value::Null => V::Null,
        Value::Text(s) => V::Text(s.clone()),
        Value::Real(x) => V::Real(*x),
        Value::Integer(i) => V::Integer(*i),
        Value::Blob(b) => V::Blob(b.clone()),
    }
}

/// Insert `rows` (each the same columns, in the same order) in one transaction: their
/// ids, or an error naming the store (and nothing written).
pub fn insert(
    conn: &mut Connection,
    path: &Path,
    sql: &str,
    rows: &[Vec<Value>],
) -> Result<Vec<i64>> {
    let e = |e| db_error(path, e);
    let tx = conn
        .transaction_with_behavior(TransactionBehavior::Immediate)
        .map_err(e)?;
    let mut ids = Vec::with_capacity(rows.len());
    {
        let mut st = tx.prepare_cached(sql).map_err(e)?;
        for r in rows {
            st.execute(params_from_iter(r.iter().map(param)))
                .map_err(e)?;
            ids.push(tx.last_insert_rowid());
        }
    }
    tx.commit().map_err(e)?;
    Ok(ids)
}

/// The rows of `sql` (selecting `names`, in that order) with `params`.
pub fn select(
    conn: &Connection,
    path: &Path,
    sql: &str,
    names: &[String],
    params: &[Value],
) -> Result<Vec<Row>> {
    use rusqlite::types::ValueRef;
    let e = |e| db_error(path, e);
    let index = index_of(names);
    let mut st = conn.prepare_cached(sql).map_err(e)?;
    let mut rows = st
        .query(params_from_iter(params.iter().map(param)))
        .map_err(e)?;
    let mut out = Vec::new();
    while let Some(r) = rows.next().map_err(e)? {
        let mut values = Vec::with_capacity(names.len());
        for i in 0..names.len() {
            values.push(match r.get_ref(i).map_err(e)? {
                ValueRef::Null => Value::Null,
                ValueRef::Integer(v) => Value::Integer(v),
                ValueRef::Real(v) => Value::Real(v),
                ValueRef::Text(t) => Value::Text(String::from_utf8_lossy(t).into_owned()),
                ValueRef::Blob(b) => Value::Blob(b.to_vec()),
            });
        }
        out.push(Row::new(index.clone(), values));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn conn(p: &Path) -> Connection {
        Connection::open(p).unwrap()
    }

    #[test]
    fn migrations_run_in_order_and_all_or_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("s.sqlite");
        let mut c = conn(&p);
        let steps = schema::migrations(Dialect::Sqlite);
        // a version-1 store, as an older host-fit made it, with a record
        prepare(&mut c, &p, Mode::Create, &steps[..1]).unwrap();
        c.execute(
            "INSERT INTO runs (run_id, serial, time_utc, host_fit_version, host_fit_commit, command, options, input) VALUES (?1, 'A', 't', 'v', 'c', 'fit', '{}', 'r.csv')",
            ["0".repeat(32)],
        )
        .unwrap();
        // opened by this host-fit it is refused with the command that upgrades it
        let e = prepare(&mut c, &p, Mode::Create, &steps).unwrap_err();
        assert!(e.message.contains("store migrate"), "{e}");
        // a broken next version changes nothing: the store stays at version 1
        let mut broken = steps.clone();
        broken.push("ALTER TABLE runs ADD COLUMN x TEXT; SELECT * FROM no_such_table;".into());
        let e = prepare(&mut c, &p, Mode::Migrate, &broken).unwrap_err();
        let next = schema::SCHEMA_VERSION + 1;
        assert!(e.message.contains(&format!("version {next} failed")), "{e}");
        assert_eq!(version(&c, &p).unwrap().0, 1);
        // migrated: the record is kept, the new columns are there
        prepare(&mut c, &p, Mode::Migrate, &steps).unwrap();
        assert_eq!(version(&c, &p).unwrap().0, schema::SCHEMA_VERSION);
        let n: i64 = c
            .query_row("SELECT count(*) FROM runs WHERE station IS NULL", [], |r| {
                r.get(0)
            })
            .unwrap();
        assert_eq!(n, 1);
        // and an older host-fit (version 1) refuses it, naming the version
        let e = prepare(&mut c, &p, Mode::Existing, &steps[..1]).unwrap_err();
        let now = format!("schema version {}", schema::SCHEMA_VERSION);
        assert!(e.message.contains(&now), "{e}");
    }

    #[test]
    fn append_only_and_closed_sets_are_the_databases_own_rules() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("s.sqlite");
        let mut c = conn(&p);
        prepare(
            &mut c,
            &p,
            Mode::Create,
            &schema::migrations(Dialect::Sqlite),
        )
        .unwrap();
        let insert = |cmd: &str, acc: &str| {
            c.execute(
                "INSERT INTO runs (run_id, serial, time_utc, host_fit_version, host_fit_commit, command, options, input, acceptance) VALUES (lower(hex(randomblob(16))), 'A', 't', 'v', 'c', ?1, '{}', 'r.csv', ?2)",
                [cmd, acc],
            )
        };
        insert("fit", "pass").unwrap();
        assert!(insert("refit", "pass").is_err());
        assert!(insert("fit", "maybe").is_err());
        let e = c.execute("UPDATE runs SET serial = 'B'", []).unwrap_err();
        assert!(e.to_string().contains("append-only"), "{e}");
        assert!(c.execute("DELETE FROM runs", []).is_err());
    }

    #[test]
    fn other_databases_are_left_alone() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("other.sqlite");
        let mut c = conn(&p);
        c.execute_batch("CREATE TABLE notes (x TEXT);").unwrap();
        let steps = schema::migrations(Dialect::Sqlite);
        let e = prepare(&mut c, &p, Mode::Create, &steps).unwrap_err();
        assert!(e.message.contains("not a host-fit record store"), "{e}");
        let q = dir.path().join("empty.sqlite");
        let mut c = conn(&q);
        let e = prepare(&mut c, &q, Mode::Existing, &steps).unwrap_err();
        assert!(e.message.contains("empty database"), "{e}");
    }
}
