//! Reading records back: every record of a unit in the order written, its latest
//! calibration marked (`host-fit history`), and a stored blob re-issued bit for bit
//! after its CRC is checked (`--blob RUN`).
use super::db::{record_columns, Store};
use super::fault::db_error;
use super::record::{AtT0, Command, Judged, Record, RunId, COEFFS};
use crate::error::{ErrorKind, HostError, Result};
use rusqlite::types::ValueRef;
use rusqlite::{Row, ToSql};
use serde::Serialize;

/// A record from a row of `SELECT id, <record_columns()>`.
fn from_row(row: &Row) -> rusqlite::Result<Record> {
    let text = |i: usize| -> rusqlite::Result<Option<String>> { row.get(i) };
    let real = |i: usize| -> rusqlite::Result<Option<f64>> { row.get(i) };
    let bad = |i: usize, what: &str| {
        rusqlite::Error::FromSqlConversionFailure(
            i,
            rusqlite::types::Type::Text,
            format!("{what} in column {i}").into(),
        )
    };
    let run: String = row.get(1)?;
    let command: String = row.get(6)?;
    let json = |i: usize| -> rusqlite::Result<Option<serde_json::Value>> {
        text(i)?
            .map(|s| serde_json::from_str(&s).map_err(|_| bad(i, "not JSON")))
            .transpose()
    };
    // columns: 0 id, 1..=13 run_id .. t0_c, 14.. the coefficients, their sigmas, then
    // blob, blob_crc, acceptance, reason, worst_dg_mg, diagnosis_verdict, findings
    let c0 = 14;
    let mut values = [0.0; COEFFS];
    let mut sigma = [0.0; COEFFS];
    let (mut have, mut have_sigma) = (true, true);
    for k in 0..COEFFS {
        match real(c0 + k)? {
            Some(v) => values[k] = v,
            None => have = false,
        }
        match real(c0 + COEFFS + k)? {
            Some(v) => sigma[k] = v,
            None => have_sigma = false,
        }
    }
    let t0 = real(13)?;
    let after = c0 + 2 * COEFFS;
    let acceptance = text(after + 2)?;
    Ok(Record {
        id: row.get(0)?,
        run_id: RunId::parse(&run).ok_or_else(|| bad(1, "a run id that is not 32 hex digits"))?,
        serial: row.get(2)?,
        time_utc: row.get(3)?,
        version: row.get(4)?,
        commit: row.get(5)?,
        command: Command::from_name(&command).ok_or_else(|| bad(6, "an unknown command"))?,
        options: json(7)?.unwrap_or_default(),
        lot: text(8)?,
        input: row.get(9)?,
        input_sha256: text(10)?,
        output_unit: text(11)?,
        model: text(12)?,
        at_t0: match (t0, have) {
            (Some(t0_c), true) => Some(AtT0 {
                t0_c,
                values,
                sigma: have_sigma.then_some(sigma),
            }),
            _ => None,
        },
        blob: match row.get_ref(after)? {
            ValueRef::Blob(b) => Some(b.to_vec()),
            _ => None,
        },
        judged: match (acceptance, text(after + 3).ok().flatten()) {
            (Some(verdict), reason) => Some(Judged {
                verdict,
                reason: reason.unwrap_or_default(),
            }),
            // a reason without a verdict: judged, and a band had nothing to judge
            (None, Some(reason)) => Some(Judged {
                verdict: super::record::NOT_JUDGED.to_string(),
                reason,
            }),
            (None, None) => None,
        },
        worst_dg_mg: real(after + 4)?,
        diagnosis_verdict: text(after + 5)?,
        findings: json(after + 6)?,
    })
}

/// The records matching `filter` (an SQL `WHERE ...` on `runs`, or empty), in the order
/// written.
pub fn read(store: &Store, filter: &str, params: &[&dyn ToSql]) -> Result<Vec<Record>> {
    let sql = format!(
        "SELECT id, {} FROM runs {filter} ORDER BY id",
        record_columns().join(", ")
    );
    let e = |e| db_error(store.path(), e);
    let mut st = store.conn().prepare(&sql).map_err(e)?;
    let rows = st.query_map(params, from_row).map_err(e)?;
    rows.collect::<rusqlite::Result<Vec<_>>>().map_err(e)
}

