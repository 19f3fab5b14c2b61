//! Mixtures (issue 18, item 4): a larger effect at its nominal size beside a smaller one
//! acting where the larger does not (here a position). After the effects accepted, the
//! search looks again where the rest is located and names the smaller one when it passes
//! the same acceptance rules, its share of the excess counted there; the report says
//! what the re-search looked at. Nominal sizes are the blind suite's
//! (host-fit/src/blind/config.rs).
use host_fit::data::positions::Positions;
use host_fit::data::recording::Recording;
use host_fit::diagnose::location::Grouping;
use host_fit::diagnose::{diagnose, EffectId};
use host_fit::simulate::{simulate, SimConfig};

fn recording(cfg: &SimConfig) -> Recording {
    let sim = simulate(cfg, |_| {}).unwrap();
    Recording::from_reader(
        std::path::Path::new("twin.csv"),
        sim.csv.as_bytes(),
        Positions::default(),
    )
    .unwrap()
}

/// The blind suite's catalogue forms: `large` at its nominal size, each of `small` at
/// its scale, the random sizes, signs, axes and positions drawn from `seed`.
fn mixture(large: EffectId, small: &[(EffectId, f64)], seed: u64) -> SimConfig {
    use host_fit::blind::{configure, Case};
    let mut c = configure(&Case::catalogue(vec![large], 1.0, seed));
    for (k, &(id, scale)) in small.iter().enumerate() {
        let s = configure(&Case::catalogue(
            vec![id],
            scale,
            seed + 100 * (k as u64 + 1),
        ));
        let (e, f) = (&mut c.effects, s.effects);
        match id {
            EffectId::TempCurvature => e.temp_curvature = f.temp_curvature,
            EffectId::ThermalLag => e.thermal_lag = f.thermal_lag,
            EffectId::TempRate => e.temp_rate = f.temp_rate,
            EffectId::Hysteresis => e.hysteresis = f.hysteresis,
            EffectId::NonlinearityK2 => e.nonlinearity_k2 = f.nonlinearity_k2,
            EffectId::ScaleAsymmetry => e.scale_asymmetry = f.scale_asymmetry,
            EffectId::FixtureError => e.fixture_error = f.fixture_error,
            EffectId::WarmupDrift => e.warmup_drift = f.warmup_drift,
            // a mixture of the catalogue's effects: no discovered term is drawn
            EffectId::Discovered => {}
        }
    }
    c
}

/// temp_rate at its nominal size, a thermal lag, and a fixture error at half its nominal
/// size: before item 4, the rate and the lag were found and the fixture error was not
/// (it explains a tenth of the excess the other two leave over the whole recording),
/// although what was left stood out 16x the floor at exactly its position and axis.
#[test]
fn a_fixture_error_beside_a_rate_and_a_lag_is_found_where_the_rest_is_located() {
    let small = [(EffectId::ThermalLag, 0.3), (EffectId::FixtureError, 0.5)];
    let cfg = mixture(EffectId::TempRate, &small, 52);
    let truth = cfg.effects.fixture_error.clone().unwrap();
    let rec = recording(&cfg);
    let d = diagnose(&rec).unwrap();
    let c = d.contract();
    let text = c.text();
    let mut found: Vec<EffectId> = c.findings.iter().map(|f| f.effect).collect();
    found.sort();
    assert_eq!(
        found,
        [
            EffectId::ThermalLag,
            EffectId::TempRate,
            EffectId::FixtureError
        ],
        "{text}"
    );
    let f = c
        .findings
        .iter()
        .find(|f| f.effect == EffectId::FixtureError)
        .unwrap();
    assert_eq!(
        f.position.as_deref(),
        Some(truth.position.as_str()),
        "{text}"
    );
    // the report says where the re-search looked and what it found there
    let r = c
        .research
        .iter()
        .find(|r| r.found == Some(EffectId::FixtureError))
        .unwrap_or_else(|| panic!("no re-search found it\n{text}"));
    assert!(
        r.region
            .iter()
            .any(|h| h.value == truth.position && h.group == Grouping::Position),
        "{text}"
    );
    assert!(
        text.contains("re-search where the rest is located"),
        "{text}"
    );
    let json = serde_json::to_value(&c).unwrap();
    assert!(json["research"].as_array().is_some_and(|a| !a.is_empty()));
}
