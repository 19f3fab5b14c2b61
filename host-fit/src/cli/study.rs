//! `diagnose`, `report` and `blind`: looking into a recording, and testing the looking.
use super::args::{BlindArgs, DiagnoseArgs, ReportArgs};
use super::common::{load_for_blob, load_to_fit, oriented, w};
use crate::analysis::{analyse, table};
use crate::blob::build_blob_with_terms;
use crate::data::recording::Recording;
use crate::diagnose::contract::BlobNote;
use crate::error::{ErrorKind, HostError, Result};
use crate::output::{check_writable, json, write_atomic};
use crate::progress::with_progress;
use crate::simulate::{SimConfig, TrueUnit};
use serde::Deserialize;
use std::io::Write;
use std::path::Path;

pub(super) fn diagnose(a: DiagnoseArgs, out: &mut dyn Write, err: &mut dyn Write) -> Result<()> {
    for p in a.report.iter().chain(a.out.iter()) {
        check_writable(p, a.force)?;
    }
    // a blob written is refused over partial data, as `fit` refuses it
    let load = if a.out.is_some() {
        load_for_blob
    } else {
        load_to_fit
    };
    let rec = oriented(load(&a.input, err)?, err)?;
    let d = crate::diagnose::diagnose(&rec)?;
    let mut c = d.contract();
    let name = a.serial.as_deref().unwrap_or(rec.serial());
    let built = match &a.out {
        // the discovered terms of the unit's state go in the blob's term table
        Some(_) => Some(
            build_blob_with_terms(
                name,
                &rec.output_unit,
                &d.calibration(rec.t0_c)?,
                &d.terms()?,
            )
            .map(|(blob, bytes, (dep, _))| (blob, bytes, dep))?,
        ),
        None => None,
    };
    let run = super::records::Run {
        args: &a.record,
        serial: name,
        rec: &rec,
        err,
    };
    let stamped = super::records::diagnose(run, &d, &c, built.as_ref().map(|b| b.1.clone()))?;
    if let (Some(b), Some((blob, _, dep)), Some(bytes)) = (&a.out, built, stamped) {
        write_atomic(b, &bytes, a.force)?;
        c.blob = Some(BlobNote {
            path: b.display().to_string(),
            bytes: bytes.len(),
            physics: blob.calibration.physics.is_some(),
            discovered_terms: blob.terms.len(),
            f32_departure_g: dep,
        });
    }
    if let Some(r) = &a.report {
        let html = crate::report::diagnosis::diagnosis_report(&d)?;
        write_atomic(r, html.as_bytes(), a.force)?;
    }
    if a.json {
        w(out, json(&c)?)
    } else {
        w(out, c.text())
    }
}

pub(super) fn report(a: ReportArgs, out: &mut dyn Write, err: &mut dyn Write) -> Result<()> {
    check_writable(&a.out, a.force)?;
    let rec = oriented(load_to_fit(&a.input, err)?, err)?;
    let truth = match &a.truth {
        Some(p) => Some(twin_truth(p, &rec)?),
        None => None,
    };
    let oc = analyse(rec, truth)?;
    let names = crate::analysis::verification_names(&oc.recording);
    let t = format!(
        "{}{}",
        table(&oc.rows, &names),
        crate::analysis::verdicts(&oc)
    );
    let html = crate::report::demo::demo_report(&oc)?;
    write_atomic(&a.out, html.as_bytes(), a.force)?;
    w(out, t)?;
    w(out, format!("report: {}", a.out.display()))
}

/// The twin's truth from `simulate --truth` (or a demo's truth.json): its `config`.
fn twin_truth(path: &Path, rec: &Recording) -> Result<TrueUnit> {
    let text = std::fs::read_to_string(path).map_err(|e| HostError::io(path, &e))?;
    let bad = |e: serde_json::Error| {
        HostError::in_file(
            ErrorKind::Malformed,
            path,
            format!("is not a twin's truth (`simulate --truth`): {e}"),
        )
    };
    let v: serde_json::Value = serde_json::from_str(&text).map_err(bad)?;
    let cfg =
        SimConfig::deserialize(v.get("config").unwrap_or(&serde_json::Value::Null)).map_err(bad)?;
    if cfg.unit.serial != rec.unit {
        return Err(HostError::in_file(
            ErrorKind::Mismatch,
            path,
            format!(
                "is the truth of unit `{}`, the recording is of unit `{}`",
                cfg.unit.serial, rec.unit
            ),
        ));
    }
    TrueUnit::new(&cfg).map_err(|e| e.within(path))
}

pub(super) fn blind(a: BlindArgs, out: &mut dyn Write, err: &mut dyn Write) -> Result<()> {
    use rayon::prelude::*;
    // every case is independent and deterministic: run them on all cores
    let mut cases = crate::blind::suite(a.long);
    if !a.class.is_empty() {
        cases.retain(|c| a.class.contains(&c.class()));
    }
    if let Some(only) = &a.only {
        cases.retain(|c| c.name().contains(only.as_str()));
        for c in &cases {
            w(
                out,
                format!("== {} (scale {}, seed {})", c.name(), c.scale, c.seed),
            )?;
            w(out, crate::blind::diagnosis_text(c))?;
        }
    }
    // the long suite takes minutes: its progress on stderr
    let outcomes: Vec<_> = with_progress("blind suite", "cases", cases.len(), err, |tick| {
        cases
            .par_iter()
            .map(|c| {
                let o = crate::blind::run(c);
                tick();
                o
            })
            .collect()
    });
    w(out, crate::blind::report(&outcomes))
}
