//! Production batches: fit (and optionally diagnose) every recording in a folder in
//! parallel, one blob and one JSON per unit, each unit judged against the acceptance
//! specification on its verification dwells, `summary.csv` (one line per unit:
//! acceptance `pass`, `fail`, `not_judged` or `error`, and why) and the lot's statistics (`lot.csv`:
//! every coefficient's distribution over the units, and the units far from the lot by a
//! robust z-score). One unit's bad file is reported and does not stop the batch. With a
//! record store every unit's run is recorded (an error too), in chunks of
//! [`RECORD_CHUNK`] units, one transaction each.
use crate::acceptance::{judge, Acceptance, Spec, Verdict};
use crate::blob::{build_blob_with_terms, singular_k};
use crate::data::positions::{Positions, Role};
use crate::data::recording::Recording;
use crate::diagnose::contract::Contract;
use crate::diagnose::EffectId;
use crate::error::{ErrorKind, HostError, Result};
use crate::fit::pipeline::{ModelKind, ModelRequest};
use crate::fit::predict::Uncertain;
use crate::fit::route::{fit_on, Flash, Routed};
use crate::fit::select::Selection;
use crate::fit::temperature::span;
use crate::output::{check_writable, write_atomic, write_json};
use crate::store::record::{sha256_file, stamp, AtT0, Command as Recorded, HashingReader, Record};
use crate::store::resume::Prior;
use crate::store::{test_record, Store, Target};
use crate::verify::{verify, TempMax};
use firmware_core::compensate::Method;
use firmware_core::model::COEFF_NAMES;
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;
use serde::Serialize;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};

/// A unit is far from the lot when one of its coefficients lies more than this many
/// robust standard deviations (1.4826 MAD) from the lot's median.
pub const OUTLIER_Z: f64 = 3.5;

/// Units recorded in one transaction of the record store.
pub const RECORD_CHUNK: usize = 64;

/// How a unit of the batch ended (the store's acceptance verdict: one set).
pub use crate::store::record::UnitStatus;

/// One unit's line of the summary.
#[derive(Debug, Clone)]
pub struct UnitResult {
    /// The recording file.
    pub file: PathBuf,
    /// Unit serial (from the metadata), or the file stem.
    pub unit: String,
    /// Pass, fail or error.
    pub acceptance: UnitStatus,
    /// Why (the acceptance's reason, or the error).
    pub reason: String,
    /// The model in the blob.
    pub model: String,
    /// max |dg| in the verification positions with the T0 constants, mg.
    pub max_dg_before_mg: Option<f64>,
    /// ... compensated with method 1 by the unit's blob.
    pub max_dg_after_mg: Option<f64>,
    /// Diagnosis findings (with `--diagnose`).
    pub findings: Vec<EffectId>,
    /// The 12 coefficients at T0 of the unit's blob (for the lot statistics).
    pub at_t0: Option<[f64; 12]>,
    /// Their 1-sigma from the model the blob carries (the chosen fit's, or with
    /// `--diagnose` the diagnosed model's; zeros when unknown).
    pub at_t0_sigma: [f64; 12],
    /// The coefficients far from the lot, with their robust z-scores.
    pub outlier: Vec<(&'static str, f64)>,
    /// The unit's record (with a record store).
    pub record: Option<Record>,
}

/// What a batch does with every unit.
#[derive(Debug, Clone)]
pub struct BatchOptions {
    /// Parallel jobs (None: one per core).
    pub jobs: Option<usize>,
    /// The temperature model's family (None: chosen by the data per unit; the order or
    /// breakpoints are chosen by the data within a family given).
    pub model: Option<ModelKind>,
    /// The acceptance specification.
    pub spec: Spec,
    /// Diagnose every unit, and take its blob from the diagnosed model.
    pub diagnose: bool,
    /// Overwrite outputs of an earlier run.
    pub force: bool,
    /// The positions every recording is read with (built in, or a lab's own file with
    /// its roles).
    pub positions: Positions,
    /// Record every unit in this store.
    pub store: Option<Target>,
    /// The checks at the door every unit's data are let past (each then a warning).
    pub allow: Vec<crate::data::door::Check>,
}

/// The per-unit JSON.
#[derive(Serialize)]
struct UnitJson<'a> {
    unit: &'a str,
    file: String,
    model: &'a str,
    #[serde(skip_serializing_if = "Option::is_none")]
    chosen_by: Option<&'a Selection>,
    t_min_c: f64,
    t_max_c: f64,
    f32_departure_g: f64,
    max_abs_dg_mg_uncompensated: Option<f64>,
    max_abs_dg_mg_method1: Option<f64>,
    #[serde(flatten)]
    acceptance: &'a Acceptance,
    warnings: usize,
    /// Why the route `fit` would first try was not kept (a settling seen, no lag kept).
    #[serde(skip_serializing_if = "<[String]>::is_empty")]
    route_notes: &'a [String],
    /// Positions missing at a stop, each named with the stop (also counted in
    /// `warnings`).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    missing_positions: Vec<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    diagnosis: Option<Contract>,
}

