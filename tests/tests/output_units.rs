//! Output units of recording-format.md end to end: the twin writes m/s2 and counts (as
//! integers, `# output_unit=` stated), `fit` calibrates them and records the unit in the
//! blob, `verify` judges them, and `diagnose` reads them; a digital output of a few
//! counts per g, its noise below one count, is diagnosed with the quantisation's floor
//! instead of refused (issue 17 item 6, issue 18 item 2).
use host_fit::data::output_unit::OutputUnit;
use host_fit::simulate::{simulate, SimConfig, Stop};
use serde_json::Value;
use std::path::Path;
use tests::{cli, cli_json, s};

/// A short production test (three stops, TP and PP at each) written in `unit`, `per_v`
/// written units per volt (0: the unit's nominal factor).
fn twin(unit: OutputUnit, per_v: f64) -> SimConfig {
    let mut c = SimConfig {
        seed: 11,
        ..SimConfig::default()
    };
    c.schedule.stops = [-10.0, 20.0, 50.0]
        .iter()
        .map(|t| Stop {
            temp_c: *t,
            soak_s: 1500.0,
            ramp_c_per_min: 1.0,
            positions: None,
        })
        .collect();
    c.output.unit = unit;
    c.output.per_v = per_v;
    c
}

fn write(dir: &Path, name: &str, cfg: &SimConfig) -> std::path::PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, simulate(cfg, |_| {}).unwrap().csv).unwrap();
    p
}

/// The output columns of a recording's data rows.
fn outputs(text: &str) -> Vec<&str> {
    text.lines()
        .filter(|l| !l.starts_with('#') && !l.starts_with("t_s"))
        .flat_map(|l| l.split(',').skip(4))
        .collect()
}

/// The worst verification |dg| of `verify --json`, mg.
fn worst_dg(rec: &Path, blob: &Path) -> f64 {
    // exit 3: judged, the acceptance failed (one count is 1 mg, beyond its 0.3 mg)
    let (code, out, err) = cli(&["verify", s(rec), "--blob", s(blob), "--json"]);
    assert!(code == 0 || code == 3, "{err}");
    let j: Value = serde_json::from_str(&out).unwrap();
    j["dwells"]
        .as_array()
        .unwrap()
        .iter()
        .map(|d| d["dg_mg"].as_f64().unwrap().abs())
        .fold(0.0, f64::max)
}

#[test]
fn m_s2_and_counts_are_written_fitted_verified_and_diagnosed() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    // m/s2: 9.80665 / 0.55 per volt; counts: about 1000 per g, integers, the voltmeter's
    // 2e-5 V noise (0.036 count) far below one count
    for (unit, label, bound_mg) in [
        (OutputUnit::MetresPerS2, "m/s2", 0.05),
        (OutputUnit::Counts, "counts", 1.0),
    ] {
        let rec = write(dir, "rec.csv", &twin(unit.clone(), 0.0));
        let text = std::fs::read_to_string(&rec).unwrap();
        assert!(
            text.contains(&format!("\n# output_unit={label}\n")),
            "{label}"
        );
        let out = outputs(&text);
        assert!(out.len() > 10_000);
        if unit == OutputUnit::Counts {
            assert!(
                out.iter().all(|v| v.parse::<i64>().is_ok() && *v != "-0"),
                "counts are integers"
            );
        } else {
            // about 9.8 m/s2 on the axis along gravity
            let z: f64 = out[2].parse().unwrap();
            assert!((9.0..10.5).contains(&z.abs()), "{z}");
        }
        let blob = dir.join("u.blob");
        let (code, _, err) = cli(&["fit", s(&rec), "--out", s(&blob), "--force"]);
        assert_eq!(code, 0, "{label}: {err}");
        let (_, inspect, _) = cli(&["inspect", s(&blob)]);
        assert!(inspect.contains(label), "{label}: {inspect}");
        // within the unit's noise (m/s2) or its one-count (1 mg) quantisation (counts)
        let worst = worst_dg(&rec, &blob);
        assert!(worst < bound_mg, "{label}: worst |dg| {worst} mg");
        let j = cli_json(&["diagnose", s(&rec), "--json"]);
        assert_eq!(j["verdict"], "none", "{label}: {j}");
        let d = j["final"]["max_abs_dg_mg"].as_f64().unwrap();
        assert!(d < bound_mg, "{label}: diagnose's worst |dg| {d} mg");
    }
}

/// The noise far below one count: the samples of a dwell repeat, the floor is the step's
/// (1 / sqrt(12) count) on every axis, and `diagnose` does what `fit` does: calibrate. A
/// recording missing the positions that determine the scales is still refused, with that
/// reason.
#[test]
fn a_few_counts_per_g_is_diagnosed_on_the_quantisations_floor() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    // 7 counts per volt: about 4 counts per g
    let cfg = twin(OutputUnit::Counts, 7.0);
    let rec = write(dir, "few.csv", &cfg);
    let (code, _, err) = cli(&["fit", s(&rec), "--out", s(&dir.join("few.blob"))]);
    assert_eq!(code, 0, "{err}");
    let j: Value = cli_json(&["diagnose", s(&rec), "--json"]);
    assert_eq!(j["floor"]["measured"], true, "{j}");
    for a in j["floor"]["axes"].as_array().unwrap() {
        assert_eq!(a["quantum"], 1.0, "{a}");
        let sigma = a["window_sigma"].as_f64().unwrap();
        assert!((sigma - 12f64.sqrt().recip()).abs() < 1e-9, "{a}");
    }
    assert!(
        j["quality"]
            .as_array()
            .unwrap()
            .iter()
            .any(|q| q["kind"] == "quantised"),
        "{j}"
    );
    // nothing beyond the floor is called physics
    assert!(j["findings"].as_array().unwrap().is_empty(), "{j}");
    // TP1 and TP2 only: x is never along gravity, so its scale is not determined:
    // refused, for that reason (as `fit` refuses it)
    let mut two = cfg.clone();
    two.schedule.positions = vec!["TP1".into(), "TP2".into()];
    let rec = write(dir, "two.csv", &two);
    let (code, _, err) = cli(&["diagnose", s(&rec), "--json"]);
    assert_eq!(code, 1);
    assert!(
        err.contains("the positions present do not determine"),
        "{err}"
    );
}
