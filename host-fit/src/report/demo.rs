//! The demo's report (and `report`'s, for any recording): the compensation error in the
//! verification positions against the acceptance specification (worst per temperature on
//! a log scale, uncompensated in a panel of its own, compensated per temperature on its
//! own scale), the 12 coefficients against temperature and their departures from the
//! truth (or from the chosen model) with 1-sigma error bars, residuals against time above
//! the temperature.
use crate::acceptance::{Spec, Verdict};
use crate::analysis::{
    names_text, verification_names, Compared, Compensation, DemoModel, DemoOutcome, T0_CONSTANTS,
};
use crate::data::positions::Role;
use crate::error::Result;
use crate::report::axis::prefixed;
use crate::report::page::{esc, html, Section};
use crate::report::plot::{
    Band, Dash, Marker, Plot, Rgb, Series, ACCEPT, MODEL_COLORS, PALETTE, TRUTH,
};
use crate::report::trace::{temperature_plot, time_span, AXIS_COLORS, AXIS_MARKERS};
use firmware_core::model::{AXES, COEFF_NAMES, K_INDEX, U0_INDEX};

/// A model's colour: the same in every plot, told apart at a glance ([`MODEL_COLORS`]).
fn model_color(i: usize) -> Rgb {
    MODEL_COLORS[i % MODEL_COLORS.len()]
}

/// The legend name of the per-stop values (formula (10) at each stop), and with their
/// error bars.
const PER_STOP: [&str; 2] = [
    "identified at each stop (formula (10))",
    "identified at each stop (formula (10), ±1 sigma)",
];

/// Method 1 and 2: marker and line.
const METHODS: [(usize, Compensation, Marker, Dash); 2] = [
    (0, Compensation::Method1, Marker::Circle, Dash::Solid),
    (1, Compensation::Method2, Marker::Triangle, Dash::Dashed),
];

/// Sideways offset of series `k` of `n` within a category (so equal values stay visible).
fn dodge(k: usize, n: usize) -> f64 {
    if n < 2 {
        return 0.0;
    }
    (k as f64 - (n as f64 - 1.0) / 2.0) * 0.64 / n as f64
}

/// The verification positions' names, in the recording's order.
fn positions(oc: &DemoOutcome) -> Vec<String> {
    let mut names: Vec<String> = Vec::new();
    for m in &oc.models {
        for d in &m.verifications[0].dwells {
            if !names.contains(&d.position) {
                names.push(d.position.clone());
            }
        }
    }
    names
}

/// The limit at temperature `t`, mg.
fn limit(spec: &Spec, t0: f64, t: f64) -> f64 {
    if (t - t0).abs() <= spec.t0_band_c {
        spec.t0_mg
    } else {
        spec.range_mg
    }
}

fn accept_band(spec: &Spec, lim: f64, fit: bool) -> Band {
    let what = if lim == spec.t0_mg {
        format!("T0 ±{} C", spec.t0_band_c)
    } else {
        "valid range".to_string()
    };
    Band {
        lo: -lim,
        hi: lim,
        x: None,
        label: format!("acceptance ±{lim} mg ({what})"),
        color: ACCEPT,
        fit,
    }
}

