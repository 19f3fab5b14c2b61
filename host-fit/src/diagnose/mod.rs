//! Diagnosis: when the model and a recording disagree, locate the mismatch, name the
//! physics left out (physics-catalogue.md), model it, and show the fit improve.
//!
//! All three axes are fitted in one weighted least squares (weights n / sigma^2 from the
//! in-dwell noise): per axis the temperature models of its K row and offset, and the
//! candidate effects as extra columns; effects with a nonlinear parameter (thermal lag
//! and warm-up time constants) are profiled over it. A candidate is accepted when it
//! lowers BIC by more than [`BIC_MARGIN`] and improves the chi-square of dwells it was
//! not fitted on (two folds of alternate dwells); candidates that explain the data
//! equally well are reported as ambiguous, with the measurement that would separate them.
//!
//! `HOSTFIT_DEBUG=1` prints every candidate's BIC change and held-out chi-square to stderr.
pub mod calibration;
pub mod contract;
pub mod design;
pub mod findings;
pub mod location;
pub mod metrics;
pub mod observations;
pub mod params;
pub mod search;

use crate::data::recording::Recording;
use crate::error::{HostError, Result};
use crate::fit::noise::{noise, Noise};
use design::{Data, Fit};
use findings::{Ambiguity, Finding};
use location::{locate, Hotspot};
use observations::{observations, series, DObs};

pub use design::EFFECT_IDS;
pub use search::{AMBIGUITY_MARGIN, BIC_MARGIN};

/// The whole diagnosis.
#[derive(Debug, Clone)]
pub struct Diagnosis {
    /// In-dwell noise per axis.
    pub noise: Noise,
    /// Baseline.
    pub baseline: Fit,
    /// Final model.
    pub final_fit: Fit,
    /// Accepted findings.
    pub findings: Vec<Finding>,
    /// Ambiguities.
    pub ambiguous: Vec<Ambiguity>,
    /// Where the baseline residual exceeds noise.
    pub hotspots: Vec<Hotspot>,
    /// What cannot be identified from this recording.
    pub not_identifiable: Vec<String>,
    /// The data.
    pub obs: Vec<DObs>,
    /// Expected residual RMS from noise alone (output units, per window).
    pub noise_rms: f64,
    /// The final model's coefficients on a grid over the data's temperatures (for the blob).
    pub table: Vec<(f64, [f64; 12])>,
    /// Median sample period of the recording, s.
    pub sample_period_s: f64,
    /// Direction of the hysteresis state at the start of the recording.
    pub initial_direction: f64,
}

/// The final model's coefficients on a grid of up to 16 points, about one per 2 C, over
/// the data's temperature range.
fn final_table(data: &Data, f: &Fit, tmin: f64, tmax: f64) -> Vec<(f64, [f64; 12])> {
    let nb = 16usize
        .min(((tmax - tmin) / 2.0).floor() as usize + 1)
        .max(2);
    let grid: Vec<f64> = (0..nb)
        .map(|k| tmin + (tmax - tmin) * k as f64 / (nb - 1) as f64)
        .collect();
    let (ks, us) = data.coefficients_at(&f.spec, &f.x, &f.labels, &grid);
    grid.iter()
        .zip(ks.iter().zip(&us))
        .map(|(t, (k, u))| {
            (
                *t,
                firmware_core::model::Coeffs { k: *k, u0: *u }.to_array(),
            )
        })
        .collect()
}

/// The median time between rows, s.
fn sample_period(rec: &Recording) -> f64 {
    let mut gaps: Vec<f64> = rec
        .rows
        .windows(2)
        .map(|w| w[1].t_s - w[0].t_s)
        .filter(|d| *d > 0.0)
        .collect();
    gaps.sort_by(f64::total_cmp);
    gaps.get(gaps.len() / 2).copied().unwrap_or(1.0)
}

/// Run the diagnosis.
pub fn diagnose(rec: &Recording) -> Result<Diagnosis> {
    let obs = observations(rec, 0.25, 300.0);
    if obs.len() < 6 {
        return Err(HostError::in_file(
            &rec.path,
            "too few static observations to diagnose",
        ));
    }
    let data = Data {
        rec,
        obs,
        noise: noise(rec),
        t0: rec.t0_c,
    };
    let (baseline, not_identifiable) = search::baseline(&data).ok_or_else(|| {
        HostError::in_file(
            &rec.path,
            "the positions present do not determine even the per-axis offset and scale",
        )
    })?;
    let hotspots = locate(&data, &baseline);
    let (tmin, tmax) = data
        .obs
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), o| {
            (a.min(o.temp_c), b.max(o.temp_c))
        });
    let found = search::forward(&data, &baseline, &search::fine_breakpoints(tmin, tmax));
    Ok(Diagnosis {
        noise: data.noise,
        noise_rms: metrics::noise_rms(&data),
        table: final_table(&data, &found.current, tmin, tmax),
        sample_period_s: sample_period(rec),
        initial_direction: series(rec).dir.first().copied().unwrap_or(0.0),
        baseline,
        final_fit: found.current,
        findings: found.findings,
        ambiguous: found.ambiguous,
        hotspots,
        not_identifiable,
        obs: data.obs,
    })
}
