//! The HTML page: one self-contained file, sections of text and plots laid out in a grid
//! that uses the page's width (2-3 columns on a desktop screen; plots along time span it
//! all, one above the other, so that they line up), every plot's drawn data embedded
//! beside it as JSON so a test can check the drawing against the numbers.
use crate::error::{ErrorKind, HostError, Result};
use crate::report::plot::{prepare, Plot};
pub use crate::report::svg::esc;
use crate::report::svg::svg;

/// A section of the page: heading, a paragraph, plots.
pub struct Section {
    /// Heading.
    pub head: String,
    /// What the plots show (plain text).
    pub text: String,
    /// The plots.
    pub plots: Vec<Plot>,
    /// Two columns (pairs side by side, before and after) rather than three.
    pub pairs: bool,
}

const STYLE: &str = "body{font-family:'DejaVu Sans',Verdana,Arial,sans-serif;color:#222;margin:0 auto;padding:16px 24px;max-width:1800px}\
h1{font-size:24px;margin:8px 0}h2{font-size:19px;margin:28px 0 6px;border-bottom:1px solid #ccc}\
p{max-width:1100px;line-height:1.4}\
pre{background:#f5f5f5;padding:10px;font-size:12.5px;white-space:pre-wrap;overflow-wrap:anywhere}\
table.verdicts td{padding:2px 10px 2px 0;vertical-align:top}\
.plots{display:grid;grid-template-columns:repeat(auto-fill,minmax(420px,1fr));gap:14px 22px;align-items:start}\
.plots.pairs{grid-template-columns:repeat(auto-fill,minmax(560px,1fr))}\
figure{margin:0;min-width:0}figure.wide{grid-column:1/-1}\
@media (min-width:960px){figure.double{grid-column:span 2}}\
figure svg{display:block;width:100%;height:auto}\
figcaption{font-size:13px;color:#444;margin:2px 0 0 8px}";

/// JSON text safe inside a `<script>` element of a page that is also well-formed XML.
fn script_json(v: &impl serde::Serialize) -> Result<String> {
    let s =
        serde_json::to_string(v).map_err(|e| HostError::new(ErrorKind::Internal, e.to_string()))?;
    Ok(s.replace('<', "\\u003c")
        .replace('>', "\\u003e")
        .replace('&', "\\u0026"))
}

/// One plot as a figure: its SVG, its note (and how much was thinned for drawing), its
/// drawn data.
fn figure(p: &Plot) -> Result<String> {
    let prepared = prepare(p);
    let natural = format!(" class=\"wide\" style=\"max-width:{}px\"", p.width);
    let class = if p.natural {
        natural.as_str()
    } else if p.wide {
        " class=\"wide\""
    } else if p.double {
        " class=\"double\""
    } else {
        ""
    };
    let (drawn, all) = prepared
        .plot
        .series
        .iter()
        .zip(&prepared.points_in_data)
        .fold((0, 0), |(a, b), (s, n)| (a + s.points.len(), b + n));
    let mut note = p.note.clone();
    if drawn < all && p.series.iter().all(|s| s.line.is_none()) {
        note.push_str(&format!(
            "{}{drawn} of {all} points drawn: the others would cover markers already drawn.",
            if note.is_empty() { "" } else { " " }
        ));
    }
    let note = if note.is_empty() {
        String::new()
    } else {
        format!("<figcaption>{}</figcaption>\n", esc(&note))
    };
    Ok(format!(
        "<figure id=\"{}\"{class}>\n{}\n{note}<script type=\"application/json\" class=\"plot-data\">{}</script>\n</figure>\n",
        esc(&p.id),
        svg(&prepared),
        script_json(&prepared.data())?
    ))
}

/// A whole HTML page: a title, an introduction (HTML) and the sections.
pub fn html(title: &str, intro: &str, sections: &[Section]) -> Result<String> {
    let mut h = String::new();
    h.push_str("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\"/>\n");
    h.push_str("<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\"/>\n");
    h.push_str(&format!("<title>{}</title>\n", esc(title)));
    h.push_str(&format!("<style>{STYLE}</style>\n</head>\n<body>\n"));
    h.push_str(&format!("<h1>{}</h1>\n{}\n", esc(title), intro));
    for s in sections {
        h.push_str(&format!(
            "<section>\n<h2>{}</h2>\n<p>{}</p>\n<div class=\"plots{}\">\n",
            esc(&s.head),
            esc(&s.text),
            if s.pairs { " pairs" } else { "" }
        ));
        for p in &s.plots {
            h.push_str(&figure(p)?);
        }
        h.push_str("</div>\n</section>\n");
    }
    h.push_str("</body>\n</html>\n");
    Ok(h)
}
