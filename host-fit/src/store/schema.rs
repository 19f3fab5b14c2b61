//! The store's schema, its version (`PRAGMA user_version`) and the migrations that bring
//! an older store up to it. A store is marked as host-fit's by `PRAGMA application_id`;
//! one of a newer version is refused (with its version named), never altered; a
//! migration runs in one transaction, so a store is at one version or the next, never
//! between.
use super::record::{coefficient_columns, Command};
use crate::error::{ErrorKind, HostError, Result};
use rusqlite::{Connection, TransactionBehavior};
use std::path::Path;

/// The schema version this host-fit writes and reads.
pub const SCHEMA_VERSION: i64 = 1;

/// `PRAGMA application_id` of a record store: "ATCR" (accelerometer temperature
/// calibration records).
pub const APPLICATION_ID: i64 = 0x4154_4352;

/// Which records are calibrations (SQL): those that made a blob that was judged or not
/// judged, but did not end in an error, and are not a verification of another's blob.
pub const CALIBRATION: &str =
    "command <> 'verify' AND blob IS NOT NULL AND (acceptance IS NULL OR acceptance <> 'error')";

/// The migrations: the i-th brings a store from version i to i + 1.
pub fn migrations() -> Vec<String> {
    let commands = Command::ALL
        .iter()
        .map(|c| format!("'{}'", c.name()))
        .collect::<Vec<_>>()
        .join(",");
    let coefficients = coefficient_columns()
        .iter()
        .map(|c| format!("  {c:<18} REAL,\n"))
        .collect::<String>();
    vec![format!(
        "CREATE TABLE runs (
  id                INTEGER PRIMARY KEY,
  run_id            TEXT    NOT NULL UNIQUE CHECK (length(run_id) = 32),
  serial            TEXT    NOT NULL,
  time_utc          TEXT    NOT NULL,
  host_fit_version  TEXT    NOT NULL,
  host_fit_commit   TEXT    NOT NULL,
  command           TEXT    NOT NULL CHECK (command IN ({commands})),
  options           TEXT    NOT NULL,
  lot               TEXT,
  input             TEXT    NOT NULL,
  input_sha256      TEXT    CHECK (input_sha256 IS NULL OR length(input_sha256) = 64),
  output_unit       TEXT,
  model             TEXT,
  t0_c              REAL,
{coefficients}  blob              BLOB,
  blob_crc          INTEGER,
  acceptance        TEXT    CHECK (acceptance IS NULL OR acceptance IN ('pass','fail','error')),
  reason            TEXT,
  worst_dg_mg       REAL,
  diagnosis_verdict TEXT,
  findings          TEXT
);
CREATE INDEX runs_by_serial ON runs (serial, id);
CREATE INDEX runs_by_time ON runs (time_utc, id);
CREATE TRIGGER runs_append_only_update BEFORE UPDATE ON runs
  BEGIN SELECT RAISE(ABORT, 'the record store is append-only: records are never changed'); END;
CREATE TRIGGER runs_append_only_delete BEFORE DELETE ON runs
  BEGIN SELECT RAISE(ABORT, 'the record store is append-only: records are never deleted'); END;
CREATE VIEW latest_calibrations AS
  SELECT * FROM runs r
  WHERE r.id = (SELECT max(id) FROM runs WHERE serial = r.serial AND {CALIBRATION});
"
    )]
}

fn db(path: &Path, e: rusqlite::Error) -> HostError {
    super::fault::db_error(path, e)
}

/// The store's version, checked to be a record store this host-fit can read.
fn version(conn: &Connection, path: &Path, known: i64) -> Result<(i64, bool)> {
    let app: i64 = conn
        .query_row("PRAGMA application_id", [], |r| r.get(0))
        .map_err(|e| db(path, e))?;
    let version: i64 = conn
        .query_row("PRAGMA user_version", [], |r| r.get(0))
        .map_err(|e| db(path, e))?;
    let objects: i64 = conn
        .query_row("SELECT count(*) FROM sqlite_schema", [], |r| r.get(0))
        .map_err(|e| db(path, e))?;
    let empty = app == 0 && version == 0 && objects == 0;
    if !empty && app != APPLICATION_ID {
        return Err(HostError::in_file(
            ErrorKind::Store,
            path,
            format!("is an SQLite database but not a host-fit record store (application id {app:#x}, {objects} tables and indexes): left as it is; give the path of a record store, or of a new file"),
        ));
    }
    if version > known {
        return Err(HostError::in_file(
            ErrorKind::Store,
            path,
            format!("is a record store of schema version {version}; this host-fit ({}) reads versions up to {known}: use a newer host-fit (the store is left as it is)", env!("CARGO_PKG_VERSION")),
        ));
    }
    Ok((version, empty))
}

