//! Control charts across lots (`host-fit trend`): every calibration of the store in
//! time order, a unit calibrated again as a point of its own (marked as a
//! recalibration), the calibrations of one batch, which share its start, in the order
//! of their files (never in the order parallel jobs happened to finish them, which
//! interleaves a lot's halves); each coefficient at T0 and the worst verification |dg|
//! as an individuals chart whose centre line and limits come from a reference period
//! (a limit never beyond what the quantity can reach: |dg| is never below 0), and the
//! points flagged by Nelson's run rules (the first four of
//! which include Western Electric's: Nelson 1 = WE 1, Nelson 5 = WE 2, Nelson 6 = WE 3).
//!
//! Centre: the reference points' mean; sigma: their mean moving range / 1.128 (the
//! individuals chart's estimate, blind to a slow drift inside the reference). A stable
//! process (independent normal points, limits known) flags each point by rule k with
//! the probability [`Rule::false_alarm_rate`]; with all eight rules a point is flagged
//! with probability [`ALL_RULES_FALSE_ALARM_RATE`], 2.5 %; with limits estimated from a
//! reference of 20, 50 or 100 units, 5.4 %, 3.5 % or 3.0 % ([`ALL_RULES_BY_REFERENCE`]).
//! Monte-Carlo tests hold every one of these rates.
use super::db::{Filter, Order, Store};
use super::record::Command;
use crate::error::{ErrorKind, HostError, Result};
use firmware_core::model::{COEFF_NAMES, U0_INDEX};
use serde::Serialize;
use std::collections::HashMap;

/// A run rule (Nelson, 1984).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
pub enum Rule {
    /// One point beyond 3 sigma.
    BeyondThree,
    /// Nine points in a row on one side of the centre line.
    NineOneSide,
    /// Six points in a row steadily increasing or decreasing.
    SixTrending,
    /// Fourteen points in a row alternating up and down.
    FourteenAlternating,
    /// Two of three points in a row beyond 2 sigma on one side.
    TwoOfThreeBeyondTwo,
    /// Four of five points in a row beyond 1 sigma on one side.
    FourOfFiveBeyondOne,
    /// Fifteen points in a row within 1 sigma.
    FifteenWithinOne,
    /// Eight points in a row beyond 1 sigma, on both sides.
    EightBeyondOne,
}

/// The probability that a point of a stable process (independent normal points, limits
/// known) is flagged by at least one of the eight rules (measured: 0.0252 +- 0.0003 over
/// seven runs of 400 000 points; a Monte-Carlo test holds it to within 0.001).
pub const ALL_RULES_FALSE_ALARM_RATE: f64 = 0.0252;

impl Rule {
    /// Every rule, in Nelson's order.
    pub const ALL: [Rule; 8] = [
        Rule::BeyondThree,
        Rule::NineOneSide,
        Rule::SixTrending,
        Rule::FourteenAlternating,
        Rule::TwoOfThreeBeyondTwo,
        Rule::FourOfFiveBeyondOne,
        Rule::FifteenWithinOne,
        Rule::EightBeyondOne,
    ];

    /// Nelson's number, 1..=8.
    pub fn number(self) -> u8 {
        match self {
            Rule::BeyondThree => 1,
            Rule::NineOneSide => 2,
            Rule::SixTrending => 3,
            Rule::FourteenAlternating => 4,
            Rule::TwoOfThreeBeyondTwo => 5,
            Rule::FourOfFiveBeyondOne => 6,
            Rule::FifteenWithinOne => 7,
            Rule::EightBeyondOne => 8,
        }
    }

    /// The rule of Nelson's number `n`.
    pub fn from_number(n: u8) -> Option<Rule> {
        Rule::ALL.into_iter().find(|r| r.number() == n)
    }

