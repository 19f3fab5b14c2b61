//! The diagnosis's figures: the extended model in firmware, the real recordings
//! diagnosed, and the long blind suite.
use super::joined;
use crate::{cli, cli_json, repo};

/// The extended model of a recording with K2, rate and warm-up (3x nominal) written by
/// `diagnose --out` and compensated through firmware-core: |dg| of every dwell with
/// the physics terms and with the same tables alone (mg), and the line quoting them.
pub fn physics_blob() -> (Vec<f64>, Vec<f64>, String) {
    use firmware_core::blob::Blob;
    use firmware_core::compensate::Method;
    use host_fit::data::positions::Positions;
    use host_fit::data::recording::Recording;
    use host_fit::diagnose::EffectId;
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let case = host_fit::blind::Case::catalogue(
        vec![
            EffectId::NonlinearityK2,
            EffectId::TempRate,
            EffectId::WarmupDrift,
        ],
        3.0,
        5,
    );
    let sim = host_fit::simulate::simulate(&host_fit::blind::configure(&case), |_| {}).unwrap();
    let p = dir.join("rec.csv");
    std::fs::write(&p, &sim.csv).unwrap();
    let blob_path = dir.join("unit.blob");
    let j = cli_json(&[
        "diagnose",
        p.to_str().unwrap(),
        "--out",
        blob_path.to_str().unwrap(),
        "--json",
        "--force",
    ]);
    for e in &case.effects {
        assert!(
            j["findings"]
                .as_array()
                .unwrap()
                .iter()
                .any(|f| f["effect"] == e.as_str()),
            "{e} not found: {j}"
        );
    }
    assert_eq!(j["blob"]["physics"], true);
    let with = Blob::decode(&std::fs::read(&blob_path).unwrap()).unwrap();
    let mut without = with.clone();
    without.calibration.physics = None;
    let rec = Recording::from_reader(&p, sim.csv.as_bytes(), Positions::default()).unwrap();
    let all = |_: usize| true;
    let dg = |b: &Blob| -> Vec<f64> {
        let v = host_fit::verify::verify(&rec, b, Method::CorrectConstants, &all).unwrap();
        v.dwells.iter().map(|d| d.dg_mg.abs()).collect()
    };
    let (a, b) = (dg(&with), dg(&without));
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let worst = |v: &[f64]| v.iter().copied().fold(0.0, f64::max);
    let line = format!(
        "{} dwells: mean |dg| {:.4} mg with the physics terms, {:.4} mg with the tables alone; worst {:.4} mg and {:.4} mg",
        a.len(),
        mean(&a),
        mean(&b),
        worst(&a),
        worst(&b)
    );
    (a, b, line)
}

/// `host-fit diagnose` on ../shared/real/cats-tag: its text output.
pub fn cats_tag() -> String {
    let rec = repo().join("../shared/real/cats-tag/recording.csv");
    let pos = repo().join("../shared/real/cats-tag/positions.csv");
    let (code, out, err) = cli(&[
        "diagnose",
        rec.to_str().unwrap(),
        "--positions",
        pos.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    out.trim_end().to_string()
}

/// `host-fit diagnose --json` of the three real recordings, one line each: verdict,
/// findings (and whether each reproduced on both halves), ambiguities, residual over
/// the floor, max |dg| and the held-out chi-square, before and after.
pub fn real_recordings() -> (Vec<serde_json::Value>, String) {
    let runs = [
        ("cats-tag", vec!["--positions", "{dir}/positions.csv"]),
        (
            "ggir-wrist",
            vec![
                "--positions",
                "{dir}/positions.csv",
                "--unknown-orientations",
            ],
        ),
        ("imucal-ferraris", vec![]),
    ];
    let mut s = String::from(
        "recording         verdict            residual/floor   max |dg| mg     held-out chi2 (floor units)\n",
    );
    let mut all = Vec::new();
    for (name, extra) in runs {
        let j = crate::real_diagnosis(name, &extra);
        let (b, f) = (&j["baseline"], &j["final"]);
        let num = |v: &serde_json::Value, k: &str| v[k].as_f64().unwrap_or(f64::NAN);
        s.push_str(&format!(
            "{:<17} {:<18} {:>6.1} -> {:<6.1} {:>5.2} -> {:<5.2} {:>10.0} -> {:.0}\n",
            name,
            j["verdict"].as_str().unwrap_or("?"),
            num(b, "residual_rms_over_noise"),
            num(f, "residual_rms_over_noise"),
            num(b, "max_abs_dg_mg"),
            num(f, "max_abs_dg_mg"),
            num(f, "heldout_chi2_before"),
            num(f, "heldout_chi2_after"),
        ));
        for x in j["findings"].as_array().into_iter().flatten() {
            s.push_str(&format!(
                "    finding: {} on {} ({})\n",
                x["effect"].as_str().unwrap_or("?"),
                joined(&x["axes"], ","),
                if x["reproduced"] == true {
                    "reproduced on both halves"
                } else {
                    "not reproduced on both halves"
                }
            ));
        }
        for x in j["ambiguous"].as_array().into_iter().flatten() {
            s.push_str(&format!(
                "    ambiguous: {} (needs {})\n",
                joined(&x["candidates"], " or "),
                x["needed"].as_str().unwrap_or("?")
            ));
        }
        for q in j["quality"].as_array().into_iter().flatten() {
            s.push_str(&format!(
                "    data: {}\n",
                q["kind"].as_str().unwrap_or("?")
            ));
        }
        all.push(j);
    }
    (all, s.trim_end().to_string())
}

/// `host-fit blind --long`: the summary after the per-case lines.
pub fn blind_long() -> String {
    let (code, out, err) = cli(&["blind", "--long"]);
    assert_eq!(code, 0, "{err}");
    let at = out.find("confusion").unwrap_or(0);
    out[at..].trim_end().to_string()
}
