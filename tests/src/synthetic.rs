//! A tiny synthetic six-position recording writer (the full digital twin is
//! `host_fit::simulate`), with model.md's TP positions and the paper's coefficients at T0.
use host_fit::rng::Rng;
use std::fmt::Write;

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
