//! A plot: named series (markers, lines, 1-sigma error bars), shaded bands (acceptance,
//! the floor) and a zero line, on a value or a category x axis. [`prepare`] fixes the
//! ranges and the layout and decimates long series to what the pixels can show (for
//! drawing only: the data fitted are never touched); the drawn data go beside the SVG as
//! JSON, so that a test can check the drawing against the numbers.
use crate::report::axis::{padded_range, round_down_125, text_px, Scale};
use serde::Serialize;

/// A colour.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Rgb(pub u8, pub u8, pub u8);

impl Rgb {
    /// `#RRGGBB`.
    pub fn hex(&self) -> String {
        format!("#{:02X}{:02X}{:02X}", self.0, self.1, self.2)
    }
}

/// Colours that stay apart for colour-blind readers (Okabe and Ito), black first.
pub const PALETTE: [Rgb; 7] = [
    Rgb(0, 0, 0),
    Rgb(0, 114, 178),
    Rgb(213, 94, 0),
    Rgb(230, 159, 0),
    Rgb(204, 121, 167),
    Rgb(86, 180, 233),
    Rgb(0, 158, 115),
];

/// The models' colours, in turn: Paul Tol's high-contrast scheme (blue, red, yellow),
/// then Okabe and Ito's sky blue. Every pair stays at least 20 apart (CIEDE2000) in
/// normal vision and in simulated protanopia, deuteranopia and tritanopia, and from
/// black (the T0 constants, the per-stop values); the browser test holds it. (Okabe
/// and Ito's vermillion and orange, the models' colours before, are 12.5 apart to a
/// deuteranope.)
pub const MODEL_COLORS: [Rgb; 4] = [
    Rgb(0, 68, 136),
    Rgb(187, 85, 102),
    Rgb(221, 170, 51),
    Rgb(86, 180, 233),
];

/// The truth's colour (a wide, light line under the models: a reference, not data).
pub const TRUTH: Rgb = Rgb(185, 185, 185);

/// The acceptance bands' green (darker than any series colour, drawn shaded).
pub const ACCEPT: Rgb = Rgb(26, 128, 54);
/// The floor band's grey.
pub const FLOOR: Rgb = Rgb(110, 110, 110);

/// A marker's shape.
#[derive(
    Clone,
    Copy,
    Debug,
    PartialEq,
    Eq,
    strum::Display,
    strum::EnumString,
    strum::IntoStaticStr,
    strum::EnumIter,
)]
#[strum(serialize_all = "lowercase")]
pub enum Marker {
    /// Filled circle.
    Circle,
    /// Filled square.
    Square,
    /// Filled triangle, point up.
    Triangle,
    /// Filled diamond.
    Diamond,
    /// A cross (x), stroked.
    Cross,
    /// An open ring, wider than the other markers: drawn around points of another
    /// series to mark them (held-out dwells).
    Ring,
    /// No marker: a line only (a reference such as the truth, which is not data).
    None,
}

impl Marker {
    /// The shapes in turn.
    pub const ALL: [Marker; 5] = [
        Marker::Circle,
        Marker::Triangle,
        Marker::Square,
        Marker::Diamond,
        Marker::Cross,
    ];

    /// Name in the JSON.
    pub fn name(self) -> &'static str {
        self.into()
    }
}

/// A line's dash pattern.
#[derive(
    Clone,
    Copy,
    Debug,
    PartialEq,
    Eq,
    strum::Display,
    strum::EnumString,
    strum::IntoStaticStr,
    strum::EnumIter,
)]
#[strum(serialize_all = "lowercase")]
pub enum Dash {
    /// Solid.
    Solid,
    /// Long dashes.
    Dashed,
    /// Dots.
    Dotted,
    /// Dash and dot.
    DashDot,
}

impl Dash {
    /// Name in the JSON.
    pub fn name(self) -> &'static str {
        self.into()
    }

    /// The SVG `stroke-dasharray` (none for solid).
    pub fn dasharray(self) -> Option<&'static str> {
        match self {
            Dash::Solid => None,
            Dash::Dashed => Some("7 4"),
            Dash::Dotted => Some("2 3"),
            Dash::DashDot => Some("8 3 2 3"),
        }
    }
}

