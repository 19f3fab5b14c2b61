//! Production calibration end to end: the data-chosen model against the plain
//! least-squares fit on twins it was not tuned to, the predicted error's coverage,
//! acceptance and its exit codes, unknown orientations, dwell-averaged recordings.
use tests::readme::same;
use tests::{cli_json, figures, s};

/// The default fit is never worse than the plain least-squares cubic by more than the
/// noise of a verification dwell's mean can make a worst |dg| differ (twice its 1-sigma:
/// the in-dwell noise over the root of the dwell's samples, from the fit's own JSON).
#[test]
fn default_fit_is_never_worse_than_the_plain_least_squares_cubic_beyond_dwell_noise() {
    let (rows, text) = figures::model_choice();
    println!("{text}");
    same("model-choice", &text);
    for r in &rows {
        let (name, model, plain) = (&r.name, &r.model, r.plain);
        let noise = 2.0 * r.dwell_noise_mg;
        assert!(
            noise > 0.0 && noise < 0.1,
            "{name}: a dwell's noise of {noise:.4} mg"
        );
        assert!(
            r.default <= plain + noise,
            "{name}: default ({model}) {:.4} mg, plain cubic {plain:.4} mg, dwell noise {noise:.4} mg",
            r.default
        );
        // the static route with the same cubic is the plain fit but for its even-order
        // term (the plain fit has none): within 5% or the dwell noise
        assert!(
            (r.static_cubic - plain).abs() <= 0.05 * plain + noise,
            "{name}: static poly3 {:.4} mg, plain cubic {plain:.4} mg",
            r.static_cubic
        );
    }
}

#[test]
fn the_predicted_error_covers_the_held_out_error_at_about_its_rate() {
    let (rows, text) = figures::coverage();
    println!("{text}");
    same("coverage", &text);
    // the twins whose truth the chosen family holds and that settle at their stops; the
    // others (a truth between the stops no family follows, a recording never in
    // equilibrium) are where the covariance cannot know the model's error, and the
    // book says so (docs/production.md)
    let in_family = |name: &str| {
        !["kinks", "outside", "ramps"]
            .iter()
            .any(|k| name.contains(k))
    };
    let (n, one, two) = rows
        .iter()
        .filter(|r| in_family(&r.0))
        .fold((0, 0, 0), |a, r| (a.0 + r.1, a.1 + r.2, a.2 + r.3));
    let (f1, f2) = (one as f64 / n as f64, two as f64 / n as f64);
    assert!(n >= 150, "{n} dwells");
    // 68% and 95% for a normal error; the binomial spread over 180 dwells is 3.5% and 1.6%
    assert!((0.58..=0.78).contains(&f1), "1 sigma covers {f1:.2}");
    assert!((0.89..=0.995).contains(&f2), "2 sigma covers {f2:.2}");
}

/// ../shared/real/ggir-wrist with every orientation unknown: the held-out dwells'
/// |a| - 1 beats GGIR's own calibration on the same dwells (2.92 mg).
#[test]
fn unknown_orientations_on_the_wrist_recording_beat_ggir_on_held_out_dwells() {
    let (rms, model, line) = figures::ggir_wrist();
    println!("{line}");
    same("ggir-wrist", &line);
    assert!(rms < 2.92, "{line}");
    assert!(
        model.starts_with("poly") || model.starts_with("pwl"),
        "{model}"
    );
}

/// One temperature: the 12 coefficients, and a plain statement that no temperature
/// model can be fitted; the coefficients are the per-stop identification's.
#[test]
fn one_temperature_gives_the_twelve_coefficients_and_says_no_temperature_model() {
    let (j, text) = figures::imucal();
    println!("{text}");
    same("imucal", &text);
    assert_eq!(j["model"], "poly0");
    assert!(j["no_temperature_model"]
        .as_str()
        .unwrap()
        .contains("no temperature model can be fitted"));
    let rec = tests::repo().join("../shared/real/imucal-ferraris/recording.csv");
    let (code, out, err) = tests::cli(&["identify", rec.to_str().unwrap(), "--json"]);
    assert_eq!(code, 0, "{err}");
    let id: serde_json::Value = serde_json::from_str(&out).unwrap();
    let stops = id["stops"].as_array().unwrap();
    assert_eq!(stops.len(), 1);
    for (name, v) in stops[0]["coefficients"].as_object().unwrap() {
        let (a, b) = (
            v.as_f64().unwrap(),
            j["temperature_model"]["at_t0"][name].as_f64().unwrap(),
        );
        // m/s^2 per g and m/s^2: the same least squares, so to rounding
        assert!(
            (a - b).abs() < 1e-9 * (1.0 + a.abs()),
            "{name}: identify {a}, fit {b}"
        );
    }
    // scale factors of a MEMS in m/s^2 per g, offsets of tens of mg
    let c = &j["temperature_model"]["at_t0"];
    for k in ["kxx", "kyy", "kzz"] {
        let v = c[k].as_f64().unwrap();
        assert!((v / 9.80665 - 1.0).abs() < 0.03, "{k} {v}");
    }
}

