//! The error floor: how much the mean of a window of n samples scatters from noise alone,
//! measured inside the dwells at every time scale (so time-correlated noise counts), with
//! robust statistics (so spikes do not inflate it) and second differences of block means
//! (so a slow drift through the dwell, a settling temperature, does not count as noise).
//! Quantised outputs (a digital sensor's counts, a coarse logger) whose noise is below one
//! step do not average down: their floor is the step's own, `q^2 / 12` for any mean.
use crate::data::recording::Recording;
use crate::model::rules::Rules;

/// Median of a chi-square with one degree of freedom: robust variance from squares.
const CHI2_1_MEDIAN: f64 = 0.454_936_423_119_572_8;

/// The measured floor of one axis.
#[derive(Debug, Clone, PartialEq)]
pub struct AxisFloor {
    /// `(m, support, variance of the mean of m consecutive samples)`, m = 1, 2, 4, ...:
    /// the support is the number of second differences behind the estimate.
    pub scales: Vec<(f64, f64, f64)>,
    /// The step of the axis's values when the noise is below it (half a step, sigma):
    /// the quantisation error then repeats sample after sample instead of averaging,
    /// and no mean is known better than `q / sqrt(12)` (the variance of a uniform error
    /// over one step).
    pub quantum: Option<f64>,
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
    /// The measured scales made consistent with stationary, positively correlated
    /// noise: the variance of a mean never rises with more samples, nor falls faster than
    /// white noise (1/m); each estimate is clamped into that band from the one before.
    fn consistent(&self) -> Vec<(f64, f64)> {
        let mut out: Vec<(f64, f64)> = Vec::with_capacity(self.scales.len());
        for &(m, _, v) in &self.scales {
            let v = match out.last() {
                Some(&(pm, pv)) => v.clamp(pv * pm / m, pv),
                None => v,
            };
            out.push((m, v));
        }
        out
    }

    /// Variance of the mean of `n` consecutive samples: interpolated in log-log between
    /// the (consistent) measured scales; beyond the longest one, continued with the last
    /// slope (between white, -1, and flat, 0). `None` when no scale was measurable (one
    /// sample per dwell).
    /// With a [`AxisFloor::quantum`], never below `q^2 / 12`.
    pub fn var_of_mean(&self, n: f64) -> Option<f64> {
        let v = self.measured_var_of_mean(n)?;
        Some(match self.quantum {
            Some(q) => v.max(q * q / 12.0),
            None => v,
        })
    }

    /// [`AxisFloor::var_of_mean`] from the measured scales alone (0 where they measured
    /// none: a quantised axis whose samples repeat).
    fn measured_var_of_mean(&self, n: f64) -> Option<f64> {
        let s = self.consistent();
        if s.iter().any(|(_, v)| v.is_nan() || *v <= 0.0) {
            return (!s.is_empty()).then_some(0.0);
        }
        let (m0, v0) = *s.first()?;
        let n = n.max(1.0);
        if n <= m0 {
            return Some(v0 * m0 / n);
        }
        let slope = |a: (f64, f64), b: (f64, f64)| (b.1.ln() - a.1.ln()) / (b.0.ln() - a.0.ln());
        for w in s.windows(2) {
            if n <= w[1].0 {
                let k = slope(w[0], w[1]);
                return Some((w[0].1.ln() + k * (n.ln() - w[0].0.ln())).exp());
            }
        }
        let k = match s.len() {
            1 => -1.0,
            l => slope(s[l - 2], s[l - 1]).clamp(-1.0, 0.0),
        };
        let (ml, vl) = s[s.len() - 1];
        Some((vl.ln() + k * (n.ln() - ml.ln())).exp())
    }

