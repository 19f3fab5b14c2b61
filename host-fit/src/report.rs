//! The engineer's report: one self-contained HTML file with SVG plots (plotters' SVG
//! backend: text is left to the browser, no system fonts needed). Every plot's data is
//! embedded beside it as JSON, so a test can check the drawing against the numbers.
use crate::demo::{DemoModel, DemoOutcome};
use crate::error::{HostError, Result};
use crate::identify::{K_INDEX, U0_INDEX};
use firmware_core::model::COEFF_NAMES;
use plotters::prelude::*;
use serde_json::{json, Value};

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

const PALETTE: [RGBColor; 8] = [
    RGBColor(0, 0, 0),
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
];

fn hex(c: &RGBColor) -> String {
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

    /// The plot's data as JSON (embedded beside the SVG).
    pub fn data(&self) -> Value {
        json!({
            "id": self.id,
            "title": self.title,
            "series": self.series.iter().map(|s| json!({
                "name": s.name, "color": hex(&s.color), "markers": s.markers,
                "points": s.points.iter().map(|p| [p.0, p.1]).collect::<Vec<_>>(),
                "errors": s.errors,
            })).collect::<Vec<_>>(),
            "hlines": self.hlines.iter().map(|h| h.0).collect::<Vec<_>>(),
        })
    }
}

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// A whole HTML page from sections of (heading, text, plots).
pub fn html(title: &str, intro: &str, sections: &[(String, String, Vec<Plot>)]) -> Result<String> {
    let mut h = String::new();
    h.push_str("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\"/>\n");
    h.push_str(&format!("<title>{}</title>\n", esc(title)));
    h.push_str("<style>body{font-family:sans-serif;margin:24px;max-width:1400px}figure{display:inline-block;margin:6px;vertical-align:top}pre{background:#f6f6f6;padding:8px}</style>\n</head>\n<body>\n");
    h.push_str(&format!("<h1>{}</h1>\n{}\n", esc(title), intro));
    for (head, text, plots) in sections {
        h.push_str(&format!("<h2>{}</h2>\n<p>{}</p>\n", esc(head), esc(text)));
        for p in plots {
            h.push_str(&format!(
                "<figure id=\"{}\">\n{}\n<figcaption>",
                p.id,
                p.svg()?
            ));
            for s in &p.series {
                let mark = if s.markers { "&#9679;" } else { "&#9644;" };
                h.push_str(&format!(
                    "<span style=\"color:{}\">{mark}</span> {} &#160; ",
                    hex(&s.color),
                    esc(&s.name)
                ));
            }
            for (v, label) in p.hlines.iter().filter(|h| !h.1.is_empty()) {
                h.push_str(&format!(
                    "<span style=\"color:#969696\">&#9644;</span> {} ({v}) ",
                    esc(label)
                ));
            }
            h.push_str("</figcaption>\n");
            let data =
                serde_json::to_string(&p.data()).map_err(|e| HostError::msg(e.to_string()))?;
            h.push_str(&format!(
                "<script type=\"application/json\" class=\"plot-data\">{}</script>\n</figure>\n",
                data.replace("</", "<\\/")
            ));
        }
    }
    h.push_str("</body>\n</html>\n");
    Ok(h)
}

fn dg_plots(oc: &DemoOutcome) -> Vec<Plot> {
    let Some(first) = oc.models.first() else {
        return Vec::new();
    };
    let temps: Vec<f64> = first.verifications[0]
        .max_by_temperature
        .iter()
        .map(|t| t.temp_c)
        .collect();
    let mut plots = Vec::new();
    for (ti, t) in temps.iter().enumerate() {
        let pos_x = |name: &str| name.trim_start_matches("PP").parse::<f64>().unwrap_or(0.0);
        let near = |m: &DemoModel, k: usize| -> Vec<(f64, f64, f64)> {
            m.verifications[k]
                .dwells
                .iter()
                .filter(|d| (d.temp_c - t).abs() <= 2.5)
                .map(|d| (pos_x(&d.position), d.dg_mg_uncompensated, d.dg_mg))
                .collect()
        };
        let mut series = vec![Series {
            name: "T0 constants".into(),
            color: PALETTE[0],
            points: near(first, 0).iter().map(|p| (p.0, p.1)).collect(),
            markers: false,
            errors: None,
        }];
        let mut ci = 1;
        for m in &oc.models {
            for (k, mname) in [(0, "method 1"), (1, "method 2")] {
                series.push(Series {
                    name: format!("{} {mname}", m.name),
                    color: PALETTE[ci % PALETTE.len()],
                    points: near(m, k).iter().map(|p| (p.0, p.2)).collect(),
                    markers: false,
                    errors: None,
                });
                ci += 1;
            }
        }
        let band = if (t - oc.recording.t0_c).abs() < 2.5 {
            0.3
        } else {
            1.0
        };
        plots.push(Plot {
            id: format!("dg-{ti}"),
            title: format!("dg at {t:.1} C"),
            x_label: "verification position PPn".into(),
            y_label: "dg, mg".into(),
            series,
            hlines: vec![
                (band, format!("+-{band} mg acceptance")),
                (-band, String::new()),
            ],
            size: (640, 400),
        });
    }
    plots
}

