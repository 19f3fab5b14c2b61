//! The diagnosis: blind tests on concealed effects, the JSON contract, and the real
//! recording of ../shared/real/cats-tag.
use host_fit::blind::{report, run, suite};
use tests::{cli, repo};

#[test]
fn blind_suite_names_the_concealed_effects() {
    let outcomes: Vec<_> = suite(false).iter().map(run).collect();
    let text = report(&outcomes);
    println!("{text}");
    let exact = outcomes.iter().filter(|o| o.exact).count();
    assert!(
        exact as f64 >= 0.9 * outcomes.len() as f64,
        "exactly right in {exact}/{}:\n{text}",
        outcomes.len()
    );
    for o in outcomes.iter().filter(|o| o.case.effects.is_empty()) {
        assert!(
            o.found.is_empty() && o.ambiguous.is_empty(),
            "false finding on a clean recording:\n{text}"
        );
        assert!(o.final_over_noise < 1.5);
    }
    for o in outcomes.iter().filter(|o| o.exact) {
        assert_ne!(
            o.params_ok,
            Some(false),
            "parameters off by more than 3 sigma:\n{text}"
        );
        assert!(
            o.final_over_noise <= 1.5,
            "final residual {} x noise:\n{text}",
            o.final_over_noise
        );
    }
    // the TP-only recording cannot separate K2 from scale asymmetry: reported, not guessed
    let tp = outcomes.iter().find(|o| o.case.tp_only).unwrap();
    assert!(
        tp.ambiguous
            .iter()
            .any(|a| a.contains(&"nonlinearity_k2".to_string())
                && a.contains(&"scale_asymmetry".to_string())),
        "{text}"
    );
    assert!(tp
        .found
        .iter()
        .all(|f| f != "nonlinearity_k2" && f != "scale_asymmetry"));
}

#[test]
fn json_contract_on_a_clean_and_an_effect_recording() {
    let dir = std::env::temp_dir().join(format!("hf-diag-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for (name, effects) in [("clean", vec![]), ("rate", vec!["temp_rate"])] {
        let case = host_fit::blind::Case::catalogue(effects, 1.0, 3);
        let cfg = host_fit::blind::configure(&case);
        let sim = host_fit::simulate::simulate(&cfg, |_| {}).unwrap();
        let p = dir.join(format!("{name}.csv"));
        std::fs::write(&p, sim.csv).unwrap();
        let report = dir.join(format!("{name}.html"));
        let _ = std::fs::remove_file(&report);
        let (code, out, err) = cli(&[
            "diagnose",
            p.to_str().unwrap(),
            "--json",
            "--report",
            report.to_str().unwrap(),
        ]);
        assert_eq!(code, 0, "{err}");
        let j: serde_json::Value = serde_json::from_str(&out).unwrap();
        assert_eq!(j["format"], "at-diagnosis/1");
        for k in [
            "noise_rms",
            "baseline",
            "findings",
            "ambiguous",
            "final",
            "verdict",
        ] {
            assert!(j.get(k).is_some(), "{k} missing");
        }
        assert!(j["noise_rms"].as_f64().unwrap() > 0.0);
        for k in ["residual_rms", "max_abs_dg_mg"] {
            assert!(j["baseline"][k].as_f64().is_some() && j["final"][k].as_f64().is_some());
        }
        assert!(j["baseline"]["temperature_model"].as_str().is_some());
        let html = std::fs::read_to_string(&report).unwrap();
        assert!(html.contains("resid-time-before") && html.contains("resid-time-after"));
        if name == "clean" {
            assert_eq!(j["verdict"], "none");
            assert!(j["findings"].as_array().unwrap().is_empty());
        } else {
            let f = &j["findings"][0];
            assert_eq!(f["effect"], "temp_rate");
            for k in [
                "axes",
                "parameters",
                "uncertainties",
                "delta_bic",
                "residual_rms_after",
                "max_abs_dg_mg_after",
                "evidence",
            ] {
                assert!(f.get(k).is_some(), "finding.{k} missing");
            }
            assert!(f["delta_bic"].as_f64().unwrap() < -10.0);
            assert_eq!(j["verdict"], "explained");
            assert!(
                j["final"]["residual_rms"].as_f64().unwrap()
                    < j["baseline"]["residual_rms"].as_f64().unwrap()
            );
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn real_tag_recording_finding_improves_the_held_out_fit() {
    let rec = repo().join("../shared/real/cats-tag/recording.csv");
    let pos = repo().join("../shared/real/cats-tag/positions.csv");
    assert!(
        rec.exists(),
        "the shared real recording is missing: {}",
        rec.display()
    );
    let (code, out, err) = cli(&[
        "diagnose",
        rec.to_str().unwrap(),
        "--positions",
        pos.to_str().unwrap(),
        "--json",
    ]);
    assert_eq!(code, 0, "{err}");
    let j: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert!(
        j["not_identifiable"]
            .as_array()
            .unwrap()
            .iter()
            .any(|n| n.as_str().unwrap().contains("cross-sensitivities")),
        "three orientations: cross terms not identifiable"
    );
    assert!(!j["findings"].as_array().unwrap().is_empty(), "{out}");
    let before = j["final"]["heldout_chi2_before"].as_f64().unwrap();
    let after = j["final"]["heldout_chi2_after"].as_f64().unwrap();
    assert!(after < 0.5 * before, "held-out chi2 {before} -> {after}");
    assert!(
        j["final"]["residual_rms"].as_f64().unwrap()
            < j["baseline"]["residual_rms"].as_f64().unwrap()
    );
}

/// The extended model goes into the blob and firmware-core compensates with it: on a
/// recording with in-flight effects (K2, rate, warm-up at 3x nominal), every dwell's
/// |dg| is within 0.05 mg with the physics terms (over 0.5 mg at worst with the same
/// tables alone), and the mean over all dwells is at least 20x smaller.
#[test]
fn extended_model_in_the_blob_compensates_better_in_firmware() {
    let (a, b, line) = tests::figures::physics_blob();
    println!("{line}");
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let worst = |v: &[f64]| v.iter().copied().fold(0.0, f64::max);
    assert!(
        worst(&a) <= 0.05,
        "with the physics terms every dwell is within 0.05 mg: {line}"
    );
    assert!(mean(&b) >= 20.0 * mean(&a), "not 20x better: {line}");
    assert!(
        worst(&b) > 0.5,
        "the effects are visible without the terms: {line}"
    );
}
