//! A prepared plot drawn as SVG, by hand: every part is an element with a class the
//! tests can find (`title`, `x-label`, `y-label`, `tick`, `band`, `series` with its
//! `line`, `errors` and `markers`, `legend-entry`), coordinates to 0.1 px, text left to
//! the browser (no fonts needed here). A series' markers are one path through their
//! centres with an SVG `<marker>` at every vertex.
use crate::report::axis::{category_stride, integer_ticks, linear_ticks, log_ticks, text_px};
use crate::report::plot::{
    Band, Legend, Marker, Prepared, Series, BELOW, LEFT, LEGEND_FONT, RIGHT, TOP,
};
use std::fmt::Write;

/// Escaped for HTML and SVG text and attributes.
pub fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// A coordinate to 0.1 px, without a trailing `.0`.
fn f(v: f64) -> String {
    let s = format!("{:.1}", v);
    let s = s.strip_suffix(".0").unwrap_or(&s).to_string();
    if s == "-0" {
        "0".into()
    } else {
        s
    }
}

const GRID: &str = "#E4E4E4";
const AXIS: &str = "#444444";
const FONT: &str = "DejaVu Sans, Verdana, Arial, sans-serif";

/// The plot as an SVG element.
pub fn svg(p: &Prepared) -> String {
    let (w, h) = p.size;
    let id = &p.plot.id;
    let mut o = String::new();
    let _ = write!(
        o,
        r#"<svg xmlns="http://www.w3.org/2000/svg" class="plot" viewBox="0 0 {w} {h}" width="{w}" height="{h}" font-family="{FONT}">"#,
        w = f(w),
        h = f(h)
    );
    let (x0, x1, y0, y1) = (LEFT, w - RIGHT, p.y.p1, p.y.p0);
    let _ = write!(
        o,
        r#"<defs><clipPath id="clip-{id}"><rect x="{}" y="{}" width="{}" height="{}"/></clipPath></defs>"#,
        f(x0),
        f(y0),
        f(x1 - x0),
        f(y1 - y0)
    );
    let _ = write!(
        o,
        r##"<rect x="0" y="0" width="{}" height="{}" fill="#FFFFFF"/><text class="title" x="{}" y="{}" font-size="14" font-weight="bold" text-anchor="middle">{}</text>"##,
        f(w),
        f(h),
        f((x0 + x1) / 2.0),
        f(TOP - 13.0),
        esc(&p.plot.title)
    );
    ticks(p, &mut o);
    let _ = write!(o, r#"<g clip-path="url(#clip-{id})">"#);
    for (i, b) in p.plot.bands.iter().enumerate() {
        band(p, i, b, &mut o);
    }
    if p.plot.zero_line && p.y.lo < 0.0 && p.y.hi > 0.0 {
        let y = f(p.y.px(0.0));
        let _ = write!(
            o,
            r##"<path class="zero" d="M{} {y}H{}" stroke="#777777" stroke-width="1"/>"##,
            f(x0),
            f(x1)
        );
    }
    for (i, s) in p.plot.series.iter().enumerate() {
        series(p, i, s, &mut o);
    }
    o.push_str("</g>");
    point_labels(p, &mut o);
    let _ = write!(
        o,
        r#"<rect x="{}" y="{}" width="{}" height="{}" fill="none" stroke="{AXIS}" stroke-width="1"/>"#,
        f(x0),
        f(y0),
        f(x1 - x0),
        f(y1 - y0)
    );
    let _ = write!(
        o,
        r#"<text class="x-label" x="{}" y="{}" font-size="12" text-anchor="middle">{}</text>"#,
        f((x0 + x1) / 2.0),
        f(y1 + BELOW - 12.0),
        esc(&p.plot.x_label)
    );
    let _ = write!(
        o,
        r#"<text class="y-label" transform="translate(16 {}) rotate(-90)" font-size="12" text-anchor="middle">{}</text>"#,
        f((y0 + y1) / 2.0),
        esc(&p.plot.y_label)
    );
    legend(p, &mut o);
    o.push_str("</svg>");
    o
}

/// Grid lines and tick labels of both axes.
fn ticks(p: &Prepared, o: &mut String) {
    let (x0, x1, y0, y1) = (LEFT, p.size.0 - RIGHT, p.y.p1, p.y.p0);
    let yt = if p.y.log {
        log_ticks(p.y.lo, p.y.hi, y1 - y0)
    } else {
        linear_ticks(p.y.lo, p.y.hi, y1 - y0, 42.0)
    };
    for (v, l) in yt {
        let y = f(p.y.px(v));
        let _ = write!(
            o,
            r#"<path d="M{} {y}H{}" stroke="{GRID}" stroke-width="1"/><text class="tick y" x="{}" y="{}" font-size="11" text-anchor="end">{}</text>"#,
            f(x0),
            f(x1),
            f(x0 - 6.0),
            f(p.y.px(v) + 4.0),
            esc(&l)
        );
    }
    let names = &p.plot.x_names;
    let xt: Vec<(f64, String)> = if names.is_empty() {
        let widest = text_px(&format!("{:.3}", p.x.hi.abs().max(p.x.lo.abs())), 11.0);
        if p.plot.x_integer {
            integer_ticks(p.x.lo, p.x.hi, x1 - x0, (widest + 24.0).max(70.0))
        } else {
            linear_ticks(p.x.lo, p.x.hi, x1 - x0, (widest + 24.0).max(70.0))
        }
    } else {
        let widest = names.iter().map(|n| text_px(n, 11.0)).fold(0.0, f64::max);
        let k = category_stride(names.len(), x1 - x0, widest);
        // lines between the categories, where they are few enough to tell apart
        for i in (1..names.len()).filter(|_| names.len() <= 60) {
            let x = f(p.x.px(i as f64 - 0.5));
            let _ = write!(
                o,
                r#"<path d="M{x} {}V{}" stroke="{GRID}" stroke-width="1"/>"#,
                f(y0),
                f(y1)
            );
        }
        names
            .iter()
            .enumerate()
            .filter(|(i, _)| i % k == 0)
            .map(|(i, n)| (i as f64, n.clone()))
            .collect()
    };
    for (v, l) in xt {
        let x = f(p.x.px(v));
        if names.is_empty() {
            let _ = write!(
                o,
                r#"<path d="M{x} {}V{}" stroke="{GRID}" stroke-width="1"/>"#,
                f(y0),
                f(y1)
            );
        }
        let _ = write!(
            o,
            r#"<path d="M{x} {}v5" stroke="{AXIS}" stroke-width="1"/><text class="tick x" x="{x}" y="{}" font-size="11" text-anchor="middle">{}</text>"#,
            f(y1),
            f(y1 + 17.0),
            esc(&l)
        );
    }
}

/// A band's shaded area and its edges (those inside the plot).
fn band(p: &Prepared, i: usize, b: &Band, o: &mut String) {
    let (x0, x1) = match b.x {
        Some((a, c)) => (p.x.px(a).max(LEFT), p.x.px(c).min(p.size.0 - RIGHT)),
        None => (LEFT, p.size.0 - RIGHT),
    };
    let clamp = |v: f64| p.y.px(v.clamp(p.y.lo, p.y.hi));
    let (ya, yb) = (clamp(b.hi), clamp(b.lo));
    let c = b.color.hex();
    let _ = write!(
        o,
        r#"<g class="band" data-band="{i}"><rect x="{}" y="{}" width="{}" height="{}" fill="{c}" fill-opacity="0.12"/>"#,
        f(x0),
        f(ya),
        f((x1 - x0).max(0.0)),
        f((yb - ya).max(0.0))
    );
    for v in [b.lo, b.hi] {
        if v.is_finite() && v > p.y.lo && v < p.y.hi {
            let _ = write!(
                o,
                r#"<path class="band-edge" d="M{} {}H{}" stroke="{c}" stroke-width="1.5" stroke-dasharray="6 3"/>"#,
                f(x0),
                f(p.y.px(v)),
                f(x1)
            );
        }
    }
    o.push_str("</g>");
}

/// One marker's path: it starts at the marker's centre (`M x y`), so a reader of the SVG
/// finds where each marker is.
fn marker(m: Marker, x: f64, y: f64, r: f64) -> String {
    let (x, y) = (f(x), f(y));
    match m {
        Marker::Circle | Marker::Square => format!("M{x} {y}h0"),
        Marker::Triangle => format!(
            "M{x} {y}m0 {}l{} {}h{}z",
            f(-1.25 * r),
            f(1.08 * r),
            f(1.9 * r),
            f(-2.16 * r)
        ),
        Marker::Diamond => format!(
            "M{x} {y}m0 {m}l{d} {d} {m} {d} {m} {m}z",
            d = f(1.25 * r),
            m = f(-1.25 * r)
        ),
        Marker::Cross => format!(
            "M{x} {y}m{a} {a}l{b} {b}m0 {c}l{c} {b}",
            a = f(-r),
            b = f(2.0 * r),
            c = f(-2.0 * r)
        ),
        Marker::Ring => format!(
            "M{x} {y}m{m} 0a{r} {r} 0 1 0 {d} 0a{r} {r} 0 1 0 {m2} 0",
            m = f(-RING * r),
            r = f(RING * r),
            d = f(2.0 * RING * r),
            m2 = f(-2.0 * RING * r)
        ),
        Marker::None => format!("M{x} {y}"),
    }
}

/// A ring's radius, in marker radii: it encloses the marker it marks.
const RING: f64 = 1.9;

/// The attributes that draw a marker of shape `m` as a path (in the legend).
fn marker_style(m: Marker, c: &str, r: f64, opacity: f64) -> String {
    match m {
        Marker::Circle | Marker::Square => format!(
            r#"fill="none" stroke="{c}" stroke-opacity="{opacity}" stroke-width="{}" stroke-linecap="{}""#,
            f(2.0 * r),
            if m == Marker::Circle {
                "round"
            } else {
                "square"
            }
        ),
        Marker::Triangle | Marker::Diamond => {
            format!(r#"fill="{c}" fill-opacity="{opacity}" stroke="none""#)
        }
        Marker::Cross => format!(r#"fill="none" stroke="{c}" stroke-width="1.8""#),
        Marker::Ring => format!(r#"fill="none" stroke="{c}" stroke-width="1.6""#),
        Marker::None => r#"fill="none" stroke="none""#.to_string(),
    }
}

/// A series' marker as an SVG `<marker>` (drawn at every vertex of the markers path:
/// about 11 bytes a point whatever the shape).
fn marker_def(id: &str, m: Marker, c: &str, r: f64, opacity: f64) -> String {
    let shape = match m {
        Marker::Circle => format!(r#"<circle r="{}"/>"#, f(r)),
        Marker::Square => format!(
            r#"<rect x="{a}" y="{a}" width="{w}" height="{w}"/>"#,
            a = f(-r * 0.9),
            w = f(r * 1.8)
        ),
        Marker::Ring => format!(r#"<circle r="{}"/>"#, f(RING * r)),
        Marker::Triangle | Marker::Diamond | Marker::Cross | Marker::None => {
            format!(r#"<path d="{}"/>"#, marker(m, 0.0, 0.0, r))
        }
    };
    let paint = match m {
        Marker::Cross => format!(r#"fill="none" stroke="{c}" stroke-width="1.8""#),
        Marker::Ring => format!(r#"fill="none" stroke="{c}" stroke-width="1.6""#),
        Marker::Circle | Marker::Square | Marker::Triangle | Marker::Diamond | Marker::None => {
            format!(r#"fill="{c}" fill-opacity="{opacity}""#)
        }
    };
    format!(
        r#"<marker id="{id}" viewBox="-6 -6 12 12" markerWidth="12" markerHeight="12" markerUnits="userSpaceOnUse" overflow="visible"><g {paint}>{shape}</g></marker>"#
    )
}

fn series(p: &Prepared, i: usize, s: &Series, o: &mut String) {
    let c = s.color.hex();
    let px: Vec<(f64, f64)> = s
        .points
        .iter()
        .map(|q| (p.x.px(q.0), p.y.px(q.1)))
        .collect();
    let _ = write!(o, r#"<g class="series" data-series="{i}">"#);
    if let Some(dash) = s.line {
        let mut d = String::new();
        for (k, (q, v)) in px.iter().zip(&s.points).enumerate() {
            let gap = k > 0 && s.gap.is_some_and(|g| v.0 - s.points[k - 1].0 > g);
            // after a moveto, further pairs are linetos
            let cmd = if k == 0 || gap { "M" } else { " " };
            let _ = write!(d, "{cmd}{} {}", f(q.0), f(q.1));
        }
        let dash = dash
            .dasharray()
            .map(|a| format!(r#" stroke-dasharray="{a}""#))
            .unwrap_or_default();
        let _ = write!(
            o,
            r#"<path class="line" d="{d}" fill="none" stroke="{c}" stroke-width="{}" stroke-linejoin="round"{dash}/>"#,
            f(s.width)
        );
    }
    if let Some(e) = &s.errors {
        let mut d = String::new();
        for (v, sd) in s.points.iter().zip(e) {
            let (x, a, b) = (p.x.px(v.0), p.y.px(v.1 - sd), p.y.px(v.1 + sd));
            let _ = write!(
                d,
                "M{x} {a}V{b}M{l} {a}h8M{l} {b}h8",
                x = f(x),
                a = f(a),
                b = f(b),
                l = f(x - 4.0)
            );
        }
        let _ = write!(
            o,
            r#"<path class="errors" d="{d}" fill="none" stroke="{c}" stroke-width="1.3"/>"#
        );
    }
    if s.marker == Marker::None {
        o.push_str("</g>");
        return;
    }
    let r = if s.line.is_some() { 3.2 } else { 3.4 };
    let opacity = if s.line.is_none() && s.points.len() > 200 {
        0.7
    } else {
        1.0
    };
    let id = format!("mk-{}-{i}", p.plot.id);
    let mut d = String::new();
    for (k, q) in px.iter().step_by(s.marker_every.max(1)).enumerate() {
        let _ = write!(d, "{}{} {}", if k == 0 { "M" } else { " " }, f(q.0), f(q.1));
    }
    let _ = write!(
        o,
        r#"<defs>{}</defs><path class="markers" data-marker="{}" d="{d}" fill="none" stroke="none" marker-start="url(#{id})" marker-mid="url(#{id})" marker-end="url(#{id})"/></g>"#,
        marker_def(&id, s.marker, &c, r, opacity),
        s.marker.name()
    );
}

/// Size of the labels beside points, px.
pub const POINT_LABEL_FONT: f64 = 13.0;

/// A text's box `[left, top, right, bottom]` from its left end and baseline, px, with a
/// margin of a pixel (the browser's box includes the font's ascent and descent).
fn text_box(x: f64, baseline: f64, width: f64, size: f64) -> [f64; 4] {
    [
        x - 1.0,
        baseline - size - 1.0,
        x + width + 1.0,
        baseline + 0.3 * size + 1.0,
    ]
}

fn meets(a: &[f64; 4], b: &[f64; 4]) -> bool {
    a[0] < b[2] && b[0] < a[2] && a[1] < b[3] && b[1] < a[3]
}

/// The labels of the labelled series beside their points: each at the first of a few
/// spots (right, left, above, below, then further out) whose box meets neither a
/// label placed before nor a labelled point's marker and stays inside the plotting area
/// (at the first spot inside it when none is free).
fn point_labels(p: &Prepared, o: &mut String) {
    let size = POINT_LABEL_FONT;
    let area = [LEFT, p.y.p1, p.size.0 - RIGHT, p.y.p0];
    let points: Vec<(f64, f64, &str)> = p
        .plot
        .series
        .iter()
        .flat_map(|s| s.points.iter().zip(&s.labels))
        .map(|(q, l)| (p.x.px(q.0), p.y.px(q.1), l.as_str()))
        .collect();
    if points.is_empty() {
        return;
    }
    // every labelled point's marker, a ring's width about it
    let mut taken: Vec<[f64; 4]> = points
        .iter()
        .map(|(x, y, _)| [x - 7.0, y - 7.0, x + 7.0, y + 7.0])
        .collect();
    o.push_str(r#"<g class="point-labels">"#);
    for (x, y, label) in points {
        // bold: a tenth wider than the estimate for regular text
        let w = 1.1 * text_px(label, size);
        let spots = (1..=5).flat_map(|k| {
            // the first spot clears a ring about the point (the chosen one)
            let d = 5.0 + 4.0 * f64::from(k);
            [
                (x + d, y + 0.35 * size),
                (x - d - w, y + 0.35 * size),
                (x - w / 2.0, y - d),
                (x - w / 2.0, y + d + 0.7 * size),
                (x + d, y - d),
                (x - d - w, y + d + 0.7 * size),
            ]
        });
        let inside =
            |b: &[f64; 4]| b[0] >= area[0] && b[1] >= area[1] && b[2] <= area[2] && b[3] <= area[3];
        let mut first_inside = None;
        let mut chosen = None;
        for (lx, ly) in spots {
            let b = text_box(lx, ly, w, size);
            if !inside(&b) {
                continue;
            }
            first_inside.get_or_insert((lx, ly, b));
            if !taken.iter().any(|t| meets(t, &b)) {
                chosen = Some((lx, ly, b));
                break;
            }
        }
        let Some((lx, ly, b)) = chosen.or(first_inside) else {
            continue;
        };
        taken.push(b);
        let _ = write!(
            o,
            r#"<text class="point-label" x="{}" y="{}" font-size="{size}" font-weight="bold">{}</text>"#,
            f(lx),
            f(ly),
            esc(label)
        );
    }
    o.push_str("</g>");
}

/// The legend under the x label: a sample of each series' line and marker, a swatch of
/// each labelled band, and their names.
fn legend(p: &Prepared, o: &mut String) {
    o.push_str(r#"<g class="legend">"#);
    for e in &p.legend {
        let (x, y) = (e.x, e.y);
        let ym = y - 4.0;
        let (attr, sample, name) = match e.of {
            Legend::Series(i) => {
                let s = &p.plot.series[i];
                let c = s.color.hex();
                let mut g = String::new();
                if let Some(dash) = s.line {
                    let da = dash
                        .dasharray()
                        .map(|a| format!(r#" stroke-dasharray="{a}""#))
                        .unwrap_or_default();
                    let _ = write!(
                        g,
                        r#"<path d="M{} {}h28" stroke="{c}" stroke-width="{}"{da}/>"#,
                        f(x),
                        f(ym),
                        f(s.width)
                    );
                }
                let _ = write!(
                    g,
                    r#"<path d="{}" {}/>"#,
                    marker(s.marker, x + 14.0, ym, 3.4),
                    marker_style(s.marker, &c, 3.4, 1.0)
                );
                (format!(r#"data-series="{i}""#), g, &s.name)
            }
            Legend::Band(i) => {
                let b = &p.plot.bands[i];
                let c = b.color.hex();
                let g = format!(
                    r#"<rect x="{}" y="{}" width="28" height="12" fill="{c}" fill-opacity="0.12" stroke="{c}" stroke-width="1.5" stroke-dasharray="6 3"/>"#,
                    f(x),
                    f(ym - 6.0)
                );
                (format!(r#"data-band="{i}""#), g, &b.label)
            }
        };
        let _ = write!(
            o,
            r#"<g class="legend-entry" {attr}>{sample}<text x="{}" y="{}" font-size="{LEGEND_FONT}">{}</text></g>"#,
            f(x + 34.0),
            f(y),
            esc(name)
        );
    }
    o.push_str("</g>");
}
