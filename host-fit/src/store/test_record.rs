//! A unit's test record for the line's systems (MES, traceability, yield dashboards):
//! one JSON document per unit of a batch, written beside its blob
//! (`UNIT.test-record.json`) and kept in its store record (`host-fit history SERIAL
//! --db ... --test-record`). Its shape follows OpenHTF's test record, so that a line
//! that already reads those reads this: the device (`dut_id`), the station, start and
//! end times in milliseconds since 1970, the `outcome` (`PASS`, `FAIL`, `ERROR`) with
//! `outcome_details`, `metadata`, and `phases`, each with its `measurements`: a name,
//! the measured value, its units, its `validators` (the limits, as text) and its own
//! `outcome` (`PASS`, `FAIL`, or `UNSET` when nothing was measured).
//!
//! The fields (schema `host-fit-test-record/1`; docs/records.md shows an example):
//! - `dut_id`: the unit's serial; `station_id`: the station (or null).
//! - `start_time_millis`: the batch's start; `end_time_millis`: when the unit was done.
//! - `outcome`: `PASS` (accepted), `FAIL` (over a limit, or not judged: what was not
//!   judged cannot pass, `outcome_details` says `NOT_JUDGED`), `ERROR` (not processed).
//! - `metadata`: run id, lot, operator, chamber, tilter, host-fit version and commit,
//!   the recording and its SHA-256, the model, the blob's CRC-32.
//! - `phases`: `fit` (T0 and the 12 coefficients at T0 with their 1-sigma, no limits)
//!   and `verify` (the worst compensated |dg| near T0 and over the range against the
//!   acceptance limits, the dwells outside the valid range, the uncompensated |dg|).
use super::record::Record;
use super::record::UnitStatus;
pub use super::test_document::{
    Detail, Measurement, MeasurementOutcome, Outcome, Phase, TestRecord, UNCOMPENSATED, VERIFY,
};
use crate::acceptance::{Acceptance, OutsideRange, Verdict};
use firmware_core::model::COEFF_NAMES;
use std::collections::BTreeMap;

/// Where a unit's test record is written: `OUT/STEM.test-record.json`.
pub fn path(out: &std::path::Path, stem: &str) -> std::path::PathBuf {
    out.join(format!("{stem}.test-record.json"))
}

/// The schema's name and version.
pub const SCHEMA: &str = "host-fit-test-record/1";

fn measurement(name: &str, v: Option<f64>, units: &str, limit: Option<f64>) -> Measurement {
    let outcome = match (v, limit) {
        (None, _) => MeasurementOutcome::Unset,
        // over the limit, or not a number
        (Some(x), Some(l)) if x.is_nan() || x > l => MeasurementOutcome::Fail,
        (Some(_), _) => MeasurementOutcome::Pass,
    };
    Measurement {
        name: name.to_string(),
        measured_value: v,
        units: units.to_string(),
        validators: limit.map(|l| format!("x <= {l}")).into_iter().collect(),
        outcome,
    }
}

fn phase(name: &str, outcome: Outcome, ms: Vec<Measurement>) -> Phase {
    Phase {
        name: name.to_string(),
        outcome,
        measurements: ms.into_iter().map(|m| (m.name.clone(), m)).collect(),
    }
}

/// What a batch unit came to: its acceptance (None: it could not be processed), the
/// reason, and the uncompensated worst |dg|.
pub struct Unit<'a> {
    /// The acceptance (None for a unit that errored).
    pub acceptance: Option<&'a Acceptance>,
    /// The unit's status.
    pub status: UnitStatus,
    /// Why.
    pub reason: &'a str,
    /// The worst |dg| with the T0 constants only, mg.
    pub uncompensated_mg: Option<f64>,
}

/// The test record's metadata of the store record `r`: the run, the tool, the
/// recording, the blob, and where and by whom (every field of the trace but the station,
/// which is the record's `station_id`).
fn metadata(r: &Record) -> BTreeMap<String, serde_json::Value> {
    use serde_json::json as j;
    [
        ("test_name", j!("accelerometer temperature calibration")),
        ("run_id", j!(r.run_id.to_string())),
        ("command", j!(r.command.name())),
        ("lot", j!(r.lot)),
        ("host_fit_version", j!(r.version)),
        ("host_fit_commit", j!(r.commit)),
        ("recording", j!(r.input)),
        ("recording_sha256", j!(r.input_sha256)),
        ("output_unit", j!(r.output_unit)),
        ("model", j!(r.model)),
        ("blob_crc32", j!(r.blob_crc().map(|c| format!("{c:#010x}")))),
    ]
    .into_iter()
    .map(|(k, v)| (k.to_string(), v))
    // where and by whom, every field but the station (the record's `station_id`)
    .chain(
        r.trace
            .fields()
            .into_iter()
            .filter(|(n, _)| n != "station")
            .map(|(n, v)| (n, j!(v))),
    )
    .collect()
}

