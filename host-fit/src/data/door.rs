//! The checks at the door: a recording's numbers judged against the units it states (the
//! outputs' change per g, the temperatures' scale) and its temperatures against what its
//! test promised (its own T0, a test cut off on its way to the next stop), before anything
//! is fitted; each finding says in words what is wrong and what to do.
//!
//! Version 1 of the format has no field that states a test's range, so "promised" is
//! what the recording itself says: its reference temperature `t0_c` (default 20 C: the
//! model is expanded about it and the acceptance judges +-[`T0_BAND_C`] about it apart),
//! and the path of its temperature (a test that ends still ramping away from where it
//! began was cut off before its next stop). A production blob of such data is refused;
//! a study of them (`identify`, `diagnose`, `report`) warns.
use crate::data::output_unit::OutputUnit;
use crate::data::positions::Role;
use crate::data::recording::{Dwell, Recording, MAX_DWELL_DRIFT_C};
use crate::error::{ErrorKind, HostError, Result};
use std::fmt::Write as _;

/// A check at the door that data may legitimately fail, and be let past (`--allow`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Check {
    /// The outputs' change per g is implausible for their stated unit.
    OutputScale,
    /// The temperatures look like Kelvin or Fahrenheit.
    TemperatureScale,
    /// The recording covers less than its test promised.
    Partial,
}

impl Check {
    /// Every check.
    pub const ALL: [Check; 3] = [Check::OutputScale, Check::TemperatureScale, Check::Partial];

    /// Its name on the command line (`--allow NAME`).
    pub fn name(self) -> &'static str {
        match self {
            Check::OutputScale => "output-scale",
            Check::TemperatureScale => "temperature-scale",
            Check::Partial => "partial",
        }
    }
}

/// What a check found.
#[derive(Debug, Clone, PartialEq)]
pub struct Finding {
    /// The check.
    pub check: Check,
    /// The line of the file it concerns, when one does.
    pub line: Option<usize>,
    /// The field it concerns.
    pub field: &'static str,
    /// What is wrong and what to do (without the file's name).
    pub message: String,
}

/// The acceptance judges the band of +-this about T0 apart (C): data within it of T0
/// give that band dwells.
pub const T0_BAND_C: f64 = 5.0;

/// Above this (C) a reading is beyond the widest rating of an accelerometer (125 C) by
/// a margin: a recording that reaches it is suspected of another scale.
pub const HOTTEST_PLAUSIBLE_C: f64 = 130.0;

/// A scale's conversion to C is plausible when it lands within these (C).
const PLAUSIBLE_C: (f64, f64) = (-80.0, 125.0);

/// The window over which the end of a recording is judged still ramping (s), and the
/// change (C) over it that counts as a ramp.
pub const END_WINDOW_S: f64 = 600.0;
/// See [`END_WINDOW_S`].
pub const END_RAMP_C: f64 = 2.0;
/// A ramp moves as much in the second half of [`END_WINDOW_S`] as in the first; a unit
/// settling in a hold (a first-order lag shorter than 22 min) moves less than this share.
pub const RAMP_NOT_SETTLING: f64 = 0.8;

/// The plausible change of the outputs per g for each unit (lower, upper), as
/// [`output_scale`] measures it (0.7 to 1 of the sensitivity). V: 0.01-6 (a navigation
/// accelerometer's analogue output is 0.1-10 V per g; one swinging +-15 V over a range of
/// at least +-2 g gives at most 7.5, and the edge at 6 tells m/s2 numbers, measured 6.9-9.8,
/// from V); mV the same in mV; m/s^2 about 9.8, g about 1, mg about 1000, each within a
/// factor of two (a partial set of positions, an uncalibrated sensor); counts and labels
/// of other units anything.
pub fn per_g_band(u: &OutputUnit) -> Option<(f64, f64)> {
    match u {
        OutputUnit::Volt => Some((0.01, 6.0)),
        OutputUnit::Millivolt => Some((10.0, 6000.0)),
        OutputUnit::MetresPerS2 => Some((5.0, 15.0)),
        OutputUnit::G => Some((0.5, 1.5)),
        OutputUnit::MilliG => Some((500.0, 1500.0)),
        OutputUnit::Counts | OutputUnit::Other(_) => None,
    }
}

