//! The `plan --report` page: every candidate plan's predicted worst verification |dg|
//! against its chamber hours, stops and soaks and sweeps marked apart, the chosen plan
//! ringed, the target drawn as a band.
use crate::error::Result;
use crate::plan::{Candidate, Kind, Target};
use crate::report::page::{esc, html as page, Section};
use crate::report::plot::{Band, Marker, Plot, Series, ACCEPT, PALETTE};

/// The page for `c` with `chosen` (an index of `c`) for `target`.
pub fn html(c: &[Candidate], chosen: usize, target: Target) -> Result<String> {
    let pts = |stop: bool| -> Vec<(f64, f64)> {
        c.iter()
            .filter(|x| matches!(x.kind, Kind::StopSoak { .. }) == stop)
            .map(|x| (x.hours, x.predicted_mg))
            .collect()
    };
    let mut series = vec![
        Series::markers("stops and soaks", PALETTE[1], Marker::Square, pts(true)),
        Series::markers(
            "continuous sweeps",
            PALETTE[2],
            Marker::Triangle,
            pts(false),
        ),
    ];
    let mut bands = Vec::new();
    let what = match target {
        Target::AccuracyMg(mg) => {
            bands.push(Band {
                lo: 0.0,
                hi: mg,
                x: None,
                label: format!("target: worst |dg| <= {mg} mg"),
                color: ACCEPT,
                fit: true,
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
    series.push(Series::markers(
        format!("chosen: {}", ch.kind.describe()),
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
        width: 700,
        height: 320,
        note: format!(
            "{} candidates tried on the twin; chosen: {} ({:.2} h, {:.4} mg), {what}.",
            c.len(),
            ch.kind.describe(),
            ch.hours,
            ch.predicted_mg
        ),
        ..Plot::default()
    };
    page(
        "host-fit plan",
        &format!(
            "<p>{}</p>",
            esc("Each candidate program predicted from the fit covariance of the twin's recording of it (host-fit plan --json lists the figures).")
        ),
        &[Section {
            head: "Accuracy against chamber hours".into(),
            text: format!("Chosen: {}.", ch.kind.describe()),
            plots: vec![plot],
            pairs: false,
        }],
    )
}
