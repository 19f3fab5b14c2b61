//! Reading records back: every record of a unit in the order written, its latest
//! calibration marked (`host-fit history`), and a stored blob re-issued bit for bit
//! after its CRC is checked (`--blob RUN`).
use super::db::{Filter, Store};
use super::record::{Record, RunId};
use crate::error::{ErrorKind, HostError, Result};
use serde::Serialize;

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
pub fn history(store: &mut Store, serial: &str) -> Result<History> {
    let records = store.records(&Filter::serial(serial))?;
    let latest = records
        .iter()
        .filter(|r| r.is_calibration())
        .map(|r| r.id)
        .max();
    Ok(History {
        serial: serial.to_string(),
        store: store.location().to_string(),
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
            if !r.trace.is_empty() {
                let fields: Vec<String> = r
                    .trace
                    .fields()
                    .iter()
                    .map(|(n, v)| format!("{n} {}", opt(v.as_deref())))
                    .collect();
                s.push(format!("    {}", fields.join(", ")));
            }
            let mut third = Vec::new();
            if let Some(j) = &r.judged {
                third.push(format!("acceptance {}: {}", j.verdict, j.reason));
            }
            if let Some(dg) = r.worst_dg_mg {
                third.push(format!("worst verification |dg| {dg:.4} mg"));
            }
            if let Some(v) = r.diagnosis_verdict.map(|v| v.to_string()) {
                let effects: Vec<String> = match r.finding_effects() {
                    Ok(ids) => ids.iter().map(|e| e.as_str().to_string()).collect(),
                    Err(e) => vec![format!("findings unreadable: {e}")],
                };
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

/// A run whose id starts with the digits asked for.
#[derive(Clone)]
struct Hit {
    run: String,
    serial: String,
    blob: Option<Vec<u8>>,
    crc: Option<i64>,
}

/// The blob of the run of `serial` whose id is or starts with `run` (at least 6 hex
/// digits), its CRC checked against the stored one and its own trailer.
pub fn stored_blob(store: &mut Store, serial: &str, run: &str) -> Result<(RunId, Vec<u8>)> {
    let run = run.to_ascii_lowercase();
    if run.len() < 6 || run.len() > 32 || !run.bytes().all(|c| c.is_ascii_hexdigit()) {
        return Err(HostError::new(
            ErrorKind::Invalid,
            format!(
                "--blob `{run}` is not a run id (32 hex digits, or the first 6 or more of them)"
            ),
        ));
    }
    let f = Filter {
        run_prefix: Some(run.clone()),
        ..Filter::default()
    };
    let names: Vec<String> = ["run_id", "serial", "blob", "blob_crc"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    let hits: Vec<Hit> = store
        .select(&names, &f)?
        .iter()
        .map(|r| Hit {
            run: r.text("run_id").unwrap_or_default(),
            serial: r.text("serial").unwrap_or_default(),
            blob: match r.get("blob") {
                super::columns::Value::Blob(b) => Some(b.clone()),
                _ => None,
            },
            crc: r.integer("blob_crc"),
        })
        .collect();
    let Hit {
        run: id,
        serial: unit,
        blob,
        crc,
    } = match hits.as_slice() {
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
                ErrorKind::Store,
                store.path(),
                format!(
                    "`{run}` starts {} run ids ({}): give more digits",
                    many.len(),
                    many.iter()
                        .map(|h| h.run.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            ))
        }
    };
    if unit != serial {
        return Err(HostError::in_file(
            ErrorKind::Store,
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
        return Err(HostError::in_file(ErrorKind::Store, store.path(),
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
