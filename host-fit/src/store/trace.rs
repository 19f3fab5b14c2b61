//! Where and by whom a unit was calibrated: one type, [`Trace`], with its table of fields
//! ([`Trace::FIELDS`]: each field's flag, environment variable, help and the schema
//! version that added its column). The command line's flags (`cli::args::TraceArgs`
//! builds them from the table), the store's columns and the migration that adds them,
//! the record's JSON, `history`'s line and the test record's metadata all follow from
//! it: a new traceability field is a field here and a line of the table.
use serde::{Deserialize, Serialize};

/// Where and by whom a unit was calibrated: the station (the bench computer), the
/// chamber and the tilter it ran in, the fixture it was clamped in, and the operator.
/// From the flags (`--station` ...), else their environment variables (`HOSTFIT_STATION`
/// ...); the operator else the login name (`USER`).
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Trace {
    /// The station.
    pub station: Option<String>,
    /// The climatic chamber.
    pub chamber: Option<String>,
    /// The tilter (rate table, dividing head).
    pub tilter: Option<String>,
    /// The operator.
    pub operator: Option<String>,
    /// The fixture (the adapter plate the unit is clamped in on the tilter): a
    /// `fixture_error` the diagnosis names may be the fixture's, and the record says which
    /// one it was (the trend does not group by it).
    pub fixture: Option<String>,
}

/// One field of [`Trace`]: how the command line and the store know it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Field {
    /// Its serde name: the flag (`--NAME`) and the store's column.
    pub name: &'static str,
    /// The environment variable that gives it when the flag does not.
    pub env: &'static str,
    /// The flag's help.
    pub help: &'static str,
    /// The schema version that added its column: a new field takes the next version,
    /// never one a store may already be at (that store would never get the column); the
    /// version's migration adds it ([`super::schema::migrations`]).
    pub since: i64,
}

impl Trace {
    /// Every field, in the store's column order. A test holds it to the struct's fields.
    pub const FIELDS: &'static [Field] = &[
        Field {
            name: "station",
            env: "HOSTFIT_STATION",
            help: "The station (bench computer) recorded with the run.",
            since: 2,
        },
        Field {
            name: "chamber",
            env: "HOSTFIT_CHAMBER",
            help: "The climatic chamber the unit ran in.",
            since: 2,
        },
        Field {
            name: "tilter",
            env: "HOSTFIT_TILTER",
            help: "The tilter (rate table, dividing head) the unit ran on.",
            since: 2,
        },
        Field {
            name: "operator",
            env: "HOSTFIT_OPERATOR",
            help: "The operator (default: the login name, USER).",
            since: 2,
        },
        Field {
            name: "fixture",
            env: "HOSTFIT_FIXTURE",
            help: "The fixture (adapter plate) the unit was clamped in on the tilter.",
            since: 3,
        },
    ];

    /// The newest schema version a field needs (the store's version is at least this).
    pub const fn newest_column() -> i64 {
        let mut v = 0;
        let mut i = 0;
        while i < Self::FIELDS.len() {
            if Self::FIELDS[i].since > v {
                v = Self::FIELDS[i].since;
            }
            i += 1;
        }
        v
    }

    /// The fields' names, in the order of [`Trace::FIELDS`] (the store's columns).
    pub fn names() -> Vec<String> {
        Trace::FIELDS.iter().map(|f| f.name.to_string()).collect()
    }

    /// The fields by name, in the order of [`Trace::FIELDS`], with their values.
    pub fn fields(&self) -> Vec<(String, Option<String>)> {
        // a struct of optional strings serialises to an object of strings and nulls
        let v = serde_json::to_value(self).unwrap_or_default();
        Trace::names()
            .into_iter()
            .map(|n| {
                let value = v.get(&n).and_then(|x| x.as_str()).map(String::from);
                (n, value)
            })
            .collect()
    }

    /// A trace read field by field (`value` of a field's name; None: not recorded).
    pub fn from_fields(value: impl Fn(&str) -> Option<String>) -> Trace {
        let o: serde_json::Map<String, serde_json::Value> = Trace::names()
            .into_iter()
            .map(|n| {
                let v = value(&n).map_or(serde_json::Value::Null, serde_json::Value::String);
                (n, v)
            })
            .collect();
        // every field is an optional string, so an object of strings and nulls reads
        serde_json::from_value(serde_json::Value::Object(o)).unwrap_or_default()
    }

    /// Whether no field is recorded.
    pub fn is_empty(&self) -> bool {
        self.fields().iter().all(|f| f.1.is_none())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_field_is_in_the_table_once_with_its_variable_and_version() {
        // the fields as serde names them (a struct's object: sorted keys)
        let serde_names: Vec<String> = serde_json::to_value(Trace::default())
            .unwrap()
            .as_object()
            .unwrap()
            .keys()
            .cloned()
            .collect();
        let mut listed = Trace::names();
        listed.sort();
        listed.dedup();
        assert_eq!(listed.len(), Trace::FIELDS.len(), "a field listed twice");
        assert_eq!(listed, serde_names, "Trace::FIELDS must list every field");
        let all: Vec<String> = crate::store::columns::columns()
            .into_iter()
            .map(|c| c.name)
            .collect();
        for f in Trace::FIELDS {
            // a plain SQL name (the migration writes it unquoted), no other column's
            assert!(
                f.name.chars().all(|c| c.is_ascii_lowercase() || c == '_'),
                "{f:?}"
            );
            let n = all.iter().filter(|c| *c == f.name).count();
            assert!(n == 1 && f.name != "id", "{f:?}: {n} columns of its name");
            assert_eq!(f.env, format!("HOSTFIT_{}", f.name.to_uppercase()));
            // version 1 had no traceability; a field is added by a migration
            assert!(f.since >= 2 && !f.help.is_empty(), "{f:?}");
        }
        assert!(Trace::newest_column() >= 2);
    }

    #[test]
    fn a_trace_reads_back_field_by_field() {
        let t = Trace::from_fields(|n| Some(format!("{n}-value")));
        for (n, v) in t.fields() {
            assert_eq!(v, Some(format!("{n}-value")));
        }
        let fields = t.fields();
        let again =
            Trace::from_fields(|n| fields.iter().find(|f| f.0 == n).and_then(|f| f.1.clone()));
        assert_eq!(again, t);
        assert!(Trace::default().is_empty());
        let one = Trace::from_fields(|n| (n == "operator").then(|| "ana".to_string()));
        assert!(!one.is_empty());
        assert_eq!(one.operator.as_deref(), Some("ana"));
    }
}