/// The change of the outputs per g that the data show: half the largest distance between
/// two positions' median outputs (over all their rows: a few wild rows do not move it),
/// or, with fewer than two positions held, half the 95th percentile of the distances
/// between rows (at most 2000, evenly spread). A pair of opposite positions gives the
/// sensitivity itself, two at right angles 0.71 of it. None when there is nothing to
/// compare.
pub fn output_scale(rec: &Recording) -> Option<f64> {
    let mut per: Vec<[Vec<f64>; 3]> = vec![Default::default(); rec.positions.list.len()];
    for r in &rec.rows {
        if let Some(v) = r.position.and_then(|p| per.get_mut(p)) {
            for (a, x) in v.iter_mut().zip(r.u) {
                a.push(x);
            }
        }
    }
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
    };
    let medians: Vec<[f64; 3]> = per
        .iter_mut()
        .filter(|v| !v[0].is_empty())
        .map(|v| [median(&mut v[0]), median(&mut v[1]), median(&mut v[2])])
        .collect();
    let dist = |a: &[f64; 3], b: &[f64; 3]| {
        a.iter()
            .zip(b)
            .map(|(x, y)| (x - y) * (x - y))
            .sum::<f64>()
            .sqrt()
    };
    if medians.len() >= 2 {
        let mut far: f64 = 0.0;
        for (i, a) in medians.iter().enumerate() {
            for b in medians.iter().skip(i + 1) {
                far = far.max(dist(a, b));
            }
        }
        return Some(far / 2.0);
    }
    let step = rec.rows.len().div_ceil(2000).max(1);
    let rows: Vec<[f64; 3]> = rec.rows.iter().step_by(step).map(|r| r.u).collect();
    let mut d: Vec<f64> = Vec::new();
    for (i, a) in rows.iter().enumerate() {
        d.extend(rows.iter().skip(i + 1).map(|b| dist(a, b)));
    }
    if d.is_empty() {
        return None;
    }
    d.sort_by(f64::total_cmp);
    let k = (d.len() - 1) * 95 / 100;
    d.get(k).map(|x| x / 2.0)
}

/// The outputs' scale against their stated unit: a finding when it is implausible,
/// naming the units the numbers look like.
pub fn output_scale_finding(rec: &Recording) -> Option<Finding> {
    let unit = rec.output_unit.clone();
    let (lo, hi) = per_g_band(&unit)?;
    let s = output_scale(rec)?;
    if (lo..=hi).contains(&s) || !s.is_finite() {
        return None;
    }
    let integers = rec
        .rows
        .iter()
        .all(|r| r.u.iter().all(|x| x.fract() == 0.0));
    let mut like: Vec<String> = Vec::new();
    if integers {
        like.push("counts (they are all integers)".into());
    }
    // the units whose band holds the scale, the nearest to its typical value first
    let mut fits: Vec<(f64, OutputUnit)> = [
        (1.0, OutputUnit::Volt),
        (1000.0, OutputUnit::Millivolt),
        (9.80665, OutputUnit::MetresPerS2),
        (1.0, OutputUnit::G),
        (1000.0, OutputUnit::MilliG),
    ]
    .into_iter()
    .filter(|(_, u)| *u != unit && per_g_band(u).is_some_and(|(a, b)| (a..=b).contains(&s)))
    .map(|(typical, u)| ((s / typical).ln().abs(), u))
    .collect();
    fits.sort_by(|a, b| a.0.total_cmp(&b.0));
    like.extend(fits.into_iter().map(|(_, u)| u.to_string()));
    let stated = if rec.metadata.contains_key("output_unit") {
        format!("`# output_unit={}`", rec.output_unit)
    } else {
        format!("{unit} (the default: the recording has no `# output_unit=` line)")
    };
    let looks = match like.first() {
        Some(first) => format!(
            "they look like {}: state the unit in the recording (`# output_unit={}`)",
            like.join(" or "),
            first.split(' ').next().unwrap_or(first)
        ),
        None => "they match none of the format's units (V, mV, m/s2, g, mg): check the columns' scale, or state the unit they are in (`# output_unit=LABEL`)".into(),
    };
    Some(Finding {
        check: Check::OutputScale,
        line: None,
        field: "ux_v..uz_v",
        message: format!(
            "the outputs change by about {s:.4} per g across positions, implausible for \
             {stated}, whose outputs change by {lo}-{hi} per g; {looks}; or `--allow {}` \
             if these numbers really are {unit}",
            Check::OutputScale.name()
        ),
    })
}

