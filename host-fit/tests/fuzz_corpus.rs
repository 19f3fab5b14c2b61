//! The host's fuzz corpus replayed on the ordinary build: every input kept in
//! `fuzz/corpus/recording/` and `fuzz/corpus/positions/` (the seeds and every crash
//! found and fixed) through the properties the fuzz targets hold
//! (`host_fit::fuzzing`), on every test run: the default tier fuzzes only the
//! firmware's targets, the full tier all four.
use std::path::PathBuf;

fn corpus(target: &str) -> Vec<(PathBuf, Vec<u8>)> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../fuzz/corpus")
        .join(target);
    let mut out: Vec<(PathBuf, Vec<u8>)> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.is_file())
        .map(|p| {
            let bytes = std::fs::read(&p).unwrap();
            (p, bytes)
        })
        .collect();
    out.sort();
    out
}

/// Replays `target`'s corpus through `check`; the file of a failing input is named.
fn replay(target: &str, check: fn(&[u8])) {
    let inputs = corpus(target);
    // the seeds and the regressions are there (a moved corpus replays nothing)
    assert!(inputs.len() >= 3, "{target}: {} inputs", inputs.len());
    for (path, bytes) in inputs {
        let r = std::panic::catch_unwind(|| check(&bytes));
        assert!(r.is_ok(), "{}: the property failed", path.display());
    }
}

#[test]
fn the_recording_corpus_holds() {
    replay("recording", host_fit::fuzzing::recording);
}

#[test]
fn the_positions_corpus_holds() {
    replay("positions", host_fit::fuzzing::positions);
}
