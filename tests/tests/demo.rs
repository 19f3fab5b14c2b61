//! The main job: the paper's experiment on the twin reproduces the paper's numbers, the
//! richer models reach the target, and the report's plots hold the data they claim.
use serde_json::Value;
use tests::cli;

fn rows(summary: &Value) -> Vec<(String, String, f64, f64)> {
    summary["rows"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| {
            (
                r["model"].as_str().unwrap().to_string(),
                r["method"].as_str().unwrap().to_string(),
                r["temp_c"].as_f64().unwrap(),
                r["max_abs_dg_mg"].as_f64().unwrap(),
            )
        })
        .collect()
}

fn at(rows: &[(String, String, f64, f64)], model: &str, method: &str, t: f64) -> f64 {
    rows.iter()
        .find(|r| r.0 == model && r.1 == method && (r.2 - t).abs() < 2.0)
        .unwrap_or_else(|| panic!("{model} {method} {t}"))
        .3
}

#[test]
fn demo_reproduces_the_paper_and_the_report_holds_its_data() {
    let dir = std::env::temp_dir().join(format!("hf-demo-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let d = dir.to_str().unwrap();
    let (code, out, err) = cli(&["demo", "--out", d]);
    assert_eq!(code, 0, "{err}");
    assert!(
        out.contains("paper-pwl2") && out.contains("summary.json"),
        "{out}"
    );

    let summary: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    let r = rows(&summary);
    for t in [-10.0, 45.0] {
        let unc = at(&r, "t0-constants", "none", t);
        assert!(
            (3.0..=6.0).contains(&unc),
            "uncompensated at {t}: {unc} mg (paper: ~4)"
        );
        for m in ["1", "2"] {
            let ratio = unc / at(&r, "paper-pwl2", m, t);
            assert!(
                (2.5..=5.0).contains(&ratio),
                "paper-pwl2 method {m} at {t}: {ratio}x (paper: 3-4x)"
            );
        }
        let (m1, m2) = (at(&r, "paper-pwl2", "1", t), at(&r, "paper-pwl2", "2", t));
        assert!(
            (m1 - m2).abs() < 0.1 * m1,
            "both methods about equal: {m1} vs {m2}"
        );
    }
    let richer: Vec<_> = r
        .iter()
        .filter(|x| x.0.starts_with("poly") || x.0 == "pwl-all")
        .collect();
    assert!(richer.len() >= 20);
    for x in richer {
        assert!(
            x.3 <= 0.3,
            "richer model {} method {} at {}: {} mg > 0.3",
            x.0,
            x.1,
            x.2,
            x.3
        );
    }

    // a second run does not overwrite without --force
    let (code, _, err) = cli(&["demo", "--out", d]);
    assert_eq!(code, 1);
    assert!(err.contains("--force"), "{err}");

    check_report(
        &std::fs::read_to_string(dir.join("report.html")).unwrap(),
        &r,
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

fn points(s: &str) -> Vec<(f64, f64)> {
    s.split_whitespace()
        .map(|p| {
            let (x, y) = p.split_once(',').unwrap();
            (x.parse().unwrap(), y.parse().unwrap())
        })
        .collect()
}

/// Least squares `px = a + b v`; returns (b, max residual).
fn affine(pairs: &[(f64, f64)]) -> (f64, f64) {
    let n = pairs.len() as f64;
    let (mv, mp) = (
        pairs.iter().map(|p| p.0).sum::<f64>() / n,
        pairs.iter().map(|p| p.1).sum::<f64>() / n,
    );
    let sxx: f64 = pairs.iter().map(|p| (p.0 - mv).powi(2)).sum();
    let sxy: f64 = pairs.iter().map(|p| (p.0 - mv) * (p.1 - mp)).sum();
    let b = sxy / sxx;
    let a = mp - b * mv;
    (
        b,
        pairs
            .iter()
            .map(|p| (p.1 - a - b * p.0).abs())
            .fold(0.0, f64::max),
    )
}

fn check_report(html: &str, rows: &[(String, String, f64, f64)]) {
    let doc = roxmltree::Document::parse_with_options(
        html,
        roxmltree::ParsingOptions {
            allow_dtd: true,
            ..Default::default()
        },
    )
    .expect("the report is well-formed");
    let figures: Vec<_> = doc
        .descendants()
        .filter(|n| n.has_tag_name("figure"))
        .collect();
    assert!(figures.len() >= 5 + 12 + 2, "{} figures", figures.len());
    let mut checked_dg = 0;
    for fig in figures {
        let id = fig.attribute("id").unwrap();
        let data: Value = serde_json::from_str(
            fig.descendants()
                .find(|n| n.has_tag_name("script"))
                .unwrap()
                .text()
                .unwrap(),
        )
        .unwrap();
        let polylines: Vec<_> = fig
            .descendants()
            .filter(|n| n.has_tag_name("polyline") && n.attribute("stroke-width") == Some("2"))
            .collect();
        let (mut xs, mut ys) = (Vec::new(), Vec::new());
        for s in data["series"].as_array().unwrap() {
            let color = s["color"].as_str().unwrap();
            let pts: Vec<(f64, f64)> = s["points"]
                .as_array()
                .unwrap()
                .iter()
                .map(|p| (p[0].as_f64().unwrap(), p[1].as_f64().unwrap()))
                .collect();
            if s["markers"].as_bool().unwrap() {
                let circles = fig
                    .descendants()
                    .filter(|n| n.has_tag_name("circle") && n.attribute("fill") == Some(color))
                    .count();
                assert_eq!(circles, pts.len(), "{id}: markers of {}", s["name"]);
                continue;
            }
            let line = polylines
                .iter()
                .find(|p| p.attribute("stroke") == Some(color))
                .unwrap_or_else(|| panic!("{id}: no line for {}", s["name"]));
            let px = points(line.attribute("points").unwrap());
            assert_eq!(
                px.len(),
                pts.len(),
                "{id}: {} has {} points drawn, {} in data",
                s["name"],
                px.len(),
                pts.len()
            );
            for (v, p) in pts.iter().zip(&px) {
                xs.push((v.0, p.0));
                ys.push((v.1, p.1));
            }
        }
        if xs.len() > 2 {
            let (bx, rx) = affine(&xs);
            let (by, ry) = affine(&ys);
            assert!(
                bx > 0.0 && rx <= 1.0,
                "{id}: x pixels do not follow the data (residual {rx})"
            );
            assert!(
                by < 0.0 && ry <= 1.0,
                "{id}: y pixels do not follow the data (residual {ry})"
            );
        }
        if id.starts_with("dg-") {
            // the plotted compensated dg agrees with summary.json's maximum
            let title = data["title"].as_str().unwrap();
            let t: f64 = title
                .trim_start_matches("dg at ")
                .trim_end_matches(" C")
                .parse()
                .unwrap();
            for s in data["series"].as_array().unwrap() {
                let name = s["name"].as_str().unwrap();
                let max = s["points"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .map(|p| p[1].as_f64().unwrap().abs())
                    .fold(0.0, f64::max);
                let (model, method) = match name.rsplit_once(" method ") {
                    Some((m, k)) => (m.to_string(), k.to_string()),
                    None => ("t0-constants".to_string(), "none".to_string()),
                };
                assert!(
                    (max - at(rows, &model, &method, t)).abs() < 1e-9,
                    "{id} {name}"
                );
            }
            checked_dg += 1;
        }
    }
    assert_eq!(checked_dg, 5);
}

#[test]
fn report_command_on_any_recording() {
    let dir = std::env::temp_dir().join(format!("hf-report-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let case = host_fit::blind::Case {
        effects: vec![],
        scale: 1.0,
        seed: 2,
        tp_only: false,
    };
    let sim = host_fit::simulate::simulate(&host_fit::blind::configure(&case), |_| {}).unwrap();
    let rec = dir.join("rec.csv");
    std::fs::write(&rec, sim.csv).unwrap();
    let html = dir.join("r.html");
    let (code, out, err) = cli(&[
        "report",
        rec.to_str().unwrap(),
        "--out",
        html.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(
        out.contains("pwl-all") && !out.contains("paper-pwl2"),
        "no -40/+70 stops: no paper model\n{out}"
    );
    let text = std::fs::read_to_string(&html).unwrap();
    let doc = roxmltree::Document::parse_with_options(
        &text,
        roxmltree::ParsingOptions {
            allow_dtd: true,
            ..Default::default()
        },
    )
    .unwrap();
    let dg = doc
        .descendants()
        .filter(|n| {
            n.has_tag_name("figure") && n.attribute("id").is_some_and(|i| i.starts_with("dg-"))
        })
        .count();
    assert_eq!(
        dg, 4,
        "one dg plot per verification temperature (-20, 10, 20, 40)"
    );
    let (code, _, err) = cli(&[
        "report",
        rec.to_str().unwrap(),
        "--out",
        html.to_str().unwrap(),
    ]);
    assert_eq!(code, 1);
    assert!(err.contains("--force"));
    std::fs::remove_dir_all(&dir).unwrap();
}
