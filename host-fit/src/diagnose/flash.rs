//! The model the blob carries: the final one in the forms the firmware applies (one lag
//! pole for all axes, hysteresis of the offsets, one warm-up since power-on), refitted in
//! those forms where the diagnosis found a richer one, so the blob carries exactly a model
//! that was fitted.
use crate::diagnose::design::{Data, Fit};
use crate::diagnose::effects::Extra;
use crate::diagnose::profile::time_constant;

/// `f` in the firmware's forms, refitted (a single lag pole profiled again) where it
/// differs; `f` itself when it is already flashable or a refit is not determined.
pub fn flashable(data: &Data, f: &Fit) -> Fit {
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
