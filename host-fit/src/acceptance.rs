//! Acceptance against a specification, judged on the verification dwells by formula
//! (13): |dg| within `t0_mg` where the dwell is within `t0_band_c` of T0 (the band near
//! T0), and within `range_mg` elsewhere in the blob's valid range (the band over the
//! range; the paper's: 3e-4 g at T0, 1e-3 g over the range).
//!
//! The verdict, in this order: `fail` when a judged dwell is over its limit (or not
//! finite); `fail` when a verification dwell lies outside the blob's valid range (the
//! unit was tested where its blob claims nothing), unless [`OutsideRange::Report`] asks
//! for such dwells to be reported apart; `not_judged` when a band of the specification
//! has no judged dwell (the band near T0 always; the band over the range when the
//! valid range reaches beyond T0 +- `t0_band_c`): what was not judged cannot pass;
//! `pass` otherwise.
use crate::error::{ErrorKind, HostError, Result};
use crate::verify::Verification;
use serde::Serialize;

/// What becomes of verification dwells outside the blob's valid range.
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    Serialize,
    Default,
    strum::Display,
    strum::EnumString,
    strum::IntoStaticStr,
    strum::EnumIter,
)]
#[serde(into = "&'static str")]
#[strum(serialize_all = "lowercase")]
pub enum OutsideRange {
    /// They make the verdict `fail`: the unit was tested where its blob claims nothing.
    #[default]
    Fail,
    /// They are counted and their worst |dg| reported apart; the verdict is the judged
    /// dwells' (and a band they leave empty is not judged).
    Report,
}

/// The specification.
#[derive(Debug, Clone, Copy, Serialize, PartialEq)]
pub struct Spec {
    /// Limit on |dg| within `t0_band_c` of T0, mg.
    pub t0_mg: f64,
    /// Limit on |dg| over the rest of the valid range, mg.
    pub range_mg: f64,
    /// Half-width of the band around T0, C.
    pub t0_band_c: f64,
    /// Verification dwells outside the blob's valid range.
    pub outside_range: OutsideRange,
}

impl Default for Spec {
    fn default() -> Self {
        Spec {
            t0_mg: 0.3,
            range_mg: 1.0,
            t0_band_c: 5.0,
            outside_range: OutsideRange::Fail,
        }
    }
}

impl Spec {
    /// A spec from the command line's limits, checked.
    pub fn new(t0_mg: f64, range_mg: f64) -> Result<Spec> {
        for (v, name) in [(t0_mg, "--accept-t0-mg"), (range_mg, "--accept-range-mg")] {
            if !(v.is_finite() && v > 0.0) {
                return Err(HostError::new(
                    ErrorKind::Invalid,
                    format!("{name} must be a positive number of mg, got {v}"),
                ));
            }
        }
        Ok(Spec {
            t0_mg,
            range_mg,
            ..Spec::default()
        })
    }

    /// The same with `outside` for the dwells outside the valid range.
    pub fn with_outside_range(self, outside: OutsideRange) -> Spec {
        Spec {
            outside_range: outside,
            ..self
        }
    }

    /// One line: the limits.
    pub fn text(&self) -> String {
        format!(
            "{} mg within +-{} C of T0, {} mg over the valid range",
            self.t0_mg, self.t0_band_c, self.range_mg
        )
    }
}

/// The verdict.
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    Serialize,
    strum::Display,
    strum::EnumString,
    strum::IntoStaticStr,
    strum::EnumIter,
)]
#[serde(into = "&'static str")]
#[strum(serialize_all = "snake_case")]
pub enum Verdict {
    /// Every band judged, every judged dwell within its limit, none outside the valid
    /// range (or those reported apart).
    Pass,
    /// A judged dwell over its limit, or (by default) a dwell outside the valid range.
    Fail,
    /// No judged dwell in a band of the specification: it cannot pass what it did not
    /// judge.
    NotJudged,
}

impl Verdict {
    /// `pass`, `fail` or `not_judged`.
    pub fn name(self) -> &'static str {
        self.into()
    }
}

/// A band of the specification.
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    Serialize,
    strum::Display,
    strum::EnumString,
    strum::IntoStaticStr,
    strum::EnumIter,
)]
#[serde(into = "&'static str")]
#[strum(serialize_all = "snake_case")]
pub enum Band {
    /// Within `t0_band_c` of T0.
    NearT0,
    /// The rest of the valid range.
    OverRange,
}

impl Band {
    /// In words, for a reason.
    fn text(self, spec: &Spec, range: (f64, f64)) -> String {
        match self {
            Band::NearT0 => format!("within +-{} C of T0", spec.t0_band_c),
            Band::OverRange => format!(
                "over the rest of the valid range {:.1}..{:.1} C",
                range.0, range.1
            ),
        }
    }
}

/// The judgement.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Acceptance {
    /// Pass, fail or not judged.
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
    /// Verification dwells outside the valid range (a failure, or reported apart).
    pub dwells_outside_range: usize,
    /// The worst |dg| of the dwells outside the valid range, mg.
    pub worst_outside_range_mg: Option<f64>,
    /// The bands of the specification with no judged dwell.
    pub bands_not_judged: Vec<Band>,
}