fn coeff_plots(oc: &DemoOutcome) -> Vec<Plot> {
    let (lo, hi) = oc
        .models
        .first()
        .map(|m| m.fit.t_range)
        .unwrap_or((-40.0, 70.0));
    let grid: Vec<f64> = (0..=110)
        .map(|k| lo + (hi - lo) * k as f64 / 110.0)
        .collect();
    let mut plots = Vec::new();
    for c in 0..12 {
        let (scale, unit) = if c >= 9 { (1e3, "mV") } else { (1e3, "mV/g") };
        let mut series = vec![Series {
            name: "per-stop (10)".into(),
            color: PALETTE[0],
            points: oc
                .stops
                .iter()
                .map(|s| (s.temp_c, s.coeffs[c] * scale))
                .collect(),
            markers: true,
            errors: Some(oc.stops.iter().map(|s| s.stderr[c] * scale).collect()),
        }];
        if let Some(truth) = &oc.truth {
            series.push(Series {
                name: "truth".into(),
                color: PALETTE[6],
                points: grid
                    .iter()
                    .map(|t| (*t, truth.coeffs(*t)[c] * scale))
                    .collect(),
                markers: false,
                errors: None,
            });
        }
        for (i, m) in oc.models.iter().enumerate() {
            series.push(Series {
                name: m.name.clone(),
                color: PALETTE[(i + 1) % PALETTE.len()],
                points: grid
                    .iter()
                    .map(|t| (*t, m.fit.eval(*t)[c] * scale))
                    .collect(),
                markers: false,
                errors: None,
            });
        }
        plots.push(Plot {
            id: format!("coeff-{}", COEFF_NAMES[c]),
            title: COEFF_NAMES[c].to_string(),
            x_label: "temperature, C".into(),
            y_label: unit.into(),
            series,
            hlines: Vec::new(),
            size: (460, 320),
        });
    }
    plots
}

/// Residual of every static dwell (all positions) against a model, per axis, in uV,
/// with the temperature trace.
fn residual_plots(oc: &DemoOutcome, model: &DemoModel) -> Vec<Plot> {
    let rec = &oc.recording;
    let mut axes: [Vec<(f64, f64)>; 3] = Default::default();
    for d in &rec.dwells {
        if d.len() > 120 {
            continue; // rests through ramps and soaks: shown in the temperature trace
        }
        let rows = rec.dwell_rows(d);
        let t_mid = rows.iter().map(|r| r.t_s).sum::<f64>() / rows.len().max(1) as f64 / 3600.0;
        let c = model.fit.eval(d.temp_c);
        let a = rec.positions.vector(d.position);
        for i in 0..3 {
            let pred = c[K_INDEX[i][0]] * a[0]
                + c[K_INDEX[i][1]] * a[1]
                + c[K_INDEX[i][2]] * a[2]
                + c[U0_INDEX[i]];
            axes[i].push((t_mid, (d.u_mean[i] - pred) * 1e6));
        }
    }
    let names = ["x", "y", "z"];
    let series = axes
        .iter()
        .enumerate()
        .map(|(i, p)| Series {
            name: format!("axis {}", names[i]),
            color: PALETTE[i + 1],
            points: p.clone(),
            markers: true,
            errors: None,
        })
        .collect();
    let step = (rec.rows.len() / 600).max(1);
    let temp: Vec<(f64, f64)> = rec
        .rows
        .iter()
        .step_by(step)
        .map(|r| (r.t_s / 3600.0, r.temp_c))
        .collect();
    vec![
        Plot {
            id: "residual-time".into(),
            title: format!("dwell-mean residual against {}", model.name),
            x_label: "time, h".into(),
            y_label: "residual, uV".into(),
            series,
            hlines: vec![(0.0, String::new())],
            size: (1100, 360),
        },
        Plot {
            id: "temperature-time".into(),
            title: "unit temperature sensor".into(),
            x_label: "time, h".into(),
            y_label: "temp, C".into(),
            series: vec![Series {
                name: "temp_c".into(),
                color: PALETTE[4],
                points: temp,
                markers: false,
                errors: None,
            }],
            hlines: Vec::new(),
            size: (1100, 240),
        },
    ]
}

