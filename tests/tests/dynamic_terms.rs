//! The dynamic route (issue 19) keeps a term only where the unit has it: on a sweep of a
//! unit whose element only lags its sensor, the lag is found to a fraction of a percent and
//! no temperature-rate term rides along (a lag left on the profile's lattice, 0.1 % off,
//! used to leave a rate-shaped residual that a rate term took up on every seed); a unit
//! with a true rate term keeps it, with its signs.
use host_fit::simulate::PerAxis;
use tests::cli_json;
use tests::sweep::{sweep, unit};
use tests::time_true::{s, write};

/// How close the sweep's lag must come to the unit's (relative): the fit's own scatter
/// over seeds is about 0.03 %.
const LAG_TOLERANCE: f64 = 0.005;

fn fit(dir: &std::path::Path, cfg: &host_fit::simulate::SimConfig) -> serde_json::Value {
    let (rec, _) = write(dir, "sweep", &sweep(cfg.clone()));
    let b = dir.join("b.blob");
    cli_json(&["fit", s(&rec), "--out", s(&b), "--force", "--json"])
}

#[test]
fn a_lag_only_unit_gets_its_lag_and_no_rate_term() {
    let dir = tempfile::tempdir().unwrap();
    let mut lags = Vec::new();
    for (lag_s, seed) in [(300.0, 1), (300.0, 2), (1200.0, 1), (1200.0, 3)] {
        let j = fit(dir.path(), &unit(lag_s, seed));
        let lag = j["thermal_lag_tau_s"].as_f64().unwrap_or(0.0);
        println!("lag {lag_s} s, seed {seed}: {}", j["model"]);
        assert!(
            ((lag - lag_s) / lag_s).abs() < LAG_TOLERANCE,
            "lag {lag} s for a {lag_s} s unit: {j}"
        );
        assert!(
            j.get("temp_rate").is_none(),
            "a rate term on a lag-only unit: {j}"
        );
        lags.push(lag);
    }
    // two seeds of one unit give two estimates, not one lattice point
    assert!(lags[0] != lags[1] && lags[2] != lags[3], "{lags:?}");
}

#[test]
fn a_unit_with_a_rate_term_keeps_it() {
    let dir = tempfile::tempdir().unwrap();
    let mut c = unit(300.0, 4);
    let truth = [0.02, 0.0, -0.012];
    c.effects.temp_rate = Some(PerAxis { value: truth });
    let j = fit(dir.path(), &c);
    println!("{}", j["model"]);
    let rate = &j["temp_rate"][0];
    assert!(rate.is_array(), "no rate term kept: {j}");
    for (axis, t) in truth.iter().enumerate() {
        let r = rate[axis].as_f64().unwrap();
        if *t != 0.0 {
            assert!(
                r * t > 0.0 && (r / t - 1.0).abs() < 0.5,
                "axis {axis}: {r} against {t}: {j}"
            );
        }
    }
}
