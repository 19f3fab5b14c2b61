//! A recording's stops (its static dwells grouped by temperature, in time order) and the
//! windows its dwells are cut into: the structure every fit, static, dynamic or
//! diagnostic, takes its observations from.
use crate::data::recording::{Dwell, Recording, MAX_DWELL_DRIFT_C};

/// A window of a dwell spans at most this much temperature: small enough that every
/// coefficient's temperature dependence is linear across it, so the window's mean belongs
/// to its mean temperature (on a 1 C/min ramp, 15 s of data). The static fits and the
/// diagnosis cut the same windows.
pub const WINDOW_SPAN_C: f64 = 0.25;

/// Split a dwell into consecutive windows (absolute row ranges) whose temperature spans
/// at most `span_c` and whose time at most `max_s`.
pub fn windows(rec: &Recording, d: &Dwell, span_c: f64, max_s: f64) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut start = d.start;
    while start < d.end {
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        let t_start = rec.rows.get(start).map(|r| r.t_s).unwrap_or(0.0);
        let mut end = start;
        while let Some(r) = rec.rows.get(end).filter(|_| end < d.end) {
            let (l, h) = (lo.min(r.temp_c), hi.max(r.temp_c));
            if end > start && (h - l > span_c || r.t_s - t_start > max_s) {
                break;
            }
            (lo, hi) = (l, h);
            end += 1;
        }
        out.push((start, end));
        start = end;
    }
    out
}

/// A calibration stop: consecutive static dwells at one chamber temperature.
#[derive(Debug, Clone, PartialEq)]
pub struct Stop {
    /// Dwell indices.
    pub dwells: Vec<usize>,
    /// Sample-weighted mean temperature, C.
    pub temp_c: f64,
}

/// Group the selected static dwells (temperature span <= 0.5 C) into stops: a new stop
/// starts when a dwell is more than `tol_c` from the first dwell of the current one, or
/// after a dwell that drifted (a ramp).
pub fn stops(rec: &Recording, select: &dyn Fn(usize) -> bool, tol_c: f64) -> Vec<Stop> {
    let mut out: Vec<Stop> = Vec::new();
    let mut cur: Vec<usize> = Vec::new();
    let mut first_t = f64::NAN;
    let close = |cur: &mut Vec<usize>, out: &mut Vec<Stop>| {
        if !cur.is_empty() {
            let (mut s, mut n) = (0.0, 0.0);
            for &i in cur.iter() {
                if let Some(d) = rec.dwells.get(i) {
                    s += d.temp_c * d.len() as f64;
                    n += d.len() as f64;
                }
            }
            out.push(Stop {
                dwells: std::mem::take(cur),
                temp_c: s / n,
            });
        }
    };
    for (i, d) in rec.dwells.iter().enumerate() {
        if d.temp_span_c > MAX_DWELL_DRIFT_C {
            close(&mut cur, &mut out);
            continue;
        }
        if !select(d.position) {
            continue;
        }
        if !cur.is_empty() && (d.temp_c - first_t).abs() > tol_c {
            close(&mut cur, &mut out);
        }
        if cur.is_empty() {
            first_t = d.temp_c;
        }
        cur.push(i);
    }
    close(&mut cur, &mut out);
    out
}
