//! The baseline model: per axis the temperature models of the K row and offset, the
//! cross-sensitivities where the positions identify them, the polynomial order chosen by
//! the quasi-likelihood information criterion (in the richest order's dispersion); and
//! the order chosen again once effects are in the model.
use crate::diagnose::data::Data;
use crate::diagnose::design::Spec;
use crate::diagnose::fit::{Depth, Fit};
use crate::diagnose::metrics::{dispersion, qbic};
use crate::fit::temperature::{temperature_clusters, Basis};

/// The highest polynomial order the data's temperatures support (at most
/// [`crate::diagnose::rules::Rules::max_order`]).
pub fn max_order(data: &Data) -> usize {
    let temps: Vec<f64> = data.obs.iter().map(|o| o.temp_c).collect();
    data.rules
        .max_order
        .min(temperature_clusters(&temps).len().saturating_sub(1))
}

/// Of `fits` (every order of one spec), the one with the lowest quasi-BIC in the
/// dispersion of the richest (the last).
fn best_order<'f>(data: &Data, fits: &'f [Fit]) -> Option<&'f Fit> {
    let phi = fits.last().map(|f| dispersion(data, f))?;
    fits.iter()
        .min_by(|a, b| qbic(data, a, phi).total_cmp(&qbic(data, b, phi)))
}

/// The polynomial order chosen again with `f`'s effects in the model (an effect can
/// free the baseline from bending to it, or show that it needs to bend more).
pub fn reorder(data: &Data, f: &Fit, max_order: usize) -> Fit {
    let fits: Vec<Fit> = (0..=max_order)
        .filter_map(|order| {
            let mut spec = f.spec.clone();
            spec.basis = Basis::Poly { order };
            data.fit(&spec, None, Depth::Profile)
        })
        .collect();
    best_order(data, &fits)
        .filter(|b| b.spec.basis != f.spec.basis)
        .and_then(|b| data.fit(&b.spec, None, Depth::Full))
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
                data.fit(&spec, None, Depth::Profile)
            })
            .collect();
        if fits.is_empty() {
            continue;
        }
        let best = best_order(data, &fits)?;
        let fit = data.fit(&best.spec, None, Depth::Full)?;
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
