//! A finding of the diagnosis: the effect, where it is significant, its parameters with
//! uncertainties, and the evidence in one sentence; and the candidates the data cannot
//! tell apart, with the measurement that would.
use crate::diagnose::design::{Data, Extra, Fit};
use crate::diagnose::location::locate;
use crate::diagnose::metrics::{max_dg, normalized_rms, residual_rms};
use crate::diagnose::params::{Param, Term};
use firmware_core::model::AXES;
use serde::Serialize;
use std::collections::BTreeMap;

/// A finding of the JSON contract.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Finding {
    /// Catalogue id.
    pub effect: String,
    /// Axes where the effect is significant.
    pub axes: Vec<String>,
    /// Parameters.
    pub parameters: BTreeMap<String, f64>,
    /// 1-sigma uncertainties.
    pub uncertainties: BTreeMap<String, f64>,
    /// BIC change when added.
    pub delta_bic: f64,
    /// Residual RMS after adding it.
    pub residual_rms_after: f64,
    /// max |dg| after adding it, mg.
    pub max_abs_dg_mg_after: f64,
    /// One sentence.
    pub evidence: String,
    /// The position, for fixture_error.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub position: Option<String>,
}

/// Two or more candidates the data cannot separate.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Ambiguity {
    /// Catalogue ids.
    pub candidates: Vec<String>,
    /// The measurement that separates them.
    pub needed: String,
}

/// The finding of the effect `f` added to `prev` (lowering BIC by `-d`).
pub fn finding(data: &Data, f: &Fit, prev: &Fit, d: f64, evidence: String) -> Finding {
    let e = f.spec.extras.last().cloned().unwrap_or(Extra::Rate);
    let dof = (3 * data.obs.len()).saturating_sub(f.k).max(1) as f64;
    let scale = (f.chi2 / dof).max(1.0).sqrt();
    let mut parameters = BTreeMap::new();
    let mut unc = BTreeMap::new();
    let mut axes: Vec<String> = Vec::new();
    for j in prev.k..f.k {
        let label = f.labels[j];
        let mut v = f.x[j];
        let mut s = f.cov[(j, j)].max(0.0).sqrt() * scale;
        let name = match label {
            Param::Effect {
                term: Term::Asymmetry,
                axis,
            } => {
                // c_i = K_ii delta_i: report delta_i, relative
                let kii = f.k_at.first().map(|k| k[axis][axis]).unwrap_or(1.0);
                v /= kii;
                s /= kii.abs();
                format!("delta_{}", AXES[axis])
            }
            _ => label.to_string(),
        };
        parameters.insert(name.clone(), v);
        unc.insert(name, s);
        if let Some(axis) = label.effect_axis() {
            let ax = AXES[axis].to_string();
            if v.abs() > 3.0 * s && !axes.contains(&ax) {
                axes.push(ax);
            }
        }
    }
    let all_axes = || AXES.iter().map(|a| a.to_string()).collect::<Vec<_>>();
    let mut position = None;
    match &e {
        Extra::Lag(tau) | Extra::Warmup(tau) => {
            parameters.insert("tau_s".into(), *tau);
            unc.insert("tau_s".into(), tau_sigma(data, f, prev, *tau) * scale);
            if matches!(e, Extra::Lag(_)) {
                axes = all_axes();
            }
        }
        Extra::Curvature(b) => {
            parameters.insert("breakpoints".into(), b.len() as f64);
            unc.insert("breakpoints".into(), 0.0);
            axes = all_axes();
        }
        Extra::Fixture(p) => {
            position = Some(data.rec.positions.name(*p).to_string());
            axes = all_axes();
        }
        _ => {}
    }
    Finding {
        effect: e.id().into(),
        axes,
        parameters,
        uncertainties: unc,
        delta_bic: d,
        residual_rms_after: residual_rms(f),
        max_abs_dg_mg_after: max_dg(data, f),
        evidence,
        position,
    }
}

/// 1-sigma of a profiled time constant: where chi2 rises by 1 (parabola in tau).
fn tau_sigma(data: &Data, f: &Fit, base: &Fit, tau: f64) -> f64 {
    let at = |t: f64| -> f64 {
        let mut s = f.spec.clone();
        if let Some(last) = s.extras.last_mut() {
            *last = match last {
                Extra::Lag(_) => Extra::Lag(t),
                _ => Extra::Warmup(t),
            };
        }
        data.fit(&s, Some(base))
            .map(|g| g.chi2)
            .unwrap_or(f64::INFINITY)
    };
    let h = 0.05;
    let (c0, cp, cm) = (f.chi2, at(tau * (1.0 + h)), at(tau * (1.0 - h)));
    let curv = (cp + cm - 2.0 * c0) / (h * tau).powi(2);
    if curv > 0.0 {
        (2.0 / curv).sqrt()
    } else {
        f64::INFINITY
    }
}

/// The evidence sentence of effect `id` found by going from `before` to `after`.
pub fn evidence_for(data: &Data, before: &Fit, after: &Fit, id: &str, d: f64) -> String {
    let rb = normalized_rms(data, before);
    let ra = normalized_rms(data, after);
    let top = locate(data, before)
        .into_iter()
        .take(2)
        .map(|h| format!("{} axis in {} {}", h.axis, h.group, h.value))
        .collect::<Vec<_>>()
        .join(" and ");
    let why = match id {
        "thermal_lag" => "the residual follows the temperature changes and scales with each coefficient's temperature slope, as a lagging element temperature does",
        "temp_rate" => "the offset residual is proportional to dT/dt, not to any coefficient's temperature slope",
        "hysteresis" => "the same temperature reached by heating and by cooling gives different offsets",
        "nonlinearity_k2" => "the mid-point of the +1 g and -1 g readings differs from the 0 g readings and grows as a_i^2 in tilted positions",
        "scale_asymmetry" => "the mid-point of the +1 g and -1 g readings differs from the 0 g readings and grows as |a_i| in tilted positions",
        "fixture_error" => "one position disagrees with all others at every temperature",
        "warmup_drift" => "the offset residual decays with time since power-on or handling, independent of temperature",
        "temp_curvature" => "the coefficients bend between the temperatures more than the best polynomial the data support",
        _ => "",
    };
    format!(
        "Baseline residual {rb:.1}x noise, largest on {}; {why}; modelling it lowers BIC by {:.0} and the residual to {ra:.1}x noise.",
        if top.is_empty() { "no group".to_string() } else { top },
        -d
    )
}

/// The measurement that would separate candidates `a` and `b`.
pub fn needed(a: &str, b: &str) -> String {
    let pair = |x: &str, y: &str| (a == x && b == y) || (a == y && b == x);
    if pair("nonlinearity_k2", "scale_asymmetry") {
        "tilted positions (e.g. PP1..PP6) where a_i^2 and |a_i| differ".into()
    } else if pair("thermal_lag", "temp_rate") {
        "a soak after a ramp long enough to watch the error decay (lag) or vanish with dT/dt (rate), or ramps at two rates".into()
    } else if pair("hysteresis", "thermal_lag") || pair("hysteresis", "temp_rate") {
        "a temperature visited from both directions after a long soak".into()
    } else if pair("warmup_drift", "thermal_lag") || pair("warmup_drift", "temp_rate") {
        "a power cycle or handling at a steady temperature, away from any temperature change".into()
    } else {
        format!(
            "data that changes {a} and {b} differently (other positions, temperatures or timing)"
        )
    }
}
