//! The search: the baseline (cross-sensitivities where identifiable, the polynomial
//! order by BIC), then catalogue effects added greedily while one lowers BIC clearly and
//! improves the held-out folds; time constants profiled; equally good rivals reported as
//! ambiguous.
use crate::diagnose::design::EFFECT_IDS;
use crate::diagnose::design::{Data, Extra, Fit, Spec};
use crate::diagnose::findings::{evidence_for, finding, needed, Ambiguity, Finding};
use crate::diagnose::metrics::bic;
use crate::fit::temperature::{temperature_clusters, Basis};

/// A candidate must lower BIC by more than this to be accepted ("clearly").
pub const BIC_MARGIN: f64 = 10.0;
/// Two candidates within this much BIC of each other explain the data equally well.
pub const AMBIGUITY_MARGIN: f64 = 6.0;
/// The baseline fit and what it could not identify; `None` when the positions present
/// do not determine even the per-axis offset and scale.
pub fn baseline(data: &Data) -> Option<(Fit, Vec<String>)> {
    let n_rows = 3 * data.obs.len();
    let temps: Vec<f64> = data.obs.iter().map(|o| o.temp_c).collect();
    let n_temps = temperature_clusters(&temps).len();
    for cross in [true, false] {
        let mut best: Option<Fit> = None;
        for order in 1..=5usize.min(n_temps.saturating_sub(1)).max(1) {
            let spec = Spec {
                basis: Basis::Poly { order },
                cross,
                extras: Vec::new(),
            };
            if let Some(f) = data.fit(&spec, None) {
                if best
                    .as_ref()
                    .is_none_or(|b| bic(&f, n_rows) < bic(b, n_rows))
                {
                    best = Some(f);
                }
            }
        }
        if let Some(b) = best {
            let mut not_identifiable = Vec::new();
            if !cross {
                not_identifiable.push(
                    "cross-sensitivities (need >= 4 positions not in one plane): fixed at 0"
                        .to_string(),
                );
            }
            return Some((b, not_identifiable));
        }
    }
    None
}

/// Where the forward search ended.
pub struct Outcome {
    /// The final model.
    pub current: Fit,
    /// Accepted findings.
    pub findings: Vec<Finding>,
    /// Candidates that could not be told apart.
    pub ambiguous: Vec<Ambiguity>,
}

/// `current` with `extra` added, fitted.
fn try_spec(data: &Data, extra: Extra, current: &Fit) -> Option<Fit> {
    let mut s = current.spec.clone();
    s.extras.push(extra);
    data.fit(&s, Some(current))
}

/// The best fit over a time constant: a log grid from 20 s, then golden-section search
/// in log tau around the best grid point.
fn profile(data: &Data, make: &dyn Fn(f64) -> Extra, current: &Fit) -> Option<Fit> {
    let mut best: Option<Fit> = None;
    for tau in (0..14).map(|k| 20.0 * 1.7f64.powi(k)) {
        if let Some(f) = try_spec(data, make(tau), current) {
            if best.as_ref().is_none_or(|b| f.chi2 < b.chi2) {
                best = Some(f);
            }
        }
    }
    let mut best = best?;
    let tau0 = best.spec.extras.iter().rev().find_map(|e| match e {
        Extra::Lag(t) | Extra::Warmup(t) => Some(*t),
        _ => None,
    })?;
    let (mut lo, mut hi) = ((tau0 / 1.7).ln(), (tau0 * 1.7).ln());
    let g = 0.618_033_988_75;
    for _ in 0..12 {
        let m1 = hi - g * (hi - lo);
        let m2 = lo + g * (hi - lo);
        let f1 = try_spec(data, make(m1.exp()), current);
        let f2 = try_spec(data, make(m2.exp()), current);
        let c1 = f1.as_ref().map(|f| f.chi2).unwrap_or(f64::INFINITY);
        let c2 = f2.as_ref().map(|f| f.chi2).unwrap_or(f64::INFINITY);
        let keep = if c1 < c2 {
            hi = m2;
            f1
        } else {
            lo = m1;
            f2
        };
        if let Some(f) = keep.filter(|f| f.chi2 < best.chi2) {
            best = f;
        }
    }
    Some(best)
}