/// A temporary folder (removed when the test drops it, passed or failed) with the paper
/// unit's recording (seed `seed`) in it.
fn paper_recording(seed: u64) -> (tempfile::TempDir, std::path::PathBuf) {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let cfg = host_fit::simulate::SimConfig {
        seed,
        ..Default::default()
    };
    let sim = host_fit::simulate::simulate(&cfg, |_| {}).unwrap();
    let rec = dir.join("rec.csv");
    std::fs::write(&rec, sim.csv).unwrap();
    (tmp, rec)
}

/// verify: pass exits 0, fail exits 3 with the reason, a bad specification or another
/// unit's blob exits 1 (could not run) unless --force.
#[test]
fn verify_judges_acceptance_with_its_exit_codes_and_refuses_another_units_blob() {
    use tests::cli;
    let (tmp, rec) = paper_recording(11);
    let dir = tmp.path();
    let good = dir.join("good.blob");
    let (code, _, err) = cli(&["fit", s(&rec), "--out", s(&good)]);
    assert_eq!(code, 0, "{err}");
    let (code, out, err) = cli(&["verify", s(&rec), "--blob", s(&good)]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("acceptance: pass"), "{out}");
    // the paper's own model misses its 1 mg over the range at -10 and +45 C
    let paper = dir.join("paper.blob");
    let (code, _, err) = cli(&[
        "fit",
        s(&rec),
        "--model",
        "pwl",
        "--breakpoints",
        "-40,20,70",
        "--out",
        s(&paper),
    ]);
    assert_eq!(code, 0, "{err}");
    let (code, out, err) = cli(&["verify", s(&rec), "--blob", s(&paper), "--json"]);
    assert_eq!(code, 3, "{err}");
    let j: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(j["acceptance"], "fail");
    let reason = j["reason"].as_str().unwrap();
    assert!(
        reason.contains("over the limit") && reason.contains("PP"),
        "{reason}"
    );
    assert!(j["dwells_failed"].as_u64().unwrap() >= 1);
    // the specification is the user's
    let (code, out, _) = cli(&[
        "verify",
        s(&rec),
        "--blob",
        s(&good),
        "--accept-range-mg",
        "0.001",
    ]);
    assert_eq!(code, 3, "{out}");
    let (code, _, err) = cli(&[
        "verify",
        s(&rec),
        "--blob",
        s(&good),
        "--accept-t0-mg",
        "-1",
    ]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("--accept-t0-mg"), "{err}");
    // another unit's blob
    let other = dir.join("other.csv");
    let text = std::fs::read_to_string(&rec)
        .unwrap()
        .replace("# unit=PAPER-UNIT", "# unit=OTHER-7");
    std::fs::write(&other, text).unwrap();
    let (code, _, err) = cli(&["verify", s(&other), "--blob", s(&good)]);
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains("PAPER-UNIT") && err.contains("OTHER-7") && err.contains("--force"),
        "{err}"
    );
    let (code, _, err) = cli(&["verify", s(&other), "--blob", s(&good), "--force"]);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("warning") && err.contains("OTHER-7"), "{err}");
}

