//! The points table of the report's index (`report::site`): one row per job, its grid
//! position (a link to its page), one column per axis, the replica, its label with the trust
//! mark, `T_g / E_cb`, the bridges per grain, the lateral mobility `D_lat`, the run's trend, the
//! criterion that decided the label, and its cost (simulated time, wall time). Every cell of a
//! column that sorts carries its sort value (`data-v`, a number where the column is numeric) for
//! the page's sort script (`sort.js`), which sorts on a header's click or from the address
//! (`index.html#sort=T_g`, `#sort=-T_g` descending); without the script the table stays in
//! point order.

use super::esc;
use crate::report::plot_phase::phase_color;
use crate::run::runner::short;
use crate::store::{PointRow, SweepRow};
use wetgran_core::observe::criterion::DecidedBy;

/// A cell: its text (HTML) and its sort value (`None`: sorts as missing, last).
struct Cell {
    html: String,
    sort: Option<String>,
    numeric: bool,
}

fn number(x: Option<f64>) -> Cell {
    match x.filter(|x| x.is_finite()) {
        Some(x) => Cell {
            html: short(x),
            sort: Some(format!("{x:e}")),
            numeric: true,
        },
        None => Cell {
            html: "–".to_string(),
            sort: None,
            numeric: true,
        },
    }
}

fn words(text: &str) -> Cell {
    Cell {
        html: esc(text),
        sort: Some(text.to_string()),
        numeric: false,
    }
}

/// The label of a job with its trust mark (`g?`, `g~`), its colour swatch as on the map.
fn label_cell(r: &PointRow, label: &str) -> Cell {
    let colour = r
        .phase
        .as_deref()
        .map(|p| {
            let c = phase_color(p);
            format!(
                "<span class=\"swatch\" style=\"background: rgb({}, {}, {})\"></span>",
                c.0, c.1, c.2
            )
        })
        .unwrap_or_default();
    let class = if r.status == "done" && !r.trusted() {
        " class=\"untrusted\""
    } else {
        ""
    };
    Cell {
        html: format!("{colour}<span{class}>{}</span>", esc(label)),
        sort: Some(label.to_string()),
        numeric: false,
    }
}

/// The criterion of a job's label, a fallback in red; the numbers compared in its title.
fn decided_by_cell(r: &PointRow) -> Cell {
    match r.decided_on.as_ref().and_then(DecidedBy::of_json) {
        Some(by) => {
            // A fallback's name says so (`gas_temperature_fallback`): red, no more words.
            let class = if by.fallback {
                " class=\"untrusted\""
            } else {
                ""
            };
            let name = by.criterion.name().replace('_', " ");
            Cell {
                html: format!(
                    "<span{class} title=\"{}\">{}</span>",
                    esc(&by.summary),
                    esc(&name)
                ),
                sort: Some(name),
                numeric: false,
            }
        }
        None => Cell {
            html: "–".to_string(),
            sort: None,
            numeric: false,
        },
    }
}

/// A number of the stored observables at `pointer`.
fn observable(r: &PointRow, pointer: &str) -> Option<f64> {
    r.observables.as_ref()?.pointer(pointer)?.as_f64()
}

/// The unit name of the temperatures of `rows` (`E_cb` wet, `m g d` dry), from the first
/// stored result that names it.
fn temperature_unit(rows: &[PointRow]) -> String {
    rows.iter()
        .find_map(|r| {
            r.observables
                .as_ref()?
                .get("temperature_unit_name")?
                .as_str()
                .map(String::from)
        })
        .unwrap_or_else(|| "E_cb".to_string())
}

/// The points table (HTML) of `rows` (point order), `page_of` giving a job's page and
/// `label_of` its label with the trust mark.
pub(super) fn points_table(
    sweep: &SweepRow,
    rows: &[PointRow],
    page_of: &dyn Fn(&PointRow) -> String,
    label_of: &dyn Fn(&PointRow) -> String,
) -> String {
    let unit = temperature_unit(rows);
    // (sort key, header text, title)
    let mut heads: Vec<(String, String, String)> = vec![(
        "point".into(),
        "point".into(),
        "the grid position's page".into(),
    )];
    for a in &sweep.axes {
        heads.push((a.name.clone(), a.label.clone(), format!("axis {}", a.key)));
    }
    let fixed = [
        ("replica", "replica", "replica of the grid position"),
        (
            "label",
            "label",
            "the phase; ? may still change, ~ kept by its trend",
        ),
        ("T_g", "", "granular temperature over the stationary window"),
        ("bridges", "bridges / grain", "capillary bridges per grain"),
        (
            "D_lat",
            "D_lat",
            "lateral mobility over the long lag, d² per time unit",
        ),
        ("trend", "trend", "what the whole system's history did"),
        (
            "decided_by",
            "decided by",
            "the criterion of the label (red: a fallback); the numbers in its tooltip",
        ),
        ("sim_time", "sim. time", "simulated time, √(d/g)"),
        ("wall_s", "wall s", "wall-clock seconds of the run"),
    ];
    for (key, text, title) in fixed {
        let text = if key == "T_g" {
            format!("T_g / {unit}")
        } else {
            text.to_string()
        };
        heads.push((key.into(), text, title.into()));
    }
    let mut h = String::from("<table id=\"points-table\" class=\"points\">\n<thead><tr>");
    for (key, text, title) in &heads {
        h.push_str(&format!(
            "<th data-key=\"{}\" title=\"{}\">{}</th>",
            esc(key),
            esc(title),
            esc(text)
        ));
    }
    h.push_str("</tr></thead>\n<tbody>\n");
    for r in rows {
        let page = page_of(r);
        let mut cells: Vec<Cell> = vec![Cell {
            html: format!(
                "<a href=\"{page}\">{}</a>",
                esc(page.trim_start_matches("points/").trim_end_matches(".html"))
            ),
            sort: Some(r.point.to_string()),
            numeric: true,
        }];
        for v in &r.coords {
            cells.push(match v.as_f64() {
                Some(x) => number(Some(x)),
                None => words(
                    v.as_str()
                        .map_or_else(|| v.to_string(), String::from)
                        .as_str(),
                ),
            });
        }
        cells.push(number(Some(r.replica as f64)));
        cells.push(label_cell(r, &label_of(r)));
        cells.push(number(observable(r, "/granular_temperature_reduced")));
        cells.push(number(observable(r, "/bridges_per_particle")));
        cells.push(number(observable(r, "/mobility/diffusion")));
        cells.push(match r.trend {
            Some(t) => words(&t.to_string()),
            None => words(""),
        });
        cells.push(decided_by_cell(r));
        cells.push(number(r.simulated_time));
        cells.push(number(r.wall_seconds));
        h.push_str("<tr>");
        for c in cells {
            let class = if c.numeric { " class=\"num\"" } else { "" };
            let v = c.sort.as_deref().map(esc).unwrap_or_default();
            h.push_str(&format!("<td{class} data-v=\"{v}\">{}</td>", c.html));
        }
        h.push_str("</tr>\n");
    }
    h.push_str("</tbody>\n</table>\n");
    h
}
