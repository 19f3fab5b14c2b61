//! `verify`, `inspect` and `fw-vectors`: a blob against a recording, a blob alone, and
//! the firmware's expected outputs.
use super::args::{ErrModel, FwVectorsArgs, InspectArgs, MethodArg, VerifyArgs};
use super::common::Outcome;
use super::common::{load, w};
use crate::acceptance::{judge, Acceptance, Verdict};
use crate::blob::{read_blob, singular_k, Inspection};
use crate::data::positions::Role;
use crate::error::{ErrorKind, HostError, Result};
use crate::model::precision::F32_BOUND_G;
use crate::output::{json, write_atomic};
use crate::verify::{verify as run_verify, DwellCheck, TempMax};
use firmware_core::compensate::Method;
use serde::Serialize;
use std::io::Write;

/// `verify --json`.
#[derive(Serialize)]
struct Verified<'a> {
    unit: &'a str,
    blob_serial: &'a str,
    method: String,
    dwells: &'a [DwellCheck],
    max_by_temperature: &'a [TempMax],
    #[serde(flatten)]
    acceptance: &'a Acceptance,
}

/// The firmware's method of `--method` and `--error-model`: an error model given with
/// method 1 (which has none) is an error, never ignored.
fn method(m: MethodArg, error_model: Option<ErrModel>) -> Result<Method> {
    match (m, error_model) {
        (MethodArg::One, None) => Ok(Method::CorrectConstants),
        (MethodArg::One, Some(_)) => Err(HostError::new(
            ErrorKind::Invalid,
            "--error-model applies to method 2 (correct the result); method 1 corrects the constants and has no error model: give --method 2, or leave --error-model out",
        )),
        (MethodArg::Two, e) => Ok(Method::CorrectResult(
            e.unwrap_or(ErrModel::Full).into(),
        )),
    }
}

pub(super) fn verify(a: VerifyArgs, out: &mut dyn Write, err: &mut dyn Write) -> Result<Outcome> {
    let m = method(a.method, a.error_model)?;
    let spec = a.accept.spec()?;
    let (b, blob_bytes) = read_blob(&a.blob)?;
    let rec = load(&a.input, err)?;
    let unit = rec.serial();
    if b.serial.as_str() != unit {
        if !a.force {
            return Err(HostError::in_file(
                ErrorKind::Mismatch,
                &a.blob,
                format!(
                    "is the blob of unit `{}`, the recording is of unit `{unit}`: refusing to verify another unit's blob (give --force to verify it anyway)",
                    b.serial
                ),
            ));
        }
        let _ = writeln!(
            err,
            "warning: verifying unit `{unit}` with the blob of unit `{}` (--force)",
            b.serial
        );
    }
    let check = |p: usize| rec.positions.has_role(p, Role::Verification);
    let v = run_verify(&rec, &b, m, &check).ok_or_else(|| singular_k(&a.blob))?;
    if v.dwells.is_empty() {
        return Err(HostError::in_file(
            ErrorKind::Insufficient,
            &a.input.recording,
            format!(
                "no dwells in the verification positions ({})",
                rec.positions.names_with(Role::Verification).join(",")
            ),
        ));
    }
    let cal = &b.calibration;
    let acc = judge(
        &v,
        &spec,
        f64::from(cal.t0_c),
        (f64::from(cal.t_min_c), f64::from(cal.t_max_c)),
    );
    let run = super::records::Run {
        args: &a.record,
        serial: unit,
        rec: &rec,
        err,
    };
    super::records::verify(run, (&b, &blob_bytes), &v, &acc)?;
    let outcome = match acc.acceptance {
        Verdict::Pass => Outcome::Done,
        Verdict::Fail => Outcome::Rejected,
        Verdict::NotJudged => Outcome::NotJudged,
    };
    if a.json {
        let j = Verified {
            unit,
            blob_serial: b.serial.as_str(),
            method: a.method.name(),
            dwells: &v.dwells,
            max_by_temperature: &v.max_by_temperature,
            acceptance: &acc,
        };
        w(out, json(&j)?)?;
        return Ok(outcome);
    }
    w(
        out,
        format!(
            "dg = |a| - 1 g of every verification dwell (formula (13)), uncompensated (T0 constants) and compensated sample by sample by firmware-core (method {})\n{:<8} {:>9} {:>20} {:>17} {:>8} {:>8}",
            a.method.name(), "position", "temp, C", "uncompensated, mg", "compensated, mg", "samples", "flagged"
        ),
    )?;
    let mut flagged = 0;
    for d in &v.dwells {
        flagged += usize::from(d.flagged > 0);
        w(
            out,
            format!(
                "{:<8} {:>9.2} {:>20.4} {:>17.4} {:>8} {:>8}",
                d.position, d.temp_c, d.dg_mg_uncompensated, d.dg_mg, d.samples, d.flagged
            ),
        )?;
    }
    if flagged > 0 {
        w(
            out,
            format!(
                "{flagged} dwells have flagged samples: the firmware's status said the temperature was outside the blob's valid range {:.2}..{:.2} C (extrapolated), or an input was not finite",
                b.calibration.t_min_c, b.calibration.t_max_c
            ),
        )?;
    }
    for t in &v.max_by_temperature {
        w(
            out,
            format!(
                "max |dg| at {:>7.2} C: uncompensated {:.4} mg, method {} {:.4} mg",
                t.temp_c,
                t.max_abs_dg_mg_uncompensated,
                a.method.name(),
                t.max_abs_dg_mg
            ),
        )?;
    }
    w(
        out,
        format!(
            "acceptance: {} ({}): {}",
            acc.acceptance.name(),
            spec.text(),
            acc.reason
        ),
    )?;
    Ok(outcome)
}

pub(super) fn inspect(a: InspectArgs, out: &mut dyn Write) -> Result<()> {
    let (b, bytes) = read_blob(&a.blob)?;
    let i = Inspection::of(&b, bytes.len());
    if a.json {
        w(out, json(&i)?)
    } else {
        w(out, i.text(&a.blob))
    }
}

pub(super) fn fw_vectors(a: FwVectorsArgs, out: &mut dyn Write) -> Result<()> {
    let (b, _) = read_blob(&a.blob)?;
    if let Some(p) = a.make_inputs {
        let table = crate::vectors::make_inputs(&b, a.n, a.seed);
        write_atomic(&p, &table, a.force)?;
        return w(
            out,
            format!(
                "wrote {} ({} inputs)",
                p.display(),
                table.len() / crate::vectors::RECORD
            ),
        );
    }
    let p = a.inputs.ok_or_else(|| {
        HostError::new(
            ErrorKind::Invalid,
            "give --inputs FILE or --make-inputs FILE",
        )
    })?;
    let table = std::fs::read(&p).map_err(|e| HostError::io(&p, &e))?;
    if table.len() % crate::vectors::RECORD != 0 {
        return Err(HostError::in_file(
            ErrorKind::Malformed,
            &p,
            "length is not a multiple of 20 bytes (ux uy uz temp dt, f32)",
        ));
    }
    let (lines, worst) = crate::vectors::expected(&b, &table, &a.tag_prefix);
    for l in lines {
        w(out, l)?;
    }
    w(
        out,
        format!("f64-departure {worst:e} bound {F32_BOUND_G:e}"),
    )?;
    if !crate::vectors::within_bound(worst) {
        return Err(HostError::new(
            ErrorKind::Numerical,
            format!("f32 departs from f64 by {worst:e} g, over the bound {F32_BOUND_G:e}"),
        ));
    }
    Ok(())
}
