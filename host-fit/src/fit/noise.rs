//! The measurement noise: the scatter of single samples inside dwells.
use crate::data::recording::Recording;

/// Measurement noise per axis, from the scatter inside dwells.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Noise {
    /// Standard deviation of one sample, output units.
    pub sigma: [f64; 3],
    /// Degrees of freedom behind the estimate (0: unknown, unit weights used).
    pub dof: usize,
}

impl Noise {
    /// Where the noise level comes from, in words (the one statement of it in outputs).
    pub fn source(&self) -> &'static str {
        if self.dof > 0 {
            "in-dwell (successive samples)"
        } else {
            "none in the dwells (one sample each): the fit's residual scatter is used"
        }
    }
}

/// Estimate the per-sample noise from successive differences inside dwells: half the
/// mean squared difference is the variance, and a slow drift (temperature settling)
/// barely touches it, unlike the plain in-dwell variance.
pub fn noise(rec: &Recording) -> Noise {
    let mut ss = [0.0; 3];
    let mut dof = 0usize;
    for d in &rec.dwells {
        for w in rec.dwell_rows(d).windows(2) {
            if let [a, b] = w {
                for (s, (x, y)) in ss.iter_mut().zip(a.u.iter().zip(b.u.iter())) {
                    *s += (y - x) * (y - x);
                }
                dof += 1;
            }
        }
    }
    if dof == 0 {
        return Noise {
            sigma: [1.0; 3],
            dof: 0,
        };
    }
    Noise {
        sigma: ss.map(|s| (s / (2.0 * dof as f64)).sqrt().max(1e-15)),
        dof,
    }
}
