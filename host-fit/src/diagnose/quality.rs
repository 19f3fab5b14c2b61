//! Notes on the data itself, reported as such and never as physics: spikes, gaps,
//! time-correlated noise, a temperature sensor that disagrees with the chamber, and what
//! the recording's form (one sample per dwell, one temperature) leaves unanswerable.
use crate::data::recording::Recording;
use crate::model::floor::Floor;
use crate::model::observations::DObs;
use crate::model::regressors::Events;
use crate::model::rules::Rules;
use firmware_core::model::AXES;
use serde::Serialize;

/// What a note is about.
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    Serialize,
    strum::Display,
    strum::EnumString,
    strum::IntoStaticStr,
    strum::EnumIter,
)]
#[serde(into = "&'static str")]
#[strum(serialize_all = "snake_case")]
pub enum NoteKind {
    /// Samples far from their neighbours, left out.
    Spikes,
    /// Gaps in time (the unit may have been off).
    Gaps,
    /// Time-correlated noise.
    ColouredNoise,
    /// The unit's sensor and the chamber disagree at steady temperature.
    SensorVsChamber,
    /// No dwell has two samples: no floor can be measured.
    OneSamplePerDwell,
    /// All data at one temperature.
    OneTemperature,
    /// Outputs quantised coarser than their noise: the step is the floor.
    Quantised,
}

impl NoteKind {
    /// The contract's name.
    pub fn as_str(self) -> &'static str {
        self.into()
    }
}

/// One note.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct QualityNote {
    /// What it is about.
    pub kind: NoteKind,
    /// What was found and what it means for the diagnosis.
    pub text: String,
}

/// What the notes are taken from: the recording, its floor and windows, its events.
pub struct Inputs<'a> {
    /// The recording.
    pub rec: &'a Recording,
    /// Its floor.
    pub floor: &'a Floor,
    /// Its windows.
    pub obs: &'a [DObs],
    /// Its gaps and handling.
    pub events: &'a Events,
    /// Its distinct temperatures.
    pub n_temps: usize,
    /// The rules (note thresholds).
    pub rules: &'a Rules,
}

/// The notes of a recording.
pub fn notes(inputs: &Inputs) -> Vec<QualityNote> {
    let Inputs {
        rec,
        floor,
        obs,
        events,
        n_temps,
        rules,
    } = *inputs;
    let mut out = Vec::new();
    if !floor.spikes.is_empty() {
        let lines: Vec<String> = floor
            .spikes
            .iter()
            .take(5)
            .map(|&r| rec.rows[r].line.to_string())
            .collect();
        out.push(QualityNote {
            kind: NoteKind::Spikes,
            text: format!(
                "{} samples jump more than {} floor sigmas from their neighbours (lines {}{}); left out of the window means",
                floor.spikes.len(),
                rules.spike_z,
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
            kind: NoteKind::Gaps,
            text: format!(
                "{} gaps in time (longest {longest:.0} s, the step is {:.3} s); a warm-up may restart after them",
                events.gaps.len(),
                rec.median_step_s()
            ),
        });
    }
    let mut ns: Vec<f64> = obs.iter().map(|o| o.n as f64).collect();
    ns.sort_by(f64::total_cmp);
    let n_mid = ns.get(ns.len() / 2).copied().unwrap_or(1.0);
    let quantised: Vec<String> = (0..3)
        .filter_map(|i| {
            floor.axes[i]
                .quantum
                .map(|q| format!("{} {q} {}", AXES[i], rec.output_unit))
        })
        .collect();
    if !quantised.is_empty() {
        out.push(QualityNote {
            kind: NoteKind::Quantised,
            text: format!(
                "the outputs are quantised coarser than their noise (step {}): the samples of a dwell repeat instead of averaging, so the floor of every window is the step's own, step / sqrt(12)",
                quantised.join(", ")
            ),
        });
    }
    // a quantised axis's repeated error is its floor, not time-correlated noise
    let coloured: Vec<String> = (0..3)
        .filter(|&i| floor.axes[i].quantum.is_none())
        .filter_map(|i| {
            floor.axes[i]
                .colour(n_mid)
                .filter(|c| *c > rules.colour_note)
                .map(|c| format!("{} {c:.1}x", AXES[i]))
        })
        .collect();
    if !coloured.is_empty() {
        out.push(QualityNote {
            kind: NoteKind::ColouredNoise,
            text: format!(
                "the noise is time-correlated: a window of {n_mid:.0} samples scatters more than white noise predicts ({}); the floor, and every weight and uncertainty, uses the measured scatter",
                coloured.join(", ")
            ),
        });
    }
    if floor.axes.iter().all(|a| a.scales.is_empty()) {
        out.push(QualityNote {
            kind: NoteKind::OneSamplePerDwell,
            text: "no dwell has enough samples to measure the noise: the floor is the baseline's own scatter, and effects that need a time series (thermal_lag, temp_rate, hysteresis, warmup_drift) are not judged".into(),
        });
    }
    if n_temps <= 1 {
        out.push(QualityNote {
            kind: NoteKind::OneTemperature,
            text: "all data at one temperature: no temperature model can be fitted, and only nonlinearity_k2, scale_asymmetry and fixture_error can be judged".into(),
        });
    }
    out.extend(chamber(rec, rules));
    out
}

/// The sensor against the chamber at the end of every steady soak.
fn chamber(rec: &Recording, rules: &Rules) -> Option<QualityNote> {
    let step = rec.median_step_s();
    let hold = (rules.chamber_hold_s / step).ceil() as usize;
    let steady = rules.chamber_steady_c;
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
        if ch.len() == w.len() && hi - lo < steady {
            let (cl, chh) = ch
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
                    (l.min(*v), h.max(*v))
                });
            if chh - cl < steady {
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
    let note = rules.chamber_note_c;
    (mean.abs() > note || hi - lo > note).then(|| QualityNote {
        kind: NoteKind::SensorVsChamber,
        text: format!(
            "at steady temperature the unit's sensor reads {mean:+.2} C from the chamber on average ({lo:+.2} to {hi:+.2} C over {} steady spans): one of the two is off; the model uses the unit's sensor",
            offsets.len()
        ),
    })
}