/// Bring the store at `conn` to [`SCHEMA_VERSION`] with `steps` (see [`migrations`]);
/// `create`: an empty database may be made a store (else it is refused).
pub fn prepare(conn: &mut Connection, path: &Path, create: bool, steps: &[String]) -> Result<()> {
    let target = steps.len() as i64;
    let (v, empty) = version(conn, path, target)?;
    if v == target && !empty {
        return Ok(());
    }
    if empty && !create {
        return Err(HostError::in_file(
            ErrorKind::Store,
            path,
            "is an empty database, not a record store (no fit, verify, diagnose or batch has written to it)",
        ));
    }
    // another process may be migrating at the same moment: decide inside the write lock
    let tx = conn
        .transaction_with_behavior(TransactionBehavior::Immediate)
        .map_err(|e| db(path, e))?;
    let (v, _) = version(&tx, path, target)?;
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
    .map_err(|e| db(path, e))?;
    tx.commit().map_err(|e| db(path, e))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn open(p: &Path) -> Connection {
        Connection::open(p).unwrap()
    }

    #[test]
    fn migrations_run_in_order_and_all_or_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("s.sqlite");
        let mut c = open(&p);
        let v1 = migrations();
        assert_eq!(v1.len() as i64, SCHEMA_VERSION);
        prepare(&mut c, &p, true, &v1).unwrap();
        c.execute(
            "INSERT INTO runs (run_id, serial, time_utc, host_fit_version, host_fit_commit, command, options, input) VALUES (?1, 'A', 't', 'v', 'c', 'fit', '{}', 'r.csv')",
            ["0".repeat(32)],
        )
        .unwrap();
        // a version 2 that adds a column keeps the record; a broken version 3 changes
        // nothing: the store stays at version 2
        let mut v2 = v1.clone();
        v2.push("ALTER TABLE runs ADD COLUMN operator TEXT;".into());
        prepare(&mut c, &p, false, &v2).unwrap();
        let mut v3 = v2.clone();
        v3.push("ALTER TABLE runs ADD COLUMN x TEXT; SELECT * FROM no_such_table;".into());
        let e = prepare(&mut c, &p, false, &v3).unwrap_err();
        assert_eq!(e.kind(), ErrorKind::Store);
        assert!(e.message.contains("version 3 failed"), "{e}");
        let (v, _) = version(&c, &p, 3).unwrap();
        assert_eq!(v, 2);
        let cols: i64 = c
            .query_row(
                "SELECT count(*) FROM pragma_table_info('runs') WHERE name IN ('operator', 'x')",
                [],
                |r| r.get(0),
            )
            .unwrap();
        assert_eq!(cols, 1);
        let n: i64 = c
            .query_row("SELECT count(*) FROM runs", [], |r| r.get(0))
            .unwrap();
        assert_eq!(n, 1);
        // and this host-fit (version 1) refuses the version-2 store, naming the version
        let e = prepare(&mut c, &p, false, &v1).unwrap_err();
        assert_eq!(e.kind(), ErrorKind::Store);
        assert!(e.message.contains("schema version 2"), "{e}");
        assert!(e.message.contains("up to 1"), "{e}");
    }

    #[test]
    fn append_only_and_closed_sets_are_the_databases_own_rules() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("s.sqlite");
        let mut c = open(&p);
        prepare(&mut c, &p, true, &migrations()).unwrap();
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
        let mut c = open(&p);
        c.execute_batch("CREATE TABLE notes (x TEXT);").unwrap();
        let e = prepare(&mut c, &p, true, &migrations()).unwrap_err();
        assert_eq!(e.kind(), ErrorKind::Store);
        assert!(e.message.contains("not a host-fit record store"), "{e}");
        let q = dir.path().join("empty.sqlite");
        let mut c = open(&q);
        let e = prepare(&mut c, &q, false, &migrations()).unwrap_err();
        assert_eq!(e.kind(), ErrorKind::Store);
        assert!(e.message.contains("empty database"), "{e}");
    }
}
