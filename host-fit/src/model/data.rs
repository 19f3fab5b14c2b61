//! What the diagnosis works on, built once per recording: the windows of its static
//! positions (spikes left out), their weights from the floor, the recording's restart
//! events, each window's temperature rate and direction for locating, and the rules it
//! is judged by. The [`crate::diagnose::Diagnosis`] owns it, so every figure of the
//! contract is computed on the very data the search saw.
use crate::data::recording::Recording;
use crate::model::floor::Floor;
use crate::model::observations::{observations, window_means, DObs};
use crate::model::regressors::{self, Events};
use crate::model::rules::Rules;

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
    /// When each stop of the tilter test begins (its first static dwell), s, in time
    /// order: the stops of [`crate::data::stops::stops`], dwells within 3 C of the
    /// first of their stop, ramps between them.
    pub stop_starts: Vec<f64>,
    /// Each observation's temperature rate (a low-pass over [`Rules::rate_tau_s`], held
    /// after the start, [`regressors::rates`]), C/s: where the temperature moves (for
    /// locating and for the static dg).
    pub rate: Vec<f64>,
    /// Each observation's direction of the last change of more than
    /// [`Rules::direction_threshold_c`] (0 before the first), for locating.
    pub dir: Vec<f64>,
    /// The baseline's normal equations, once per baseline (keyed by the values they
    /// read, so a change of the windows or weights above is never served stale).
    pub normal_cache: crate::model::normal_cache::NormalCache,
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
            stop_starts: stop_starts(rec),
            rate,
            dir,
            normal_cache: Default::default(),
        }
    }

    /// When stop `n` (1-based) begins, s (infinity for a stop the recording lacks).
    pub fn stop_start_s(&self, n: usize) -> f64 {
        n.checked_sub(1)
            .and_then(|k| self.stop_starts.get(k))
            .copied()
            .unwrap_or(f64::INFINITY)
    }

    /// The stop (1-based) an observation at `t_s` belongs to (0 before the first).
    pub fn stop_of(&self, t_s: f64) -> usize {
        self.stop_starts.iter().filter(|s| **s <= t_s).count()
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

    /// The recording's span in time, first row to last, s.
    pub fn span_s(&self) -> f64 {
        let rows = &self.rec.rows;
        rows.last().map(|r| r.t_s).unwrap_or(0.0) - rows.first().map(|r| r.t_s).unwrap_or(0.0)
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

/// The start time of every stop of `rec` (see [`Data::stop_starts`]).
pub(crate) fn stop_starts(rec: &Recording) -> Vec<f64> {
    crate::data::stops::stops(rec, &|_| true, 3.0)
        .iter()
        .filter_map(|s| s.dwells.first())
        .filter_map(|&d| rec.dwells.get(d))
        .filter_map(|d| rec.rows.get(d.start))
        .map(|r| r.t_s)
        .collect()
}
