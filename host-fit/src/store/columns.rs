//! A record's columns, defined once: [`columns`] names every column of the `runs` table
//! (but `id`) with its type, [`Record::to_row`] gives a record's values by those names
//! and [`Record::from_row`] reads one back by them. Insert, select, history, the trend
//! and `store copy` use these three and nothing else, on either backend; a test holds
//! the names of the three (and of a new store's table) equal.
use super::record::UnitStatus;
use super::record::{AtT0, Command, Judged, Record, RunId, Trace, COEFFS};
use crate::data::output_unit::OutputUnit;
use firmware_core::model::COEFF_NAMES;
use std::collections::HashMap;
use std::sync::Arc;

/// A column's type, as both backends spell it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SqlType {
    /// Text (SQLite TEXT, PostgreSQL TEXT with byte order: `COLLATE "C"`).
    Text,
    /// A double (SQLite REAL, PostgreSQL DOUBLE PRECISION).
    Real,
    /// A 64-bit integer (SQLite INTEGER, PostgreSQL BIGINT).
    Integer,
    /// Bytes (SQLite BLOB, PostgreSQL BYTEA).
    Blob,
}

/// One column of `runs`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Column {
    /// Its name.
    pub name: String,
    /// Its type.
    pub ty: SqlType,
}

/// A value of a column.
#[derive(Debug, Clone, PartialEq)]
pub enum Value {
    /// NULL.
    Null,
    /// Text.
    Text(String),
    /// A double.
    Real(f64),
    /// An integer.
    Integer(i64),
    /// Bytes.
    Blob(Vec<u8>),
}

impl Value {
    fn text(&self) -> Option<&str> {
        match self {
            Value::Text(s) => Some(s),
            Value::Null | Value::Real(_) | Value::Integer(_) | Value::Blob(_) => None,
        }
    }

    fn real(&self) -> Option<f64> {
        match self {
            Value::Real(v) => Some(*v),
            Value::Integer(i) => Some(*i as f64),
            Value::Null | Value::Text(_) | Value::Blob(_) => None,
        }
    }
}

fn column(name: &str, ty: SqlType) -> Column {
    Column {
        name: name.to_string(),
        ty,
    }
}

/// The coefficient columns of the store: `kxx` .. `u0z`, then `sigma_kxx` .. `sigma_u0z`.
pub fn coefficient_columns() -> Vec<String> {
    COEFF_NAMES
        .iter()
        .map(|n| n.to_string())
        .chain(COEFF_NAMES.iter().map(|n| format!("sigma_{n}")))
        .collect()
}

/// Every column of `runs` but `id`, in the table's order: the one list.
pub fn columns() -> Vec<Column> {
    use SqlType::{Blob, Integer, Real, Text};
    let head = [
        ("run_id", Text),
        ("serial", Text),
        ("time_utc", Text),
        ("host_fit_version", Text),
        ("host_fit_commit", Text),
        ("command", Text),
        ("options", Text),
        ("lot", Text),
        ("input", Text),
        ("input_sha256", Text),
        ("output_unit", Text),
        ("model", Text),
        ("t0_c", Real),
    ];
    let tail = [
        ("blob", Blob),
        ("blob_crc", Integer),
        ("acceptance", Text),
        ("reason", Text),
        ("worst_dg_mg", Real),
        ("diagnosis_verdict", Text),
        ("findings", Text),
        // schema version 2: the unit's test record (and the trace's columns, below)
        ("test_record", Text),
    ];
    head.iter()
        .map(|(n, t)| column(n, *t))
        .chain(coefficient_columns().iter().map(|n| column(n, Real)))
        .chain(tail.iter().map(|(n, t)| column(n, *t)))
        .chain(Trace::names().iter().map(|n| column(n, Text)))
        .collect()
}

/// The type of column `name` (`id` included).
pub fn type_of(name: &str) -> Option<SqlType> {
    if name == "id" {
        return Some(SqlType::Integer);
    }
    columns().into_iter().find(|c| c.name == name).map(|c| c.ty)
}

/// A row: values by column name.
#[derive(Debug, Clone)]
pub struct Row {
    index: Arc<HashMap<String, usize>>,
    values: Vec<Value>,
}

/// The index of a set of column names, shared by the rows of one query.
pub fn index_of(names: &[String]) -> Arc<HashMap<String, usize>> {
    Arc::new(
        names
            .iter()
            .enumerate()
            .map(|(i, n)| (n.clone(), i))
            .collect(),
    )
}

impl Row {
    /// A row of `values` in the order of the names `index` was made from.
    pub fn new(index: Arc<HashMap<String, usize>>, values: Vec<Value>) -> Row {
        Row { index, values }
    }

    /// The value of column `name` (NULL for a column the row does not have).
    pub fn get(&self, name: &str) -> &Value {
        self.index
            .get(name)
            .and_then(|i| self.values.get(*i))
            .unwrap_or(&Value::Null)
    }

    /// Text of column `name`.
    pub fn text(&self, name: &str) -> Option<String> {
        self.get(name).text().map(String::from)
    }

