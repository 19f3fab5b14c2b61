//! The store's schema, its version and the migrations that bring an older store up to
//! it, one list per backend that make the same tables (the i-th brings a store from
//! version i to i + 1). A migration runs in one transaction (both backends' DDL is
//! transactional), so a store is at one version or the next, never between; it runs
//! under a lock (SQLite's write lock, a PostgreSQL advisory lock), so stations starting
//! at once on a new database make it once.
//!
//! Where the version is kept: SQLite `PRAGMA user_version` (and `PRAGMA application_id`
//! marks the file as a record store); PostgreSQL the table `store_schema`, one row per
//! migration applied (version, when, by which host-fit).
//!
//! An older store is upgraded by `host-fit store migrate --db ...` (never silently: a
//! plant backs its store up first); a newer one is refused with its version named.
use super::columns::SqlType;
use super::record::Command;
use super::trace::Trace;
use firmware_core::model::COEFF_NAMES;

/// The schema version this host-fit writes and reads: 2, or the newest a traceability
/// field needs ([`Trace::FIELDS`]: a new field brings its own migration).
pub const SCHEMA_VERSION: i64 = if Trace::newest_column() > 2 {
    Trace::newest_column()
} else {
    2
};

/// `PRAGMA application_id` of an SQLite record store, and the key of the PostgreSQL
/// advisory lock migrations take: "ATCR" (accelerometer temperature calibration records).
pub const APPLICATION_ID: i64 = 0x4154_4352;

/// Which records are calibrations (SQL, both backends): those that made a blob that was
/// judged or not judged, but did not end in an error, and are not a verification of
/// another's blob.
pub const CALIBRATION: &str =
    "command <> 'verify' AND blob IS NOT NULL AND (acceptance IS NULL OR acceptance <> 'error')";

/// The two SQL dialects.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Dialect {
    /// SQLite 3.
    Sqlite,
    /// PostgreSQL 12 or newer.
    Postgres,
}

impl Dialect {
    /// The SQL type of a column type.
    pub fn ty(self, t: SqlType) -> &'static str {
        match (self, t) {
            (Dialect::Sqlite, SqlType::Text) => "TEXT",
            (Dialect::Postgres, SqlType::Text) => "TEXT COLLATE \"C\"",
            (Dialect::Sqlite, SqlType::Real) => "REAL",
            (Dialect::Postgres, SqlType::Real) => "DOUBLE PRECISION",
            (Dialect::Sqlite, SqlType::Integer) => "INTEGER",
            (Dialect::Postgres, SqlType::Integer) => "BIGINT",
            (Dialect::Sqlite, SqlType::Blob) => "BLOB",
            (Dialect::Postgres, SqlType::Blob) => "BYTEA",
        }
    }

    /// The i-th (1-based) placeholder of a statement.
    pub fn placeholder(self, i: usize) -> String {
        match self {
            Dialect::Sqlite => format!("?{i}"),
            Dialect::Postgres => format!("${i}"),
        }
    }
}

/// The view of each unit's newest calibration (its `*` is expanded when it is made on
/// PostgreSQL: made again by a migration that adds columns).
fn latest_view() -> String {
    format!(
        "CREATE VIEW latest_calibrations AS
  SELECT * FROM runs r
  WHERE r.id = (SELECT max(id) FROM runs WHERE serial = r.serial AND {CALIBRATION});
"
    )
}

