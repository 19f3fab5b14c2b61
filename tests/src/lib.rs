//! Helpers for the end-to-end tests: paths to the shared data and a tiny synthetic
//! six-position recording writer (the full digital twin is `host_fit::simulate`).
use host_fit::rng::Rng;
use std::fmt::Write;
use std::path::PathBuf;

/// The repository root.
pub fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Run the CLI in-process; returns (exit code, stdout, stderr).
pub fn cli(args: &[&str]) -> (i32, String, String) {
    let mut out = Vec::new();
    let mut err = Vec::new();
    let argv = std::iter::once("host-fit").chain(args.iter().copied());
    let code = host_fit::cli::run(argv, &mut out, &mut err);
    (
        code,
        String::from_utf8_lossy(&out).into_owned(),
        String::from_utf8_lossy(&err).into_owned(),
    )
}

/// `host-fit ARGS` that must succeed (exit 0, else the test fails with its stderr), its
/// stdout parsed as JSON.
pub fn cli_json(args: &[&str]) -> serde_json::Value {
    let (code, out, err) = cli(args);
    assert_eq!(code, 0, "host-fit {}: {err}", args.join(" "));
    serde_json::from_str(&out)
        .unwrap_or_else(|e| panic!("host-fit {}: not JSON ({e}): {out}", args.join(" ")))
}

/// `host-fit diagnose --json` of `../shared/real/NAME/recording.csv`; `{dir}` in the extra
/// arguments is that recording's folder.
pub fn real_diagnosis(name: &str, extra: &[&str]) -> serde_json::Value {
    let rec = repo().join(format!("../shared/real/{name}/recording.csv"));
    assert!(
        rec.exists(),
        "the shared real recording is missing: {}",
        rec.display()
    );
    let mut args = vec![
        "diagnose".to_string(),
        rec.display().to_string(),
        "--json".into(),
    ];
    args.extend(extra.iter().map(|s| {
        s.replace(
            "{dir}",
            &repo()
                .join(format!("../shared/real/{name}"))
                .display()
                .to_string(),
        )
    }));
    let (code, out, err) = cli(&args.iter().map(String::as_str).collect::<Vec<_>>());
    assert_eq!(code, 0, "{err}");
    serde_json::from_str(&out).unwrap()
}

/// The output of a unit with coefficients `c` (canonical order) in position `a`.
pub fn forward(c: &[f64; 12], a: [f64; 3]) -> [f64; 3] {
    let k = [[c[0], c[3], c[4]], [c[5], c[1], c[6]], [c[7], c[8], c[2]]];
    std::array::from_fn(|i| k[i][0] * a[0] + k[i][1] * a[1] + k[i][2] * a[2] + c[9 + i])
}

/// A recording of stops at `temps` for a unit with `coeffs(T)`: at each, the positions `pos`
/// with `n` samples each and Gaussian noise `sigma` (V); temperature constant per stop
/// plus `drift_per_dwell` C per dwell.
pub fn synthetic_csv(
    temps: &[f64],
    coeffs: &dyn Fn(f64) -> [f64; 12],
    pos: &[(&str, [f64; 3])],
    n: usize,
    sigma: f64,
    drift_per_dwell: f64,
    seed: u64,
) -> String {
    let mut rng = Rng::new(seed);
    let mut s = String::from(
        "# format=at-recording/1\n# unit=SYN-1\n# t0_c=20\nt_s,position,temp_c,ux_v,uy_v,uz_v\n",
    );
    let mut t = 0.0;
    for temp in temps {
        for (d, (name, a)) in pos.iter().enumerate() {
            let tc = temp + drift_per_dwell * d as f64;
            let u = forward(&coeffs(tc), *a);
            for _ in 0..n {
                let _ = writeln!(
                    s,
                    "{t},{name},{tc:.4},{:.9},{:.9},{:.9}",
                    u[0] + sigma * rng.normal(),
                    u[1] + sigma * rng.normal(),
                    u[2] + sigma * rng.normal()
                );
                t += 1.0;
            }
            let _ = writeln!(s, "{t},-,{temp:.4},0,0,0");
            t += 1.0;
        }
    }
    s
}

/// TP1..TP6 of model.md.
pub const TP: [(&str, [f64; 3]); 6] = [
    ("TP1", [0.0, 0.0, 1.0]),
    ("TP2", [0.0, -1.0, 0.0]),
    ("TP3", [0.0, 0.0, -1.0]),
    ("TP4", [0.0, 1.0, 0.0]),
    ("TP5", [-1.0, 0.0, 0.0]),
    ("TP6", [1.0, 0.0, 0.0]),
];

