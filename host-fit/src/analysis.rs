//! The demo's comparison, pure: a recording fitted with the paper's model (when it has
//! stops near -40, +20, +70 C), with the model the data choose and with the pwl through
//! every stop, each built into a blob, its verification positions compensated through
//! firmware-core with methods 1 and 2, and judged against the acceptance specification.
use crate::acceptance::{judge, Acceptance, Spec};
use crate::blob::build_blob;
use crate::data::positions::Role;
use crate::data::recording::Recording;
use crate::data::table::TableRow;
use crate::error::{HostError, Result};
use crate::fit::equilibrium::static_observations;
use crate::fit::identify::StopCoeffs;
use crate::fit::noise::noise;
use crate::fit::pipeline::{fit_chosen, identify_stops, stop_temperatures, ModelRequest};
use crate::fit::select::Selection;
use crate::fit::temperature::{fit_joint, fit_table, Basis, ModelFit};
use crate::simulate::TrueUnit;
use crate::verify::{verify, Verification};
use firmware_core::compensate::{ErrorModel, Method};
use serde::{Deserialize, Serialize};

/// One row of summary.json.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct SummaryRow {
    /// `t0-constants`, `paper-pwl2`, `polyN`, `pwl-all`.
    pub model: String,
    /// `none`, `1` or `2`.
    pub method: String,
    /// Verification temperature, C.
    pub temp_c: f64,
    /// Max |dg| over the verification positions, mg.
    pub max_abs_dg_mg: f64,
}

/// A fitted model of the comparison with its verifications.
pub struct DemoModel {
    /// Name in the summary.
    pub name: String,
    /// File name of its blob (`paper-pwl2.blob`, `poly.blob`, `pwl-all.blob`).
    pub file: &'static str,
    /// The fit.
    pub fit: ModelFit,
    /// Its blob's bytes.
    pub blob: Vec<u8>,
    /// Verification with method 1 and method 2.
    pub verifications: [Verification; 2],
    /// The acceptance of its blob (method 1), or why it could not be judged.
    pub acceptance: std::result::Result<Acceptance, String>,
}

/// Everything the comparison produced (also what the report plots).
pub struct DemoOutcome {
    /// The recording.
    pub recording: Recording,
    /// Per-stop identification (calibration positions).
    pub stops: Vec<StopCoeffs>,
    /// The models.
    pub models: Vec<DemoModel>,
    /// summary.json rows.
    pub rows: Vec<SummaryRow>,
    /// The simulated truth, when the recording is simulated.
    pub truth: Option<TrueUnit>,
    /// How the data chose their model.
    pub selection: Selection,
    /// The specification the models are judged by.
    pub spec: Spec,
}

/// Fit the paper's model: formula (10) at the stops near -40, +20, +70 C, then the
/// two-interval piecewise-linear model through them (formula (12)).
pub fn paper_pwl2(stops: &[StopCoeffs], t0: f64) -> Result<ModelFit> {
    let rows: Vec<TableRow> = stops
        .iter()
        .filter(|s| {
            [-40.0, 20.0, 70.0]
                .iter()
                .any(|t| (s.temp_c - t).abs() < 3.0)
        })
        .map(|s| TableRow {
            temp_c: s.temp_c,
            coeffs: s.coeffs,
            stderr: None,
        })
        .collect();
    let bps: Vec<f64> = rows.iter().map(|r| r.temp_c).collect();
    fit_table(&rows, &Basis::Pwl { breakpoints: bps }, t0)
}

/// A model's name in the table: `chosen-` and the family with its parameter count.
pub fn chosen_name(b: &Basis) -> String {
    match b {
        Basis::Poly { order } => format!("chosen-poly{order}"),
        Basis::Pwl { breakpoints } => format!("chosen-pwl{}", breakpoints.len()),
    }
}

