//! The demo's report: dg per verification position, the coefficients against
//! temperature, residuals against time.
use crate::analysis::{DemoModel, DemoOutcome};
use crate::error::Result;
use crate::report::page::{esc, html};
use crate::report::plot::{Plot, Series, PALETTE};
use firmware_core::model::{COEFF_NAMES, K_INDEX, U0_INDEX};

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
