//! The blob `fit` writes from a continuous sweep (issue 19), with the thermal lag it
//! found, compensates on the MCU's own sample period: the same flight of the same lagging
//! unit sampled at 10 Hz, 100 Hz and 1 kHz gives the same |dg| at every held attitude,
//! and the lag the blob carries is what makes the flight right (the same tables with the
//! lag taken out are worse).
use host_fit::simulate::SimConfig;
use tests::cli_json;
use tests::sweep::{sweep, unit};
use tests::time_true::{noiseless_flight, s, verify, write};

/// The element's lag behind its temperature sensor, s (the slowest unit).
const LAG_S: f64 = 1200.0;

/// As in `time_true.rs`: the machines step on about 0.1 s at every rate, so the held
/// attitudes' |dg| agree within this at 10 Hz, 100 Hz and 1 kHz (mg).
const RATES_BOUND_MG: f64 = 0.002;

/// A short flight of the lagging unit at `rate_hz`: a cold start soaked 10 min at -30 C,
/// a warming at 8 C/min to +10 C, 10 min there; 12 attitudes held 20 s; the voltmeter and
/// the temperature sensor noiseless so that only the clock differs between rates.
fn flight(rate_hz: f64) -> SimConfig {
    let legs = [(-30.0, 1.0, 600.0), (10.0, 8.0, 600.0)];
    noiseless_flight(unit(LAG_S, 31), rate_hz, &legs, Vec::new())
}

#[test]
fn a_sweep_blob_with_its_lag_compensates_alike_at_ten_hundred_and_thousand_hertz() {
    let dir = tempfile::tempdir().unwrap();
    let (rec, _) = write(dir.path(), "sweep", &sweep(unit(LAG_S, 31)));
    let blob = dir.path().join("sweep.blob");
    let j = cli_json(&["fit", s(&rec), "--out", s(&blob), "--force", "--json"]);
    let lag = j["thermal_lag_tau_s"].as_f64().unwrap_or(0.0);
    assert!(
        (lag - LAG_S).abs() < 0.1 * LAG_S,
        "the sweep's fit found lag {lag} s for a {LAG_S} s unit: {j}"
    );
    let runs: Vec<(f64, Vec<f64>)> = [10.0, 100.0, 1000.0]
        .iter()
        .map(|hz| {
            let (f, pos) = write(dir.path(), &format!("flight-{hz}"), &flight(*hz));
            let (worst, dg) = verify(&f, pos.as_deref(), &blob);
            println!(
                "{hz} Hz: {} held attitudes, worst |dg| {worst:.4} mg",
                dg.len()
            );
            (worst, dg)
        })
        .collect();
    let mut diff: f64 = 0.0;
    for (_, r) in &runs[1..] {
        assert_eq!(r.len(), runs[0].1.len());
        for (a, b) in r.iter().zip(&runs[0].1) {
            diff = diff.max((a - b).abs());
        }
    }
    println!("largest difference from 10 Hz: {diff:.5} mg");
    assert!(diff <= RATES_BOUND_MG, "{diff} mg");

    // the same tables without the lag: the flight's fast warming leaves the element
    // behind its sensor, which only the lag machine follows
    let mut b = firmware_core::blob::Blob::decode(&std::fs::read(&blob).unwrap()).unwrap();
    let p = b.calibration.physics.as_mut().unwrap();
    p.lag_tau_s = 0.0;
    let mut buf = [0u8; firmware_core::blob::MAX_BLOB_LEN];
    let n = b.encode(&mut buf).unwrap();
    let no_lag = dir.path().join("no-lag.blob");
    std::fs::write(&no_lag, &buf[..n]).unwrap();
    let (f, pos) = write(dir.path(), "flight-10-again", &flight(10.0));
    let (without, _) = verify(&f, pos.as_deref(), &no_lag);
    println!(
        "10 Hz: worst |dg| {:.4} mg with the lag, {without:.4} mg without",
        runs[0].0
    );
    assert!(
        runs[0].0 < 0.5 * without,
        "the lag should matter in this flight: {} mg with, {without} mg without",
        runs[0].0
    );
}