/// A unit's model for its blob: the calibration, the diagnosis when the batch diagnoses,
/// and the discovered terms of the unit's state the blob's term table carries.
struct UnitModel {
    cal: firmware_core::temperature::Calibration<f64>,
    diagnosis: Option<Contract>,
    terms: Vec<crate::terms::AxisTerm>,
}

/// The blob's model of one unit (and its diagnosis when the batch diagnoses); fills the
/// unit's model and uncertainty, the route's notes and the static route's selection.
fn unit_model(
    rec: &Recording,
    o: &BatchOptions,
    r: &mut UnitResult,
    notes: &mut Vec<String>,
    selection: &mut Option<Selection>,
) -> Result<UnitModel> {
    let req = ModelRequest {
        kind: o.model,
        order: None,
        breakpoints: None,
    };
    // the blob's model, and its own uncertainty for the lot's statistics
    Ok(if o.diagnose {
        // the static fit still checks the data (its errors are the unit's); the route
        // choice is not run, the diagnosed model makes the blob
        crate::fit::pipeline::fit_chosen(rec, &req)?;
        // the diagnosis needs every pose's vector: estimate those of unknown orientation
        let oriented = crate::fit::pipeline::with_orientations(rec, None)?;
        let d = crate::diagnose::diagnose(&oriented.rec)?;
        r.findings = d.findings.iter().map(|f| f.effect).collect();
        let names: Vec<&str> = r.findings.iter().map(|e| e.as_str()).collect();
        r.model = if names.is_empty() {
            "diagnosed (no findings)".to_string()
        } else {
            format!("diagnosed ({})", names.join("+"))
        };
        r.at_t0_sigma = d.coefficient_sigma(rec.t0_c);
        UnitModel {
            cal: d.calibration(rec.t0_c)?,
            diagnosis: Some(d.contract()),
            terms: d.terms()?,
        }
    } else {
        let routed = fit_on(rec, None, &req, notes)?;
        r.model = match &routed {
            Routed::Identified { outcome, .. } => {
                *selection = outcome.selection.clone();
                routed.describe()
            }
            Routed::Dynamic { .. } => format!("{} (dynamic route)", routed.describe()),
        };
        r.at_t0_sigma = routed.coefficient_sigma(rec.t0_c);
        UnitModel {
            cal: routed.calibration(rec, Flash::default())?.cal,
            diagnosis: None,
            terms: Vec::new(),
        }
    })
}

