//! Which data are static: the equilibrium rule of the default fit.
//!
//! A dwell whose temperature stays within the recording format's drift limit (0.5 C) is
//! static. In a dwell that drifts more, each window (at most 0.25 C) is static only where
//! the temperature moves slower than [`MAX_RATE_C_PER_MIN`] (the rate taken between the
//! neighbouring windows' means): a slow warm-up over hours is quasi-static, a ramp or the
//! fast settling after one is not. Data taken while the temperature moves carry the
//! unit's dynamics (lag, gradients, settling), which the static coefficients do not
//! model, and a rest through a ramp would outweigh the stops with its samples; they are
//! left out of the static fit, and `--route joint` takes them in on request.
use crate::data::recording::{Recording, MAX_DWELL_DRIFT_C};
use crate::data::stops::WINDOW_SPAN_C;
use crate::fit::identify::{observations, Obs};
use serde::Serialize;

/// Inside a dwell that drifts more than 0.5 C, a window is static when the temperature
/// moves slower than this, C/min. The production twin's stops settle at 0.02-0.1 C/min
/// and ramp at 1 C/min; a unit warming by 1 C an hour moves at 0.017 C/min.
pub const MAX_RATE_C_PER_MIN: f64 = 0.05;

/// What the rule left out.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct Excluded {
    /// Dwells whose temperature spans more than [`MAX_DWELL_DRIFT_C`].
    pub dwells: usize,
    /// Of their samples, those taken while the temperature moved faster than
    /// [`MAX_RATE_C_PER_MIN`]: left out.
    pub samples: usize,
    /// Of their samples, those taken slower: kept.
    pub samples_kept: usize,
    /// The largest of their temperature spans, C.
    pub max_span_c: f64,
    /// Dwells the rule looked at (the selected positions').
    pub of_dwells: usize,
}

impl Excluded {
    /// One line for the user, empty when nothing drifted.
    pub fn text(&self) -> String {
        if self.dwells == 0 {
            return String::new();
        }
        let mut s = format!(
            "{} of {} calibration dwells moved more than {MAX_DWELL_DRIFT_C} C in temperature (up to {:.1} C: ramps, settling); of their samples {} taken while it moved faster than {MAX_RATE_C_PER_MIN} C/min were left out of the static fit, {} kept",
            self.dwells, self.of_dwells, self.max_span_c, self.samples, self.samples_kept
        );
        if 2 * self.dwells > self.of_dwells {
            s.push_str(": most of the recording was not in thermal equilibrium; lengthen the soaks, or fit the ramps with --route joint (their dynamics unmodelled)");
        }
        s
    }
}

/// Whether dwell `d` of `rec` stayed within the drift limit.
pub fn is_static(rec: &Recording, d: usize) -> bool {
    rec.dwells
        .get(d)
        .is_some_and(|d| d.temp_span_c <= MAX_DWELL_DRIFT_C)
}

/// Per window of one drifting dwell (`ws`, in time order), whether the temperature
/// moved slower than the limit there: the rate between the neighbouring windows' means
/// (one-sided at the ends).
fn slow(ws: &[&Obs]) -> Vec<bool> {
    let limit = MAX_RATE_C_PER_MIN / 60.0;
    (0..ws.len())
        .map(|k| {
            let (a, b) = (ws[k.saturating_sub(1)], ws[(k + 1).min(ws.len() - 1)]);
            let dt = b.t_s - a.t_s;
            dt > 0.0 && ((b.temp_c - a.temp_c) / dt).abs() <= limit
        })
        .collect()
}

/// The static observations of the positions `select` accepts (windows of at most
/// [`WINDOW_SPAN_C`], each at its own temperature), and what was left out.
pub fn static_observations(
    rec: &Recording,
    select: &dyn Fn(usize) -> bool,
) -> (Vec<Obs>, Excluded) {
    let mut ex = Excluded::default();
    let all = observations(rec, select, WINDOW_SPAN_C);
    let mut keep = vec![true; all.len()];
    let mut i = 0;
    while i < all.len() {
        let d = all[i].dwell;
        let j = i + all[i..].iter().take_while(|o| o.dwell == d).count();
        ex.of_dwells += 1;
        if !is_static(rec, d) {
            ex.dwells += 1;
            ex.max_span_c = ex
                .max_span_c
                .max(rec.dwells.get(d).map_or(0.0, |d| d.temp_span_c));
            let ws: Vec<&Obs> = all[i..j].iter().collect();
            for (k, s) in slow(&ws).into_iter().enumerate() {
                keep[i + k] = s;
                if s {
                    ex.samples_kept += all[i + k].n;
                } else {
                    ex.samples += all[i + k].n;
                }
            }
        }
        i = j;
    }
    let obs = all
        .into_iter()
        .zip(keep)
        .filter_map(|(o, k)| k.then_some(o))
        .collect();
    (obs, ex)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::positions::Positions;
    use std::fmt::Write;

    #[test]
    fn a_slow_warm_up_is_static_a_ramp_is_not() {
        // TP1 for 2 h warming 1 C/h (0.017 C/min), then TP2 ramping 1 C/min for 10 min,
        // then TP3 steady
        let mut s = String::from("t_s,position,temp_c,ux_v,uy_v,uz_v\n");
        let mut t = 0.0;
        for k in 0..720 {
            let _ = writeln!(s, "{t},TP1,{:.4},0,0,1", 20.0 + k as f64 * 10.0 / 3600.0);
            t += 10.0;
        }
        for k in 0..60 {
            let _ = writeln!(s, "{t},TP2,{:.4},0,-1,0", 22.0 + k as f64 * 10.0 / 60.0);
            t += 10.0;
        }
        for _ in 0..30 {
            let _ = writeln!(s, "{t},TP3,32.0,0,0,-1");
            t += 10.0;
        }
        let rec = Recording::from_reader(
            std::path::Path::new("r.csv"),
            s.as_bytes(),
            Positions::default(),
        )
        .unwrap();
        let (obs, ex) = static_observations(&rec, &|_| true);
        let n = |p: &str| {
            let i = rec.positions.index(p).unwrap();
            obs.iter()
                .filter(|o| o.position == i)
                .map(|o| o.n)
                .sum::<usize>()
        };
        assert_eq!((n("TP1"), n("TP2"), n("TP3")), (720, 0, 30), "{ex:?}");
        assert_eq!((ex.dwells, ex.samples, ex.samples_kept), (2, 60, 720));
        assert!(
            ex.text().contains("2 of 3 calibration dwells"),
            "{}",
            ex.text()
        );
    }
}
