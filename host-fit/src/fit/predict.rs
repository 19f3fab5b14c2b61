//! The predicted compensation error: the fit's covariance propagated to formula (13).
//!
//! The compensated output is `a = N(T) (U - U0(T))`; an error `e_i` in the predicted
//! output of axis i moves |a| by `-(a^T N)_i e_i`. Each axis is its own least squares,
//! so `var(dg) = sum_i (a^T N)_i^2 g_i^T C_i g_i`, with `g_i` the design row of the
//! direction `a` at `T` and `C_i` the axis's covariance, widened by its reduced
//! chi-square when the residuals scatter more than the noise (misfit shows up here
//! rather than being hidden). A dwell of `n` samples adds its own noise,
//! `sum_i (a^T N)_i^2 sigma_i^2 / n` with `sigma_i` the in-dwell scatter (successive
//! samples): the dwell's own, never widened by the chosen model's residuals (a model that
//! misfits the calibration dwells is uncertain, which the covariance's widening says; it
//! does not make a verification dwell noisier). Between the calibration temperatures this is the
//! uncertainty of the chosen model, not a bound on how far the truth may stray from the
//! model's shape there: only data at those temperatures can show that. Every figure is
//! stated inside the valid range only (T0 among them when it lies there).
use crate::fit::noise::Noise;
use crate::fit::temperature::ModelFit;
use crate::model::basis::Basis;
use firmware_core::model::{invert, Coeffs};
use serde::Serialize;

/// The predicted 1-sigma of |dg| at one temperature.
#[derive(Debug, Clone, Copy, Serialize, PartialEq)]
pub struct PredictedPoint {
    /// Temperature, C.
    pub temp_c: f64,
    /// 1-sigma of |dg| from the coefficients' uncertainty, worst of the directions, mg.
    pub dg_1sigma_mg: f64,
}

/// The predicted compensation error against temperature.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Prediction {
    /// The directions it is evaluated at (position names).
    pub directions: Vec<String>,
    /// The valid range, C.
    pub t_min_c: f64,
    /// The valid range, C.
    pub t_max_c: f64,
    /// On a grid over the valid range.
    pub points: Vec<PredictedPoint>,
    /// A verification dwell's own noise (1 sigma, mg) for a dwell of `dwell_samples`.
    pub dwell_noise_1sigma_mg: f64,
    /// The dwell length that is for.
    pub dwell_samples: usize,
    /// The firmware's cache step (`--update-step`), C.
    pub cache_step_c: f64,
    /// The most the cache's lag can add to |dg| (|d|a|/dT| x step, worst of the grid and
    /// directions), mg; not part of the 1-sigma: it is the firmware's, not the model's.
    pub cache_lag_max_mg: f64,
    /// Per axis, the factor the residuals put on the covariance (reduced chi-square).
    pub covariance_scale: [f64; 3],
}

/// A fitted model as a prediction needs it: its 12 coefficients at a temperature, and
/// the variance of a linear function of them from the fit's covariance. The static
/// route's per-axis fits ([`StaticModel`]) and the dynamic route's joint one
/// (`fit::route::Routed`) are both read through it, so the covariance is propagated to
/// |dg| in one place.
pub trait Uncertain {
    /// The 12 coefficients (canonical order) at `t`.
    fn coefficients(&self, t: f64) -> [f64; 12];

    /// The variance of `sum_c s_c coeff_c(t)` from the fit's covariance (widened by its
    /// misfit); NaN when the fit carries none.
    fn variance(&self, t: f64, s: &[f64; 12]) -> f64;

    /// The 1-sigma of each of the 12 coefficients at `t`.
    fn coefficient_sigma(&self, t: f64) -> [f64; 12] {
        std::array::from_fn(|c| {
            let mut e = [0.0; 12];
            e[c] = 1.0;
            self.variance(t, &e).max(0.0).sqrt()
        })
    }
}

