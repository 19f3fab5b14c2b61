//! The diagnosis report: residuals against time, temperature and position, before and
//! after the findings.
use crate::data::recording::Recording;
use crate::diagnose::Diagnosis;
use crate::error::Result;
use crate::report::page::{esc, html};
use crate::report::plot::{Plot, Series, PALETTE};

/// The diagnosis report: residuals against time, temperature and position, before and
/// after the findings.
pub fn diagnosis_report(rec: &Recording, d: &Diagnosis) -> Result<String> {
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
    let intro = format!(
        "<p>Recording {}.</p>\n<pre>{}</pre>",
        esc(&rec.path.display().to_string()),
        esc(&d.contract(rec).text())
    );
    html("Diagnosis", &intro, &[("Residuals before and after".to_string(), "Window means minus the baseline model (before) and the final model with the findings (after); below, the temperature.".to_string(), plots)])
}
