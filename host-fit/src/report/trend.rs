//! The trend report: one control chart per coefficient at T0 and one of the worst
//! verification |dg|, units in time order, the reference period and every other lot
//! shaded, the centre line and the 3-sigma limits, each lot's mean, the points each run
//! rule flags in a series of their own (named by the rule), and a table of the flagged
//! units.
use crate::error::Result;
use crate::report::axis::prefixed;
use crate::report::page::{esc, html, Section};
use crate::report::plot::{Band, Dash, Marker, Plot, Rgb, Series, ACCEPT, FLOOR, PALETTE};
use crate::store::trend::{
    Chart, Limits, Quantity, Rule, Trend, ALL_RULES_BY_REFERENCE, ALL_RULES_FALSE_ALARM_RATE,
};

/// Flagged units listed per chart in the page (all of them: `host-fit trend --json`).
const LISTED_FLAGS: usize = 12;

/// Lot spans shaded (beyond it, lots interleave too finely to shade).
const SHADED_LOTS: usize = 400;

/// The bands: the reference period, every other lot, the control limits (through `y`).
fn bands(t: &Trend, limits: Option<Limits>, y: &dyn Fn(f64) -> f64) -> Vec<Band> {
    let mut b = Vec::new();
    if let (Some(a), Some(z)) = (t.reference_units.first(), t.reference_units.last()) {
        b.push(Band {
            lo: f64::NEG_INFINITY,
            hi: f64::INFINITY,
            x: Some((*a as f64 + 0.5, *z as f64 + 1.5)),
            label: "reference period".into(),
            color: FLOOR,
            fit: false,
        });
    }
    if t.lots.len() > 1 && t.lots.len() <= SHADED_LOTS {
        for (i, l) in t.lots.iter().enumerate().skip(1).step_by(2) {
            b.push(Band {
                lo: f64::NEG_INFINITY,
                hi: f64::INFINITY,
                x: Some((l.first as f64 + 0.5, l.last as f64 + 1.5)),
                label: if i == 1 {
                    "every other lot".into()
                } else {
                    String::new()
                },
                color: PALETTE[5],
                fit: false,
            });
        }
    }
    if let Some(l) = limits {
        let clipped = l.lower > l.centre - 3.0 * l.sigma;
        b.push(Band {
            lo: y(l.lower),
            hi: y(l.upper),
            x: None,
            label: if clipped {
                "control limits: centre ± 3 sigma, the lower at the bound".into()
            } else {
                "control limits: centre ± 3 sigma".into()
            },
            color: ACCEPT,
            fit: true,
        });
    }
    b
}

/// The recalibrations' colour.
const RECALIBRATED: Rgb = Rgb(200, 120, 0);

/// The lots' colour (apart from the palette's, which the rules use).
const LOT_MEANS: Rgb = Rgb(110, 60, 160);

/// Each lot's mean at the middle of its units, joined: what moves from lot to lot stays
/// visible where thousands of units fill the chart. None with fewer than two lots.
fn lot_means(t: &Trend, c: &Chart, y: &dyn Fn(f64) -> f64) -> Option<Series> {
    if t.lots.len() < 2 || t.lots.len() > SHADED_LOTS {
        return None;
    }
    let mut pts = Vec::new();
    let mut k = 0;
    for l in &t.lots {
        let (mut sum, mut n) = (0.0, 0usize);
        while k < c.points.len() && c.points[k].place <= l.last {
            if c.points[k].place >= l.first {
                sum += c.points[k].value;
                n += 1;
            }
            k += 1;
        }
        if n > 0 {
            pts.push((0.5 * (l.first + l.last) as f64 + 1.0, y(sum / n as f64)));
        }
    }
    let mut s = Series::line("lot means", LOT_MEANS, Dash::Solid, Marker::Diamond, pts);
    s.marker_every = 1;
    Some(s)
}

/// The points each rule flags, one series per rule that flags any, named by it.
fn flag_series(c: &Chart, y: &dyn Fn(f64) -> f64) -> Vec<Series> {
    let mut out = Vec::new();
    let shapes = [
        Marker::Triangle,
        Marker::Diamond,
        Marker::Cross,
        Marker::Square,
    ];
    for (i, r) in Rule::ALL.iter().enumerate() {
        let hits: Vec<(f64, f64)> = c
            .flags
            .iter()
            .filter(|f| f.rules.contains(&r.number()))
            .map(|f| (f.unit as f64 + 1.0, y(f.value)))
            .collect();
        if !hits.is_empty() {
            out.push(Series::markers(
                format!("{} ({})", r.name(), hits.len()),
                PALETTE[2 + i % 5],
                shapes[i % shapes.len()],
                hits,
            ));
        }
    }
    out
}

