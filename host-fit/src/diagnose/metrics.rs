//! Figures of merit of a diagnosis fit: the dispersion (residual over the floor), the
//! quasi-likelihood information criterion that scales by it, residual RMS (raw and in
//! floor units), and the worst |dg| the fitted model leaves in the static windows.
use crate::diagnose::design::{Data, Fit};

/// The dispersion of a fit: chi-square per degree of freedom in floor units, at least 1
/// (a floor measured too high is not a reason to trust a model more).
pub fn dispersion(data: &Data, f: &Fit) -> f64 {
    let dof = data.n_rows().saturating_sub(f.params()).max(1) as f64;
    (f.chi2 / dof).max(1.0)
}

/// Quasi-likelihood BIC: the chi-square divided by the dispersion `phi` of the larger
/// model compared, plus ln(n) per parameter (structural unknowns included). A model
/// still far from the data (large phi) cannot buy a finding with a small improvement.
pub fn qbic(data: &Data, f: &Fit, phi: f64) -> f64 {
    f.chi2 / phi + f.params() as f64 * (data.n_rows() as f64).ln()
}

/// RMS of the residuals (output units).
pub fn residual_rms(f: &Fit) -> f64 {
    let n = f.resid.len() * 3;
    (f.resid.iter().flatten().map(|r| r * r).sum::<f64>() / n.max(1) as f64).sqrt()
}

/// Residual RMS in units of the floor (1 = noise only).
pub fn normalized_rms(data: &Data, f: &Fit) -> f64 {
    (f.chi2 / data.n_rows().max(1) as f64).sqrt()
}

/// The floor's expected residual RMS per window (output units).
pub fn floor_rms(data: &Data) -> f64 {
    (data.w.iter().map(|w| 1.0 / w).sum::<f64>() / data.n_rows().max(1) as f64).sqrt()
}

/// Residuals in floor units, per observation and axis.
pub fn z(data: &Data, f: &Fit) -> Vec<[f64; 3]> {
    f.resid
        .iter()
        .enumerate()
        .map(|(r, v)| std::array::from_fn(|i| v[i] * data.w[3 * r + i].sqrt()))
        .collect()
}

/// max |dg| (mg) over the static windows: the position's |a| from the fitted model.
pub fn max_dg(data: &Data, f: &Fit) -> f64 {
    dg_per_window(data, f)
        .into_iter()
        .flatten()
        .fold(0.0, |w, v| w.max(v.abs()))
}

/// dg (mg) of every window by the fitted model (None where the temperature moves faster
/// than 0.002 C/s, or K is singular): the window's specific force from its mean outputs
/// with the fitted in-flight terms removed, against 1 g.
pub fn dg_per_window(data: &Data, f: &Fit) -> Vec<Option<f64>> {
    let mut out = Vec::with_capacity(data.obs.len());
    for (r, o) in data.obs.iter().enumerate() {
        out.push(None);
        if data.rate[r].abs() > 0.002 {
            continue;
        }
        let k = f.k_at[r];
        let Some(n) = firmware_core::model::invert(&k) else {
            continue;
        };
        // the output without the fitted in-flight terms: the prediction minus the
        // residual is the model; its static part is K a + U0
        let u: [f64; 3] = std::array::from_fn(|i| {
            let model = o.u[i] - f.resid[r][i];
            let static_part =
                k[i][0] * o.a[0] + k[i][1] * o.a[1] + k[i][2] * o.a[2] + f.u0_at[r][i];
            o.u[i] - (model - static_part)
        });
        let a = firmware_core::model::apply(&n, u, f.u0_at[r]);
        out[r] = Some(firmware_core::model::dg(&a) * 1e3);
    }
    out
}