/// An option that does not apply to the model is an error, never ignored; the data's
/// choice takes an order when it chose a polynomial.
#[test]
fn options_that_do_not_apply_are_errors() {
    use tests::cli;
    let (tmp, rec) = paper_recording(12);
    let dir = tmp.path();
    let b = dir.join("u.blob");
    for (args, says) in [
        (vec!["--model", "pwl", "--order", "3"], "--order"),
        (
            vec!["--model", "poly", "--breakpoints", "-40,20,70"],
            "--breakpoints",
        ),
        // the data choose poly4 here: breakpoints do not apply to it
        (vec!["--breakpoints", "-40,20,70"], "the data chose poly4"),
        (vec!["--route", "joint"], "give --model"),
    ] {
        let mut a = vec!["fit", s(&rec), "--out", s(&b)];
        a.extend(args.iter());
        let (code, _, err) = cli(&a);
        assert_eq!(code, 1, "{args:?}");
        assert!(err.contains(says), "{args:?}: {err}");
        assert!(!b.exists(), "{args:?} wrote a blob");
    }
    let j = cli_json(&["fit", s(&rec), "--out", s(&b), "--order", "2", "--json"]);
    assert_eq!(j["model"], "poly2");
    assert_eq!(j["chosen_by"]["chosen"], "poly4");
    // a family alone: the data choose its order (or breakpoints) within it
    for (family, prefix) in [("poly", "poly"), ("pwl", "pwl[")] {
        let j = cli_json(&[
            "fit",
            s(&rec),
            "--out",
            s(&b),
            "--force",
            "--model",
            family,
            "--json",
        ]);
        assert!(
            j["model"].as_str().unwrap().starts_with(prefix),
            "{}",
            j["model"]
        );
        let cands = j["chosen_by"]["candidates"].as_array().unwrap();
        assert!(
            cands.len() > 1
                && cands
                    .iter()
                    .all(|c| c["model"].as_str().unwrap().starts_with(prefix))
        );
    }
    let table = tests::repo().join("testdata/paper/paper-tables.csv");
    let (code, _, err) = cli(&["temp-fit", s(&table), "--model", "pwl", "--order", "2"]);
    assert_eq!(code, 1);
    assert!(err.contains("--order"), "{err}");
}

/// The default fit says what it chose and why, with the predicted error against
/// temperature over the valid range, and what the equilibrium rule left out.
#[test]
fn the_default_fit_states_its_choice_and_its_predicted_error() {
    let (tmp, rec) = paper_recording(13);
    let dir = tmp.path();
    let b = dir.join("u.blob");
    let j = cli_json(&["fit", s(&rec), "--out", s(&b), "--json"]);
    let sel = &j["chosen_by"];
    assert!(sel["reason"]
        .as_str()
        .unwrap()
        .contains(j["model"].as_str().unwrap()));
    let cands = sel["candidates"].as_array().unwrap();
    assert!(cands.len() >= 6, "{sel}");
    let score = |m: &str| {
        cands.iter().find(|c| c["model"] == m).unwrap()["held_out_rms_dg_mg"]
            .as_f64()
            .unwrap()
    };
    // the paper unit is a quartic: the cubic misses the held-out dwells by ~1 mg
    assert!(score("poly3") > 20.0 * score("poly4"), "{sel}");
    let p = &j["predicted_error"];
    let (lo, hi) = (
        p["t_min_c"].as_f64().unwrap(),
        p["t_max_c"].as_f64().unwrap(),
    );
    assert_eq!(
        (lo, hi),
        (
            j["t_min_c"].as_f64().unwrap(),
            j["t_max_c"].as_f64().unwrap()
        )
    );
    let pts = p["points"].as_array().unwrap();
    assert!(pts.len() >= 10);
    for q in pts {
        let v = q["dg_1sigma_mg"].as_f64().unwrap();
        assert!(v > 0.0 && v < 0.05, "{q}");
    }
    // the firmware's cache, stated apart: by default its step is chosen from the unit's
    // slopes so that it never costs more than a verification dwell's own noise anywhere
    // in the valid range; a given step scales its cost
    let c = &j["cache"];
    let (step, lag, floor) = (
        c["step_c"].as_f64().unwrap(),
        c["worst_mg"].as_f64().unwrap(),
        c["floor_mg"].as_f64().unwrap(),
    );
    assert_eq!(c["chosen"], true, "{c}");
    assert!(step > 0.0 && step <= 0.1, "{c}");
    assert!(lag > 0.0 && lag <= floor, "{c}");
    assert_eq!(p["cache_lag_max_mg"].as_f64().unwrap(), lag);
    assert_eq!(p["dwell_noise_1sigma_mg"].as_f64().unwrap(), floor);
    let j2 = cli_json(&[
        "fit",
        s(&rec),
        "--out",
        s(&b),
        "--json",
        "--force",
        "--update-step",
        "0.2",
    ]);
    let lag2 = j2["predicted_error"]["cache_lag_max_mg"].as_f64().unwrap();
    assert!((lag2 / lag - 0.2 / step).abs() < 1e-9, "{lag} {lag2}");
    assert_eq!(j2["cache"]["chosen"], false);
    let ex = &j["excluded_not_in_equilibrium"];
    assert_eq!(ex["dwells"], 5, "the five rests through the ramps: {ex}");
}