/// The test record of the unit `u` whose store record is `r`.
pub fn build(r: &Record, u: &Unit<'_>) -> TestRecord {
    let ms = |t: &str| super::clock::parse(t, false).map_or(0, |us| us.div_euclid(1000));
    let unit = r.output_unit.as_ref().map_or("unit", |u| u.as_str());
    let mut fit = vec![measurement("t0_c", r.at_t0.map(|a| a.t0_c), "C", None)];
    for (k, n) in COEFF_NAMES.iter().enumerate() {
        let u = if k < firmware_core::model::U0_INDEX[0] {
            format!("{unit}/g")
        } else {
            unit.to_string()
        };
        fit.push(measurement(n, r.at_t0.map(|a| a.values[k]), &u, None));
        fit.push(measurement(
            &format!("sigma_{n}"),
            r.at_t0.and_then(|a| a.sigma).map(|s| s[k]),
            &u,
            None,
        ));
    }
    let mut details = Vec::new();
    let verify = match u.acceptance {
        Some(a) => {
            let spec = a.spec;
            let outside_limit = (spec.outside_range == OutsideRange::Fail).then_some(0.0);
            let m = vec![
                measurement(
                    "worst_dg_near_t0_mg",
                    a.worst_at_t0_mg,
                    "mg",
                    Some(spec.t0_mg),
                ),
                measurement(
                    "worst_dg_over_range_mg",
                    a.worst_over_range_mg,
                    "mg",
                    Some(spec.range_mg),
                ),
                measurement(
                    "dwells_outside_valid_range",
                    Some(a.dwells_outside_range as f64),
                    "dwells",
                    outside_limit,
                ),
                measurement(UNCOMPENSATED, u.uncompensated_mg, "mg", None),
            ];
            let code = match a.acceptance {
                Verdict::Pass => None,
                Verdict::Fail if a.dwells_failed == 0 && a.dwells_outside_range > 0 => {
                    Some("OUTSIDE_RANGE")
                }
                Verdict::Fail => Some("OVER_LIMIT"),
                Verdict::NotJudged => Some("NOT_JUDGED"),
            };
            if let Some(code) = code {
                details.push(Detail {
                    code: code.into(),
                    description: a.reason.clone(),
                });
            }
            let o = if a.acceptance == Verdict::Pass {
                Outcome::Pass
            } else {
                Outcome::Fail
            };
            Some(phase(VERIFY, o, m))
        }
        None => None,
    };
    let outcome = match u.status {
        UnitStatus::Pass => Outcome::Pass,
        UnitStatus::Fail | UnitStatus::NotJudged => Outcome::Fail,
        UnitStatus::Error => {
            details.push(Detail {
                code: "PROCESSING_ERROR".into(),
                description: u.reason.to_string(),
            });
            Outcome::Error
        }
    };
    let fit_outcome = if r.at_t0.is_some() {
        Outcome::Pass
    } else {
        Outcome::Error
    };
    let mut phases = vec![phase("fit", fit_outcome, fit)];
    phases.extend(verify);
    let meta = metadata(r);
    TestRecord {
        schema: SCHEMA.into(),
        dut_id: r.serial.clone(),
        station_id: r.trace.station.clone(),
        start_time_millis: ms(&r.time_utc),
        end_time_millis: super::clock::now_micros().div_euclid(1000),
        outcome,
        outcome_details: details,
        metadata: meta,
        phases,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::acceptance::Spec;
    use crate::store::record::Command;
    use std::path::Path;

    fn acceptance(v: Verdict, t0: Option<f64>, over: Option<f64>) -> Acceptance {
        Acceptance {
            acceptance: v,
            reason: "why".into(),
            spec: Spec::default(),
            worst_at_t0_mg: t0,
            worst_over_range_mg: over,
            dwells_judged: 4,
            dwells_failed: usize::from(v == Verdict::Fail),
            dwells_outside_range: 0,
            worst_outside_range_mg: None,
            bands_not_judged: Vec::new(),
        }
    }

    #[test]
    fn measurements_carry_their_limits_and_outcomes() {
        let r = Record::new(Command::Batch, None, "SN-9", Path::new("a.csv")).unwrap();
        let a = acceptance(Verdict::Fail, Some(0.1), Some(1.4));
        let t = build(
            &r,
            &Unit {
                acceptance: Some(&a),
                status: UnitStatus::Fail,
                reason: "why",
                uncompensated_mg: Some(9.0),
            },
        );
        assert_eq!(t.outcome, Outcome::Fail);
        assert_eq!(t.outcome_details[0].code, "OVER_LIMIT");
        let v = &t.phases[1].measurements;
        assert_eq!(v["worst_dg_near_t0_mg"].outcome, MeasurementOutcome::Pass);
        assert_eq!(v["worst_dg_near_t0_mg"].validators, ["x <= 0.3"]);
        assert_eq!(
            v["worst_dg_over_range_mg"].outcome,
            MeasurementOutcome::Fail
        );
        assert_eq!(t.phases[1].outcome, Outcome::Fail);
        // not judged: the measurement is unset and the test does not pass
        let a = acceptance(Verdict::NotJudged, None, Some(0.2));
        let t = build(
            &r,
            &Unit {
                acceptance: Some(&a),
                status: UnitStatus::NotJudged,
                reason: "why",
                uncompensated_mg: None,
            },
        );
        assert_eq!(t.outcome, Outcome::Fail);
        assert_eq!(t.outcome_details[0].code, "NOT_JUDGED");
        assert_eq!(
            t.phases[1].measurements["worst_dg_near_t0_mg"].outcome,
            MeasurementOutcome::Unset
        );
        // the JSON reads back, OpenHTF's names spelled as OpenHTF spells them
        let text = serde_json::to_string(&t).unwrap();
        assert!(text.contains("\"outcome\":\"FAIL\"") && text.contains("\"UNSET\""));
        assert_eq!(serde_json::from_str::<TestRecord>(&text).unwrap(), t);
    }
}
