//! The baseline model: per axis the temperature models of the K row and offset, the
//! cross-sensitivities where the positions identify them, the polynomial order chosen by
//! the quasi-likelihood information criterion (in the richest order's dispersion); and
//! the order chosen again once effects are in the model.
use crate::error::{ErrorKind, HostError, Result};
use crate::model::basis::Basis;
use crate::model::data::Data;
use crate::model::design::Spec;
use crate::model::metrics::{dispersion, qbic};
use crate::model::orders::Orders;
use crate::model::solve::{Depth, Fit};

/// The highest polynomial order the data's temperatures support (at most
/// [`crate::model::rules::Rules::max_order`]).
pub fn max_order(data: &Data) -> usize {
    Orders::of(data).offsets
}

/// Of `fits` (every order of one spec), the one with the lowest quasi-BIC in the
/// dispersion of the richest (the last).
fn best_order<'f>(data: &Data, fits: &'f [Fit]) -> Option<&'f Fit> {
    let phi = fits.last().map(|f| dispersion(data, f))?;
    fits.iter()
        .min_by(|a, b| qbic(data, a, phi).total_cmp(&qbic(data, b, phi)))
}

/// The polynomial orders chosen again with `f`'s effects in the model (an effect can
/// free the baseline from bending to it, or show that it needs to bend more).
pub fn reorder(data: &Data, f: &Fit, orders: Orders) -> Fit {
    let fits: Vec<Fit> = orders
        .candidates()
        .into_iter()
        .filter_map(|(k, o)| data.fit(&f.spec.with_orders(k, o), None, Depth::Profile))
        .collect();
    best_order(data, &fits)
        .filter(|b| b.spec != f.spec)
        .and_then(|b| data.fit(&b.spec, None, Depth::Full))
        .unwrap_or_else(|| f.clone())
}

/// The baseline fit and what it could not identify; `None` when the positions present
/// do not determine even the per-axis offset and scale.
pub fn baseline(data: &Data) -> Option<(Fit, Vec<String>)> {
    let orders = Orders::of(data);
    for cross in [true, false] {
        let bare = Spec {
            basis: Basis::Poly { order: 0 },
            offset_order: None,
            cross,
            extras: Vec::new(),
        };
        let fits: Vec<Fit> = orders
            .candidates()
            .into_iter()
            .filter_map(|(k, o)| data.fit(&bare.with_orders(k, o), None, Depth::Profile))
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

/// [`baseline`], or an error naming the file that says why the data do not determine it:
/// the positions present are counted, not inferred from the failed fit.
pub fn required(data: &Data) -> Result<(Fit, Vec<String>)> {
    baseline(data).ok_or_else(|| {
        let reason = if positions_determine(data) {
            "the baseline fit is singular although the positions present determine the per-axis offset and scale (each axis both along and across gravity): the outputs do not vary with the positions"
        } else {
            "the positions present do not determine even the per-axis offset and scale (need each axis both along and across gravity)"
        };
        HostError::in_file(ErrorKind::Insufficient, &data.rec.path, reason)
    })
}

/// Whether the positions present hold each axis both along gravity (|f_i| > 1/2) and
/// across it (|f_i| < 1/2): what the per-axis offset and scale need, whatever the noise.
fn positions_determine(data: &Data) -> bool {
    (0..3).all(|i| {
        data.obs.iter().any(|o| o.a[i].abs() > 0.5) && data.obs.iter().any(|o| o.a[i].abs() < 0.5)
    })
}