    /// What it flags, in words.
    pub fn text(self) -> &'static str {
        match self {
            Rule::BeyondThree => "a point beyond 3 sigma",
            Rule::NineOneSide => "9 in a row on one side of the centre",
            Rule::SixTrending => "6 in a row rising or falling",
            Rule::FourteenAlternating => "14 in a row alternating up and down",
            Rule::TwoOfThreeBeyondTwo => "2 of 3 beyond 2 sigma on one side",
            Rule::FourOfFiveBeyondOne => "4 of 5 beyond 1 sigma on one side",
            Rule::FifteenWithinOne => "15 in a row within 1 sigma",
            Rule::EightBeyondOne => "8 in a row beyond 1 sigma, both sides",
        }
    }

    /// `Nelson N: what`.
    pub fn name(self) -> String {
        format!("Nelson {}: {}", self.number(), self.text())
    }

    /// The probability that a point of a stable process is flagged by this rule
    /// (independent normal points, limits known; exact: normal tails, 2/6! for a trend,
    /// Euler's zigzag number for alternation).
    pub fn false_alarm_rate(self) -> f64 {
        match self {
            Rule::BeyondThree => 0.002_699_796,
            Rule::NineOneSide => 0.003_906_25,
            Rule::SixTrending => 0.002_777_778,
            Rule::FourteenAlternating => 0.004_573_638,
            Rule::TwoOfThreeBeyondTwo => 0.003_058_312,
            Rule::FourOfFiveBeyondOne => 0.005_531_842,
            Rule::FifteenWithinOne => 0.003_260_981,
            Rule::EightBeyondOne => 0.000_101_969,
        }
    }

    /// How many points in a row the rule looks at.
    fn window(self) -> usize {
        match self {
            Rule::BeyondThree => 1,
            Rule::NineOneSide => 9,
            Rule::SixTrending => 6,
            Rule::FourteenAlternating => 14,
            Rule::TwoOfThreeBeyondTwo => 3,
            Rule::FourOfFiveBeyondOne => 5,
            Rule::FifteenWithinOne => 15,
            Rule::EightBeyondOne => 8,
        }
    }

    /// Whether the points `w` (the rule's window, oldest first, in sigmas from the
    /// centre) complete the rule's pattern.
    fn fires(self, w: &[f64]) -> bool {
        let count = |f: &dyn Fn(f64) -> bool| w.iter().filter(|z| f(**z)).count();
        let rising = |a: &[f64]| a.windows(2).all(|p| p[1] > p[0]);
        let falling = |a: &[f64]| a.windows(2).all(|p| p[1] < p[0]);
        match self {
            Rule::BeyondThree => w[0].abs() > 3.0,
            Rule::NineOneSide => w.iter().all(|z| *z > 0.0) || w.iter().all(|z| *z < 0.0),
            Rule::SixTrending => rising(w) || falling(w),
            Rule::FourteenAlternating => w.windows(3).all(|p| (p[1] - p[0]) * (p[2] - p[1]) < 0.0),
            Rule::TwoOfThreeBeyondTwo => count(&|z| z > 2.0) >= 2 || count(&|z| z < -2.0) >= 2,
            Rule::FourOfFiveBeyondOne => count(&|z| z > 1.0) >= 4 || count(&|z| z < -1.0) >= 4,
            Rule::FifteenWithinOne => w.iter().all(|z| z.abs() < 1.0),
            Rule::EightBeyondOne => {
                w.iter().all(|z| z.abs() > 1.0)
                    && count(&|z| z > 0.0) > 0
                    && count(&|z| z < 0.0) > 0
            }
        }
    }
}

/// The probability that a point after the reference is flagged by at least one of the
/// eight rules, on a stable process, with limits from a reference of n points (the
/// limits' own error adds false alarms): measured by Monte-Carlo (20 000 references,
/// four seeds: +-0.0015), held by a test to within 0.004.
pub const ALL_RULES_BY_REFERENCE: [(usize, f64); 3] = [(20, 0.054), (50, 0.035), (100, 0.030)];

/// [`ALL_RULES_BY_REFERENCE`] for a reference of `n` points: the entry of the largest
/// size not above n (an upper bound between entries); None below 20 points.
pub fn all_rules_rate(n: usize) -> Option<f64> {
    ALL_RULES_BY_REFERENCE
        .iter()
        .rev()
        .find(|e| e.0 <= n)
        .map(|e| e.1)
}