impl Store {
    /// The record of run `run`.
    pub fn record(&self, run: RunId) -> Result<Option<Record>> {
        read(self, "WHERE run_id = ?1", &[&run.to_string()]).map(|mut v| v.pop())
    }

    /// Every record, in the order written (for tools; a large store is read whole).
    pub fn all(&self) -> Result<Vec<Record>> {
        read(self, "", &[])
    }
}

/// One record in a unit's history.
#[derive(Debug, Clone, Serialize)]
pub struct Entry {
    /// The record (its blob's bytes are not in the JSON: `--blob RUN --out FILE`).
    #[serde(flatten)]
    pub record: Record,
    /// The blob's size, bytes.
    pub blob_bytes: Option<usize>,
    /// Its CRC-32, `0x` and 8 hex digits.
    pub blob_crc: Option<String>,
    /// The run id the blob carries (format 4 on): this record's for a blob it made, the
    /// maker's for a blob it verified.
    pub blob_run_id: Option<String>,
    /// Whether this is the unit's latest calibration (the newest record that made a
    /// blob: the blob the unit should carry).
    pub latest: bool,
}

/// Every record of a unit.
#[derive(Debug, Clone, Serialize)]
pub struct History {
    /// The serial.
    pub serial: String,
    /// The store.
    pub store: String,
    /// Oldest first.
    pub records: Vec<Entry>,
}

/// Every record of `serial`, oldest first, its latest calibration marked.
pub fn history(store: &Store, serial: &str) -> Result<History> {
    let records = read(store, "WHERE serial = ?1", &[&serial])?;
    let latest = records
        .iter()
        .filter(|r| r.is_calibration())
        .map(|r| r.id)
        .max();
    Ok(History {
        serial: serial.to_string(),
        store: store.path().display().to_string(),
        records: records
            .into_iter()
            .map(|r| Entry {
                blob_bytes: r.blob.as_ref().map(Vec::len),
                blob_crc: r.blob_crc().map(|c| format!("{c:#010x}")),
                blob_run_id: r
                    .blob
                    .as_deref()
                    .and_then(super::record::blob_run_id)
                    .map(|id| id.to_string()),
                latest: Some(r.id) == latest,
                record: r,
            })
            .collect(),
    })
}

fn opt(v: Option<&str>) -> &str {
    v.unwrap_or("-")
}

impl History {
    /// As text: two or three lines per record, `*` before the latest calibration.
    pub fn text(&self) -> String {
        if self.records.is_empty() {
            return format!(
                "unit {}: no records in {} (serials are matched exactly)",
                self.serial, self.store
            );
        }
        let mut s = vec![format!(
            "unit {}: {} records in {}, oldest first; * marks the latest calibration (the blob the unit should carry)",
            self.serial,
            self.records.len(),
            self.store
        )];
        for e in &self.records {
            let r = &e.record;
            s.push(format!(
                "{} #{} {} {} lot {} run {} (host-fit {}, commit {})",
                if e.latest { "*" } else { " " },
                r.id,
                r.time_utc,
                r.command.name(),
                opt(r.lot.as_deref()),
                r.run_id,
                r.version,
                &r.commit[..r.commit.len().min(12)]
            ));
            s.push(format!(
                "    input {} (sha256 {}), model {}{}",
                r.input,
                opt(r.input_sha256.as_deref()),
                opt(r.model.as_deref()),
                match (e.blob_bytes, &e.blob_crc) {
                    (Some(n), Some(c)) => format!(
                        ", blob {n} bytes, CRC {c}{}",
                        match &e.blob_run_id {
                            Some(id) if *id == r.run_id.to_string() =>
                                " (carries this run's id)".to_string(),
                            Some(id) => format!(" (made by run {id})"),
                            None => " (no run id in it)".to_string(),
                        }
                    ),
                    _ => String::new(),
                }
            ));
            let mut third = Vec::new();
            if let Some(j) = &r.judged {
                third.push(format!("acceptance {}: {}", j.verdict, j.reason));
            }
            if let Some(dg) = r.worst_dg_mg {
                third.push(format!("worst verification |dg| {dg:.4} mg"));
            }
            if let Some(v) = &r.diagnosis_verdict {
                let effects: Vec<&str> = r
                    .findings
                    .as_ref()
                    .and_then(|f| f.as_array())
                    .map(|a| a.iter().filter_map(|f| f["effect"].as_str()).collect())
                    .unwrap_or_default();
                third.push(format!(
                    "diagnosis {v}{}",
                    if effects.is_empty() {
                        String::new()
                    } else {
                        format!(" ({})", effects.join(", "))
                    }
                ));
            }
            if !third.is_empty() {
                s.push(format!("    {}", third.join("; ")));
            }
        }
        s.push(format!(
            "re-issue a stored blob bit for bit: host-fit history {} --db {} --blob RUN --out FILE",
            self.serial, self.store
        ));
        s.join("\n")
    }
}