    /// How much more a mean of `n` samples scatters than white noise of the same
    /// per-sample variance predicts (1 = white).
    pub fn colour(&self, n: f64) -> Option<f64> {
        Some(self.var_of_mean(n)? * n.max(1.0) / self.var_of_mean(1.0)?)
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

/// Spikes: samples whose second difference inside a dwell is more than
/// [`Rules::spike_z`] robust sigmas out, on any axis.
fn spikes(rec: &Recording, rules: &Rules) -> Vec<usize> {
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
        if d2.len() < rules.floor_min_support {
            continue;
        }
        let mut sq: Vec<f64> = d2.iter().map(|(_, v)| v * v).collect();
        let sigma = robust_var(&mut sq).sqrt();
        out.extend(
            d2.iter()
                .filter(|(_, v)| v.abs() > rules.spike_z * sigma && sigma > 0.0)
                .map(|(r, _)| *r),
        );
    }
    out.sort_unstable();
    out.dedup();
    out
}

/// The second differences of three m-sample block means (start, middle and end of a
/// piece of `piece` samples) of every clean, steady piece of every dwell, on `axis`; the
/// pieces overlap by three quarters (more support; the median does not mind). Far-apart
/// blocks are (nearly) independent even when the noise is correlated, and the second
/// difference removes a linear drift.
fn triples(
    rec: &Recording,
    spikes: &[usize],
    rules: &Rules,
    axis: usize,
    m: usize,
    piece: usize,
) -> Vec<f64> {
    let mut sq = Vec::new();
    let stride = (piece / 4).max(1);
    for d in &rec.dwells {
        let rows = rec.dwell_rows(d);
        for j in (0..rows.len().saturating_sub(piece - 1)).step_by(stride) {
            let p = &rows[j..j + piece];
            let first = d.start + j;
            if (first..first + piece).any(|r| spikes.binary_search(&r).is_ok()) {
                continue;
            }
            let third = piece / 3;
            let tm = |k: usize| {
                p[k * third..(k + 1) * third]
                    .iter()
                    .map(|r| r.temp_c)
                    .sum::<f64>()
                    / third as f64
            };
            let (ta, tb, tc) = (tm(0), tm(1), tm(2));
            if (tc - ta).abs() > rules.floor_steady_span_c
                || (tc - 2.0 * tb + ta).abs() > rules.floor_steady_bend_c
            {
                continue;
            }
            let mean = |k: usize| p[k..k + m].iter().map(|r| r.u[axis]).sum::<f64>() / m as f64;
            let v = mean(piece - m) - 2.0 * mean((piece - m) / 2) + mean(0);
            sq.push(v * v);
        }
    }
    sq
}

/// The step of `axis`'s values in the dwells, when they all sit on one grid (integer
/// counts, a logger's fixed decimals); `None` when they do not, or take one value.
/// The grid is the smallest gap between distinct values; a value more than 1e-3 of a
/// step off it means no grid.
fn quantum(rec: &Recording, axis: usize) -> Option<f64> {
    let mut v: Vec<f64> = rec
        .dwells
        .iter()
        .flat_map(|d| rec.dwell_rows(d).iter().map(move |r| r.u[axis]))
        .collect();
    v.sort_by(f64::total_cmp);
    v.dedup();
    let q = v
        .windows(2)
        .map(|w| w[1] - w[0])
        .filter(|d| *d > 0.0)
        .min_by(f64::total_cmp)?;
    let v0 = v[0];
    v.iter()
        .all(|x| {
            let k = (x - v0) / q;
            (k - k.round()).abs() < 1e-3
        })
        .then_some(q)
}

/// Measure the floor of `rec`: pieces of [`Rules::floor_piece`] samples keep the three
/// blocks of a second difference far apart; recordings without such steady spans fall
/// back to adjacent blocks (white noise assumed between neighbours).
pub fn floor(rec: &Recording, rules: &Rules) -> Floor {
    let spikes = spikes(rec, rules);
    let longest = rec.dwells.iter().map(|d| d.len()).max().unwrap_or(0);
    let piece = rules.floor_piece;
    let base = if triples(rec, &spikes, rules, 0, 1, piece).len() >= rules.floor_min_support {
        piece
    } else {
        3
    };
    let axes = std::array::from_fn(|axis| {
        let mut scales = Vec::new();
        // scales up to a third of a piece: longer blocks would take in the slow
        // physics of the outputs as noise; beyond, the floor is extrapolated
        let mut m = 1usize;
        while 3 * m <= longest.min(base.max(3)) {
            let mut sq = triples(rec, &spikes, rules, axis, m, base.max(3 * m));
            if sq.len() >= rules.floor_min_support {
                // the middle block sits (piece - m) / 2 from both ends: independent blocks
                // give Var(b2 - 2 b1 + b0) = 6 Var(b)
                let n = sq.len() as f64;
                scales.push((m as f64, n, robust_var(&mut sq) / 6.0));
            }
            m *= 2;
        }
        let mut f = AxisFloor {
            scales,
            quantum: None,
        };
        if let Some(q) = quantum(rec, axis) {
            // the noise below half a step: the samples repeat, the step is the floor
            if f.measured_var_of_mean(1.0)
                .is_some_and(|v| v.sqrt() < 0.5 * q)
            {
                f.quantum = Some(q);
            }
        }
        f
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
            quantum: None,
        };
        assert!((f.var_of_mean(3.0).unwrap() - 4.0 / 3.0).abs() < 1e-12);
        assert!((f.var_of_mean(16.0).unwrap() - 0.25).abs() < 1e-12);
        assert!((f.colour(16.0).unwrap() - 1.0).abs() < 1e-12);
        assert!(AxisFloor {
            scales: vec![],
            quantum: None
        }
        .var_of_mean(4.0)
        .is_none());
    }

    #[test]
    fn correlated_noise_keeps_its_scatter_and_estimates_stay_consistent() {
        // flat up to 8 samples, then 1/m: colour 8 at 64 samples
        let f = AxisFloor {
            scales: vec![(1.0, 50.0, 1.0), (8.0, 50.0, 1.2), (64.0, 50.0, 0.125)],
            quantum: None,
        };
        assert!(
            (f.var_of_mean(8.0).unwrap() - 1.0).abs() < 1e-12,
            "a rise is clamped"
        );
        assert!((f.colour(64.0).unwrap() - 8.0).abs() < 1e-9);
        // never below white noise's 1/m from the scale before
        let g = AxisFloor {
            scales: vec![(1.0, 50.0, 1.0), (2.0, 50.0, 0.1)],
            quantum: None,
        };
        assert!((g.var_of_mean(2.0).unwrap() - 0.5).abs() < 1e-12);
    }

    /// Sub-step noise: samples that repeat measure no scatter, and the step's own
    /// `q^2 / 12` is the floor of every mean, however many samples it has.
    #[test]
    fn a_quantised_axis_below_its_step_has_the_steps_floor() {
        let f = AxisFloor {
            scales: vec![(1.0, 100.0, 0.0), (2.0, 50.0, 0.0)],
            quantum: Some(2.0),
        };
        for n in [1.0, 10.0, 1000.0] {
            assert!((f.var_of_mean(n).unwrap() - 4.0 / 12.0).abs() < 1e-12);
        }
        // measured noise above the step's floor stands
        let g = AxisFloor {
            scales: vec![(1.0, 100.0, 1.0)],
            quantum: Some(1.0),
        };
        assert!((g.var_of_mean(1.0).unwrap() - 1.0).abs() < 1e-12);
    }
}
