//! Which data are static: the equilibrium rule of the default fit. A dwell whose
//! temperature moves more than the recording format's drift limit (0.5 C) was taken
//! while the unit was not in thermal equilibrium (the rest position through a ramp and
//! its soak, a hand-held pose while the unit warms): its readings carry the unit's
//! dynamics (lag, gradients, settling), which the static coefficients do not model, and
//! its many samples would outweigh the stops. Such dwells are left out of the static
//! fit; `--route joint` takes them in on request.
use crate::data::recording::{Recording, MAX_DWELL_DRIFT_C};
use crate::fit::identify::{observations, Obs};
use serde::Serialize;

/// What the rule left out.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct Excluded {
    /// Dwells whose temperature spans more than [`MAX_DWELL_DRIFT_C`].
    pub dwells: usize,
    /// Their samples.
    pub samples: usize,
    /// The largest of their temperature spans, C.
    pub max_span_c: f64,
    /// Dwells the rule looked at (the selected positions').
    pub of_dwells: usize,
}

impl Excluded {
    /// One line for the user, empty when nothing was left out.
    pub fn text(&self) -> String {
        if self.dwells == 0 {
            return String::new();
        }
        let mut s = format!(
            "{} of {} calibration dwells ({} samples) moved more than {MAX_DWELL_DRIFT_C} C in temperature (up to {:.1} C: ramps, settling) and were left out of the static fit",
            self.dwells, self.of_dwells, self.samples, self.max_span_c
        );
        if 2 * self.dwells > self.of_dwells {
            s.push_str(": most of the recording was not in thermal equilibrium; lengthen the soaks, or fit the ramps with --route joint (their dynamics unmodelled)");
        }
        s
    }
}

/// Whether dwell `d` of `rec` was taken in thermal equilibrium.
pub fn is_static(rec: &Recording, d: usize) -> bool {
    rec.dwells
        .get(d)
        .is_some_and(|d| d.temp_span_c <= MAX_DWELL_DRIFT_C)
}

/// The static observations of the positions `select` accepts (windows of at most
/// `span_c`, each at its own temperature), and what was left out.
pub fn static_observations(
    rec: &Recording,
    select: &dyn Fn(usize) -> bool,
    span_c: f64,
) -> (Vec<Obs>, Excluded) {
    let mut ex = Excluded::default();
    for (i, d) in rec.dwells.iter().enumerate() {
        if select(d.position) {
            ex.of_dwells += 1;
        }
        if select(d.position) && !is_static(rec, i) {
            ex.dwells += 1;
            ex.samples += d.len();
            ex.max_span_c = ex.max_span_c.max(d.temp_span_c);
        }
    }
    let obs = observations(rec, select, span_c)
        .into_iter()
        .filter(|o| is_static(rec, o.dwell))
        .collect();
    (obs, ex)
}