/// What the dwells of a verification came to, before the verdict.
#[derive(Default)]
struct Tally<'v> {
    at_t0: Option<f64>,
    over: Option<f64>,
    judged: usize,
    failed: usize,
    /// Outside the range: count, worst |dg|, coldest and hottest temperature.
    outside: (usize, Option<f64>, f64, f64),
    /// The judged dwell furthest over its limit: excess ratio, name, T, |dg|.
    worst: Option<(f64, &'v str, f64, f64)>,
}

fn tally<'v>(v: &'v Verification, spec: &Spec, t0: f64, range: (f64, f64)) -> Tally<'v> {
    let mut t = Tally {
        outside: (0, None, f64::INFINITY, f64::NEG_INFINITY),
        ..Tally::default()
    };
    for d in &v.dwells {
        let g = d.dg_mg.abs();
        // a dwell's temperature is a mean of sensor readings: 0.05 C of slack at the
        // range's ends keeps a dwell at the last stop inside it
        if d.temp_c < range.0 - 0.05 || d.temp_c > range.1 + 0.05 {
            let o = &mut t.outside;
            o.0 += 1;
            o.1 = Some(o.1.map_or(g, |w: f64| if g.is_nan() { g } else { w.max(g) }));
            (o.2, o.3) = (o.2.min(d.temp_c), o.3.max(d.temp_c));
            continue;
        }
        t.judged += 1;
        let near = (d.temp_c - t0).abs() <= spec.t0_band_c;
        let limit = if near { spec.t0_mg } else { spec.range_mg };
        let slot = if near { &mut t.at_t0 } else { &mut t.over };
        *slot = Some(slot.map_or(g, |w| w.max(g)));
        // a NaN |dg| (a non-finite compensation) is a failure, never a pass
        if g.is_nan() || g > limit {
            t.failed += 1;
        }
        let ratio = g / limit;
        if t.worst.is_none_or(|w| ratio > w.0 || ratio.is_nan()) {
            t.worst = Some((ratio, &d.position, d.temp_c, g));
        }
    }
    t
}

/// The bands of `spec` a blob with reference `t0` and valid range `range` claims: the
/// band near T0 always (the specification's first limit), the band over the range when
/// the range reaches beyond it.
fn claimed(spec: &Spec, t0: f64, range: (f64, f64)) -> Vec<Band> {
    let mut b = vec![Band::NearT0];
    if range.0 < t0 - spec.t0_band_c || range.1 > t0 + spec.t0_band_c {
        b.push(Band::OverRange);
    }
    b
}

