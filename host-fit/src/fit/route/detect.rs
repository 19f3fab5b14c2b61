//! Which identification route a recording calls for: the static route for a unit in
//! equilibrium, the dynamic one for a sweep (most dwells move in temperature: its
//! [`Shape`]), and for a stop-and-soak test whose dwells still carry the sensing element's
//! settling (a thermal lag its soaks did not wait out: the static fit cannot see it and
//! leaves it in its residuals). Looking for the settling costs one pass over the rows; the
//! dynamic route, which then decides on held-out blocks of time, runs only where it is
//! seen.
use crate::data::positions::Role;
use crate::data::recording::{Dwell, Recording, MAX_DWELL_DRIFT_C};
use crate::fit::temperature::ModelFit;
use crate::model::basis::temperature_clusters;
use crate::model::lsq::residual;
use firmware_core::model::Coeffs;
use nalgebra::{DMatrix, DVector};
use serde::Serialize;

/// A recording is a sweep when at least this share of its dwells drift more than
/// [`MAX_DWELL_DRIFT_C`] (the static route keeps none of them). Counted in dwells, not
/// samples: a stop-and-soak test's few long rests through its ramps hold most of its
/// samples, its tilter's dwells are static.
pub const SWEEP_MOVING_SHARE: f64 = crate::data::recording::SWEEP_MOVING_SHARE;

/// How much of a recording's dwells move in temperature.
#[derive(Debug, Clone, Copy, Serialize, PartialEq)]
pub struct Shape {
    /// Dwells within [`MAX_DWELL_DRIFT_C`] (the static route's data).
    pub static_dwells: usize,
    /// Dwells drifting more.
    pub moving_dwells: usize,
    /// Share of the dwells that move.
    pub moving_share: f64,
}

impl Shape {
    /// The dwells of `rec`.
    pub fn of(rec: &Recording) -> Shape {
        let m = rec
            .dwells
            .iter()
            .filter(|d| d.temp_span_c > MAX_DWELL_DRIFT_C)
            .count();
        let n = rec.dwells.len();
        Shape {
            static_dwells: n - m,
            moving_dwells: m,
            moving_share: rec.moving_share(),
        }
    }

    /// Most dwells move in temperature: a sweep, for the dynamic route.
    pub fn is_sweep(&self) -> bool {
        self.moving_share >= SWEEP_MOVING_SHARE
    }
}

/// The settling the static fit left in its dwells.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Settling {
    /// The first-order lag (s) whose settling best matches the residuals.
    pub tau_s: f64,
    /// Share of the dwells' residual sum of squares it explains (0..1).
    pub explained: f64,
    /// Its scale: 1 when the residual is the whole settling, less where the static model
    /// took part of it up.
    pub beta: f64,
}

impl Settling {
    /// Whether the dynamic route should be tried: the settling explains at least
    /// [`SETTLING_SHARE`] of the residual with a physical scale (0 < beta < 2).
    pub fn seen(&self) -> bool {
        self.explained >= SETTLING_SHARE && self.beta > 0.0 && self.beta < 2.0
    }
}

/// Share of the static fit's residual a settling must explain before `fit` tries the
/// dynamic route. Chance correlation of noise with the best of the lag grid is a few
/// percent over a test's 60-360 dwell-axes; a 10-min lag behind 40-min soaks explains
/// most of it. A false trigger costs the dynamic route's time only: the held-out blocks,
/// not this share, decide whether a lag is kept.
pub const SETTLING_SHARE: f64 = 0.3;

/// Lags tried, s: from a minute by this ratio up to a third of the recording.
const GRID_FIRST_S: f64 = 60.0;
/// See [`GRID_FIRST_S`].
const GRID_RATIO: f64 = 1.5;

/// The element's temperature minus the sensor's at every row, for a first-order lag of
/// `tau_s` on the rows' own clock, the sensor taken as linear between rows (exact for
/// that input, whatever the spacing); settled at the first row.
pub fn lag_offset(rec: &Recording, tau_s: f64) -> Vec<f64> {
    let mut e = 0.0;
    let mut prev: Option<(f64, f64)> = None;
    rec.rows
        .iter()
        .map(|r| {
            if let Some((t, temp)) = prev {
                let dt = r.t_s - t;
                let dtemp = r.temp_c - temp;
                if dt > 0.0 {
                    // de/dt = -e/tau - s with s the sensor's slope over the step
                    let s = dtemp / dt;
                    let a = (-dt / tau_s).exp();
                    e = -s * tau_s + (e + s * tau_s) * a;
                } else {
                    e -= dtemp;
                }
            }
            prev = Some((r.t_s, r.temp_c));
            e
        })
        .collect()
}

