//! The `plan --report` page: every candidate plan's predicted worst verification |dg|
//! against its chamber hours, each labelled as in `plan`'s table (A, B, ...), stops and
//! soaks and sweeps marked apart, those whose blob falls short of the range asked for
//! crossed out, the chosen plan ringed, the target drawn as a band; the plot drawn at its
//! own size (legible text on any desktop screen), the candidates' table above it.
use crate::error::Result;
use crate::plan::{Candidate, Kind, Limits, Target, COVER_TOLERANCE_C};
use crate::report::page::{esc, html as page, Section};
use crate::report::plot::{Band, Marker, Plot, Series, ACCEPT, FLOOR, PALETTE};

/// The plot's width and plotting height, px: drawn at this size, never scaled up.
pub const PLOT_SIZE: (u32, u32) = (960, 440);

/// The candidates `keep` selects as a labelled series.
fn series_of(
    c: &[Candidate],
    name: String,
    color: crate::report::plot::Rgb,
    marker: Marker,
    keep: &dyn Fn(&Candidate) -> bool,
) -> Option<Series> {
    let (points, labels): (Vec<(f64, f64)>, Vec<String>) = c
        .iter()
        .enumerate()
        .filter(|(_, x)| keep(x))
        .map(|(i, x)| ((x.hours, x.predicted_mg), Candidate::label(i)))
        .unzip();
    (!points.is_empty()).then(|| Series::markers(name, color, marker, points).with_labels(labels))
}

/// The candidates as an HTML table: label, plan, hours, prediction, lag, valid range.
fn candidates_table(c: &[Candidate], chosen: usize) -> String {
    let mut h = String::from(
        "<table class=\"verdicts\"><tr><th></th><th>plan</th><th>chamber h</th><th>predicted worst |dg|, mg</th><th>lag kept, s</th><th>blob valid over, C</th></tr>\n",
    );
    for (i, x) in c.iter().enumerate() {
        h.push_str(&format!(
            "<tr><td>{}{}</td><td>{}</td><td>{:.2}</td><td>{:.4}</td><td>{}</td><td>{}{}</td></tr>\n",
            if i == chosen { "* " } else { "" },
            Candidate::label(i),
            esc(&x.kind.describe()),
            x.hours,
            x.predicted_mg,
            x.lag_s.map_or("none".into(), |t| format!("{t:.0}")),
            x.valid_text(),
            match (x.covers, x.separates) {
                (true, true) => "",
                (false, _) => " (short of the range)",
                (true, false) => " (does not separate the diagnosis's coupled effects)",
            }
        ));
    }
    h.push_str("</table>");
    h
}

/// The page for `c` with `chosen` (an index of `c`) for `target` over the range of `l`.
pub fn html(c: &[Candidate], chosen: usize, target: Target, l: &Limits) -> Result<String> {
    let stop = |x: &Candidate| matches!(x.kind, Kind::StopSoak { .. });
    let mut series: Vec<Series> = [
        series_of(
            c,
            "stops and soaks".into(),
            PALETTE[1],
            Marker::Square,
            &|x| x.covers && x.separates && stop(x),
        ),
        series_of(
            c,
            "continuous sweeps".into(),
            PALETTE[2],
            Marker::Triangle,
            &|x| x.covers && x.separates && !stop(x),
        ),
        series_of(
            c,
            if l.separate.is_empty() {
                format!("blob short of {}..{} C (not chosen)", l.lo_c, l.hi_c)
            } else {
                format!(
                    "blob short of {}..{} C, or not separating the diagnosis's effects (not chosen)",
                    l.lo_c, l.hi_c
                )
            },
            FLOOR,
            Marker::Cross,
            &|x| !x.covers || !x.separates,
        ),
    ]
    .into_iter()
    .flatten()
    .collect();
    let mut bands = Vec::new();
    let what = match target {
        Target::AccuracyMg(mg) => {
            bands.push(Band {
                lo: 0.0,
                hi: mg,
                x: None,
                label: format!("target: worst |dg| <= {mg} mg"),
                color: ACCEPT,
                // the candidates' spread, not the band, sets the scale: a target far above
                // them would squeeze them into a line
                fit: false,
            });
            format!("the shortest predicted within {mg} mg")
        }
        Target::Hours(h) => {
            bands.push(Band {
                lo: 0.0,
                hi: f64::INFINITY,
                x: Some((0.0, h)),
                label: format!("target: at most {h} chamber hours"),
                color: ACCEPT,
                fit: false,
            });
            format!("the most accurate within {h} chamber hours")
        }
    };
    let ch = &c[chosen];
    let name = format!("{} {}", Candidate::label(chosen), ch.kind.describe());
    series.push(Series::markers(
        format!("chosen: {name}"),
        PALETTE[0],
        Marker::Ring,
        vec![(ch.hours, ch.predicted_mg)],
    ));
    let plot = Plot {
        id: "plan-accuracy-hours".into(),
        title: "Predicted worst verification |dg| against chamber hours".into(),
        x_label: "chamber hours (calibration program, verification block apart)".into(),
        y_label: "predicted worst verification |dg|, mg".into(),
        series,
        bands,
        width: PLOT_SIZE.0,
        height: PLOT_SIZE.1,
        natural: true,
        note: format!(
            "{} candidates tried on the twin, labelled as in the table below; chosen: {name} ({:.2} h, {:.4} mg, valid over {} C), {what}, among those whose blob covers {}..{} C within {COVER_TOLERANCE_C} C of each end.",
            c.len(),
            ch.hours,
            ch.predicted_mg,
            ch.valid_text(),
            l.lo_c,
            l.hi_c
        ),
        ..Plot::default()
    };
    page(
        "host-fit plan",
        &format!(
            "<p>{}</p>\n{}",
            esc("Each candidate program predicted from the fit covariance of the twin's recording of it (host-fit plan --json lists the figures); a candidate whose blob would not cover the range asked for is not chosen."),
            candidates_table(c, chosen)
        ),
        &[Section {
            head: "Accuracy against chamber hours".into(),
            text: format!("Chosen: {name}."),
            plots: vec![plot],
            pairs: false,
        }],
    )
}
