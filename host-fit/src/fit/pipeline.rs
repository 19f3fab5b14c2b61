//! The fit pipeline: a recording's calibration dwells -> temperature model, by the
//! static route (the dwells taken in thermal equilibrium, each window at its own
//! temperature: the default), the joint route (every window, ramps included) or the
//! paper's per-stop route (formula (10) per stop, then a fit across stops); the model
//! given, or chosen by the data (`fit::select`); poses of unknown orientation estimated
//! first (`fit::orientation`).
use crate::data::positions::Role;
use crate::data::recording::Recording;
use crate::data::stops::{stops, WINDOW_SPAN_C};
use crate::data::table::TableRow;
use crate::error::{ErrorKind, HostError, Result};
use crate::fit::equilibrium::{static_observations, Excluded};
use crate::fit::identify::{identify_stop, observations, Obs, StopCoeffs};
use crate::fit::noise::{noise, Noise};
use crate::fit::orientation::{estimate_with, has_unknown, provisional_basis, Orientation};
use crate::fit::select::{choose_among, Selection};
use crate::fit::temperature::{fit_joint, fit_table, Frame, ModelFit, Setting};
use crate::model::basis::{temperature_clusters, Basis};
use std::borrow::Cow;

/// Temperature model kind.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ModelKind {
    /// Piecewise-linear through breakpoints.
    Pwl,
    /// Polynomial of dT.
    Poly,
}

/// How a model given is identified from a recording's dwells (the routes of
/// [`crate::fit::route::Route`] that take a model given; the dynamic route chooses its
/// own).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Identification {
    /// The dwells taken in thermal equilibrium (temperature span <= 0.5 C), each window
    /// at its own temperature, all at once.
    Static,
    /// Every dwell, ramps included (their dynamics are not modelled), each window at
    /// its own temperature.
    Joint,
    /// The paper's route: formula (10) per stop, then a fit across stops.
    PerStop,
}

/// The temperature model asked for.
#[derive(Clone, Debug, PartialEq)]
pub struct ModelChoice {
    /// Family.
    pub kind: ModelKind,
    /// Polynomial order (default: 3, or less with fewer temperatures; 0 with one).
    pub order: Option<usize>,
    /// Breakpoints, C (default: the given temperatures).
    pub breakpoints: Option<Vec<f64>>,
}

impl ModelChoice {
    /// The basis for data at the distinct temperatures `temps`.
    pub fn basis(&self, temps: &[f64]) -> Basis {
        match self.kind {
            ModelKind::Poly => Basis::Poly {
                order: self
                    .order
                    .unwrap_or_else(|| 3.min(temps.len().saturating_sub(1))),
            },
            ModelKind::Pwl => Basis::Pwl {
                breakpoints: self.breakpoints.clone().unwrap_or_else(|| temps.to_vec()),
            },
        }
    }
}

/// Per-stop identification of the calibration positions.
pub fn identify_stops(rec: &Recording) -> Result<Vec<StopCoeffs>> {
    rec.positions
        .require_known(
            rec.dwells
                .iter()
                .map(|d| d.position)
                .filter(|p| rec.positions.has_role(*p, Role::Calibration)),
            "identification per stop",
        )
        .map_err(|e| e.within(&rec.path))?;
    let nz = noise(rec);
    let cal = |p: usize| rec.positions.has_role(p, Role::Calibration);
    let st = stops(rec, &cal, 3.0);
    if st.is_empty() {
        return Err(HostError::in_file(
            ErrorKind::Insufficient,
            &rec.path,
            "no static calibration dwells (a calibration position held within 0.5 C): this is not a production test with stops; a recording without them (a soak, a field recording) is diagnosed with `host-fit diagnose REC --report R.html`",
        ));
    }
    st.iter().map(|s| identify_stop(rec, s, &nz)).collect()
}

/// What a fit decided and measured.
pub struct FitOutcome {
    /// The fitted model.
    pub fit: ModelFit,
    /// Per-stop identification (for the report and the paper comparison; empty when
    /// the positions do not form full stops).
    pub stops: Vec<StopCoeffs>,
    /// The noise the fit was weighted with.
    pub noise: Noise,
    /// How the data chose the model (None when it was given).
    pub selection: Option<Selection>,
    /// The dwells the equilibrium rule left out.
    pub excluded: Excluded,
    /// The estimated orientations, when the recording has poses of unknown orientation.
    pub orientation: Option<Orientation>,
}

/// What the user asked of the model: a family (or the data's choice) and, for it, an
/// order or breakpoints. The default leaves everything to the data.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ModelRequest {
    /// The family; None: chosen by the data.
    pub kind: Option<ModelKind>,
    /// `--order`.
    pub order: Option<usize>,
    /// `--breakpoints`.
    pub breakpoints: Option<Vec<f64>>,
}

