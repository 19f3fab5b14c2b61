//! The search: the baseline (cross-sensitivities where identifiable, the polynomial
//! order by the information criterion), then catalogue effects added one at a time while
//! one passes every acceptance rule, then a backward check of the joint model and a check
//! that each effect explains the data where it acts.
//!
//! Acceptance rules (all scaled by the dispersion phi of the larger model, so a model
//! still far from the data cannot buy findings with small improvements):
//! - the quasi-BIC drops by more than [`Q_MARGIN`];
//! - the effect explains at least [`MATERIAL_SHARE`] of the chi-square above the floor;
//! - one of its parameters is at least [`Z_SIGNIFICANT`] scaled sigmas from zero;
//! - the held-out time chunks improve by more than 2 per parameter (in floor units);
//! - its profiled structure (time constant, bend) is determined by the data.
use crate::diagnose::design::{Data, Fit, Spec};
use crate::diagnose::effects::{Extra, EFFECT_IDS};
use crate::diagnose::metrics::{dispersion, qbic};
use crate::diagnose::profile;
use crate::fit::temperature::{temperature_clusters, Basis};

/// A candidate must lower the quasi-BIC by more than this to be accepted.
pub const Q_MARGIN: f64 = 10.0;
/// Two candidates within this much quasi-BIC of each other explain the data equally well.
pub const AMBIGUITY_MARGIN: f64 = 6.0;
/// A candidate must explain at least this share of the chi-square above the floor.
pub const MATERIAL_SHARE: f64 = 0.2;
/// A parameter is significant at this many sigmas (scaled by the dispersion).
pub const Z_SIGNIFICANT: f64 = 4.0;
/// Where an effect acts, the final residual must be at most this fraction of what it is
/// without the effect (RMS), or at the floor (below [`AT_FLOOR_RMS`]).
pub const ADEQUATE_RATIO: f64 = 0.5;
/// A residual RMS (floor units) at or below this is at the floor.
pub const AT_FLOOR_RMS: f64 = 1.5;

/// What the data can identify.
pub struct Scope {
    /// Temperature-dependent effects (more than one temperature).
    pub temperature: bool,
    /// Time-series effects (the floor is measurable and the temperature moves).
    pub dynamics: bool,
    /// The direction of temperature changes reverses (hysteresis).
    pub reversals: bool,
    /// Highest polynomial order of the baseline the temperatures support.
    pub max_order: usize,
}

/// The highest polynomial order the data's temperatures support (5 at most).
pub fn max_order(data: &Data) -> usize {
    let temps: Vec<f64> = data.obs.iter().map(|o| o.temp_c).collect();
    5usize.min(temperature_clusters(&temps).len().saturating_sub(1))
}

/// The polynomial order chosen again with `f`'s effects in the model (an effect can
/// free the baseline from bending to it, or show that it needs to bend more).
pub fn reorder(data: &Data, f: &Fit, max_order: usize) -> Fit {
    let fits: Vec<Fit> = (0..=max_order)
        .filter_map(|order| {
            let mut spec = f.spec.clone();
            spec.basis = Basis::Poly { order };
            data.fit(&spec, None, false)
        })
        .collect();
    let Some(phi) = fits.last().map(|x| dispersion(data, x)) else {
        return f.clone();
    };
    fits.iter()
        .min_by(|a, b| qbic(data, a, phi).total_cmp(&qbic(data, b, phi)))
        .filter(|b| b.spec.basis != f.spec.basis)
        .and_then(|b| data.fit(&b.spec, None, true))
        .unwrap_or_else(|| f.clone())
}

/// The baseline fit and what it could not identify; `None` when the positions present
/// do not determine even the per-axis offset and scale.
pub fn baseline(data: &Data) -> Option<(Fit, Vec<String>)> {
    let max_order = max_order(data);
    for cross in [true, false] {
        let fits: Vec<Fit> = (0..=max_order)
            .filter_map(|order| {
                let spec = Spec {
                    basis: Basis::Poly { order },
                    cross,
                    extras: Vec::new(),
                };
                data.fit(&spec, None, false)
            })
            .collect();
        // one dispersion for all orders: the richest's
        let Some(phi) = fits.last().map(|f| dispersion(data, f)) else {
            continue;
        };
        let best = fits
            .iter()
            .min_by(|a, b| qbic(data, a, phi).total_cmp(&qbic(data, b, phi)))?;
        let fit = data.fit(&best.spec, None, true)?;
        let mut not_identifiable = Vec::new();
        if !cross {
            not_identifiable.push(
                "cross-sensitivities (need >= 4 positions not in one plane): fixed at 0"
                    .to_string(),
            );
        }
        return Some((fit, not_identifiable));
    }
    None
}

