//! Production batches: fit (and optionally diagnose) every recording in a folder in
//! parallel, one blob and one JSON per unit, and a summary CSV. One unit's bad file is
//! reported in the summary and does not stop the batch.
use crate::calib::build_blob;
use crate::cli::{fit_recording, ModelKind, Route};
use crate::error::{HostError, Result};
use crate::io::{check_writable, write_atomic};
use crate::positions::Positions;
use crate::recording::Recording;
use crate::verify::verify;
use firmware_core::compensate::Method;
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;
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

fn one(path: &Path, out: &Path, kind: ModelKind, diagnose: bool, force: bool) -> UnitResult {
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let mut r = UnitResult {
        file: path.to_path_buf(),
        unit: stem.clone(),
        status: "ok".into(),
        max_dg_before_mg: None,
        max_dg_after_mg: None,
        findings: Vec::new(),
    };
    let res = (|| -> Result<()> {
        let rec = Recording::read(path, Positions::default())?;
        if !rec.unit.is_empty() {
            r.unit = rec.unit.clone();
        }
        let pp: Vec<bool> = (0..rec.positions.list.len())
            .map(|i| rec.positions.name(i).starts_with("PP"))
            .collect();
        let is_pp = |p: usize| pp.get(p).copied().unwrap_or(false);
        let fit_sel = |p: usize| !is_pp(p);
        let oc = fit_recording(&rec, &fit_sel, kind, None, None, Route::Joint)?;
        let cal = oc.fit.calibration(0.1, false);
        let (blob, bytes, dep) = build_blob(&r.unit, &cal)?;
        write_atomic(&out.join(format!("{stem}.blob")), &bytes, force)?;
        if let Some(v) = verify(&rec, &blob, Method::CorrectConstants, &is_pp) {
            if !v.max_by_temperature.is_empty() {
                r.max_dg_before_mg = Some(
                    v.max_by_temperature
                        .iter()
                        .map(|t| t.max_abs_dg_mg_uncompensated)
                        .fold(0.0, f64::max),
                );
                r.max_dg_after_mg = Some(
                    v.max_by_temperature
                        .iter()
                        .map(|t| t.max_abs_dg_mg)
                        .fold(0.0, f64::max),
                );
            }
        }
        let mut j = serde_json::json!({
            "unit": r.unit, "file": path.display().to_string(), "model": oc.fit.basis.describe(),
            "t_min_c": cal.t_min_c, "t_max_c": cal.t_max_c, "f32_departure_g": dep,
            "max_abs_dg_mg_uncompensated": r.max_dg_before_mg, "max_abs_dg_mg_method1": r.max_dg_after_mg,
            "warnings": rec.warnings.len(),
        });
        if diagnose {
            let d = crate::diagnose::diagnose(&rec)?;
            r.findings = d.findings.iter().map(|f| f.effect.clone()).collect();
            j["diagnosis"] = d.json(&rec);
        }
        write_atomic(
            &out.join(format!("{stem}.json")),
            serde_json::to_string_pretty(&j)
                .unwrap_or_default()
                .as_bytes(),
            force,
        )
    })();
    if let Err(e) = res {
        r.status = format!("error: {e}");
    }
    r
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
    let mut csv =
        String::from("unit,file,status,max_abs_dg_mg_before,max_abs_dg_mg_after,findings\n");
    let opt = |v: Option<f64>| v.map(|x| format!("{x:.4}")).unwrap_or_default();
    for r in &results {
        let status = r.status.replace(['"', '\n'], " ");
        csv.push_str(&format!(
            "{},{},\"{}\",{},{},{}\n",
            r.unit,
            r.file.display(),
            status,
            opt(r.max_dg_before_mg),
            opt(r.max_dg_after_mg),
            r.findings.join(";")
        ));
    }
    write_atomic(&summary, csv.as_bytes(), force)?;
    Ok(results)
}
