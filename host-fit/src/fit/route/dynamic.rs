//! The dynamic route: a recording through temperature changes (a continuous sweep, the
//! tilter turning while the chamber heats and cools) fitted as the 12 temperature models
//! jointly with the unit's thermal lag (one pole in seconds on the recording's own
//! `t_s`, through firmware-core's lag state machine, as the blob will run it but across
//! an unlogged gap, crossed along the sensor's bend: `model::regressors::Cubic`) and a
//! temperature-rate term where the data carry it. It reuses the diagnosis's machinery
//! (floor-weighted windows of every dwell, contiguous held-out blocks of time, profiled
//! time constants) restricted to the terms the firmware compensates in flight: each term
//! is kept only when the held-out blocks and every acceptance rule of the diagnosis
//! support it, so a unit without dynamics keeps none, and the temperature model's order
//! is chosen on the same held-out blocks.
use crate::data::recording::Recording;
use crate::error::{ErrorKind, HostError, Result};
use crate::fit::route::detect::Shape;
use crate::model::baseline;
use crate::model::basis::Basis;
use crate::model::data::Data;
use crate::model::design::Spec;
use crate::model::effects::Extra;
use crate::model::flashed::Flashed;
use crate::model::metrics::{self, judge};
use crate::model::params::Term;
use crate::model::precision::check;
use crate::model::profile::{self, time_constant, Grid};
use crate::model::rules::Rules;
use crate::model::solve::{Depth, Fit};
use crate::model::weights::{weighed, Purpose, Weighed};
use firmware_core::temperature::Calibration;
use serde::Serialize;

/// One candidate model and what the held-out blocks said of it.
#[derive(Debug, Clone, Serialize)]
pub struct Candidate {
    /// What it is (`poly3`, `poly3 + thermal_lag 1200 s`, ...).
    pub model: String,
    /// Held-out chi-square over the blocks of time (floor units).
    pub heldout_chi2: f64,
    /// Kept.
    pub chosen: bool,
}

/// The dynamic fit of a recording.
pub struct DynamicFit<'a> {
    /// The windows, weights and held-out blocks.
    pub data: Data<'a>,
    /// The chosen model.
    pub fit: Fit,
    /// It in the firmware's form.
    pub flashed: Flashed,
    /// The thermal lag kept, s.
    pub lag_tau_s: Option<f64>,
    /// The rate term kept: per axis (output units per C/s) and the estimator's time
    /// constant, s.
    pub rate: Option<([f64; 3], f64)>,
    /// Every model compared, in order.
    pub candidates: Vec<Candidate>,
    /// The dwells' shape.
    pub shape: Shape,
    /// Held-out blocks of time.
    pub blocks: usize,
    /// The floor of a window mean (output units, RMS).
    pub noise_rms: f64,
    /// Why the model chosen on the held-out blocks is not the one flashed (its f32
    /// path departs beyond the bound), when it is not.
    pub notes: Vec<String>,
}

impl DynamicFit<'_> {
    /// The blob's calibration (temperature model and in-flight physics), its cache step
    /// chosen within the floor.
    pub fn calibration(&self) -> Result<Calibration<f64>> {
        self.flashed
            .calibration(self.data.t0, None)
            .map(|(cal, _)| cal)
    }

    /// The chosen model's description.
    pub fn describe(&self) -> String {
        describe(&self.fit)
    }
}

fn describe(f: &Fit) -> String {
    let mut s = f.spec.temperature_model();
    // only the in-flight terms this route fits (the lag and the rate) are in its specs
    for e in &f.spec.extras {
        if let Extra::Lag { taus } = e {
            s.push_str(&format!(" + thermal_lag {:.0} s", taus[0][0]));
        } else if let Extra::Rate { tau_s, centred } = e {
            s.push_str(&format!(
                " + temp_rate ({})",
                crate::model::effects::fitted_rate_estimator(*tau_s, *centred)
            ));
        }
    }
    s
}

fn candidate(f: &Fit, chosen: bool) -> Candidate {
    Candidate {
        model: describe(f),
        heldout_chi2: f.heldout,
        chosen,
    }
}

