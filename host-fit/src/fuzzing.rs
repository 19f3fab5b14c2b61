//! What the fuzz targets of the host's readers hold, as functions: `fuzz/` calls them
//! on libFuzzer's inputs (`cargo xtask fuzz`), and the tests replay every input kept in
//! `fuzz/corpus/` through them on the ordinary build, so the readers' properties are
//! checked on every test run without the fuzzer's instrumented build.
use crate::data::positions::Positions;
use crate::data::recording::Recording;
use std::path::Path;

/// Any bytes as a recording: an error or a recording, never a panic; whatever reads
/// also gets through the noise estimate, the stops and their identification. Panics
/// (the fuzzer's finding) where a property fails.
pub fn recording(data: &[u8]) {
    if let Ok(rec) = Recording::from_reader(Path::new("fuzz.csv"), data, Positions::default()) {
        let nz = crate::fit::noise::noise(&rec);
        assert!(nz.sigma.iter().all(|s| s.is_finite()));
        let all = |_: usize| true;
        for st in crate::data::stops::stops(&rec, &all, 3.0) {
            let _ = crate::fit::identify::identify_stop(&rec, &st, &nz);
        }
    }
}

/// Any text as a positions file: an error or positions, never a panic; every position
/// is a unit vector, or of unknown orientation (all three fields empty) with an all-NaN
/// vector that can never pass for data. Panics where a property fails.
pub fn positions(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok((p, _)) = Positions::parse(Path::new("fuzz.csv"), text) {
        for pos in &p.list {
            if pos.known {
                let n = pos.a.iter().map(|v| v * v).sum::<f64>().sqrt();
                assert!((n - 1.0).abs() < 1e-9, "{} has length {n}", pos.name);
            } else {
                assert!(
                    pos.a.iter().all(|v| v.is_nan()),
                    "{} unknown but {:?}",
                    pos.name,
                    pos.a
                );
            }
        }
    }
}
