//! The error floor: how much the mean of a window of n samples scatters from noise alone,
//! measured inside the dwells at every time scale (so time-correlated noise counts), with
//! robust statistics (so spikes do not inflate it) and second differences of block means
//! (so a slow drift through the dwell, a settling temperature, does not count as noise).
use crate::data::recording::Recording;

/// Median of a chi-square with one degree of freedom: robust variance from squares.
const CHI2_1_MEDIAN: f64 = 0.454_936_423_119_572_8;
/// A scale is measured when at least this many second differences support it.
const MIN_SUPPORT: usize = 12;
/// Block triples are used only where the temperature spans at most this (C): at long
/// time scales a moving temperature drives the outputs, and that is physics, not noise.
const STEADY_SPAN_C: f64 = 0.2;
/// A sample whose second difference is this many robust sigmas out is a spike.
pub const SPIKE_Z: f64 = 8.0;

/// The measured floor of one axis.
#[derive(Debug, Clone, PartialEq)]
pub struct AxisFloor {
    /// `(m, support, variance of the mean of m consecutive samples)`, m = 1, 2, 4, ...:
    /// the support is the number of second differences behind the estimate.
    pub scales: Vec<(f64, f64, f64)>,
}

/// The floor of the three axes, and the spikes found on the way.
#[derive(Debug, Clone, PartialEq)]
pub struct Floor {
    /// Per axis.
    pub axes: [AxisFloor; 3],
    /// Rows whose sample is a spike on some axis (excluded from window means).
    pub spikes: Vec<usize>,
}

impl AxisFloor {
    /// The floor model `v(m) = white / m + flat`: white noise, plus a part that does not
    /// average down within a window (flicker, slow wander). Fitted by least squares in
    /// relative terms to the measured scales (each weighted by its support), both parts
    /// kept non-negative. `None` when no scale was measurable (one sample per dwell).
    pub fn model(&self) -> Option<(f64, f64)> {
        let s = &self.scales;
        let (_, _, v0) = *s.first()?;
        // minimise sum n_j ((A/m_j + B) / v_j - 1)^2 over A, B >= 0
        let (mut saa, mut sab, mut sbb, mut sa, mut sb) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for &(m, n, v) in s {
            let (x, y) = (1.0 / (m * v), 1.0 / v);
            saa += n * x * x;
            sab += n * x * y;
            sbb += n * y * y;
            sa += n * x;
            sb += n * y;
        }
        let det = saa * sbb - sab * sab;
        let (a, b) = if det > 0.0 {
            ((sa * sbb - sb * sab) / det, (sb * saa - sa * sab) / det)
        } else {
            (v0, 0.0)
        };
        Some(match (a >= 0.0, b >= 0.0) {
            (true, true) => (a, b),
            (false, _) => (0.0, sb / sbb),
            (true, false) => (sa / saa, 0.0),
        })
    }

    /// Variance of the mean of `n` consecutive samples ([`AxisFloor::model`]).
    pub fn var_of_mean(&self, n: f64) -> Option<f64> {
        let (a, b) = self.model()?;
        Some(a / n.max(1.0) + b)
    }

    /// How much more a mean of `n` samples scatters than white noise of the same
    /// per-sample variance predicts (1 = white).
    pub fn colour(&self, n: f64) -> Option<f64> {
        let (a, b) = self.model()?;
        let white = (a + b) / n.max(1.0);
        Some((a / n.max(1.0) + b) / white)
    }

    /// Standard deviation of one sample.
    pub fn sample_sigma(&self) -> Option<f64> {
        self.var_of_mean(1.0).map(f64::sqrt)
    }
}

fn robust_var(sq: &mut [f64]) -> f64 {
    sq.sort_by(f64::total_cmp);
    sq[sq.len() / 2] / CHI2_1_MEDIAN
}