/// One series: its points with markers (every `marker_every`-th), optionally joined by a
/// line, optionally with 1-sigma error bars.
#[derive(Debug, Clone)]
pub struct Series {
    /// Legend text.
    pub name: String,
    /// Colour.
    pub color: Rgb,
    /// (x, y) points; on a category axis x is the category's index (plus an offset).
    pub points: Vec<(f64, f64)>,
    /// The line joining the points, if any.
    pub line: Option<Dash>,
    /// The marker's shape.
    pub marker: Marker,
    /// A marker on every n-th point (1: all).
    pub marker_every: usize,
    /// 1-sigma error bars at the points, same order.
    pub errors: Option<Vec<f64>>,
    /// The line breaks where consecutive x differ by more than this (gaps in time).
    pub gap: Option<f64>,
    /// The line's width, px.
    pub width: f64,
    /// Labels drawn beside the points, same order (empty: none); a labelled series is
    /// never thinned.
    pub labels: Vec<String>,
}

impl Series {
    /// Points with markers, no line.
    pub fn markers(
        name: impl Into<String>,
        color: Rgb,
        marker: Marker,
        points: Vec<(f64, f64)>,
    ) -> Series {
        Series {
            name: name.into(),
            color,
            points,
            line: None,
            marker,
            marker_every: 1,
            errors: None,
            gap: None,
            width: 2.0,
            labels: Vec::new(),
        }
    }

    /// A line with about ten markers along it (so that the legend names it even where
    /// lines cross or overlap).
    pub fn line(
        name: impl Into<String>,
        color: Rgb,
        dash: Dash,
        marker: Marker,
        points: Vec<(f64, f64)>,
    ) -> Series {
        let every = (points.len() / 10).max(1);
        Series {
            marker_every: every,
            line: Some(dash),
            ..Series::markers(name, color, marker, points)
        }
    }

    /// A reference curve, not data (the twin's truth): a wide light line without
    /// markers, drawn under the series that follow it so that both show where they
    /// coincide.
    pub fn reference(name: impl Into<String>, color: Rgb, points: Vec<(f64, f64)>) -> Series {
        Series {
            line: Some(Dash::Solid),
            width: 7.0,
            ..Series::markers(name, color, Marker::None, points)
        }
    }

    /// With 1-sigma error bars.
    pub fn with_errors(mut self, e: Vec<f64>) -> Series {
        self.errors = Some(e);
        self
    }

    /// With a label beside each point.
    pub fn with_labels(mut self, labels: Vec<String>) -> Series {
        self.labels = labels;
        self
    }
}

/// A shaded band between two values (an acceptance band, the floor), over all x or
/// over `x`; `fit`: the y range is widened to show its edges.
#[derive(Debug, Clone)]
pub struct Band {
    /// Lower edge (may be -inf).
    pub lo: f64,
    /// Upper edge (may be +inf).
    pub hi: f64,
    /// Its x extent, or all of the axis.
    pub x: Option<(f64, f64)>,
    /// Legend text (and the label at its edge); empty: none.
    pub label: String,
    /// Colour.
    pub color: Rgb,
    /// Whether the y range must show its edges.
    pub fit: bool,
}

/// A plot.
#[derive(Debug, Clone, Default)]
pub struct Plot {
    /// Element id in the HTML.
    pub id: String,
    /// Title (drawn in the SVG).
    pub title: String,
    /// x axis label: quantity, unit.
    pub x_label: String,
    /// y axis label: quantity, unit.
    pub y_label: String,
    /// Category names: a category axis, category i at x = i.
    pub x_names: Vec<String>,
    /// Fixed x range (plots that must align in time share it).
    pub x_range: Option<(f64, f64)>,
    /// The x axis counts things (units, runs): whole-number ticks only.
    pub x_integer: bool,
    /// Fixed y range (plots compared side by side share it).
    pub y_range: Option<(f64, f64)>,
    /// log10 y axis.
    pub y_log: bool,
    /// The series.
    pub series: Vec<Series>,
    /// Shaded bands.
    pub bands: Vec<Band>,
    /// A line at y = 0.
    pub zero_line: bool,
    /// Width of the drawing, px (it is scaled to its place on the page).
    pub width: u32,
    /// Height of the plotting area, px (legend and labels come on top of it).
    pub height: u32,
    /// Spans the page's width.
    pub wide: bool,
    /// Spans two columns of the page's grid (where it has two or more).
    pub double: bool,
    /// Drawn across the page's grid but never wider than `width`: its text keeps its
    /// size in px on any screen wide enough (a lone plot read closely).
    pub natural: bool,
    /// A sentence under the plot.
    pub note: String,
}

