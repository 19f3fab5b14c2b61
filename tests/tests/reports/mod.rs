//! What every report's plots must be, read from the page itself: each figure's SVG has
//! its title, both axis labels (quantity, unit), a tick label per category name, a legend
//! entry per series and per labelled band, and draws exactly the data embedded beside
//! it: every series' line and markers pass through its points by one affine map per axis
//! (log10 on a log axis), error bars where it has them; a series without markers (a
//! reference such as the twin's truth) has its line.
use serde_json::Value;

/// One figure: its id and its embedded data.
#[allow(dead_code)] // not every test reads the data
pub struct Figure {
    pub id: String,
    pub data: Value,
}

/// Coordinate pairs of an SVG path made of `M` and implicit linetos (`M x y x y M x y`).
fn pairs(d: &str) -> Vec<(f64, f64)> {
    let nums: Vec<f64> = d
        .replace('M', " ")
        .split_whitespace()
        .map(|v| {
            v.parse()
                .unwrap_or_else(|_| panic!("not a number `{v}` in `{d}`"))
        })
        .collect();
    assert_eq!(nums.len() % 2, 0, "odd coordinates in `{d}`");
    nums.chunks(2).map(|c| (c[0], c[1])).collect()
}

/// Least squares `px = a + b v`; returns (b, max residual).
pub fn affine(pairs: &[(f64, f64)]) -> (f64, f64) {
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

fn texts<'a>(svg: roxmltree::Node<'a, 'a>, class: &str) -> Vec<String> {
    svg.descendants()
        .filter(|n| n.has_tag_name("text") && n.attribute("class") == Some(class))
        .map(|n| n.text().unwrap_or("").to_string())
        .collect()
}

fn by_attr<'a>(
    svg: roxmltree::Node<'a, 'a>,
    tag: &str,
    class: &str,
    attr: &str,
    value: &str,
) -> Option<roxmltree::Node<'a, 'a>> {
    svg.descendants().find(|n| {
        n.has_tag_name(tag)
            && n.attribute("class") == Some(class)
            && n.attribute(attr) == Some(value)
    })
}

/// The structure of one figure's SVG: title, axis labels with units, category names,
/// a legend entry per series and labelled band.
fn structure(id: &str, svg: roxmltree::Node, data: &Value) {
    let s = |k: &str| data[k].as_str().unwrap().to_string();
    assert_eq!(texts(svg, "title"), [s("title")], "{id}: title");
    assert!(!s("title").is_empty(), "{id}: no title");
    for (class, key) in [("x-label", "x_label"), ("y-label", "y_label")] {
        let label = s(key);
        assert_eq!(
            texts(svg, class),
            std::slice::from_ref(&label),
            "{id}: {class}"
        );
        let categories = class == "x-label" && !data["x_names"].as_array().unwrap().is_empty();
        assert!(
            label.contains(", ") || categories,
            "{id}: {class} `{label}` names no unit (quantity, unit)"
        );
    }
    let ticks: Vec<String> = svg
        .descendants()
        .filter(|n| n.has_tag_name("text") && n.attribute("class") == Some("tick x"))
        .map(|n| n.text().unwrap_or("").to_string())
        .collect();
    assert!(ticks.len() >= 2, "{id}: {} x tick labels", ticks.len());
    assert!(
        ticks
            .iter()
            .all(|t| !t.starts_with("-0") || t.parse::<f64>().is_ok_and(|v| v != 0.0)),
        "{id}: a tick reads -0: {ticks:?}"
    );
    let names: Vec<&str> = data["x_names"]
        .as_array()
        .unwrap()
        .iter()
        .map(|n| n.as_str().unwrap())
        .collect();
    if !names.is_empty() {
        assert!(
            ticks.iter().all(|t| names.contains(&t.as_str())),
            "{id}: category ticks {ticks:?} are not the names"
        );
        if names.len() <= 12 {
            assert_eq!(ticks, names, "{id}: every category named");
        }
    }
    for (i, se) in data["series"].as_array().unwrap().iter().enumerate() {
        let e = by_attr(svg, "g", "legend-entry", "data-series", &i.to_string())
            .unwrap_or_else(|| panic!("{id}: no legend entry for {}", se["name"]));
        let text = e.descendants().find(|n| n.has_tag_name("text")).unwrap();
        assert_eq!(text.text(), se["name"].as_str(), "{id}: legend entry {i}");
    }
    for (i, b) in data["bands"].as_array().unwrap().iter().enumerate() {
        if b["label"].as_str().unwrap().is_empty() {
            continue;
        }
        let e = by_attr(svg, "g", "legend-entry", "data-band", &i.to_string())
            .unwrap_or_else(|| panic!("{id}: no legend entry for band {}", b["label"]));
        let text = e.descendants().find(|n| n.has_tag_name("text")).unwrap();
        assert_eq!(text.text(), b["label"].as_str(), "{id}: band legend {i}");
    }
}