/// Golden-section steps for the lag the blob carries (see [`Grid::golden_steps`]): the
/// diagnosis's 10 leave it up to 0.9 % off its optimum, on a lattice of points.
const FLASHED_GOLDEN_STEPS: u32 = 30;

fn lag(t: f64) -> Extra {
    Extra::Lag {
        taus: [[t, 0.0]; 3],
    }
}

/// The thermal lag of `spec`, one pole for all axes (the firmware's form), profiled on
/// `grid`, then fitted in full.
fn with_lag(data: &Data, spec: &Spec, base: &Fit, grid: Grid) -> Option<Fit> {
    let (tau, _) = time_constant(
        &|t| data.fit(&spec.with(lag(t)), Some(base), Depth::Profile),
        grid,
    )?;
    data.fit(&spec.with(lag(tau)), Some(base), Depth::Full)
}

/// `f`'s lag profiled again around its value (its other terms as they are): the
/// temperature model's order, chosen after the lag was first profiled, moves it.
fn refine_lag(data: &Data, f: &Fit) -> Fit {
    let Some(i) = f
        .spec
        .extras
        .iter()
        .position(|e| matches!(e, Extra::Lag { .. }))
    else {
        return f.clone();
    };
    let Extra::Lag { taus } = f.spec.extras[i] else {
        return f.clone();
    };
    let make = |t: f64| data.fit(&f.spec.replaced(i, lag(t)), None, Depth::Profile);
    let grid = Grid {
        golden_steps: FLASHED_GOLDEN_STEPS,
        max_s: max_lag_s(data),
        ..Grid::around(data, taus[0][0], 2, 5)
    };
    time_constant(&make, grid)
        .and_then(|(t, _)| data.fit(&f.spec.replaced(i, lag(t)), None, Depth::Full))
        .filter(|g| g.chi2 <= f.chi2)
        .unwrap_or_else(|| f.clone())
}

/// The longest lag this route keeps on `data` ([`Rules::lag_max_fraction`] of it).
fn max_lag_s(data: &Data) -> f64 {
    data.span_s() * data.rules.lag_max_fraction
}

/// `larger` (the last extra added to `smaller`) passes every acceptance rule of the
/// diagnosis, the held-out blocks among them.
fn kept(data: &Data, smaller: &Fit, larger: &Fit) -> bool {
    let e = larger.spec.extras.len().saturating_sub(1);
    judge(data, smaller, larger, e).accepted(data)
}

/// The polynomial order chosen on the held-out blocks with `f`'s extras; every order
/// fitted goes to `tried` too.
fn order_by_heldout(data: &Data, f: &Fit, cands: &mut Vec<Candidate>, tried: &mut Vec<Fit>) -> Fit {
    let fits: Vec<Fit> = (0..=baseline::max_order(data))
        .filter_map(|order| {
            let mut spec = f.spec.clone();
            spec.basis = Basis::Poly { order };
            spec.offset_order = None;
            if spec == f.spec {
                return Some(f.clone());
            }
            data.fit(&spec, None, Depth::Full)
        })
        .collect();
    let best = fits
        .iter()
        .min_by(|a, b| a.heldout.total_cmp(&b.heldout))
        .cloned()
        .unwrap_or_else(|| f.clone());
    for g in &fits {
        cands.push(candidate(g, g.spec == best.spec));
    }
    tried.extend(fits);
    best
}

/// The models compared, each once (its first judgement), the final model `f` alone
/// chosen (added when refining its lag made it a model of its own).
fn compared(cands: Vec<Candidate>, f: &Fit) -> Vec<Candidate> {
    let last = describe(f);
    let mut out: Vec<Candidate> = Vec::new();
    for c in cands {
        if !out.iter().any(|o| o.model == c.model) {
            out.push(Candidate {
                chosen: c.model == last,
                ..c
            });
        }
    }
    if !out.iter().any(|o| o.chosen) {
        out.push(candidate(f, true));
    }
    out
}

