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

/// The figures the README quotes, each produced by the command or test it names; the
/// README test (`tests/readme.rs`) holds the README's blocks to them.
pub mod figures {
    use super::{cli, repo};

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
        let (code, out, err) = cli(&[
            "temp-fit",
            tables.to_str().unwrap(),
            "--model",
            "pwl",
            "--relative",
            "--json",
        ]);
        assert_eq!(code, 0, "{err}");
        let j: serde_json::Value = serde_json::from_str(&out).unwrap();
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
        for e in &case.effects {
            assert!(
                j["findings"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .any(|f| f["effect"] == *e),
                "{e} not found: {out}"
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

    /// `host-fit blind --long`: the summary after the per-case lines.
    pub fn blind_long() -> String {
        let (code, out, err) = cli(&["blind", "--long"]);
        assert_eq!(code, 0, "{err}");
        let at = out.find("confusion").unwrap_or(0);
        out[at..].trim_end().to_string()
    }
}