/// The settling left by `fit` in the calibration dwells of `rec` (those the static route
/// takes: known positions, within [`MAX_DWELL_DRIFT_C`]); None when there are no such
/// dwells or the recording is too short for the grid's first lag.
///
/// A lag shifts every dwell of a stop by the output's slope in temperature times the
/// element's offset `e`; the part of that shift common to a stop (linear in the position
/// vector: `dK a + dU0`) the static model takes up as if the stop sat at another
/// temperature. What it cannot take up is how `e` still decays while the tilter turns
/// through the stop's positions: both the residuals and the lag's signature are compared
/// after removing, per stop and axis, their least-squares fit on `[a, 1]`.
pub fn settling(rec: &Recording, fit: &ModelFit) -> Option<Settling> {
    let span = rec.rows.last()?.t_s - rec.rows.first()?.t_s;
    let forward = |t: f64, a: [f64; 3]| -> [f64; 3] {
        let mut u = Coeffs::from_array(&fit.eval(t)).forward(a);
        for (axis, k2) in fit.k2.iter().enumerate() {
            if let (Some(k2), Some(ui)) = (k2, u.get_mut(axis)) {
                *ui += k2 * a[axis] * a[axis];
            }
        }
        u
    };
    let used: Vec<&Dwell> = rec
        .dwells
        .iter()
        .filter(|d| {
            d.temp_span_c <= MAX_DWELL_DRIFT_C
                && rec.positions.is_known(d.position)
                && rec.positions.has_role(d.position, Role::Calibration)
                && !d.is_empty()
        })
        .collect();
    let temps: Vec<f64> = used.iter().map(|d| d.temp_c).collect();
    let centres = temperature_clusters(&temps);
    let stop_of = |t: f64| {
        (0..centres.len())
            .min_by(|i, j| (centres[*i] - t).abs().total_cmp(&(centres[*j] - t).abs()))
            .unwrap_or(0)
    };
    let stops: Vec<Vec<usize>> = (0..centres.len())
        .map(|k| {
            (0..used.len())
                .filter(|i| stop_of(used[*i].temp_c) == k)
                .collect()
        })
        .collect();
    // per dwell and axis: the residual and the output's slope in temperature
    let mut r: Vec<[f64; 3]> = Vec::with_capacity(used.len());
    let mut slope: Vec<[f64; 3]> = Vec::with_capacity(used.len());
    for d in &used {
        let a = rec.positions.vector(d.position);
        let u = forward(d.temp_c, a);
        let (up, down) = (forward(d.temp_c + 0.5, a), forward(d.temp_c - 0.5, a));
        r.push(std::array::from_fn(|i| d.u_mean[i] - u[i]));
        slope.push(std::array::from_fn(|i| up[i] - down[i]));
    }
    let vectors: Vec<[f64; 3]> = used
        .iter()
        .map(|d| rec.positions.vector(d.position))
        .collect();
    let r = within_stops(&r, &vectors, &stops);
    let rr: f64 = r.iter().flatten().map(|x| x * x).sum();
    let mut best: Option<Settling> = None;
    let mut tau = GRID_FIRST_S;
    while tau <= span / 3.0 {
        let off = lag_offset(rec, tau);
        let x: Vec<[f64; 3]> = used
            .iter()
            .zip(&slope)
            .map(|(d, sl)| {
                let o = off.get(d.start..d.end).unwrap_or(&[]);
                let mean = o.iter().sum::<f64>() / o.len().max(1) as f64;
                sl.map(|v| v * mean)
            })
            .collect();
        let x = within_stops(&x, &vectors, &stops);
        let (mut rx, mut xx) = (0.0, 0.0);
        for (ri, xi) in r.iter().zip(&x) {
            for i in 0..3 {
                rx += ri[i] * xi[i];
                xx += xi[i] * xi[i];
            }
        }
        if xx > 0.0 && rr > 0.0 {
            let s = Settling {
                tau_s: tau,
                explained: rx * rx / (xx * rr),
                beta: rx / xx,
            };
            if s.beta > 0.0 && best.is_none_or(|b| s.explained > b.explained) {
                best = Some(s);
            }
        }
        tau *= GRID_RATIO;
    }
    best
}

/// `y` with its least-squares fit on `[a, 1]` removed per stop and axis (what a static
/// model's per-temperature coefficients would take up); stops with fewer than five
/// dwells are zeroed (nothing is left once four parameters are fitted).
fn within_stops(y: &[[f64; 3]], a: &[[f64; 3]], stops: &[Vec<usize>]) -> Vec<[f64; 3]> {
    let mut out = vec![[0.0; 3]; y.len()];
    for idx in stops.iter().filter(|s| s.len() >= 5) {
        let m = DMatrix::from_fn(idx.len(), 4, |i, j| {
            a.get(idx[i]).and_then(|v| v.get(j)).copied().unwrap_or(1.0)
        });
        for axis in 0..3 {
            let b = DVector::from_iterator(idx.len(), idx.iter().map(|k| y[*k][axis]));
            let Some(res) = residual(&m, &b) else {
                continue;
            };
            for (i, k) in idx.iter().enumerate() {
                out[*k][axis] = res[i];
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::positions::Positions;
    use std::path::Path;

    fn recording(rows: &[(f64, f64)]) -> Recording {
        let mut text = String::from("t_s,position,temp_c,ux_v,uy_v,uz_v\n");
        for (t, temp) in rows {
            text.push_str(&format!("{t},-,{temp},0,0,0\n"));
        }
        Recording::from_reader(Path::new("r.csv"), text.as_bytes(), Positions::default()).unwrap()
    }

    /// A step of the sensor: the element's offset decays as exp(-t/tau) whatever the
    /// rows' spacing (exact to rounding: 1e-12 C on a 10 C step).
    #[test]
    fn the_lag_offset_decays_on_the_rows_own_clock() {
        let tau = 300.0;
        let mut even = vec![(0.0, 20.0), (1.0, 30.0)];
        even.extend((2..2000).map(|k| (k as f64, 30.0)));
        let mut uneven = vec![(0.0, 20.0), (1.0, 30.0)];
        let mut t = 1.0;
        while t < 2000.0 {
            t += if (t as i64) % 7 == 0 { 13.7 } else { 0.9 };
            uneven.push((t, 30.0));
        }
        for rows in [even, uneven] {
            let rec = recording(&rows);
            let off = lag_offset(&rec, tau);
            // over the first second the sensor rose linearly: e(1) = -s tau (1 - a)
            let a1 = (-1.0f64 / tau).exp();
            let e1 = -10.0 * tau * (1.0 - a1);
            for (r, o) in rows.iter().zip(&off).skip(1) {
                let want = e1 * (-(r.0 - 1.0) / tau).exp();
                assert!((o - want).abs() < 1e-12, "t {}: {o} against {want}", r.0);
            }
        }
    }
}