/// Version 1: the table, its indexes, its append-only rule, the view.
fn version_1(d: Dialect) -> String {
    use SqlType::{Blob, Integer, Real, Text};
    let t = |x| d.ty(x);
    let commands = Command::ALL
        .iter()
        .map(|c| format!("'{}'", c.name()))
        .collect::<Vec<_>>()
        .join(",");
    let coefficients = COEFF_NAMES
        .iter()
        .map(|n| n.to_string())
        .chain(COEFF_NAMES.iter().map(|n| format!("sigma_{n}")))
        .map(|c| format!("  {c:<18} {},\n", t(Real)))
        .collect::<String>();
    let id = match d {
        Dialect::Sqlite => "INTEGER PRIMARY KEY",
        Dialect::Postgres => "BIGINT GENERATED ALWAYS AS IDENTITY PRIMARY KEY",
    };
    let append_only = match d {
        Dialect::Sqlite => "CREATE TRIGGER runs_append_only_update BEFORE UPDATE ON runs
  BEGIN SELECT RAISE(ABORT, 'the record store is append-only: records are never changed'); END;
CREATE TRIGGER runs_append_only_delete BEFORE DELETE ON runs
  BEGIN SELECT RAISE(ABORT, 'the record store is append-only: records are never deleted'); END;
"
        .to_string(),
        Dialect::Postgres => "CREATE FUNCTION runs_append_only() RETURNS trigger LANGUAGE plpgsql AS $$
  BEGIN RAISE EXCEPTION 'the record store is append-only: records are never changed or deleted'; END $$;
CREATE TRIGGER runs_append_only_rows BEFORE UPDATE OR DELETE ON runs
  FOR EACH ROW EXECUTE FUNCTION runs_append_only();
CREATE TRIGGER runs_append_only_truncate BEFORE TRUNCATE ON runs
  FOR EACH STATEMENT EXECUTE FUNCTION runs_append_only();
CREATE TABLE store_schema (
  version           INTEGER PRIMARY KEY,
  applied_utc       TEXT    NOT NULL,
  host_fit_version  TEXT    NOT NULL
);
COMMENT ON TABLE runs IS 'host-fit record store: one record per run and unit, append-only';
"
        .to_string(),
    };
    format!(
        "CREATE TABLE runs (
  id                {id},
  run_id            {text} NOT NULL UNIQUE CHECK (length(run_id) = 32),
  serial            {text} NOT NULL,
  time_utc          {text} NOT NULL,
  host_fit_version  {text} NOT NULL,
  host_fit_commit   {text} NOT NULL,
  command           {text} NOT NULL CHECK (command IN ({commands})),
  options           {text} NOT NULL,
  lot               {text},
  input             {text} NOT NULL,
  input_sha256      {text} CHECK (input_sha256 IS NULL OR length(input_sha256) = 64),
  output_unit       {text},
  model             {text},
  t0_c              {real},
{coefficients}  blob              {blob},
  blob_crc          {int},
  acceptance        {text} CHECK (acceptance IS NULL OR acceptance IN ('pass','fail','error')),
  reason            {text},
  worst_dg_mg       {real},
  diagnosis_verdict {text},
  findings          {text}
);
CREATE INDEX runs_by_serial ON runs (serial, id);
CREATE INDEX runs_by_time ON runs (time_utc, id);
{append_only}{view}",
        text = t(Text),
        real = t(Real),
        blob = t(Blob),
        int = t(Integer),
        view = latest_view(),
    )
}

/// The traceability columns version `v` adds (text), as `ALTER TABLE` statements.
fn trace_columns(d: Dialect, v: i64) -> String {
    let text = d.ty(SqlType::Text);
    Trace::FIELDS
        .iter()
        .filter(|f| f.since == v)
        .map(|f| format!("ALTER TABLE runs ADD COLUMN {} {text};\n", f.name))
        .collect()
}

/// Version 2: traceability (station, chamber, tilter, operator), the unit's test
/// record, and an index by lot (a batch resumed after a crash finds its units by it).
fn version_2(d: Dialect) -> String {
    format!(
        "{}ALTER TABLE runs ADD COLUMN test_record {};
CREATE INDEX runs_by_lot ON runs (lot, id);
DROP VIEW latest_calibrations;
{}",
        trace_columns(d, 2),
        d.ty(SqlType::Text),
        latest_view()
    )
}

/// Version 3 on: the traceability fields added since ([`Trace::FIELDS`]), and the
/// view made again (PostgreSQL expands its `*` when it is made).
fn trace_version(d: Dialect, v: i64) -> String {
    format!(
        "{}DROP VIEW latest_calibrations;\n{}",
        trace_columns(d, v),
        latest_view()
    )
}