/// Left margin of every plot (tick labels and the y label): the same everywhere so that
/// plots stacked on a page line up.
pub const LEFT: f64 = 78.0;
/// Right margin.
pub const RIGHT: f64 = 20.0;
/// Above the plotting area (the title).
pub const TOP: f64 = 34.0;
/// Below the plotting area: tick labels and the x label, before the legend.
pub const BELOW: f64 = 48.0;
/// Where the legend's rows start.
pub const LEGEND_LEFT: f64 = 14.0;
/// Height of a legend row.
pub const LEGEND_ROW: f64 = 18.0;
/// Legend text size, px.
pub const LEGEND_FONT: f64 = 12.0;

/// One legend entry: what it names and where it sits.
#[derive(Debug, Clone)]
pub struct LegendItem {
    /// A series (its index) or a band (its index).
    pub of: Legend,
    /// Left edge, px.
    pub x: f64,
    /// Baseline of its row, px.
    pub y: f64,
}

/// What a legend entry names.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Legend {
    /// Series `i`.
    Series(usize),
    /// Band `i`.
    Band(usize),
}

/// A plot ready to draw: the drawn (possibly decimated) series, the scales, the legend.
#[derive(Debug, Clone)]
pub struct Prepared {
    /// The plot with its series as drawn.
    pub plot: Plot,
    /// Points of each series before decimation.
    pub points_in_data: Vec<usize>,
    /// x scale.
    pub x: Scale,
    /// y scale.
    pub y: Scale,
    /// Legend entries.
    pub legend: Vec<LegendItem>,
    /// Width and height of the whole drawing, px.
    pub size: (f64, f64),
}

/// A y range for `vals` with the margin every plot gives (for plots that share one).
pub fn padded_y(vals: impl Iterator<Item = f64>) -> (f64, f64) {
    padded_range(vals, 0.07, false)
}

fn ranges(p: &Plot) -> ((f64, f64), (f64, f64)) {
    let pts = || p.series.iter().flat_map(|s| s.points.iter());
    let x = if !p.x_names.is_empty() {
        // a margin so that the outermost categories' markers stay whole
        let m = 0.01 * p.x_names.len() as f64;
        (-0.5 - m, p.x_names.len() as f64 - 0.5 + m)
    } else if let Some(r) = p.x_range {
        r
    } else {
        padded_range(
            pts()
                .map(|q| q.0)
                .chain(p.bands.iter().filter_map(|b| b.x).flat_map(|x| [x.0, x.1])),
            0.03,
            false,
        )
    };
    let y = p.y_range.unwrap_or_else(|| {
        let errs = p.series.iter().flat_map(|s| {
            let e = s.errors.clone().unwrap_or_default();
            s.points.iter().enumerate().flat_map(move |(i, q)| {
                let d = e.get(i).copied().unwrap_or(0.0);
                [q.1 - d, q.1 + d]
            })
        });
        let bands = p
            .bands
            .iter()
            .filter(|b| b.fit)
            .flat_map(|b| [b.lo, b.hi])
            .filter(|v| v.is_finite());
        let zero = p.zero_line.then_some(0.0);
        let (lo, hi) = padded_range(errs.chain(bands).chain(zero), 0.07, p.y_log);
        // a log axis starts at a round value (1, 2 or 5 times a power of ten) at or
        // below the data, so that the lowest data have a labelled tick under them
        (if p.y_log { round_down_125(lo) } else { lo }, hi)
    });
    (x, y)
}

fn legend(p: &Plot, top: f64) -> (Vec<LegendItem>, f64) {
    let w = f64::from(p.width);
    let entries = (0..p.series.len())
        .map(|i| (Legend::Series(i), p.series[i].name.as_str()))
        .chain(
            p.bands
                .iter()
                .enumerate()
                .filter(|b| !b.1.label.is_empty())
                .map(|(i, b)| (Legend::Band(i), b.label.as_str())),
        );
    let (mut x, mut y) = (LEGEND_LEFT, top + LEGEND_FONT);
    let mut out = Vec::new();
    for (of, name) in entries {
        let need = 34.0 + text_px(name, LEGEND_FONT) + 16.0;
        if x > LEGEND_LEFT && x + need > w - 4.0 {
            x = LEGEND_LEFT;
            y += LEGEND_ROW;
        }
        out.push(LegendItem { of, x, y });
        x += need;
    }
    (out, y + 8.0)
}