/// Worst |dg| per temperature, every model and method and the T0 constants, on a log
/// scale under the acceptance limits.
fn max_dg_plot(oc: &DemoOutcome) -> Plot {
    let t0 = oc.recording.t0_c;
    let spec = &oc.spec;
    let row_points = |model: &str, method: Compensation, dx: f64| -> Vec<(f64, f64)> {
        oc.rows
            .iter()
            .filter(|r| r.model == model && r.method == method)
            .map(|r| (r.temp_c + dx, r.max_abs_dg_mg))
            .collect()
    };
    let n = 2 * oc.models.len() + 1;
    let mut series = vec![Series::line(
        "T0 constants (uncompensated)",
        PALETTE[0],
        Dash::Dotted,
        Marker::Cross,
        row_points(T0_CONSTANTS, Compensation::None, dodge(0, n) * 3.0),
    )];
    for (i, m) in oc.models.iter().enumerate() {
        for (k, method, marker, dash) in METHODS {
            let mut s = Series::line(
                format!("{} method {}", m.model, method.name()),
                model_color(i),
                dash,
                marker,
                row_points(&m.model.to_string(), method, dodge(1 + 2 * i + k, n) * 3.0),
            );
            s.marker_every = 1;
            series.push(s);
        }
    }
    let (lo, hi) = oc
        .models
        .first()
        .map(|m| m.fit.t_range)
        .unwrap_or((-40.0, 70.0));
    let (lo, hi) = (lo.min(t0 - 10.0) - 3.0, hi.max(t0 + 10.0) + 3.0);
    let near = (t0 - spec.t0_band_c, t0 + spec.t0_band_c);
    let band = |x: (f64, f64), lim: f64, label: String| Band {
        lo: f64::NEG_INFINITY,
        hi: lim,
        x: Some(x),
        label,
        color: ACCEPT,
        fit: true,
    };
    let verdicts: Vec<String> = oc
        .models
        .iter()
        .map(|m| format!("{} {}", m.model, m.acceptance.acceptance.name()))
        .collect();
    Plot {
        id: "max-dg".into(),
        title: format!(
            "worst |dg| over the verification positions {}",
            names_text(&verification_names(&oc.recording))
        ),
        x_label: "temperature, C".into(),
        y_label: "max |dg|, mg (log scale)".into(),
        x_range: Some((lo, hi)),
        y_log: true,
        series,
        bands: vec![
            band(
                (lo, near.0),
                spec.range_mg,
                format!("acceptance {} mg (valid range)", spec.range_mg),
            ),
            band((near.1, hi), spec.range_mg, String::new()),
            band(
                near,
                spec.t0_mg,
                format!("acceptance {} mg (T0 ±{} C)", spec.t0_mg, spec.t0_band_c),
            ),
        ],
        width: 900,
        height: 330,
        double: true,
        note: format!(
            "Markers sit at the verification temperatures, nudged sideways up to 1 C so that equal values stay visible. Acceptance (method 1): {}.",
            verdicts.join(", ")
        ),
        ..Plot::default()
    }
}

/// The signed dg with the T0 constants (no compensation), per position, every
/// temperature: its own panel, so that the compensated plots keep their own scale.
fn uncompensated_plot(oc: &DemoOutcome, names: &[String]) -> Plot {
    let Some(first) = oc.models.first() else {
        return Plot::default();
    };
    let temps: Vec<f64> = first.verifications[0]
        .max_by_temperature
        .iter()
        .map(|t| t.temp_c)
        .collect();
    let series = temps
        .iter()
        .enumerate()
        .map(|(k, t)| {
            let pts = first.verifications[0]
                .dwells
                .iter()
                .filter(|d| (d.temp_c - t).abs() <= 2.5)
                .filter_map(|d| {
                    let i = names.iter().position(|n| *n == d.position)?;
                    Some((i as f64 + dodge(k, temps.len()), d.dg_mg_uncompensated))
                })
                .collect();
            Series::markers(
                format!("{t:.1} C"),
                PALETTE[k % PALETTE.len()],
                Marker::ALL[k % Marker::ALL.len()],
                pts,
            )
        })
        .collect();
    let spec = &oc.spec;
    Plot {
        id: "dg-uncompensated".into(),
        title: "dg with the T0 constants (uncompensated)".into(),
        x_label: "verification position".into(),
        y_label: "dg, mg".into(),
        x_names: names.to_vec(),
        series,
        bands: vec![
            accept_band(spec, spec.range_mg, true),
            accept_band(spec, spec.t0_mg, true),
        ],
        zero_line: true,
        width: 460,
        height: 330,
        note: "What the temperature does to an uncompensated unit; each temperature's markers side by side in its position.".into(),
        ..Plot::default()
    }
}

