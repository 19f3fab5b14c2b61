//! The PostgreSQL backend: a store in a database on a server that every station of a
//! line writes to at once (each record batch one transaction; ids from an identity
//! column, so writers never wait for one another), through the synchronous `postgres`
//! client. The schema is made by the first station that finds the database empty, or by
//! `host-fit store migrate`, under an advisory lock.
use super::columns::{index_of, type_of, Row, SqlType, Value};
use super::location::PgUrl;
use super::schema::{self, Dialect, Mode, APPLICATION_ID};
use crate::error::{ErrorKind, HostError, Result};
use postgres::error::SqlState;
use postgres::types::ToSql;
use postgres::{Client, NoTls};
use std::path::{Path, PathBuf};

/// A PostgreSQL error said plainly, naming the store (its URL without the password).
pub fn pg_error(at: &Path, e: &postgres::Error) -> HostError {
    let m = match e.as_db_error() {
        Some(db) => {
            let c = db.code();
            if *c == SqlState::INVALID_PASSWORD
                || *c == SqlState::INVALID_AUTHORIZATION_SPECIFICATION
            {
                format!("the server refused the login ({}): give the password in PGPASSWORD or a pgpass file (docs/records.md)", db.message())
            } else if *c == SqlState::INVALID_CATALOG_NAME {
                format!(
                    "{}: the plant's administrator makes the database (docs/records.md)",
                    db.message()
                )
            } else if *c == SqlState::INSUFFICIENT_PRIVILEGE {
                format!(
                    "the server refused ({}): this user may not do that (docs/records.md, roles)",
                    db.message()
                )
            } else {
                format!("record store: {}", db.message())
            }
        }
        None => {
            // the client's own words, with their causes (refused, timed out, no route)
            let mut m = e.to_string();
            let mut cause = std::error::Error::source(e);
            while let Some(c) = cause {
                m.push_str(&format!(": {c}"));
                cause = c.source();
            }
            format!("cannot reach the record store's server: {m}")
        }
    };
    HostError::in_file(ErrorKind::Store, at, m)
}

/// Connect to the database of `url`.
pub fn connect(url: &PgUrl, at: &Path) -> Result<Client> {
    url.config().connect(NoTls).map_err(|e| pg_error(at, &e))
}

/// The store's version (0: an empty database) and whether the database is empty.
fn version(c: &mut impl postgres::GenericClient, at: &Path) -> Result<(i64, bool)> {
    let e = |e: postgres::Error| pg_error(at, &e);
    let row = c
        .query_one(
            "SELECT to_regclass('store_schema') IS NOT NULL,
                    (SELECT count(*) FROM pg_catalog.pg_class k
                       JOIN pg_catalog.pg_namespace n ON n.oid = k.relnamespace
                      WHERE n.nspname = current_schema() AND k.relkind IN ('r', 'v', 'p'))",
            &[],
        )
        .map_err(e)?;
    let (marked, objects): (bool, i64) = (row.get(0), row.get(1));
    if !marked {
        if objects > 0 {
            return Err(HostError::in_file(ErrorKind::Store, at,
                format!("is a database with {objects} tables and views but not a host-fit record store: left as it is; give a database of its own for the store"),
            ));
        }
        return Ok((0, true));
    }
    let v: i64 = c
        .query_one(
            "SELECT coalesce(max(version), 0)::BIGINT FROM store_schema",
            &[],
        )
        .map_err(e)?
        .get(0);
    Ok((v, false))
}

/// Bring the database to the version of `steps` as `mode` allows (under an advisory
/// lock: stations that start at once on an empty database make the store once).
pub fn prepare(c: &mut Client, at: &Path, shown: &str, mode: Mode, steps: &[String]) -> Result<()> {
    let target = steps.len() as i64;
    let refuse = |m: String| HostError::in_file(ErrorKind::Store, at, m);
    let (v, empty) = version(c, at)?;
    if !schema::decide(v, empty, target, mode, shown).map_err(refuse)? {
        return Ok(());
    }
    let e = |e: postgres::Error| pg_error(at, &e);
    let mut tx = c.transaction().map_err(e)?;
    tx.execute("SELECT pg_advisory_xact_lock($1)", &[&APPLICATION_ID])
        .map_err(e)?;
    let (v, empty) = version(&mut tx, at)?;
    if !schema::decide(v, empty, target, mode, shown).map_err(refuse)? {
        return Ok(());
    }
    for (i, step) in steps.iter().enumerate().skip(v as usize) {
        tx.batch_execute(step).map_err(|err| {
            HostError::in_file(
                ErrorKind::Store,
                at,
                format!(
                    "migration of the record store to version {} failed (nothing changed): {}",
                    i + 1,
                    err.as_db_error()
                        .map_or(err.to_string(), |d| d.message().to_string())
                ),
            )
        })?;
        let version = (i + 1) as i32;
        tx.execute(
            "INSERT INTO store_schema (version, applied_utc, host_fit_version) VALUES ($1, $2, $3)",
            &[&version, &super::clock::now(), &env!("CARGO_PKG_VERSION")],
        )
        .map_err(e)?;
    }
    tx.commit().map_err(e)
}

/// Open the store at `url` as `mode` allows.
pub fn open(url: &PgUrl, mode: Mode) -> Result<Client> {
    let at = PathBuf::from(url.to_string());
    let mut c = connect(url, &at)?;
    prepare(
        &mut c,
        &at,
        &url.to_string(),
        mode,
        &schema::migrations(Dialect::Postgres),
    )?;
    Ok(c)
}

