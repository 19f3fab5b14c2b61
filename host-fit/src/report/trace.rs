//! What both reports draw the same way: the axes' colours and markers, the time range,
//! and the unit's temperature against time (every sample, decimated per pixel column for
//! drawing).
use crate::data::recording::Recording;
use crate::report::plot::{Dash, Marker, Plot, Rgb, Series, PALETTE};

/// The axes' colours in the residual plots.
pub const AXIS_COLORS: [Rgb; 3] = [PALETTE[2], PALETTE[6], PALETTE[1]];

/// The axes' markers.
pub const AXIS_MARKERS: [Marker; 3] = [Marker::Circle, Marker::Square, Marker::Triangle];

/// The unit's temperature sensor against time, on the time range `span` (h).
pub fn temperature_plot(rec: &Recording, id: &str, span: Option<(f64, f64)>) -> Plot {
    let pts: Vec<(f64, f64)> = rec
        .rows
        .iter()
        .map(|r| (r.t_s / 3600.0, r.temp_c))
        .collect();
    let mut steps: Vec<f64> = pts.windows(2).map(|w| w[1].0 - w[0].0).collect();
    steps.sort_by(f64::total_cmp);
    let median = steps.get(steps.len() / 2).copied().unwrap_or(0.0);
    let mut s = Series::line(
        "unit temperature sensor",
        PALETTE[4],
        Dash::Solid,
        Marker::Diamond,
        pts,
    );
    s.gap = (median > 0.0).then_some(median * 20.0);
    Plot {
        id: id.into(),
        title: "unit temperature sensor".into(),
        x_label: "time, h".into(),
        y_label: "temperature, C".into(),
        x_range: span,
        series: vec![s],
        width: 1300,
        height: 180,
        wide: true,
        note: "Drawn from every sample (the lowest and highest of each pixel column); breaks mark gaps in the recording.".into(),
        ..Plot::default()
    }
}

/// The recording's time span, h, with a margin of 1% each side: the x range of every
/// plot against time, so that they line up.
pub fn time_span(rec: &Recording) -> (f64, f64) {
    let a = rec.rows.first().map_or(0.0, |r| r.t_s / 3600.0);
    let b = rec.rows.last().map_or(1.0, |r| r.t_s / 3600.0);
    let b = b.max(a + 1e-3);
    let m = (b - a) * 0.01;
    (a - m, b + m)
}