/// Compensated dg per position at one temperature, every model and method, with the
/// acceptance band that applies there.
fn dg_plot(oc: &DemoOutcome, names: &[String], ti: usize, t: f64) -> Plot {
    let n = 2 * oc.models.len();
    let mut series = Vec::new();
    let mut max_abs = 0.0f64;
    for (i, m) in oc.models.iter().enumerate() {
        for (k, method, marker, _) in METHODS {
            let pts: Vec<(f64, f64)> = m.verifications[k]
                .dwells
                .iter()
                .filter(|d| (d.temp_c - t).abs() <= 2.5)
                .filter_map(|d| {
                    let p = names.iter().position(|x| *x == d.position)?;
                    Some((p as f64 + dodge(2 * i + k, n), d.dg_mg))
                })
                .collect();
            max_abs = pts.iter().fold(max_abs, |a, p| a.max(p.1.abs()));
            series.push(Series::markers(
                format!("{} method {}", m.model, method.name()),
                model_color(i),
                marker,
                pts,
            ));
        }
    }
    let lim = limit(&oc.spec, oc.recording.t0_c, t);
    // the band's edges widen the scale only when that leaves the points readable
    let fit = lim <= 2.5 * max_abs;
    Plot {
        id: format!("dg-{ti}"),
        title: format!("dg after compensation at {t:.1} C"),
        x_label: "verification position".into(),
        y_label: "dg, mg".into(),
        x_names: names.to_vec(),
        series,
        bands: vec![if fit {
            accept_band(&oc.spec, lim, true)
        } else {
            let b = accept_band(&oc.spec, lim, false);
            Band {
                label: format!("{}: edges off scale, every point inside", b.label),
                ..b
            }
        }],
        zero_line: true,
        width: 460,
        height: 270,
        ..Plot::default()
    }
}

fn dg_plots(oc: &DemoOutcome) -> Vec<Plot> {
    let Some(first) = oc.models.first() else {
        return Vec::new();
    };
    let names = positions(oc);
    let mut plots = vec![max_dg_plot(oc), uncompensated_plot(oc, &names)];
    for (ti, t) in first.verifications[0].max_by_temperature.iter().enumerate() {
        plots.push(dg_plot(oc, &names, ti, t.temp_c));
    }
    plots
}

/// What coefficient `c` is, and its unit (per g for K).
fn coeff_meaning(c: usize, unit: &str) -> (String, String) {
    let n = COEFF_NAMES[c];
    if c >= 9 {
        (format!("{n}: offset of {}", AXES[c - 9]), unit.to_string())
    } else if c < 3 {
        (
            format!("{n}: scale factor of {}", AXES[c]),
            format!("{unit}/g"),
        )
    } else {
        let (i, j) = (&n[1..2], &n[2..3]);
        (
            format!("{n}: {i} output per g along {j}"),
            format!("{unit}/g"),
        )
    }
}

/// Coefficient `c` on the temperature grid: the truth (when simulated) and every model.
fn curves(oc: &DemoOutcome, c: usize, grid: &[f64]) -> (Option<Vec<f64>>, Vec<Vec<f64>>) {
    let truth = oc
        .truth
        .as_ref()
        .map(|t| grid.iter().map(|x| t.coeffs(*x)[c]).collect());
    let models = oc
        .models
        .iter()
        .map(|m| grid.iter().map(|x| m.fit.eval(*x)[c]).collect())
        .collect();
    (truth, models)
}

