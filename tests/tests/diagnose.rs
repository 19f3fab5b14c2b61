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
        let case = host_fit::blind::Case {
            effects,
            scale: 1.0,
            seed: 3,
            tp_only: false,
        };
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
/// recording with in-flight effects, every dwell's |dg| is smaller with the physics
/// terms than with the same tables alone.
#[test]
fn extended_model_in_the_blob_compensates_better_in_firmware() {
    use firmware_core::blob::Blob;
    use firmware_core::compensate::Method;
    use host_fit::data::positions::Positions;
    use host_fit::data::recording::Recording;
    let dir = std::env::temp_dir().join(format!("hf-phys-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let case = host_fit::blind::Case {
        effects: vec!["nonlinearity_k2", "temp_rate", "warmup_drift"],
        scale: 3.0,
        seed: 5,
        tp_only: false,
    };
    let sim = host_fit::simulate::simulate(&host_fit::blind::configure(&case), |_| {}).unwrap();
    let p = dir.join("rec.csv");
    std::fs::write(&p, &sim.csv).unwrap();
    let blob_path = dir.join("unit.blob");
    let (code, out, err) = cli(&[
        "diagnose",
        p.to_str().unwrap(),
        "--out",
        blob_path.to_str().unwrap(),
        "--json",
        "--force",
    ]);
    assert_eq!(code, 0, "{err}");
    let j: serde_json::Value = serde_json::from_str(&out).unwrap();
    let found: Vec<&str> = j["findings"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f["effect"].as_str().unwrap())
        .collect();
    for e in &case.effects {
        assert!(found.contains(e), "{e} not found: {found:?}");
    }
    assert_eq!(j["blob"]["physics"], true);
    let with = Blob::decode(&std::fs::read(&blob_path).unwrap()).unwrap();
    let p = with.calibration.physics.clone().unwrap();
    assert!(
        p.k2.iter().any(|v| *v != 0.0)
            && p.rate.iter().any(|v| *v != 0.0)
            && p.warmup.iter().any(|v| *v != 0.0)
    );
    let mut without = with.clone();
    without.calibration.physics = None;
    let rec = Recording::from_reader(
        &dir.join("rec.csv"),
        sim.csv.as_bytes(),
        Positions::default(),
    )
    .unwrap();
    let all = |_: usize| true;
    let mean_dg = |b: &Blob| {
        let v = host_fit::verify::verify(&rec, b, Method::CorrectConstants, &all).unwrap();
        v.dwells.iter().map(|d| d.dg_mg.abs()).sum::<f64>() / v.dwells.len() as f64
    };
    let (a, b) = (mean_dg(&with), mean_dg(&without));
    println!("mean |dg| over all dwells: with physics {a:.4} mg, tables alone {b:.4} mg");
    assert!(a < 0.5 * b, "with physics {a} mg, without {b} mg");
    std::fs::remove_dir_all(&dir).unwrap();
}
