//! The main job: the paper's experiment on the digital twin, fitted with the paper's
//! model and with richer ones, compensated through firmware-core, summarised.
use crate::calib::build_blob;
use crate::cli::identify_stops;
use crate::error::{HostError, Result};
use crate::identify::{noise, observations, StopCoeffs};
use crate::io::{check_writable, write_atomic};
use crate::positions::Positions;
use crate::recording::Recording;
use crate::simulate::{simulate, SimConfig, TrueUnit};
use crate::temperature::{
    choose_poly_order, fit_joint, fit_table, temperature_clusters, Basis, ModelFit, TableRow,
};
use crate::verify::{verify, Verification};
use firmware_core::compensate::{ErrorModel, Method};
use indicatif::{ProgressBar, ProgressStyle};
use serde::Serialize;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};

/// One row of summary.json.
#[derive(Debug, Clone, Serialize, PartialEq)]
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

/// A fitted model of the demo with its verifications.
pub struct DemoModel {
    /// Name in the summary.
    pub name: String,
    /// The fit.
    pub fit: ModelFit,
    /// Verification with method 1 and method 2.
    pub verifications: [Verification; 2],
    /// Blob path.
    pub blob: PathBuf,
}

/// Everything the demo produced (also what the report plots).
pub struct DemoOutcome {
    /// The recording.
    pub recording: Recording,
    /// Per-stop identification (TP positions).
    pub stops: Vec<StopCoeffs>,
    /// The models.
    pub models: Vec<DemoModel>,
    /// summary.json rows.
    pub rows: Vec<SummaryRow>,
    /// The simulated truth, when the recording is simulated.
    pub truth: Option<TrueUnit>,
    /// Files written (the demo's).
    pub files: Vec<PathBuf>,
}

