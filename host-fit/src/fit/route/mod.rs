//! The route a recording is fitted on, in one place: which route it calls for
//! ([`detect`]: a sweep, a test whose dwells still settle), the dynamic fit
//! ([`dynamic`]), the choice between them ([`fit_on`]), and the one function that turns a
//! route's fit into the firmware's calibration ([`Routed::calibration`]), used by `fit`,
//! `batch`, the demo and `plan`.
pub mod detect;
pub mod dynamic;

use crate::data::recording::Recording;
use crate::error::{ErrorKind, HostError, Result};
use crate::fit::pipeline::{
    fit_chosen, fit_recording, FitOutcome, Identification, ModelChoice, ModelRequest,
};
use crate::fit::predict::{coefficient_sigma, StaticModel, Uncertain};
use crate::model::cache::Cache;
use crate::model::metrics;
use detect::{settling, Settling, Shape};
use dynamic::{fit_dynamic, DynamicFit};
use firmware_core::temperature::Calibration;

/// Identification route.
#[derive(
    Clone,
    Copy,
    Debug,
    PartialEq,
    Eq,
    strum::Display,
    strum::EnumString,
    strum::IntoStaticStr,
    strum::EnumIter,
)]
#[strum(serialize_all = "kebab-case")]
pub enum Route {
    /// The dwells taken in thermal equilibrium (temperature span <= 0.5 C), each window
    /// at its own temperature, all at once.
    Static,
    /// Every dwell, ramps included (their dynamics are not modelled), each window at
    /// its own temperature.
    Joint,
    /// The paper's route: formula (10) per stop, then a fit across stops.
    PerStop,
    /// Every window through temperature changes, fitted jointly with the unit's thermal
    /// lag and rate where the held-out blocks support them ([`dynamic`]).
    Dynamic,
}

impl Route {
    /// The name used in outputs.
    pub fn name(self) -> &'static str {
        self.into()
    }
}

impl From<Identification> for Route {
    fn from(i: Identification) -> Self {
        match i {
            Identification::Static => Route::Static,
            Identification::Joint => Route::Joint,
            Identification::PerStop => Route::PerStop,
        }
    }
}

/// A recording fitted on its route.
pub enum Routed<'a> {
    /// A model of the static, joint or per-stop route (the dwells taken as they are).
    Identified {
        /// Which of them.
        how: Identification,
        /// The fit.
        outcome: Box<FitOutcome>,
    },
    /// The dynamic route's fit; `settling` says why a stop-and-soak test took it (None:
    /// a sweep, or the route asked for).
    Dynamic {
        /// The fit.
        fit: Box<DynamicFit<'a>>,
        /// The settling the static fit left, when that is why.
        settling: Option<Settling>,
    },
}

/// How a route's fit becomes the firmware's calibration: the options `fit` takes.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Flash {
    /// Clamp the temperature to the valid range instead of extrapolating.
    pub clamp: bool,
    /// The firmware cache's step (`--update-step`), C; None: chosen within the noise.
    pub update_step: Option<f64>,
}

/// A route's fit as the firmware's calibration.
#[derive(Debug, Clone)]
pub struct Calibrated {
    /// The calibration the blob carries.
    pub cal: Calibration<f64>,
    /// Its cache of N(T): the step and what it costs.
    pub cache: Cache,
}

impl Routed<'_> {
    /// The route taken.
    pub fn route(&self) -> Route {
        match self {
            Routed::Identified { how, .. } => Route::from(*how),
            Routed::Dynamic { .. } => Route::Dynamic,
        }
    }

    /// The model fitted, in words (`poly3`, `poly4 + thermal_lag 528 s + ...`).
    pub fn describe(&self) -> String {
        match self {
            Routed::Identified { outcome, .. } => outcome.fit.basis.describe(),
            Routed::Dynamic { fit, .. } => fit.describe(),
        }
    }

    /// The thermal lag the blob carries, s (None: none).
    pub fn lag_tau_s(&self) -> Option<f64> {
        match self {
            Routed::Identified { .. } => None,
            Routed::Dynamic { fit, .. } => fit.lag_tau_s,
        }
    }

    /// The one place a route's fit becomes the firmware's calibration: the model the
    /// blob carries (the static route's temperature model; the dynamic route's in the
    /// firmware's forms, with its in-flight terms), and the cache's step chosen within the
    /// noise a verification dwell adds of its own (or `flash.update_step`).
    pub fn calibration(&self, rec: &Recording, flash: Flash) -> Result<Calibrated> {
        match self {
            Routed::Identified { outcome, .. } => {
                let mut cal = outcome.fit.calibration(0.0, flash.clamp);
                let cache = Cache::for_fit(rec, outcome, &mut cal, flash.update_step);
                Ok(Calibrated { cal, cache })
            }
            Routed::Dynamic { fit, .. } => {
                let (mut cal, cache) = fit.flashed.calibration(fit.data.t0, flash.update_step)?;
                cal.clamp = flash.clamp;
                Ok(Calibrated { cal, cache })
            }
        }
    }
}