/// Fit one unit, write its blob, JSON and test record (over files of an earlier run
/// when `force`); fills `r`.
fn fit_unit(
    path: &Path,
    out: &Path,
    o: &BatchOptions,
    force: bool,
    r: &mut UnitResult,
) -> Result<()> {
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    // read once: for the recording and for its SHA-256
    let file = std::fs::File::open(path).map_err(|e| HostError::io(path, &e))?;
    let mut input = HashingReader::new(file);
    let mut rec = Recording::from_reader(path, &mut input, o.positions.clone())?;
    crate::data::door::admit(&mut rec, &crate::data::door::Check::ALL, &o.allow)?;
    let missing: Vec<String> = crate::fit::coverage::missing(&rec)
        .iter()
        .map(|m| m.text())
        .collect();
    rec.warnings.extend(missing.iter().cloned());
    let sha = input.finish().map_err(|e| HostError::io(path, &e))?;
    if !rec.unit.is_empty() {
        r.unit = rec.unit.clone();
    }
    let mut notes = Vec::new();
    let mut selection = None;
    let UnitModel {
        cal,
        diagnosis,
        terms,
    } = unit_model(&rec, o, r, &mut notes, &mut selection)?;
    r.at_t0 = Some(cal.at_t0());
    let (blob, mut bytes, (dep, _)) =
        build_blob_with_terms(&r.unit, &rec.output_unit, &cal, &terms)?;
    if let Some(t) = &o.store {
        let mut rc = t.record(Recorded::Batch, &r.unit, path)?;
        rc.input_sha256 = Some(sha);
        rc.output_unit = Some(rec.output_unit.clone());
        rc.model = Some(r.model.clone());
        rc.at_t0 = Some(AtT0 {
            t0_c: cal.t0_c,
            values: cal.at_t0(),
            sigma: Some(r.at_t0_sigma),
        });
        if let Some(d) = &diagnosis {
            rc.with_diagnosis(d)?;
        }
        // the blob carries its run's id: a unit in the field leads back to this record
        bytes = stamp(&bytes, rc.run_id)?;
        rc.blob = Some(bytes.clone());
        r.record = Some(rc);
    }
    write_atomic(&out.join(format!("{stem}.blob")), &bytes, force)?;
    let check = |p: usize| rec.positions.has_role(p, Role::Verification);
    let v =
        verify(&rec, &blob, Method::CorrectConstants, &check).ok_or_else(|| singular_k(path))?;
    let worst = |f: &dyn Fn(&TempMax) -> f64| {
        (!v.max_by_temperature.is_empty())
            .then(|| v.max_by_temperature.iter().map(f).fold(0.0, f64::max))
    };
    r.max_dg_before_mg = worst(&|t| t.max_abs_dg_mg_uncompensated);
    r.max_dg_after_mg = worst(&|t| t.max_abs_dg_mg);
    let acc = judge(&v, &o.spec, cal.t0_c, (cal.t_min_c, cal.t_max_c));
    r.acceptance = acc.acceptance.into();
    r.reason = acc.reason.clone();
    if let Some(rc) = &mut r.record {
        rc.worst_dg_mg = r.max_dg_after_mg;
        rc.with_verdict(acc.acceptance, &acc.reason);
    }
    let j = UnitJson {
        unit: &r.unit,
        file: path.display().to_string(),
        model: &r.model,
        chosen_by: selection.as_ref(),
        route_notes: &notes,
        t_min_c: cal.t_min_c,
        t_max_c: cal.t_max_c,
        f32_departure_g: dep,
        max_abs_dg_mg_uncompensated: r.max_dg_before_mg,
        max_abs_dg_mg_method1: r.max_dg_after_mg,
        acceptance: &acc,
        warnings: rec.warnings.len(),
        missing_positions: missing,
        diagnosis,
    };
    write_json(&out.join(format!("{stem}.json")), &j, force)?;
    let reason = r.reason.clone();
    let unit = test_record::Unit {
        acceptance: Some(&acc),
        status: r.acceptance,
        reason: &reason,
        uncompensated_mg: r.max_dg_before_mg,
    };
    write_test_record(out, &stem, r, o, &unit, force)
}

