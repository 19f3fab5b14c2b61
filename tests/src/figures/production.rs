//! Production calibration's figures: the data-chosen model against the plain least
//! squares, the predicted error's coverage, unknown orientations on the wrist recording,
//! one temperature.
use crate::{cli, cli_json, repo, s, twins};
use std::path::Path;

/// One twin compared: the default fit's chosen model and worst verification |dg|, the
/// same for `--model poly --order 3` on the static route and on the joint route (ramps
/// in), and the plain least-squares cubic's; all mg.
#[derive(Debug, Clone)]
pub struct ChoiceRow {
    /// The twin.
    pub name: String,
    /// The model the default fit chose.
    pub model: String,
    /// Its worst |dg|.
    pub default: f64,
    /// The in-dwell noise of a verification dwell's mean, in g (1 sigma, the noisiest
    /// axis), by the default fit's JSON.
    pub dwell_noise_mg: f64,
    /// The static cubic's worst |dg|.
    pub static_cubic: f64,
    /// The joint cubic's worst |dg|.
    pub joint_cubic: f64,
    /// The plain least-squares cubic's worst |dg|.
    pub plain: f64,
}

/// What `fit ARGS` then `verify` gave.
pub struct FitVerified {
    /// The model the fit reports.
    pub model: String,
    /// The worst verification |dg|, mg.
    pub worst_mg: f64,
    /// The in-dwell noise of a verification dwell's mean (1 sigma, the noisiest axis: its
    /// per-sample noise over its scale factor and the root of the dwell's samples), mg.
    pub dwell_noise_mg: f64,
}