/// The demo's report.
pub fn demo_report(oc: &DemoOutcome, table: &str) -> Result<String> {
    let intro = format!(
        "<p>Unit {}, {} samples. Models: {}. Compensation by firmware-core in f32 (methods 1 and 2).</p>\n<pre>{}</pre>",
        esc(&oc.recording.unit),
        oc.recording.rows.len(),
        oc.models.iter().map(|m| esc(&m.name)).collect::<Vec<_>>().join(", "),
        esc(table)
    );
    let best = oc
        .models
        .iter()
        .min_by(|a, b| worst(a).total_cmp(&worst(b)));
    let mut sections = vec![
        ("dg in the verification positions (formula (13))".to_string(), "Per temperature: uncompensated (T0 constants) and every model with methods 1 and 2; the acceptance band is 0.3 mg at T0 and 1 mg elsewhere.".to_string(), dg_plots(oc)),
        ("The 12 coefficients against temperature".to_string(), "Per-stop identification by formula (10) with 1-sigma error bars (from the in-dwell noise), the simulated truth (when simulated), and each fitted temperature model.".to_string(), coeff_plots(oc)),
    ];
    if let Some(b) = best {
        sections.push(("Residuals against time".to_string(), format!("Dwell means minus the {} model at the dwell's temperature; below, the temperature trace.", b.name), residual_plots(oc, b)));
    }
    html("Temperature calibration report", &intro, &sections)
}

fn worst(m: &DemoModel) -> f64 {
    m.verifications[0]
        .max_by_temperature
        .iter()
        .map(|t| t.max_abs_dg_mg)
        .fold(0.0, f64::max)
}

/// The diagnosis report: residuals against time, temperature and position, before and
/// after the findings.
pub fn diagnosis_report(
    rec: &crate::recording::Recording,
    d: &crate::diagnose::Diagnosis,
) -> Result<String> {
    let mut plots = Vec::new();
    for (tag, fit) in [("before", &d.baseline), ("after", &d.final_fit)] {
        let per_axis = |x: &dyn Fn(usize) -> f64| -> Vec<Series> {
            (0..3)
                .map(|i| Series {
                    name: format!("axis {}", ["x", "y", "z"][i]),
                    color: PALETTE[i + 1],
                    points: d
                        .obs
                        .iter()
                        .enumerate()
                        .map(|(r, _)| (x(r), fit.resid[r][i]))
                        .collect(),
                    markers: true,
                    errors: None,
                })
                .collect()
        };
        plots.push(Plot {
            id: format!("resid-time-{tag}"),
            title: format!("residual against time, {tag}"),
            x_label: "time, h".into(),
            y_label: format!("residual, {}", rec.output_unit),
            series: per_axis(&|r| d.obs[r].t_s / 3600.0),
            hlines: vec![(0.0, String::new())],
            size: (900, 300),
        });
        plots.push(Plot {
            id: format!("resid-temp-{tag}"),
            title: format!("residual against temperature, {tag}"),
            x_label: "temperature, C".into(),
            y_label: format!("residual, {}", rec.output_unit),
            series: per_axis(&|r| d.obs[r].temp_c),
            hlines: vec![(0.0, String::new())],
            size: (600, 300),
        });
        plots.push(Plot {
            id: format!("resid-pos-{tag}"),
            title: format!("residual against position index, {tag}"),
            x_label: "position (index in the positions list)".into(),
            y_label: format!("residual, {}", rec.output_unit),
            series: per_axis(&|r| d.obs[r].position as f64),
            hlines: vec![(0.0, String::new())],
            size: (600, 300),
        });
    }
    let step = (rec.rows.len() / 800).max(1);
    plots.push(Plot {
        id: "temperature".into(),
        title: "temperature sensor".into(),
        x_label: "time, h".into(),
        y_label: "C".into(),
        series: vec![Series {
            name: "temp_c".into(),
            color: PALETTE[4],
            points: rec
                .rows
                .iter()
                .step_by(step)
                .map(|r| (r.t_s / 3600.0, r.temp_c))
                .collect(),
            markers: false,
            errors: None,
        }],
        hlines: Vec::new(),
        size: (900, 220),
    });
    let j = d.json(rec);
    let intro = format!(
        "<p>Recording {}.</p>\n<pre>{}</pre>",
        esc(&rec.path.display().to_string()),
        esc(&crate::diagnose::text(&j))
    );
    html("Diagnosis", &intro, &[("Residuals before and after".to_string(), "Window means minus the baseline model (before) and the final model with the findings (after); below, the temperature.".to_string(), plots)])
}