/// Rules from the command line: Nelson numbers, comma-separated (`1,2,5`), or `all`.
pub fn parse_rules(s: &str) -> Result<Vec<Rule>> {
    if s.trim() == "all" {
        return Ok(Rule::ALL.to_vec());
    }
    let mut out = Vec::new();
    for p in s.split(',') {
        let r = p
            .trim()
            .parse::<u8>()
            .ok()
            .and_then(Rule::from_number)
            .ok_or_else(|| {
                HostError::new(ErrorKind::Invalid, format!(
                    "--rules `{s}`: `{p}` is not a rule: Nelson's numbers 1 to 8, comma-separated, or `all`"
                ))
            })?;
        if !out.contains(&r) {
            out.push(r);
        }
    }
    out.sort();
    Ok(out)
}

/// A chart's centre line and sigma.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Limits {
    /// The reference points' mean.
    pub centre: f64,
    /// Their mean moving range / 1.128.
    pub sigma: f64,
    /// How many reference points.
    pub points: usize,
    /// The lower control limit: centre - 3 sigma, or the quantity's own lower bound
    /// when that is higher (a worst |dg| is never below 0).
    pub lower: f64,
    /// The upper control limit: centre + 3 sigma.
    pub upper: f64,
}

impl Limits {
    /// The same limits within the bounds a quantity cannot cross.
    pub fn bounded(self, q: Quantity) -> Limits {
        let (lo, hi) = q.bounds();
        Limits {
            lower: lo.map_or(self.lower, |b| self.lower.max(b)),
            upper: hi.map_or(self.upper, |b| self.upper.min(b)),
            ..self
        }
    }
}

/// d2 of a moving range of two: the mean |x_i - x_(i-1)| of a normal process is
/// 1.128 sigma.
const D2: f64 = 1.128;

/// The limits from `reference` (in time order); None with fewer than two points or no
/// spread.
pub fn limits(reference: &[f64]) -> Option<Limits> {
    let n = reference.len();
    if n < 2 {
        return None;
    }
    let centre = reference.iter().sum::<f64>() / n as f64;
    let mr = reference
        .windows(2)
        .map(|w| (w[1] - w[0]).abs())
        .sum::<f64>()
        / (n - 1) as f64;
    let sigma = mr / D2;
    (sigma > 0.0 && sigma.is_finite()).then_some(Limits {
        centre,
        sigma,
        points: n,
        lower: centre - 3.0 * sigma,
        upper: centre + 3.0 * sigma,
    })
}

/// The rules each point of `values` (in time order) completes.
pub fn flags(values: &[f64], l: &Limits, rules: &[Rule]) -> Vec<Vec<Rule>> {
    let z: Vec<f64> = values.iter().map(|v| (v - l.centre) / l.sigma).collect();
    (0..z.len())
        .map(|i| {
            rules
                .iter()
                .copied()
                .filter(|r| i + 1 >= r.window() && r.fires(&z[i + 1 - r.window()..=i]))
                .collect()
        })
        .collect()
}

/// Which units set the limits.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub enum Reference {
    /// The first N units in time order.
    First(usize),
    /// The units calibrated between two times (store times, inclusive).
    Between(String, String),
}

impl Reference {
    /// In words.
    pub fn text(&self) -> String {
        match self {
            Reference::First(n) => format!("the first {n} calibrations"),
            Reference::Between(a, b) => format!("the calibrations from {a} to {b}"),
        }
    }
}

/// What a chart plots.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Quantity {
    /// A coefficient at T0 ([`COEFF_NAMES`] index).
    Coefficient(usize),
    /// The worst compensated |dg| over the verification dwells.
    WorstDg,
}

impl Quantity {
    /// `kxx` .. `u0z`, or `worst_dg`.
    pub fn name(self) -> &'static str {
        match self {
            Quantity::Coefficient(c) => COEFF_NAMES.get(c).copied().unwrap_or("?"),
            Quantity::WorstDg => "worst_dg",
        }
    }

    /// The bounds the quantity cannot cross (lower, upper).
    pub fn bounds(self) -> (Option<f64>, Option<f64>) {
        match self {
            Quantity::Coefficient(_) => (None, None),
            // an absolute value
            Quantity::WorstDg => (Some(0.0), None),
        }
    }

    /// Its unit, the recordings' output unit being `out`.
    pub fn unit(self, out: &str) -> String {
        match self {
            Quantity::Coefficient(c) if c < U0_INDEX[0] => format!("{out}/g"),
            Quantity::Coefficient(_) => out.to_string(),
            Quantity::WorstDg => "mg".into(),
        }
    }
}