/// A model of the static, joint or per-stop route with the noise it was weighted by.
#[derive(Debug, Clone, Copy)]
pub struct StaticModel<'a> {
    /// The model.
    pub fit: &'a ModelFit,
    /// Its noise.
    pub noise: &'a Noise,
}

impl Uncertain for StaticModel<'_> {
    fn coefficients(&self, t: f64) -> [f64; 12] {
        self.fit.eval(t)
    }

    /// Each axis is its own least squares: `sum_i g_i^T C_i g_i`, `g_i` the design row
    /// of the axis's K row and offset weighted by `s`, `C_i` the axis's covariance
    /// widened by its reduced chi-square.
    fn variance(&self, t: f64, s: &[f64; 12]) -> f64 {
        use firmware_core::model::{K_INDEX, U0_INDEX};
        let fit = self.fit;
        let phi = fit.basis.eval(fit.t0_c, t);
        let mut var = 0.0;
        for i in 0..3 {
            let Some(c) = fit.axis_cov.get(i) else {
                return f64::NAN;
            };
            let slots = [K_INDEX[i][0], K_INDEX[i][1], K_INDEX[i][2], U0_INDEX[i]];
            let g: Vec<f64> = slots
                .iter()
                .flat_map(|slot| phi.iter().map(move |f| s[*slot] * f))
                .collect();
            let mut q = 0.0;
            for (r, gr) in g.iter().enumerate() {
                for (u, gu) in g.iter().enumerate() {
                    q += gr * c[(r, u)] * gu;
                }
            }
            var += self.fit.axis_scale(i, self.noise.dof > 0) * q;
        }
        var
    }
}

/// `(a^T N(T))_i` of `m` at `t`: how an error in axis i's output moves |a|; None when
/// K is singular.
fn sensitivity(m: &dyn Uncertain, t: f64, a: [f64; 3]) -> Option<[f64; 3]> {
    let c = Coeffs::from_array(&m.coefficients(t));
    let n = invert(&c.k)?;
    Some(std::array::from_fn(|i| {
        (0..3).map(|j| a[j] * n[j][i]).sum()
    }))
}

/// 1-sigma of |dg| (g) at direction `a` and temperature `t` from the coefficients'
/// uncertainty, of any fitted model: |dg| moves by `-(a^T N)_i (dK_i a + dU0_i)`,
/// linear in the 12 coefficients; NaN when the fit carries no covariance or K is
/// singular.
pub fn sigma_of(m: &dyn Uncertain, t: f64, a: [f64; 3]) -> f64 {
    use firmware_core::model::{K_INDEX, U0_INDEX};
    let Some(w) = sensitivity(m, t, a) else {
        return f64::NAN;
    };
    let mut s = [0.0; 12];
    for i in 0..3 {
        for j in 0..3 {
            s[K_INDEX[i][j]] = w[i] * a[j];
        }
        s[U0_INDEX[i]] = w[i];
    }
    m.variance(t, &s).max(0.0).sqrt()
}

/// The noise of one dwell's mean of `n` samples in |dg| (g) at direction `a`, the
/// outputs scattering with variance `var[i]` per sample: `sum_i (a^T N)_i^2 var_i / n`.
pub fn dwell_noise_of(m: &dyn Uncertain, t: f64, a: [f64; 3], var: [f64; 3], n: f64) -> f64 {
    let Some(w) = sensitivity(m, t, a) else {
        return f64::NAN;
    };
    (0..3)
        .map(|i| w[i] * w[i] * var[i] / n.max(1.0))
        .sum::<f64>()
        .sqrt()
}

/// 1-sigma of |dg| (g) at direction `a` and temperature `t` from the coefficients'
/// uncertainty; NaN when the fit carries no covariance.
pub fn sigma_model(fit: &ModelFit, noise: &Noise, t: f64, a: [f64; 3]) -> f64 {
    sigma_of(&StaticModel { fit, noise }, t, a)
}