/// Coefficient `c` against temperature (`diff`: minus the reference, the truth or else
/// the chosen model, with the per-stop 1-sigma error bars).
fn coeff_plot(oc: &DemoOutcome, c: usize, grid: &[f64], diff: bool) -> Plot {
    let (truth, models) = curves(oc, c, grid);
    let chosen = oc
        .models
        .iter()
        .position(|m| matches!(m.model, Compared::Chosen(_)));
    let at = |t: f64| -> f64 {
        match (&oc.truth, chosen) {
            (Some(tr), _) => tr.coeffs(t)[c],
            (None, Some(k)) => oc.models[k].fit.eval(t)[c],
            _ => 0.0,
        }
    };
    let reference: Vec<f64> = grid
        .iter()
        .map(|t| if diff { at(*t) } else { 0.0 })
        .collect();
    let stops: Vec<(f64, f64)> = oc
        .stops
        .iter()
        .map(|s| {
            (
                s.temp_c,
                s.coeffs[c] - if diff { at(s.temp_c) } else { 0.0 },
            )
        })
        .collect();
    let all = stops.iter().map(|p| p.1).chain(
        models
            .iter()
            .flatten()
            .zip(reference.iter().cycle())
            .map(|(v, r)| v - r),
    );
    let (lo, hi) = all.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
        (a.min(v), b.max(v))
    });
    let unit = oc.recording.output_unit.as_str();
    // departures by their size; values by how much they change (kxx in mV/g, not V/g)
    let scale_by = if diff {
        lo.abs().max(hi.abs())
    } else {
        (hi - lo) * 10.0
    };
    let (k, prefixed_unit) = prefixed(scale_by, unit);
    let (meaning, unit) = coeff_meaning(c, &prefixed_unit);
    let curve = |v: &[f64]| -> Vec<(f64, f64)> {
        grid.iter()
            .zip(v)
            .zip(&reference)
            .map(|((t, v), r)| (*t, (v - r) * k))
            .collect()
    };
    let styles = [Dash::Solid, Dash::Solid, Dash::DashDot, Dash::Dashed];
    // the truth first: a wide light line under the models, with no markers, so that it
    // reads as a reference and not as data, and both show where they coincide
    let mut series: Vec<Series> = truth
        .iter()
        .map(|t| Series::reference("truth (the twin's)", TRUTH, curve(t)))
        .collect();
    series.extend(models.iter().enumerate().map(|(i, v)| {
        Series::line(
            oc.models[i].model.to_string(),
            model_color(i),
            styles[i % styles.len()],
            Marker::ALL[(i + 2) % Marker::ALL.len()],
            curve(v),
        )
    }));
    let mut per_stop = Series::markers(
        PER_STOP[usize::from(diff)],
        PALETTE[0],
        Marker::Circle,
        stops.iter().map(|p| (p.0, p.1 * k)).collect(),
    );
    if diff {
        per_stop = per_stop.with_errors(oc.stops.iter().map(|s| s.stderr[c] * k).collect());
    }
    series.push(per_stop);
    let reference_name = match (&oc.truth, chosen) {
        (Some(_), _) => "the truth (the twin's)".to_string(),
        (None, Some(i)) => oc.models[i].model.to_string(),
        _ => "0".to_string(),
    };
    Plot {
        id: format!(
            "coeff-{}{}",
            COEFF_NAMES[c],
            if diff { "-diff" } else { "" }
        ),
        title: if diff {
            format!("{} minus {reference_name}", COEFF_NAMES[c])
        } else {
            meaning
        },
        x_label: "temperature, C".into(),
        y_label: if diff {
            format!("{} departure, {unit}", COEFF_NAMES[c])
        } else {
            format!("{}, {unit}", COEFF_NAMES[c])
        },
        series,
        zero_line: diff,
        width: 460,
        height: 250,
        ..Plot::default()
    }
}

fn coeff_plots(oc: &DemoOutcome, diff: bool) -> Vec<Plot> {
    let (lo, hi) = oc
        .models
        .first()
        .map(|m| m.fit.t_range)
        .unwrap_or((-40.0, 70.0));
    // about every 2 C, and every stop (where a pwl bends)
    let n = ((hi - lo) / 2.0).ceil().max(8.0) as usize;
    let mut grid: Vec<f64> = (0..=n)
        .map(|k| lo + (hi - lo) * k as f64 / n as f64)
        .chain(
            oc.stops
                .iter()
                .map(|s| s.temp_c)
                .filter(|t| *t > lo && *t < hi),
        )
        .collect();
    grid.sort_by(f64::total_cmp);
    grid.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
    (0..12).map(|c| coeff_plot(oc, c, &grid, diff)).collect()
}

/// Residual of every static dwell (all positions) against a model, per axis, and the
/// temperature trace below it on the same time axis.
fn residual_plots(oc: &DemoOutcome, model: &DemoModel) -> Vec<Plot> {
    let rec = &oc.recording;
    let mut axes: [Vec<(f64, f64)>; 3] = Default::default();
    // the dwells held out of every fit (the verification positions'), ringed
    let mut held_out: Vec<(f64, f64)> = Vec::new();
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
            axes[i].push((t_mid, d.u_mean[i] - pred));
            if rec.positions.has_role(d.position, Role::Verification) {
                held_out.push((t_mid, d.u_mean[i] - pred));
            }
        }
    }
    let max_abs = axes.iter().flatten().fold(0.0f64, |a, p| a.max(p.1.abs()));
    let (k, unit) = prefixed(max_abs, rec.output_unit.as_str());
    let mut series: Vec<Series> = axes
        .iter()
        .enumerate()
        .map(|(i, p)| {
            Series::markers(
                format!("axis {}", AXES[i]),
                AXIS_COLORS[i],
                AXIS_MARKERS[i],
                p.iter().map(|q| (q.0, q.1 * k)).collect(),
            )
        })
        .collect();
    if !held_out.is_empty() {
        series.push(Series::markers(
            format!(
                "held out of every fit (verification positions {})",
                names_text(&verification_names(rec))
            ),
            PALETTE[0],
            Marker::Ring,
            held_out.iter().map(|q| (q.0, q.1 * k)).collect(),
        ));
    }
    let span = Some(time_span(rec));
    vec![
        Plot {
            id: "residual-time".into(),
            title: format!("dwell-mean residual against {}", model.model),
            x_label: "time, h".into(),
            y_label: format!("residual, {unit}"),
            x_range: span,
            series,
            zero_line: true,
            width: 1300,
            height: 260,
            wide: true,
            ..Plot::default()
        },
        temperature_plot(rec, "temperature-time", span),
    ]
}

