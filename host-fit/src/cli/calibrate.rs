//! `temp-fit`, `identify` and `fit`: from data to coefficients and blobs.
use super::args::{FitArgs, IdentifyArgs, TempFitArgs};
use super::common::{load_for_blob, load_to_fit, oriented, w};
use crate::blob::build_blob;
use crate::data::output_unit::OutputUnit;
use crate::data::table::{read_table, to_csv, TableRow};
use crate::error::Result;
use crate::fit::describe::ModelDescription;
use crate::fit::equilibrium::Excluded;
use crate::fit::identify::StopCoeffs;
use crate::fit::noise::{noise, Noise};
use crate::fit::orientation::PoseEstimate;
use crate::fit::pipeline::{
    identify_stops, FitOutcome, Identification, ModelChoice, ModelKind, ModelRequest,
};
use crate::fit::predict::{directions, predict, Prediction, Request};
use crate::fit::route::detect::Settling;
use crate::fit::route::detect::Shape;
use crate::fit::route::dynamic::{Candidate, DynamicFit};
use crate::fit::route::{fit_on, Calibrated, Flash, Route, Routed};
use crate::fit::select::Selection;
use crate::fit::temperature::fit_table;
use crate::model::cache::Cache;
use crate::model::precision::F32_BOUND_G;
use crate::output::{check_writable, json, write_atomic};
use firmware_core::model::COEFF_NAMES;
use serde::Serialize;
use std::collections::BTreeMap;
use std::io::Write;

impl From<&super::args::ModelArgs> for ModelRequest {
    fn from(m: &super::args::ModelArgs) -> Self {
        ModelRequest {
            kind: m.model.map(ModelKind::from),
            order: m.order,
            breakpoints: m.breakpoints.clone(),
        }
    }
}

