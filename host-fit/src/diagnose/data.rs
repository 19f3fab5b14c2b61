//! What the diagnosis works on, built once per recording: the windows of its static
//! positions (spikes left out), their weights from the floor, the recording's restart
//! events, each window's temperature rate and direction for locating, and the rules it
//! is judged by. The [`crate::diagnose::Diagnosis`] owns it, so every figure of the
//! contract is computed on the very data the search saw.
use crate::data::recording::Recording;
use crate::diagnose::floor::Floor;
use crate::diagnose::observations::{observations, window_means, DObs};
use crate::diagnose::regressors::{self, Events};
use crate::diagnose::rules::Rules;

/// The data of a diagnosis.
#[derive(Debug, Clone)]
pub struct Data<'a> {
    /// The recording.
    pub rec: &'a Recording,
    /// The rules the diagnosis judges by.
    pub rules: Rules,
    /// Observations.
    pub obs: Vec<DObs>,
    /// Rows left out as spikes (sorted).
    pub spikes: Vec<usize>,
    /// Weight of every residual row (observation x axis): 1 / floor variance.
    pub w: Vec<f64>,
    /// Reference temperature.
    pub t0: f64,
    /// Gaps and handling.
    pub events: Events,
    /// Each observation's temperature rate (the firmware's estimate, over
    /// [`Rules::rate_tau_s`]), C/s: where the temperature moves (for locating and for the
    /// static dg).
    pub rate: Vec<f64>,
    /// Each observation's direction of the last change of more than
    /// [`Rules::direction_threshold_c`] (0 before the first), for locating.
    pub dir: Vec<f64>,
}

impl<'a> Data<'a> {
    /// The windows of `rec` (spikes of `floor` left out), with unit weights until
    /// [`Data::w`] is set from the floor.
    pub fn new(rec: &'a Recording, floor: &Floor, rules: Rules) -> Data<'a> {
        let obs = observations(rec, &floor.spikes, &rules);
        let spikes = floor.spikes.clone();
        let rate = window_means(&obs, &regressors::rates(rec, rules.rate_tau_s), &spikes);
        let dir = window_means(
            &obs,
            &regressors::directions(rec, rules.direction_threshold_c, 0.0),
            &spikes,
        );
        Data {
            rec,
            rules,
            w: vec![1.0; 3 * obs.len()],
            obs,
            spikes,
            t0: rec.t0_c,
            events: regressors::events(rec, &rules),
            rate,
            dir,
        }
    }

    /// Residual rows.
    pub fn n_rows(&self) -> usize {
        3 * self.obs.len()
    }

    /// Window means of a per-row series.
    pub fn means(&self, series: &[f64]) -> Vec<f64> {
        window_means(&self.obs, series, &self.spikes)
    }

    /// The number of held-out chunks.
    pub fn n_chunks(&self) -> usize {
        self.obs.iter().map(|o| o.chunk + 1).max().unwrap_or(1)
    }

    /// The lowest and highest window temperature, C.
    pub fn temperature_range(&self) -> (f64, f64) {
        self.obs
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), o| {
                (a.min(o.temp_c), b.max(o.temp_c))
            })
    }
}
