//! `diagnose`, `report` and `blind`: looking into a recording, and testing the looking.
use super::args::{BlindArgs, DiagnoseArgs, ReportArgs};
use super::common::{load, oriented, serial, w};
use crate::analysis::{analyse, table};
use crate::blob::build_blob;
use crate::diagnose::contract::BlobNote;
use crate::error::Result;
use crate::output::{check_writable, json, write_atomic};
use crate::progress::with_progress;
use std::io::Write;

pub(super) fn diagnose(a: DiagnoseArgs, out: &mut dyn Write, err: &mut dyn Write) -> Result<()> {
    for p in a.report.iter().chain(a.out.iter()) {
        check_writable(p, a.force)?;
    }
    let rec = oriented(load(&a.input, None, err)?, err)?;
    let d = crate::diagnose::diagnose(&rec)?;
    let mut c = d.contract(&rec);
    if let Some(b) = &a.out {
        let name = a.serial.as_deref().unwrap_or(serial(&rec));
        let (blob, bytes, dep) = build_blob(name, &rec.output_unit, &d.calibration(rec.t0_c)?)?;
        write_atomic(b, &bytes, a.force)?;
        c.blob = Some(BlobNote {
            path: b.display().to_string(),
            bytes: bytes.len(),
            physics: blob.calibration.physics.is_some(),
            f32_departure_g: dep,
        });
    }
    if let Some(r) = &a.report {
        let html = crate::report::diagnosis::diagnosis_report(&rec, &d)?;
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
    let rec = oriented(load(&a.input, None, err)?, err)?;
    let oc = analyse(rec, None)?;
    let t = format!("{}{}", table(&oc.rows), crate::analysis::verdicts(&oc));
    let html = crate::report::demo::demo_report(&oc)?;
    write_atomic(&a.out, html.as_bytes(), a.force)?;
    w(out, t)?;
    w(out, format!("report: {}", a.out.display()))
}

pub(super) fn blind(a: BlindArgs, out: &mut dyn Write, err: &mut dyn Write) -> Result<()> {
    use rayon::prelude::*;
    // every case is independent and deterministic: run them on all cores
    let mut cases = crate::blind::suite(a.long);
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
