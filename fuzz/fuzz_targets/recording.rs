//! Any bytes as a recording: an error or a recording, never a panic.
#![no_main]
use host_fit::data::positions::Positions;
use host_fit::data::recording::Recording;
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    if let Ok(rec) = Recording::from_reader(Path::new("fuzz.csv"), data, Positions::default()) {
        // whatever reads must also get through the noise estimate and identification
        let nz = host_fit::fit::noise::noise(&rec);
        assert!(nz.sigma.iter().all(|s| s.is_finite()));
        let all = |_: usize| true;
        for st in host_fit::data::stops::stops(&rec, &all, 3.0) {
            let _ = host_fit::fit::identify::identify_stop(&rec, &st, &nz);
        }
    }
});
