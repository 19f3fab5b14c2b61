//! Figures of merit of a diagnosis fit: BIC, residual RMS (raw and in noise units), and
//! the worst |dg| the fitted model leaves in the static windows.
use crate::diagnose::design::{Data, Fit};

/// Bayesian information criterion of `f` over `n` residuals.
pub fn bic(f: &Fit, n: usize) -> f64 {
    f.chi2 + f.k as f64 * (n as f64).ln()
}

/// RMS of the residuals (output units).
pub fn residual_rms(f: &Fit) -> f64 {
    let n = f.resid.len() * 3;
    (f.resid.iter().flatten().map(|r| r * r).sum::<f64>() / n.max(1) as f64).sqrt()
}

/// Noise-weighted residual RMS in units of the in-dwell noise (1 = noise only).
pub fn normalized_rms(data: &Data, f: &Fit) -> f64 {
    (f.chi2 / (3 * data.obs.len()) as f64).sqrt()
}

/// Expected residual RMS from noise alone (output units, per window).
pub fn noise_rms(data: &Data) -> f64 {
    let mut s = 0.0;
    for o in &data.obs {
        for i in 0..3 {
            s += data.noise.sigma[i] * data.noise.sigma[i] / o.n as f64;
        }
    }
    (s / (3 * data.obs.len()).max(1) as f64).sqrt()
}

/// max |dg| (mg) over the static windows: the position's |a| from the fitted model.
pub fn max_dg(data: &Data, f: &Fit) -> f64 {
    let mut worst: f64 = 0.0;
    for (r, o) in data.obs.iter().enumerate() {
        if o.dtdt.abs() > 0.002 {
            continue;
        }
        let k = f.k_at[r];
        let Some(n) = firmware_core::model::invert(&k) else {
            continue;
        };
        // the output without the fitted extras: the prediction minus residual is the
        // model; the model's static part is K a + U0, so a = N (U - extras - U0)
        let extras: Vec<f64> = (0..3)
            .map(|i| {
                o.u[i]
                    - f.resid[r][i]
                    - (k[i][0] * o.a[0] + k[i][1] * o.a[1] + k[i][2] * o.a[2] + f.u0_at[r][i])
            })
            .collect();
        let u: [f64; 3] = std::array::from_fn(|i| o.u[i] - extras[i]);
        let a = firmware_core::model::apply(&n, u, f.u0_at[r]);
        worst = worst.max(firmware_core::model::dg(&a).abs() * 1e3);
    }
    worst
}
