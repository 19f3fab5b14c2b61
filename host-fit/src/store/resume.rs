//! What the store holds of a batch's lot, for a batch run again after a crash (a station's power cut, `kill -9`) picks up where it
//! stopped: the units its store already holds a whole record of (this lot, `batch`, the
//! same recording file with the same SHA-256, not an `error`) are kept as recorded, not
//! recomputed (a missing blob or test record file is written again from the store, bit
//! for bit); the others are done, over the files the crashed run left of them where
//! those were never recorded (a blob whose run id no record holds: never issued); the
//! summary and the lot's statistics cover every unit. Without a store nothing is
//! known of the earlier run: its files are refused as ever without `--force`.
use super::db::{Filter, Store};
use super::record::{blob_run_id, sha256_file, Command, Record};
use crate::error::{ErrorKind, HostError, Result};
use crate::output::write_atomic;
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
        // a whole record: it made a blob and did not end in an error
        if r.is_calibration() && r.judged.is_some() {
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

/// Write again, from the store, a kept unit's blob and test record files that are
/// missing from `out` (bit for bit).
pub fn restore_files(path: &Path, out: &Path, r: &Record) -> Result<()> {
    let s = stem(path);
    let blob = out.join(format!("{s}.blob"));
    if let (false, Some(b)) = (blob.exists(), &r.blob) {
        write_atomic(&blob, b, false)?;
    }
    let tr = super::test_record::path(out, &s);
    if let (false, Some(t)) = (tr.exists(), &r.test_record) {
        let text = serde_json::to_string_pretty(t).map_err(|e| {
            HostError::new(
                ErrorKind::Internal,
                format!("cannot encode the test record: {e}"),
            )
        })?;
        write_atomic(&tr, format!("{text}\n").as_bytes(), false)?;
    }
    Ok(())
}