/// The migrations of a dialect: the i-th brings a store from version i to i + 1.
pub fn migrations(d: Dialect) -> Vec<String> {
    let mut m = vec![version_1(d), version_2(d)];
    // versions 3 on, while there are any (the range may be empty)
    m.extend(
        (3..)
            .take_while(|v| *v <= SCHEMA_VERSION)
            .map(|v| trace_version(d, v)),
    );
    m
}

/// What opening a store may do to its schema.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// Make a new store of an empty database; an older store is refused (with the
    /// command that upgrades it).
    Create,
    /// Only an existing store of this version.
    Existing,
    /// Make a new store, or bring an older one up to this version (`store migrate`).
    Migrate,
}

/// The refusal of an older store: which version, and the command that upgrades it.
pub fn older(version: i64, shown: &str) -> String {
    format!(
        "is a record store of schema version {version}; this host-fit ({}) uses version {SCHEMA_VERSION}: back it up, then upgrade it with `host-fit store migrate --db {shown}` (it is left as it is)",
        env!("CARGO_PKG_VERSION")
    )
}

/// The refusal of a newer store.
pub fn newer(version: i64, known: i64) -> String {
    format!(
        "is a record store of schema version {version}; this host-fit ({}) reads versions up to {known}: use a newer host-fit (the store is left as it is)",
        env!("CARGO_PKG_VERSION")
    )
}

/// What to do with a store at `version` (0: empty) in `mode`, `target` the newest
/// version: Ok(true) migrate, Ok(false) use as it is, Err(why) refuse.
pub fn decide(
    version: i64,
    empty: bool,
    target: i64,
    mode: Mode,
    shown: &str,
) -> Result<bool, String> {
    if version > target {
        return Err(newer(version, target));
    }
    if empty {
        return match mode {
            Mode::Existing => Err("is an empty database, not a record store (no fit, verify, diagnose or batch has written to it)".into()),
            Mode::Create | Mode::Migrate => Ok(true),
        };
    }
    if version == target {
        return Ok(false);
    }
    match mode {
        Mode::Migrate => Ok(true),
        Mode::Create | Mode::Existing => Err(older(version, shown)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::store::columns::columns;

    #[test]
    fn both_dialects_make_every_column_of_the_record() {
        for d in [Dialect::Sqlite, Dialect::Postgres] {
            let all = migrations(d).join("\n");
            // each column made once: `  name   TYPE ...` in the table, or added
            let made: Vec<(String, String)> = all
                .lines()
                .filter_map(|l| {
                    let l = l.strip_prefix("ALTER TABLE runs ADD COLUMN ").unwrap_or(l);
                    let mut w = l.split_whitespace();
                    Some((w.next()?.to_string(), w.collect::<Vec<_>>().join(" ")))
                })
                .collect();
            for c in columns() {
                let n = made
                    .iter()
                    .filter(|(name, ty)| *name == c.name && ty.starts_with(d.ty(c.ty)))
                    .count();
                assert_eq!(n, 1, "{d:?}: {}", c.name);
            }
            assert_eq!(migrations(d).len() as i64, SCHEMA_VERSION);
        }
    }

    #[test]
    fn older_stores_wait_for_the_migrate_command_and_newer_ones_are_refused() {
        assert_eq!(decide(2, false, 2, Mode::Existing, "s"), Ok(false));
        assert_eq!(decide(0, true, 2, Mode::Create, "s"), Ok(true));
        assert!(decide(0, true, 2, Mode::Existing, "s")
            .unwrap_err()
            .contains("empty database"));
        let e = decide(1, false, 2, Mode::Create, "line.sqlite").unwrap_err();
        assert!(
            e.contains("version 1") && e.contains("store migrate --db line.sqlite"),
            "{e}"
        );
        assert_eq!(decide(1, false, 2, Mode::Migrate, "s"), Ok(true));
        let e = decide(7, false, 2, Mode::Migrate, "s").unwrap_err();
        assert!(
            e.contains("schema version 7") && e.contains("up to 2"),
            "{e}"
        );
    }
}
