//! The main job: the paper's experiment on the digital twin, compared by
//! [`crate::analysis`], written to a folder (recording, truth, blobs, summary, report),
//! every model's blob recorded in the folder's record store (`records.sqlite`, appended
//! to when the demo runs again with `--force`); then the plan `host-fit plan` chooses for
//! the same accuracy, run on the same unit, beside it ([`crate::demo_plan`]).
use crate::acceptance::{Acceptance, Spec};
use crate::analysis::{analyse, Compared, DemoOutcome, SummaryRow};
use crate::data::positions::Positions;
use crate::data::recording::Recording;
use crate::demo_plan::{beside, Beside, TargetFrom};
use crate::error::{ErrorKind, HostError, Result};
use crate::fit::select::Selection;
use crate::output::{check_writable, write_atomic, write_json};
use crate::simulate::{simulate, SimConfig, TrueUnit, PAPER_UNIT, PAPER_UNIT_TEMPS};
use crate::store::record::{stamp, AtT0, Command, HashingReader, Record};
use crate::store::Store;
use indicatif::{ProgressBar, ProgressStyle};
use serde::Serialize;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};

/// truth.json: the simulation's configuration and the unit's table.
#[derive(Serialize)]
struct Truth<'a> {
    config: &'a SimConfig,
    unit_table_temps_c: [f64; 5],
    unit_table: [[f64; 12]; 5],
}

/// summary.json.
#[derive(Serialize)]
struct Summary<'a> {
    unit: &'a str,
    seed: u64,
    rows: &'a [SummaryRow],
    chosen_by: &'a Selection,
    spec: Spec,
    acceptance: Vec<ModelAcceptance<'a>>,
    plan: PlanSummary<'a>,
}

/// The plan beside the paper test, in summary.json.
#[derive(Serialize)]
struct PlanSummary<'a> {
    candidates: &'a [crate::plan::Candidate],
    chosen: &'a crate::plan::Candidate,
    paper_predicted_mg: f64,
    target_from: TargetFrom,
    program: &'static str,
    blob: &'static str,
    judged: &'a [crate::demo_plan::Judged; 2],
}

/// One model's verdict in summary.json.
#[derive(Serialize)]
struct ModelAcceptance<'a> {
    model: &'a Compared,
    judged: &'a Acceptance,
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

/// The demo's record store, in its folder.
pub const STORE: &str = "records.sqlite";

/// The chosen plan's program (calibration and verification block, as `plan` writes it).
pub const PLAN_PROGRAM: &str = "plan.csv";
/// The twin's recording of the plan's calibration program.
pub const PLAN_RECORDING: &str = "plan-recording.csv";
/// The twin's recording of the plan's verification block, both blobs judged on it.
pub const PLAN_VERIFICATION: &str = "plan-verification.csv";
/// The plan's blob.
pub const PLAN_BLOB: &str = "plan.blob";

/// The demo's output files in `dir`.
pub fn outputs(dir: &Path) -> Vec<PathBuf> {
    [
        "recording.csv",
        "truth.json",
        Compared::files()[0],
        Compared::files()[1],
        Compared::files()[2],
        PLAN_PROGRAM,
        PLAN_RECORDING,
        PLAN_VERIFICATION,
        PLAN_BLOB,
        "summary.json",
        "report.html",
        STORE,
    ]
    .iter()
    .map(|f| dir.join(f))
    .collect()
}

/// One record per model of the demo: its blob, model, coefficients at T0 and verdict.
fn records(
    oc: &DemoOutcome,
    plan: &Beside,
    rec_path: &Path,
    csv: &str,
    seed: u64,
) -> Result<Vec<Record>> {
    let sha = HashingReader::new(csv.as_bytes())
        .finish()
        .map_err(|e| HostError::io(rec_path, &e))?;
    let mut out = Vec::new();
    // one run: its records share its time
    let started = crate::store::clock::now();
    for m in &oc.models {
        let mut r = Record::new(Command::Demo, None, &oc.recording.unit, rec_path)?;
        r.time_utc.clone_from(&started);
        r.options = serde_json::json!({ "seed": seed, "model": m.model.to_string(), "blob": m.model.file() });
        r.input_sha256 = Some(sha.clone());
        r.output_unit = Some(oc.recording.output_unit.clone());
        r.model = Some(m.model.to_string());
        let cal = m.fit.calibration(0.1, false);
        r.at_t0 = Some(AtT0 {
            t0_c: cal.t0_c,
            values: cal.at_t0(),
            sigma: None,
        });
        r.blob = Some(stamp(&m.blob, r.run_id)?);
        r.worst_dg_mg = m.verifications[0]
            .max_by_temperature
            .iter()
            .map(|t| t.max_abs_dg_mg)
            .reduce(f64::max);
        r.with_verdict(m.acceptance.acceptance, &m.acceptance.reason);
        out.push(r);
    }
    out.push(plan_record(
        oc,
        plan,
        &rec_path.with_file_name(PLAN_RECORDING),
        seed,
        &started,
    )?);
    // the data-chosen model's blob is the unit's calibration: recorded last, it is the
    // one `history` marks as the latest
    out.sort_by_key(|r| r.options["blob"] == "chosen.blob");
    Ok(out)
}

