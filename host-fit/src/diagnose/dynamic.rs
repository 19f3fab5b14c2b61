//! The dynamic route: a recording through temperature changes (a continuous sweep, the
//! tilter turning while the chamber heats and cools) fitted as the 12 temperature models
//! jointly with the unit's thermal lag (one pole in seconds on the recording's own
//! `t_s`, through firmware-core's lag state machine, as the blob will run it) and a
//! temperature-rate term where the data carry it. It reuses the diagnosis's machinery
//! (floor-weighted windows of every dwell, contiguous held-out blocks of time, profiled
//! time constants) restricted to the terms the firmware compensates in flight: each term
//! is kept only when the held-out blocks and every acceptance rule of the diagnosis
//! support it, so a unit without dynamics keeps none, and the temperature model's order
//! is chosen on the same held-out blocks.
use crate::data::recording::{Recording, MAX_DWELL_DRIFT_C};
use crate::diagnose::baseline;
use crate::diagnose::data::Data;
use crate::diagnose::design::Spec;
use crate::diagnose::effects::Extra;
use crate::diagnose::firmware::Flashed;
use crate::diagnose::fit::{Depth, Fit};
use crate::diagnose::floor;
use crate::diagnose::metrics::{self, judge};
use crate::diagnose::profile::{self, time_constant, Grid};
use crate::diagnose::Rules;
use crate::error::{ErrorKind, HostError, Result};
use crate::fit::route::{settling, Settling};
use crate::fit::temperature::Basis;
use firmware_core::temperature::Calibration;
use serde::Serialize;

/// A recording is a sweep when at least this share of its dwells drift more than
/// [`MAX_DWELL_DRIFT_C`] (the static route keeps none of them). Counted in dwells, not
/// samples: a stop-and-soak test's few long rests through its ramps hold most of its
/// samples, its tilter's dwells are static.
pub const SWEEP_MOVING_SHARE: f64 = crate::data::recording::SWEEP_MOVING_SHARE;

/// How much of a recording's dwells move in temperature.
#[derive(Debug, Clone, Copy, Serialize, PartialEq)]
pub struct Shape {
    /// Dwells within [`MAX_DWELL_DRIFT_C`] (the static route's data).
    pub static_dwells: usize,
    /// Dwells drifting more.
    pub moving_dwells: usize,
    /// Share of the dwells that move.
    pub moving_share: f64,
}

impl Shape {
    /// The dwells of `rec`.
    pub fn of(rec: &Recording) -> Shape {
        let m = rec
            .dwells
            .iter()
            .filter(|d| d.temp_span_c > MAX_DWELL_DRIFT_C)
            .count();
        let n = rec.dwells.len();
        Shape {
            static_dwells: n - m,
            moving_dwells: m,
            moving_share: m as f64 / n.max(1) as f64,
        }
    }

    /// Most dwells move in temperature: a sweep, for the dynamic route.
    pub fn is_sweep(&self) -> bool {
        self.moving_share >= SWEEP_MOVING_SHARE
    }
}

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
}

impl DynamicFit<'_> {
    /// The blob's calibration (temperature model and in-flight physics).
    pub fn calibration(&self) -> Result<Calibration<f64>> {
        self.flashed.calibration(self.data.t0)
    }

    /// The chosen model's description.
    pub fn describe(&self) -> String {
        describe(&self.fit)
    }
}

