//! Diagnosis: when the model and a recording disagree, locate the mismatch, name the
//! physics left out (physics-catalogue.md) where the data support it, model it, show the
//! fit improve on held-out data, and say plainly what stays unexplained.
//!
//! The error floor is measured inside the dwells at every time scale ([`floor`]), every
//! window weighted by it; the baseline and the catalogue's effects (their structural
//! unknowns profiled, [`profile`]) are fitted in one weighted least squares over all three
//! axes ([`design`]); an effect joins only when it passes every rule of [`search`] in the
//! dispersion of the larger model, survives the backward check of the joint model, and
//! explains the data where it acts. Findings take their parameters from the final joint
//! fit. `HOSTFIT_DEBUG=1` prints every candidate's judgement to stderr.
pub mod calibration;
pub mod contract;
pub mod design;
pub mod effects;
pub mod findings;
pub mod flash;
pub mod floor;
pub mod location;
pub mod metrics;
pub mod observations;
pub mod params;
pub mod profile;
pub mod quality;
pub mod regressors;
pub mod search;

pub use effects::EFFECT_IDS;

use crate::data::recording::Recording;
use crate::error::{HostError, Result};
use crate::fit::temperature::temperature_clusters;
use design::{Data, Fit};
use findings::{Ambiguity, Finding};
use floor::Floor;
use location::{locate, Hotspot};
use observations::{observations, window_means, DObs};
use quality::QualityNote;
use regressors::Events;

/// The whole diagnosis.
#[derive(Debug, Clone)]
pub struct Diagnosis {
    /// The measured error floor.
    pub floor: Floor,
    /// Whether the floor was measured (else the baseline's own scatter stands in).
    pub floor_measured: bool,
    /// Baseline.
    pub baseline: Fit,
    /// Final model.
    pub final_fit: Fit,
    /// Accepted findings.
    pub findings: Vec<Finding>,
    /// Ambiguities.
    pub ambiguous: Vec<Ambiguity>,
    /// Where the baseline residual exceeds the floor.
    pub hotspots: Vec<Hotspot>,
    /// Where the final residual still exceeds the floor (empty when at the floor).
    pub unexplained: Vec<Hotspot>,
    /// What cannot be identified from this recording.
    pub not_identifiable: Vec<String>,
    /// Notes on the data.
    pub quality: Vec<QualityNote>,
    /// The observations.
    pub obs: Vec<DObs>,
    /// Their weights (per observation and axis).
    pub w: Vec<f64>,
    /// Spike rows.
    pub spikes: Vec<usize>,
    /// Gaps and handling.
    pub events: Events,
    /// Expected residual RMS from the floor alone (output units, per window).
    pub noise_rms: f64,
    /// The model the blob carries: the final one in the firmware's forms (one lag pole
    /// for all axes, offsets-only hysteresis, one warm-up), refitted where it differs.
    pub flashed: Fit,
    /// The flashed model's coefficients on a grid over the data's temperatures.
    pub table: Vec<(f64, [f64; 12])>,
    /// Median sample period of the recording, s.
    pub sample_period_s: f64,
}

impl Diagnosis {
    /// The data the diagnosis was made on (to evaluate its fits again).
    pub fn data<'a>(&self, rec: &'a Recording) -> Data<'a> {
        make_data(
            rec,
            self.obs.clone(),
            self.spikes.clone(),
            self.w.clone(),
            self.events.clone(),
        )
    }
}

fn make_data(
    rec: &Recording,
    obs: Vec<DObs>,
    spikes: Vec<usize>,
    w: Vec<f64>,
    events: Events,
) -> Data<'_> {
    let rate = window_means(&obs, &regressors::rates(rec, 60.0), &spikes);
    let dir = window_means(&obs, &regressors::directions(rec, 0.5, 0.0), &spikes);
    Data {
        rec,
        obs,
        spikes,
        w,
        t0: rec.t0_c,
        events,
        rate,
        dir,
    }
}

/// The final model's coefficients on a grid of up to 16 points, about one per 2 C, over
/// the data's temperature range.
fn final_table(data: &Data, f: &Fit) -> Vec<(f64, [f64; 12])> {
    let (tmin, tmax) = data
        .obs
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), o| {
            (a.min(o.temp_c), b.max(o.temp_c))
        });
    let nb = 16usize
        .min(((tmax - tmin) / 2.0).floor() as usize + 1)
        .max(2);
    let mut grid: Vec<f64> = (0..nb)
        .map(|k| tmin + (tmax - tmin) * k as f64 / (nb - 1) as f64)
        .collect();
    // a bend sits on a breakpoint (the nearest interior one moves to it), so the table
    // carries it sharp
    for e in &f.spec.extras {
        if let effects::Extra::Bend { knot_c } = e {
            if let Some(g) = grid[1..nb - 1]
                .iter_mut()
                .min_by(|a, b| (**a - knot_c).abs().total_cmp(&(**b - knot_c).abs()))
            {
                *g = *knot_c;
            }
        }
    }
    grid.sort_by(f64::total_cmp);
    grid.dedup();
    grid.iter()
        .zip(data.coefficients_at(f, &grid))
        .map(|(t, (k, u0))| (*t, firmware_core::model::Coeffs { k, u0 }.to_array()))
        .collect()
}

