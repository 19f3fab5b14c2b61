//! Acceptance against a specification, judged on the verification dwells by formula
//! (13): |dg| within `t0_mg` where the dwell is within `t0_band_c` of T0, and within
//! `range_mg` elsewhere in the blob's valid range (the paper's: 3e-4 g at T0, 1e-3 g over
//! the range). Dwells outside the valid range are not judged (the blob does not claim
//! them) and are counted; with no dwell to judge there is no verdict.
use crate::error::{HostError, Result};
use crate::verify::Verification;
use serde::Serialize;

/// The specification.
#[derive(Debug, Clone, Copy, Serialize, PartialEq)]
pub struct Spec {
    /// Limit on |dg| within `t0_band_c` of T0, mg.
    pub t0_mg: f64,
    /// Limit on |dg| over the rest of the valid range, mg.
    pub range_mg: f64,
    /// Half-width of the band around T0, C.
    pub t0_band_c: f64,
}

impl Default for Spec {
    fn default() -> Self {
        Spec {
            t0_mg: 0.3,
            range_mg: 1.0,
            t0_band_c: 5.0,
        }
    }
}

impl Spec {
    /// A spec from the command line's limits, checked.
    pub fn new(t0_mg: f64, range_mg: f64) -> Result<Spec> {
        for (v, name) in [(t0_mg, "--accept-t0-mg"), (range_mg, "--accept-range-mg")] {
            if !(v.is_finite() && v > 0.0) {
                return Err(HostError::msg(format!(
                    "{name} must be a positive number of mg, got {v}"
                )));
            }
        }
        Ok(Spec {
            t0_mg,
            range_mg,
            ..Spec::default()
        })
    }

    /// One line: the limits.
    pub fn text(&self) -> String {
        format!(
            "{} mg within +-{} C of T0, {} mg over the valid range",
            self.t0_mg, self.t0_band_c, self.range_mg
        )
    }
}

/// Pass or fail.
#[derive(Debug, Clone, Copy, Serialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum Verdict {
    /// Every judged dwell within its limit.
    Pass,
    /// At least one over.
    Fail,
}

impl Verdict {
    /// `pass` or `fail`.
    pub fn name(self) -> &'static str {
        match self {
            Verdict::Pass => "pass",
            Verdict::Fail => "fail",
        }
    }
}

/// The judgement.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Acceptance {
    /// Pass or fail.
    pub acceptance: Verdict,
    /// Why, in one sentence.
    pub reason: String,
    /// The specification.
    pub spec: Spec,
    /// The worst |dg| within the band around T0, mg.
    pub worst_at_t0_mg: Option<f64>,
    /// The worst |dg| elsewhere in the valid range, mg.
    pub worst_over_range_mg: Option<f64>,
    /// Dwells judged.
    pub dwells_judged: usize,
    /// Dwells over their limit.
    pub dwells_failed: usize,
    /// Verification dwells outside the valid range, not judged.
    pub dwells_outside_range: usize,
}