fn describe(f: &Fit) -> String {
    let mut s = f.spec.basis.describe();
    // only the in-flight terms this route fits (the lag and the rate) are in its specs
    for e in &f.spec.extras {
        if let Extra::Lag { taus } = e {
            s.push_str(&format!(" + thermal_lag {:.0} s", taus[0][0]));
        } else if let Extra::Rate { tau_s } = e {
            s.push_str(&format!(" + temp_rate (estimator {tau_s:.0} s)"));
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
        ..Grid::around(data, taus[0][0], 2, 5)
    };
    time_constant(&make, grid)
        .and_then(|(t, _)| data.fit(&f.spec.replaced(i, lag(t)), None, Depth::Full))
        .filter(|g| g.chi2 <= f.chi2)
        .unwrap_or_else(|| f.clone())
}

/// `larger` (the last extra added to `smaller`) passes every acceptance rule of the
/// diagnosis, the held-out blocks among them.
fn kept(data: &Data, smaller: &Fit, larger: &Fit) -> bool {
    let e = larger.spec.extras.len().saturating_sub(1);
    judge(data, smaller, larger, e).accepted(data)
}

/// The polynomial order chosen on the held-out blocks with `f`'s extras.
fn order_by_heldout(data: &Data, f: &Fit, cands: &mut Vec<Candidate>) -> Fit {
    let fits: Vec<Fit> = (0..=baseline::max_order(data))
        .filter_map(|order| {
            let mut spec = f.spec.clone();
            spec.basis = Basis::Poly { order };
            if spec.basis == f.spec.basis {
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
    let rules = Rules::default();
    let fl = floor::floor(rec, &rules);
    let mut data = Data::new(rec, &fl, rules);
    if data.obs.len() < rules.min_windows {
        return Err(HostError::in_file(
            ErrorKind::Insufficient,
            &rec.path,
            format!(
                "{} windows of known positions: too few for the dynamic route (need {})",
                data.obs.len(),
                rules.min_windows
            ),
        ));
    }
    if !crate::diagnose::weigh(&mut data, &fl) {
        return Err(HostError::in_file(
            ErrorKind::Insufficient,
            &rec.path,
            "the noise floor cannot be measured inside the dwells (too few samples per dwell): the dynamic route weighs every window by it",
        ));
    }
    let (base, _) = baseline::baseline(&data).ok_or_else(|| {
        HostError::in_file(
            ErrorKind::Insufficient,
            &rec.path,
            "the positions present do not determine even the per-axis offset and scale (need each axis both along and across gravity)",
        )
    })?;
    // the lag profiled with the richest temperature model the data support, so that
    // the model's own bending cannot stand in for it, then judged against that model
    let top = Spec {
        basis: Basis::Poly {
            order: baseline::max_order(&data),
        },
        ..base.spec.clone()
    };
    let mut f = data.fit(&top, None, Depth::Full).unwrap_or(base);
    let mut cands = vec![];
    let grid = Grid {
        golden_steps: FLASHED_GOLDEN_STEPS,
        ..Grid::new(&data, 20.0, 14)
    };
    if let Some(lagged) = with_lag(&data, &f.spec, &f, grid) {
        let keep = kept(&data, &f, &lagged);
        cands.push(candidate(&f, !keep));
        cands.push(candidate(&lagged, keep));
        if keep {
            f = lagged;
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
    let f = refine_lag(&data, &order_by_heldout(&data, &f, &mut cands));
    let cands = compared(cands, &f);
    let noise_rms = metrics::floor_rms(&data);
    let term = |f: &Fit, e: usize| -> [f64; 3] {
        std::array::from_fn(|axis| {
            f.labels
                .iter()
                .position(|l| {
                    *l == crate::diagnose::params::Param::Effect {
                        term: crate::diagnose::params::Term::Rate,
                        axis,
                        extra: e,
                    }
                })
                .map(|j| f.x[j])
                .unwrap_or(0.0)
        })
    };
    let (mut lag_tau_s, mut rate) = (None, None);
    for (e, x) in f.spec.extras.iter().enumerate() {
        if let Extra::Lag { taus } = x {
            lag_tau_s = Some(taus[0][0]);
        } else if let Extra::Rate { tau_s } = x {
            rate = Some((term(&f, e), *tau_s));
        }
    }
    Ok(DynamicFit {
        flashed: Flashed::of(&data, &f, noise_rms),
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

/// The route `fit` and `batch` take by default (`--route auto`), chosen by the data.
pub enum Routed<'a> {
    /// The static route's fit (the dwells in equilibrium).
    Static(Box<crate::fit::pipeline::FitOutcome>),
    /// The dynamic route's; `settling` says why a stop-and-soak test took it (None: a sweep).
    Dynamic {
        /// The fit.
        fit: Box<DynamicFit<'a>>,
        /// The settling the static fit left, when that is why.
        settling: Option<Settling>,
    },
}

/// The data's route for `rec` with the model request `req` (a given family keeps the
/// static route): a sweep takes the dynamic route; a stop-and-soak test whose dwells
/// still settle ([`settling`]) is fitted on it too and kept there when its held-out blocks
/// keep a lag or rate term; anything else the static route. Why the static fit stood
/// where a settling was seen goes to `notes`.
pub fn auto<'a>(
    rec: &'a Recording,
    req: &crate::fit::pipeline::ModelRequest,
    notes: &mut Vec<String>,
) -> Result<Routed<'a>> {
    if req.kind.is_none() && Shape::of(rec).is_sweep() {
        return Ok(Routed::Dynamic {
            fit: Box::new(fit_dynamic(rec)?),
            settling: None,
        });
    }
    let oc = crate::fit::pipeline::fit_chosen(rec, req)?;
    if req.kind.is_none() {
        if let Some(st) = settling(rec, &oc.fit).filter(Settling::seen) {
            let why = format!(
                "the dwells look unsettled (a lag near {:.0} s explains {:.0}% of the static fit's residual)",
                st.tau_s,
                100.0 * st.explained
            );
            match fit_dynamic(rec) {
                Ok(d) if d.lag_tau_s.is_some() || d.rate.is_some() => {
                    return Ok(Routed::Dynamic {
                        fit: Box::new(d),
                        settling: Some(st),
                    })
                }
                Ok(_) => notes.push(format!(
                    "{why}, but the held-out blocks keep no lag or rate term: static route"
                )),
                Err(e) => notes.push(format!(
                    "{why}; the dynamic route could not be taken ({e}): static route"
                )),
            }
        }
    }
    Ok(Routed::Static(Box::new(oc)))
}