/// A parameter of type `ty` holding `v`.
fn param(v: &Value, ty: SqlType) -> Box<dyn ToSql + Sync> {
    match (v, ty) {
        (Value::Null, SqlType::Text) => Box::new(None::<String>),
        (Value::Null, SqlType::Real) => Box::new(None::<f64>),
        (Value::Null, SqlType::Integer) => Box::new(None::<i64>),
        (Value::Null, SqlType::Blob) => Box::new(None::<Vec<u8>>),
        (Value::Text(s), _) => Box::new(s.clone()),
        (Value::Real(x), _) => Box::new(*x),
        (Value::Integer(i), _) => Box::new(*i),
        (Value::Blob(b), _) => Box::new(b.clone()),
    }
}

/// The parameters of a filter (their types from their values).
fn params(values: &[Value]) -> Vec<Box<dyn ToSql + Sync>> {
    values
        .iter()
        .map(|v| {
            let ty = match v {
                Value::Real(_) => SqlType::Real,
                Value::Integer(_) => SqlType::Integer,
                Value::Blob(_) => SqlType::Blob,
                Value::Text(_) | Value::Null => SqlType::Text,
            };
            param(v, ty)
        })
        .collect()
}

/// Rows per INSERT statement (each row binds one parameter per column: PostgreSQL
/// takes at most 65 535 a statement).
const ROWS_PER_INSERT: usize = 200;

/// Insert `rows` (each of the columns `names`, typed `types`, in order) into `runs` in
/// one transaction, [`ROWS_PER_INSERT`] rows a statement: their ids, in the order of
/// `rows` (matched by run id, the column `run_id`).
pub fn insert(
    c: &mut Client,
    at: &Path,
    names: &[&str],
    types: &[SqlType],
    rows: &[Vec<Value>],
) -> Result<Vec<i64>> {
    let e = |e: postgres::Error| pg_error(at, &e);
    let run_col = names.iter().position(|n| *n == "run_id");
    let mut tx = c.transaction().map_err(e)?;
    let mut ids = Vec::with_capacity(rows.len());
    for chunk in rows.chunks(ROWS_PER_INSERT) {
        let k = names.len();
        let values = (0..chunk.len())
            .map(|r| {
                let ph: Vec<String> = (1..=k).map(|i| format!("${}", r * k + i)).collect();
                format!("({})", ph.join(", "))
            })
            .collect::<Vec<_>>()
            .join(", ");
        let sql = format!(
            "INSERT INTO runs ({}) VALUES {values} RETURNING id, run_id",
            names.join(", ")
        );
        let p: Vec<Box<dyn ToSql + Sync>> = chunk
            .iter()
            .flat_map(|r| r.iter().zip(types).map(|(v, t)| param(v, *t)))
            .collect();
        let refs: Vec<&(dyn ToSql + Sync)> = p.iter().map(|b| b.as_ref()).collect();
        let back = tx.query(&sql, &refs).map_err(e)?;
        let by_run: std::collections::HashMap<String, i64> = back
            .iter()
            .map(|r| (r.get::<_, String>(1), r.get::<_, i64>(0)))
            .collect();
        for r in chunk {
            let run = run_col.and_then(|i| match &r[i] {
                Value::Text(t) => by_run.get(t).copied(),
                Value::Null | Value::Real(_) | Value::Integer(_) | Value::Blob(_) => None,
            });
            ids.push(run.ok_or_else(|| {
                HostError::in_file(
                    ErrorKind::Store,
                    at,
                    "the server did not return the id of a record it wrote",
                )
            })?);
        }
    }
    tx.commit().map_err(e)?;
    Ok(ids)
}

/// The rows of `sql` (selecting the columns `names`, in that order) with `values`.
pub fn select(
    c: &mut Client,
    at: &Path,
    sql: &str,
    names: &[String],
    values: &[Value],
) -> Result<Vec<Row>> {
    let e = |e: postgres::Error| pg_error(at, &e);
    let p = params(values);
    let refs: Vec<&(dyn ToSql + Sync)> = p.iter().map(|b| b.as_ref()).collect();
    let rows = c.query(sql, &refs).map_err(e)?;
    let index = index_of(names);
    let types: Vec<SqlType> = names
        .iter()
        .map(|n| type_of(n).unwrap_or(SqlType::Integer))
        .collect();
    let mut out = Vec::with_capacity(rows.len());
    for r in &rows {
        let mut v = Vec::with_capacity(names.len());
        for (i, t) in types.iter().enumerate() {
            v.push(match t {
                SqlType::Text => r
                    .try_get::<_, Option<String>>(i)
                    .map_err(e)?
                    .map_or(Value::Null, Value::Text),
                SqlType::Real => r
                    .try_get::<_, Option<f64>>(i)
                    .map_err(e)?
                    .map_or(Value::Null, Value::Real),
                SqlType::Integer => r
                    .try_get::<_, Option<i64>>(i)
                    .map_err(e)?
                    .map_or(Value::Null, Value::Integer),
                SqlType::Blob => r
                    .try_get::<_, Option<Vec<u8>>>(i)
                    .map_err(e)?
                    .map_or(Value::Null, Value::Blob),
            });
        }
        out.push(Row::new(index.clone(), v));
    }
    Ok(out)
}