/// The model the blob carries, as the prediction sees it.
impl Uncertain for Routed<'_> {
    fn coefficients(&self, t: f64) -> [f64; 12] {
        match self {
            Routed::Identified { outcome, .. } => outcome.fit.eval(t),
            Routed::Dynamic { fit, .. } => metrics::coefficients(&fit.data, &fit.flashed.fit, t),
        }
    }

    fn variance(&self, t: f64, s: &[f64; 12]) -> f64 {
        match self {
            Routed::Identified { outcome, .. } => StaticModel {
                fit: &outcome.fit,
                noise: &outcome.noise,
            }
            .variance(t, s),
            Routed::Dynamic { fit, .. } => metrics::variance(&fit.data, &fit.flashed.fit, t, s),
        }
    }

    /// The static route's from its per-axis covariances; the dynamic route's also at
    /// least its Newey-West bound (residuals correlated in time).
    fn coefficient_sigma(&self, t: f64) -> [f64; 12] {
        match self {
            Routed::Identified { outcome, .. } => {
                coefficient_sigma(&outcome.fit, &outcome.noise, t)
            }
            Routed::Dynamic { fit, .. } => {
                metrics::coefficient_sigma(&fit.data, &fit.flashed.fit, t)
            }
        }
    }
}

/// Fit `rec` on `route`, or with None on the route the data choose ([`choose`]), with
/// the model request `req` (a model given keeps the static route); why a route tried
/// was not kept goes to `notes`.
pub fn fit_on<'a>(
    rec: &'a Recording,
    route: Option<Route>,
    req: &ModelRequest,
    notes: &mut Vec<String>,
) -> Result<Routed<'a>> {
    req.check()?;
    let how = match route {
        None => return choose(rec, req, notes),
        Some(Route::Dynamic) if req.kind.is_some() => {
            return Err(HostError::new(ErrorKind::Invalid,
                "the dynamic route chooses its model on held-out blocks of time; --model does not apply to it",
            ))
        }
        Some(Route::Dynamic) => return dynamic(rec, None, notes),
        Some(Route::Static) => {
            return Ok(Routed::Identified {
                how: Identification::Static,
                outcome: Box::new(fit_chosen(rec, req)?),
            })
        }
        Some(Route::Joint) => Identification::Joint,
        Some(Route::PerStop) => Identification::PerStop,
    };
    let Some(kind) = req.kind else {
        return Err(HostError::new(ErrorKind::Invalid, format!(
            "the model is chosen by the data on the static route only; with --route {} give --model",
            Route::from(how).name()
        )));
    };
    let choice = ModelChoice {
        kind,
        order: req.order,
        breakpoints: req.breakpoints.clone(),
    };
    Ok(Routed::Identified {
        how,
        outcome: Box::new(fit_recording(rec, &choice, how)?),
    })
}

/// The route the data choose for `rec` with the model request `req` (a given family
/// keeps the static route): a sweep takes the dynamic route; a stop-and-soak test whose
/// dwells still settle ([`settling`]) is fitted on it too and kept there when its
/// held-out blocks keep a lag or rate term; anything else the static route. A step that
/// fails does not end the choice while another route can be taken: a static fit that
/// cannot be made, or whose model the firmware's f32 path cannot carry within its bound,
/// leaves the choice to the dynamic route when that keeps a lag or rate term (the
/// dwells' dynamics are then why). Why a route tried was not kept goes to `notes`.
pub fn choose<'a>(
    rec: &'a Recording,
    req: &ModelRequest,
    notes: &mut Vec<String>,
) -> Result<Routed<'a>> {
    if req.kind.is_none() && Shape::of(rec).is_sweep() {
        return dynamic(rec, None, notes);
    }
    let static_fit = fit_chosen(rec, req).and_then(|oc| {
        let cal = oc.fit.calibration(0.0, false);
        flashable(&cal).map(|()| oc)
    });
    let oc = match static_fit {
        Ok(oc) => oc,
        Err(e) if req.kind.is_none() => {
            return match fit_dynamic(rec) {
                Ok(d) if d.lag_tau_s.is_some() || d.rate.is_some() => {
                    notes.push(format!(
                        "the static route could not be taken ({e}): dynamic route, whose held-out blocks keep the dwells' dynamics"
                    ));
                    Ok(taken(d, None, notes))
                }
                _ => Err(e),
            };
        }
        Err(e) => return Err(e),
    };
    if req.kind.is_none() {
        if let Some(st) = settling(rec, &oc.fit).filter(Settling::seen) {
            let why = format!(
                "the dwells look unsettled (a lag near {:.0} s explains {:.0}% of the static fit's residual)",
                st.tau_s,
                100.0 * st.explained
            );
            match fit_dynamic(rec) {
                Ok(d) if d.lag_tau_s.is_some() || d.rate.is_some() => {
                    return Ok(taken(d, Some(st), notes))
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
    Ok(Routed::Identified {
        how: Identification::Static,
        outcome: Box::new(oc),
    })
}

/// `rec` on the dynamic route ([`taken`]).
fn dynamic<'a>(
    rec: &'a Recording,
    settling: Option<Settling>,
    notes: &mut Vec<String>,
) -> Result<Routed<'a>> {
    Ok(taken(fit_dynamic(rec)?, settling, notes))
}

/// The dynamic fit `d` as the route taken, its notes (why the model flashed is not the
/// one chosen, when it is not) added to `notes`.
fn taken<'a>(d: DynamicFit<'a>, settling: Option<Settling>, notes: &mut Vec<String>) -> Routed<'a> {
    notes.extend(d.notes.iter().cloned());
    Routed::Dynamic {
        fit: Box::new(d),
        settling,
    }
}

/// Whether the firmware's f32 path carries `cal` within its bound; the error names why
/// not ([`crate::model::precision::check`]).
fn flashable(cal: &Calibration<f64>) -> Result<()> {
    crate::model::precision::check(cal).map(|_| ())
}