/// The noise of one dwell's mean of `n` samples in |dg| (g) at direction `a`.
pub fn sigma_dwell_noise(fit: &ModelFit, noise: &Noise, t: f64, a: [f64; 3], n: usize) -> f64 {
    // without an in-dwell noise level the residual scatter of the fit's observations
    // (one per dwell) is the only noise there is; with it, the dwell's own scatter,
    // whatever the model's residuals (one dwell missing once made a misfitting model's
    // reduced chi-square of 36 000 a "dwell noise")
    let var = std::array::from_fn(|i| {
        if noise.dof > 0 {
            noise.sigma[i].powi(2)
        } else {
            fit.axis_scale(i, false)
        }
    });
    dwell_noise_of(&StaticModel { fit, noise }, t, a, var, n as f64)
}

/// The 1-sigma of a verification dwell's |dg| (g): the model's and the dwell's own.
pub fn sigma_dwell(fit: &ModelFit, noise: &Noise, t: f64, a: [f64; 3], n: usize) -> f64 {
    sigma_model(fit, noise, t, a).hypot(sigma_dwell_noise(fit, noise, t, a, n))
}

/// One direction a prediction is stated for.
#[derive(Debug, Clone, PartialEq)]
pub struct Direction {
    /// The position's name.
    pub name: String,
    /// Its unit vector.
    pub a: [f64; 3],
}

/// What a prediction is asked for.
#[derive(Debug, Clone, PartialEq)]
pub struct Request {
    /// The directions.
    pub directions: Vec<Direction>,
    /// The length of a verification dwell, samples.
    pub dwell_samples: usize,
    /// The valid range, C.
    pub t_min_c: f64,
    /// The valid range, C.
    pub t_max_c: f64,
    /// The firmware's cache step, C.
    pub update_step_c: f64,
}

/// The prediction over the request's valid range at its directions.
pub fn predict(fit: &ModelFit, noise: &Noise, req: &Request) -> Prediction {
    let (lo, hi) = (req.t_min_c, req.t_max_c);
    let (dwell_samples, update_step_c) = (req.dwell_samples, req.update_step_c);
    let dirs = &req.directions;
    let constant = is_constant(&fit.basis);
    let n_pts = if constant { 0 } else { 11 };
    let mut temps: Vec<f64> = (0..n_pts)
        .map(|k| lo + (hi - lo) * k as f64 / (n_pts.max(2) - 1) as f64)
        .collect();
    // inside the valid range only: T0 where it lies there, else (one temperature) the
    // middle of the range; the dwell's own noise at the same place
    let inside = (lo..=hi).contains(&fit.t0_c);
    let at = if inside { fit.t0_c } else { 0.5 * (lo + hi) };
    if inside || constant {
        temps.push(at);
        temps.sort_by(f64::total_cmp);
    }
    let worst = |t: f64| {
        dirs.iter()
            .map(|d| sigma_model(fit, noise, t, d.a))
            .fold(0.0, f64::max)
    };
    let points = temps
        .iter()
        .map(|t| PredictedPoint {
            temp_c: (t * 100.0).round() / 100.0,
            dg_1sigma_mg: worst(*t) * 1e3,
        })
        .collect();
    // the firmware recomputes N(T) only when T has moved by the step: until then the
    // compensation lags by up to the step, |d|a|/dT| x step
    let cache = temps
        .iter()
        .flat_map(|t| dirs.iter().map(move |d| (*t, d.a)))
        .map(|(t, a)| dg_slope(fit, noise, t, a).abs() * update_step_c)
        .fold(0.0, f64::max);
    let dwell = dirs
        .iter()
        .map(|d| sigma_dwell_noise(fit, noise, at, d.a, dwell_samples))
        .fold(0.0, f64::max);
    Prediction {
        directions: dirs.iter().map(|d| d.name.clone()).collect(),
        t_min_c: lo,
        t_max_c: hi,
        points,
        dwell_noise_1sigma_mg: dwell * 1e3,
        dwell_samples,
        cache_step_c: update_step_c,
        cache_lag_max_mg: cache * 1e3,
        covariance_scale: std::array::from_fn(|i| fit.axis_scale(i, noise.dof > 0)),
    }
}