pub(super) fn temp_fit(a: TempFitArgs, out: &mut dyn Write) -> Result<()> {
    let req = ModelRequest::from(&a.model);
    req.check()?;
    let rows = read_table(&a.coeffs)?;
    let temps: Vec<f64> = rows.iter().map(|r| r.temp_c).collect();
    let kind = match (req.kind, req.order) {
        (Some(k), _) => k,
        (None, Some(_)) => ModelKind::Poly,
        (None, None) => ModelKind::Pwl,
    };
    let choice = ModelChoice {
        kind,
        order: req.order,
        breakpoints: req.breakpoints,
    };
    let basis = choice.basis(&temps);
    let fit = fit_table(&rows, &basis, a.t0).map_err(|e| e.within(&a.coeffs))?;
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
    /// The outputs' unit: K is in it per g, U0 in it.
    output_unit: &'a OutputUnit,
    /// None when no dwell has two samples (a dwell-averaged recording).
    noise_sigma: Option<[f64; 3]>,
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
    let rec = oriented(load_to_fit(&a.input, err)?, err)?;
    let nz = noise(&rec);
    let st = identify_stops(&rec)?;
    let table = to_csv(&table_rows(&st))?;
    if let Some(c) = &a.csv {
        write_atomic(c, table.as_bytes(), a.force)?;
    }
    if a.json {
        let j = Identified {
            unit: &rec.unit,
            output_unit: &rec.output_unit,
            noise_sigma: (nz.dof > 0).then_some(nz.sigma),
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
        let noise_line = if nz.dof > 0 {
            format!(
                "noise sigma (per sample) x {:.3e} y {:.3e} z {:.3e} {}",
                nz.sigma[0], nz.sigma[1], nz.sigma[2], rec.output_unit
            )
        } else {
            // a dwell-averaged recording: nothing to take the noise from
            "no dwell has two samples: the noise is not known, and the standard errors below are for unit noise (relative only)".to_string()
        };
        w(out, format!("unit {}  {noise_line}", rec.unit))?;
        w(out, identified_text(&st, rec.output_unit.as_str()))
    }
}

/// The stops' coefficients as a table for a terminal: one row per coefficient with its
/// unit, one column per stop, each value with its 1-sigma.
fn identified_text(st: &[StopCoeffs], unit: &str) -> String {
    let mut s = format!(
        "coefficients at each stop (value +- 1 sigma; K in {unit}/g, U0 in {unit}):\n{:<5} {:<8}",
        "", "unit"
    );
    for x in st {
        s.push_str(&format!(" {:>23}", format!("{:.2} C", x.temp_c)));
    }
    for (c, name) in COEFF_NAMES.iter().enumerate() {
        let u = if c < 9 {
            format!("{unit}/g")
        } else {
            unit.to_string()
        };
        s.push_str(&format!("\n{name:<5} {u:<8}"));
        for x in st {
            s.push_str(&format!(
                " {:>23}",
                format!("{:.8} +- {:.1e}", x.coeffs[c], x.stderr[c])
            ));
        }
    }
    s.push_str(&format!(
        "\npositions: {}\n(`--csv FILE` writes the table in the format of paper-tables.csv)",
        st.iter()
            .map(|x| format!("{:.2} C: {}", x.temp_c, x.positions.join(" ")))
            .collect::<Vec<_>>()
            .join("; ")
    ));
    s
}

/// `fit --json`.
#[derive(Serialize)]
struct Fitted<'a> {
    unit: &'a str,
    route: &'static str,
    model: String,
    /// How the data chose the model (absent when `--model` gave it).
    #[serde(skip_serializing_if = "Option::is_none")]
    chosen_by: Option<&'a Selection>,
    /// Said plainly when the data hold one temperature.
    #[serde(skip_serializing_if = "Option::is_none")]
    no_temperature_model: Option<String>,
    t0_c: f64,
    t_min_c: f64,
    t_max_c: f64,
    /// The firmware's cache of N(T): its step and its worst cost.
    cache: Cache,
    noise_sigma: [f64; 3],
    noise_source: &'static str,
    /// Where every noise figure of this output comes from.
    noise_figures: NoiseFigures,
    /// The predicted compensation error against temperature (joint fits).
    #[serde(skip_serializing_if = "Option::is_none")]
    predicted_error: Option<Prediction>,
    excluded_not_in_equilibrium: Excluded,
    #[serde(skip_serializing_if = "Option::is_none")]
    orientations: Option<Orientations<'a>>,
    k2: [Option<f64>; 3],
    stops: Vec<StopSummary<'a>>,
    f32_departure_g: f64,
    f32_bound_g: f64,
    blob: String,
    blob_bytes: usize,
    temperature_model: ModelDescription,
    warnings: &'a [String],
}

/// Each noise figure of `fit` and its source.
#[derive(Serialize)]
struct NoiseFigures {
    /// `noise_sigma`.
    noise_sigma: &'static str,
    /// `predicted_error.covariance_scale`.
    covariance_scale: &'static str,
    /// `predicted_error.dwell_noise_1sigma_mg`.
    dwell_noise_1sigma_mg: &'static str,
}

impl NoiseFigures {
    fn of(noise: &Noise) -> NoiseFigures {
        let known = noise.dof > 0;
        NoiseFigures {
            noise_sigma: noise.source(),
            covariance_scale: if known {
                "residual scatter: the reduced chi-square of the calibration windows against their in-dwell noise, at least 1"
            } else {
                "residual scatter: the calibration windows' residual variance (no in-dwell noise)"
            },
            dwell_noise_1sigma_mg: if known {
                "in-dwell scatter (successive samples) over the root of the dwell's samples; not widened by the model's residuals"
            } else {
                "residual scatter of the fit (no in-dwell noise)"
            },
        }
    }
}

#[derive(Serialize)]
struct Orientations<'a> {
    estimated: usize,
    alternations: usize,
    #[serde(skip_serializing_if = "Option::is_none")]
    frame: Option<&'a str>,
    poses: &'a [PoseEstimate],
}

#[derive(Serialize)]
struct StopSummary<'a> {
    temp_c: f64,
    positions: &'a [String],
}

/// The blob `fit` wrote.
struct Written<'a> {
    serial: &'a str,
    bytes: usize,
    f32_departure_g: f64,
    /// The firmware's cache of N(T), as chosen.
    cache: Cache,
}