/// The paper's Table 1 row at +20 C.
pub const PAPER_T0: [f64; 12] = [
    -0.55060863,
    -0.54854890,
    -0.54859224,
    -0.00051742,
    0.01639328,
    -0.01322881,
    -0.00066841,
    -0.01466957,
    -0.00035441,
    0.00449084,
    -0.00442299,
    -0.00347099,
];

pub mod time_true;

/// The digital twin's recordings with varied truth and nuisances, for the tests of the
/// data-chosen model (none of them was used to tune it), and the plain least-squares
/// fit they are compared with.
pub mod twins {
    use host_fit::data::positions::{Positions, Role};
    use host_fit::data::recording::{Recording, MAX_DWELL_DRIFT_C};
    use host_fit::simulate::{
        simulate, Curvature, SimConfig, TrueUnit, PAPER_UNIT, PAPER_UNIT_TEMPS,
    };
    use nalgebra::{DMatrix, DVector, Matrix3, Vector3};
    use std::path::Path;

    fn seeded(seed: u64) -> SimConfig {
        SimConfig {
            seed,
            ..SimConfig::default()
        }
    }

    /// A twin whose truth is the table `rows` at `temps`, interpolated by `interp`.
    fn table(seed: u64, temps: Vec<f64>, rows: Vec<[f64; 12]>, interp: &str) -> SimConfig {
        let mut c = seeded(seed);
        c.unit.model = "table".into();
        c.unit.temps_c = temps;
        c.unit.coeffs = rows;
        c.unit.interp = interp.into();
        c
    }

    /// The twins: (name, configuration).
    pub fn all() -> Vec<(&'static str, SimConfig)> {
        let paper = TrueUnit::new(&SimConfig::default()).unwrap();
        let mut out = vec![
            ("paper unit, seed 1", seeded(1)),
            ("paper unit, seed 2", seeded(2)),
            ("paper unit, seed 3", seeded(3)),
        ];
        // a cubic: the polynomial through four of the paper unit's rows
        let idx = [0usize, 1, 3, 4];
        out.push((
            "cubic truth",
            table(
                4,
                idx.iter().map(|i| PAPER_UNIT_TEMPS[*i]).collect(),
                idx.iter().map(|i| PAPER_UNIT[*i]).collect(),
                "poly",
            ),
        ));
        // piecewise-linear with its kinks between the stops (-25, 5, 32 C)
        let kinks = [-40.0, -25.0, 5.0, 32.0, 70.0];
        let rows = kinks
            .iter()
            .enumerate()
            .map(|(k, t)| {
                let mut r = paper.coeffs(*t);
                let s = if k % 2 == 1 { 1.0 } else { -1.0 };
                if (1..4).contains(&k) {
                    for (c, v) in r.iter_mut().enumerate() {
                        *v += if c >= 9 { s * 1e-3 } else { s * 5e-4 * *v };
                    }
                }
                r
            })
            .collect();
        out.push((
            "pwl truth, kinks off the stops",
            table(5, kinks.to_vec(), rows, "pwl"),
        ));
        let mut wavy = seeded(6);
        wavy.effects.temp_curvature = Some(Curvature {
            u0_v: [3e-4, -2e-4, 2e-4],
            k_rel: [2e-4, 1e-4, -2e-4],
            period_c: 37.0,
        });
        out.push(("outside every family (sin, 37 C period)", wavy));
        let mut noisy = seeded(7);
        noisy.unit.noise_v *= 5.0;
        out.push(("paper unit, 5x the noise", noisy));
        let mut missing = seeded(8);
        missing.schedule.stops[1].positions = Some(
            [
                "TP1", "TP2", "TP3", "TP5", "TP6", "PP1", "PP2", "PP3", "PP4", "PP5", "PP6",
            ]
            .iter()
            .map(|s| s.to_string())
            .collect(),
        );
        out.push(("paper unit, TP4 missing at -10 C", missing));
        let mut ramps = seeded(9);
        for s in &mut ramps.schedule.stops {
            s.ramp_c_per_min = 3.0;
            s.soak_s = 900.0;
        }
        out.push(("paper unit, 3 C/min ramps, short soaks", ramps));
        out
    }

    /// The recording of a twin.
    pub fn recording(name: &str, cfg: &SimConfig) -> (String, Recording) {
        let sim = simulate(cfg, |_| {}).unwrap();
        let rec = Recording::from_reader(Path::new(name), sim.csv.as_bytes(), Positions::default())
            .unwrap();
        (sim.csv, rec)
    }

