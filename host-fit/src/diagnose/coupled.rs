//! Effects found together whose split the design pins only in part: a hysteresis beside
//! a rate or a lag on a test that shows no temperature at rest on both of the
//! hysteresis's branches. Their sum is measured; how it divides between them rests on
//! the ramps, and a flight (faster ramps, turns at any temperature) pays for a wrong
//! division. Reported with the correlation of their estimates in the final joint fit
//! (beside each finding's own 1-sigma) and the measurement that separates them.
use crate::data::recording::MAX_DWELL_DRIFT_C;
use crate::diagnose::findings::{needed, scaled_profile, Finding};
use crate::model::data::Data;
use crate::model::effects::{EffectId, Extra};
use crate::model::params::{Param, Term};
use crate::model::regressors;
use crate::model::solve::Fit;
use serde::Serialize;

/// Two effects of the findings whose split this recording pins only through its ramps.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Coupling {
    /// The two effects (the hysteresis first).
    pub effects: [EffectId; 2],
    /// Per axis (x, y, z): the correlation of the two effects' estimates on that axis in
    /// the final joint fit, at unit dispersion (a hysteresis's offset term with a rate's
    /// coefficient from the formal covariance; with a lag's time constants, which are
    /// profiled, from that profile), on the axes where both findings matter; null
    /// elsewhere, and where the profile gives no variance.
    pub correlation: [Option<f64>; 3],
    /// Why the design leaves their split to the ramps.
    pub why: String,
    /// The measurement that separates them.
    pub needed: String,
}

/// Temperatures of two windows at rest closer than this are one temperature here, C.
const SAME_TEMPERATURE_C: f64 = 2.0;

/// Whether some temperature is seen at rest (in a dwell that drifts no more than
/// [`MAX_DWELL_DRIFT_C`]; a ramp's dwell drifts more) on both of the fitted
/// hysteresis's branches: its own state (`threshold_c`, `initial`: the column the fit
/// used) averaged over each window, beyond the rules' direction majority either way.
fn seen_both_ways(data: &Data, threshold_c: f64, initial: f64) -> bool {
    let majority = data.rules.direction_majority;
    let state = regressors::directions(data.rec, threshold_c, initial);
    let branch: Vec<f64> = data
        .obs
        .iter()
        .map(|o| {
            let rows = state.get(o.start..o.end).unwrap_or_default();
            rows.iter().sum::<f64>() / rows.len().max(1) as f64
        })
        .collect();
    let temps = |sign: f64| -> Vec<f64> {
        data.obs
            .iter()
            .zip(&branch)
            .filter(|(o, b)| {
                *b * sign > majority
                    && data
                        .rec
                        .dwells
                        .get(o.dwell)
                        .is_some_and(|d| d.temp_span_c <= MAX_DWELL_DRIFT_C)
            })
            .map(|(o, _)| o.temp_c)
            .collect()
    };
    let (heated, cooled) = (temps(1.0), temps(-1.0));
    heated
        .iter()
        .any(|h| cooled.iter().any(|c| (h - c).abs() < SAME_TEMPERATURE_C))
}

/// What a partner of the hysteresis is estimated by, and so how their correlation is
/// found.
#[derive(Debug, Clone, Copy)]
enum Estimate {
    /// A linear coefficient per axis (a rate's `r_i`): the fit's covariance.
    Coefficient,
    /// Profiled time constants (a lag's): the profile.
    TimeConstant,
}

/// The column of extra `e`'s first term on `axis` in `f`.
fn column(f: &Fit, e: usize, axis: usize) -> Option<usize> {
    f.labels.iter().position(|l| {
        matches!(l, Param::Effect { extra, axis: i, term } if *extra == e && *i == axis && *term != Term::Discovered)
    })
}

/// The correlation of the estimates of extras `a` and `b` on each axis of `on` in `f`
/// (the first term of each on the axis).
fn correlation(f: &Fit, a: usize, b: usize, on: [bool; 3]) -> [Option<f64>; 3] {
    std::array::from_fn(|axis| {
        if !on[axis] {
            return None;
        }
        let (i, j) = (column(f, a, axis)?, column(f, b, axis)?);
        let c = f.cov.as_ref()?;
        let r = c[(i, j)] / (c[(i, i)] * c[(j, j)]).sqrt();
        r.is_finite().then_some(r)
    })
}

