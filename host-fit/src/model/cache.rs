//! The firmware's cache of N(T): it recomputes its matrices only after the temperature
//! has moved by a step; how fast |a| drifts meanwhile (the calibration's own slopes, any
//! attitude), and the largest step whose cost stays within a noise floor. What floor a
//! fitted model gives is the fit's ([`crate::fit::cache`] for the static route's models;
//! [`crate::model::flashed`] for the diagnosed and dynamic ones).
use crate::model::precision::directions26;
use firmware_core::model::Coeffs;
use firmware_core::temperature::Calibration;
use serde::Serialize;

/// The largest cache step `fit`, `diagnose --out`, `batch` and the demo give the
/// firmware by default, C.
pub const MAX_CACHE_STEP_C: f64 = 0.1;
/// Grid of [`cache_slope`], C.
const CACHE_GRID_C: f64 = 0.05;

/// How fast |a| drifts while the firmware holds its cached coefficients and the unit's
/// temperature moves, g/C: `|d|a|/dT| = |a^T N (dK/dT a + dU0/dT)|` of the calibration's
/// own model, by differences over every 0.05 C cell of the valid range (exact within a
/// piecewise-linear segment), worst of 26 directions (any attitude: in flight too).
pub fn cache_slope(cal: &Calibration<f64>) -> f64 {
    let dirs = directions26();
    let eval = |t: f64| Coeffs::from_array(&cal.model.eval(cal.t0_c, t));
    let mut worst: f64 = 0.0;
    let mut t = cal.t_min_c;
    while t < cal.t_max_c {
        let h = CACHE_GRID_C.min(cal.t_max_c - t).max(1e-6);
        let (c0, c1) = (eval(t), eval(t + h));
        let Some(n) = firmware_core::model::invert(&c0.k) else {
            t += CACHE_GRID_C;
            continue;
        };
        for a in &dirs {
            // d|a'|/dT for the reading U(T + h) compensated with the coefficients of T
            let du: [f64; 3] = std::array::from_fn(|i| {
                (0..3)
                    .map(|j| (c1.k[i][j] - c0.k[i][j]) * a[j])
                    .sum::<f64>()
                    + c1.u0[i]
                    - c0.u0[i]
            });
            let da: [f64; 3] = std::array::from_fn(|i| (0..3).map(|j| n[i][j] * du[j]).sum());
            let d = (a[0] * da[0] + a[1] * da[1] + a[2] * da[2]).abs() / h;
            worst = worst.max(d);
        }
        t += CACHE_GRID_C;
    }
    worst
}

/// The firmware's cache of N(T): its step and the most it can cost.
#[derive(Debug, Clone, Copy, Serialize, PartialEq)]
pub struct Cache {
    /// The update step written into the blob, C.
    pub step_c: f64,
    /// The most the cache can add to |dg| anywhere in the valid range, at any attitude
    /// (`cache_slope` x step), mg.
    pub worst_mg: f64,
    /// The noise floor the default step keeps it within (a verification dwell's own
    /// noise, 1 sigma), mg; None when none is known.
    pub floor_mg: Option<f64>,
    /// Whether the step was chosen from the unit's slopes (true) or given.
    pub chosen: bool,
}

impl Cache {
    /// `given` (`--update-step`), or by default the largest step up to
    /// [`MAX_CACHE_STEP_C`] whose worst cost stays within `floor_mg` (rounded down to
    /// 1e-4 C); with no floor known, 0 (the model at every temperature).
    pub fn choose(cal: &Calibration<f64>, floor_mg: Option<f64>, given: Option<f64>) -> Cache {
        let slope_mg = cache_slope(cal) * 1e3;
        let step_c = match (given, floor_mg) {
            (Some(s), _) => s,
            (None, Some(f)) if f > 0.0 && slope_mg > 0.0 => {
                (((f / slope_mg).min(MAX_CACHE_STEP_C) * 1e4).floor() / 1e4).max(0.0)
            }
            (None, Some(f)) if f > 0.0 => MAX_CACHE_STEP_C,
            (None, _) => 0.0,
        };
        Cache {
            step_c,
            worst_mg: slope_mg * step_c,
            floor_mg,
            chosen: given.is_none(),
        }
    }

    /// One line for the command's text output.
    pub fn text(&self) -> String {
        let how = if self.chosen {
            match self.floor_mg {
                Some(f) => format!(
                    "chosen from the unit's slopes to stay within the dwell-noise floor {f:.4} mg"
                ),
                None => "no noise floor known: the model at every temperature".to_string(),
            }
        } else {
            "as given (--update-step)".to_string()
        };
        format!(
            "firmware cache: N(T) recomputed after {} C ({how}); it costs at most {:.4} mg anywhere in the valid range, at any attitude",
            self.step_c, self.worst_mg
        )
    }
}
