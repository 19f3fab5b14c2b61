//! Any text as a positions file: an error or positions, never a panic; every position
//! is a unit vector, or of unknown orientation (all three fields empty) with an all-NaN
//! vector that can never pass for data.
#![no_main]
use host_fit::data::positions::Positions;
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
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
});