/// The unit's test record: built from its store record (a bare one without a store),
/// kept in it, and written beside the blob as `UNIT.test-record.json`.
fn write_test_record(
    out: &Path,
    stem: &str,
    r: &mut UnitResult,
    o: &BatchOptions,
    unit: &test_record::Unit<'_>,
    force: bool,
) -> Result<()> {
    let bare;
    let rc = match &r.record {
        Some(rc) => rc,
        None => {
            let t = o
                .store
                .clone()
                .unwrap_or_else(|| Target::new(PathBuf::new()));
            bare = t.record(Recorded::Batch, &r.unit, &r.file)?;
            &bare
        }
    };
    let tr = test_record::build(rc, unit);
    if let Some(rc) = &mut r.record {
        rc.test_record = Some(tr.clone());
    }
    write_json(&test_record::path(out, stem), &tr, force)
}

/// A unit kept as an earlier run of the batch recorded it (see
/// [`crate::store::resume`]): its line of the summary from its record, its blob and test
/// record files written again from the store if they are missing.
fn kept(path: &Path, out: &Path, r: &Record) -> Result<UnitResult> {
    crate::store::resume::restore_files(path, out, r)?;
    let judged = r.judged.as_ref();
    // the uncompensated |dg| is in the test record's verify phase
    let uncompensated = r
        .test_record
        .as_ref()
        .and_then(test_record::TestRecord::uncompensated_mg);
    let findings = r.finding_effects()?;
    Ok(UnitResult {
        file: path.to_path_buf(),
        unit: r.serial.clone(),
        acceptance: judged.map_or(UnitStatus::NotJudged, |j| j.verdict),
        reason: judged.map(|j| j.reason.clone()).unwrap_or_default(),
        model: r.model.clone().unwrap_or_default(),
        max_dg_before_mg: uncompensated,
        max_dg_after_mg: r.worst_dg_mg,
        findings,
        at_t0: r.at_t0.map(|a| a.values),
        at_t0_sigma: r.at_t0.and_then(|a| a.sigma).unwrap_or([0.0; 12]),
        outlier: Vec::new(),
        record: None,
    })
}

fn one(path: &Path, out: &Path, o: &BatchOptions, force: bool) -> UnitResult {
    let mut r = UnitResult {
        file: path.to_path_buf(),
        unit: path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default(),
        acceptance: UnitStatus::Error,
        reason: String::new(),
        model: String::new(),
        max_dg_before_mg: None,
        max_dg_after_mg: None,
        findings: Vec::new(),
        at_t0: None,
        at_t0_sigma: [0.0; 12],
        outlier: Vec::new(),
        record: None,
    };
    if let Err(e) = fit_unit(path, out, o, force, &mut r) {
        r.acceptance = UnitStatus::Error;
        r.reason = e.to_string();
        if let Some(t) = &o.store {
            let begun = r.record.take();
            r.record = error_record(t, path, &r, begun);
            if let Some(rc) = &mut r.record {
                let unit = test_record::Unit {
                    acceptance: None,
                    status: UnitStatus::Error,
                    reason: &r.reason,
                    uncompensated_mg: None,
                };
                rc.test_record = Some(test_record::build(rc, &unit));
            }
        }
    }
    r
}

/// The record of a unit that could not be processed: the record begun (its blob, if it
/// was made), or a new one with the file's SHA-256 where it can be read.
fn error_record(t: &Target, path: &Path, r: &UnitResult, begun: Option<Record>) -> Option<Record> {
    let mut rc = match begun {
        Some(rc) => rc,
        None => {
            let mut rc = t.record(Recorded::Batch, &r.unit, path).ok()?;
            rc.input_sha256 = sha256_file(path).ok();
            rc
        }
    };
    rc.with_verdict(UnitStatus::Error, &r.reason);
    Some(rc)
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
            ErrorKind::Insufficient,
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
            "acceptance",
            "reason",
            "model",
            "max_abs_dg_mg_before",
            "max_abs_dg_mg_after",
            "far_from_lot",
            "findings",
        ],
        results.iter().map(|r| {
            [
                r.unit.clone(),
                r.file.display().to_string(),
                r.acceptance.name().to_string(),
                r.reason.clone(),
                r.model.clone(),
                opt(r.max_dg_before_mg),
                opt(r.max_dg_after_mg),
                r.outlier
                    .iter()
                    .map(|(c, z)| format!("{c} z={z:.1}"))
                    .collect::<Vec<_>>()
                    .join(";"),
                r.findings
                    .iter()
                    .map(|e| e.as_str())
                    .collect::<Vec<_>>()
                    .join(";"),
            ]
        }),
    )
}

