//! `temp-fit`, `identify` and `fit`: from data to coefficients and blobs.
use super::args::{FitArgs, IdentifyArgs, TempFitArgs};
use super::common::{load, serial, w};
use crate::blob::{build_blob, F32_BOUND_G};
use crate::data::table::{read_table, to_csv, TableRow};
use crate::error::{HostError, Result};
use crate::fit::describe::ModelDescription;
use crate::fit::identify::StopCoeffs;
use crate::fit::noise::noise;
use crate::fit::pipeline::{fit_recording, identify_stops, ModelChoice};
use crate::fit::temperature::fit_table;
use crate::output::{check_writable, json, write_atomic};
use firmware_core::model::COEFF_NAMES;
use serde::Serialize;
use std::collections::BTreeMap;
use std::io::Write;

impl From<&super::args::ModelArgs> for ModelChoice {
    fn from(m: &super::args::ModelArgs) -> Self {
        ModelChoice {
            kind: m.model,
            order: m.order,
            breakpoints: m.breakpoints.clone(),
        }
    }
}

pub(super) fn temp_fit(a: TempFitArgs, out: &mut dyn Write) -> Result<()> {
    let rows = read_table(&a.coeffs)?;
    let temps: Vec<f64> = rows.iter().map(|r| r.temp_c).collect();
    let basis = ModelChoice::from(&a.model).basis(&temps);
    let fit =
        fit_table(&rows, &basis, a.t0).map_err(|e| HostError::in_file(&a.coeffs, e.message))?;
    let d = ModelDescription::of(&fit, a.relative);
    if a.json {
        w(out, json(&d)?)
    } else {
        w(out, d.text(&fit.basis))
    }
}

/// `identify --json`.
#[derive(Serialize)]
struct Identified<'a> {
    unit: &'a str,
    noise_sigma: [f64; 3],
    stops: Vec<IdentifiedStop<'a>>,
}

#[derive(Serialize)]
struct IdentifiedStop<'a> {
    temp_c: f64,
    positions: &'a [String],
    coefficients: BTreeMap<&'static str, f64>,
    stderr: BTreeMap<&'static str, f64>,
    k2: [Option<f64>; 3],
}

fn named(v: &[f64; 12]) -> BTreeMap<&'static str, f64> {
    COEFF_NAMES.iter().copied().zip(v.iter().copied()).collect()
}

fn table_rows(st: &[StopCoeffs]) -> Vec<TableRow> {
    st.iter()
        .map(|s| TableRow {
            temp_c: s.temp_c,
            coeffs: s.coeffs,
            stderr: Some(s.stderr),
        })
        .collect()
}

pub(super) fn identify(a: IdentifyArgs, out: &mut dyn Write, err: &mut dyn Write) -> Result<()> {
    if let Some(c) = &a.csv {
        check_writable(c, a.force)?;
    }
    let rec = load(&a.input, None, err)?;
    let nz = noise(&rec);
    let st = identify_stops(&rec)?;
    let table = to_csv(&table_rows(&st))?;
    if let Some(c) = &a.csv {
        write_atomic(c, table.as_bytes(), a.force)?;
    }
    if a.json {
        let j = Identified {
            unit: &rec.unit,
            noise_sigma: nz.sigma,
            stops: st
                .iter()
                .map(|s| IdentifiedStop {
                    temp_c: s.temp_c,
                    positions: &s.positions,
                    coefficients: named(&s.coeffs),
                    stderr: named(&s.stderr),
                    k2: s.k2,
                })
                .collect(),
        };
        w(out, json(&j)?)
    } else {
        w(
            out,
            format!(
                "unit {}  noise sigma (per sample) x {:.3e} y {:.3e} z {:.3e} {}",
                rec.unit, nz.sigma[0], nz.sigma[1], nz.sigma[2], rec.output_unit
            ),
        )?;
        w(out, table.trim_end())
    }
}

/// `fit --json`.
#[derive(Serialize)]
struct Fitted<'a> {
    unit: &'a str,
    route: &'static str,
    model: String,
    t0_c: f64,
    t_min_c: f64,
    t_max_c: f64,
    noise_sigma: [f64; 3],
    k2: [Option<f64>; 3],
    stops: Vec<StopSummary<'a>>,
    f32_departure_g: f64,
    f32_bound_g: f64,
    blob: String,
    blob_bytes: usize,
    temperature_model: ModelDescription,
    warnings: &'a [String],
}

#[derive(Serialize)]
struct StopSummary<'a> {
    temp_c: f64,
    positions: &'a [String],
}

pub(super) fn fit(a: FitArgs, out: &mut dyn Write, err: &mut dyn Write) -> Result<()> {
    check_writable(&a.out, a.force)?;
    let rec = load(&a.input, a.positions_for_check.as_deref(), err)?;
    let oc = fit_recording(&rec, &ModelChoice::from(&a.model), a.route)?;
    let cal = oc.fit.calibration(a.update_step, a.clamp);
    let (blob, bytes, dep) = build_blob(serial(&rec), &cal)?;
    write_atomic(&a.out, &bytes, a.force)?;
    let j = Fitted {
        unit: serial(&rec),
        route: a.route.name(),
        model: oc.fit.basis.describe(),
        t0_c: cal.t0_c,
        t_min_c: cal.t_min_c,
        t_max_c: cal.t_max_c,
        noise_sigma: noise(&rec).sigma,
        k2: oc.fit.k2,
        stops: oc
            .stops
            .iter()
            .map(|s| StopSummary {
                temp_c: s.temp_c,
                positions: &s.positions,
            })
            .collect(),
        f32_departure_g: dep,
        f32_bound_g: F32_BOUND_G,
        blob: a.out.display().to_string(),
        blob_bytes: bytes.len(),
        temperature_model: ModelDescription::of(&oc.fit, false),
        warnings: &rec.warnings,
    };
    if a.json {
        return w(out, json(&j)?);
    }
    w(
        out,
        format!(
            "unit {}: {} route, model {}, T0 {} C, valid {:.2}..{:.2} C",
            j.unit, j.route, j.model, j.t0_c, j.t_min_c, j.t_max_c
        ),
    )?;
    let stops: Vec<String> = j
        .stops
        .iter()
        .map(|s| format!("{:.2} C ({} positions)", s.temp_c, s.positions.len()))
        .collect();
    w(out, format!("stops: {}", stops.join(", ")))?;
    w(
        out,
        format!("f32 firmware path vs f64 model: max {dep:.2e} g (bound {F32_BOUND_G:.0e} g)"),
    )?;
    w(
        out,
        format!(
            "wrote {} ({} bytes, serial {})",
            a.out.display(),
            bytes.len(),
            blob.serial
        ),
    )
}