/// Every candidate not yet used, fitted on top of `current`, with its BIC change; the
/// best per effect id.
fn trials(data: &Data, current: &Fit, used: &[&str], fine: &[f64]) -> Vec<(Fit, f64)> {
    let n_rows = 3 * data.obs.len();
    let mut cands: Vec<Option<Fit>> = Vec::new();
    if !used.contains(&"temp_curvature") {
        cands.push(try_spec(data, Extra::Curvature(fine.to_vec()), current));
    }
    if !used.contains(&"thermal_lag") {
        cands.push(profile(data, &Extra::Lag, current));
    }
    if !used.contains(&"warmup_drift") {
        cands.push(profile(data, &Extra::Warmup, current));
    }
    for e in [Extra::Rate, Extra::Hysteresis, Extra::K2, Extra::Asymmetry] {
        if !used.contains(&e.id()) {
            cands.push(try_spec(data, e, current));
        }
    }
    if !used.contains(&"fixture_error") {
        let mut positions: Vec<usize> = data.obs.iter().map(|o| o.position).collect();
        positions.sort_unstable();
        positions.dedup();
        for p in positions {
            cands.push(try_spec(data, Extra::Fixture(p), current));
        }
    }
    let mut per_id: Vec<(Fit, f64)> = Vec::new();
    for f in cands.into_iter().flatten() {
        let d = bic(&f, n_rows) - bic(current, n_rows);
        let id = last_id(&f);
        match per_id.iter_mut().find(|(g, _)| last_id(g) == id) {
            Some(slot) if d < slot.1 => *slot = (f, d),
            Some(_) => {}
            None => per_id.push((f, d)),
        }
    }
    per_id
}

fn last_id(f: &Fit) -> &'static str {
    f.spec.extras.last().map(|e| e.id()).unwrap_or("")
}

/// The fine piecewise-linear basis of the temp_curvature candidate: about one
/// breakpoint per 4 C over the data's range, at most 16.
pub fn fine_breakpoints(tmin: f64, tmax: f64) -> Vec<f64> {
    let nb = 16usize
        .min(((tmax - tmin) / 4.0).floor() as usize + 1)
        .max(2);
    (0..nb)
        .map(|k| tmin + (tmax - tmin) * k as f64 / (nb - 1) as f64)
        .collect()
}

/// Add effects to `baseline` while one is accepted.
pub fn forward(data: &Data, baseline: &Fit, fine: &[f64]) -> Outcome {
    let mut current = baseline.clone();
    let mut findings = Vec::new();
    let mut ambiguous = Vec::new();
    let mut used: Vec<&'static str> = Vec::new();
    loop {
        let mut per_id = trials(data, &current, &used, fine);
        if std::env::var_os("HOSTFIT_DEBUG").is_some() {
            for (f, d) in &per_id {
                eprintln!(
                    "  trial {:?}: dBIC {d:.1}, heldout {:.1} vs {:.1}",
                    f.spec.extras.last(),
                    f.heldout,
                    current.heldout
                );
            }
        }
        per_id.retain(|(f, d)| {
            *d < -BIC_MARGIN && f.heldout < current.heldout - 2.0 * (f.k - current.k) as f64
        });
        per_id.sort_by(|a, b| a.1.total_cmp(&b.1));
        let Some((best, d)) = per_id.first().cloned() else {
            break;
        };
        let id = last_id(&best);
        let rivals: Vec<&'static str> = per_id[1..]
            .iter()
            .filter(|(_, d2)| (d2 - d).abs() < AMBIGUITY_MARGIN)
            .map(|(f, _)| last_id(f))
            .collect();
        let evidence = evidence_for(data, &current, &best, id, d);
        if rivals.is_empty() {
            findings.push(finding(data, &best, &current, d, evidence));
        } else {
            let mut c = vec![id.to_string()];
            c.extend(rivals.iter().map(|s| s.to_string()));
            ambiguous.push(Ambiguity {
                candidates: c,
                needed: needed(id, rivals[0]),
            });
            used.extend(rivals.iter().copied());
        }
        used.push(id);
        current = best;
        if used.len() >= EFFECT_IDS.len() {
            break;
        }
    }
    Outcome {
        current,
        findings,
        ambiguous,
    }
}