/// The correlation of extra `a`'s estimate on each axis of `on` with the lag `lag`'s
/// time constants (all scaled together), in `f` of `data`. A lag has no linear
/// coefficient: its time constant is profiled, so the joint covariance is taken from
/// the profile at unit dispersion, as the linear one is ([`scaled_profile`]): the
/// variance of the scale `s`, the slope `b = d a / d s` of `a`'s estimate at a fixed
/// lag, and with `a`'s variance at that lag `v`, `corr = b sd(s) / sqrt(v + b^2 var(s))`
/// (a Gaussian's conditional mean and variance).
fn lag_correlation(data: &Data, f: &Fit, a: usize, lag: usize, on: [bool; 3]) -> [Option<f64>; 3] {
    let none = [None; 3];
    if !matches!(f.spec.extras.get(lag), Some(Extra::Lag { .. })) || !on.contains(&true) {
        return none;
    }
    let (Some(p), Some(cov)) = (scaled_profile(data, f, lag, None), &f.cov) else {
        return none;
    };
    std::array::from_fn(|axis| {
        if !on[axis] {
            return None;
        }
        let i = column(f, a, axis)?;
        let r = from_profile(*p.slope.get(i)?, p.var_s, cov[(i, i)]);
        r.is_finite().then_some(r)
    })
}

/// The correlation of `a` and `s` in a Gaussian, from what a profile in `s` gives: the
/// slope `b` of `a`'s estimate in `s`, the variance `var_s` of `s`, and `a`'s variance
/// `v` at a fixed `s` (then `cov = b var_s`, `var(a) = v + b^2 var_s`). Exact in
/// arithmetic; in floating point within a few ulps (`a_profile_gives_the_gaussians_correlation`).
fn from_profile(b: f64, var_s: f64, v: f64) -> f64 {
    b * var_s.sqrt() / (v + b * b * var_s).sqrt()
}

/// The couplings of `findings` in the final fit `f` of `data`: a hysteresis beside a
/// rate or a lag where no temperature is seen at rest on both of the hysteresis's
/// branches (every stop reached from one side: after the first turn the hysteresis is one
/// constant in every dwell, which the temperature model takes; the ramps, where the rate
/// and the lag act, are what is left to tell it from them).
pub fn coupled(data: &Data, f: &Fit, findings: &[Finding]) -> Vec<Coupling> {
    let finding = |id: EffectId| findings.iter().find(|x| x.effect == id);
    let fitted = f.spec.extras.iter().enumerate().find_map(|(e, x)| {
        if let Extra::Hysteresis {
            threshold_c,
            initial,
            ..
        } = x
        {
            Some((e, *threshold_c, *initial))
        } else {
            None
        }
    });
    let (Some(h), Some((he, threshold_c, initial))) = (finding(EffectId::Hysteresis), fitted)
    else {
        return Vec::new();
    };
    if seen_both_ways(data, threshold_c, initial) {
        return Vec::new();
    }
    let extra = |id: EffectId| f.spec.extras.iter().position(|e| e.id() == id);
    [
        (EffectId::TempRate, Estimate::Coefficient),
        (EffectId::ThermalLag, Estimate::TimeConstant),
    ]
    .into_iter()
    .filter_map(|(id, how)| Some((id, how, finding(id)?)))
    .map(|(id, how, other)| {
            let pair = [EffectId::Hysteresis, id];
            let on = ["x", "y", "z"].map(|a| {
                h.axes.iter().any(|x| x == a) && other.axes.iter().any(|x| x == a)
            });
            Coupling {
                effects: pair,
                correlation: extra(id).map_or([None; 3], |b| match how {
                    Estimate::TimeConstant => lag_correlation(data, f, he, b, on),
                    Estimate::Coefficient => correlation(f, he, b, on),
                }),
                why: format!(
                    "no temperature is seen at rest on both of the hysteresis's branches: it is one constant in the dwells after the first turn, which the temperature model takes, and is told from {id} by the ramps alone"
                ),
                needed: needed(&pair),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    /// Any 2x2 covariance: the profile's slope and conditional variance give back its
    /// correlation.
    #[test]
    fn a_profile_gives_the_gaussians_correlation() {
        let mut rng = Rng::new(27);
        for _ in 0..1000 {
            let (sa, ss) = (
                10f64.powf(4.0 * rng.uniform() - 6.0),
                10f64.powf(4.0 * rng.uniform() - 2.0),
            );
            let rho = 1.98 * rng.uniform() - 0.99;
            let c = rho * sa * ss;
            let (b, v) = (c / (ss * ss), sa * sa - c * c / (ss * ss));
            let r = from_profile(b, ss * ss, v);
            assert!((r - rho).abs() < 1e-12, "{r} for {rho}");
        }
    }
}