/// The temperatures' scale: a finding when the readings look like Kelvin (all of them
/// above [`HOTTEST_PLAUSIBLE_C`], and plausible once converted) or Fahrenheit (some of
/// them above it, plausible once converted).
pub fn temperature_scale_finding(rec: &Recording) -> Option<Finding> {
    let (lo, hi) = rec
        .rows
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), r| {
            (a.min(r.temp_c), b.max(r.temp_c))
        });
    if hi <= HOTTEST_PLAUSIBLE_C {
        return None;
    }
    let plausible = |a: f64, b: f64| a >= PLAUSIBLE_C.0 && b <= PLAUSIBLE_C.1;
    let (k_lo, k_hi) = (lo - 273.15, hi - 273.15);
    let (f_lo, f_hi) = ((lo - 32.0) / 1.8, (hi - 32.0) / 1.8);
    let hottest = rec.rows.iter().find(|r| r.temp_c == hi).map(|r| r.line);
    let mut m = format!(
        "the unit's temperatures read {lo:.2}..{hi:.2} C, {} above {HOTTEST_PLAUSIBLE_C} C \
         (beyond the widest rating of an accelerometer, 125 C); ",
        if lo > HOTTEST_PLAUSIBLE_C {
            "all of them"
        } else {
            "the hottest"
        }
    );
    if lo > HOTTEST_PLAUSIBLE_C && plausible(k_lo, k_hi) {
        let _ = write!(
            m,
            "they look like Kelvin ({k_lo:.2}..{k_hi:.2} C): convert the column (temp_c = K - 273.15)"
        );
    } else if plausible(f_lo, f_hi) {
        let _ = write!(
            m,
            "they look like Fahrenheit ({f_lo:.2}..{f_hi:.2} C): convert the column (temp_c = (F - 32) / 1.8)"
        );
    } else {
        m.push_str("check the column's unit (temp_c is in C)");
    }
    let _ = write!(
        m,
        "; or `--allow {}` if they really are C",
        Check::TemperatureScale.name()
    );
    Some(Finding {
        check: Check::TemperatureScale,
        line: hottest,
        field: "temp_c",
        message: m,
    })
}

/// The temperatures the calibration data cover (C), and whether they are those of a
/// stop-and-soak test: the rows of the calibration dwells in thermal equilibrium when
/// most dwells are (fitted on those), else of every calibration dwell (a sweep, fitted
/// through its ramps).
pub fn covered(rec: &Recording) -> Option<((f64, f64), bool)> {
    let cal: Vec<&Dwell> = rec
        .dwells
        .iter()
        .filter(|d| rec.positions.has_role(d.position, Role::Calibration))
        .collect();
    let still: Vec<&Dwell> = cal
        .iter()
        .copied()
        .filter(|d| d.temp_span_c <= MAX_DWELL_DRIFT_C)
        .collect();
    let stops = !still.is_empty() && 2 * still.len() >= cal.len();
    let span = |ds: &[&Dwell]| {
        ds.iter()
            .flat_map(|d| rec.dwell_rows(d))
            .fold(None, |acc: Option<(f64, f64)>, r| {
                Some(acc.map_or((r.temp_c, r.temp_c), |(a, b)| {
                    (a.min(r.temp_c), b.max(r.temp_c))
                }))
            })
    };
    span(if stops { &still } else { &cal }).map(|r| (r, stops))
}

/// The mean temperature of the rows in `[from, to]` s, None when there are none.
fn mean_temp(rec: &Recording, from: f64, to: f64) -> Option<f64> {
    let (s, n) = rec
        .rows
        .iter()
        .filter(|r| r.t_s >= from && r.t_s <= to)
        .fold((0.0, 0.0), |(s, n), r| (s + r.temp_c, n + 1.0));
    (n > 0.0).then(|| s / n)
}

