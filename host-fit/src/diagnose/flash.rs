//! The model the blob carries: the final one in the forms the firmware applies (one lag
//! pole for all axes, hysteresis of the offsets, one warm-up since power-on, a rate
//! estimator smoothing for flight), refitted in those forms where the diagnosis found
//! another, so the blob carries exactly a model that was fitted.
use crate::diagnose::design::{Data, Fit};
use crate::diagnose::effects::Extra;
use crate::diagnose::profile::time_constant;

/// The rate estimator's time constant the blob carries at most, s: chosen for flight, not
/// for the chamber (`r` is refitted with it). `r` is the unit's physics, an offset per C/s
/// of its temperature's rate; the estimator only measures that rate. The one that fits a
/// chamber recording best smooths its 10-s rows of a quantised sensor over tens of
/// seconds, which in flight lags a fast change by as much (the twin's flight, warming and
/// cooling at 5-8 C/min: 0.44 mg at the chamber's 40 s, 0.045 mg at 2 s). The price is
/// noise: the mean of the estimate over a held attitude of D seconds is the change of its
/// low-pass over the hold over D, whose noise is about sigma sqrt(h / tau) / D (sigma the
/// sensor's 0.027 C, h the 0.1 s step: 1.5e-4 C/s over 40 s at 2 s, times `r`); each
/// sample's, about sigma h / tau / h = sigma / tau (0.013 C/s at 2 s, 0.0007 C/s at 40 s).
pub const FLIGHT_RATE_TAU_S: f64 = 2.0;

/// `f` with its rate estimator at [`FLIGHT_RATE_TAU_S`] at most, `r` refitted with it
/// (`f` itself without a rate term, or when the refit is not determined).
fn rate_for_flight(data: &Data, f: Fit) -> Fit {
    let at = f
        .spec
        .extras
        .iter()
        .position(|e| matches!(e, Extra::Rate { tau_s } if *tau_s > FLIGHT_RATE_TAU_S));
    let Some(i) = at else {
        return f;
    };
    let mut spec = f.spec.clone();
    spec.extras[i] = Extra::Rate {
        tau_s: FLIGHT_RATE_TAU_S,
    };
    data.fit(&spec, None, true).unwrap_or(f)
}

/// `f` in the firmware's forms, refitted (a single lag pole profiled again) where it
/// differs, its rate estimator for flight ([`FLIGHT_RATE_TAU_S`]); `f` itself when it is
/// already flashable or a refit is not determined.
pub fn flashable(data: &Data, f: &Fit) -> Fit {
    rate_for_flight(data, firmware_forms(data, f))
}

/// `f` in the firmware's forms, the rate estimator aside (see [`flashable`]).
fn firmware_forms(data: &Data, f: &Fit) -> Fit {
    let mut spec = f.spec.clone();
    let mut changed = false;
    let mut warmups = 0;
    spec.extras.retain(|e| match e {
        Extra::Warmup { .. } => {
            warmups += 1;
            changed |= warmups > 1;
            warmups == 1
        }
        _ => true,
    });
    let mut lag_at = None;
    for (i, e) in spec.extras.iter_mut().enumerate() {
        match e {
            Extra::Hysteresis { scale, .. } if *scale => {
                *scale = false;
                changed = true;
            }
            Extra::Lag { taus } if taus.iter().any(|t| *t != taus[0] || t[1] > 0.0) => {
                lag_at = Some((i, taus.iter().map(|t| t[0] + t[1]).sum::<f64>() / 3.0));
                changed = true;
            }
            _ => {}
        }
    }
    if !changed {
        return f.clone();
    }
    if let Some((i, tau)) = lag_at {
        let make = |t: f64| {
            let mut s = spec.clone();
            s.extras[i] = Extra::Lag {
                taus: [[t, 0.0]; 3],
            };
            data.fit(&s, None, false)
        };
        if let Some((t, _)) = time_constant(&make, tau / 1.7f64.powi(3), 7) {
            spec.extras[i] = Extra::Lag {
                taus: [[t, 0.0]; 3],
            };
        }
    }
    data.fit(&spec, None, true).unwrap_or_else(|| f.clone())
}
