//! The diagnosis report: window-mean residuals against time (above the temperature, on
//! the same time axis), against temperature and against position (by name), before and
//! after the findings, each pair on one scale so that what the findings explain shows,
//! with the band the noise alone would fill.
use crate::data::recording::Recording;
use crate::diagnose::Diagnosis;
use crate::error::Result;
use crate::model::solve::Fit;
use crate::report::axis::prefixed;
use crate::report::page::{esc, html, Section};
use crate::report::plot::{padded_y, Band, Plot, Series, FLOOR};
use crate::report::trace::{temperature_plot, time_span, AXIS_COLORS, AXIS_MARKERS};
use firmware_core::model::AXES;

/// How the residuals are drawn: the output unit's prefix, the shared y range, the floor.
struct Frame {
    /// Multiplier to the prefixed unit.
    k: f64,
    /// The prefixed unit.
    unit: String,
    /// y range shared by before and after.
    y: (f64, f64),
    /// Half-width of the floor band (prefixed unit).
    floor: f64,
}

fn frame(rec: &Recording, d: &Diagnosis) -> Frame {
    let all = || {
        d.baseline
            .resid
            .iter()
            .chain(&d.final_fit.resid)
            .flat_map(|r| r.iter().copied())
    };
    let max_abs = all().fold(0.0f64, |a, v| a.max(v.abs()));
    let (k, unit) = prefixed(max_abs, rec.output_unit.as_str());
    let floor = 2.0 * d.noise_rms * k;
    let y = padded_y(all().map(|v| v * k).chain([floor, -floor]));
    Frame { k, unit, y, floor }
}

/// The three axes' residuals of `fit` against `x` (one value per observation), nudged
/// sideways by `dodge` per axis (on a category axis).
fn per_axis(fit: &Fit, fr: &Frame, x: &dyn Fn(usize) -> f64, dodge: f64) -> Vec<Series> {
    (0..3)
        .map(|i| {
            Series::markers(
                format!("axis {}", AXES[i]),
                AXIS_COLORS[i],
                AXIS_MARKERS[i],
                fit.resid
                    .iter()
                    .enumerate()
                    .map(|(r, v)| (x(r) + dodge * (i as f64 - 1.0), v[i] * fr.k))
                    .collect(),
            )
        })
        .collect()
}

fn floor_band(fr: &Frame) -> Band {
    Band {
        lo: -fr.floor,
        hi: fr.floor,
        x: None,
        label: "floor: ±2x the RMS of the noise alone".into(),
        color: FLOOR,
        fit: true,
    }
}

/// The positions observed, by name, in the positions list's order; and each
/// observation's category.
fn position_axis(rec: &Recording, d: &Diagnosis) -> (Vec<String>, Vec<f64>) {
    let mut used: Vec<usize> = d.data.obs.iter().map(|o| o.position).collect();
    used.sort_unstable();
    used.dedup();
    let names = used
        .iter()
        .map(|p| rec.positions.name(*p).to_string())
        .collect();
    let cat = d
        .data
        .obs
        .iter()
        .map(|o| used.binary_search(&o.position).unwrap_or(0) as f64)
        .collect();
    (names, cat)
}

/// The residual plots of `fit`; `tag`: `before` or `after` the findings, or empty when
/// the final model is the baseline.
fn plots_of(rec: &Recording, d: &Diagnosis, fr: &Frame, tag: &str, fit: &Fit) -> [Plot; 3] {
    let (id, when) = if tag.is_empty() {
        ("model".to_string(), String::new())
    } else {
        (tag.to_string(), format!(", {tag} the findings"))
    };
    let t = |r: usize| d.data.obs[r].t_s / 3600.0;
    let span = time_span(rec);
    let (names, cat) = position_axis(rec, d);
    let many = names.len() > 24;
    let y_label = format!("residual, {}", fr.unit);
    let base = Plot {
        y_label: y_label.clone(),
        y_range: Some(fr.y),
        bands: vec![floor_band(fr)],
        zero_line: true,
        ..Plot::default()
    };
    [
        Plot {
            id: format!("resid-time-{id}"),
            title: format!("residual against time{when}"),
            x_label: "time, h".into(),
            x_range: Some(span),
            series: per_axis(fit, fr, &t, 0.0),
            width: 1300,
            height: 230,
            wide: true,
            ..base.clone()
        },
        Plot {
            id: format!("resid-temp-{id}"),
            title: format!("residual against temperature{when}"),
            x_label: "temperature, C".into(),
            series: per_axis(fit, fr, &|r| d.data.obs[r].temp_c, 0.0),
            width: 620,
            height: 260,
            ..base.clone()
        },
        Plot {
            id: format!("resid-pos-{id}"),
            title: format!("residual against position{when}"),
            x_label: if many {
                format!("position ({} positions, not every name shown)", names.len())
            } else {
                "position".into()
            },
            x_names: names,
            series: per_axis(fit, fr, &|r| cat[r], if many { 0.0 } else { 0.18 }),
            width: if many { 1300 } else { 620 },
            height: 260,
            wide: many,
            ..base
        },
    ]
}

/// The diagnosis report: residuals against time, temperature and position, before and
/// after the findings.
pub fn diagnosis_report(d: &Diagnosis) -> Result<String> {
    let rec = d.recording();
    let fr = frame(rec, d);
    let temp = temperature_plot(rec, "temperature", Some(time_span(rec)));
    // with nothing found the final model is the baseline: its residuals once
    let same = d
        .baseline
        .resid
        .iter()
        .zip(&d.final_fit.resid)
        .all(|(a, b)| a == b);
    let (time, by_temp, by_pos) = if same {
        let [t, te, p] = plots_of(rec, d, &fr, "", &d.baseline);
        // alone, they take the page's width
        let wide = |p: Plot| Plot {
            wide: true,
            width: 1300,
            ..p
        };
        (vec![t, temp], vec![wide(te)], vec![wide(p)])
    } else {
        let [bt, btemp, bpos] = plots_of(rec, d, &fr, "before", &d.baseline);
        let [at, atemp, apos] = plots_of(rec, d, &fr, "after", &d.final_fit);
        (vec![bt, at, temp], vec![btemp, atemp], vec![bpos, apos])
    };
    let contract = d.contract();
    let intro = format!(
        "<p>Recording {}: {} samples, output in {}; {} window means of static positions. Verdict: <b>{}</b>.</p>\n<pre>{}</pre>",
        esc(&rec.path.display().to_string()),
        rec.rows.len(),
        esc(rec.output_unit.as_str()),
        d.data.obs.len(),
        esc(contract.verdict.as_str()),
        esc(&contract.text())
    );
    let sections = [
        Section {
            head: "Residuals against time".into(),
            text: if same {
                "Window means minus the model (nothing found: the final model is the baseline), per axis; the grey band is what the noise alone would fill. Below, on the same time axis, the temperature.".into()
            } else {
                "Window means minus the baseline model (before) and minus the final model with the findings (after), per axis, on one scale; the grey band is what the noise alone would fill. Below, on the same time axis, the temperature.".into()
            },
            plots: time,
            pairs: false,
        },
        Section {
            head: "Residuals against temperature".into(),
            text: "The same residuals against the window's temperature.".into(),
            plots: by_temp,
            pairs: true,
        },
        Section {
            head: "Residuals against position".into(),
            text: "The same residuals per position, by name (the axes side by side in each)."
                .into(),
            plots: by_pos,
            pairs: true,
        },
    ];
    html("Diagnosis", &intro, &sections)
}