fn fitted<'a>(
    a: &'a FitArgs,
    rec: &'a crate::data::recording::Recording,
    (route, oc): (Route, &'a FitOutcome),
    cal: &firmware_core::temperature::Calibration<f64>,
    written: &Written<'a>,
) -> Fitted<'a> {
    let prediction = (!oc.fit.axis_cov.is_empty()).then(|| {
        // the estimated poses' vectors, carried with the fit
        let positions = oc
            .orientation
            .as_ref()
            .map_or(&rec.positions, |o| &o.positions);
        let (directions, dwell_samples) = directions(rec, positions);
        let req = Request {
            directions,
            dwell_samples,
            t_min_c: cal.t_min_c,
            t_max_c: cal.t_max_c,
            update_step_c: cal.update_step_c,
        };
        let mut p = predict(&oc.fit, &oc.noise, &req);
        // the cache's cost over the whole range and every attitude, as chosen
        p.cache_step_c = written.cache.step_c;
        p.cache_lag_max_mg = written.cache.worst_mg;
        p
    });
    let one_temp = crate::fit::predict::is_constant(&oc.fit.basis);
    Fitted {
        unit: written.serial,
        route: route.name(),
        model: oc.fit.basis.describe(),
        chosen_by: oc.selection.as_ref(),
        no_temperature_model: one_temp.then(|| format!(
            "all calibration data are at one temperature ({:.1} C): the 12 coefficients are identified there and no temperature model can be fitted; the blob holds them constant",
            oc.fit.t_range.0
        )),
        t0_c: cal.t0_c,
        t_min_c: cal.t_min_c,
        t_max_c: cal.t_max_c,
        cache: written.cache,
        noise_sigma: oc.noise.sigma,
        noise_source: oc.noise.source(),
        noise_figures: NoiseFigures::of(&oc.noise),
        predicted_error: prediction,
        excluded_not_in_equilibrium: oc.excluded,
        orientations: oc.orientation.as_ref().map(|o| Orientations {
            estimated: o.poses.len(),
            alternations: o.iterations,
            frame: o.frame.as_deref(),
            poses: &o.poses,
        }),
        k2: oc.fit.k2,
        stops: oc
            .stops
            .iter()
            .map(|s| StopSummary {
                temp_c: s.temp_c,
                positions: &s.positions,
            })
            .collect(),
        f32_departure_g: written.f32_departure_g,
        f32_bound_g: F32_BOUND_G,
        blob: a.out.display().to_string(),
        blob_bytes: written.bytes,
        temperature_model: ModelDescription::of(&oc.fit, false),
        warnings: &rec.warnings,
    }
}

pub(super) fn fit(a: FitArgs, out: &mut dyn Write, err: &mut dyn Write) -> Result<()> {
    check_writable(&a.out, a.force)?;
    let req = ModelRequest::from(&a.model);
    req.check()?;
    let rec = load_for_blob(&a.input, err)?;
    let mut notes = Vec::new();
    let routed = fit_on(&rec, a.route.into(), &req, &mut notes)?;
    for n in notes {
        w(err, format!("note: {n}"))?;
    }
    let flash = Flash {
        clamp: a.clamp,
        update_step: a.update_step,
    };
    let calibrated = routed.calibration(&rec, flash)?;
    match routed {
        Routed::Dynamic { fit, settling } => {
            fit_dynamic_cli(&a, &rec, (&fit, settling), calibrated, out, err)
        }
        Routed::Identified { how, outcome } => {
            fit_static_cli(&a, &rec, (how, &outcome), calibrated, out, err)
        }
    }
}

