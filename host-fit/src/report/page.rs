//! The HTML page: one self-contained file, sections of text and plots, every plot's data
//! embedded beside it as JSON so a test can check the drawing against the numbers.
use crate::error::{HostError, Result};
use crate::report::plot::{hex, Plot};

/// Escaped for HTML text.
pub fn esc(s: &str) -> String {
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