/// Every candidate's best form on top of `current`, for profiling (no held-out chunks).
fn candidates(data: &Data, current: &Fit, scope: &Scope, used: &[&str]) -> Vec<Fit> {
    let spec = &current.spec;
    let count = |id: &str| spec.extras.iter().filter(|e| e.id() == id).count();
    let open = |id: &str| !used.contains(&id) && count(id) < Extra::max_count(id);
    let mut out = Vec::new();
    let single = |e: Extra| data.fit(&spec.with(e), Some(current), false);
    if scope.temperature && open("temp_curvature") {
        let broad = !spec.extras.iter().any(|e| matches!(e, Extra::Curvature(_)));
        out.extend(choose_form(
            data,
            current,
            profile::curvature(data, spec, current, broad),
        ));
    }
    if scope.dynamics && open("thermal_lag") {
        out.extend(choose_form(
            data,
            current,
            profile::lag(data, spec, current),
        ));
    }
    if scope.dynamics && open("temp_rate") {
        out.extend(profile::rate(data, spec, current));
    }
    if scope.dynamics && scope.reversals && open("hysteresis") {
        out.extend(choose_form(
            data,
            current,
            profile::hysteresis(data, spec, current),
        ));
    }
    if scope.dynamics && open("warmup_drift") {
        out.extend(choose_form(
            data,
            current,
            profile::warmup(data, spec, current),
        ));
    }
    for e in [Extra::K2, Extra::Asymmetry] {
        if open(e.id()) {
            out.extend(single(e));
        }
    }
    if open("fixture_error") {
        let mut positions: Vec<usize> = data.obs.iter().map(|o| o.position).collect();
        positions.sort_unstable();
        positions.dedup();
        let taken: Vec<usize> = spec
            .extras
            .iter()
            .filter_map(|e| match e {
                Extra::Fixture(p) => Some(*p),
                _ => None,
            })
            .collect();
        for p in positions.into_iter().filter(|p| !taken.contains(p)) {
            out.extend(single(Extra::Fixture(p)));
        }
    }
    out
}

/// Of several forms of one effect on top of `current`, the simplest, unless a richer one
/// fits better AND passes every acceptance rule against it (a richer form must earn its
/// parameters as an effect must).
fn choose_form(data: &Data, current: &Fit, mut forms: Vec<Fit>) -> Option<Fit> {
    forms.sort_by_key(|f| f.params());
    let mut pick: Option<Fit> = None;
    for f in forms {
        let Some(p) = &pick else {
            pick = Some(f);
            continue;
        };
        if f.chi2 >= p.chi2 {
            continue;
        }
        let (Some(pf), Some(ff)) = (
            data.fit(&p.spec, Some(current), true),
            data.fit(&f.spec, Some(current), true),
        ) else {
            continue;
        };
        let e = ff.spec.extras.len() - 1;
        if judge(data, &pf, &ff, e).accepted() {
            pick = Some(f);
        }
    }
    pick
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
    /// curves enough that its 1-sigma is within a factor e^0.5 (time constants) or 5 C (a
    /// bend). A flat profile means the form is not what the data show.
    pub determined: bool,
}