/// `fit` on the static, joint or per-stop route: the blob, the record, the output.
fn fit_static_cli(
    a: &FitArgs,
    rec: &crate::data::recording::Recording,
    (how, oc): (Identification, &FitOutcome),
    c: Calibrated,
    out: &mut dyn Write,
    err: &mut dyn Write,
) -> Result<()> {
    let Calibrated { cal, cache } = c;
    let serial_name = a.serial.as_deref().unwrap_or(rec.serial());
    let (blob, bytes, dep) = build_blob(serial_name, &rec.output_unit, &cal)?;
    let run = super::records::Run {
        args: &a.record,
        serial: serial_name,
        rec,
        err,
    };
    let bytes = super::records::fit(run, oc, &cal, bytes)?;
    write_atomic(&a.out, &bytes, a.force)?;
    let written = Written {
        serial: serial_name,
        bytes: bytes.len(),
        f32_departure_g: dep,
        cache,
    };
    let j = fitted(a, rec, (Route::from(how), oc), &cal, &written);
    if a.json {
        return w(out, json(&j)?);
    }
    w(out, fit_text(&j))?;
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

/// `fit --json` on the dynamic route.
#[derive(Serialize)]
struct FittedDynamic<'a> {
    unit: &'a str,
    route: &'static str,
    model: String,
    /// The recording's dwells: how many move in temperature.
    shape: Shape,
    /// Why a stop-and-soak test took this route: the settling its dwells showed.
    #[serde(skip_serializing_if = "Option::is_none")]
    settling: Option<Settling>,
    /// The thermal lag the blob carries, s (absent: none was supported).
    #[serde(skip_serializing_if = "Option::is_none")]
    thermal_lag_tau_s: Option<f64>,
    /// The temperature-rate term per axis (output units per C/s) and the estimator's
    /// time constant, s.
    #[serde(skip_serializing_if = "Option::is_none")]
    temp_rate: Option<([f64; 3], f64)>,
    /// Held-out blocks of time the models were compared on.
    heldout_blocks: usize,
    /// Every model compared.
    candidates: &'a [Candidate],
    t0_c: f64,
    t_min_c: f64,
    t_max_c: f64,
    cache_step_c: f64,
    f32_departure_g: f64,
    f32_bound_g: f64,
    blob: String,
    blob_bytes: usize,
    warnings: &'a [String],
}