/// The temperature about `t` s: the mean of the minute before it, or the last row
/// before it.
fn temp_at(rec: &Recording, t: f64) -> Option<f64> {
    mean_temp(rec, t - 60.0, t)
        .or_else(|| rec.rows.iter().rev().find(|r| r.t_s <= t).map(|r| r.temp_c))
}

/// A stop-and-soak test cut off before its next stop: in its last [`END_WINDOW_S`] its
/// temperature still ramps (by more than [`END_RAMP_C`], its second half moving at least
/// [`RAMP_NOT_SETTLING`] of its first: not a unit settling in a hold), away from where the
/// recording began (not back to the ambient) and past the range its stops cover.
fn cut_off(rec: &Recording, (lo, hi): (f64, f64)) -> Option<Finding> {
    let (first, last) = (rec.rows.first()?, rec.rows.last()?);
    if last.t_s - first.t_s < 2.0 * END_WINDOW_S {
        return None;
    }
    let end = temp_at(rec, last.t_s)?;
    let mid = temp_at(rec, last.t_s - END_WINDOW_S / 2.0)?;
    let before = temp_at(rec, last.t_s - END_WINDOW_S)?;
    let moved = end - before;
    let ramp = (end - mid) * moved.signum() >= RAMP_NOT_SETTLING * (mid - before) * moved.signum();
    let away = (end - first.temp_c).abs() > (before - first.temp_c).abs();
    let past = if moved > 0.0 {
        end > hi + 1.0
    } else {
        end < lo - 1.0
    };
    if moved.abs() < END_RAMP_C || !ramp || !away || !past {
        return None;
    }
    Some(Finding {
        check: Check::Partial,
        line: Some(last.line),
        field: "temp_c",
        message: format!(
            "the recording ends while the temperature still {} ({before:.1} -> {end:.1} C \
             in its last {:.0} min, away from the {:.1} C it began at), past the {lo:.1}..{hi:.1} C \
             its stops cover: the test looks cut off before its next stop; run the rest of it, \
             or `--allow {}` to fit the range it covers (the blob is then valid over about \
             {lo:.1}..{hi:.1} C only)",
            if moved > 0.0 { "rises" } else { "falls" },
            END_WINDOW_S / 60.0,
            first.temp_c,
            Check::Partial.name()
        ),
    })
}

/// The reference temperature outside the temperatures the calibration dwells cover (by
/// more than [`T0_BAND_C`]).
fn t0_outside(rec: &Recording, (lo, hi): (f64, f64)) -> Option<Finding> {
    let t0 = rec.t0_c;
    if t0 >= lo - T0_BAND_C && t0 <= hi + T0_BAND_C {
        return None;
    }
    let stated = if rec.metadata.contains_key("t0_c") {
        "stated by `# t0_c=`"
    } else {
        "the default: the recording has no `# t0_c=` line"
    };
    Some(Finding {
        check: Check::Partial,
        line: None,
        field: "t0_c",
        message: format!(
            "the reference temperature T0 = {t0} C ({stated}) lies outside the {lo:.1}..{hi:.1} C \
             the calibration dwells cover: the blob would extrapolate to its own reference, and \
             the acceptance's band of +-{T0_BAND_C} C about T0 could not be judged; the test \
             looks cut short: run the rest of it, or state the reference temperature within the \
             range covered (`# t0_c=`) if this range is the one intended, or `--allow {}` to \
             fit it as it is",
            Check::Partial.name()
        ),
    })
}

/// What the recording's temperatures promised and do not cover (a cut-off test first).
/// A sweep covers what it swept: only its T0 is judged.
pub fn partial_findings(rec: &Recording) -> Vec<Finding> {
    let Some((range, stops)) = covered(rec) else {
        return Vec::new();
    };
    stops
        .then(|| cut_off(rec, range))
        .flatten()
        .into_iter()
        .chain(t0_outside(rec, range))
        .collect()
}

/// Every finding at the door, in the order they are reported: the temperatures' scale
/// (a wrong one also moves T0 out of the data), the outputs' scale, then what the
/// recording covers.
pub fn findings(rec: &Recording) -> Vec<Finding> {
    let scale = temperature_scale_finding(rec);
    let partial = if scale.is_some() {
        Vec::new()
    } else {
        partial_findings(rec)
    };
    scale
        .into_iter()
        .chain(output_scale_finding(rec))
        .chain(partial)
        .collect()
}