/// The acceptance verdicts as an HTML table.
fn verdict_table(oc: &DemoOutcome) -> String {
    let mut s = format!(
        "<p>Acceptance, method 1 ({}):</p>\n<table class=\"verdicts\">\n",
        esc(&oc.spec.text())
    );
    for m in &oc.models {
        let a = &m.acceptance;
        let (v, why) = (a.acceptance.name(), a.reason.clone());
        let color = match a.acceptance {
            Verdict::Pass => "#1A8036",
            Verdict::Fail => "#B00020",
            Verdict::NotJudged => "#7A5A00",
        };
        s.push_str(&format!(
            "<tr><td>{}</td><td style=\"color:{color};font-weight:bold\">{v}</td><td>{}</td></tr>\n",
            esc(&m.model.to_string()),
            esc(&why)
        ));
    }
    s.push_str("</table>\n");
    s
}

/// The demo's report.
pub fn demo_report(oc: &DemoOutcome) -> Result<String> {
    let verification = verification_names(&oc.recording);
    let table = crate::analysis::table(&oc.rows, &verification);
    let intro = format!(
        "<p>Unit {}, {} samples, output in {}. Models: {}. Compensation by firmware-core in f32 (method 1: correct the constants; method 2: correct the result).</p>\n<pre>{}</pre>\n{}<p>Data-chosen model: {} by {}; {}</p>\n",
        esc(&oc.recording.unit),
        oc.recording.rows.len(),
        esc(oc.recording.output_unit.as_str()),
        oc.models.iter().map(|m| esc(&m.model.to_string())).collect::<Vec<_>>().join(", "),
        esc(&table),
        verdict_table(oc),
        esc(&oc.selection.chosen),
        esc(&oc.selection.method),
        esc(&oc.selection.reason)
    );
    let reference = if oc.truth.is_some() {
        "the truth (the twin's)"
    } else {
        "the data-chosen model"
    };
    let mut sections = vec![
        Section {
            head: format!(
                "Compensation error in the verification positions {} (formula (13))",
                names_text(&verification)
            ),
            text: "dg = |a| - 1 in the positions held out of every fit. Top left: the worst per temperature for every model and method against the acceptance limits; top right: without compensation; then the compensated dg per position at each temperature, each on its own scale, with the acceptance band that applies there.".into(),
            plots: dg_plots(oc),
            pairs: false,
        },
        Section {
            head: "The 12 coefficients against temperature".into(),
            text: "The 12 coefficients identified at each stop by formula (10) (black dots), each fitted temperature model, and the twin's truth when the recording is simulated (the wide grey line under the models: a reference, not data).".into(),
            plots: coeff_plots(oc, false),
            pairs: false,
        },
        Section {
            head: format!("The coefficients minus {reference}"),
            text: format!("The same, minus {reference}: where the models depart from it, and the per-stop values with their 1-sigma error bars (from the in-dwell noise)."),
            plots: coeff_plots(oc, true),
            pairs: false,
        },
    ];
    let best = oc
        .models
        .iter()
        .min_by(|a, b| worst(a).total_cmp(&worst(b)));
    if let Some(b) = best {
        sections.push(Section {
            head: "Residuals against time".into(),
            text: format!("Dwell means minus the {} model at the dwell's temperature, per axis; the dwells held out of every fit (the verification positions {}) ringed; below, on the same time axis, the temperature.", b.model, names_text(&verification)),
            plots: residual_plots(oc, b),
            pairs: false,
        });
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