/// Thin a markers-only series to one point per 2 px cell (what is drawn looks the same:
/// markers are more than three times as wide), keeping the first in each cell.
fn thin_markers(points: &[(f64, f64)], x: &Scale, y: &Scale) -> Vec<(f64, f64)> {
    let mut seen = std::collections::HashSet::new();
    points
        .iter()
        .filter(|q| {
            let cell = (
                (x.px(q.0) / 2.0).round() as i64,
                (y.px(q.1) / 2.0).round() as i64,
            );
            seen.insert(cell)
        })
        .copied()
        .collect()
}

/// Thin a line to the first, lowest, highest and last point of every column of two
/// pixels, in their order (the drawn line, 2 px wide, covers the same pixels).
fn thin_line(points: &[(f64, f64)], x: &Scale) -> Vec<(f64, f64)> {
    let mut out: Vec<(f64, f64)> = Vec::new();
    let mut i = 0;
    while i < points.len() {
        let col = (x.px(points[i].0) / 2.0).floor();
        let mut j = i;
        while j < points.len() && (x.px(points[j].0) / 2.0).floor() == col {
            j += 1;
        }
        let run = &points[i..j];
        let lo = (0..run.len()).min_by(|a, b| run[*a].1.total_cmp(&run[*b].1));
        let hi = (0..run.len()).max_by(|a, b| run[*a].1.total_cmp(&run[*b].1));
        let mut keep: Vec<usize> = [Some(0), lo, hi, Some(run.len() - 1)]
            .into_iter()
            .flatten()
            .collect();
        keep.sort_unstable();
        keep.dedup();
        out.extend(keep.iter().map(|k| run[*k]));
        i = j;
    }
    out
}

/// Ranges, layout and decimation: the plot as it will be drawn.
pub fn prepare(p: &Plot) -> Prepared {
    let ((x0, x1), (y0, y1)) = ranges(p);
    let w = f64::from(p.width);
    let h = f64::from(p.height);
    let x = Scale {
        lo: x0,
        hi: x1,
        p0: LEFT,
        p1: w - RIGHT,
        log: false,
    };
    let y = Scale {
        lo: y0,
        hi: y1,
        p0: TOP + h,
        p1: TOP,
        log: p.y_log,
    };
    let mut plot = p.clone();
    let points_in_data = p.series.iter().map(|s| s.points.len()).collect();
    for s in &mut plot.series {
        if s.errors.is_some() || !s.labels.is_empty() {
            continue;
        }
        if s.line.is_none() && s.points.len() > 400 {
            s.points = thin_markers(&s.points, &x, &y);
        } else if s.line.is_some() && s.points.len() as f64 > x.span_px() {
            let every = s.points.len() / s.marker_every.max(1);
            s.points = thin_line(&s.points, &x);
            s.marker_every = (s.points.len() / every.max(1)).max(1);
            // thinned points lie up to two columns apart: a gap is wider than that
            let columns = 3.0 * 2.0 * (x.hi - x.lo) / x.span_px();
            s.gap = s.gap.map(|g| g.max(columns));
        }
    }
    let (legend, bottom) = legend(&plot, TOP + h + BELOW);
    Prepared {
        plot,
        points_in_data,
        x,
        y,
        legend,
        size: (w, bottom),
    }
}

/// A plot's drawn data, as embedded beside its SVG.
#[derive(Serialize)]
pub struct PlotData<'a> {
    id: &'a str,
    title: &'a str,
    x_label: &'a str,
    y_label: &'a str,
    x_names: &'a [String],
    y_log: bool,
    series: Vec<SeriesData<'a>>,
    bands: Vec<BandData<'a>>,
}

#[derive(Serialize)]
struct SeriesData<'a> {
    name: &'a str,
    color: String,
    line: Option<&'static str>,
    marker: &'static str,
    marker_every: usize,
    width: f64,
    points: Vec<[f64; 2]>,
    points_in_data: usize,
    errors: Option<&'a [f64]>,
    #[serde(skip_serializing_if = "<[String]>::is_empty")]
    labels: &'a [String],
}

#[derive(Serialize)]
struct BandData<'a> {
    lo: Option<f64>,
    hi: Option<f64>,
    label: &'a str,
}

/// Series longer than this are stored to 1/100000 of their axis (exactly below it).
pub const EXACT_UP_TO: usize = 50;

