//! Notes on the data itself, reported as such and never as physics: spikes, gaps,
//! time-correlated noise, a temperature sensor that disagrees with the chamber, and what
//! the recording's form (one sample per dwell, one temperature) leaves unanswerable.
use crate::data::recording::Recording;
use crate::diagnose::floor::Floor;
use crate::diagnose::observations::DObs;
use crate::diagnose::regressors::{median_step, Events};
use firmware_core::model::AXES;
use serde::Serialize;

/// One note.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct QualityNote {
    /// `spikes`, `gaps`, `coloured_noise`, `sensor_vs_chamber`, `one_sample_per_dwell`,
    /// `one_temperature`.
    pub kind: &'static str,
    /// What was found and what it means for the diagnosis.
    pub text: String,
}

/// A window mean scatters this many times what white noise predicts: noted.
const COLOUR_NOTE: f64 = 2.0;
/// Steady sensor-vs-chamber offsets beyond this (C), or spread across soaks beyond it: noted.
const CHAMBER_NOTE_C: f64 = 1.0;

/// The notes of a recording.
pub fn notes(
    rec: &Recording,
    floor: &Floor,
    obs: &[DObs],
    events: &Events,
    n_temps: usize,
) -> Vec<QualityNote> {
    let mut out = Vec::new();
    if !floor.spikes.is_empty() {
        let lines: Vec<String> = floor
            .spikes
            .iter()
            .take(5)
            .map(|&r| rec.rows[r].line.to_string())
            .collect();
        out.push(QualityNote {
            kind: "spikes",
            text: format!(
                "{} samples jump more than {} floor sigmas from their neighbours (lines {}{}); left out of the window means",
                floor.spikes.len(),
                crate::diagnose::floor::SPIKE_Z,
                lines.join(", "),
                if floor.spikes.len() > 5 { ", ..." } else { "" }
            ),
        });
    }
    if !events.gaps.is_empty() {
        let longest = events
            .gaps
            .iter()
            .map(|&k| rec.rows[k].t_s - rec.rows[k - 1].t_s)
            .fold(0.0, f64::max);
        out.push(QualityNote {
            kind: "gaps",
            text: format!(
                "{} gaps in time (longest {longest:.0} s, the step is {:.3} s); a warm-up may restart after them",
                events.gaps.len(),
                median_step(rec)
            ),
        });
    }
    let mut ns: Vec<f64> = obs.iter().map(|o| o.n as f64).collect();
    ns.sort_by(f64::total_cmp);
    let n_mid = ns.get(ns.len() / 2).copied().unwrap_or(1.0);
    let coloured: Vec<String> = (0..3)
        .filter_map(|i| {
            floor.axes[i]
                .colour(n_mid)
                .filter(|c| *c > COLOUR_NOTE)
                .map(|c| format!("{} {c:.1}x", AXES[i]))
        })
        .collect();
    if !coloured.is_empty() {
        out.push(QualityNote {
            kind: "coloured_noise",
            text: format!(
                "the noise is time-correlated: a window of {n_mid:.0} samples scatters more than white noise predicts ({}); the floor, and every weight and uncertainty, uses the measured scatter",
                coloured.join(", ")
            ),
        });
    }
    if floor.axes.iter().all(|a| a.scales.is_empty()) {
        out.push(QualityNote {
            kind: "one_sample_per_dwell",
            text: "no dwell has enough samples to measure the noise: the floor is the baseline's own scatter, and effects that need a time series (thermal_lag, temp_rate, hysteresis, warmup_drift) are not judged".into(),
        });
    }
    if n_temps <= 1 {
        out.push(QualityNote {
            kind: "one_temperature",
            text: "all data at one temperature: no temperature model can be fitted, and only nonlinearity_k2, scale_asymmetry and fixture_error can be judged".into(),
        });
    }
    out.extend(chamber(rec));
    out
}

/// The sensor against the chamber at the end of every steady soak.
fn chamber(rec: &Recording) -> Option<QualityNote> {
    let step = median_step(rec);
    let hold = (600.0 / step).ceil() as usize;
    let mut offsets = Vec::new();
    let mut k = hold;
    while k < rec.rows.len() {
        let w = &rec.rows[k - hold..k];
        let (lo, hi) = w
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), r| {
                (l.min(r.temp_c), h.max(r.temp_c))
            });
        let ch: Vec<f64> = w.iter().filter_map(|r| r.chamber_c).collect();
        if ch.len() == w.len() && hi - lo < 0.2 {
            let (cl, chh) = ch
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
                    (l.min(*v), h.max(*v))
                });
            if chh - cl < 0.2 {
                let mean = |v: &mut dyn Iterator<Item = f64>| v.sum::<f64>() / w.len() as f64;
                offsets.push(mean(&mut w.iter().map(|r| r.temp_c)) - mean(&mut ch.iter().copied()));
                k += hold;
                continue;
            }
        }
        k += hold / 4 + 1;
    }
    if offsets.len() < 2 {
        return None;
    }
    let (lo, hi) = offsets
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
            (l.min(*v), h.max(*v))
        });
    let mean = offsets.iter().sum::<f64>() / offsets.len() as f64;
    (mean.abs() > CHAMBER_NOTE_C || hi - lo > CHAMBER_NOTE_C).then(|| QualityNote {
        kind: "sensor_vs_chamber",
        text: format!(
            "at steady temperature the unit's sensor reads {mean:+.2} C from the chamber on average ({lo:+.2} to {hi:+.2} C over {} steady spans): one of the two is off; the model uses the unit's sensor",
            offsets.len()
        ),
    })
}