impl Judgement {
    /// Every acceptance rule passed.
    pub fn accepted(&self) -> bool {
        self.gain > Q_MARGIN
            && self.share >= MATERIAL_SHARE
            && self.heldout_gain > 2.0
            && self.max_z.is_none_or(|z| z >= Z_SIGNIFICANT)
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

/// Where the forward search ended.
pub struct Outcome {
    /// The model with the effects accepted.
    pub current: Fit,
    /// Groups of candidates that explained the data equally well (the best of each group
    /// is in the model, none is named).
    pub ambiguous: Vec<Vec<&'static str>>,
}

/// Add effects to `baseline` while one is accepted.
pub fn forward(data: &Data, baseline: &Fit, scope: &Scope) -> Outcome {
    let mut current = baseline.clone();
    let mut ambiguous = Vec::new();
    let mut used: Vec<&'static str> = Vec::new();
    let dbg = std::env::var_os("HOSTFIT_DEBUG").is_some();
    loop {
        let cands = candidates(data, &current, scope, &used);
        // rank by quasi-BIC gain, each in its own dispersion
        let mut ranked: Vec<(f64, Fit)> = cands
            .into_iter()
            .map(|f| {
                let phi = dispersion(data, &f);
                (qbic(data, &current, phi) - qbic(data, &f, phi), f)
            })
            .filter(|(g, _)| *g > Q_MARGIN)
            .collect();
        ranked.sort_by(|a, b| b.0.total_cmp(&a.0));
        let mut accepted: Option<(f64, Fit)> = None;
        let mut rivals: Vec<&'static str> = Vec::new();
        for (gain, f) in ranked.into_iter().take(6) {
            let id = last_id(&f);
            if let Some((best_gain, best)) = &accepted {
                if id != last_id(best)
                    && best_gain - gain < AMBIGUITY_MARGIN
                    && !rivals.contains(&id)
                {
                    rivals.push(id);
                }
                continue;
            }
            let Some(full) = data.fit(&f.spec, Some(&current), true) else {
                continue;
            };
            let j = judge(data, &current, &full, full.spec.extras.len() - 1);
            if dbg {
                eprintln!(
                    "  {:?}: {j:?} accepted {}",
                    full.spec.extras.last(),
                    j.accepted()
                );
            }
            if j.accepted() {
                accepted = Some((gain, full));
            }
        }
        let Some((_, best)) = accepted else {
            break;
        };
        let id = last_id(&best);
        if !rivals.is_empty() {
            let mut group = vec![id];
            group.extend(rivals.iter().copied());
            used.extend(rivals);
            ambiguous.push(group);
        }
        if best.spec.extras.iter().filter(|e| e.id() == id).count() >= Extra::max_count(id) {
            used.push(id);
        }
        current = reorder(data, &best, scope.max_order);
        if used.len() >= EFFECT_IDS.len() {
            break;
        }
    }
    Outcome { current, ambiguous }
}

fn last_id(f: &Fit) -> &'static str {
    f.spec.extras.last().map(|e| e.id()).unwrap_or("")
}

/// The joint model without extra `e`, refitted.
pub fn without(data: &Data, f: &Fit, e: usize) -> Option<Fit> {
    data.fit(&f.spec.without(e), None, true)
}

/// Drop, one at a time, the effect the joint model needs least while one of them no
/// longer passes the acceptance rules against the model without it.
pub fn backward(data: &Data, mut current: Fit) -> Fit {
    loop {
        let mut weakest: Option<(f64, Fit)> = None;
        for e in 0..current.spec.extras.len() {
            let Some(reduced) = without(data, &current, e) else {
                continue;
            };
            let j = judge(data, &reduced, &current, e);
            if !j.accepted() && weakest.as_ref().is_none_or(|(g, _)| j.gain < *g) {
                weakest = Some((j.gain, reduced));
            }
        }
        match weakest {
            Some((_, reduced)) => current = reduced,
            None => return current,
        }
    }
}

/// RMS (floor units) of `f`'s residual over the rows where `contribution` (floor units)
/// exceeds 2.
fn region_rms(data: &Data, f: &Fit, contribution: &[f64]) -> Option<f64> {
    let rows: Vec<usize> = (0..contribution.len())
        .filter(|&r| contribution[r].abs() > 2.0)
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

/// An effect's contribution to the model, per residual row in floor units: the joint
/// model's prediction minus the prediction without it.
pub fn contribution(data: &Data, full: &Fit, reduced: &Fit) -> Vec<f64> {
    (0..data.n_rows())
        .map(|r| (reduced.resid[r / 3][r % 3] - full.resid[r / 3][r % 3]) * data.w[r].sqrt())
        .collect()
}

/// Whether extra `e` explains the data where it acts: there the joint model's residual is
/// at the floor, or at most [`ADEQUATE_RATIO`] of the residual without the effect.
pub fn adequate(data: &Data, full: &Fit, reduced: &Fit) -> bool {
    let c = contribution(data, full, reduced);
    match (region_rms(data, full, &c), region_rms(data, reduced, &c)) {
        (Some(after), Some(before)) => after <= AT_FLOOR_RMS || after <= ADEQUATE_RATIO * before,
        _ => false,
    }
}

/// Drop every effect that does not explain the data where it acts (its region is
/// reported as unexplained instead); refits after each drop.
pub fn keep_adequate(data: &Data, mut current: Fit) -> Fit {
    'again: loop {
        for e in 0..current.spec.extras.len() {
            let Some(reduced) = without(data, &current, e) else {
                continue;
            };
            if !adequate(data, &current, &reduced) {
                if std::env::var_os("HOSTFIT_DEBUG").is_some() {
                    eprintln!("  not adequate: {:?}", current.spec.extras[e]);
                }
                current = reduced;
                continue 'again;
            }
        }
        return current;
    }
}
