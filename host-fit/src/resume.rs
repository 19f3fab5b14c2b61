//! A batch run again after a crash (a station's power cut, `kill -9`) picks up where it
//! stopped: the units its store already holds a whole record of (this lot, `batch`, the
//! same recording file with the same SHA-256, not an `error`) are kept as recorded, not
//! recomputed (a missing blob or test record file is written again from the store, bit
//! for bit); the others are done, over the files the crashed run left of them where
//! those were never recorded (a blob whose run id no record holds: never issued); the
//! summary and the lot's statistics cover every unit. Without a store nothing is
//! known of the earlier run: its files are refused as ever without `--force`.
use crate::batch::{test_record_path, UnitResult, UnitStatus};
use crate::diagnose::EffectId;
use crate::error::{HostError, Result};
use crate::output::write_atomic;
use crate::store::record::{blob_run_id, sha256_file, Command, Record};
use crate::store::{Filter, Store};
use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};

/// What the store already holds of a lot.
#[derive(Debug, Default)]
pub struct Prior {
    /// The newest whole record of each recording file (as the batch names it).
    pub recorded: HashMap<String, Record>,
    /// Units whose files in the output folder a crashed run left unrecorded.
    pub orphans: HashSet<PathBuf>,
}

/// What the store holds of `lot` for the recordings `files` written into `out`.
pub fn prior(store: &mut Store, lot: &str, files: &[PathBuf], out: &Path) -> Result<Prior> {
    let f = Filter {
        lot: Some(lot.to_string()),
        command: Some(Command::Batch),
        ..Filter::default()
    };
    let mut recorded = HashMap::new();
    for r in store.records(&f)? {
        let whole = r.blob.is_some()
            && r.judged
                .as_ref()
                .is_some_and(|j| j.verdict != UnitStatus::Error);
        if whole {
            // oldest first: a later record of the same file wins
            recorded.insert(r.input.clone(), r);
        }
    }
    let mut orphans = HashSet::new();
    for f in files {
        if recorded.contains_key(&f.display().to_string()) {
            continue;
        }
        let blob = out.join(format!("{}.blob", stem(f)));
        let Ok(bytes) = std::fs::read(&blob) else {
            continue;
        };
        // a blob of ours whose run no record holds: made by a run that died before
        // recording it, never issued
        if let Some(id) = blob_run_id(&bytes) {
            if store.record(id)?.is_none() {
                orphans.insert(f.clone());
            }
        }
    }
    Ok(Prior { recorded, orphans })
}

fn stem(p: &Path) -> String {
    p.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// The record of `path` the store already holds, if its recording is still the one
/// recorded (same SHA-256).
pub fn recorded_for<'a>(prior: &'a Prior, path: &Path) -> Option<&'a Record> {
    let r = prior.recorded.get(&path.display().to_string())?;
    let sha = sha256_file(path).ok()?;
    (r.input_sha256.as_deref() == Some(sha.as_str())).then_some(r)
}

/// A unit kept as recorded: its line of the summary from its record, its blob and test
/// record files written again from the store if they are missing.
pub fn kept(path: &Path, out: &Path, r: &Record) -> Result<UnitResult> {
    let s = stem(path);
    let blob = out.join(format!("{s}.blob"));
    if let (false, Some(b)) = (blob.exists(), &r.blob) {
        write_atomic(&blob, b, false)?;
    }
    let tr = test_record_path(out, &s);
    if let (false, Some(t)) = (tr.exists(), &r.test_record) {
        let text = serde_json::to_string_pretty(t)
            .map_err(|e| HostError::msg(format!("cannot encode the test record: {e}")))?;
        write_atomic(&tr, format!("{text}\n").as_bytes(), false)?;
    }
    let judged = r.judged.as_ref();
    // the uncompensated |dg| is in the test record's verify phase
    let uncompensated = r.test_record.as_ref().and_then(|t| {
        t["phases"]
            .as_array()?
            .iter()
            .find(|p| p["name"] == "verify")?["measurements"]["worst_dg_uncompensated_mg"]
            ["measured_value"]
            .as_f64()
    });
    let findings = r
        .findings
        .as_ref()
        .and_then(|f| f.as_array())
        .map(|a| {
            a.iter()
                .filter_map(|f| f["effect"].as_str().and_then(EffectId::parse))
                .collect()
        })
        .unwrap_or_default();
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
