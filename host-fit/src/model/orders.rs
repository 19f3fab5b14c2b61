//! The polynomial orders of a temperature model, the K rows' and the offsets': those a
//! recording's temperatures support (ramps logged at rest count for the offsets only),
//! and the candidates the baseline's order is chosen from.
use crate::model::basis::temperature_clusters;
use crate::model::data::Data;

/// Polynomial orders of the K rows and of the offsets: those a recording supports
/// ([`Orders::of`]), or a model's ([`crate::model::design::Spec::poly_orders`]). A
/// chamber ramp logged at one position counts as many temperatures, but it shows one
/// direction of the twelve coefficients:
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
    /// The K rows' order (the offsets' at least).
    pub k: usize,
    /// The offsets' order (at least `k`).
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