impl Serialize for Quantity {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        s.serialize_str(self.name())
    }
}

/// A calibration on the charts (every calibration of the store, recalibrations too).
#[derive(Debug, Clone, Serialize)]
pub struct Unit {
    /// Serial.
    pub serial: String,
    /// Lot.
    pub lot: Option<String>,
    /// When calibrated.
    pub time_utc: String,
    /// The calibration's run.
    pub run_id: String,
    /// Whether the unit was calibrated before (an earlier point of the chart).
    pub recalibration: bool,
}

/// A point of a chart.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Point {
    /// The calibration's place on the chart (0-based, in time order).
    pub place: usize,
    /// Its value.
    pub value: f64,
}

/// A flagged point.
#[derive(Debug, Clone, Serialize)]
pub struct Flag {
    /// The calibration's place on the chart (0-based, in time order).
    pub unit: usize,
    /// Its serial.
    pub serial: String,
    /// Its value.
    pub value: f64,
    /// The rules it completes (Nelson's numbers).
    pub rules: Vec<u8>,
}

/// One control chart.
#[derive(Debug, Clone, Serialize)]
pub struct Chart {
    /// `kxx` .. `u0z`, or `worst_dg`.
    pub quantity: Quantity,
    /// The values' unit (`V/g`, `V`, `mg`).
    pub unit: String,
    /// In time order.
    #[serde(skip)]
    pub points: Vec<Point>,
    /// The limits (None: too few reference points, or none spread).
    pub limits: Option<Limits>,
    /// The flagged points.
    pub flags: Vec<Flag>,
    /// Flagged points per rule (Nelson's number, count).
    pub by_rule: Vec<(u8, usize)>,
    /// Why the chart has no limits, or what else to know.
    pub note: Option<String>,
}

/// Consecutive calibrations of one lot.
#[derive(Debug, Clone, Serialize)]
pub struct LotSpan {
    /// The lot (`-` for none).
    pub lot: String,
    /// First calibration's place.
    pub first: usize,
    /// Last calibration's place.
    pub last: usize,
}

/// The charts of a store.
#[derive(Debug, Clone, Serialize)]
pub struct Trend {
    /// The store.
    pub store: String,
    /// The calibrations in time order.
    #[serde(skip)]
    pub units: Vec<Unit>,
    /// How many calibrations (points per chart at most).
    pub unit_count: usize,
    /// How many of them are recalibrations of a unit calibrated before.
    pub recalibrations: usize,
    /// The lots as they follow in time.
    pub lots: Vec<LotSpan>,
    /// The reference period.
    pub reference: Reference,
    /// Its calibrations' places.
    #[serde(skip)]
    pub reference_units: Vec<usize>,
    /// The rules applied (Nelson's numbers).
    pub rules: Vec<u8>,
    /// The charts: the 12 coefficients at T0, then the worst |dg|.
    pub charts: Vec<Chart>,
}

/// What the charts are made of: every calibration in time order with its coefficients,
/// output unit and worst |dg|.
struct Loaded {
    units: Vec<Unit>,
    coeffs: Vec<[Option<f64>; COEFF_COUNT]>,
    out_units: Vec<Option<String>>,
    worst_dg: Vec<Option<f64>>,
}

/// The coefficients per calibration.
const COEFF_COUNT: usize = COEFF_NAMES.len();

/// A calibration's worst |dg|: its own (a batch verifies what it makes), else that of
/// the first `verify` of the same unit after it and before its next calibration.
fn verified_after(
    serial: &str,
    id: i64,
    next: Option<i64>,
    verifies: &HashMap<String, Vec<(i64, f64)>>,
) -> Option<f64> {
    verifies.get(serial).and_then(|v| {
        v.iter()
            .find(|(vid, _)| *vid > id && next.is_none_or(|n| *vid < n))
            .map(|(_, dg)| *dg)
    })
}