/// Spikes: samples whose second difference inside a dwell is more than [`SPIKE_Z`] robust
/// sigmas out, on any axis.
fn spikes(rec: &Recording) -> Vec<usize> {
    let mut out = Vec::new();
    for axis in 0..3 {
        let mut d2: Vec<(usize, f64)> = Vec::new();
        for d in &rec.dwells {
            let rows = rec.dwell_rows(d);
            for k in 1..rows.len().saturating_sub(1) {
                let v = rows[k + 1].u[axis] - 2.0 * rows[k].u[axis] + rows[k - 1].u[axis];
                d2.push((d.start + k, v));
            }
        }
        if d2.len() < MIN_SUPPORT {
            continue;
        }
        let mut sq: Vec<f64> = d2.iter().map(|(_, v)| v * v).collect();
        let sigma = robust_var(&mut sq).sqrt();
        out.extend(
            d2.iter()
                .filter(|(_, v)| v.abs() > SPIKE_Z * sigma && sigma > 0.0)
                .map(|(r, _)| *r),
        );
    }
    out.sort_unstable();
    out.dedup();
    out
}

/// Measure the floor of `rec`.
pub fn floor(rec: &Recording) -> Floor {
    let spikes = spikes(rec);
    let is_spike = |r: usize| spikes.binary_search(&r).is_ok();
    let longest = rec.dwells.iter().map(|d| d.len()).max().unwrap_or(0);
    let axes = std::array::from_fn(|axis| {
        let mut scales = Vec::new();
        let mut m = 1usize;
        while 3 * m <= longest {
            let mut sq = Vec::new();
            for d in &rec.dwells {
                let rows = rec.dwell_rows(d);
                // (mean, lowest and highest temperature) of each clean block
                let blocks: Vec<Option<(f64, f64, f64)>> = rows
                    .chunks_exact(m)
                    .enumerate()
                    .map(|(j, c)| {
                        let clean = (0..m).all(|k| !is_spike(d.start + j * m + k));
                        clean.then(|| {
                            let (lo, hi) = c.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), r| {
                                (l.min(r.temp_c), h.max(r.temp_c))
                            });
                            (c.iter().map(|r| r.u[axis]).sum::<f64>() / m as f64, lo, hi)
                        })
                    })
                    .collect();
                for w in blocks.windows(3) {
                    if let [Some(a), Some(b), Some(c)] = w {
                        let span = a.2.max(b.2).max(c.2) - a.1.min(b.1).min(c.1);
                        if span <= STEADY_SPAN_C {
                            let v = c.0 - 2.0 * b.0 + a.0;
                            sq.push(v * v);
                        }
                    }
                }
            }
            if sq.len() >= MIN_SUPPORT {
                // Var(b2 - 2 b1 + b0) = 6 Var(b) for independent block means
                let n = sq.len() as f64;
                scales.push((m as f64, n, robust_var(&mut sq) / 6.0));
            }
            m *= 2;
        }
        AxisFloor { scales }
    });
    Floor { axes, spikes }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn white_noise_scales_as_one_over_n() {
        let f = AxisFloor {
            scales: vec![(1.0, 100.0, 4.0), (2.0, 50.0, 2.0), (4.0, 25.0, 1.0)],
        };
        assert!((f.var_of_mean(3.0).unwrap() - 4.0 / 3.0).abs() < 1e-12);
        assert!((f.var_of_mean(16.0).unwrap() - 0.25).abs() < 1e-12);
        assert!((f.colour(16.0).unwrap() - 1.0).abs() < 1e-12);
        assert!(AxisFloor { scales: vec![] }.var_of_mean(4.0).is_none());
    }

    #[test]
    fn a_part_that_does_not_average_down_is_kept() {
        // v(m) = 4/m + 1
        let f = AxisFloor {
            scales: (0..6)
                .map(|k| {
                    let m = f64::from(1u32 << k);
                    (m, 100.0 / m, 4.0 / m + 1.0)
                })
                .collect(),
        };
        let (a, b) = f.model().unwrap();
        assert!((a - 4.0).abs() < 1e-9 && (b - 1.0).abs() < 1e-9, "{a} {b}");
        assert!(f.colour(64.0).unwrap() > 10.0);
    }
}
