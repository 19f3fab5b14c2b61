//! The regressors of the in-flight effects, made by stepping firmware-core's own state
//! machines (`firmware_core::inflight`) over the recording's rows, so the diagnosis fits
//! exactly what the firmware will apply; plus the recording's restart events.
use crate::data::recording::Recording;
use crate::diagnose::rules::Rules;
use firmware_core::inflight::{Direction, Lag, Rate, Warmup};

/// The low-pass constant of a step of `dt` for time constant `tau` (1 = no lag).
pub fn alpha(dt: f64, tau: f64) -> f64 {
    if tau > 0.0 {
        1.0 - (-dt.max(0.0) / tau).exp()
    } else {
        1.0
    }
}

/// Median time step, s.
pub fn median_step(rec: &Recording) -> f64 {
    let mut d: Vec<f64> = rec
        .rows
        .windows(2)
        .map(|w| w[1].t_s - w[0].t_s)
        .filter(|d| *d > 0.0)
        .collect();
    d.sort_by(f64::total_cmp);
    d.get(d.len() / 2).copied().unwrap_or(1.0)
}

/// Where a warm-up clock may restart: after gaps in the recording, and after handling.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Events {
    /// First row after each gap.
    pub gaps: Vec<usize>,
    /// First row after each handling run.
    pub handling: Vec<usize>,
}

/// The recording's gaps (a step of [`Rules::gap_factor`] times the median one, and at
/// least [`Rules::gap_min_s`]: the unit may have been powered off) and handling runs (a
/// `-` run longer than [`Rules::handling_s`]: the unit re-mounted, turned by hand).
pub fn events(rec: &Recording, rules: &Rules) -> Events {
    let step = median_step(rec);
    let mut e = Events::default();
    let rows = &rec.rows;
    for k in 1..rows.len() {
        if rows[k].t_s - rows[k - 1].t_s > (rules.gap_factor * step).max(rules.gap_min_s) {
            e.gaps.push(k);
        }
    }
    let mut k = 0;
    while k < rows.len() {
        if rows[k].position.is_none() {
            let s = k;
            while k < rows.len() && rows[k].position.is_none() {
                k += 1;
            }
            let end_t = rows
                .get(k)
                .map(|r| r.t_s)
                .unwrap_or(rows[rows.len() - 1].t_s);
            if end_t - rows[s].t_s > rules.handling_s && k < rows.len() {
                e.handling.push(k);
            }
            continue;
        }
        k += 1;
    }
    e
}

/// The first row's temperature: where the firmware's filters start.
fn first_temp(rec: &Recording) -> f64 {
    rec.rows.first().map(|r| r.temp_c).unwrap_or(0.0)
}

/// The time step before each row (the median step for the first).
fn steps(rec: &Recording) -> Vec<f64> {
    let first = median_step(rec);
    std::iter::once(first)
        .chain(rec.rows.windows(2).map(|w| (w[1].t_s - w[0].t_s).max(0.0)))
        .collect()
}

/// Per row, each axis's element temperature through the lag of time constants
/// `taus[axis] = [tau1, tau2]` (tau2 = 0: one pole).
pub fn lagged(rec: &Recording, taus: &[[f64; 2]; 3]) -> [Vec<f64>; 3] {
    let dts = steps(rec);
    std::array::from_fn(|axis| {
        let mut lag = Lag::<f64>::default();
        lag.start(first_temp(rec));
        let [t1, t2] = taus[axis];
        rec.rows
            .iter()
            .zip(&dts)
            .map(|(r, dt)| lag.step(alpha(*dt, t1), alpha(*dt, t2), r.temp_c))
            .collect()
    })
}

/// Per row, the firmware's rate estimate (C/s) with low-pass time constant `tau_s`.
pub fn rates(rec: &Recording, tau_s: f64) -> Vec<f64> {
    let dts = steps(rec);
    let mut m = Rate::<f64>::default();
    m.start(first_temp(rec));
    rec.rows
        .iter()
        .zip(&dts)
        .map(|(r, dt)| m.step(alpha(*dt, tau_s), r.temp_c, dt.max(1e-9)))
        .collect()
}

/// Per row, the hysteresis direction (threshold in C, initial state +1 or -1).
pub fn directions(rec: &Recording, threshold_c: f64, initial: f64) -> Vec<f64> {
    let mut m = Direction::default();
    m.start(initial, first_temp(rec));
    rec.rows
        .iter()
        .map(|r| m.step(threshold_c, r.temp_c))
        .collect()
}

/// Per row, the warm-up weight for time constant `tau_s`, the clock restarted at the
/// rows `restarts` (sorted) as well as at the first row.
pub fn warmup(rec: &Recording, tau_s: f64, restarts: &[usize]) -> Vec<f64> {
    let dts = steps(rec);
    let mut m = Warmup::<f64>::default();
    let mut next = restarts.iter().peekable();
    (0..rec.rows.len())
        .map(|k| {
            if next.peek() == Some(&&k) {
                next.next();
                m.restart();
            }
            // the weight of this row, then decay over the step to the next one
            let decay = (-dts.get(k + 1).copied().unwrap_or(0.0) / tau_s).exp();
            m.step(decay)
        })
        .collect()
}