impl ModelRequest {
    /// An option that does not apply to the family is an error, never ignored.
    pub fn check(&self) -> Result<()> {
        match (self.kind, &self.order, &self.breakpoints) {
            (Some(ModelKind::Pwl), Some(_), _) => Err(HostError::new(
                ErrorKind::Invalid,
                "--order applies to a polynomial model, not to --model pwl (give --breakpoints)",
            )),
            (Some(ModelKind::Poly), _, Some(_)) => Err(HostError::new(
                ErrorKind::Invalid,
                "--breakpoints apply to a piecewise-linear model, not to --model poly (give --order)",
            )),
            (None, Some(_), Some(_)) => Err(HostError::new(
                ErrorKind::Invalid,
                "--order and --breakpoints belong to different models; give --model",
            )),
            _ => Ok(()),
        }
    }

    /// With the family chosen by the data as `chosen`, the basis the request makes of
    /// it: an order or breakpoints given must fit the chosen family.
    fn refine(&self, chosen: &Basis) -> Result<Basis> {
        match (chosen, self.order, &self.breakpoints) {
            (Basis::Poly { .. }, Some(order), _) => Ok(Basis::Poly { order }),
            (Basis::Pwl { .. }, _, Some(b)) => Ok(Basis::Pwl {
                breakpoints: b.clone(),
            }),
            (Basis::Pwl { .. }, Some(_), _) => Err(HostError::new(ErrorKind::Invalid, format!(
                "--order applies to a polynomial model; the data chose {} (give --model poly to insist)",
                chosen.describe()
            ))),
            (Basis::Poly { .. }, _, Some(_)) => Err(HostError::new(ErrorKind::Invalid, format!(
                "--breakpoints apply to a piecewise-linear model; the data chose {} (give --model pwl to insist)",
                chosen.describe()
            ))),
            _ => Ok(chosen.clone()),
        }
    }
}

/// A recording with its poses of unknown orientation estimated, and the estimate.
#[derive(Debug, Clone)]
pub struct Oriented<'r> {
    /// The recording, every position with a vector (borrowed when none was unknown).
    pub rec: Cow<'r, Recording>,
    /// The estimate, when the recording had poses of unknown orientation.
    pub orientation: Option<Orientation>,
}

impl Oriented<'_> {
    /// The frame every fit of the recording keeps: lower triangular when the estimated
    /// poses left it to the convention (no known pose fixed it), as the estimate did.
    pub fn frame(&self) -> Frame {
        match &self.orientation {
            Some(o) if o.frame.is_some() => Frame::LowerTriangular,
            _ => Frame::Given,
        }
    }
}

/// `rec` with its poses of unknown orientation estimated with the temperature model
/// `basis`, or the provisional one (the recording borrowed unchanged when it has none).
pub fn with_orientations<'r>(rec: &'r Recording, basis: Option<&Basis>) -> Result<Oriented<'r>> {
    if !has_unknown(rec) {
        return Ok(Oriented {
            rec: Cow::Borrowed(rec),
            orientation: None,
        });
    }
    let basis = match basis {
        Some(b) => b.clone(),
        None => {
            let (obs, _) = static_calibration(rec);
            provisional_basis(&obs.iter().map(|o| o.temp_c).collect::<Vec<_>>())
        }
    };
    let o = estimate_with(rec, &basis)?;
    let mut r = rec.clone();
    r.positions = o.positions.clone();
    Ok(Oriented {
        rec: Cow::Owned(r),
        orientation: Some(o),
    })
}

fn static_calibration(rec: &Recording) -> (Vec<Obs>, Excluded) {
    let cal = |p: usize| rec.positions.has_role(p, Role::Calibration);
    static_observations(rec, &cal)
}

fn require_known(rec: &Recording, obs: &[Obs]) -> Result<()> {
    rec.positions
        .require_known(obs.iter().map(|o| o.position), "the fit")
        .map_err(|e| e.within(&rec.path))
}

/// The joint fits' setting of `rec` weighted by `noise` in `frame`.
fn setting<'a>(rec: &'a Recording, noise: &'a Noise, frame: Frame) -> Setting<'a> {
    Setting {
        noise,
        t0_c: rec.t0_c,
        frame,
        path: &rec.path,
    }
}

/// The static route with the model the request leaves to the data (see the module
/// doc): the family and its order or breakpoints, or only the order or breakpoints
/// within a family the user named. Poses of unknown orientation are estimated with the
/// provisional model and the model chosen on them; when the model chosen is another,
/// the poses are estimated again with it (the directions depend on the model they are
/// read with).
pub fn fit_chosen(rec: &Recording, req: &ModelRequest) -> Result<FitOutcome> {
    req.check()?;
    let family: &dyn Fn(&Basis) -> bool = match (req.kind, &req.order, &req.breakpoints) {
        (None, _, _) => &|_| true,
        // the family and its order or breakpoints given: nothing is left to choose
        (Some(kind), Some(_), _) | (Some(kind), _, Some(_)) => {
            let choice = ModelChoice {
                kind,
                order: req.order,
                breakpoints: req.breakpoints.clone(),
            };
            return fit_recording(rec, &choice, Identification::Static);
        }
        (Some(ModelKind::Poly), None, None) => &|b| matches!(b, Basis::Poly { .. }),
        (Some(ModelKind::Pwl), None, None) => &|b| matches!(b, Basis::Pwl { .. }),
    };
    let provisional = with_orientations(rec, None)?;
    let frame = provisional.frame();
    let r = &*provisional.rec;
    let (obs, excluded) = static_calibration(r);
    require_known(r, &obs)?;
    if obs.is_empty() {
        return Err(no_static(rec, &excluded));
    }
    let nz = noise(r);
    let selection = choose_among(&obs, &setting(r, &nz, frame), family, &r.positions)?;
    let basis = req.refine(&selection.basis)?;
    let oriented = match &provisional.orientation {
        Some(o) if o.fit.basis != basis => with_orientations(rec, Some(&basis))?,
        _ => provisional,
    };
    let r = &*oriented.rec;
    let (obs, _) = static_calibration(r);
    let fit = fit_joint(&obs, &basis, &setting(r, &nz, frame))?;
    Ok(FitOutcome {
        fit,
        stops: identify_stops(r).unwrap_or_default(),
        noise: nz,
        selection: Some(selection),
        excluded,
        orientation: oriented.orientation,
    })
}