/// One coefficient's distribution over the lot.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct LotCoefficient {
    /// Coefficient name.
    pub coefficient: &'static str,
    /// Units with a fit.
    pub units: usize,
    /// Median.
    pub median: f64,
    /// 1.4826 x the median absolute deviation (the standard deviation of a normal lot),
    /// at least the median of the units' own 1-sigma of the coefficient.
    pub robust_sigma: f64,
    /// Smallest.
    pub min: f64,
    /// Largest.
    pub max: f64,
    /// Units more than [`OUTLIER_Z`] robust sigmas from the median.
    pub far: usize,
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    match n {
        0 => f64::NAN,
        _ if n % 2 == 1 => v[n / 2],
        _ => 0.5 * (v[n / 2 - 1] + v[n / 2]),
    }
}

/// The lot statistics of the coefficients at T0, marking the units far from the lot.
pub fn lot(results: &mut [UnitResult]) -> Vec<LotCoefficient> {
    let mut out = Vec::new();
    for (c, name) in COEFF_NAMES.iter().enumerate() {
        let vals: Vec<f64> = results
            .iter()
            .filter_map(|r| r.at_t0.map(|a| a[c]))
            .collect();
        if vals.is_empty() {
            continue;
        }
        let med = median(&mut vals.clone());
        let mut dev: Vec<f64> = vals.iter().map(|v| (v - med).abs()).collect();
        let mut own: Vec<f64> = results
            .iter()
            .filter(|r| r.at_t0.is_some())
            .map(|r| r.at_t0_sigma[c])
            .collect();
        // a small lot's MAD can come out far below the spread its units' own
        // measurement uncertainty alone makes: never take the lot tighter than that
        let sigma = (1.4826 * median(&mut dev)).max(median(&mut own));
        let mut far = 0;
        for r in results.iter_mut() {
            let Some(v) = r.at_t0.map(|a| a[c]) else {
                continue;
            };
            let z = (v - med) / sigma;
            // with fewer than 5 units, or a lot of identical units, no one is "far"
            if vals.len() >= 5 && sigma > 0.0 && z.abs() > OUTLIER_Z {
                r.outlier.push((name, z));
                far += 1;
            }
        }
        let (min, max) = span(&vals);
        out.push(LotCoefficient {
            coefficient: name,
            units: vals.len(),
            median: med,
            robust_sigma: sigma,
            min,
            max,
            far,
        });
    }
    out
}

/// The lot statistics as CSV text.
pub fn lot_csv(lot: &[LotCoefficient]) -> Result<String> {
    crate::output::csv(
        &[
            "coefficient",
            "units",
            "median",
            "robust_sigma",
            "min",
            "max",
            "far_from_lot",
        ],
        lot.iter().map(|l| {
            [
                l.coefficient.to_string(),
                l.units.to_string(),
                format!("{:.9e}", l.median),
                format!("{:.3e}", l.robust_sigma),
                format!("{:.9e}", l.min),
                format!("{:.9e}", l.max),
                l.far.to_string(),
            ]
        }),
    )
}

/// What a batch produced.
pub struct BatchOutcome {
    /// Per unit.
    pub units: Vec<UnitResult>,
    /// The lot's coefficients.
    pub lot: Vec<LotCoefficient>,
    /// Records written to the store.
    pub recorded: Option<usize>,
    /// Units kept as an earlier run recorded them (a batch resumed after a crash).
    pub resumed: usize,
}