/// Judge `v` (verification dwells compensated by a blob with reference `t0` and valid
/// range `range`); an error when no dwell lies in the valid range.
pub fn judge(v: &Verification, spec: &Spec, t0: f64, range: (f64, f64)) -> Result<Acceptance> {
    let (mut at_t0, mut over): (Option<f64>, Option<f64>) = (None, None);
    let (mut judged, mut failed, mut outside) = (0, 0, 0);
    let mut worst: Option<(f64, &str, f64, f64)> = None; // excess ratio, name, T, |dg|
    for d in &v.dwells {
        // a dwell's temperature is a mean of sensor readings: 0.05 C of slack at the
        // range's ends keeps a dwell at the last stop inside it
        if d.temp_c < range.0 - 0.05 || d.temp_c > range.1 + 0.05 {
            outside += 1;
            continue;
        }
        judged += 1;
        let g = d.dg_mg.abs();
        let near = (d.temp_c - t0).abs() <= spec.t0_band_c;
        let limit = if near { spec.t0_mg } else { spec.range_mg };
        let slot = if near { &mut at_t0 } else { &mut over };
        *slot = Some(slot.map_or(g, |w| w.max(g)));
        // a NaN |dg| (a non-finite compensation) is a failure, never a pass
        if g.is_nan() || g > limit {
            failed += 1;
        }
        let ratio = g / limit;
        if worst.is_none_or(|w| ratio > w.0 || ratio.is_nan()) {
            worst = Some((ratio, &d.position, d.temp_c, g));
        }
    }
    let Some((ratio, name, temp, g)) = worst else {
        return Err(HostError::msg(format!(
            "no verification dwell lies in the valid range {:.2}..{:.2} C ({outside} outside it): acceptance cannot be judged",
            range.0, range.1
        )));
    };
    let fmt = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.4} mg"));
    let outside_note = if outside > 0 {
        format!("; {outside} dwells outside the valid range not judged")
    } else {
        String::new()
    };
    let (acceptance, reason) = if failed == 0 {
        (
            Verdict::Pass,
            format!(
                "worst |dg| {} within +-{} C of T0 (limit {} mg), {} over {:.1}..{:.1} C (limit {} mg); {judged} verification dwells{outside_note}",
                fmt(at_t0),
                spec.t0_band_c,
                spec.t0_mg,
                fmt(over),
                range.0,
                range.1,
                spec.range_mg
            ),
        )
    } else {
        (
            Verdict::Fail,
            format!(
                "{failed} of {judged} verification dwells over the limit; worst {name} at {temp:.1} C: |dg| {g:.4} mg, {ratio:.1}x its limit{outside_note}"
            ),
        )
    };
    Ok(Acceptance {
        acceptance,
        reason,
        spec: *spec,
        worst_at_t0_mg: at_t0,
        worst_over_range_mg: over,
        dwells_judged: judged,
        dwells_failed: failed,
        dwells_outside_range: outside,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::verify::DwellCheck;

    fn v(dwells: &[(f64, f64)]) -> Verification {
        Verification {
            dwells: dwells
                .iter()
                .enumerate()
                .map(|(i, (t, dg))| DwellCheck {
                    position: format!("P{i}"),
                    temp_c: *t,
                    dg_mg_uncompensated: 9.0,
                    dg_mg: *dg,
                    samples: 60,
                    flagged: 0,
                })
                .collect(),
            max_by_temperature: Vec::new(),
        }
    }

    #[test]
    fn limits_by_band_range_and_nan() {
        let spec = Spec::default();
        let range = (-40.0, 70.0);
        // 0.29 mg at T0 + 4.9 C passes, 0.31 fails; 0.99 mg at -30 C passes
        let a = judge(&v(&[(24.9, 0.29), (-30.0, -0.99)]), &spec, 20.0, range).unwrap();
        assert_eq!(a.acceptance, Verdict::Pass, "{a:?}");
        assert_eq!(
            (a.worst_at_t0_mg, a.worst_over_range_mg),
            (Some(0.29), Some(0.99))
        );
        let a = judge(&v(&[(24.9, 0.31), (-30.0, 0.5)]), &spec, 20.0, range).unwrap();
        assert_eq!(a.acceptance, Verdict::Fail);
        assert!(
            a.reason.contains("P0") && a.reason.contains("24.9"),
            "{}",
            a.reason
        );
        // 0.5 mg 5.1 C from T0 is judged against the range's 1 mg
        let a = judge(&v(&[(25.1, 0.5)]), &spec, 20.0, range).unwrap();
        assert_eq!(a.acceptance, Verdict::Pass);
        // a NaN is never a pass
        let a = judge(&v(&[(20.0, f64::NAN), (21.0, 0.1)]), &spec, 20.0, range).unwrap();
        assert_eq!((a.acceptance, a.dwells_failed), (Verdict::Fail, 1));
    }

    #[test]
    fn outside_the_range_is_counted_not_judged_and_nothing_to_judge_is_an_error() {
        let spec = Spec::default();
        let a = judge(&v(&[(80.0, 5.0), (20.0, 0.1)]), &spec, 20.0, (-40.0, 70.0)).unwrap();
        assert_eq!(a.acceptance, Verdict::Pass);
        assert_eq!((a.dwells_judged, a.dwells_outside_range), (1, 1));
        assert!(a.reason.contains("1 dwells outside"), "{}", a.reason);
        let e = judge(&v(&[(80.0, 0.1)]), &spec, 20.0, (-40.0, 70.0)).unwrap_err();
        assert!(e.message.contains("cannot be judged"), "{e}");
        assert!(Spec::new(0.0, 1.0).is_err() && Spec::new(0.3, f64::NAN).is_err());
    }
}