    /// The plain least-squares fit of the cubic model over the TP dwells at their own
    /// temperatures (every dwell whose temperature spans at most 0.5 C, its mean at its
    /// mean temperature, unit weights), then formula (13) at every verification dwell
    /// (dwell mean, f64): the largest |dg|, mg.
    pub fn plain_cubic_max_dg_mg(rec: &Recording) -> f64 {
        let x = |t: f64| (t - rec.t0_c) / 50.0;
        let phi = |t: f64| [1.0, x(t), x(t).powi(2), x(t).powi(3)];
        let dwells: Vec<_> = rec
            .dwells
            .iter()
            .filter(|d| {
                rec.positions.has_role(d.position, Role::Calibration)
                    && d.temp_span_c <= MAX_DWELL_DRIFT_C
            })
            .collect();
        let mut theta = Vec::new();
        for axis in 0..3 {
            let mut a = DMatrix::zeros(dwells.len(), 16);
            let mut b = DVector::zeros(dwells.len());
            for (r, d) in dwells.iter().enumerate() {
                let v = rec.positions.vector(d.position);
                let g = [v[0], v[1], v[2], 1.0];
                for j in 0..4 {
                    for (k, f) in phi(d.temp_c).iter().enumerate() {
                        a[(r, j * 4 + k)] = g[j] * f;
                    }
                }
                b[r] = d.u_mean[axis];
            }
            theta.push(a.svd(true, true).solve(&b, 1e-14).unwrap());
        }
        let mut worst: f64 = 0.0;
        for d in rec
            .dwells
            .iter()
            .filter(|d| rec.positions.has_role(d.position, Role::Verification))
        {
            let p = phi(d.temp_c);
            let val = |axis: usize, j: usize| -> f64 {
                (0..4).map(|k| theta[axis][j * 4 + k] * p[k]).sum()
            };
            let k = Matrix3::from_fn(&val);
            let u0 = Vector3::from_fn(|i, _| val(i, 3));
            let a = k.try_inverse().unwrap() * (Vector3::from(d.u_mean) - u0);
            worst = worst.max((a.norm() - 1.0).abs() * 1e3);
        }
        worst
    }
}

/// The figures the README quotes, each produced by the command or test it names; the
/// README test (`tests/readme.rs`) holds the README's blocks to them.
pub mod figures {
    /// A JSON array of strings as one string.
    fn joined(v: &serde_json::Value, sep: &str) -> String {
        v.as_array()
            .into_iter()
            .flatten()
            .filter_map(|a| a.as_str())
            .collect::<Vec<_>>()
            .join(sep)
    }

    use super::{cli, cli_json, repo};