/// One chart as a plot. Coefficients are drawn as their departure from the centre line
/// in a prefixed unit (their digits differ far behind the point); |dg| as it is.
fn plot(t: &Trend, c: &Chart, wide: bool) -> Plot {
    let dg = c.quantity == Quantity::WorstDg;
    let centre = c.limits.map_or(0.0, |l| l.centre);
    let shift = if dg { 0.0 } else { centre };
    let max_dev = c
        .points
        .iter()
        .map(|p| (p.value - shift).abs())
        .chain(c.limits.map(|l| 3.0 * l.sigma))
        .fold(0.0, f64::max);
    let (k, unit) = if dg {
        (1.0, c.unit.clone())
    } else {
        prefixed(max_dev, &c.unit)
    };
    let y = |v: f64| (v - shift) * k;
    let pts: Vec<(f64, f64)> = c
        .points
        .iter()
        .map(|p| (p.place as f64 + 1.0, y(p.value)))
        .collect();
    let recal: Vec<(f64, f64)> = c
        .points
        .iter()
        .filter(|p| t.units[p.place].recalibration)
        .map(|p| (p.place as f64 + 1.0, y(p.value)))
        .collect();
    let n = pts.len();
    let mut units = Series::line(
        "calibrations in time order",
        PALETTE[0],
        Dash::Solid,
        Marker::Circle,
        pts,
    );
    if n <= 200 {
        units.marker_every = 1;
    }
    let mut series = vec![units];
    if !recal.is_empty() {
        series.push(Series::markers(
            format!("recalibrations: a unit calibrated again ({})", recal.len()),
            RECALIBRATED,
            Marker::Square,
            recal,
        ));
    }
    let x_end = t.unit_count as f64;
    if c.limits.is_some() {
        series.push(Series::line(
            "centre line: mean of the reference",
            PALETTE[1],
            Dash::Dashed,
            Marker::Square,
            vec![(1.0, y(centre)), (x_end, y(centre))],
        ));
    }
    if let Some(means) = lot_means(t, c, &y) {
        series.push(means);
    }
    series.extend(flag_series(c, &y));
    let flagged: Vec<String> = c
        .by_rule
        .iter()
        .filter(|r| r.1 > 0)
        .map(|(n, k)| format!("Nelson {n}: {k}"))
        .collect();
    let mut note = match c.limits {
        Some(l) => format!(
            "Centre {:.9} {u}, sigma {:.3e} {u} from {} reference calibrations, limits {:.6} to {:.6} {u}; flagged {}.",
            l.centre,
            l.sigma,
            l.points,
            l.lower,
            l.upper,
            if flagged.is_empty() {
                "none".to_string()
            } else {
                flagged.join(", ")
            },
            u = c.unit
        ),
        None => String::new(),
    };
    if let Some(extra) = &c.note {
        let mut c = extra.chars();
        let first: String = c
            .next()
            .map(|f| f.to_uppercase().collect())
            .unwrap_or_default();
        note.push_str(&format!(" {first}{}.", c.as_str()));
    }
    Plot {
        id: format!("trend-{}", c.quantity.name().replace('_', "-")),
        title: match (dg, c.limits) {
            (false, Some(l)) => format!("{} (centre {:.9} {})", c.title(), l.centre, c.unit),
            _ => c.title(),
        },
        x_label: "calibration, in time order (number)".into(),
        x_integer: true,
        y_label: if dg {
            format!("{}, {unit}", c.title())
        } else if c.limits.is_some() {
            format!("{} minus centre, {unit}", c.title())
        } else {
            format!("{}, {unit}", c.title())
        },
        x_range: Some((0.5, x_end + 0.5)),
        series,
        bands: bands(t, c.limits, &y),
        width: if wide { 1300 } else { 620 },
        height: if wide { 240 } else { 220 },
        wide,
        note: note.trim().to_string(),
        ..Plot::default()
    }
}