/// `v` to about 1/100000 of `span` (or six significant digits on a log axis), as the
/// shortest decimal that reads back the same.
fn rounded(v: f64, span: f64, log: bool) -> f64 {
    let s = if log {
        format!("{v:.5e}")
    } else {
        let d = (-(span.abs() / 1e5).log10().floor()).clamp(0.0, 15.0) as usize;
        format!("{v:.d$}")
    };
    s.parse().unwrap_or(v)
}

/// The points as stored in the JSON: exact for short series, rounded far below a pixel
/// for long ones (the page stays small).
fn stored(points: &[(f64, f64)], x: &Scale, y: &Scale) -> Vec<[f64; 2]> {
    if points.len() <= EXACT_UP_TO {
        return points.iter().map(|q| [q.0, q.1]).collect();
    }
    points
        .iter()
        .map(|q| {
            [
                rounded(q.0, x.hi - x.lo, false),
                rounded(q.1, y.hi - y.lo, y.log),
            ]
        })
        .collect()
}

impl Prepared {
    /// The drawn data (embedded beside the SVG as JSON).
    pub fn data(&self) -> PlotData<'_> {
        let p = &self.plot;
        PlotData {
            id: &p.id,
            title: &p.title,
            x_label: &p.x_label,
            y_label: &p.y_label,
            x_names: &p.x_names,
            y_log: p.y_log,
            series: p
                .series
                .iter()
                .zip(&self.points_in_data)
                .map(|(s, n)| SeriesData {
                    name: &s.name,
                    color: s.color.hex(),
                    line: s.line.map(Dash::name),
                    marker: s.marker.name(),
                    marker_every: s.marker_every,
                    width: s.width,
                    points: stored(&s.points, &self.x, &self.y),
                    points_in_data: *n,
                    errors: s.errors.as_deref(),
                    labels: &s.labels,
                })
                .collect(),
            bands: p
                .bands
                .iter()
                .map(|b| BandData {
                    lo: b.lo.is_finite().then_some(b.lo),
                    hi: b.hi.is_finite().then_some(b.hi),
                    label: &b.label,
                })
                .collect(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plot(series: Vec<Series>) -> Plot {
        Plot {
            id: "t".into(),
            width: 600,
            height: 200,
            series,
            ..Plot::default()
        }
    }

    #[test]
    fn long_series_are_thinned_for_drawing_only_where_pixels_coincide() {
        let n = 100_000;
        let trace: Vec<(f64, f64)> = (0..n)
            .map(|i| (i as f64, (i as f64 / 500.0).sin()))
            .collect();
        let p = prepare(&plot(vec![Series::line(
            "trace",
            PALETTE[1],
            Dash::Solid,
            Marker::Circle,
            trace.clone(),
        )]));
        let drawn = &p.plot.series[0].points;
        assert!(drawn.len() <= 4 * 252, "{}", drawn.len());
        assert_eq!(p.points_in_data, vec![n]);
        // the extremes survive
        let max = |v: &[(f64, f64)]| v.iter().map(|q| q.1).fold(f64::MIN, f64::max);
        assert_eq!(max(drawn), max(&trace));
        let scatter: Vec<(f64, f64)> = (0..5000)
            .map(|i| ((i % 50) as f64, (i % 7) as f64))
            .collect();
        let p = prepare(&plot(vec![Series::markers(
            "s",
            PALETTE[2],
            Marker::Square,
            scatter,
        )]));
        assert_eq!(p.plot.series[0].points.len(), 50 * 7);
        // a short series is drawn as it is
        let p = prepare(&plot(vec![Series::markers(
            "s",
            PALETTE[2],
            Marker::Square,
            vec![(0.0, 1.0), (0.0, 1.0)],
        )]));
        assert_eq!(p.plot.series[0].points.len(), 2);
    }

    #[test]
    fn the_legend_wraps_inside_the_width() {
        let s: Vec<Series> = (0..12)
            .map(|i| {
                Series::markers(
                    format!("a fairly long series name {i}"),
                    PALETTE[i % 7],
                    Marker::Circle,
                    vec![(0.0, 0.0)],
                )
            })
            .collect();
        let p = prepare(&plot(s));
        assert_eq!(p.legend.len(), 12);
        for e in &p.legend {
            assert!(e.x + 34.0 + text_px("a fairly long series name 10", LEGEND_FONT) <= 600.0);
        }
        assert!(p.size.1 > f64::from(p.plot.height) + TOP + BELOW + 3.0 * LEGEND_ROW);
    }
}
