//! The fit pipeline: a recording's calibration dwells -> per-stop identification ->
//! temperature model, by the joint route (every window at its own temperature) or the
//! paper's per-stop route.
use crate::data::positions::Role;
use crate::data::recording::Recording;
use crate::data::table::TableRow;
use crate::error::{HostError, Result};
use crate::fit::identify::{identify_stop, observations, stops, StopCoeffs};
use crate::fit::noise::noise;
use crate::fit::temperature::{fit_joint, fit_table, temperature_clusters, Basis, ModelFit};

/// Temperature model kind.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum ModelKind {
    /// Piecewise-linear through breakpoints.
    Pwl,
    /// Polynomial of dT.
    Poly,
}

/// Identification route.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Route {
    /// All dwells at once, each (window) at its own temperature.
    Joint,
    /// The paper's route: formula (10) per stop, then a fit across stops.
    PerStop,
}

impl Route {
    /// The name used in outputs.
    pub fn name(self) -> &'static str {
        match self {
            Route::Joint => "joint",
            Route::PerStop => "per-stop",
        }
    }
}

/// The temperature model asked for.
#[derive(Clone, Debug, PartialEq)]
pub struct ModelChoice {
    /// Family.
    pub kind: ModelKind,
    /// Polynomial order (default: 3, or less with fewer temperatures).
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
                    .unwrap_or_else(|| 3.min(temps.len().saturating_sub(1)).max(1)),
            },
            ModelKind::Pwl => Basis::Pwl {
                breakpoints: self.breakpoints.clone().unwrap_or_else(|| temps.to_vec()),
            },
        }
    }
}

/// Per-stop identification of the calibration positions.
pub fn identify_stops(rec: &Recording) -> Result<Vec<StopCoeffs>> {
    let nz = noise(rec);
    let cal = |p: usize| rec.positions.has_role(p, Role::Calibration);
    let st = stops(rec, &cal, 3.0);
    if st.is_empty() {
        return Err(HostError::in_file(
            &rec.path,
            "no static calibration dwells (temperature steady within 0.5 C) in the fit positions",
        ));
    }
    st.iter().map(|s| identify_stop(rec, s, &nz)).collect()
}

/// What a fit decided and measured.
pub struct FitOutcome {
    /// The fitted model.
    pub fit: ModelFit,
    /// Per-stop identification (for the report and the paper comparison).
    pub stops: Vec<StopCoeffs>,
}

/// The stops' distinct temperatures, rounded to 0.01 C (the default breakpoints).
pub fn stop_temperatures(stops: &[StopCoeffs]) -> Vec<f64> {
    let temps: Vec<f64> = stops.iter().map(|s| s.temp_c).collect();
    let mut b: Vec<f64> = temperature_clusters(&temps)
        .iter()
        .map(|t| (t * 100.0).round() / 100.0)
        .collect();
    b.dedup();
    b
}

/// Fit a recording's calibration positions: the joint route by default, the per-stop
/// route on request.
pub fn fit_recording(rec: &Recording, choice: &ModelChoice, route: Route) -> Result<FitOutcome> {
    let st = identify_stops(rec)?;
    let basis = match choice.kind {
        ModelKind::Poly => choice.basis(&st.iter().map(|s| s.temp_c).collect::<Vec<_>>()),
        ModelKind::Pwl => choice.basis(&stop_temperatures(&st)),
    };
    let fit = match route {
        Route::Joint => {
            let cal = |p: usize| rec.positions.has_role(p, Role::Calibration);
            let obs = observations(rec, &cal, 0.25);
            fit_joint(&obs, &noise(rec), &basis, rec.t0_c, &rec.path)?
        }
        Route::PerStop => {
            let rows: Vec<TableRow> = st
                .iter()
                .map(|s| TableRow {
                    temp_c: s.temp_c,
                    coeffs: s.coeffs,
                    stderr: Some(s.stderr),
                })
                .collect();
            fit_table(&rows, &basis, rec.t0_c)
                .map_err(|e| HostError::in_file(&rec.path, e.message))?
        }
    };
    Ok(FitOutcome { fit, stops: st })
}