/// The record of the plan's blob: fitted from the plan's recording, judged on the
/// verification block.
fn plan_record(
    oc: &DemoOutcome,
    plan: &Beside,
    path: &Path,
    seed: u64,
    started: &str,
) -> Result<Record> {
    let sha = HashingReader::new(plan.recording_csv.as_bytes())
        .finish()
        .map_err(|e| HostError::io(path, &e))?;
    let j = &plan.judged[1];
    let mut r = Record::new(Command::Demo, None, &oc.recording.unit, path)?;
    r.time_utc = started.to_string();
    r.options = serde_json::json!({
        "seed": seed,
        "model": j.fitted,
        "blob": PLAN_BLOB,
        "plan": plan.candidates[plan.chosen].kind.describe(),
    });
    r.input_sha256 = Some(sha);
    r.output_unit = Some(plan.recording.output_unit.clone());
    r.model = Some(format!("plan ({})", j.fitted));
    r.at_t0 = Some(AtT0 {
        t0_c: plan.calibration.t0_c,
        values: plan.calibration.at_t0(),
        sigma: None,
    });
    r.blob = Some(stamp(&plan.blob, r.run_id)?);
    r.worst_dg_mg = Some(j.worst_mg);
    r.with_verdict(j.acceptance.acceptance, &j.acceptance.reason);
    Ok(r)
}

/// Run the demo into `dir`: the paper test's comparison and the plan beside it.
pub fn run(dir: &Path, seed: u64, force: bool) -> Result<(DemoOutcome, Beside)> {
    std::fs::create_dir_all(dir).map_err(|e| HostError::io(dir, &e))?;
    for f in outputs(dir) {
        check_writable(&f, force)?;
    }
    // opened first: a bad store stops the demo before it writes anything
    let mut store = Store::open(dir.join(STORE))?;
    let cfg = SimConfig {
        seed,
        ..SimConfig::default()
    };
    let b = bar(1000, "simulating the test");
    let sim = simulate(&cfg, |f| b.set_position((f * 1000.0) as u64))?;
    b.finish_and_clear();
    let rec_path = dir.join("recording.csv");
    write_atomic(&rec_path, sim.csv.as_bytes(), force)?;
    let truth = Truth {
        config: &cfg,
        unit_table_temps_c: PAPER_UNIT_TEMPS,
        unit_table: PAPER_UNIT,
    };
    write_json(&dir.join("truth.json"), &truth, force)?;
    let rec = Recording::from_reader(&rec_path, sim.csv.as_bytes(), Positions::default())?;
    let oc = analyse(rec, Some(TrueUnit::new(&cfg)?))?;
    let b = bar(1, "planning beside it");
    let paper = oc
        .models
        .iter()
        .find(|m| matches!(m.model, Compared::Chosen(_)))
        .ok_or_else(|| HostError::new(ErrorKind::Internal, "internal: no data-chosen model"))?;
    let plan = beside(&cfg, &oc.recording, (&paper.blob, &paper.model))?;
    b.finish_and_clear();
    let mut recorded = records(&oc, &plan, &rec_path, &sim.csv, seed)?;
    store.append(&mut recorded)?;
    // each blob as recorded: with its run's id
    for m in &oc.models {
        let blob = recorded
            .iter()
            .find(|r| r.options["blob"] == m.model.file())
            .and_then(|r| r.blob.as_deref())
            .unwrap_or(&m.blob);
        write_atomic(&dir.join(m.model.file()), blob, force)?;
    }
    let plan_blob = recorded
        .iter()
        .find(|r| r.options["blob"] == PLAN_BLOB)
        .and_then(|r| r.blob.as_deref())
        .unwrap_or(&plan.blob);
    write_atomic(&dir.join(PLAN_BLOB), plan_blob, force)?;
    for (f, text) in [
        (PLAN_PROGRAM, &plan.program_csv),
        (PLAN_RECORDING, &plan.recording_csv),
        (PLAN_VERIFICATION, &plan.verification_csv),
    ] {
        write_atomic(&dir.join(f), text.as_bytes(), force)?;
    }
    let summary = Summary {
        unit: &oc.recording.unit,
        seed,
        rows: &oc.rows,
        chosen_by: &oc.selection,
        spec: oc.spec,
        acceptance: oc
            .models
            .iter()
            .map(|m| ModelAcceptance {
                model: &m.model,
                judged: &m.acceptance,
            })
            .collect(),
        plan: PlanSummary {
            candidates: &plan.candidates,
            chosen: &plan.candidates[plan.chosen],
            paper_predicted_mg: plan.paper_predicted_mg,
            target_from: plan.target_from,
            program: PLAN_PROGRAM,
            blob: PLAN_BLOB,
            judged: &plan.judged,
        },
    };
    write_json(&dir.join("summary.json"), &summary, force)?;
    let report = crate::report::demo::demo_report(&oc)?;
    write_atomic(&dir.join("report.html"), report.as_bytes(), force)?;
    Ok((oc, plan))
}
