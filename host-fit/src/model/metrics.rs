//! Figures of merit of a diagnosis fit: the dispersion (residual over the floor), the
//! quasi-likelihood information criterion that scales by it, residual RMS (raw and in
//! floor units), the worst |dg| the fitted model leaves in the static windows, a
//! parameter's standard error, an effect's contribution, and the judgement of a larger
//! model against a smaller one by the acceptance rules of [`Rules`].
use crate::model::data::Data;
use crate::model::design::static_at;
use crate::model::profile;
#[cfg(doc)]
use crate::model::rules::Rules;
use crate::model::solve::Fit;

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
/// than [`Rules::steady_rate_c_per_s`], or K is singular): the window's specific force
/// from its mean outputs with the fitted in-flight terms removed, against 1 g.
pub fn dg_per_window(data: &Data, f: &Fit) -> Vec<Option<f64>> {
    let mut out = Vec::with_capacity(data.obs.len());
    for (r, o) in data.obs.iter().enumerate() {
        out.push(None);
        if data.rate[r].abs() > data.rules.steady_rate_c_per_s {
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

/// The standard error of parameter `j`: the covariance's scaled by the dispersion, or the
/// Newey-West one where that is larger (residuals correlated in time).
pub fn sigma(f: &Fit, j: usize, phi: f64) -> f64 {
    let formal = f
        .cov
        .as_ref()
        .map(|c| (c[(j, j)].max(0.0) * phi).sqrt())
        .unwrap_or(f64::INFINITY);
    let hac = f.hac.as_ref().map(|v| v[j]).unwrap_or(0.0);
    formal.max(hac)
}

/// The 12 coefficients (canonical order) of `f` at temperature `t`.
pub fn coefficients(data: &Data, f: &Fit, t: f64) -> [f64; 12] {
    let (k, u0) = static_at(&f.spec, &f.labels, &f.x, data.t0, [t; 3]);
    firmware_core::model::Coeffs { k, u0 }.to_array()
}

/// The 12 coefficients of `f` at `t` are linear in its parameters: their gradient over
/// every parameter, their values at unit vectors.
fn gradients(data: &Data, f: &Fit, t: f64) -> Vec<[f64; 12]> {
    let p = f.x.len();
    (0..p)
        .map(|c| {
            let e = nalgebra::DVector::from_fn(p, |i, _| if i == c { 1.0 } else { 0.0 });
            let (k, u0) = static_at(&f.spec, &f.labels, &e, data.t0, [t; 3]);
            firmware_core::model::Coeffs { k, u0 }.to_array()
        })
        .collect()
}

/// The variance of `sum_c s_c coeff_c(t)` of `f`: its gradient over the parameters `h`,
/// `h^T C h` scaled by the dispersion; NaN when `f` carries no covariance.
pub fn variance(data: &Data, f: &Fit, t: f64, s: &[f64; 12]) -> f64 {
    let Some(cov) = &f.cov else {
        return f64::NAN;
    };
    let h: Vec<f64> = gradients(data, f, t)
        .iter()
        .map(|g| g.iter().zip(s).map(|(g, s)| g * s).sum())
        .collect();
    let p = h.len();
    (0..p)
        .flat_map(|x| (0..p).map(move |y| (x, y)))
        .map(|(x, y)| h[x] * cov[(x, y)] * h[y])
        .sum::<f64>()
        * dispersion(data, f)
}

/// The 1-sigma of the 12 coefficients (canonical order) of `f` at temperature `t`: each
/// is linear in the parameters, `g^T x`; its variance the covariance's `g^T C g` scaled
/// by the dispersion, or where larger the Newey-West bound `sum |g_j| sigma_j` (exact
/// when one parameter carries the coefficient, as a polynomial's at T0). Zeros when `f`
/// carries no covariance.
pub fn coefficient_sigma(data: &Data, f: &Fit, t: f64) -> [f64; 12] {
    let Some(cov) = &f.cov else {
        return [0.0; 12];
    };
    let phi = dispersion(data, f);
    let p = f.x.len();
    let unit = gradients(data, f, t);
    std::array::from_fn(|slot| {
        let g: Vec<f64> = unit.iter().map(|u| u[slot]).collect();
        let formal: f64 = (0..p)
            .flat_map(|a| (0..p).map(move |b| (a, b)))
            .map(|(a, b)| g[a] * cov[(a, b)] * g[b])
            .sum::<f64>()
            .max(0.0)
            * phi;
        let hac: f64 = f
            .hac
            .as_ref()
            .map(|h| g.iter().zip(h).map(|(g, s)| g.abs() * s).sum())
            .unwrap_or(0.0);
        formal.sqrt().max(hac)
    })
}

/// An effect's contribution to the model, per residual row in floor units: the joint
/// model's prediction minus the prediction without it.
pub fn contribution(data: &Data, full: &Fit, reduced: &Fit) -> Vec<f64> {
    (0..data.n_rows())
        .map(|r| (reduced.resid[r / 3][r % 3] - full.resid[r / 3][r % 3]) * data.w[r].sqrt())
        .collect()
}

/// How a candidate compares with the model it extends.
#[derive(Debug, Clone)]
pub struct Judgement {
    /// Quasi-BIC drop (positive: better), in the larger model's dispersion.
    pub gain: f64,
    /// Share of the chi-square above the floor that it explains.
    pub share: f64,
    /// Held-out chi-square drop per added parameter, in floor units x dispersion.
    pub heldout_gain: f64,
    /// Largest |parameter| / scaled sigma among the effect's own parameters (None when the
    /// effect has none: lag and broad curvature act through the temperature).
    pub max_z: Option<f64>,
    /// The effect's largest contribution to one window, in floor sigmas (95th
    /// percentile over the windows, so one window cannot carry it).
    pub peak: f64,
    /// The profiled time constant (or bend) is determined by the data: the profile
    /// curves enough that its 1-sigma is within [`Rules::tau_determined_ln`] (time
    /// constants, in log) or [`Rules::bend_determined_c`] (a bend). A flat profile means
    /// the form is not what the data show.
    pub determined: bool,
}

impl Judgement {
    /// Every acceptance rule of `data`'s [`Rules`] passed: the quasi-BIC drops by more
    /// than the margin, the effect explains a material share of the excess, one of its
    /// parameters is significant, the held-out chunks improve, its structure is
    /// determined.
    pub fn accepted(&self, data: &Data) -> bool {
        let r = &data.rules;
        self.gain > r.q_margin
            && self.share >= r.material_share
            && self.heldout_gain > r.heldout_gain
            && self.max_z.is_none_or(|z| z >= r.z_significant)
            && self.determined
    }
}

/// Judge `larger` (a full fit) against `smaller`, the extra number `e` of `larger` being
/// the difference.
pub fn judge(data: &Data, smaller: &Fit, larger: &Fit, e: usize) -> Judgement {
    let phi = dispersion(data, larger);
    let dk = larger.params().saturating_sub(smaller.params()).max(1) as f64;
    let excess = (smaller.chi2 - data.n_rows().saturating_sub(smaller.params()) as f64)
        .max(f64::MIN_POSITIVE);
    let max_z = (0..larger.k)
        .filter(|&j| larger.labels[j].extra() == Some(e))
        .map(|j| larger.x[j].abs() / sigma(larger, j, phi))
        .reduce(f64::max);
    let mut c: Vec<f64> = contribution(data, larger, smaller)
        .iter()
        .map(|v| v.abs())
        .collect();
    c.sort_by(f64::total_cmp);
    Judgement {
        determined: profile::determined(data, larger, e, phi),
        peak: c.get(c.len() * 95 / 100).copied().unwrap_or(0.0),
        gain: qbic(data, smaller, phi) - qbic(data, larger, phi),
        share: (smaller.chi2 - larger.chi2) / excess,
        heldout_gain: {
            let (hs, hl) = data.heldout_pair(smaller, larger);
            (hs - hl) / phi / dk
        },
        max_z,
    }
}

/// RMS (floor units) of `f`'s residual over the rows where `contribution` (floor units)
/// exceeds [`Rules::acts_sigmas`].
fn region_rms(data: &Data, f: &Fit, contribution: &[f64]) -> Option<f64> {
    let rows: Vec<usize> = (0..contribution.len())
        .filter(|&r| contribution[r].abs() > data.rules.acts_sigmas)
        .collect();
    if rows.is_empty() {
        return None;
    }
    let ss: f64 = rows
        .iter()
        .map(|&r| data.w[r] * f.resid[r / 3][r % 3] * f.resid[r / 3][r % 3])
        .sum();
    Some((ss / rows.len() as f64).sqrt())
}

/// Whether the effect `full` has and `reduced` lacks explains the data where it acts:
/// there the joint model's residual is at the floor, or at most
/// [`Rules::adequate_ratio`] of the residual without the effect.
pub fn adequate(data: &Data, full: &Fit, reduced: &Fit) -> bool {
    let c = contribution(data, full, reduced);
    let r = &data.rules;
    match (region_rms(data, full, &c), region_rms(data, reduced, &c)) {
        (Some(after), Some(before)) => {
            after <= r.at_floor_rms || after <= r.adequate_ratio * before
        }
        _ => false,
    }
}

/// Whether the discovered term `full` has and `reduced` lacks explains its region as well
/// as the model explains the rest: the residual RMS (floor units) where the term acts
/// (its contribution above [`Rules::acts_sigmas`]) is at the floor, or at most the RMS of
/// the rows of the same axis where it does not act (of the other axes where it acts on
/// every row of its own). A library term is the last resort: one that only dents a
/// misfit (a linear drift through a sudden step) fits a shape the data do not have,
/// where a catalogue effect's imperfect form may still be the right name.
pub fn adequate_term(data: &Data, full: &Fit, reduced: &Fit, axis: usize) -> bool {
    let c = contribution(data, full, reduced);
    let r = &data.rules;
    let z2 = |row: usize| data.w[row] * full.resid[row / 3][row % 3].powi(2);
    let rms = |rows: &[usize]| {
        (!rows.is_empty())
            .then(|| (rows.iter().map(|&k| z2(k)).sum::<f64>() / rows.len() as f64).sqrt())
    };
    let acts: Vec<usize> = (0..c.len())
        .filter(|&k| c[k].abs() > r.acts_sigmas)
        .collect();
    let Some(inside) = rms(&acts) else {
        return false;
    };
    let same: Vec<usize> = (0..c.len())
        .filter(|&k| k % 3 == axis && c[k].abs() <= r.acts_sigmas)
        .collect();
    let others: Vec<usize> = (0..c.len()).filter(|&k| k % 3 != axis).collect();
    let outside = rms(&same).or_else(|| rms(&others)).unwrap_or(0.0);
    inside <= r.at_floor_rms.max(outside)
}
