//! A plot: series and reference lines drawn to SVG by plotters (text left to the
//! browser, no system fonts needed), with its data beside it as JSON.
use crate::error::{HostError, Result};
use plotters::prelude::*;
use serde::Serialize;

/// One line of a plot: name, colour (#rrggbb) and points.
#[derive(Debug, Clone)]
pub struct Series {
    /// Legend text.
    pub name: String,
    /// Colour.
    pub color: RGBColor,
    /// (x, y) points.
    pub points: Vec<(f64, f64)>,
    /// Draw markers only (no line), e.g. identified values.
    pub markers: bool,
    /// Vertical error bars (1 sigma) at the points, same order.
    pub errors: Option<Vec<f64>>,
}

/// A plot: title, axes, series and horizontal reference lines.
#[derive(Debug, Clone)]
pub struct Plot {
    /// Element id in the HTML.
    pub id: String,
    /// Caption.
    pub title: String,
    /// x label.
    pub x_label: String,
    /// y label.
    pub y_label: String,
    /// The series.
    pub series: Vec<Series>,
    /// Horizontal lines (value, label), e.g. acceptance bands.
    pub hlines: Vec<(f64, String)>,
    /// Size in pixels.
    pub size: (u32, u32),
}

/// The colours series take in turn.
pub const PALETTE: [RGBColor; 8] = [
    RGBColor(0, 0, 0),
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
];

/// `#RRGGBB`.
pub fn hex(c: &RGBColor) -> String {
    format!("#{:02X}{:02X}{:02X}", c.0, c.1, c.2)
}

fn range(vals: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in vals.filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    let pad = ((hi - lo) * 0.08)
        .max(hi.abs().max(lo.abs()) * 1e-9)
        .max(1e-12);
    (lo - pad, hi + pad)
}

impl Plot {
    /// Render to SVG.
    pub fn svg(&self) -> Result<String> {
        let err = |e: &dyn std::fmt::Display| HostError::msg(format!("plot {}: {e}", self.id));
        let xs = range(
            self.series
                .iter()
                .flat_map(|s| s.points.iter().map(|p| p.0)),
        );
        let ys = range(
            self.series
                .iter()
                .flat_map(|s| {
                    let e = s.errors.clone().unwrap_or_default();
                    s.points.iter().enumerate().flat_map(move |(i, p)| {
                        let d = e.get(i).copied().unwrap_or(0.0);
                        [p.1 - d, p.1 + d]
                    })
                })
                .chain(self.hlines.iter().map(|h| h.0)),
        );
        let mut svg = String::new();
        {
            let root = SVGBackend::with_string(&mut svg, self.size).into_drawing_area();
            root.fill(&WHITE).map_err(|e| err(&e))?;
            let mut chart = ChartBuilder::on(&root)
                .caption(&self.title, ("sans-serif", 15))
                .margin(8)
                .x_label_area_size(34)
                .y_label_area_size(64)
                .build_cartesian_2d(xs.0..xs.1, ys.0..ys.1)
                .map_err(|e| err(&e))?;
            chart
                .configure_mesh()
                .x_desc(self.x_label.as_str())
                .y_desc(self.y_label.as_str())
                .light_line_style(RGBColor(235, 235, 235))
                .draw()
                .map_err(|e| err(&e))?;
            for (v, label) in &self.hlines {
                let style = RGBColor(150, 150, 150).stroke_width(1);
                let _ = label;
                chart
                    .draw_series(std::iter::once(PathElement::new(
                        vec![(xs.0, *v), (xs.1, *v)],
                        style,
                    )))
                    .map_err(|e| err(&e))?;
            }
            for s in &self.series {
                let c = s.color;
                if s.markers {
                    chart
                        .draw_series(s.points.iter().map(|p| Circle::new(*p, 3, c.filled())))
                        .map_err(|e| err(&e))?;
                    if let Some(e) = &s.errors {
                        chart
                            .draw_series(s.points.iter().zip(e).map(|(p, d)| {
                                ErrorBar::new_vertical(
                                    p.0,
                                    p.1 - d,
                                    p.1,
                                    p.1 + d,
                                    c.stroke_width(1),
                                    6,
                                )
                            }))
                            .map_err(|e| err(&e))?;
                    }
                } else {
                    chart
                        .draw_series(LineSeries::new(s.points.iter().copied(), c.stroke_width(2)))
                        .map_err(|e| err(&e))?;
                }
            }
            root.present().map_err(|e| err(&e))?;
        }
        Ok(svg)
    }

    /// The plot's data (embedded beside the SVG as JSON).
    pub fn data(&self) -> PlotData<'_> {
        PlotData {
            id: &self.id,
            title: &self.title,
            series: self
                .series
                .iter()
                .map(|s| SeriesData {
                    name: &s.name,
                    color: hex(&s.color),
                    markers: s.markers,
                    points: s.points.iter().map(|p| [p.0, p.1]).collect(),
                    errors: s.errors.as_deref(),
                })
                .collect(),
            hlines: self.hlines.iter().map(|h| h.0).collect(),
        }
    }
}

/// A plot's data as embedded in the page.
#[derive(Serialize)]
pub struct PlotData<'a> {
    id: &'a str,
    title: &'a str,
    series: Vec<SeriesData<'a>>,
    hlines: Vec<f64>,
}

#[derive(Serialize)]
struct SeriesData<'a> {
    name: &'a str,
    color: String,
    markers: bool,
    points: Vec<[f64; 2]>,
    errors: Option<&'a [f64]>,
}