/// The models compared: the paper's (when its stops exist), the one the data choose,
/// and the pwl through every stop, the last two from the dwells in equilibrium.
type Fits = (Vec<(String, &'static str, ModelFit)>, Selection);

fn fits(rec: &Recording, stops: &[StopCoeffs]) -> Result<Fits> {
    let cal = |p: usize| rec.positions.has_role(p, Role::Calibration);
    let (obs, _) = static_observations(rec, &cal, 0.25);
    let nz = noise(rec);
    let chosen = fit_chosen(
        rec,
        &ModelRequest {
            kind: None,
            order: None,
            breakpoints: None,
        },
    )?;
    let selection = chosen
        .selection
        .clone()
        .ok_or_else(|| HostError::msg("internal: no selection"))?;
    let pwl_all = fit_joint(
        &obs,
        &nz,
        &Basis::Pwl {
            breakpoints: stop_temperatures(stops),
        },
        rec.t0_c,
        &rec.path,
    )?;
    let mut out = Vec::new();
    if let Ok(p) = paper_pwl2(stops, rec.t0_c) {
        out.push(("paper-pwl2".to_string(), "paper-pwl2.blob", p));
    }
    out.push((chosen_name(&chosen.fit.basis), "chosen.blob", chosen.fit));
    out.push(("pwl-all".to_string(), "pwl-all.blob", pwl_all));
    Ok((out, selection))
}

/// Compare the models on `rec` (see the module doc).
pub fn analyse(rec: Recording, truth: Option<TrueUnit>) -> Result<DemoOutcome> {
    let stops = identify_stops(&rec)?;
    let serial = if rec.unit.is_empty() {
        "UNKNOWN".to_string()
    } else {
        rec.unit.clone()
    };
    let check = |p: usize| rec.positions.has_role(p, Role::Verification);
    let mut models: Vec<DemoModel> = Vec::new();
    let mut rows = Vec::new();
    let spec = Spec::default();
    let (list, selection) = fits(&rec, &stops)?;
    for (name, file, fit) in list {
        let mut cal = fit.calibration(0.0, false);
        crate::blob::Cache::for_model(&rec, &fit, &noise(&rec), &mut cal, None);
        let (blob, bytes, _) = build_blob(&serial, &rec.output_unit, &cal)?;
        let run = |m: Method| -> Result<Verification> {
            verify(&rec, &blob, m, &check).ok_or_else(|| HostError::msg("singular K(T0)"))
        };
        let v = [
            run(Method::CorrectConstants)?,
            run(Method::CorrectResult(ErrorModel::Full))?,
        ];
        if models.is_empty() {
            rows.extend(summary_rows("t0-constants", "none", &v[0], true));
        }
        rows.extend(summary_rows(&name, "1", &v[0], false));
        rows.extend(summary_rows(&name, "2", &v[1], false));
        let acceptance =
            judge(&v[0], &spec, cal.t0_c, (cal.t_min_c, cal.t_max_c)).map_err(|e| e.message);
        models.push(DemoModel {
            name,
            file,
            fit,
            blob: bytes,
            verifications: v,
            acceptance,
        });
    }
    Ok(DemoOutcome {
        recording: rec,
        stops,
        models,
        rows,
        truth,
        selection,
        spec,
    })
}

/// The data's choice and every model's acceptance verdict (method 1), as text lines.
pub fn verdicts(oc: &DemoOutcome) -> String {
    let mut s = format!(
        "data-chosen model: {} by {}\n  {}\nacceptance, method 1 ({}):\n",
        oc.selection.chosen,
        oc.selection.method,
        oc.selection.reason,
        oc.spec.text()
    );
    for m in &oc.models {
        let line = match &m.acceptance {
            Ok(a) => format!("{}: {}", a.acceptance.name(), a.reason),
            Err(e) => format!("not judged: {e}"),
        };
        s.push_str(&format!("  {:<14} {line}\n", m.name));
    }
    s
}

fn summary_rows(
    model: &str,
    method: &str,
    v: &Verification,
    uncompensated: bool,
) -> Vec<SummaryRow> {
    v.max_by_temperature
        .iter()
        .map(|t| SummaryRow {
            model: model.to_string(),
            method: method.to_string(),
            temp_c: (t.temp_c * 100.0).round() / 100.0,
            max_abs_dg_mg: if uncompensated {
                t.max_abs_dg_mg_uncompensated
            } else {
                t.max_abs_dg_mg
            },
        })
        .collect()
}

/// The summary table as text: max |dg| (mg) per temperature, and the reduction
/// against the uncompensated case.
pub fn table(rows: &[SummaryRow]) -> String {
    let mut temps: Vec<f64> = rows.iter().map(|r| r.temp_c).collect();
    temps.sort_by(f64::total_cmp);
    temps.dedup();
    let mut keys: Vec<(String, String)> = Vec::new();
    for r in rows {
        let k = (r.model.clone(), r.method.clone());
        if !keys.contains(&k) {
            keys.push(k);
        }
    }
    let get = |m: &str, me: &str, t: f64| {
        rows.iter()
            .find(|r| r.model == m && r.method == me && r.temp_c == t)
            .map(|r| r.max_abs_dg_mg)
    };
    let mut s = String::from(
        "max |dg| in the verification positions PP1..PP6, mg (in brackets: how many times smaller than with the T0 constants)\n",
    );
    s.push_str(&format!("{:<14} {:<6}", "model", "method"));
    for t in &temps {
        s.push_str(&format!(" {:>16}", format!("{t:.1} C")));
    }
    s.push('\n');
    for (m, me) in &keys {
        s.push_str(&format!("{m:<14} {me:<6}"));
        for t in &temps {
            let v = get(m, me, *t).unwrap_or(f64::NAN);
            let cell = match get("t0-constants", "none", *t) {
                Some(u) if me != "none" && v > 0.0 && u >= v => format!("{v:.3} ({:.1}x)", u / v),
                Some(u) if me != "none" && u > 0.0 => format!("{v:.3} ({:.1}x worse)", v / u),
                _ => format!("{v:.3}"),
            };
            s.push_str(&format!(" {cell:>16}"));
        }
        s.push('\n');
    }
    s
}
