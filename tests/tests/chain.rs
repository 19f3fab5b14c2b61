//! The whole chain through the CLI: recording -> fit -> blob -> inspect -> verify.
use tests::{cli, cli_json, synthetic_csv, PAPER_T0, TP};

fn pp() -> Vec<(&'static str, [f64; 3])> {
    let (s, c) = 25f64.to_radians().sin_cos();
    vec![
        ("PP1", [s, 0.0, c]),
        ("PP2", [0.0, -c, s]),
        ("PP3", [-s, 0.0, -c]),
        ("PP4", [0.0, c, -s]),
        ("PP5", [-c, s, 0.0]),
        ("PP6", [c, -s, 0.0]),
    ]
}

/// Offsets 0.1 mV/C and scale 1e-4/C, linear: a pwl through the stops is exact.
fn truth(t: f64) -> [f64; 12] {
    let mut c = PAPER_T0;
    for (i, v) in c.iter_mut().enumerate() {
        if i < 3 {
            *v *= 1.0 + 1e-4 * (t - 20.0);
        } else if i >= 9 {
            *v += 1e-4 * (t - 20.0) * (1.0 + i as f64 / 10.0);
        }
    }
    c
}

#[test]
fn fit_inspect_verify_and_never_overwrite() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let cal = synthetic_csv(&[-40.0, 20.0, 70.0], &truth, &TP, 20, 2e-6, 0.0, 3);
    // a verification stop near T0 (20 C) too: without one the band near T0 is not judged
    let ver = synthetic_csv(&[-10.0, 22.0, 45.0], &truth, &pp(), 20, 2e-6, 0.0, 4);
    // one recording: the calibration stops, then the verification stops (time shifted)
    let mut text = cal.clone();
    let t_end = 10_000.0;
    for l in ver
        .lines()
        .filter(|l| !l.starts_with('#') && !l.starts_with("t_s"))
    {
        let (t, rest) = l.split_once(',').unwrap();
        text.push_str(&format!("{},{rest}\n", t.parse::<f64>().unwrap() + t_end));
    }
    let rec = dir.join("rec.csv");
    std::fs::write(&rec, text).unwrap();
    let blob = dir.join("unit.blob");
    let _ = std::fs::remove_file(&blob);
    let (r, b) = (rec.to_str().unwrap(), blob.to_str().unwrap());

    let (code, out, err) = cli(&["fit", r, "--model", "pwl", "--out", b, "--json"]);
    assert_eq!(code, 0, "{err}");
    // the noise source is stated once, not again in the prediction in other words
    assert_eq!(out.matches("\"noise_source\"").count(), 1, "{out}");
    let j: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(j["noise_source"], "in-dwell (successive samples)");
    assert!(j["predicted_error"]["noise_source"].is_null(), "{j}");
    assert_eq!(j["route"], "static");
    assert_eq!(j["unit"], "SYN-1");
    assert!(j["f32_departure_g"].as_f64().unwrap() <= 2e-6);
    let bytes = std::fs::read(&blob).unwrap();

    // never overwrite without --force; the file is untouched
    let (code, _, err) = cli(&["fit", r, "--model", "poly", "--order", "1", "--out", b]);
    assert_eq!(code, 1);
    assert!(err.contains("--force"), "{err}");
    assert_eq!(std::fs::read(&blob).unwrap(), bytes);

    let j = cli_json(&["inspect", b, "--json"]);
    assert_eq!(j["serial"], "SYN-1");
    assert_eq!(j["model"], "pwl");
    assert_eq!(j["rows"].as_array().unwrap().len(), 3);

    for method in ["1", "2"] {
        let j = cli_json(&["verify", r, "--blob", b, "--method", method, "--json"]);
        let temps = j["max_by_temperature"].as_array().unwrap();
        assert_eq!(temps.len(), 3, "{j}");
        assert_eq!(j["acceptance"], "pass", "{j}");
        for t in temps {
            let unc = t["max_abs_dg_mg_uncompensated"].as_f64().unwrap();
            let comp = t["max_abs_dg_mg"].as_f64().unwrap();
            if (t["temp_c"].as_f64().unwrap() - 20.0).abs() > 10.0 {
                assert!(unc > 0.5, "the drift is visible uncompensated: {unc}");
            }
            // method 2 keeps its second-order term ||N0 dK|| |e| (~3e-3 x 17.6 mg here)
            let limit = if method == "1" { 0.02 } else { 0.1 };
            println!(
                "method {method} at {:.1} C: uncompensated {unc:.3} mg, compensated {comp:.4} mg",
                t["temp_c"].as_f64().unwrap()
            );
            assert!(comp < limit, "compensated with method {method}: {comp} mg");
        }
        assert_eq!(j["dwells"].as_array().unwrap().len(), 18);
    }
    // an option that does not apply is an error: method 1 has no error model
    let (code, out, err) = cli(&[
        "verify",
        r,
        "--blob",
        b,
        "--method",
        "1",
        "--error-model",
        "simplified",
    ]);
    assert_eq!(code, 1, "{out}");
    assert!(err.contains("--error-model applies to method 2"), "{err}");
    let (code, _, err) = cli(&["verify", r, "--blob", b, "--error-model", "simplified"]);
    assert_eq!(code, 1, "the default method is 1: {err}");
    let j = cli_json(&[
        "verify",
        r,
        "--blob",
        b,
        "--method",
        "2",
        "--error-model",
        "simplified",
        "--json",
    ]);
    assert_eq!(j["method"], "2");

    // corrupt one byte: inspect and verify refuse with the reason
    let mut bad = bytes.clone();
    bad[20] ^= 0x10;
    let badp = dir.join("bad.blob");
    std::fs::write(&badp, bad).unwrap();
    let (code, _, err) = cli(&["inspect", badp.to_str().unwrap()]);
    assert_eq!(code, 1);
    assert!(
        err.contains("bad.blob") && err.contains("CRC-32 mismatch"),
        "{err}"
    );

    // --force replaces it; the per-stop route works too
    let (code, _, err) = cli(&[
        "fit", r, "--model", "poly", "--order", "2", "--route", "per-stop", "--out", b, "--force",
    ]);
    assert_eq!(code, 0, "{err}");
    assert_ne!(std::fs::read(&blob).unwrap(), bytes);
}
