//! Effects found together whose split the design pins only in part: a hysteresis beside
//! a rate or a lag on a test that shows no temperature from both directions at rest.
//! Their sum is measured; how it divides between them rests on the ramps alone, and a
//! flight (faster ramps, turns at any temperature) pays for a wrong division. Reported
//! with the correlation of their coefficients in the final joint fit (the joint
//! uncertainty, beside each finding's own 1-sigma) and the measurement that separates
//! them.
use crate::data::recording::MAX_DWELL_DRIFT_C;
use crate::diagnose::findings::{needed, Finding};
use crate::model::data::Data;
use crate::model::effects::EffectId;
use crate::model::params::{Param, Term};
use crate::model::solve::Fit;
use serde::Serialize;

/// Two effects of the findings whose split this recording pins only through its ramps.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Coupling {
    /// The two effects (the hysteresis first).
    pub effects: [EffectId; 2],
    /// Per axis (x, y, z): the correlation of the two effects' coefficients on that axis
    /// in the final joint fit; null where one of them has no coefficient there (a lag
    /// acts through the temperature slopes, by its time constant).
    pub correlation: [Option<f64>; 3],
    /// Why the design leaves their split to the ramps.
    pub why: String,
    /// The measurement that separates them.
    pub needed: String,
}

/// Temperatures of two static windows closer than this are one temperature here, C.
const SAME_TEMPERATURE_C: f64 = 2.0;

/// Whether some temperature is seen at rest (in a static dwell, one that drifts no
/// more than [`MAX_DWELL_DRIFT_C`]: the dwells at a stop, not the ramps) after heating
/// and after cooling.
fn seen_both_ways(data: &Data) -> bool {
    let r = &data.rules;
    let at_rest = |k: usize, sign: f64| {
        let static_dwell = data
            .rec
            .dwells
            .get(data.obs[k].dwell)
            .is_some_and(|d| d.temp_span_c <= MAX_DWELL_DRIFT_C);
        static_dwell
            && data
                .dir
                .get(k)
                .is_some_and(|d| d * sign > r.direction_majority)
    };
    let temps = |sign: f64| -> Vec<f64> {
        (0..data.obs.len())
            .filter(|&k| at_rest(k, sign))
            .map(|k| data.obs[k].temp_c)
            .collect()
    };
    let (heated, cooled) = (temps(1.0), temps(-1.0));
    heated
        .iter()
        .any(|h| cooled.iter().any(|c| (h - c).abs() < SAME_TEMPERATURE_C))
}

/// The correlation of the effect terms of extras `a` and `b` on each axis in `f`.
fn correlation(f: &Fit, a: usize, b: usize) -> [Option<f64>; 3] {
    let column = |e: usize, axis: usize| {
        f.labels.iter().position(|l| {
            matches!(l, Param::Effect { extra, axis: i, term } if *extra == e && *i == axis && *term != Term::Discovered)
        })
    };
    std::array::from_fn(|axis| {
        let (i, j) = (column(a, axis)?, column(b, axis)?);
        let c = f.cov.as_ref()?;
        let r = c[(i, j)] / (c[(i, i)] * c[(j, j)]).sqrt();
        r.is_finite().then_some(r)
    })
}

/// The couplings of `findings` in the final fit `f` of `data`: a hysteresis beside a
/// rate or a lag where no temperature is seen at rest from both directions (every stop
/// reached from one side: after the first turn the hysteresis is one constant in every
/// dwell, which the temperature model takes; the ramps, where the rate and the lag act,
/// are what is left to tell it from them).
pub fn coupled(data: &Data, f: &Fit, findings: &[Finding]) -> Vec<Coupling> {
    let has = |id: EffectId| findings.iter().any(|x| x.effect == id);
    if !has(EffectId::Hysteresis) || seen_both_ways(data) {
        return Vec::new();
    }
    let extra = |id: EffectId| f.spec.extras.iter().position(|e| e.id() == id);
    [EffectId::TempRate, EffectId::ThermalLag]
        .into_iter()
        .filter(|&id| has(id))
        .map(|id| {
            let pair = [EffectId::Hysteresis, id];
            Coupling {
                effects: pair,
                correlation: match (extra(pair[0]), extra(id)) {
                    (Some(a), Some(b)) => correlation(f, a, b),
                    _ => [None; 3],
                },
                why: format!(
                    "no temperature is seen at rest after heating and after cooling: the hysteresis is one constant in the dwells after the first turn, which the temperature model takes, and is told from {id} by the ramps alone"
                ),
                needed: needed(&pair),
            }
        })
        .collect()
}