    /// A double of column `name`.
    pub fn real(&self, name: &str) -> Option<f64> {
        self.get(name).real()
    }

    /// An integer of column `name`.
    pub fn integer(&self, name: &str) -> Option<i64> {
        match self.get(name) {
            Value::Integer(i) => Some(*i),
            Value::Null | Value::Text(_) | Value::Real(_) | Value::Blob(_) => None,
        }
    }
}

/// Builds a row by name.
struct Builder(Vec<(String, Value)>);

impl Builder {
    fn set(&mut self, name: &str, v: Value) {
        self.0.push((name.to_string(), v));
    }
    fn text(&mut self, name: &str, v: Option<&str>) {
        self.set(name, v.map_or(Value::Null, |s| Value::Text(s.to_string())));
    }
    fn real(&mut self, name: &str, v: Option<f64>) {
        self.set(
            name,
            v.filter(|x| x.is_finite()).map_or(Value::Null, Value::Real),
        );
    }
}

impl Record {
    /// The record's values by column name: every column of [`columns`].
    pub fn to_row(&self) -> Vec<(String, Value)> {
        let mut b = Builder(Vec::with_capacity(64));
        b.text("run_id", Some(&self.run_id.to_string()));
        b.text("serial", Some(&self.serial));
        b.text("time_utc", Some(&self.time_utc));
        b.text("host_fit_version", Some(&self.version));
        b.text("host_fit_commit", Some(&self.commit));
        b.text("command", Some(self.command.name()));
        b.text("options", Some(&self.options.to_string()));
        b.text("lot", self.lot.as_deref());
        b.text("input", Some(&self.input));
        b.text("input_sha256", self.input_sha256.as_deref());
        b.text(
            "output_unit",
            self.output_unit.as_ref().map(OutputUnit::as_str),
        );
        b.text("model", self.model.as_deref());
        b.real("t0_c", self.at_t0.map(|a| a.t0_c));
        for (k, n) in COEFF_NAMES.iter().enumerate() {
            b.real(n, self.at_t0.map(|a| a.values[k]));
        }
        for (k, n) in COEFF_NAMES.iter().enumerate() {
            b.real(
                &format!("sigma_{n}"),
                self.at_t0.and_then(|a| a.sigma).map(|s| s[k]),
            );
        }
        b.set("blob", self.blob.clone().map_or(Value::Null, Value::Blob));
        b.set(
            "blob_crc",
            self.blob_crc()
                .map_or(Value::Null, |c| Value::Integer(i64::from(c))),
        );
        // not judged is stored as NULL with its reason (the column predates it)
        let judged = self.judged.as_ref();
        b.text(
            "acceptance",
            judged
                .filter(|j| j.verdict != UnitStatus::NotJudged)
                .map(|j| j.verdict.to_string())
                .as_deref(),
        );
        b.text("reason", judged.map(|j| j.reason.as_str()));
        b.real("worst_dg_mg", self.worst_dg_mg);
        b.text(
            "diagnosis_verdict",
            self.diagnosis_verdict.map(|v| v.to_string()).as_deref(),
        );
        b.text(
            "findings",
            self.findings.as_ref().map(|f| f.to_string()).as_deref(),
        );
        b.text(
            "test_record",
            // a TestRecord always serialises (string keys, strings, numbers; NaN as null)
            self.test_record
                .as_ref()
                .and_then(|t| serde_json::to_string(t).ok())
                .as_deref(),
        );
        for (n, v) in self.trace.fields() {
            b.text(&n, v.as_deref());
        }
        b.0
    }