fn bar(len: u64, msg: &str) -> ProgressBar {
    if !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let b = ProgressBar::new(len);
    b.set_style(
        ProgressStyle::with_template("{msg:24} [{bar:40}] {percent:>3}%")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    b.set_message(msg.to_string());
    b
}

/// The demo's output files in `dir`.
pub fn outputs(dir: &Path) -> Vec<PathBuf> {
    [
        "recording.csv",
        "truth.json",
        "paper-pwl2.blob",
        "poly.blob",
        "pwl-all.blob",
        "summary.json",
        "report.html",
    ]
    .iter()
    .map(|f| dir.join(f))
    .collect()
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

/// Run the demo into `dir`.
pub fn run(dir: &Path, seed: u64, force: bool) -> Result<DemoOutcome> {
    std::fs::create_dir_all(dir).map_err(|e| HostError::io(dir, &e))?;
    for f in outputs(dir) {
        check_writable(&f, force)?;
    }
    let cfg = SimConfig {
        seed,
        ..SimConfig::default()
    };
    let b = bar(1000, "simulating the test");
    let sim = simulate(&cfg, |f| b.set_position((f * 1000.0) as u64))?;
    b.finish_and_clear();
    let rec_path = dir.join("recording.csv");
    write_atomic(&rec_path, sim.csv.as_bytes(), force)?;
    let truth_json = serde_json::to_string_pretty(&serde_json::json!({"config": cfg, "unit_table_temps_c": crate::simulate::PAPER_UNIT_TEMPS, "unit_table": crate::simulate::PAPER_UNIT}))
        .map_err(|e| HostError::msg(e.to_string()))?;
    write_atomic(&dir.join("truth.json"), truth_json.as_bytes(), force)?;
    let rec = Recording::from_reader(&rec_path, sim.csv.as_bytes(), Positions::default())?;
    let oc = analyse(rec, Some((dir, force)), Some(TrueUnit::new(&cfg)?))?;
    let serial = oc.recording.unit.clone();
    let summary = serde_json::to_string_pretty(
        &serde_json::json!({"unit": serial, "seed": seed, "rows": oc.rows}),
    )
    .map_err(|e| HostError::msg(e.to_string()))?;
    write_atomic(&dir.join("summary.json"), summary.as_bytes(), force)?;
    let report = crate::report::demo_report(&oc, &table(&oc.rows))?;
    write_atomic(&dir.join("report.html"), report.as_bytes(), force)?;
    Ok(oc)
}

/// Fit a recording with the paper's model (when it has stops near -40, +20 and +70 C)
/// and the richer ones, build the blobs (written to `blobs` when given), compensate its
/// verification dwells (PP positions) with methods 1 and 2 through firmware-core.
pub fn analyse(
    rec: Recording,
    blobs: Option<(&Path, bool)>,
    truth: Option<TrueUnit>,
) -> Result<DemoOutcome> {
    let b = bar(4, "fitting");
    let pp: Vec<bool> = (0..rec.positions.list.len())
        .map(|i| rec.positions.name(i).starts_with("PP"))
        .collect();
    let is_pp = |p: usize| pp.get(p).copied().unwrap_or(false);
    let fit_sel = |p: usize| !is_pp(p);
    let stops = identify_stops(&rec, &fit_sel)?;
    let t0 = rec.t0_c;
    let paper = paper_pwl2(&stops, t0).ok();
    b.inc(1);
    let obs = observations(&rec, &fit_sel, 0.25);
    let nz = noise(&rec);
    let poly = choose_poly_order(&obs, &nz, t0, 5, &rec.path)?;
    b.inc(1);
    let temps: Vec<f64> = stops.iter().map(|s| s.temp_c).collect();
    let bps: Vec<f64> = temperature_clusters(&temps)
        .iter()
        .map(|t| (t * 100.0).round() / 100.0)
        .collect();
    let pwl_all = fit_joint(&obs, &nz, &Basis::Pwl { breakpoints: bps }, t0, &rec.path)?;
    b.inc(1);
    let serial = if rec.unit.is_empty() {
        "UNKNOWN".to_string()
    } else {
        rec.unit.clone()
    };
    let mut models = Vec::new();
    let mut rows = Vec::new();
    let poly_name = poly.basis.describe();
    let mut fits = Vec::new();
    if let Some(p) = paper {
        fits.push(("paper-pwl2", "paper-pwl2.blob", p));
    }
    fits.push((poly_name.as_str(), "poly.blob", poly));
    fits.push(("pwl-all", "pwl-all.blob", pwl_all));
    for (name, file, fit) in fits {
        let cal = fit.calibration(0.1, false);
        let (blob, bytes, _) = build_blob(&serial, &cal)?;
        let path = match blobs {
            Some((dir, force)) => {
                let p = dir.join(file);
                write_atomic(&p, &bytes, force)?;
                p
            }
            None => PathBuf::from(file),
        };
        let v1 = verify(&rec, &blob, Method::CorrectConstants, &is_pp)
            .ok_or_else(|| HostError::msg("singular K(T0)"))?;
        let v2 = verify(&rec, &blob, Method::CorrectResult(ErrorModel::Full), &is_pp)
            .ok_or_else(|| HostError::msg("singular K(T0)"))?;
        if models.is_empty() {
            for t in &v1.max_by_temperature {
                rows.push(SummaryRow {
                    model: "t0-constants".into(),
                    method: "none".into(),
                    temp_c: round2(t.temp_c),
                    max_abs_dg_mg: t.max_abs_dg_mg_uncompensated,
                });
            }
        }
        for (m, v) in [("1", &v1), ("2", &v2)] {
            for t in &v.max_by_temperature {
                rows.push(SummaryRow {
                    model: name.to_string(),
                    method: m.into(),
                    temp_c: round2(t.temp_c),
                    max_abs_dg_mg: t.max_abs_dg_mg,
                });
            }
        }
        models.push(DemoModel {
            name: name.to_string(),
            fit,
            verifications: [v1, v2],
            blob: path,
        });
    }
    b.inc(1);
    b.finish_and_clear();
    Ok(DemoOutcome {
        recording: rec,
        stops,
        models,
        rows,
        truth,
        files: Vec::new(),
    })
}

fn round2(t: f64) -> f64 {
    (t * 100.0).round() / 100.0
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
        "max |dg| in the verification positions PP1..PP6, mg (reduction vs T0 constants)\n",
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
                Some(u) if me != "none" && v > 0.0 => format!("{v:.3} ({:.1}x)", u / v),
                _ => format!("{v:.3}"),
            };
            s.push_str(&format!(" {cell:>16}"));
        }
        s.push('\n');
    }
    s
}