fn load(store: &mut Store) -> Result<Loaded> {
    let names: Vec<String> = [
        "id",
        "serial",
        "lot",
        "time_utc",
        "run_id",
        "output_unit",
        "worst_dg_mg",
    ]
    .iter()
    .map(|s| s.to_string())
    .chain(COEFF_NAMES.iter().map(|s| s.to_string()))
    .collect();
    let rows = store.select(
        &names,
        &Filter {
            calibrations: true,
            order: Order::Time,
            ..Filter::default()
        },
    )?;
    let verifies = store.select(
        &["id".into(), "serial".into(), "worst_dg_mg".into()],
        &Filter {
            command: Some(Command::Verify),
            ..Filter::default()
        },
    )?;
    let mut by_serial: HashMap<String, Vec<(i64, f64)>> = HashMap::new();
    for r in &verifies {
        if let (Some(s), Some(id), Some(dg)) =
            (r.text("serial"), r.integer("id"), r.real("worst_dg_mg"))
        {
            by_serial.entry(s).or_default().push((id, dg));
        }
    }
    // each serial's calibrations by id: the next one bounds a verify's reach
    let mut cal_ids: HashMap<String, Vec<i64>> = HashMap::new();
    for r in &rows {
        if let (Some(s), Some(id)) = (r.text("serial"), r.integer("id")) {
            cal_ids.entry(s).or_default().push(id);
        }
    }
    cal_ids.values_mut().for_each(|v| v.sort_unstable());
    let mut seen = std::collections::HashSet::new();
    let mut l = Loaded {
        units: Vec::with_capacity(rows.len()),
        coeffs: Vec::with_capacity(rows.len()),
        out_units: Vec::with_capacity(rows.len()),
        worst_dg: Vec::with_capacity(rows.len()),
    };
    for r in &rows {
        let serial = r.text("serial").unwrap_or_default();
        let id = r.integer("id").unwrap_or(0);
        let next = cal_ids
            .get(&serial)
            .and_then(|v| v.iter().find(|x| **x > id).copied());
        l.worst_dg.push(
            r.real("worst_dg_mg")
                .or_else(|| verified_after(&serial, id, next, &by_serial)),
        );
        l.units.push(Unit {
            recalibration: !seen.insert(serial.clone()),
            serial,
            lot: r.text("lot"),
            time_utc: r.text("time_utc").unwrap_or_default(),
            run_id: r.text("run_id").unwrap_or_default(),
        });
        l.out_units.push(r.text("output_unit"));
        l.coeffs
            .push(std::array::from_fn(|k| r.real(COEFF_NAMES[k])));
    }
    Ok(l)
}

fn lot_spans(units: &[Unit]) -> Vec<LotSpan> {
    let mut out: Vec<LotSpan> = Vec::new();
    for (i, u) in units.iter().enumerate() {
        let lot = u.lot.clone().unwrap_or_else(|| "-".into());
        match out.last_mut() {
            Some(l) if l.lot == lot => l.last = i,
            _ => out.push(LotSpan {
                lot,
                first: i,
                last: i,
            }),
        }
    }
    out
}

/// The output unit most units share (ties: the first met), and a note when they differ.
fn common_unit(out_units: &[Option<String>]) -> (String, Option<String>) {
    let mut counts: Vec<(String, usize)> = Vec::new();
    for u in out_units.iter().flatten() {
        match counts.iter_mut().find(|c| &c.0 == u) {
            Some(c) => c.1 += 1,
            None => counts.push((u.clone(), 1)),
        }
    }
    let best = counts
        .iter()
        .max_by_key(|c| c.1)
        .map_or("unit".to_string(), |c| c.0.clone());
    let note = (counts.len() > 1).then(|| {
        format!(
            "the units' recordings are in different output units ({}): the coefficients of different units do not compare",
            counts.iter().map(|c| format!("{} {}", c.1, c.0)).collect::<Vec<_>>().join(", ")
        )
    });
    (best, note)
}