fn no_static(rec: &Recording, ex: &Excluded) -> HostError {
    HostError::in_file(
        ErrorKind::Insufficient,
        &rec.path,
        format!(
            "no calibration dwell was taken in thermal equilibrium (temperature steady within {} C){}",
            crate::data::recording::MAX_DWELL_DRIFT_C,
            if ex.dwells > 0 {
                format!("; {}; --route joint uses them", ex.text())
            } else {
                String::new()
            }
        ),
    )
}

/// The stops' distinct temperatures, rounded to 0.01 C (the default breakpoints).
pub fn stop_temperatures(stops: &[StopCoeffs]) -> Vec<f64> {
    let temps: Vec<f64> = stops.iter().map(|s| s.temp_c).collect();
    rounded_clusters(&temps)
}

/// The distinct temperatures of observations, rounded to 0.01 C (the default
/// breakpoints of the static and joint routes).
fn obs_temperatures(obs: &[Obs]) -> Vec<f64> {
    let temps: Vec<f64> = obs.iter().map(|o| o.temp_c).collect();
    rounded_clusters(&temps)
}

fn rounded_clusters(temps: &[f64]) -> Vec<f64> {
    let mut b: Vec<f64> = temperature_clusters(temps)
        .iter()
        .map(|t| (t * 100.0).round() / 100.0)
        .collect();
    b.dedup();
    b
}

/// Fit a recording's calibration positions with the model given in `choice`, by
/// `how`; poses of unknown orientation are estimated first (with that model).
pub fn fit_recording(
    rec: &Recording,
    choice: &ModelChoice,
    how: Identification,
) -> Result<FitOutcome> {
    match how {
        Identification::PerStop => fit_per_stop(rec, choice),
        Identification::Static | Identification::Joint => fit_windows(rec, choice, how),
    }
}

fn fit_windows(rec: &Recording, choice: &ModelChoice, how: Identification) -> Result<FitOutcome> {
    let (obs0, _) = static_calibration(rec);
    let basis0 = choice.basis(&obs_temperatures(&obs0));
    let oriented = with_orientations(rec, Some(&basis0))?;
    let r = &*oriented.rec;
    let (obs, excluded) = match how {
        Identification::Joint => {
            let cal = |p: usize| r.positions.has_role(p, Role::Calibration);
            (observations(r, &cal, WINDOW_SPAN_C), Excluded::default())
        }
        Identification::Static | Identification::PerStop => static_calibration(r),
    };
    require_known(r, &obs)?;
    if obs.is_empty() {
        return Err(no_static(rec, &excluded));
    }
    // the default breakpoints are the static dwells' temperatures (the stops), also
    // on the joint route, whose ramp windows would make every 2 C a breakpoint
    let basis = if obs0.is_empty() {
        choice.basis(&obs_temperatures(&obs))
    } else {
        basis0
    };
    let nz = noise(r);
    let fit = fit_joint(&obs, &basis, &setting(r, &nz, oriented.frame()))?;
    Ok(FitOutcome {
        fit,
        stops: identify_stops(r).unwrap_or_default(),
        noise: nz,
        selection: None,
        excluded,
        orientation: oriented.orientation,
    })
}

fn fit_per_stop(rec: &Recording, choice: &ModelChoice) -> Result<FitOutcome> {
    let oriented = with_orientations(rec, None)?;
    let rec = &*oriented.rec;
    let st = identify_stops(rec)?;
    let basis = match choice.kind {
        ModelKind::Poly => choice.basis(&st.iter().map(|s| s.temp_c).collect::<Vec<_>>()),
        ModelKind::Pwl => choice.basis(&stop_temperatures(&st)),
    };
    let rows: Vec<TableRow> = st
        .iter()
        .map(|s| TableRow {
            temp_c: s.temp_c,
            coeffs: s.coeffs,
            stderr: Some(s.stderr),
        })
        .collect();
    let fit = fit_table(&rows, &basis, rec.t0_c).map_err(|e| e.within(&rec.path))?;
    Ok(FitOutcome {
        fit,
        stops: st,
        noise: noise(rec),
        selection: None,
        excluded: Excluded::default(),
        orientation: oriented.orientation,
    })
}