/// The blob of the run of `serial` whose id is or starts with `run` (at least 6 hex
/// digits), its CRC checked against the stored one and its own trailer.
pub fn stored_blob(store: &Store, serial: &str, run: &str) -> Result<(RunId, Vec<u8>)> {
    let run = run.to_ascii_lowercase();
    if run.len() < 6 || run.len() > 32 || !run.bytes().all(|c| c.is_ascii_hexdigit()) {
        return Err(HostError::new(
            ErrorKind::Invalid,
            format!(
                "--blob `{run}` is not a run id (32 hex digits, or the first 6 or more of them)"
            ),
        ));
    }
    let e = |e| db_error(store.path(), e);
    let mut st = store
        .conn()
        .prepare("SELECT run_id, serial, blob, blob_crc FROM runs WHERE run_id >= ?1 AND run_id < ?2 ORDER BY id")
        .map_err(e)?;
    // every id starting with the prefix lies in [prefix, prefix + 1 at its last digit)
    let upper = format!("{run}g");
    let hits = st
        .query_map([&run, &upper], |r| {
            Ok((
                r.get::<_, String>(0)?,
                r.get::<_, String>(1)?,
                r.get::<_, Option<Vec<u8>>>(2)?,
                r.get::<_, Option<i64>>(3)?,
            ))
        })
        .map_err(e)?
        .collect::<rusqlite::Result<Vec<_>>>()
        .map_err(e)?;
    let (id, unit, blob, crc) = match hits.as_slice() {
        [] => {
            return Err(HostError::in_file(
                ErrorKind::Store,
                store.path(),
                format!("no run `{run}` in the record store"),
            ))
        }
        [one] => one.clone(),
        many => {
            return Err(HostError::in_file(
                ErrorKind::Invalid,
                store.path(),
                format!(
                    "`{run}` starts {} run ids ({}): give more digits",
                    many.len(),
                    many.iter()
                        .map(|h| h.0.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            ))
        }
    };
    if unit != serial {
        return Err(HostError::in_file(
            ErrorKind::Mismatch,
            store.path(),
            format!("run {id} is of unit `{unit}`, not `{serial}`"),
        ));
    }
    let blob = blob.ok_or_else(|| {
        HostError::in_file(
            ErrorKind::Store,
            store.path(),
            format!("run {id} made no blob (a run that failed, or a diagnosis without --out)"),
        )
    })?;
    let n = blob.len();
    let trailer = super::record::blob_crc(&blob);
    let computed = (n >= 4).then(|| firmware_core::crc::crc32(&blob[..n - 4]));
    if trailer.is_none() || trailer != computed || crc != trailer.map(i64::from) {
        return Err(HostError::in_file(
            ErrorKind::Blob,
            store.path(),
            format!("the stored blob of run {id} fails its CRC check (stored {crc:?}, trailer {trailer:?}, computed {computed:?}): not re-issued"),
        ));
    }
    let rid = RunId::parse(&id).ok_or_else(|| {
        HostError::in_file(
            ErrorKind::Store,
            store.path(),
            format!("run id `{id}` is not 32 hex digits"),
        )
    })?;
    Ok((rid, blob))
}