/// One chart of `points` with the reference's limits (within the quantity's bounds).
fn chart(
    quantity: Quantity,
    unit: String,
    points: Vec<Point>,
    in_reference: &[bool],
    rules: &[Rule],
    units: &[Unit],
) -> Chart {
    let reference: Vec<f64> = points
        .iter()
        .filter(|p| in_reference[p.place])
        .map(|p| p.value)
        .collect();
    let l = limits(&reference).map(|l| l.bounded(quantity));
    let note = match (&l, reference.len()) {
        (None, n) if n < 2 => Some(format!(
            "{n} reference points: no limits (at least 2 needed)"
        )),
        (None, _) => Some("the reference points do not vary: no limits".to_string()),
        (Some(_), n) if n < 20 => Some(format!(
            "only {n} reference points: the limits are rough (20 or more are usual)"
        )),
        _ => None,
    };
    let values: Vec<f64> = points.iter().map(|p| p.value).collect();
    let per_point = l
        .as_ref()
        .map(|l| flags(&values, l, rules))
        .unwrap_or_default();
    let flags: Vec<Flag> = per_point
        .iter()
        .enumerate()
        .filter(|(_, f)| !f.is_empty())
        .map(|(i, f)| Flag {
            unit: points[i].place,
            serial: units[points[i].place].serial.clone(),
            value: points[i].value,
            rules: f.iter().map(|r| r.number()).collect(),
        })
        .collect();
    let by_rule = rules
        .iter()
        .map(|r| {
            (
                r.number(),
                flags
                    .iter()
                    .filter(|f| f.rules.contains(&r.number()))
                    .count(),
            )
        })
        .collect();
    Chart {
        quantity,
        unit,
        points,
        limits: l,
        flags,
        by_rule,
        note,
    }
}

/// The charts of every calibration in `store` (recalibrations as points of their own),
/// the limits from `reference`, the points flagged by `rules`.
pub fn trend(store: &mut Store, reference: Reference, rules: &[Rule]) -> Result<Trend> {
    let l = load(store)?;
    if l.units.is_empty() {
        return Err(HostError::in_file(
            ErrorKind::Store,
            store.path(),
            "holds no calibration (no fit, diagnose --out, batch or demo record): nothing to chart",
        ));
    }
    let units = l.units;
    let in_reference: Vec<bool> = match &reference {
        Reference::First(n) => (0..units.len()).map(|i| i < *n).collect(),
        Reference::Between(a, b) => units
            .iter()
            .map(|u| u.time_utc.as_str() >= a.as_str() && u.time_utc.as_str() <= b.as_str())
            .collect(),
    };
    let (out_unit, mixed) = common_unit(&l.out_units);
    let mut charts = Vec::new();
    for c in 0..COEFF_COUNT {
        let q = Quantity::Coefficient(c);
        let points = l
            .coeffs
            .iter()
            .enumerate()
            .filter_map(|(i, v)| v[c].map(|value| Point { place: i, value }))
            .collect();
        let mut ch = chart(q, q.unit(&out_unit), points, &in_reference, rules, &units);
        if let Some(m) = &mixed {
            ch.note = Some(ch.note.map_or(m.clone(), |n| format!("{n}; {m}")));
        }
        charts.push(ch);
    }
    let points = l
        .worst_dg
        .iter()
        .enumerate()
        .filter_map(|(i, v)| v.map(|value| Point { place: i, value }))
        .collect();
    let q = Quantity::WorstDg;
    charts.push(chart(
        q,
        q.unit(&out_unit),
        points,
        &in_reference,
        rules,
        &units,
    ));
    Ok(Trend {
        store: store.location().to_string(),
        unit_count: units.len(),
        recalibrations: units.iter().filter(|u| u.recalibration).count(),
        lots: lot_spans(&units),
        reference,
        reference_units: in_reference
            .iter()
            .enumerate()
            .filter(|(_, r)| **r)
            .map(|(i, _)| i)
            .collect(),
        rules: rules.iter().map(|r| r.number()).collect(),
        units,
        charts,
    })
}

impl Chart {
    /// What the chart plots, in words (`kxx at T0`, `worst verification |dg|`).
    pub fn title(&self) -> String {
        match self.quantity {
            Quantity::WorstDg => "worst verification |dg|".into(),
            Quantity::Coefficient(_) => format!("{} at T0", self.quantity.name()),
        }
    }
}