/// Unit names of any length up to the blob format's limit (MAX_SERIAL_LEN bytes of
/// printable ASCII); a longer one, or one with other characters, is refused with the rule
/// stated, and --serial gives another.
#[test]
fn serials_up_to_the_blob_limit_and_a_clear_refusal_beyond() {
    use firmware_core::blob::MAX_SERIAL_LEN;
    use tests::cli;
    let (tmp, rec) = paper_recording(14);
    let dir = tmp.path();
    let text = std::fs::read_to_string(&rec).unwrap();
    let b = dir.join("u.blob");
    // exactly the limit fits (with the CATS tag's kind of characters), one more does not
    let fits = format!("CATS-tag ({})", "x".repeat(MAX_SERIAL_LEN - 11));
    let over = "x".repeat(MAX_SERIAL_LEN + 1);
    assert_eq!(fits.len(), MAX_SERIAL_LEN);
    for (name, ok) in [(fits.as_str(), true), (over.as_str(), false)] {
        let p = dir.join("named.csv");
        std::fs::write(
            &p,
            text.replace("# unit=PAPER-UNIT", &format!("# unit={name}")),
        )
        .unwrap();
        let (code, _, err) = cli(&["fit", s(&p), "--out", s(&b), "--force", "--model", "poly"]);
        if ok {
            assert_eq!(code, 0, "{err}");
            let (_, out, _) = cli(&["inspect", s(&b), "--json"]);
            let j: serde_json::Value = serde_json::from_str(&out).unwrap();
            assert_eq!(j["serial"], name);
        } else {
            assert_eq!(code, 1);
            assert!(
                err.contains(&format!("at most {MAX_SERIAL_LEN} bytes"))
                    && err.contains("--serial"),
                "{err}"
            );
            let (code, _, err) = cli(&[
                "fit",
                s(&p),
                "--out",
                s(&b),
                "--force",
                "--model",
                "poly",
                "--serial",
                "SHORT-1",
            ]);
            assert_eq!(code, 0, "{err}");
            let (_, out, _) = cli(&["inspect", s(&b)]);
            assert!(out.contains("serial SHORT-1"), "{out}");
            let (code, _, err) = cli(&["diagnose", s(&p), "--out", s(&b), "--force"]);
            assert_eq!(code, 1);
            assert!(err.contains("diagnose --serial"), "{err}");
            let (code, _, err) = cli(&[
                "diagnose",
                s(&p),
                "--out",
                s(&b),
                "--force",
                "--serial",
                "SHORT-2",
            ]);
            assert_eq!(code, 0, "{err}");
            let (_, out, _) = cli(&["inspect", s(&b)]);
            assert!(out.contains("serial SHORT-2"), "{out}");
        }
    }
    // not ASCII: refused with the reason
    let p = dir.join("named.csv");
    std::fs::write(&p, text.replace("# unit=PAPER-UNIT", "# unit=Gerät-7")).unwrap();
    let (code, _, err) = cli(&["fit", s(&p), "--out", s(&b), "--force", "--model", "poly"]);
    assert_eq!(code, 1);
    assert!(
        err.contains("printable ASCII") && err.contains("--serial"),
        "{err}"
    );
}

