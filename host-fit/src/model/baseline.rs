//! The baseline model: per axis the temperature models of the K row and offset, the
//! cross-sensitivities where the positions identify them, the polynomial order chosen by
//! the quasi-likelihood information criterion (in the richest order's dispersion); and
//! the order chosen again once effects are in the model.
use crate::error::{ErrorKind, HostError, Result};
use crate::model::basis::{temperature_clusters, Basis};
use crate::model::data::Data;
use crate::model::design::Spec;
use crate::model::metrics::{dispersion, qbic};
use crate::model::solve::{Depth, Fit};

/// The highest polynomial order the data's temperatures support (at most
/// [`crate::model::rules::Rules::max_order`]).
pub fn max_order(data: &Data) -> usize {
    Orders::of(data).offsets
}

/// The polynomial orders a recording supports. A chamber ramp logged at one position
/// counts as many temperatures, but it shows one direction of the twelve coefficients:
/// that position's outputs, which the offsets carry. The K rows need each of four
/// positions (the fewest not in one plane) seen at as many temperatures as their order
/// has terms, so their order is counted per position; the offsets' over all the
/// windows ([`Orders::candidates`] adds the offsets alone one order up beyond the K
/// rows' count). A quintic of all twelve on five stops and their ramps rests, in the
/// directions no ramp shows, on the temperature's spread inside the stops: the lag +
/// rate twin of seed 4 chose it without that candidate and flew at 0.073 mg between
/// two stops; with it, the quartic, at 0.035 mg.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Orders {
    /// The K rows' highest order (and the offsets' with it).
    pub k: usize,
    /// The offsets' highest order (at least `k`).
    pub offsets: usize,
}

impl Orders {
    /// The orders `data` supports.
    pub fn of(data: &Data) -> Orders {
        let cap = data.rules.max_order;
        let all: Vec<f64> = data.obs.iter().map(|o| o.temp_c).collect();
        let offsets = cap.min(temperature_clusters(&all).len().saturating_sub(1));
        let mut per_position: Vec<usize> = Vec::new();
        let mut positions: Vec<usize> = data.obs.iter().map(|o| o.position).collect();
        positions.sort_unstable();
        positions.dedup();
        for p in positions {
            let temps: Vec<f64> = data
                .obs
                .iter()
                .filter(|o| o.position == p)
                .map(|o| o.temp_c)
                .collect();
            per_position.push(temperature_clusters(&temps).len());
        }
        per_position.sort_unstable_by(|a, b| b.cmp(a));
        // the fourth best, or the worst when fewer positions (the fit then drops the
        // cross terms, or cannot be made)
        let k_temps = per_position
            .get(3)
            .or(per_position.last())
            .copied()
            .unwrap_or(0);
        Orders {
            k: offsets.min(k_temps.saturating_sub(1)),
            offsets,
        }
    }

    /// Every (K order, offsets' order) tried, each nested in the next: every order up to
    /// the offsets' for all twelve, and between the K rows' own highest and the next the
    /// offsets alone one order up. The orders above the K rows' stay candidates: the
    /// temperatures inside the stops (a stop reached from above and from below, a soak
    /// still settling) do show the K rows' bend, and a unit that bends more than the
    /// stops' count allows would otherwise be handed to `temp_curvature` (the clean unit
    /// of three heat-cool cycles, four distinct stops, was); the information criterion
    /// chooses.
    pub fn candidates(self) -> Vec<(usize, usize)> {
        let mut out = Vec::new();
        for n in 0..=self.offsets {
            out.push((n, n));
            if n == self.k && self.k < self.offsets {
                out.push((n, n + 1));
            }
        }
        out
    }
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