fn fit_dynamic_cli(
    a: &FitArgs,
    rec: &crate::data::recording::Recording,
    (d, settling): (&DynamicFit<'_>, Option<Settling>),
    c: Calibrated,
    out: &mut dyn Write,
    err: &mut dyn Write,
) -> Result<()> {
    let cal = c.cal;
    let serial_name = a.serial.as_deref().unwrap_or(rec.serial());
    let (blob, bytes, dep) = build_blob(serial_name, &rec.output_unit, &cal)?;
    let run = super::records::Run {
        args: &a.record,
        serial: serial_name,
        rec,
        err,
    };
    let bytes = super::records::fit_dynamic(run, d, &cal, bytes)?;
    write_atomic(&a.out, &bytes, a.force)?;
    let j = FittedDynamic {
        unit: serial_name,
        route: Route::Dynamic.name(),
        model: d.describe(),
        shape: d.shape,
        settling,
        thermal_lag_tau_s: d.lag_tau_s,
        temp_rate: d.rate,
        heldout_blocks: d.blocks,
        candidates: &d.candidates,
        t0_c: cal.t0_c,
        t_min_c: cal.t_min_c,
        t_max_c: cal.t_max_c,
        cache_step_c: cal.update_step_c,
        f32_departure_g: dep,
        f32_bound_g: F32_BOUND_G,
        blob: a.out.display().to_string(),
        blob_bytes: bytes.len(),
        warnings: &rec.warnings,
    };
    if a.json {
        return w(out, json(&j)?);
    }
    let mut s = format!(
        "unit {}: dynamic route ({} of {} dwells move in temperature, {:.0}%), model {}, T0 {} C, valid {:.2}..{:.2} C\nmodels compared on {} held-out blocks of time (held-out chi-square, floor units):\n",
        j.unit,
        j.shape.moving_dwells,
        j.shape.moving_dwells + j.shape.static_dwells,
        100.0 * j.shape.moving_share,
        j.model,
        j.t0_c,
        j.t_min_c,
        j.t_max_c,
        j.heldout_blocks
    );
    if let Some(st) = j.settling {
        s.insert_str(
            0,
            &format!(
                "the dwells still settle (a lag near {:.0} s explains {:.0}% of the static fit's residual): fitted on the dynamic route\n",
                st.tau_s,
                100.0 * st.explained
            ),
        );
    }
    for c in j.candidates {
        s.push_str(&format!(
            "  {} {:<48} {:.1}\n",
            if c.chosen { "*" } else { " " },
            c.model,
            c.heldout_chi2
        ));
    }
    s.push_str(&match j.thermal_lag_tau_s {
        Some(t) => format!(
            "the blob carries the thermal lag ({t:.1} s = {:.2} min): the unit compensates with it on its own clock\n",
            t / 60.0
        ),
        None => "no thermal lag supported by the held-out blocks: none in the blob\n".into(),
    });
    s.push_str(&format!(
        "wrote {} ({} bytes, serial {})",
        a.out.display(),
        bytes.len(),
        blob.serial
    ));
    w(out, s)
}

fn fit_text(j: &Fitted<'_>) -> String {
    let mut s = vec![format!(
        "unit {}: {} route, model {}{}, T0 {} C, valid {:.2}..{:.2} C",
        j.unit,
        j.route,
        j.model,
        if j.chosen_by.is_some() {
            " (chosen by the data)"
        } else {
            ""
        },
        j.t0_c,
        j.t_min_c,
        j.t_max_c
    )];
    if let Some(sel) = j.chosen_by.filter(|s| !s.candidates.is_empty()) {
        s.push(format!("chosen by {}: {}", sel.method, sel.reason));
        let c: Vec<String> = sel
            .candidates
            .iter()
            .map(|c| match c.held_out_rms_dg_mg {
                Some(v) => format!("{} {v:.4}", c.model),
                None => format!("{} -", c.model),
            })
            .collect();
        if !c.is_empty() {
            s.push(format!("held-out rms |dg|, mg: {}", c.join(", ")));
        }
    }
    if let Some(n) = &j.no_temperature_model {
        s.push(n.clone());
    }
    let ex = j.excluded_not_in_equilibrium.text();
    if !ex.is_empty() {
        s.push(ex);
    }
    if let Some(o) = &j.orientations {
        s.push(format!(
            "{} poses of unknown orientation estimated ({} alternations){}",
            o.estimated,
            o.alternations,
            o.frame.map(|f| format!("; {f}")).unwrap_or_default()
        ));
    }
    if let Some(p) = &j.predicted_error {
        let pts: Vec<String> = p
            .points
            .iter()
            .map(|q| format!("{:.1} C {:.4}", q.temp_c, q.dg_1sigma_mg))
            .collect();
        let widened: Vec<String> = ["x", "y", "z"]
            .iter()
            .zip(p.covariance_scale)
            .map(|(a, c)| format!("{a} {c:.2}"))
            .collect();
        s.push(format!(
            "predicted compensation error (1 sigma of |dg| from the fit's covariance, widened by the residual scatter of the calibration windows: reduced chi-square {}; worst of {} directions; inside the valid range only), mg: {}",
            widened.join(" "),
            p.directions.len(),
            pts.join(", ")
        ));
        s.push(format!(
            "a verification dwell of {} samples adds {:.4} mg of its own noise (noise: {}, over the root of its samples; not the model's residuals); valid range {:.2}..{:.2} C",
            p.dwell_samples, p.dwell_noise_1sigma_mg, j.noise_source, p.t_min_c, p.t_max_c
        ));
    }
    s.push(j.cache.text());
    if !j.stops.is_empty() {
        let stops: Vec<String> = j
            .stops
            .iter()
            .map(|s| format!("{:.2} C ({} positions)", s.temp_c, s.positions.len()))
            .collect();
        s.push(format!("stops: {}", stops.join(", ")));
    }
    s.push(format!(
        "f32 firmware path vs f64 model: max {:.2e} g (bound {F32_BOUND_G:.0e} g)",
        j.f32_departure_g
    ));
    s.join("\n")
}