/// How fast |a| read with the coefficients of `t` drifts from the truth as the
/// coefficients' temperature is held while the unit's moves, g/C: `-(a^T N)(dK/dT a +
/// dU0/dT)`, by central difference.
fn dg_slope(fit: &ModelFit, noise: &Noise, t: f64, a: [f64; 3]) -> f64 {
    let h = 0.05;
    let Some(w) = sensitivity(&StaticModel { fit, noise }, t, a) else {
        return 0.0;
    };
    let (up, dn) = (fit.eval(t + h), fit.eval(t - h));
    let d: [f64; 12] = std::array::from_fn(|c| (up[c] - dn[c]) / (2.0 * h));
    let dc = Coeffs::from_array(&d);
    (0..3)
        .map(|i| {
            let du = (0..3).map(|j| dc.k[i][j] * a[j]).sum::<f64>() + dc.u0[i];
            -w[i] * du
        })
        .sum()
}

/// Whether a basis is a constant (one temperature).
pub fn is_constant(b: &Basis) -> bool {
    matches!(b, Basis::Poly { order: 0 })
}

/// The directions a prediction is stated for: the recording's verification positions
/// with a known vector in `positions` (the recording's, or with the poses of unknown
/// orientation estimated), else its calibration positions; with their median dwell
/// length.
pub fn directions(
    rec: &crate::data::recording::Recording,
    positions: &crate::data::positions::Positions,
) -> (Vec<Direction>, usize) {
    use crate::data::positions::Role;
    for role in [Role::Verification, Role::Calibration] {
        let mut idx: Vec<usize> = rec
            .dwells
            .iter()
            .map(|d| d.position)
            .filter(|p| positions.has_role(*p, role) && positions.is_known(*p))
            .collect();
        idx.sort_unstable();
        idx.dedup();
        if idx.is_empty() {
            continue;
        }
        let mut lens: Vec<usize> = rec
            .dwells
            .iter()
            .filter(|d| idx.binary_search(&d.position).is_ok())
            .map(|d| d.len())
            .collect();
        lens.sort_unstable();
        let n = lens.get(lens.len() / 2).copied().unwrap_or(1);
        let dirs = idx
            .iter()
            .map(|p| Direction {
                name: positions.name(*p).to_string(),
                a: positions.vector(*p),
            })
            .collect();
        return (dirs, n);
    }
    (Vec::new(), 1)
}

/// The 1-sigma of the 12 coefficients at temperature `t` from the fit's covariance
/// (widened as in [`sigma_model`]); zeros when the fit carries none.
pub fn coefficient_sigma(fit: &ModelFit, noise: &Noise, t: f64) -> [f64; 12] {
    use firmware_core::model::{K_INDEX, U0_INDEX};
    let mut out = [0.0; 12];
    let phi = fit.basis.eval(fit.t0_c, t);
    let nb = phi.len();
    for (axis, c) in fit.axis_cov.iter().enumerate().take(3) {
        let scale = fit.axis_scale(axis, noise.dof > 0);
        let slots = [
            K_INDEX[axis][0],
            K_INDEX[axis][1],
            K_INDEX[axis][2],
            U0_INDEX[axis],
        ];
        for (j, slot) in slots.iter().enumerate() {
            let mut q = 0.0;
            for (r, fr) in phi.iter().enumerate() {
                for (s, fs) in phi.iter().enumerate() {
                    q += fr * c[(j * nb + r, j * nb + s)] * fs;
                }
            }
            out[*slot] = (q * scale).max(0.0).sqrt();
        }
    }
    out
}
