//! One dwell missing (issue 17 item 2): the four-stop twin without its TP4 dwell at the
//! 5 C stop. The missing position is named with its stop; the cross-validation's folds
//! keep every training fold's design determined (the dwell whose removal would not is
//! never held out, and named), so every candidate is scored on the same held-out dwells
//! and the data-chosen model stays within 1.5x of the plain cubic and no worse than no
//! compensation at T0; `fit` and `diagnose` agree on the noise, and the dwell noise `fit`
//! states does not grow with a misfit (it was 0.2251 mg here, against 0.0092 mg with the
//! dwell present: the chosen model's reduced chi-square had widened it).
use serde_json::Value;
use std::path::Path;
use tests::four_stops::{simulate, without_dwell, FOUR};
use tests::{cli, s};

/// `fit REC --json` with `extra`; its JSON and stderr.
fn fit(rec: &Path, blob: &Path, extra: &[&str]) -> (Value, String) {
    let mut args = vec!["fit", s(rec), "--out", s(blob), "--json"];
    args.extend(extra);
    let (code, out, err) = cli(&args);
    assert_eq!(code, 0, "{err}");
    (serde_json::from_str(&out).unwrap(), err)
}

/// `verify --json`: (worst method-1 |dg|, (compensated, uncompensated) worst near T0), mg.
fn verify(rec: &Path, blob: &Path) -> (f64, (f64, f64)) {
    let (code, out, err) = cli(&["verify", "--blob", s(blob), s(rec), "--json"]);
    assert_eq!(code, 0, "{out}{err}");
    let j: Value = serde_json::from_str(&out).unwrap();
    let by_t = j["max_by_temperature"].as_array().unwrap();
    let worst = by_t
        .iter()
        .map(|t| t["max_abs_dg_mg"].as_f64().unwrap())
        .fold(0.0, f64::max);
    let t0 = by_t
        .iter()
        .find(|t| (t["temp_c"].as_f64().unwrap() - 25.0).abs() < 1.0)
        .unwrap();
    let g = |k: &str| t0[k].as_f64().unwrap();
    (
        worst,
        (g("max_abs_dg_mg"), g("max_abs_dg_mg_uncompensated")),
    )
}

#[test]
fn one_missing_dwell_is_named_and_does_not_cost_the_data_chosen_model_its_accuracy() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let full = simulate(dir, "four", FOUR);
    let miss = dir.join("miss.csv");
    without_dwell(&full, "TP4", 1, &miss);

    let (chosen, err) = fit(&miss, &dir.join("d.blob"), &[]);
    // named with its stop
    let line = err
        .lines()
        .find(|l| l.contains("position TP4 has no static dwell at the "))
        .unwrap_or_else(|| panic!("no warning names TP4: {err}"));
    let at: f64 = line
        .split("at the ")
        .nth(1)
        .and_then(|r| r.split(' ').next())
        .and_then(|t| t.parse().ok())
        .unwrap_or_else(|| panic!("{line}"));
    assert!((at - 5.0).abs() < 0.5, "{line}");
    assert!(line.starts_with("warning: calibration position"), "{line}");
    // nothing missing in the full recording
    let (_, err_full) = fit(&full, &dir.join("f.blob"), &[]);
    assert!(!err_full.contains("has no static dwell"), "{err_full}");
    // a verification position missing at the 60 C stop: named, and not judged there
    let pp = dir.join("pp.csv");
    without_dwell(&full, "PP3", 3, &pp);
    let (_, err_pp) = fit(&pp, &dir.join("pp.blob"), &[]);
    assert!(
        err_pp.lines().any(|l| l
            .starts_with("warning: verification position PP3 has no static dwell at the 59.")
            && l.ends_with("C stop (it has at -29.9, 4.9, 24.9 C): it is not judged there")),
        "{err_pp}"
    );

    // every candidate scored, on the same held-out dwells; the dwell that keeps the 5 C
    // stop's design determined (TP2, opposite the missing TP4) never held out
    let sel = &chosen["chosen_by"];
    for c in sel["candidates"].as_array().unwrap() {
        assert!(c["held_out_rms_dg_mg"].is_f64(), "not scored: {c}");
    }
    let never: Vec<&str> = sel["never_held_out"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    assert!(
        !never.is_empty() && never.iter().all(|n| n.starts_with("TP2 at 4.")),
        "{never:?}"
    );
    assert!(
        sel["method"].as_str().unwrap().contains("never held out"),
        "{sel}"
    );

    // within 1.5x of the plain cubic, and no worse than no compensation at T0
    fit(
        &miss,
        &dir.join("p3.blob"),
        &["--model", "poly", "--order", "3"],
    );
    let (d, (d_t0, raw_t0)) = verify(&miss, &dir.join("d.blob"));
    let (p3, _) = verify(&miss, &dir.join("p3.blob"));
    assert!(d <= 1.5 * p3, "default {d} mg, poly3 {p3} mg");
    assert!(
        d_t0 <= raw_t0,
        "at T0 {d_t0} mg compensated, {raw_t0} without"
    );

    // the dwell noise fit states: the same with and without the dwell (it is the
    // dwell's own, not the chosen model's misfit)
    let noise_of = |j: &Value| {
        j["predicted_error"]["dwell_noise_1sigma_mg"]
            .as_f64()
            .unwrap()
    };
    let (fj, _) = fit(&full, &dir.join("f.blob"), &["--force"]);
    let (n_miss, n_full) = (noise_of(&chosen), noise_of(&fj));
    // 2e-5 V a sample over the root of 60 samples: 0.0047 mg (widened by the paper
    // unit's reduced chi-square of 4.3 on x it was 0.0097 mg)
    assert!(
        (n_miss / n_full - 1.0).abs() < 0.1 && n_miss < 0.006,
        "{n_miss} mg without the dwell, {n_full} mg with it"
    );
    // a model that misfits by far (a line through four stops) is uncertain, and says so
    // in its covariance; its verification dwells are no noisier
    let (p1, _) = fit(
        &miss,
        &dir.join("p1.blob"),
        &["--model", "poly", "--order", "1"],
    );
    let chi2 = p1["predicted_error"]["covariance_scale"][0]
        .as_f64()
        .unwrap();
    assert!(chi2 > 100.0, "reduced chi-square {chi2}");
    assert!(
        (noise_of(&p1) / n_miss - 1.0).abs() < 0.1,
        "{} mg with poly1, {n_miss} mg with the chosen model",
        noise_of(&p1)
    );
    assert!(
        chosen["noise_figures"]["dwell_noise_1sigma_mg"]
            .as_str()
            .unwrap()
            .contains("not widened by the model's residuals"),
        "{}",
        chosen["noise_figures"]
    );

    // diagnose on the same file: the same per-sample noise (within its estimator's
    // difference, 25%), and a model at the noise: the fit's verification within 2.5x of
    // the diagnosis's reach
    let (code, out, err) = cli(&["diagnose", s(&miss), "--json"]);
    assert_eq!(code, 0, "{err}");
    let dj: Value = serde_json::from_str(&out).unwrap();
    for axis in 0..3 {
        let f = chosen["noise_sigma"][axis].as_f64().unwrap();
        let g = dj["noise_sigma_per_sample"][axis].as_f64().unwrap();
        assert!(
            (g / f - 1.0).abs() < 0.25,
            "axis {axis}: fit {f}, diagnose {g}"
        );
    }
    let reach = dj["final"]["max_abs_dg_mg"].as_f64().unwrap();
    assert!(d <= 2.5 * reach, "fit {d} mg, diagnose {reach} mg");
}
