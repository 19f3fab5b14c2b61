//! Production batches: fit (and optionally diagnose) every recording in a folder in
//! parallel, one blob and one JSON per unit, and a summary CSV. One unit's bad file is
//! reported in the summary and does not stop the batch.
use crate::blob::build_blob;
use crate::data::positions::{Positions, Role};
use crate::data::recording::Recording;
use crate::diagnose::contract::Contract;
use crate::error::{HostError, Result};
use crate::fit::pipeline::{fit_recording, ModelChoice, ModelKind, Route};
use crate::output::{check_writable, write_atomic, write_json};
use crate::verify::verify;
use firmware_core::compensate::Method;
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;
use serde::Serialize;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};

/// One unit's line of the summary.
#[derive(Debug, Clone)]
pub struct UnitResult {
    /// The recording file.
    pub file: PathBuf,
    /// Unit serial (from the metadata), or the file stem.
    pub unit: String,
    /// `ok` or `error: ...`.
    pub status: String,
    /// max |dg| in the verification positions with the T0 constants, mg.
    pub max_dg_before_mg: Option<f64>,
    /// ... compensated with method 1.
    pub max_dg_after_mg: Option<f64>,
    /// Diagnosis findings (with `--diagnose`).
    pub findings: Vec<String>,
}

/// The per-unit JSON.
#[derive(Serialize)]
struct UnitJson {
    unit: String,
    file: String,
    model: String,
    t_min_c: f64,
    t_max_c: f64,
    f32_departure_g: f64,
    max_abs_dg_mg_uncompensated: Option<f64>,
    max_abs_dg_mg_method1: Option<f64>,
    warnings: usize,
    #[serde(skip_serializing_if = "Option::is_none")]
    diagnosis: Option<Contract>,
}

/// Fit one unit, write its blob and JSON; fills `r`.
fn fit_unit(
    path: &Path,
    out: &Path,
    kind: ModelKind,
    diagnose: bool,
    force: bool,
    r: &mut UnitResult,
) -> Result<()> {
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let rec = Recording::read(path, Positions::default())?;
    if !rec.unit.is_empty() {
        r.unit = rec.unit.clone();
    }
    let choice = ModelChoice {
        kind,
        order: None,
        breakpoints: None,
    };
    let oc = fit_recording(&rec, &choice, Route::Joint)?;
    let cal = oc.fit.calibration(0.1, false);
    let (blob, bytes, dep) = build_blob(&r.unit, &cal)?;
    write_atomic(&out.join(format!("{stem}.blob")), &bytes, force)?;
    let check = |p: usize| rec.positions.has_role(p, Role::Verification);
    if let Some(v) = verify(&rec, &blob, Method::CorrectConstants, &check) {
        if !v.max_by_temperature.is_empty() {
            let worst = |f: &dyn Fn(&crate::verify::TempMax) -> f64| {
                v.max_by_temperature.iter().map(f).fold(0.0, f64::max)
            };
            r.max_dg_before_mg = Some(worst(&|t| t.max_abs_dg_mg_uncompensated));
            r.max_dg_after_mg = Some(worst(&|t| t.max_abs_dg_mg));
        }
    }
    let diagnosis = if diagnose {
        let d = crate::diagnose::diagnose(&rec)?;
        r.findings = d.findings.iter().map(|f| f.effect.clone()).collect();
        Some(d.contract(&rec))
    } else {
        None
    };
    let j = UnitJson {
        unit: r.unit.clone(),
        file: path.display().to_string(),
        model: oc.fit.basis.describe(),
        t_min_c: cal.t_min_c,
        t_max_c: cal.t_max_c,
        f32_departure_g: dep,
        max_abs_dg_mg_uncompensated: r.max_dg_before_mg,
        max_abs_dg_mg_method1: r.max_dg_after_mg,
        warnings: rec.warnings.len(),
        diagnosis,
    };
    write_json(&out.join(format!("{stem}.json")), &j, force)
}

fn one(path: &Path, out: &Path, kind: ModelKind, diagnose: bool, force: bool) -> UnitResult {
    let mut r = UnitResult {
        file: path.to_path_buf(),
        unit: path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default(),
        status: "ok".into(),
        max_dg_before_mg: None,
        max_dg_after_mg: None,
        findings: Vec::new(),
    };
    if let Err(e) = fit_unit(path, out, kind, diagnose, force, &mut r) {
        r.status = format!("error: {e}");
    }
    r
}

/// The `*.csv` files of `dir`, sorted.
fn recordings(dir: &Path) -> Result<Vec<PathBuf>> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(|e| HostError::io(dir, &e))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x.eq_ignore_ascii_case("csv")))
        .collect();
    files.sort();
    if files.is_empty() {
        return Err(HostError::in_file(
            dir,
            "no *.csv recordings in this folder",
        ));
    }
    Ok(files)
}

/// The summary as CSV text.
pub fn summary_csv(results: &[UnitResult]) -> Result<String> {
    let opt = |v: Option<f64>| v.map(|x| format!("{x:.4}")).unwrap_or_default();
    crate::output::csv(
        &[
            "unit",
            "file",
            "status",
            "max_abs_dg_mg_before",
            "max_abs_dg_mg_after",
            "findings",
        ],
        results.iter().map(|r| {
            [
                r.unit.clone(),
                r.file.display().to_string(),
                r.status.clone(),
                opt(r.max_dg_before_mg),
                opt(r.max_dg_after_mg),
                r.findings.join(";"),
            ]
        }),
    )
}

/// Run a batch over every `*.csv` in `dir`; returns the per-unit results (also written
/// as `summary.csv` in `out`).
pub fn run(
    dir: &Path,
    out: &Path,
    jobs: Option<usize>,
    kind: ModelKind,
    diagnose: bool,
    force: bool,
) -> Result<Vec<UnitResult>> {
    let files = recordings(dir)?;
    std::fs::create_dir_all(out).map_err(|e| HostError::io(out, &e))?;
    let summary = out.join("summary.csv");
    check_writable(&summary, force)?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(jobs.unwrap_or(0))
        .build()
        .map_err(|e| HostError::msg(e.to_string()))?;
    let bar = if std::io::stderr().is_terminal() {
        ProgressBar::new(files.len() as u64)
    } else {
        ProgressBar::hidden()
    };
    bar.set_style(
        ProgressStyle::with_template("{pos}/{len} units [{bar:40}] {elapsed_precise} eta {eta}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let results: Vec<UnitResult> = pool.install(|| {
        files
            .par_iter()
            .map(|f| {
                let r = one(f, out, kind, diagnose, force);
                bar.inc(1);
                r
            })
            .collect()
    });
    bar.finish_and_clear();
    write_atomic(&summary, summary_csv(&results)?.as_bytes(), force)?;
    Ok(results)
}