/// The flagged units per chart, as an HTML table: how many, by rule, and the first
/// [`LISTED_FLAGS`] with their rules (every one: `host-fit trend --json`).
fn flag_table(t: &Trend) -> String {
    if t.charts.iter().all(|c| c.flags.is_empty()) {
        return "<p>No point is flagged by the rules applied.</p>\n".into();
    }
    let mut s = String::from(
        "<p>Flagged units per chart (Nelson's rule numbers in brackets; `host-fit trend --json` lists every one with its value):</p>\n<table class=\"verdicts\">\n",
    );
    for c in t.charts.iter().filter(|c| !c.flags.is_empty()) {
        let by_rule: Vec<String> = c
            .by_rule
            .iter()
            .filter(|r| r.1 > 0)
            .map(|(n, k)| format!("Nelson {n}: {k}"))
            .collect();
        let first: Vec<String> = c
            .flags
            .iter()
            .take(LISTED_FLAGS)
            .map(|f| {
                let rules: Vec<String> = f.rules.iter().map(u8::to_string).collect();
                format!("{} ({})", f.serial, rules.join(","))
            })
            .collect();
        s.push_str(&format!(
            "<tr><td>{}</td><td>{}&#160;flagged</td><td>{}</td><td>{}{}</td></tr>\n",
            esc(&c.title()),
            c.flags.len(),
            esc(&by_rule.join(", ")),
            esc(&first.join(", ")),
            if c.flags.len() > LISTED_FLAGS {
                ", ..."
            } else {
                ""
            }
        ));
    }
    s.push_str("</table>\n");
    s
}

/// The trend report of `t`.
pub fn trend_report(t: &Trend) -> Result<String> {
    let lots: Vec<String> = t
        .lots
        .iter()
        .take(40)
        .map(|l| format!("{} (units {}-{})", l.lot, l.first + 1, l.last + 1))
        .collect();
    let intro = format!(
        "<p>Record store {}: {} calibrations in the order they were made, every one of each unit ({} recalibrations of a unit calibrated before, marked). Lots in that order: {}{}. Centre line and limits from {} ({} units): the centre is their mean, sigma their mean moving range / 1.128. Points are flagged by Nelson's run rules {}; on a stable process with its limits known each flags a point with probability {} (all eight together {:.2}%); limits estimated from 20, 50 or 100 reference units flag more: all eight together {}.</p>\n<pre>{}</pre>\n{}",
        esc(&t.store),
        t.unit_count,
        t.recalibrations,
        esc(&lots.join(", ")),
        if t.lots.len() > lots.len() {
            format!(" and {} more", t.lots.len() - lots.len())
        } else {
            String::new()
        },
        esc(&t.reference.text()),
        t.reference_units.len(),
        t.rules.iter().map(u8::to_string).collect::<Vec<_>>().join(", "),
        Rule::ALL
            .iter()
            .map(|r| format!("{:.2}% (Nelson {})", 100.0 * r.false_alarm_rate(), r.number()))
            .collect::<Vec<_>>()
            .join(", "),
        100.0 * ALL_RULES_FALSE_ALARM_RATE,
        ALL_RULES_BY_REFERENCE
            .iter()
            .map(|(n, r)| format!("{:.1}% ({n})", 100.0 * r))
            .collect::<Vec<_>>()
            .join(", "),
        esc(&t.text()),
        flag_table(t)
    );
    let (coeffs, dg): (Vec<&Chart>, Vec<&Chart>) = t
        .charts
        .iter()
        .partition(|c| c.quantity != Quantity::WorstDg);
    let dg_text = "The worst compensated |dg| over each calibration's verification dwells (formula (13)): a batch's own, or the first `verify` of that unit after it. |dg| is never below 0: no lower limit below 0 is drawn.";
    let drawn = |c: &&&Chart| !c.points.is_empty();
    let sections = [
        Section {
            head: "Verification".into(),
            text: if dg.iter().any(|c| drawn(&c)) {
                dg_text.into()
            } else {
                format!("{dg_text} No unit of the store has one (its records are fits or diagnoses only).")
            },
            plots: dg.iter().filter(drawn).map(|c| plot(t, c, true)).collect(),
            pairs: false,
        },
        Section {
            head: "The 12 coefficients at T0".into(),
            text: "Each coefficient at T0 minus the centre line, in time order; K in the recordings' output unit per g, U0 in it.".into(),
            plots: coeffs.iter().filter(drawn).map(|c| plot(t, c, false)).collect(),
            pairs: false,
        },
    ];
    html("Calibration trend across lots", &intro, &sections)
}
