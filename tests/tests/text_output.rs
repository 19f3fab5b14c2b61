//! The text output says what happened, without glitches (issue 29 item 4): a sweep
//! fitted on the dynamic route is not warned of dwells "left out of static fits" and
//! lists each model it compared once, the kept one alone marked; `diagnose` says a
//! parameter is fixed instead of printing `+- NaN`; `batch --diagnose` names a clean
//! unit's model in words; `history` of a serial the store does not hold says so and
//! exits non-zero. (A closed pipe: host-fit's `tests/closed_pipe.rs`.)
use host_fit::data::positions::Positions;
use host_fit::data::recording::{Recording, MAX_DWELL_DRIFT_C, RAMP_SPAN_C};
use host_fit::simulate::{simulate, SimConfig};
use std::path::Path;
use tests::{cli, s};

fn write(dir: &Path, name: &str, cfg: &SimConfig) -> std::path::PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, simulate(cfg, |_| {}).unwrap().csv).unwrap();
    p
}

#[test]
fn a_sweep_on_the_dynamic_route_lists_each_model_once_and_warns_of_no_static_fit() {
    let tmp = tempfile::tempdir().unwrap();
    let rec = write(
        tmp.path(),
        "sweep.csv",
        &tests::sweep::sweep(tests::sweep::unit(0.0, 7)),
    );
    // dwells that drift more than the static fits take and less than a ramp: what the
    // reader warned of as "left out of static fits"
    let r = Recording::read(&rec, Positions::default()).unwrap();
    let drifting = r
        .dwells
        .iter()
        .filter(|d| d.temp_span_c > MAX_DWELL_DRIFT_C && d.temp_span_c < RAMP_SPAN_C)
        .count();
    assert!(drifting >= 4, "{drifting} drifting dwells");
    let blob = tmp.path().join("sweep.blob");
    let (code, out, err) = cli(&["fit", s(&rec), "--out", s(&blob)]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("dynamic route"), "{out}");
    assert!(!err.contains("left out of static fits"), "{err}");
    // said where notes are asked for: expected, fitted through
    let (_, _, verbose) = cli(&["fit", s(&rec), "--out", s(&blob), "--force", "--verbose"]);
    assert!(
        verbose.contains(&format!("{drifting} dwells drift"))
            && verbose.contains("expected in a sweep"),
        "{verbose}"
    );
    // the models compared: each once, one kept
    let models: Vec<&str> = out
        .lines()
        .skip_while(|l| !l.starts_with("models compared"))
        .skip(1)
        .take_while(|l| l.starts_with("  "))
        .collect();
    assert!(models.len() >= 4, "{out}");
    let kept = models.iter().filter(|l| l.starts_with("  *")).count();
    assert_eq!(kept, 1, "{out}");
    let mut names: Vec<&str> = models
        .iter()
        .map(|l| l[4..].rsplit_once(' ').unwrap().0.trim())
        .collect();
    let n = names.len();
    names.sort_unstable();
    names.dedup();
    assert_eq!(names.len(), n, "a model listed twice: {out}");
    // the JSON says the same
    let (_, j, _) = cli(&["fit", s(&rec), "--out", s(&blob), "--force", "--json"]);
    let j: serde_json::Value = serde_json::from_str(&j).unwrap();
    let chosen: Vec<&serde_json::Value> = j["candidates"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|c| c["chosen"] == true)
        .collect();
    assert_eq!(chosen.len(), 1, "{j}");
    assert_eq!(chosen[0]["model"], j["model"]);
}

#[test]
fn diagnose_says_a_fixed_parameter_is_fixed() {
    let tmp = tempfile::tempdir().unwrap();
    let case =
        host_fit::blind::Case::catalogue(vec![host_fit::diagnose::EffectId::TempRate], 1.0, 3);
    let rec = write(tmp.path(), "rate.csv", &host_fit::blind::configure(&case));
    let (code, out, err) = cli(&["diagnose", s(&rec)]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("finding: temp_rate"), "{out}");
    // the rate estimator's time constant is the search's choice, not a fitted value
    let line = out
        .lines()
        .find(|l| l.trim_start().starts_with("rate_tau_s = "))
        .unwrap_or_else(|| panic!("no rate_tau_s: {out}"));
    assert!(line.ends_with("s (fixed, not fitted)"), "{line}");
    assert!(!out.contains("NaN"), "{out}");
    // fitted parameters keep their uncertainty
    assert!(out.contains(" +- "), "{out}");
}

#[test]
fn batch_names_a_clean_units_diagnosed_model_and_history_refuses_an_unknown_serial() {
    let tmp = tempfile::tempdir().unwrap();
    let units = tmp.path().join("units");
    std::fs::create_dir_all(&units).unwrap();
    write(&units, "u1.csv", &SimConfig::default());
    let out = tmp.path().join("out");
    let (code, stdout, err) = cli(&["batch", s(&units), "--out", s(&out), "--diagnose"]);
    assert_eq!(code, 0, "{stdout}{err}");
    let mut r = csv::Reader::from_path(out.join("summary.csv")).unwrap();
    let header: Vec<String> = r.headers().unwrap().iter().map(String::from).collect();
    let row = r.records().next().unwrap().unwrap();
    let col = |k: &str| row[header.iter().position(|h| h == k).unwrap()].to_string();
    assert_eq!(col("findings"), "", "{row:?}");
    assert_eq!(col("model"), "diagnosed (no findings)");

    // the batch recorded its unit: its history is there, another serial's is not
    let db = out.join("records.sqlite");
    let (code, h, err) = cli(&["history", "PAPER-UNIT", "--db", s(&db)]);
    assert_eq!(code, 0, "{err}");
    assert!(h.contains("unit PAPER-UNIT: 1 records"), "{h}");
    for extra in [&[][..], &["--json"][..]] {
        let mut a = vec!["history", "PAPER-UNlT", "--db", s(&db)];
        a.extend_from_slice(extra);
        let (code, h, err) = cli(&a);
        assert_eq!(code, 1, "{extra:?}: {h}");
        assert!(h.is_empty(), "{h}");
        assert!(
            err.contains("records.sqlite: no records of unit `PAPER-UNlT` in this store"),
            "{err}"
        );
    }
}