impl BatchOutcome {
    /// Whether every unit passed.
    pub fn all_pass(&self) -> bool {
        self.units.iter().all(|u| u.acceptance == UnitStatus::Pass)
    }

    /// The batch's verdict: `Fail` when a unit failed or errored, else `NotJudged` when
    /// a unit was not judged, else `Pass`.
    pub fn verdict(&self) -> Verdict {
        let any = |s: UnitStatus| self.units.iter().any(|u| u.acceptance == s);
        if any(UnitStatus::Fail) || any(UnitStatus::Error) {
            Verdict::Fail
        } else if any(UnitStatus::NotJudged) {
            Verdict::NotJudged
        } else {
            Verdict::Pass
        }
    }
}

/// The store's writer and what it already holds of the lot (nothing with `--force`: the
/// lot is done again). Opened before any unit is processed: a bad store stops the batch
/// before it starts.
fn open_store(
    o: &BatchOptions,
    files: &[PathBuf],
    out: &Path,
) -> Result<(Option<crate::store::Writer>, Prior)> {
    let Some(t) = &o.store else {
        return Ok((None, Prior::default()));
    };
    let mut store = Store::open(&t.db)?;
    let prior = match (&t.lot, o.force) {
        (Some(lot), false) => crate::store::resume::prior(&mut store, lot, files, out)?,
        _ => Prior::default(),
    };
    Ok((Some(store.writer(RECORD_CHUNK)), prior))
}

/// Run a batch over every `*.csv` in `dir`; writes `summary.csv` and `lot.csv` in `out`.
/// Run again after a crash, it resumes (see [`crate::store::resume`]).
pub fn run(dir: &Path, out: &Path, o: &BatchOptions) -> Result<BatchOutcome> {
    let files = recordings(dir)?;
    let summary = out.join("summary.csv");
    let lot_path = out.join("lot.csv");
    // an output folder made for a batch that cannot start is taken away again
    let made = !out.exists();
    let opened = std::fs::create_dir_all(out)
        .map_err(|e| HostError::io(out, &e))
        .and_then(|_| check_writable(&summary, o.force))
        .and_then(|_| check_writable(&lot_path, o.force))
        .and_then(|_| open_store(o, &files, out));
    let (writer, prior) = match opened {
        Ok(v) => v,
        Err(e) => {
            if made {
                let _ = std::fs::remove_dir(out);
            }
            return Err(e);
        }
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(o.jobs.unwrap_or(0))
        .build()
        .map_err(|e| HostError::new(ErrorKind::Io, e.to_string()))?;
    let bar = if std::io::stderr().is_terminal() {
        ProgressBar::new(files.len() as u64)
    } else {
        ProgressBar::hidden()
    };
    bar.set_style(
        ProgressStyle::with_template("{pos}/{len} units [{bar:40}] {elapsed_precise} eta {eta}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let mut units: Vec<UnitResult> = pool.install(|| {
        files
            .par_iter()
            .map(|f| {
                let r = match crate::store::resume::recorded_for(&prior, f) {
                    Some(rc) => kept(f, out, rc).unwrap_or_else(|e| {
                        let mut r = one(f, out, o, o.force);
                        r.reason = format!("{} (kept record unreadable: {e})", r.reason);
                        r
                    }),
                    None => one(f, out, o, o.force || prior.orphans.contains(f)),
                };
                if let (Some(w), Some(rc)) = (&writer, &r.record) {
                    w.send(rc.clone());
                }
                bar.inc(1);
                r
            })
            .collect()
    });
    bar.finish_and_clear();
    let recorded = writer.map(|w| w.finish()).transpose()?;
    let lot = lot(&mut units);
    write_atomic(&summary, summary_csv(&units)?.as_bytes(), o.force)?;
    write_atomic(&lot_path, lot_csv(&lot)?.as_bytes(), o.force)?;
    let resumed = units.iter().filter(|u| u.record.is_none()).count();
    Ok(BatchOutcome {
        resumed: if recorded.is_some() { resumed } else { 0 },
        units,
        lot,
        recorded,
    })
}
