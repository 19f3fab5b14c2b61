//! The diagnosis's observations: windows of every dwell with their temperature rate,
//! heating/cooling direction and time since power-on or handling, and the held-out folds.
use crate::data::recording::Recording;

/// A `-` run longer than this (s) is handling (the unit re-mounted, turned by hand).
pub const HANDLING_S: f64 = 120.0;

/// One observation: the mean of a window of a dwell.
#[derive(Debug, Clone)]
pub struct DObs {
    /// Position index and vector.
    pub position: usize,
    /// Specific force, g.
    pub a: [f64; 3],
    /// Samples.
    pub n: usize,
    /// Row range `[start, end)`.
    pub start: usize,
    /// End of the row range.
    pub end: usize,
    /// Dwell index.
    pub dwell: usize,
    /// Held-out fold (0 or 1): alternate windows of short dwells, alternate hours of long ones.
    pub fold: usize,
    /// Mean sensor temperature, C.
    pub temp_c: f64,
    /// Mean time, s.
    pub t_s: f64,
    /// Mean rate of the sensor temperature, C/s.
    pub dtdt: f64,
    /// Direction of the last temperature change (+1 heating, -1 cooling, 0 unknown).
    pub dir: f64,
    /// Mean time since power-on or the last handling, s.
    pub since_event_s: f64,
    /// Mean outputs.
    pub u: [f64; 3],
}

/// Per-row derived series.
pub(crate) struct Series {
    pub(crate) dtdt: Vec<f64>,
    pub(crate) dir: Vec<f64>,
    pub(crate) since: Vec<f64>,
}

pub(crate) fn series(rec: &Recording) -> Series {
    let n = rec.rows.len();
    let t: Vec<f64> = rec.rows.iter().map(|r| r.t_s).collect();
    let temp: Vec<f64> = rec.rows.iter().map(|r| r.temp_c).collect();
    // smoothed temperature derivative: least-squares slope over +-60 s
    let mut dtdt = vec![0.0; n];
    let (mut lo, mut hi) = (0usize, 0usize);
    for k in 0..n {
        while t[k] - t[lo] > 60.0 {
            lo += 1;
        }
        while hi + 1 < n && t[hi + 1] - t[k] <= 60.0 {
            hi += 1;
        }
        let m = (hi - lo + 1) as f64;
        if m >= 3.0 {
            let mt = t[lo..=hi].iter().sum::<f64>() / m;
            let my = temp[lo..=hi].iter().sum::<f64>() / m;
            let (mut sxy, mut sxx) = (0.0, 0.0);
            for j in lo..=hi {
                sxy += (t[j] - mt) * (temp[j] - my);
                sxx += (t[j] - mt) * (t[j] - mt);
            }
            dtdt[k] = if sxx > 0.0 { sxy / sxx } else { 0.0 };
        }
    }
    // direction of the last change of more than 0.5 C; before the first change the unit
    // is taken to have come from the other side (its history before the recording is
    // unknown, and a unit cooled first was usually warm before)
    let mut dir = vec![0.0; n];
    let first = temp.first().copied().unwrap_or(0.0);
    let first_change = temp
        .iter()
        .find(|v| (**v - first).abs() > 0.5)
        .map(|v| if *v > first { 1.0 } else { -1.0 })
        .unwrap_or(0.0);
    let (mut d, mut reference) = (-first_change, first);
    for k in 0..n {
        let s = temp[k];
        if s - reference > 0.5 {
            d = 1.0;
            reference = s;
        } else if reference - s > 0.5 {
            d = -1.0;
            reference = s;
        } else if (s - reference) * d > 0.0 {
            reference = s;
        }
        dir[k] = d;
    }
    // time since power-on or handling
    let mut since = vec![0.0; n];
    let mut event = t.first().copied().unwrap_or(0.0);
    let mut k = 0;
    while k < n {
        if rec.rows[k].position.is_none() {
            let s = k;
            while k < n && rec.rows[k].position.is_none() {
                since[k] = t[k] - event;
                k += 1;
            }
            let end_t = if k < n { t[k] } else { t[n - 1] };
            if end_t - t[s] > HANDLING_S {
                event = end_t;
            }
            continue;
        }
        since[k] = t[k] - event;
        k += 1;
    }
    Series { dtdt, dir, since }
}

/// Windows of every dwell of a known position: at most `span_c` of temperature and
/// `max_s` of time each.
pub fn observations(rec: &Recording, span_c: f64, max_s: f64) -> Vec<DObs> {
    let s = series(rec);
    let mut out = Vec::new();
    for (di, d) in rec.dwells.iter().enumerate() {
        let a = rec.positions.vector(d.position);
        let mut windows = crate::fit::identify::windows(rec, d, span_c, max_s);
        // at least two windows per dwell, so each held-out fold sees every dwell
        if windows.len() == 1 && d.len() >= 4 {
            let mid = d.start + d.len() / 2;
            windows = vec![(d.start, mid), (mid, d.end)];
        }
        let short = windows.len() <= 4;
        for (wi, (start, end)) in windows.into_iter().enumerate() {
            let m = (end - start) as f64;
            let mean = |f: &dyn Fn(usize) -> f64| (start..end).map(f).sum::<f64>() / m;
            // held-out folds: alternate windows of short dwells, alternate hours of long ones
            let fold = if short {
                wi % 2
            } else {
                (di + ((rec.rows[start].t_s - rec.rows[d.start].t_s) / 3600.0) as usize) % 2
            };
            out.push(DObs {
                position: d.position,
                a,
                n: end - start,
                start,
                end,
                dwell: di,
                fold,
                temp_c: mean(&|k| rec.rows[k].temp_c),
                t_s: mean(&|k| rec.rows[k].t_s),
                dtdt: mean(&|k| s.dtdt[k]),
                dir: mean(&|k| s.dir[k]),
                since_event_s: mean(&|k| s.since[k]),
                u: [
                    mean(&|k| rec.rows[k].u[0]),
                    mean(&|k| rec.rows[k].u[1]),
                    mean(&|k| rec.rows[k].u[2]),
                ],
            });
        }
    }
    out
}

/// Mean of the first-order low-pass (time constant `tau`) of the sensor temperature
/// over each observation's rows.
pub(crate) fn lagged_temps(rec: &Recording, obs: &[DObs], tau: f64) -> Vec<f64> {
    let mut f = vec![0.0; rec.rows.len()];
    let mut y = rec.rows.first().map(|r| r.temp_c).unwrap_or(0.0);
    let mut prev_t = rec.rows.first().map(|r| r.t_s).unwrap_or(0.0);
    for (k, r) in rec.rows.iter().enumerate() {
        let dt = (r.t_s - prev_t).max(0.0);
        y += (r.temp_c - y) * (1.0 - (-dt / tau).exp());
        prev_t = r.t_s;
        f[k] = y;
    }
    obs.iter()
        .map(|o| f[o.start..o.end].iter().sum::<f64>() / o.n as f64)
        .collect()
}