/// Weights from the floor, or (floor not measurable) from the scatter per axis that the
/// most general static model leaves (the baseline with every static catalogue term the
/// positions determine: what none of the candidates could explain is the floor).
fn weights(data: &mut Data, floor: &Floor) -> bool {
    let measured = floor.axes.iter().all(|a| !a.scales.is_empty());
    if measured {
        data.w = data
            .obs
            .iter()
            .flat_map(|o| {
                (0..3).map(move |i| 1.0 / floor.axes[i].var_of_mean(o.n as f64).unwrap_or(1.0))
            })
            .collect();
        return true;
    }
    data.w = vec![1.0; data.n_rows()];
    if let Some((b, _)) = search::baseline(data) {
        let general = [
            vec![effects::Extra::K2, effects::Extra::Asymmetry],
            vec![effects::Extra::K2],
            vec![],
        ]
        .into_iter()
        .find_map(|extras| {
            let spec = design::Spec {
                extras,
                basis: crate::fit::temperature::Basis::Poly {
                    order: search::max_order(data),
                },
                ..b.spec.clone()
            };
            data.fit(&spec, None, false)
        })
        .unwrap_or(b);
        let per_axis: [f64; 3] = std::array::from_fn(|i| {
            let ss: f64 = general.resid.iter().map(|r| r[i] * r[i]).sum();
            let dof = data.obs.len().saturating_sub(general.k.div_ceil(3));
            (ss / dof.max(1) as f64).max(1e-300)
        });
        data.w = (0..data.n_rows()).map(|r| 1.0 / per_axis[r % 3]).collect();
    }
    false
}

/// What this recording can judge.
fn scope(data: &Data, measured: bool, n_temps: usize, notes: &mut Vec<String>) -> search::Scope {
    let moving = data.rate.iter().any(|r| r.abs() > 2e-4);
    let reversals = data.dir.iter().any(|d| *d > 0.5) && data.dir.iter().any(|d| *d < -0.5);
    let s = search::Scope {
        temperature: n_temps > 1,
        dynamics: measured && moving && n_temps > 1,
        reversals,
        max_order: search::max_order(data),
    };
    if !s.dynamics {
        notes.push("thermal_lag, temp_rate, warmup_drift, hysteresis: need a time series through temperature changes with a measurable floor".into());
    } else if !s.reversals {
        notes
            .push("hysteresis: needs a temperature visited after heating and after cooling".into());
    }
    if !s.temperature {
        notes.push(
            "temp_curvature and every temperature model: need more than one temperature".into(),
        );
    }
    s
}

/// Findings of the final model (an effect that matters on no axis is dropped and the
/// model refitted).
fn findings_of(data: &Data, mut f: Fit, ambiguous: &[Vec<&'static str>]) -> (Fit, Vec<Finding>) {
    'again: loop {
        let mut out = Vec::new();
        for e in 0..f.spec.extras.len() {
            let Some(reduced) = search::without(data, &f, e) else {
                continue;
            };
            let id = f.spec.extras[e].id();
            match findings::finding(data, &f, &reduced, e) {
                None => {
                    f = reduced;
                    continue 'again;
                }
                Some(x) if !ambiguous.iter().any(|g| g.contains(&id)) => out.push(x),
                Some(_) => {}
            }
        }
        return (f, out);
    }
}

/// Run the diagnosis.
pub fn diagnose(rec: &Recording) -> Result<Diagnosis> {
    let floor = floor::floor(rec);
    let obs = observations(rec, &floor.spikes, 0.25, 300.0);
    if obs.len() < 6 {
        return Err(HostError::in_file(
            &rec.path,
            format!(
                "{} static windows of known positions: too few to diagnose (need 6, e.g. 6 positions)",
                obs.len()
            ),
        ));
    }
    let mut data = make_data(
        rec,
        obs,
        floor.spikes.clone(),
        Vec::new(),
        regressors::events(rec),
    );
    let measured = weights(&mut data, &floor);
    let temps: Vec<f64> = data.obs.iter().map(|o| o.temp_c).collect();
    let n_temps = temperature_clusters(&temps).len();
    let (baseline, mut not_identifiable) = search::baseline(&data).ok_or_else(|| {
        HostError::in_file(
            &rec.path,
            "the positions present do not determine even the per-axis offset and scale (need each axis both along and across gravity)",
        )
    })?;
    let scope = scope(&data, measured, n_temps, &mut not_identifiable);
    let z = metrics::z(&data, &baseline);
    let hotspots = locate(&data, &z, &baseline.resid, 2.0);
    let found = search::forward(&data, &baseline, &scope);
    let joint = search::keep_adequate(&data, search::backward(&data, found.current));
    let ambiguous_groups: Vec<Vec<&'static str>> = found
        .ambiguous
        .into_iter()
        .filter(|g| joint.spec.extras.iter().any(|e| g.contains(&e.id())))
        .collect();
    let (final_fit, findings) = findings_of(&data, joint, &ambiguous_groups);
    let ambiguous = ambiguous_groups
        .iter()
        .map(|g| Ambiguity {
            candidates: g.iter().map(|s| s.to_string()).collect(),
            needed: findings::needed(g[0], g.get(1).copied().unwrap_or("")),
        })
        .collect();
    let unexplained = if metrics::normalized_rms(&data, &final_fit) > search::AT_FLOOR_RMS {
        locate(&data, &metrics::z(&data, &final_fit), &final_fit.resid, 2.0)
    } else {
        Vec::new()
    };
    let quality = quality::notes(rec, &floor, &data.obs, &data.events, n_temps);
    let flashed = flash::flashable(&data, &final_fit);
    Ok(Diagnosis {
        noise_rms: metrics::floor_rms(&data),
        table: final_table(&data, &flashed),
        flashed,
        sample_period_s: regressors::median_step(rec),
        floor,
        floor_measured: measured,
        baseline,
        final_fit,
        findings,
        ambiguous,
        hotspots,
        unexplained,
        not_identifiable,
        quality,
        obs: data.obs,
        w: data.w,
        spikes: data.spikes,
        events: data.events,
    })
}
