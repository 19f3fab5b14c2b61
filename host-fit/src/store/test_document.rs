//! The test record's document as types (OpenHTF's shape: the test's outcome with its
//! details, metadata, phases of named measurements with their limits and outcomes), as
//! the store keeps it in a record and [`super::test_record`] builds and writes it. The
//! store reads its documents back as these types, so a change to them is a change of the
//! store's schema: it comes with a migration ([`super::schema`]) that rewrites the stored
//! documents, or every record holding an older one would stop reading.
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// A test's or a phase's outcome (OpenHTF's names).
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    Serialize,
    Deserialize,
    strum::Display,
    strum::EnumString,
    strum::IntoStaticStr,
    strum::EnumIter,
)]
#[serde(rename_all = "SCREAMING_SNAKE_CASE")]
#[strum(serialize_all = "SCREAMING_SNAKE_CASE")]
pub enum Outcome {
    /// Accepted.
    Pass,
    /// Over a limit, or not judged.
    Fail,
    /// Not processed.
    Error,
}

/// A measurement's outcome (OpenHTF's names).
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    Serialize,
    Deserialize,
    strum::Display,
    strum::EnumString,
    strum::IntoStaticStr,
    strum::EnumIter,
)]
#[serde(rename_all = "SCREAMING_SNAKE_CASE")]
#[strum(serialize_all = "SCREAMING_SNAKE_CASE")]
pub enum MeasurementOutcome {
    /// Within its limits (or measured, where it has none).
    Pass,
    /// Outside its limits.
    Fail,
    /// Not measured.
    Unset,
}

/// Why an outcome is what it is.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Detail {
    /// `OVER_LIMIT`, `NOT_JUDGED`, `OUTSIDE_RANGE`, `PROCESSING_ERROR`.
    pub code: String,
    /// In words.
    pub description: String,
}

/// One measurement.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Measurement {
    /// Its name.
    pub name: String,
    /// The value (null: not measured).
    pub measured_value: Option<f64>,
    /// Its units (`mg`, `C`, `V/g`, ...).
    pub units: String,
    /// The limits, as text (`x <= 0.3`); none for a measurement kept for the record.
    pub validators: Vec<String>,
    /// Its outcome.
    pub outcome: MeasurementOutcome,
}

/// One phase of the test.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Phase {
    /// `fit` or `verify`.
    pub name: String,
    /// Its outcome.
    pub outcome: Outcome,
    /// Its measurements, by name.
    pub measurements: BTreeMap<String, Measurement>,
}

/// The verification phase's name.
pub const VERIFY: &str = "verify";
/// The measurement of the uncompensated worst |dg| (verification phase), mg.
pub const UNCOMPENSATED: &str = "worst_dg_uncompensated_mg";

/// A unit's test record.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TestRecord {
    /// [`SCHEMA`].
    pub schema: String,
    /// The unit's serial.
    pub dut_id: String,
    /// The station.
    pub station_id: Option<String>,
    /// When the run started, ms since 1970 (UTC).
    pub start_time_millis: i64,
    /// When the unit was done, ms since 1970 (UTC).
    pub end_time_millis: i64,
    /// The test's outcome.
    pub outcome: Outcome,
    /// Why.
    pub outcome_details: Vec<Detail>,
    /// Where it came from.
    pub metadata: BTreeMap<String, serde_json::Value>,
    /// The phases.
    pub phases: Vec<Phase>,
}

impl TestRecord {
    /// The uncompensated worst |dg| its verification phase measured, mg (what a batch
    /// run again after a crash puts back in its summary).
    pub fn uncompensated_mg(&self) -> Option<f64> {
        self.phases
            .iter()
            .find(|p| p.name == VERIFY)?
            .measurements
            .get(UNCOMPENSATED)?
            .measured_value
    }
}
