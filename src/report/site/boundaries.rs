//! The boundaries section of the report's index (`report::site`), as tables made from the
//! phase map (`boundary::PhaseMap`), not from the text of `wetgran boundaries`: per slice (and
//! branch), one table per phase pair with the boundary point's coordinates, the container's
//! amplitude and frequency (shaking sweeps), its uncertainty, the two grid points it lies
//! between (links to their pages) and the share of replicas that agree; where a slice has no
//! boundary, why.

use super::esc;
use crate::boundary::{Extraction, PhaseMap, Slice};
use crate::report::boundaries_text::{chain_model_note, fixed_text, no_boundary_reason};
use crate::run::runner::short;
use crate::store::PointSummary;

fn opt(v: Option<f64>) -> String {
    v.map(short).unwrap_or_else(|| "–".to_string())
}

/// A grid point of a slice as text with a link to its page (`page_of` of its coordinates);
/// `has_y`: whether the plane has a y axis.
fn end_point(
    slice: &Slice,
    k: usize,
    has_y: bool,
    page_of: &dyn Fn(&[serde_json::Value]) -> Option<String>,
) -> String {
    let Some(p) = slice.points.get(k) else {
        return "–".to_string();
    };
    let text = if has_y {
        format!("{} at ({}, {})", p.phase, short(p.x), short(p.y))
    } else {
        format!("{} at {}", p.phase, short(p.x))
    };
    match page_of(&p.coords) {
        Some(page) => format!("<a href=\"{page}\">{}</a>", esc(&text)),
        None => esc(&text),
    }
}

/// The boundaries section (HTML, after its heading) of `map`; `points`: the sweep's
/// summaries (for the chain-model note of a shear sweep); `page_of`: the page of a grid point
/// by its coordinates.
pub(super) fn boundaries_html(
    map: &PhaseMap,
    points: &[PointSummary],
    how: Extraction,
    page_of: &dyn Fn(&[serde_json::Value]) -> Option<String>,
) -> String {
    let mut h = String::new();
    if let Some(n) = chain_model_note(points) {
        h.push_str(&format!("<p>{}</p>\n", esc(n.trim())));
    }
    let Some(xa) = &map.x else {
        h.push_str("<p>No numeric axis: no phase map, no boundaries.</p>\n");
        return h;
    };
    let ya = map.y.as_ref();
    let err_head = |log: bool, what: &str| {
        if log {
            format!("± {what} (decades)")
        } else {
            format!("± {what}")
        }
    };
    for slice in &map.slices {
        let mut title = fixed_text(&slice.fixed);
        if let Some(b) = &slice.branch {
            if !title.is_empty() {
                title.push_str(", ");
            }
            title.push_str(&crate::boundary::branch_words(b));
        }
        if !title.is_empty() {
            h.push_str(&format!("<h3>{}</h3>\n", esc(&title)));
        }
        if slice.points.is_empty() {
            h.push_str("<p>No classified point yet.</p>\n");
            continue;
        }
        let unsettled = slice.points.iter().filter(|p| !p.trusted).count();
        if unsettled > 0 {
            h.push_str(&format!(
                "<p class=\"note\">{unsettled} point(s) not settled, their label may change: {}.</p>\n",
                if how.include_unconverged {
                    "used for the boundaries as asked (--include-unconverged)"
                } else {
                    "left out of the boundaries (--include-unconverged uses them)"
                }
            ));
        }
        if slice.boundaries.is_empty() {
            h.push_str(&format!(
                "<p>No boundary: {}.</p>\n",
                esc(no_boundary_reason(slice, how))
            ));
            continue;
        }
        for (pair, list) in &slice.boundaries {
            h.push_str(&format!(
                "<table class=\"boundary\">\n<caption>boundary {} ({} point{})</caption>\n\
                 <thead><tr><th>{}</th>",
                esc(pair),
                list.len(),
                if list.len() == 1 { "" } else { "s" },
                esc(&xa.label)
            ));
            if let Some(ya) = ya {
                h.push_str(&format!("<th>{}</th>", esc(&ya.label)));
            }
            if map.shaking {
                h.push_str("<th>A</th><th>ω</th>");
            }
            h.push_str(&format!("<th>{}</th>", esc(&err_head(xa.log, &xa.label))));
            if let Some(ya) = ya {
                h.push_str(&format!("<th>{}</th>", esc(&err_head(ya.log, &ya.label))));
            }
            h.push_str("<th>between</th><th>and</th><th>agree</th></tr></thead>\n<tbody>\n");
            for b in list {
                h.push_str(&format!("<tr><td class=\"num\">{}</td>", short(b.x)));
                if ya.is_some() {
                    h.push_str(&format!("<td class=\"num\">{}</td>", short(b.y)));
                }
                if map.shaking {
                    h.push_str(&format!(
                        "<td class=\"num\">{}</td><td class=\"num\">{}</td>",
                        opt(b.amplitude),
                        opt(b.omega)
                    ));
                }
                h.push_str(&format!("<td class=\"num\">{}</td>", short(b.x_half)));
                if ya.is_some() {
                    h.push_str(&format!("<td class=\"num\">{}</td>", short(b.y_half)));
                }
                h.push_str(&format!(
                    "<td>{}</td><td>{}</td><td class=\"num\">{:.2}</td></tr>\n",
                    end_point(slice, b.between[0], ya.is_some(), page_of),
                    end_point(slice, b.between[1], ya.is_some(), page_of),
                    b.confidence
                ));
            }
            h.push_str("</tbody>\n</table>\n");
        }
    }
    h
}