/// inspect shows every in-flight term of a blob, in text and JSON, and says when there
/// are none.
#[test]
fn inspect_shows_every_in_flight_term() {
    use firmware_core::blob::example_blob;
    use firmware_core::temperature::Physics;
    use tests::cli;
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let write = |b: &firmware_core::blob::Blob, name: &str| {
        let mut buf = [0u8; firmware_core::blob::MAX_BLOB_LEN];
        let n = b.encode(&mut buf).unwrap();
        let p = dir.join(name);
        std::fs::write(&p, &buf[..n]).unwrap();
        p
    };
    let plain = write(&example_blob(), "plain.blob");
    let (code, out, _) = cli(&["inspect", s(&plain)]);
    assert_eq!(code, 0);
    assert!(out.contains("in-flight terms: none"), "{out}");
    let (_, out, _) = cli(&["inspect", s(&plain), "--json"]);
    let j: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert!(j["physics"].is_null());

    let mut b = example_blob();
    b.output_unit = firmware_core::blob::OutputUnit::MetrePerSecond2;
    b.calibration.physics = Some(Physics {
        lag_tau_s: 250.0,
        rate: [0.011, -0.012, 0.013],
        rate_tau_s: 30.0,
        hysteresis: [1.1e-4, -1.2e-4, 1.3e-4],
        hysteresis_threshold_c: 0.5,
        hysteresis_initial: -1.0,
        k2: [2.1e-4, -2.2e-4, 2.3e-4],
        asymmetry: [3.1e-4, -3.2e-4, 3.3e-4],
        warmup: [4.1e-4, -4.2e-4, 4.3e-4],
        warmup_tau_s: 3600.0,
    });
    let p = write(&b, "physics.blob");
    let j = cli_json(&["inspect", s(&p), "--json"]);
    let ph = &j["physics"];
    let close = |v: &serde_json::Value, want: f64, rel: f64| {
        let g = v.as_f64().unwrap();
        assert!((g - want).abs() <= rel * want.abs(), "{v} vs {want}");
    };
    for (field, want) in [
        ("rate", [0.011, -0.012, 0.013]),
        ("hysteresis", [1.1e-4, -1.2e-4, 1.3e-4]),
        ("k2", [2.1e-4, -2.2e-4, 2.3e-4]),
        ("asymmetry", [3.1e-4, -3.2e-4, 3.3e-4]),
        ("warmup", [4.1e-4, -4.2e-4, 4.3e-4]),
    ] {
        for (i, w) in want.iter().enumerate() {
            close(&ph[field][i], *w, 1e-6);
        }
    }
    close(&ph["hysteresis_threshold_c"], 0.5, 0.0);
    close(&ph["hysteresis_initial"], -1.0, 0.0);
    // the time constants, in seconds as the blob stores them (format 4)
    close(&ph["lag_tau_s"], 250.0, 0.0);
    close(&ph["rate_tau_s"], 30.0, 0.0);
    close(&ph["warmup_tau_s"], 3600.0, 0.0);
    assert_eq!(j["output_unit"], "m/s2");
    assert_eq!(j["format_version"], 4);
    let (_, text, _) = cli(&["inspect", s(&p)]);
    for term in [
        "thermal_lag",
        "temp_rate",
        "hysteresis",
        "nonlinearity_k2",
        "scale_asymmetry",
        "warmup_drift",
    ] {
        assert!(text.contains(term), "{term} missing:\n{text}");
    }
    assert!(
        text.contains("2.1000e-4") && text.contains("-4.2000e-4"),
        "{text}"
    );
}