impl Trend {
    /// As text: one line per chart (centre, sigma, flagged points by rule).
    pub fn text(&self) -> String {
        let mut s = vec![format!(
            "{} calibrations ({} of them recalibrations of a unit calibrated before), in time order, in {} lot runs from {}; limits from {} ({} calibrations): centre = their mean, sigma = their mean moving range / 1.128; rules: Nelson {}",
            self.unit_count,
            self.recalibrations,
            self.lots.len(),
            self.store,
            self.reference.text(),
            self.reference_units.len(),
            self.rules.iter().map(u8::to_string).collect::<Vec<_>>().join(",")
        )];
        s.push(format!(
            "{:<24} {:>16} {:>11} {:>7}  flagged points by rule",
            "chart", "centre", "sigma", "points"
        ));
        for c in &self.charts {
            let (centre, sigma) = c.limits.map_or(("-".to_string(), "-".to_string()), |l| {
                (format!("{:.9}", l.centre), format!("{:.3e}", l.sigma))
            });
            let rules: Vec<String> = c
                .by_rule
                .iter()
                .filter(|r| r.1 > 0)
                .map(|(n, k)| format!("N{n} {k}"))
                .collect();
            s.push(format!(
                "{:<24} {centre:>16} {sigma:>11} {:>7}  {} ({}){}",
                format!("{}, {}", c.title(), c.unit),
                c.points.len(),
                c.flags.len(),
                if rules.is_empty() {
                    "none".to_string()
                } else {
                    rules.join(", ")
                },
                c.note
                    .as_ref()
                    .map(|n| format!("; {n}"))
                    .unwrap_or_default()
            ));
        }
        s.push(format!(
            "a stable process flags each point by Nelson k with probability (limits known): {}; by all eight {:.2}%{}",
            Rule::ALL
                .iter()
                .map(|r| format!("N{} {:.2}%", r.number(), 100.0 * r.false_alarm_rate()))
                .collect::<Vec<_>>()
                .join(", "),
            100.0 * ALL_RULES_FALSE_ALARM_RATE,
            match all_rules_rate(self.reference_units.len()) {
                Some(r) => format!(
                    ", with limits from {} reference units up to {:.1}%",
                    self.reference_units.len(),
                    100.0 * r
                ),
                None => format!(
                    ", more with limits from only {} reference units",
                    self.reference_units.len()
                ),
            }
        ));
        s.join("\n")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    fn known() -> Limits {
        Limits {
            centre: 0.0,
            sigma: 1.0,
            points: 0,
            lower: -3.0,
            upper: 3.0,
        }
    }

    fn fired(values: &[f64], r: Rule) -> Vec<usize> {
        flags(values, &known(), &[r])
            .iter()
            .enumerate()
            .filter(|(_, f)| !f.is_empty())
            .map(|(i, _)| i)
            .collect()
    }

    #[test]
    fn each_rule_fires_on_its_pattern_and_not_one_short_of_it() {
        assert_eq!(fired(&[0.0, 3.1, -2.9, -3.2], Rule::BeyondThree), [1, 3]);
        let side: Vec<f64> = [0.5; 9].into_iter().chain([-0.5]).collect();
        assert_eq!(fired(&side, Rule::NineOneSide), [8]);
        assert!(fired(&side[1..], Rule::NineOneSide).is_empty());
        let rising = [0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.55];
        assert_eq!(fired(&rising, Rule::SixTrending), [5]);
        assert!(fired(&rising[1..], Rule::SixTrending).is_empty());
        let alt: Vec<f64> = (0..15)
            .map(|i| if i % 2 == 0 { 0.3 } else { -0.3 })
            .collect();
        assert_eq!(fired(&alt, Rule::FourteenAlternating), [13, 14]);
        assert!(fired(&alt[2..], Rule::FourteenAlternating).is_empty());
        assert_eq!(
            fired(&[2.1, 0.0, 2.2, -2.1], Rule::TwoOfThreeBeyondTwo),
            [2]
        );
        assert_eq!(
            fired(&[2.1, -2.2, 0.0], Rule::TwoOfThreeBeyondTwo),
            Vec::<usize>::new()
        );
        assert_eq!(
            fired(&[1.1, 1.2, 0.0, 1.3, 1.4], Rule::FourOfFiveBeyondOne),
            [4]
        );
        assert!(fired(&[1.1, 1.2, 0.0, -1.3, 1.4], Rule::FourOfFiveBeyondOne).is_empty());
        let quiet = [0.2; 15];
        assert_eq!(fired(&quiet, Rule::FifteenWithinOne), [14]);
        assert!(fired(&quiet[1..], Rule::FifteenWithinOne).is_empty());
        let wide = [1.5, -1.5, 1.5, -1.5, 1.5, -1.5, 1.5, -1.5];
        assert_eq!(fired(&wide, Rule::EightBeyondOne), [7]);
        // all on one side is Nelson 2's and 6's, not 8's
        assert!(fired(&[1.5; 8], Rule::EightBeyondOne).is_empty());
    }

    /// The stated false-alarm rates hold on a stable process: 400 000 independent
    /// normal points, each rule's share of flagged points within 4.5 binomial standard
    /// errors (runs make neighbours' flags correlated: the bound allows 1.5x the
    /// independent error) and the eight rules together within 0.0005.
    #[test]
    fn false_alarm_rates_hold_on_a_stable_process() {
        let mut rng = Rng::new(20);
        let n = 400_000;
        let x: Vec<f64> = (0..n).map(|_| rng.normal()).collect();
        let f = flags(&x, &known(), &Rule::ALL);
        for r in Rule::ALL {
            let k = f.iter().filter(|p| p.contains(&r)).count() as f64 / n as f64;
            let p = r.false_alarm_rate();
            let se = (p * (1.0 - p) / n as f64).sqrt();
            assert!(
                (k - p).abs() < 4.5 * 1.5 * se,
                "{}: {k:.5} flagged, stated {p:.5}",
                r.name()
            );
        }
        let any = f.iter().filter(|p| !p.is_empty()).count() as f64 / n as f64;
        assert!(
            (any - ALL_RULES_FALSE_ALARM_RATE).abs() < 1e-3,
            "all rules: {any:.5} flagged, stated {ALL_RULES_FALSE_ALARM_RATE}"
        );
    }

    /// With limits from a reference of n points the points after it are flagged at the
    /// stated rate (20 000 references of 20 and 50 points, 20 points after each).
    #[test]
    fn false_alarm_rates_with_estimated_limits_hold() {
        let mut rng = Rng::new(7);
        for (n, stated) in ALL_RULES_BY_REFERENCE.into_iter().take(2) {
            let (mut flagged, mut total) = (0usize, 0usize);
            for _ in 0..20_000 {
                let x: Vec<f64> = (0..n + 20).map(|_| rng.normal()).collect();
                let l = limits(&x[..n]).unwrap();
                let f = flags(&x, &l, &Rule::ALL);
                flagged += f[n..].iter().filter(|p| !p.is_empty()).count();
                total += 20;
            }
            let rate = flagged as f64 / total as f64;
            assert!(
                (rate - stated).abs() < 0.004,
                "reference {n}: {rate:.4}, stated {stated}"
            );
        }
        assert_eq!(all_rules_rate(19), None);
        assert_eq!(all_rules_rate(49), Some(0.054));
        assert_eq!(all_rules_rate(5000), Some(0.030));
    }

    #[test]
    fn limits_from_the_moving_range_and_rules_from_the_command_line() {
        let l = limits(&[1.0, 3.0, 2.0]).unwrap();
        assert_eq!(l.centre, 2.0);
        assert!((l.sigma - 1.5 / 1.128).abs() < 1e-12);
        assert!(limits(&[1.0]).is_none() && limits(&[2.0, 2.0]).is_none());
        // a |dg| near zero with a wide spread: the lower limit stops at zero, the
        // coefficients' limits are centre -+ 3 sigma
        let l = limits(&[0.05, 0.4, 0.1, 0.3]).unwrap();
        assert!(l.lower < 0.0);
        let dg = l.bounded(Quantity::WorstDg);
        assert_eq!((dg.lower, dg.upper), (0.0, l.upper));
        assert_eq!(l.bounded(Quantity::Coefficient(9)), l);
        assert_eq!(Quantity::Coefficient(9).unit("V"), "V");
        assert_eq!(Quantity::Coefficient(8).unit("V"), "V/g");
        assert_eq!(
            parse_rules("2,1, 2").unwrap(),
            [Rule::BeyondThree, Rule::NineOneSide]
        );
        assert_eq!(parse_rules("all").unwrap().len(), 8);
        let e = parse_rules("1,9").unwrap_err();
        assert!(e.message.contains("`9`"), "{e}");
    }
}