    /// A record from a row holding `id` and every column of [`columns`]; the error
    /// names the column that does not read.
    pub fn from_row(row: &Row) -> std::result::Result<Record, String> {
        let need = |n: &str| row.text(n).ok_or_else(|| format!("column `{n}` is NULL"));
        let json = |n: &str| -> std::result::Result<Option<serde_json::Value>, String> {
            row.text(n)
                .map(|s| serde_json::from_str(&s).map_err(|e| format!("column `{n}`: {e}")))
                .transpose()
        };
        let named = |n: &str, v: &str| format!("column `{n}`: `{v}` is not a known name");
        // a column holding a typed JSON document
        fn typed<T: serde::de::DeserializeOwned>(
            row: &Row,
            n: &str,
        ) -> std::result::Result<Option<T>, String> {
            row.text(n)
                .map(|s| serde_json::from_str(&s).map_err(|e| format!("column `{n}`: {e}")))
                .transpose()
        }
        let run = need("run_id")?;
        let command = need("command")?;
        let mut values = [0.0; COEFFS];
        let mut sigma = [0.0; COEFFS];
        let (mut have, mut have_sigma) = (true, true);
        for (k, n) in COEFF_NAMES.iter().enumerate() {
            match row.real(n) {
                Some(v) => values[k] = v,
                None => have = false,
            }
            match row.real(&format!("sigma_{n}")) {
                Some(v) => sigma[k] = v,
                None => have_sigma = false,
            }
        }
        let judged = match (row.text("acceptance"), row.text("reason")) {
            (Some(v), reason) => Some(Judged {
                verdict: v.parse().ok().ok_or_else(|| named("acceptance", &v))?,
                reason: reason.unwrap_or_default(),
            }),
            // a reason without a verdict: judged, and a band had nothing to judge
            (None, Some(reason)) => Some(Judged {
                verdict: UnitStatus::NotJudged,
                reason,
            }),
            (None, None) => None,
        };
        Ok(Record {
            id: row.integer("id").unwrap_or(0),
            run_id: RunId::parse(&run)
                .ok_or_else(|| format!("column `run_id`: `{run}` is not 32 hex digits"))?,
            serial: need("serial")?,
            time_utc: need("time_utc")?,
            version: need("host_fit_version")?,
            commit: need("host_fit_commit")?,
            command: Command::from_name(&command).ok_or_else(|| named("command", &command))?,
            options: json("options")?.unwrap_or_default(),
            lot: row.text("lot"),
            input: need("input")?,
            input_sha256: row.text("input_sha256"),
            output_unit: row.text("output_unit").map(|u| OutputUnit::parse(&u)),
            model: row.text("model"),
            at_t0: match (row.real("t0_c"), have) {
                (Some(t0_c), true) => Some(AtT0 {
                    t0_c,
                    values,
                    sigma: have_sigma.then_some(sigma),
                }),
                _ => None,
            },
            blob: match row.get("blob") {
                Value::Blob(b) => Some(b.clone()),
                Value::Null | Value::Text(_) | Value::Real(_) | Value::Integer(_) => None,
            },
            judged,
            worst_dg_mg: row.real("worst_dg_mg"),
            diagnosis_verdict: match row.text("diagnosis_verdict") {
                Some(v) => Some(
                    v.parse()
                        .ok()
                        .ok_or_else(|| named("diagnosis_verdict", &v))?,
                ),
                None => None,
            },
            findings: json("findings")?,
            trace: Trace::from_fields(|n| row.text(n)),
            test_record: typed(row, "test_record")?,
        })
    }
}

/// The names of `id` and every column: what a select of whole records asks for.
pub fn record_select() -> Vec<String> {
    std::iter::once("id".to_string())
        .chain(columns().into_iter().map(|c| c.name))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    #[test]
    fn a_record_round_trips_through_its_columns_by_name() {
        let mut r = Record::new(Command::Batch, None, "SN-1", Path::new("a.csv")).unwrap();
        r.id = 7;
        r.at_t0 = Some(AtT0 {
            t0_c: 20.0,
            values: std::array::from_fn(|i| i as f64 + 0.5),
            sigma: Some(std::array::from_fn(|i| 1e-6 * (i + 1) as f64)),
        });
        r.blob = Some(vec![9, 8, 7, 6, 5]);
        r.with_verdict(UnitStatus::NotJudged, "no dwell near T0");
        r.diagnosis_verdict = Some(crate::diagnose::contract::Verdict::PartlyExplained);
        r.findings = Some(serde_json::json!([{"effect": "temp_rate"}]));
        r.trace.station = Some("ST-3".into());
        r.trace.operator = Some("ana".into());
        r.output_unit = Some(OutputUnit::parse("mV"));
        let unit = crate::store::test_record::Unit {
            acceptance: None,
            status: UnitStatus::Error,
            reason: "the recording holds no dwell",
            uncompensated_mg: None,
        };
        r.test_record = Some(crate::store::test_record::build(&r, &unit));
        assert_eq!(
            r.finding_effects().unwrap(),
            vec![crate::diagnose::EffectId::TempRate]
        );
        let named = r.to_row();
        // every column, each once, in the table's order
        let names: Vec<String> = named.iter().map(|c| c.0.clone()).collect();
        let want: Vec<String> = columns().into_iter().map(|c| c.name).collect();
        assert_eq!(names, want);
        // read back from a row whose columns come in another order
        let mut all: Vec<(String, Value)> = named;
        all.push(("id".into(), Value::Integer(7)));
        all.reverse();
        let names: Vec<String> = all.iter().map(|c| c.0.clone()).collect();
        let row = Row::new(index_of(&names), all.into_iter().map(|c| c.1).collect());
        assert_eq!(Record::from_row(&row).unwrap(), r);
        assert!(matches!(row.get("acceptance"), Value::Null));
        assert_eq!(row.text("reason").as_deref(), Some("no dwell near T0"));
    }

    #[test]
    fn a_bad_name_in_a_column_is_named() {
        let r = Record::new(Command::Fit, None, "SN", Path::new("a.csv")).unwrap();
        let mut named = r.to_row();
        for c in &mut named {
            if c.0 == "command" {
                c.1 = Value::Text("refit".into());
            }
        }
        let names: Vec<String> = named.iter().map(|c| c.0.clone()).collect();
        let row = Row::new(index_of(&names), named.into_iter().map(|c| c.1).collect());
        let e = Record::from_row(&row).unwrap_err();
        assert!(e.contains("`command`") && e.contains("refit"), "{e}");
    }
}