/// The drawn coordinates of series `i` against its data: (value, pixel) pairs for x and y.
fn drawn(
    id: &str,
    svg: roxmltree::Node,
    i: usize,
    se: &Value,
    log_y: bool,
) -> Vec<((f64, f64), (f64, f64))> {
    let g = by_attr(svg, "g", "series", "data-series", &i.to_string())
        .unwrap_or_else(|| panic!("{id}: series {i} not drawn"));
    let path = |class: &str| {
        g.descendants()
            .find(|n| n.has_tag_name("path") && n.attribute("class") == Some(class))
            .and_then(|n| n.attribute("d"))
    };
    let pts: Vec<(f64, f64)> = se["points"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| {
            let y = p[1].as_f64().unwrap();
            (p[0].as_f64().unwrap(), if log_y { y.log10() } else { y })
        })
        .collect();
    let name = &se["name"];
    let mut out = Vec::new();
    let every = se["marker_every"].as_u64().unwrap() as usize;
    if se["marker"] == "none" {
        // a reference line (the twin's truth): no markers, so a line it must have
        assert!(path("markers").is_none(), "{id}: {name} has markers");
        assert!(
            se["line"].is_string(),
            "{id}: {name} has neither markers nor a line"
        );
    } else {
        let markers =
            pairs(path("markers").unwrap_or_else(|| panic!("{id}: {name} has no markers")));
        let marked: Vec<_> = pts.iter().step_by(every.max(1)).copied().collect();
        assert_eq!(markers.len(), marked.len(), "{id}: markers of {name}");
        out.extend(marked.into_iter().zip(markers));
    }
    if se["line"].is_string() {
        let line = pairs(path("line").unwrap_or_else(|| panic!("{id}: no line for {name}")));
        assert_eq!(line.len(), pts.len(), "{id}: points of {name}'s line");
        out.extend(pts.iter().copied().zip(line));
    }
    if let Some(e) = se["errors"].as_array() {
        let d = path("errors").unwrap_or_else(|| panic!("{id}: no error bars for {name}"));
        assert_eq!(
            d.matches('M').count(),
            3 * e.len(),
            "{id}: error bars of {name}"
        );
    }
    out.into_iter()
        .map(|(v, p)| ((v.0, p.0), (v.1, p.1)))
        .collect()
}

/// Every figure of `html`: its structure, and its drawing against its data.
pub fn check_plots(html: &str) -> Vec<Figure> {
    let doc = roxmltree::Document::parse_with_options(
        html,
        roxmltree::ParsingOptions {
            allow_dtd: true,
            ..Default::default()
        },
    )
    .expect("the report is well-formed");
    let mut out = Vec::new();
    for fig in doc.descendants().filter(|n| n.has_tag_name("figure")) {
        let id = fig.attribute("id").unwrap().to_string();
        let data: Value = serde_json::from_str(
            fig.descendants()
                .find(|n| n.has_tag_name("script"))
                .unwrap()
                .text()
                .unwrap(),
        )
        .unwrap();
        assert_eq!(data["id"], id.as_str());
        let svg = fig
            .descendants()
            .find(|n| n.has_tag_name("svg"))
            .unwrap_or_else(|| panic!("{id}: no svg"));
        structure(&id, svg, &data);
        let log_y = data["y_log"].as_bool().unwrap();
        let (mut xs, mut ys) = (Vec::new(), Vec::new());
        for (i, se) in data["series"].as_array().unwrap().iter().enumerate() {
            for (x, y) in drawn(&id, svg, i, se, log_y) {
                xs.push(x);
                ys.push(y);
            }
        }
        for (axis, v, sign) in [("x", &xs, 1.0), ("y", &ys, -1.0)] {
            let distinct = v.iter().any(|p| (p.0 - v[0].0).abs() > 1e-12);
            if v.len() > 2 && distinct {
                let (b, r) = affine(v);
                assert!(
                    b * sign > 0.0 && r <= 1.0,
                    "{id}: {axis} pixels do not follow the data (residual {r} px)"
                );
            }
        }
        out.push(Figure { id, data });
    }
    out
}