/// Fit `rec` on the dynamic route (see the module doc).
pub fn fit_dynamic(rec: &Recording) -> Result<DynamicFit<'_>> {
    let Weighed { data, measured, .. } = weighed(rec, Rules::default(), Purpose::DynamicRoute)?;
    if !measured {
        return Err(HostError::in_file(
            ErrorKind::Insufficient,
            &rec.path,
            "the noise floor cannot be measured inside the dwells (too few samples per dwell): the dynamic route weighs every window by it",
        ));
    }
    let (base, _) = baseline::required(&data)?;
    // the lag profiled with the richest temperature model the data support, so that
    // the model's own bending cannot stand in for it, then judged against that model
    let top = Spec {
        basis: Basis::Poly {
            order: baseline::max_order(&data),
        },
        offset_order: None,
        ..base.spec.clone()
    };
    let mut f = data.fit(&top, None, Depth::Full).unwrap_or(base);
    let mut cands = vec![];
    let mut tried = vec![f.clone()];
    let grid = Grid {
        golden_steps: FLASHED_GOLDEN_STEPS,
        max_s: max_lag_s(&data),
        ..Grid::new(&data, 20.0, 14)
    };
    if let Some(lagged) = with_lag(&data, &f.spec, &f, grid) {
        let keep = kept(&data, &f, &lagged);
        cands.push(candidate(&f, !keep));
        cands.push(candidate(&lagged, keep));
        if keep {
            f = lagged;
            tried.push(f.clone());
        }
    }
    if let Some(rated) =
        profile::rate(&data, &f.spec, &f).and_then(|r| data.fit(&r.spec, Some(&f), Depth::Full))
    {
        let keep = kept(&data, &f, &rated);
        cands.push(candidate(&rated, keep));
        if keep {
            f = rated;
        }
    }
    let f = refine_lag(&data, &order_by_heldout(&data, &f, &mut cands, &mut tried));
    let cands = compared(cands, &f);
    let noise_rms = metrics::floor_rms(&data);
    let (f, flashed, notes) = flashable(&data, f, tried, noise_rms)?;
    let (mut lag_tau_s, mut rate) = (None, None);
    for (e, x) in f.spec.extras.iter().enumerate() {
        if let Extra::Lag { taus } = x {
            lag_tau_s = Some(taus[0][0]);
        } else if let Extra::Rate { tau_s, .. } = x {
            rate = Some((f.term(e, Term::Rate), *tau_s));
        }
    }
    Ok(DynamicFit {
        flashed,
        notes,
        blocks: data.n_chunks(),
        shape: Shape::of(rec),
        data,
        fit: f,
        lag_tau_s,
        rate,
        candidates: cands,
        noise_rms,
    })
}

/// The model chosen, `f`, in the firmware's forms, when the firmware's f32 path carries
/// it within the bound; else the first of `tried` that it carries (the richest first,
/// then by held-out chi-square), with a note naming why `f` could not be flashed. An
/// error naming the cause when none can be.
fn flashable(
    data: &Data,
    f: Fit,
    mut tried: Vec<Fit>,
    noise_rms: f64,
) -> Result<(Fit, Flashed, Vec<String>)> {
    let check = |g: &Fit| -> Result<Flashed> {
        let flashed = Flashed::of(data, g, noise_rms);
        let (cal, _) = flashed.calibration(data.t0, None)?;
        check(&cal).map(|_| flashed)
    };
    let first = match check(&f) {
        Ok(flashed) => return Ok((f, flashed, Vec::new())),
        Err(e) => e,
    };
    tried.sort_by(|a, b| {
        b.spec
            .extras
            .len()
            .cmp(&a.spec.extras.len())
            .then(a.heldout.total_cmp(&b.heldout))
    });
    for g in tried {
        if let Ok(flashed) = check(&g) {
            let note = format!(
                "the model chosen on the held-out blocks, {}, cannot be flashed ({first}): {} instead",
                describe(&f),
                describe(&g)
            );
            return Ok((g, flashed, vec![note]));
        }
    }
    Err(first)
}