/// Let `rec` in: the first finding of a check in `refuse` is an error naming the file
/// (the line where one applies) and the field, unless `allow` lets it past; every other
/// finding is kept as a warning in `rec.warnings` (a check let past says so).
pub fn admit(rec: &mut Recording, refuse: &[Check], allow: &[Check]) -> Result<()> {
    for f in findings(rec) {
        let refused = refuse.contains(&f.check);
        if refused && !allow.contains(&f.check) {
            return Err(match f.line {
                Some(line) => {
                    HostError::at_field(ErrorKind::Malformed, &rec.path, line, f.field, f.message)
                }
                None => HostError::in_file(
                    ErrorKind::Malformed,
                    &rec.path,
                    format!("field `{}`: {}", f.field, f.message),
                ),
            });
        }
        let at = f.line.map(|l| format!(":{l}")).unwrap_or_default();
        let past = if refused {
            format!(" (let past by --allow {})", f.check.name())
        } else {
            String::new()
        };
        rec.warnings.push(format!(
            "{}{at}: field `{}`: {}{past}",
            rec.path.display(),
            f.field,
            f.message
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::positions::Positions;
    use std::path::Path;

    /// Six TP dwells of 5 samples at `temp`, sensitivity `k` per g.
    fn six(temp: f64, k: f64, meta: &str) -> Recording {
        let mut s = format!("{meta}t_s,position,temp_c,ux_v,uy_v,uz_v\n");
        let pos = Positions::default();
        let mut t = 0;
        for p in pos.list.iter().take(6) {
            for _ in 0..5 {
                let u = p.a.map(|a| k * a + 0.01 * k);
                s.push_str(&format!(
                    "{t},{},{temp},{},{},{}\n",
                    p.name, u[0], u[1], u[2]
                ));
                t += 1;
            }
        }
        Recording::from_reader(Path::new("r.csv"), s.as_bytes(), pos).unwrap()
    }

    #[test]
    fn the_scale_per_g_is_the_sensitivity_for_opposite_positions() {
        let r = six(20.0, 0.55, "");
        let s = output_scale(&r).unwrap();
        assert!((s - 0.55).abs() < 1e-9, "{s}");
        assert!(output_scale_finding(&r).is_none());
        // the same numbers in mV, stated V by default: named, with the units they fit
        let f = output_scale_finding(&six(20.0, 550.0, "")).unwrap();
        assert!(f.message.contains("look like mV or mg"), "{}", f.message);
        assert!(
            f.message.contains("no `# output_unit=` line"),
            "{}",
            f.message
        );
        // stated correctly: nothing to say
        assert!(output_scale_finding(&six(20.0, 550.0, "# output_unit=mV\n")).is_none());
        // m/s2 read as g
        let f = output_scale_finding(&six(20.0, 9.81, "# output_unit=g\n")).unwrap();
        assert!(f.message.contains("look like m/s2"), "{}", f.message);
    }

    #[test]
    fn kelvin_and_fahrenheit_are_told_apart() {
        assert!(temperature_scale_finding(&six(125.0, 0.55, "")).is_none());
        let k = temperature_scale_finding(&six(293.15, 0.55, "")).unwrap();
        assert!(
            k.message.contains("look like Kelvin (20.00..20.00 C)"),
            "{}",
            k.message
        );
        let f = temperature_scale_finding(&six(158.0, 0.55, "")).unwrap();
        assert!(
            f.message.contains("look like Fahrenheit (70.00..70.00 C)"),
            "{}",
            f.message
        );
    }

    #[test]
    fn t0_outside_the_data_is_partial_and_near_it_is_not() {
        assert!(partial_findings(&six(24.0, 0.55, "")).is_empty());
        let f = partial_findings(&six(-30.0, 0.55, ""));
        assert_eq!(f.len(), 1);
        assert_eq!(f[0].field, "t0_c");
        assert!(partial_findings(&six(-30.0, 0.55, "# t0_c=-30\n")).is_empty());
    }
}