/// `fit ARGS` then `verify` on the recording `rec` (in `dir`).
pub fn fit_verify(dir: &Path, rec: &Path, args: &[&str]) -> FitVerified {
    let blob = dir.join("unit.blob");
    let mut a = vec!["fit", s(rec), "--out", s(&blob), "--force", "--json"];
    a.extend_from_slice(args);
    let (code, out, err) = cli(&a);
    assert_eq!(code, 0, "fit {args:?}: {err}");
    let j: serde_json::Value = serde_json::from_str(&out).unwrap();
    let (code, out, err) = cli(&["verify", s(rec), "--blob", s(&blob), "--json"]);
    assert!(code == 0 || code == 3, "verify: {err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let worst = v["dwells"]
        .as_array()
        .unwrap()
        .iter()
        .map(|d| d["dg_mg"].as_f64().unwrap().abs())
        .fold(0.0, f64::max);
    let samples = j["predicted_error"]["dwell_samples"]
        .as_f64()
        .unwrap_or(f64::NAN);
    let dwell_noise_mg = ["kxx", "kyy", "kzz"]
        .iter()
        .enumerate()
        .map(|(i, k)| {
            // NaN on the dynamic route, whose JSON states its floor, not these
            let sigma_v = j["noise_sigma"][i].as_f64().unwrap_or(f64::NAN);
            let k_v_per_g = j["temperature_model"]["at_t0"][k]
                .as_f64()
                .unwrap_or(f64::NAN)
                .abs();
            sigma_v / k_v_per_g / samples.sqrt() * 1e3
        })
        .fold(0.0, f64::max);
    FitVerified {
        model: j["model"].as_str().unwrap().to_string(),
        worst_mg: worst,
        dwell_noise_mg,
    }
}

/// The default `fit` against the plain least-squares cubic on every twin.
pub fn model_choice() -> (Vec<ChoiceRow>, String) {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let mut rows = Vec::new();
    for (name, cfg) in twins::all() {
        let (csv, rec) = twins::recording(name, &cfg);
        let p = dir.join("rec.csv");
        std::fs::write(&p, csv).unwrap();
        let default = fit_verify(dir, &p, &[]);
        let cubic = ["--model", "poly", "--order", "3"];
        let stat3 = fit_verify(dir, &p, &cubic);
        let joint3 = fit_verify(dir, &p, &[&cubic[..], &["--route", "joint"]].concat());
        rows.push(ChoiceRow {
            name: name.to_string(),
            model: default.model,
            default: default.worst_mg,
            dwell_noise_mg: default.dwell_noise_mg,
            static_cubic: stat3.worst_mg,
            joint_cubic: joint3.worst_mg,
            plain: twins::plain_cubic_max_dg_mg(&rec),
        });
    }
    let mut t = format!(
        "max |dg| in the verification dwells (PP1..PP6 at every stop), mg\n{:<42} {:<28} {:>8} {:>11} {:>11} {:>10}\n",
        "twin recording", "default fit: chosen model", "default", "poly3 stat", "poly3 joint", "plain LS3"
    );
    for r in &rows {
        let model = if r.model.len() > 28 {
            format!("{}...", &r.model[..25])
        } else {
            r.model.clone()
        };
        t.push_str(&format!(
            "{:<42} {:<28} {:>8.4} {:>11.4} {:>11.4} {:>10.4}\n",
            r.name, model, r.default, r.static_cubic, r.joint_cubic, r.plain
        ));
    }
    let better = rows.iter().filter(|r| r.default <= r.plain).count();
    t.push_str(&format!(
        "default fit at or below the plain least-squares cubic on {better} of {} recordings",
        rows.len()
    ));
    (rows, t)
}

/// The predicted 1-sigma of every verification dwell's |dg| (the fit's covariance
/// propagated, and the dwell's own noise) against the |dg| it shows, on the twins:
/// per twin (name, dwells, within 1 sigma, within 2 sigma), and the text.
pub fn coverage() -> (Vec<(String, usize, usize, usize)>, String) {
    use firmware_core::compensate::Method;
    use host_fit::data::positions::Role;
    use host_fit::fit::pipeline::{fit_chosen, ModelRequest};
    use host_fit::fit::predict::sigma_dwell;
    let mut rows = Vec::new();
    for (name, cfg) in twins::all() {
        let (_, rec) = twins::recording(name, &cfg);
        let req = ModelRequest::default();
        let oc = fit_chosen(&rec, &req).unwrap();
        // no cache step: the firmware then evaluates the model at every sample's
        // temperature, and the comparison is of the model alone
        let cal = oc.fit.calibration(0.0, false);
        let (blob, _, _) = host_fit::blob::build_blob("T", &rec.output_unit, &cal).unwrap();
        let check = |p: usize| rec.positions.has_role(p, Role::Verification);
        let v = host_fit::verify::verify(&rec, &blob, Method::CorrectConstants, &check).unwrap();
        let (mut n, mut one, mut two) = (0, 0, 0);
        for d in &v.dwells {
            let p = rec.positions.index(&d.position).unwrap();
            let sigma = sigma_dwell(
                &oc.fit,
                &oc.noise,
                d.temp_c,
                rec.positions.vector(p),
                d.samples,
            ) * 1e3;
            n += 1;
            one += usize::from(d.dg_mg.abs() <= sigma);
            two += usize::from(d.dg_mg.abs() <= 2.0 * sigma);
        }
        rows.push((name.to_string(), n, one, two));
    }
    let mut t = String::from(
        "verification dwells whose |dg| lies within the predicted 1 and 2 sigma\ntwin recording                               dwells   1 sigma   2 sigma\n",
    );
    let (mut n, mut one, mut two) = (0, 0, 0);
    for r in &rows {
        t.push_str(&format!(
            "{:<42} {:>8} {:>8.0}% {:>8.0}%\n",
            r.0,
            r.1,
            100.0 * r.2 as f64 / r.1 as f64,
            100.0 * r.3 as f64 / r.1 as f64
        ));
        (n, one, two) = (n + r.1, one + r.2, two + r.3);
    }
    t.push_str(&format!(
        "{:<42} {:>8} {:>8.0}% {:>8.0}%   (a normal error: 68% and 95%)",
        "all",
        n,
        100.0 * one as f64 / n as f64,
        100.0 * two as f64 / n as f64
    ));
    (rows, t)
}

/// `fit` and `verify` on ../shared/real/ggir-wrist with every orientation unknown
/// (a positions file of empty vectors) and every 10th dwell held out as a
/// verification position: the rms of |a| - 1 over the held-out dwells (mg), the
/// model, and the line quoting them.
pub fn ggir_wrist() -> (f64, String, String) {
    let real = repo().join("../shared/real/ggir-wrist");
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let given = std::fs::read_to_string(real.join("positions.csv")).unwrap();
    let mut pos = String::from("name,fx,fy,fz,role\n");
    for (k, line) in given.lines().skip(1).enumerate() {
        let name = line.split(',').next().unwrap();
        let role = if (k + 1) % 10 == 0 {
            "verification"
        } else {
            "calibration"
        };
        pos.push_str(&format!("{name},,,,{role}\n"));
    }
    let p = dir.join("unknown.csv");
    std::fs::write(&p, pos).unwrap();
    let (rec, pos) = (real.join("recording.csv"), p.to_str().unwrap().to_string());
    let blob = dir.join("ggir.blob");
    let j = cli_json(&[
        "fit",
        rec.to_str().unwrap(),
        "--positions",
        &pos,
        "--out",
        blob.to_str().unwrap(),
        "--json",
    ]);
    let (code, out, err) = cli(&[
        "verify",
        rec.to_str().unwrap(),
        "--positions",
        &pos,
        "--blob",
        blob.to_str().unwrap(),
        "--json",
    ]);
    assert!(code == 0 || code == 3, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let dg: Vec<f64> = v["dwells"]
        .as_array()
        .unwrap()
        .iter()
        .map(|d| d["dg_mg"].as_f64().unwrap())
        .collect();
    let rms = (dg.iter().map(|x| x * x).sum::<f64>() / dg.len() as f64).sqrt();
    let model = j["model"].as_str().unwrap().to_string();
    let line = format!(
        "{} poses estimated, model {model} (chosen by the data); {} held-out dwells: rms | |a| - 1 | {rms:.2} mg (GGIR's own calibration: 2.92 mg)",
        j["orientations"]["estimated"], dg.len()
    );
    (rms, model, line)
}

/// `fit --json` on ../shared/real/imucal-ferraris (one temperature): the 12
/// coefficients at T0 and the statement, as text.
pub fn imucal() -> (serde_json::Value, String) {
    let rec = repo().join("../shared/real/imucal-ferraris/recording.csv");
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let blob = dir.join("imu.blob");
    let (code, out, err) = cli(&[
        "fit",
        rec.to_str().unwrap(),
        "--out",
        blob.to_str().unwrap(),
        "--force",
        "--json",
    ]);
    assert_eq!(code, 0, "{err}");
    let j: serde_json::Value = serde_json::from_str(&out).unwrap();
    let c = &j["temperature_model"]["at_t0"];
    let mut t = format!(
        "model {}: {}\n",
        j["model"].as_str().unwrap(),
        j["no_temperature_model"].as_str().unwrap_or("-")
    );
    for row in [
        ["kxx", "kxy", "kxz", "u0x"],
        ["kyx", "kyy", "kyz", "u0y"],
        ["kzx", "kzy", "kzz", "u0z"],
    ] {
        t.push_str(
            &row.iter()
                .map(|n| format!("{n} {:>9.5}", c[n].as_f64().unwrap()))
                .collect::<Vec<_>>()
                .join("  "),
        );
        t.push('\n');
    }
    (j, t.trim_end().to_string())
}