/// Judge `v` (verification dwells compensated by a blob with reference `t0` and valid
/// range `range`) against `spec` (see the module doc for the rule).
pub fn judge(v: &Verification, spec: &Spec, t0: f64, range: (f64, f64)) -> Acceptance {
    let t = tally(v, spec, t0, range);
    let bands_not_judged: Vec<Band> = claimed(spec, t0, range)
        .into_iter()
        .filter(|b| match b {
            Band::NearT0 => t.at_t0.is_none(),
            Band::OverRange => t.over.is_none(),
        })
        .collect();
    let fmt = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.4} mg"));
    let (n_out, worst_out, cold, hot) = t.outside;
    let outside_text = format!(
        "{n_out} verification dwells outside the valid range {:.1}..{:.1} C (at {cold:.1}..{hot:.1} C, worst |dg| {})",
        range.0,
        range.1,
        fmt(worst_out)
    );
    let not_judged_text = bands_not_judged
        .iter()
        .map(|b| b.text(spec, range))
        .collect::<Vec<_>>()
        .join(" and ");
    let (acceptance, reason) = if let (true, Some((ratio, name, temp, g))) = (t.failed > 0, t.worst)
    {
        let mut r = format!(
            "{} of {} verification dwells over the limit; worst {name} at {temp:.1} C: |dg| {g:.4} mg, {ratio:.1}x its limit",
            t.failed, t.judged
        );
        if n_out > 0 {
            r.push_str(&format!("; {outside_text}"));
        }
        (Verdict::Fail, r)
    } else if n_out > 0 && spec.outside_range == OutsideRange::Fail {
        (
            Verdict::Fail,
            format!(
                "{outside_text}: the blob claims nothing there (`--outside-range report` reports them apart); {} dwells judged",
                t.judged
            ),
        )
    } else if !bands_not_judged.is_empty() {
        let apart = if n_out > 0 {
            format!("; {outside_text}, reported apart")
        } else {
            String::new()
        };
        (
            Verdict::NotJudged,
            format!(
                "no verification dwell judged {not_judged_text} (none lies there inside the valid range): not judged there, so no pass ({} dwells judged){apart}",
                t.judged
            ),
        )
    } else {
        let apart = if n_out > 0 {
            format!("; {outside_text}, reported apart")
        } else {
            String::new()
        };
        (
            Verdict::Pass,
            format!(
                "worst |dg| {} within +-{} C of T0 (limit {} mg), {} over {:.1}..{:.1} C (limit {} mg); {} verification dwells{apart}",
                fmt(t.at_t0),
                spec.t0_band_c,
                spec.t0_mg,
                fmt(t.over),
                range.0,
                range.1,
                spec.range_mg,
                t.judged
            ),
        )
    };
    Acceptance {
        acceptance,
        reason,
        spec: *spec,
        worst_at_t0_mg: t.at_t0,
        worst_over_range_mg: t.over,
        dwells_judged: t.judged,
        dwells_failed: t.failed,
        dwells_outside_range: n_out,
        worst_outside_range_mg: worst_out,
        bands_not_judged,
    }
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
        let a = judge(&v(&[(24.9, 0.29), (-30.0, -0.99)]), &spec, 20.0, range);
        assert_eq!(a.acceptance, Verdict::Pass, "{a:?}");
        assert_eq!(
            (a.worst_at_t0_mg, a.worst_over_range_mg),
            (Some(0.29), Some(0.99))
        );
        let a = judge(&v(&[(24.9, 0.31), (-30.0, 0.5)]), &spec, 20.0, range);
        assert_eq!(a.acceptance, Verdict::Fail);
        assert!(
            a.reason.contains("P0") && a.reason.contains("24.9"),
            "{}",
            a.reason
        );
        // 0.5 mg 5.1 C from T0 is judged against the range's 1 mg
        let a = judge(&v(&[(25.1, 0.5), (20.0, 0.1)]), &spec, 20.0, range);
        assert_eq!(a.acceptance, Verdict::Pass);
        // a NaN is never a pass
        let a = judge(&v(&[(20.0, f64::NAN), (-21.0, 0.1)]), &spec, 20.0, range);
        assert_eq!((a.acceptance, a.dwells_failed), (Verdict::Fail, 1));
    }

    #[test]
    fn outside_the_range_fails_or_is_reported_apart() {
        let spec = Spec::default();
        let dwells = v(&[(80.0, 5.0), (20.0, 0.1), (-30.0, 0.2)]);
        let a = judge(&dwells, &spec, 20.0, (-40.0, 70.0));
        assert_eq!(a.acceptance, Verdict::Fail, "{a:?}");
        assert_eq!((a.dwells_judged, a.dwells_outside_range), (2, 1));
        assert_eq!(a.worst_outside_range_mg, Some(5.0));
        assert!(
            a.reason.starts_with("1 verification dwells outside the valid range -40.0..70.0 C (at 80.0..80.0 C, worst |dg| 5.0000 mg)"),
            "{}",
            a.reason
        );
        let report = spec.with_outside_range(OutsideRange::Report);
        let a = judge(&dwells, &report, 20.0, (-40.0, 70.0));
        assert_eq!(a.acceptance, Verdict::Pass, "{a:?}");
        assert!(a.reason.ends_with("reported apart"), "{}", a.reason);
        // a failure inside the range is a failure whatever the option
        let a = judge(
            &v(&[(80.0, 0.1), (20.0, 0.4), (-30.0, 0.2)]),
            &report,
            20.0,
            (-40.0, 70.0),
        );
        assert_eq!(a.acceptance, Verdict::Fail);
        assert!(Spec::new(0.0, 1.0).is_err() && Spec::new(0.3, f64::NAN).is_err());
    }

    #[test]
    fn a_band_without_a_judged_dwell_is_not_judged_never_a_pass() {
        let spec = Spec::default().with_outside_range(OutsideRange::Report);
        // a blob of one stop far from T0: nothing near T0 is judged
        let one_stop = (-30.5, -28.0);
        let a = judge(&v(&[(-29.5, 0.01), (24.7, 9.8)]), &spec, 25.0, one_stop);
        assert_eq!(a.acceptance, Verdict::NotJudged, "{a:?}");
        assert_eq!(a.bands_not_judged, vec![Band::NearT0]);
        assert!(
            a.reason
                .starts_with("no verification dwell judged within +-5 C of T0"),
            "{}",
            a.reason
        );
        // by default the dwell at 24.7 C outside the range fails it
        let a = judge(
            &v(&[(-29.5, 0.01), (24.7, 9.8)]),
            &Spec::default(),
            25.0,
            one_stop,
        );
        assert_eq!(a.acceptance, Verdict::Fail);
        // a range beyond the band near T0 with dwells only near T0: the range not judged
        let a = judge(&v(&[(20.0, 0.01)]), &spec, 20.0, (-40.0, 70.0));
        assert_eq!(a.bands_not_judged, vec![Band::OverRange]);
        assert_eq!(a.acceptance, Verdict::NotJudged);
        // a range within the band near T0 claims only that band
        let a = judge(&v(&[(20.5, 0.01)]), &spec, 20.0, (19.0, 22.0));
        assert_eq!(a.acceptance, Verdict::Pass, "{a:?}");
        // nothing at all to judge
        let a = judge(&v(&[]), &spec, 20.0, (19.0, 22.0));
        assert_eq!((a.acceptance, a.dwells_judged), (Verdict::NotJudged, 0));
    }
}