    /// `host-fit demo --seed 1`: the table it prints.
    pub fn demo_table() -> String {
        let dir = std::env::temp_dir().join(format!("hf-readme-demo-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let (code, out, err) = cli(&["demo", "--out", dir.to_str().unwrap(), "--seed", "1"]);
        assert_eq!(code, 0, "{err}");
        let _ = std::fs::remove_dir_all(&dir);
        out.lines()
            .take_while(|l| !l.is_empty())
            .collect::<Vec<_>>()
            .join("\n")
    }

    /// `temp-fit` on the paper's Tables 1-2 (pwl, relative) against its Table 3: the
    /// largest relative difference over the 24 coefficients, and the line quoting it.
    pub fn golden_table3() -> (f64, String) {
        let tables = repo().join("testdata/paper/paper-tables.csv");
        let j = cli_json(&[
            "temp-fit",
            tables.to_str().unwrap(),
            "--model",
            "pwl",
            "--relative",
            "--json",
        ]);
        let iv = j["intervals"].as_array().unwrap();
        let text = std::fs::read_to_string(repo().join("testdata/paper/paper-table3.csv")).unwrap();
        let mut worst: f64 = 0.0;
        let mut n = 0;
        for l in text
            .lines()
            .filter(|l| !l.starts_with('#') && !l.starts_with("coefficient"))
        {
            let f: Vec<&str> = l.split(',').collect();
            for (k, col) in [(0, 2), (1, 3)] {
                let want: f64 = f[col].parse().unwrap();
                let got = iv[k]["coefficients"][f[0]]
                    .as_f64()
                    .unwrap_or_else(|| panic!("{} missing", f[0]));
                worst = worst.max(((got - want) / want).abs());
                n += 1;
            }
        }
        (
            worst,
            format!(
                "Table 3 reproduced: largest relative difference {worst:.1e} over {n} coefficients"
            ),
        )
    }

    /// The extended model of a recording with K2, rate and warm-up (3x nominal) written by
    /// `diagnose --out` and compensated through firmware-core: |dg| of every dwell with
    /// the physics terms and with the same tables alone (mg), and the line quoting them.
    pub fn physics_blob() -> (Vec<f64>, Vec<f64>, String) {
        use firmware_core::blob::Blob;
        use firmware_core::compensate::Method;
        use host_fit::data::positions::Positions;
        use host_fit::data::recording::Recording;
        let dir = std::env::temp_dir().join(format!("hf-phys-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let case = host_fit::blind::Case::catalogue(
            vec!["nonlinearity_k2", "temp_rate", "warmup_drift"],
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
                    .any(|f| f["effect"] == *e),
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
        let _ = std::fs::remove_dir_all(&dir);
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

    /// One twin compared: (name, chosen model, max |dg| of the default fit, of
    /// `--model poly --order 3` (static route), of the same cubic on the joint route
    /// (ramps in), and of the plain least-squares cubic), mg.
    pub type ChoiceRow = (String, String, f64, f64, f64, f64);

    /// The worst verification |dg| (mg) of `fit ARGS` then `verify` on the recording
    /// `rec` (in `dir`), and the model the fit reports.
    pub fn fit_verify(
        dir: &std::path::Path,
        rec: &std::path::Path,
        args: &[&str],
    ) -> (String, f64) {
        let blob = dir.join("unit.blob");
        let mut a = vec![
            "fit",
            rec.to_str().unwrap(),
            "--out",
            blob.to_str().unwrap(),
            "--force",
            "--json",
        ];
        a.extend_from_slice(args);
        let (code, out, err) = cli(&a);
        assert_eq!(code, 0, "fit {args:?}: {err}");
        let j: serde_json::Value = serde_json::from_str(&out).unwrap();
        let (code, out, err) = cli(&[
            "verify",
            rec.to_str().unwrap(),
            "--blob",
            blob.to_str().unwrap(),
            "--json",
        ]);
        assert!(code == 0 || code == 3, "verify: {err}");
        let v: serde_json::Value = serde_json::from_str(&out).unwrap();
        let worst = v["dwells"]
            .as_array()
            .unwrap()
            .iter()
            .map(|d| d["dg_mg"].as_f64().unwrap().abs())
            .fold(0.0, f64::max);
        (j["model"].as_str().unwrap().to_string(), worst)
    }

    /// The default `fit` against the plain least-squares cubic on every twin.
    pub fn model_choice() -> (Vec<ChoiceRow>, String) {
        let dir = std::env::temp_dir().join(format!("hf-choice-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mut rows = Vec::new();
        for (name, cfg) in super::twins::all() {
            let (csv, rec) = super::twins::recording(name, &cfg);
            let p = dir.join("rec.csv");
            std::fs::write(&p, csv).unwrap();
            let (model, default) = fit_verify(&dir, &p, &[]);
            let (_, stat3) = fit_verify(&dir, &p, &["--model", "poly", "--order", "3"]);
            let (_, joint3) = fit_verify(
                &dir,
                &p,
                &["--model", "poly", "--order", "3", "--route", "joint"],
            );
            let plain = super::twins::plain_cubic_max_dg_mg(&rec);
            rows.push((name.to_string(), model, default, stat3, joint3, plain));
        }
        let _ = std::fs::remove_dir_all(&dir);
        let mut t = format!(
            "max |dg| in the verification dwells (PP1..PP6 at every stop), mg\n{:<42} {:<28} {:>8} {:>11} {:>11} {:>10}\n",
            "twin recording", "default fit: chosen model", "default", "poly3 stat", "poly3 joint", "plain LS3"
        );
        for r in &rows {
            let model = if r.1.len() > 28 {
                format!("{}...", &r.1[..25])
            } else {
                r.1.clone()
            };
            t.push_str(&format!(
                "{:<42} {:<28} {:>8.4} {:>11.4} {:>11.4} {:>10.4}\n",
                r.0, model, r.2, r.3, r.4, r.5
            ));
        }
        let better = rows.iter().filter(|r| r.2 <= r.5).count();
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
        for (name, cfg) in super::twins::all() {
            let (_, rec) = super::twins::recording(name, &cfg);
            let req = ModelRequest {
                kind: None,
                order: None,
                breakpoints: None,
            };
            let oc = fit_chosen(&rec, &req).unwrap();
            // no cache step: the firmware then evaluates the model at every sample's
            // temperature, and the comparison is of the model alone
            let cal = oc.fit.calibration(0.0, false);
            let (blob, _, _) = host_fit::blob::build_blob("T", &rec.output_unit, &cal).unwrap();
            let check = |p: usize| rec.positions.has_role(p, Role::Verification);
            let v =
                host_fit::verify::verify(&rec, &blob, Method::CorrectConstants, &check).unwrap();
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
        let dir = std::env::temp_dir().join(format!("hf-ggir-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
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
        let _ = std::fs::remove_dir_all(&dir);
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
        let dir = std::env::temp_dir().join(format!("hf-imucal-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
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
        let _ = std::fs::remove_dir_all(&dir);
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
}