/// Poses of unknown orientation mixed with known ones: their directions are
/// estimated with the coefficients (the known poses fix the frame), the blob passes on
/// the verification positions, and diagnose and identify estimate them too. A vector
/// half given is an error naming the file, the line and the field.
#[test]
fn known_and_unknown_poses_mix_in_one_recording() {
    use tests::{cli, synthetic_csv, PAPER_T0, TP};
    let truth = |t: f64| {
        let mut c = PAPER_T0;
        for (i, v) in c.iter_mut().enumerate() {
            if i < 3 {
                *v *= 1.0 + 1e-4 * (t - 20.0);
            } else if i >= 9 {
                *v += 1e-4 * (t - 20.0);
            }
        }
        c
    };
    // 14 poses spread over the sphere (a golden spiral), orientation not given
    let extra: Vec<(String, [f64; 3])> = (0..14)
        .map(|k| {
            let z = 1.0 - (2.0 * k as f64 + 1.0) / 14.0;
            let r = (1.0 - z * z).sqrt();
            let phi = k as f64 * 2.399_963;
            (format!("X{k:02}"), [r * phi.cos(), r * phi.sin(), z])
        })
        .collect();
    let s25 = 25f64.to_radians();
    let pp = [
        ("PP1", [s25.sin(), 0.0, s25.cos()]),
        ("PP3", [-s25.sin(), 0.0, -s25.cos()]),
    ];
    let mut pos: Vec<(&str, [f64; 3])> = TP.to_vec();
    pos.extend(extra.iter().map(|(n, v)| (n.as_str(), *v)));
    pos.extend(pp);
    let csv = synthetic_csv(&[-20.0, 20.0, 60.0], &truth, &pos, 30, 1e-5, 0.0, 21);
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let rec = dir.join("rec.csv");
    std::fs::write(&rec, csv).unwrap();
    let positions = dir.join("pos.csv");
    let mut p = String::from("name,fx,fy,fz\n");
    for (n, _) in &extra {
        p.push_str(&format!("{n},,,\n"));
    }
    std::fs::write(&positions, &p).unwrap();
    let b = dir.join("u.blob");
    let j = cli_json(&[
        "fit",
        s(&rec),
        "--positions",
        s(&positions),
        "--out",
        s(&b),
        "--json",
    ]);
    let o = &j["orientations"];
    assert_eq!(o["estimated"], 14, "{o}");
    assert!(o["frame"].is_null(), "the known poses fix the frame: {o}");
    for est in o["poses"].as_array().unwrap() {
        let name = est["name"].as_str().unwrap();
        let want = extra.iter().find(|(n, _)| n == name).unwrap().1;
        let got: Vec<f64> = est["a"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        let cos: f64 = (0..3).map(|i| got[i] * want[i]).sum();
        let angle = cos.min(1.0).acos();
        let sigma = est["sigma_rad"].as_f64().unwrap();
        // noise 1e-5 V on 0.55 V/g over 90 samples: about 2e-6 rad
        assert!(
            angle < 2e-5 && angle < 6.0 * sigma + 1e-7,
            "{name}: {angle:e} rad, sigma {sigma:e}"
        );
    }
    let (code, out, err) = cli(&[
        "verify",
        s(&rec),
        "--positions",
        s(&positions),
        "--blob",
        s(&b),
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("acceptance: pass"), "{out}");
    for cmd in ["identify", "diagnose"] {
        let (code, _, err) = cli(&[cmd, s(&rec), "--positions", s(&positions)]);
        assert_eq!(code, 0, "{cmd}: {err}");
        assert!(
            err.contains("14 poses of unknown orientation estimated"),
            "{cmd}: {err}"
        );
    }
    // half a vector is a damaged line, not an unknown pose
    std::fs::write(&positions, format!("{p}X99,0.5,,\n")).unwrap();
    let (code, _, err) = cli(&[
        "fit",
        s(&rec),
        "--positions",
        s(&positions),
        "--out",
        s(&b),
        "--force",
    ]);
    assert_eq!(code, 1);
    assert!(err.contains("pos.csv:16") && err.contains("`fy`"), "{err}");
}

/// A dwell-averaged recording (one row per position and temperature, made here by
/// averaging the twin's static dwells) works in fit and verify: one warning for its
/// short dwells, its noise from the fit's residual scatter (said so), and about the
/// same verification |dg| as the full recording.
#[test]
fn dwell_averaged_recordings_work_and_say_where_their_noise_comes_from() {
    use host_fit::data::positions::Positions;
    use host_fit::data::recording::Recording;
    use tests::cli;
    let (tmp, rec) = paper_recording(15);
    let dir = tmp.path();
    let full = Recording::read(&rec, Positions::default()).unwrap();
    let mut text =
        String::from("# unit=PAPER-UNIT\n# t0_c=20\nt_s,position,temp_c,ux_v,uy_v,uz_v\n");
    for d in full.dwells.iter().filter(|d| d.temp_span_c <= 0.5) {
        let rows = full.dwell_rows(d);
        let t = rows.iter().map(|r| r.t_s).sum::<f64>() / rows.len() as f64;
        text.push_str(&format!(
            "{t:.1},{},{:.5},{:.9},{:.9},{:.9}\n",
            full.positions.name(d.position),
            d.temp_c,
            d.u_mean[0],
            d.u_mean[1],
            d.u_mean[2]
        ));
    }
    let avg = dir.join("averaged.csv");
    std::fs::write(&avg, text).unwrap();
    // no cache step: an averaged recording jumps from dwell to dwell by less than the
    // default 0.1 C step, and a cached N(T) would then lag by up to that much
    let worst = |r: &std::path::Path, b: &std::path::Path| {
        let (code, out, err) = cli(&["fit", s(r), "--out", s(b), "--json", "--update-step", "0"]);
        assert_eq!(code, 0, "{err}");
        let j: serde_json::Value = serde_json::from_str(&out).unwrap();
        let v = cli_json(&["verify", s(r), "--blob", s(b), "--json"]);
        let w = v["dwells"]
            .as_array()
            .unwrap()
            .iter()
            .map(|d| d["dg_mg"].as_f64().unwrap().abs())
            .fold(0.0, f64::max);
        (j, err, w)
    };
    let (j, err, w_avg) = worst(&avg, &dir.join("avg.blob"));
    let (_, _, w_full) = worst(&rec, &dir.join("full.blob"));
    assert_eq!(err.matches("fewer than 3 samples").count(), 1, "{err}");
    assert!(
        !err.contains("has 1 samples"),
        "no warning per dwell: {err}"
    );
    assert!(
        j["noise_source"]
            .as_str()
            .unwrap()
            .contains("residual scatter"),
        "{}",
        j["noise_source"]
    );
    assert!(
        j["predicted_error"]["noise_source"].is_null(),
        "stated once: {j}"
    );
    let sig = j["predicted_error"]["points"][0]["dg_1sigma_mg"]
        .as_f64()
        .unwrap();
    assert!(sig.is_finite() && sig > 0.0 && sig < 0.05, "{sig}");
    assert_eq!(j["model"], "poly4");
    // the dwell means carry the same information as the samples
    assert!(
        (w_avg - w_full).abs() < 0.005,
        "averaged {w_avg:.4} mg, full {w_full:.4} mg"
    );
}

/// `--unknown-orientations` treats a positions file's vectors as unknown: the wrist
/// recording's vectors (themselves estimates) are estimated afresh, the frame by
/// convention; without the flag they are taken as given.
#[test]
fn the_unknown_orientations_flag_forgets_the_files_vectors() {
    use tests::cli;
    let real = tests::repo().join("../shared/real/ggir-wrist");
    let (rec, pos) = (real.join("recording.csv"), real.join("positions.csv"));
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let b = dir.join("g.blob");
    let run = |flag: bool| {
        let mut a = vec![
            "fit",
            s(&rec),
            "--positions",
            s(&pos),
            "--out",
            s(&b),
            "--force",
            "--json",
        ];
        if flag {
            a.push("--unknown-orientations");
        }
        let (code, out, err) = cli(&a);
        assert_eq!(code, 0, "{err}");
        serde_json::from_str::<serde_json::Value>(&out).unwrap()
    };
    let given = run(false);
    assert!(given["orientations"].is_null());
    let estimated = run(true);
    assert_eq!(estimated["orientations"]["estimated"], 1050);
    assert!(estimated["orientations"]["frame"]
        .as_str()
        .unwrap()
        .contains("convention"));
    // K(T0) lower triangular: the convention's zeros
    for c in ["kxy", "kxz", "kyz"] {
        assert_eq!(estimated["temperature_model"]["at_t0"][c], 0.0, "{c}");
    }
}

/// Where the sensing elements lag the temperature sensor (300 s), the windows taken
/// through the ramps read the coefficients at the wrong temperature: the static default
/// leaves them out and compensates better than the same models fitted with them in.
#[test]
fn ramps_do_not_bias_the_static_route_when_the_unit_lags() {
    let mut cfg = host_fit::simulate::SimConfig::default();
    cfg.effects.thermal_lag = Some(host_fit::simulate::PerAxis { value: [300.0; 3] });
    let (csv, _) = tests::twins::recording("lag", &cfg);
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let p = dir.join("rec.csv");
    std::fs::write(&p, csv).unwrap();
    let run = |args: &[&str]| figures::fit_verify(dir, &p, args).worst_mg;
    let stat = run(&["--route", "static"]);
    let joint4 = run(&["--model", "poly", "--order", "4", "--route", "joint"]);
    let pwl = run(&["--model", "pwl"]);
    let pwl_joint = run(&["--model", "pwl", "--route", "joint"]);
    // the default sees the dwells settle and takes the dynamic route (route_choice.rs)
    let default = run(&[]);
    println!(
        "static {stat:.4}, joint poly4 {joint4:.4}, pwl {pwl:.4}, joint pwl {pwl_joint:.4}, default {default:.4} mg"
    );
    assert!(
        stat < 0.9 * joint4,
        "static {stat:.4} vs joint poly4 {joint4:.4}"
    );
    assert!(default <= stat, "default {default:.4} vs static {stat:.4}");
    assert!(
        pwl < 0.7 * pwl_joint,
        "pwl {pwl:.4} vs joint pwl {pwl_joint:.4}"
    );
}
