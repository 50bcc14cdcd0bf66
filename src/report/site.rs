//! The static HTML report of a sweep (`wetgran report`): plain HTML and SVG files that open
//! offline in any browser, no script. [`site`] turns the sweep's data and pictures into the
//! files (path relative to the report's folder, content); the CLI gathers the data and writes
//! them.
//!
//! Layout:
//! - `index.html`: the phase map (`map.svg`) with every drawn point a link (an HTML image map,
//!   `<map>`/`<area>`), the table of every grid position with its labels, the boundaries table,
//!   the order parameters along the lines (`lines.svg`, `lines.csv`), the sweep file
//!   (`sweep.toml`) and the command lines that reproduce the report;
//! - `points/point-N.html`: one page per grid position (N: the lowest point index there; the
//!   branches of an `initial.start` axis share a page): per job its label, trend and trust, the
//!   numbers the label was decided on, its snapshot (`points/JOB-snapshot.svg`, from the stored
//!   final state) and lateral profiles (`points/JOB-profiles.svg`), and the curves of its line of
//!   constant Gamma (`lines/gamma-K.svg`).

use super::lines::Lines;
use super::plot_phase::DrawnMap;
use super::point_text::decision_text;
use crate::boundary::START_AXIS;
use crate::store::{PointRow, SweepRow};
use std::collections::{BTreeMap, HashMap};
use std::fmt::Write as _;
use wetgran_core::observe::criterion::DecidedBy;

/// The pictures of one job, as SVG text, and why one is missing.
#[derive(Debug, Clone, Default)]
pub struct JobPictures {
    pub snapshot: Option<String>,
    pub profiles: Option<String>,
    pub notes: Vec<String>,
}

/// What a report is made of.
#[derive(Debug)]
pub struct SiteInput<'a> {
    pub sweep: &'a SweepRow,
    /// The sweep file's text as registered.
    pub source: &'a str,
    /// The database path as given on the command line (for the command lines).
    pub db: &'a str,
    /// The report folder as given (for the command lines).
    pub out: &'a str,
    pub rows: &'a [PointRow],
    /// The drawn map, or why there is none.
    pub map: Result<&'a DrawnMap, String>,
    /// The plane's axis indices `(x, y)` in the coordinates.
    pub plane: Option<(usize, usize)>,
    /// The text of `wetgran boundaries` for the sweep.
    pub boundaries: &'a str,
    /// The text of `wetgran boundaries --sensitivity` for the sweep, or why there is none.
    pub sensitivity: Result<&'a str, String>,
    /// The lines of constant Gamma, their SVG (all lines) and one SVG per Gamma (the order of
    /// `Lines::gammas`); `None` for a sweep that is not a shaking one.
    pub lines: Option<(&'a Lines, &'a str, &'a [String])>,
    /// Pictures by job id.
    pub pictures: &'a HashMap<String, JobPictures>,
}

/// Escapes text for HTML content and attribute values.
pub fn esc(s: &str) -> String {
    super::svg::esc(s)
        .replace('"', "&quot;")
        .replace('\'', "&#39;")
}

/// A grid position: the coordinates without the start axis, its jobs and its page.
struct Position<'a> {
    coords: Vec<(String, serde_json::Value)>,
    jobs: Vec<&'a PointRow>,
    page: String,
}

impl Position<'_> {
    /// The labels of its jobs with their trust marks, joined by `sep`.
    fn labels(&self, sep: &str) -> String {
        let labels: Vec<String> = self.jobs.iter().map(|j| mark_label(j)).collect();
        labels.join(sep)
    }

    /// The criterion that decided each job's label (`observe::criterion`), as HTML: a fallback
    /// marked, the numbers compared in the title; `-` where a job has none.
    fn decided_by(&self) -> String {
        let cells: Vec<String> = self
            .jobs
            .iter()
            .map(
                |j| match j.decided_on.as_ref().and_then(DecidedBy::of_json) {
                    Some(by) if by.fallback => format!(
                        "<span class=\"untrusted\" title=\"{}\">{} (fallback)</span>",
                        esc(&by.summary),
                        by.criterion
                    ),
                    Some(by) => format!(
                        "<span title=\"{}\">{}</span>",
                        esc(&by.summary),
                        by.criterion
                    ),
                    None => "-".to_string(),
                },
            )
            .collect();
        cells.join(" ")
    }
}

fn positions<'a>(sweep: &SweepRow, rows: &'a [PointRow]) -> Vec<Position<'a>> {
    let start = sweep.axes.iter().position(|a| a.key == START_AXIS);
    let mut out: Vec<Position<'a>> = Vec::new();
    let mut by_key: HashMap<String, usize> = HashMap::new();
    for r in rows {
        let coords: Vec<(String, serde_json::Value)> = sweep
            .axes
            .iter()
            .zip(&r.coords)
            .enumerate()
            .filter(|(k, _)| Some(*k) != start)
            .map(|(_, (a, v))| (a.label.clone(), v.clone()))
            .collect();
        let key =
            serde_json::Value::from(coords.iter().map(|(_, v)| v.clone()).collect::<Vec<_>>())
                .to_string();
        match by_key.get(&key) {
            Some(&k) => out[k].jobs.push(r),
            None => {
                by_key.insert(key, out.len());
                out.push(Position {
                    coords,
                    jobs: vec![r],
                    page: String::new(),
                });
            }
        }
    }
    for p in &mut out {
        let first = p.jobs.iter().map(|j| j.point).min().unwrap_or(0);
        p.page = format!("points/point-{first}.html");
    }
    out
}

fn coords_text(coords: &[(String, serde_json::Value)]) -> String {
    coords
        .iter()
        .map(|(l, v)| match v.as_f64() {
            Some(x) => format!("{l} = {}", super::svg::label(x)),
            None => format!("{l} = {v}"),
        })
        .collect::<Vec<_>>()
        .join(", ")
}

fn head(title: &str, up: &str) -> String {
    format!(
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
         <title>{}</title>\n<link rel=\"stylesheet\" href=\"{up}style.css\">\n</head>\n<body>\n",
        esc(title)
    )
}

/// The style sheet of every page.
const STYLE: &str = "body { font-family: sans-serif; margin: 1.5em; max-width: 1300px; }\n\
table { border-collapse: collapse; }\n\
td, th { border: 1px solid #ccc; padding: 2px 8px; text-align: left; }\n\
pre { background: #f6f6f6; padding: 0.6em; overflow-x: auto; }\n\
img { max-width: 100%; }\n\
img[usemap] { max-width: none; }\n\
.untrusted { color: #a00; }\n";

/// The label of a job with its trust mark (`g?`, `g~`).
fn mark_label(r: &PointRow) -> String {
    let phase = r.phase.clone().unwrap_or_else(|| r.status.clone());
    match super::trust::mark(r.trust()) {
        Some(m) if r.status == "done" => format!("{phase}{m}"),
        _ => phase,
    }
}

fn branch_of(sweep: &SweepRow, r: &PointRow) -> Option<String> {
    let k = sweep.axes.iter().position(|a| a.key == START_AXIS)?;
    r.coords.get(k)?.as_str().map(crate::boundary::branch_words)
}

/// The files of the report of `input` (module doc): `(path, content)`, paths relative to the
/// report's folder with `/` separators.
pub fn site(input: &SiteInput) -> Vec<(String, String)> {
    let sweep = input.sweep;
    let positions = positions(sweep, input.rows);
    let mut files: Vec<(String, String)> = vec![
        ("style.css".to_string(), STYLE.to_string()),
        ("sweep.toml".to_string(), input.source.to_string()),
    ];
    if let Ok(map) = &input.map {
        files.push(("map.svg".to_string(), map.svg.clone()));
    }
    let mut line_of_job: HashMap<&str, usize> = HashMap::new();
    if let Some((lines, all, per_gamma)) = input.lines {
        files.push(("lines.svg".to_string(), all.to_string()));
        files.push(("lines.csv".to_string(), super::lines::lines_csv(lines)));
        let gammas = lines.gammas();
        for (k, svg) in per_gamma.iter().enumerate() {
            files.push((format!("lines/gamma-{k}.svg"), svg.clone()));
        }
        for l in &lines.lines {
            if let Some(k) = gammas.iter().position(|g| *g == l.gamma) {
                for p in &l.points {
                    line_of_job.insert(p.job_id.as_str(), k);
                }
            }
        }
    }
    files.push(("index.html".to_string(), index(input, &positions)));
    for p in &positions {
        files.push((p.page.clone(), point_page(input, p, &line_of_job)));
        for j in &p.jobs {
            if let Some(pics) = input.pictures.get(&j.job_id) {
                if let Some(s) = &pics.snapshot {
                    files.push((format!("points/{}-snapshot.svg", j.job_id), s.clone()));
                }
                if let Some(s) = &pics.profiles {
                    files.push((format!("points/{}-profiles.svg", j.job_id), s.clone()));
                }
            }
        }
    }
    files
}

/// The page a drawn map point links to: the position whose plane coordinates are the point's.
fn page_at<'a>(
    positions: &'a [Position],
    rows_plane: (usize, usize),
    x: f64,
    y: f64,
) -> Option<&'a Position<'a>> {
    let near = |a: f64, b: f64| (a - b).abs() <= 1e-9 * a.abs().max(b.abs());
    positions.iter().find(|p| {
        p.jobs.first().is_some_and(|j| {
            let v = |k: usize| j.coords.get(k).and_then(|v| v.as_f64());
            v(rows_plane.0).is_some_and(|a| near(a, x))
                && v(rows_plane.1).is_some_and(|b| near(b, y))
        })
    })
}

/// The map section of the index: the map with an image map of links to the points' pages.
fn map_section(input: &SiteInput, positions: &[Position]) -> String {
    let sweep = input.sweep;
    let mut h = String::new();
    let _ = writeln!(h, "<h2 id=\"map\">Phase map</h2>");
    match (&input.map, input.plane) {
        (Ok(map), Some(plane)) => {
            let _ = writeln!(
                h,
                "<p>Click a point for its page.</p>\n<img src=\"map.svg\" usemap=\"#points\" \
                 width=\"{}\" height=\"{}\" alt=\"phase map of {}\">\n<map name=\"points\">",
                map.width,
                map.height,
                esc(&sweep.name)
            );
            for &(x, y, px, py) in &map.points {
                if let Some(p) = page_at(positions, plane, x, y) {
                    let what = format!("{}: {}", coords_text(&p.coords), p.labels("/"));
                    let _ = writeln!(
                        h,
                        "<area shape=\"circle\" coords=\"{px},{py},9\" href=\"{}\" alt=\"{}\" \
                         title=\"{}\">",
                        p.page,
                        esc(&what),
                        esc(&what)
                    );
                }
            }
            let _ = writeln!(h, "</map>");
        }
        (Err(e), _) => {
            let _ = writeln!(h, "<p class=\"untrusted\">No map: {}</p>", esc(e));
        }
        (Ok(_), None) => {
            let _ = writeln!(
                h,
                "<p>No map: the sweep has no plane of two numeric axes.</p>"
            );
        }
    }
    h
}

fn index(input: &SiteInput, positions: &[Position]) -> String {
    let sweep = input.sweep;
    let mut h = head(&format!("wetgran report: {}", sweep.name), "");
    let _ = writeln!(h, "<h1>Sweep {}</h1>", esc(&sweep.name));
    if let Some(d) = &sweep.description {
        let _ = writeln!(h, "<p>{}</p>", esc(d));
    }
    let done = input.rows.iter().filter(|r| r.status == "done").count();
    let mut labels: BTreeMap<String, usize> = BTreeMap::new();
    for r in input.rows.iter().filter(|r| r.status == "done") {
        *labels.entry(mark_label(r)).or_default() += 1;
    }
    let _ = writeln!(
        h,
        "<p>{} jobs, {done} finished; labels: {}. A mark after a label: <code>?</code> the \
         run did not settle and its label may still change, <code>~</code> every region its \
         label names settled, some numbers still drift. Written by wetgran {}.</p>",
        input.rows.len(),
        labels
            .iter()
            .map(|(l, n)| format!("{} &times; {n}", esc(l)))
            .collect::<Vec<_>>()
            .join(", "),
        env!("CARGO_PKG_VERSION")
    );
    let _ = writeln!(
        h,
        "<p>Contents: <a href=\"#map\">phase map</a> &middot; <a href=\"#points\">points</a> \
         &middot; <a href=\"#boundaries\">boundaries</a> &middot; <a href=\"#sensitivity\">\
         sensitivity</a> &middot; <a href=\"#lines\">lines of \
         constant Gamma</a> &middot; <a href=\"#sweep\">sweep file</a> &middot; \
         <a href=\"#reproduce\">reproduce</a></p>"
    );
    h.push_str(&map_section(input, positions));
    let _ = writeln!(
        h,
        "<h2 id=\"points\">Points</h2>\n<p><em>decided by</em>: the criterion of each job's \
         label (docs/classification.md; the numbers compared in its tooltip), in red where a \
         fallback decided it.</p>\n<table>\n<tr><th>point</th><th>coordinates</th>\
         <th>labels (jobs)</th><th>decided by</th></tr>"
    );
    for p in positions {
        let _ = writeln!(
            h,
            "<tr><td><a href=\"{}\">{}</a></td><td>{}</td><td>{}</td><td>{}</td></tr>",
            p.page,
            esc(p
                .page
                .trim_start_matches("points/")
                .trim_end_matches(".html")),
            esc(&coords_text(&p.coords)),
            esc(&p.labels(" ")),
            p.decided_by()
        );
    }
    let _ = writeln!(h, "</table>");
    let _ = writeln!(
        h,
        "<h2 id=\"boundaries\">Boundaries</h2>\n<pre>{}</pre>",
        esc(input.boundaries)
    );
    let _ = writeln!(
        h,
        "<h2 id=\"sensitivity\">Sensitivity to the thresholds</h2>\n<p>How far each boundary \
         moves when one label-deciding threshold is varied by 0.5 and by 2 (relabelled from the \
         stored observables; docs/classification.md).</p>"
    );
    match &input.sensitivity {
        Ok(text) => {
            let _ = writeln!(h, "<pre>{}</pre>", esc(text));
        }
        Err(e) => {
            let _ = writeln!(h, "<p class=\"untrusted\">Not measured: {}</p>", esc(e));
        }
    }
    let _ = writeln!(h, "<h2 id=\"lines\">Lines of constant Gamma</h2>");
    if input.lines.is_some() {
        let _ = writeln!(
            h,
            "<p>The order parameters against E* along each line (<a href=\"lines.csv\">CSV</a>).\
             </p>\n<img src=\"lines.svg\" alt=\"order parameters along lines of constant Gamma\">"
        );
    } else {
        let _ = writeln!(h, "<p>Not a shaking sweep: no lines of constant Gamma.</p>");
    }
    let _ = writeln!(
        h,
        "<h2 id=\"sweep\">Sweep file</h2>\n<p><a href=\"sweep.toml\">sweep.toml</a> (registered \
         from <code>{}</code>; its <code>base</code> scene is found relative to that file)</p>\n\
         <pre>{}</pre>",
        esc(&sweep.file),
        esc(input.source)
    );
    let _ = writeln!(
        h,
        "<h2 id=\"reproduce\">Reproduce</h2>\n<pre>{}</pre>",
        esc(&commands(input))
    );
    h.push_str("</body>\n</html>\n");
    h
}

/// A word (a path, a sweep name) for a shell command line: quoted where it holds anything but
/// letters, digits and `_-./+,:=@`.
pub(crate) fn shell_word(s: &str) -> String {
    let plain = !s.is_empty()
        && s.chars()
            .all(|c| c.is_ascii_alphanumeric() || "_-./+,:=@".contains(c));
    if plain {
        s.to_string()
    } else {
        format!("'{}'", s.replace('\'', r"'\''"))
    }
}

/// The command lines that make the database and this report again.
fn commands(input: &SiteInput) -> String {
    let (db, name) = (input.db, &input.sweep.name);
    format!(
        "# run the grid (and any `sweep refine` or `sweep resume --extend` rounds it had)\n\
         wetgran sweep run {file} --db {db}\n\
         # the tables and pictures of this report\n\
         wetgran boundaries --db {db} --sweep {name}\n\
         wetgran boundaries --db {db} --sweep {name} --sensitivity\n\
         wetgran plot --db {db} --sweep {name} -o map.svg\n\
         wetgran lines --db {db} --sweep {name} -o lines.svg --csv lines.csv\n\
         wetgran report --db {db} --sweep {name} -o {out}\n",
        file = shell_word(&input.sweep.file),
        db = shell_word(db),
        name = shell_word(name),
        out = shell_word(input.out),
    )
}

fn point_page(input: &SiteInput, p: &Position, line_of_job: &HashMap<&str, usize>) -> String {
    let sweep = input.sweep;
    let title = format!("{}: {}", sweep.name, coords_text(&p.coords));
    let mut h = head(&title, "../");
    let _ = writeln!(
        h,
        "<p><a href=\"../index.html\">&larr; sweep {}</a></p>\n<h1>{}</h1>",
        esc(&sweep.name),
        esc(&coords_text(&p.coords))
    );
    let mut lines_shown: Vec<usize> = Vec::new();
    for j in &p.jobs {
        let branch = branch_of(sweep, j)
            .map(|b| format!("{b}, "))
            .unwrap_or_default();
        let _ = writeln!(
            h,
            "<h2>{}replica {}: {}</h2>\n<p>job <code>{}</code>, status {}</p>",
            esc(&branch),
            j.replica,
            esc(&mark_label(j)),
            j.job_id,
            esc(&j.status)
        );
        if let Some(e) = &j.last_error {
            let _ = writeln!(h, "<p class=\"untrusted\">last error: {}</p>", esc(e));
        }
        let why = decision_text(j);
        if !why.is_empty() {
            let _ = writeln!(
                h,
                "<h3>Label, run state and the numbers it was decided on</h3>\n<pre>{}</pre>",
                esc(&why)
            );
        }
        if let Some(pics) = input.pictures.get(&j.job_id) {
            if pics.snapshot.is_some() {
                let _ = writeln!(
                    h,
                    "<h3>Final configuration</h3>\n<img src=\"{0}-snapshot.svg\" \
                     alt=\"snapshot of job {0}\">",
                    j.job_id
                );
            }
            if pics.profiles.is_some() {
                let _ = writeln!(
                    h,
                    "<h3>Lateral profiles</h3>\n<img src=\"{0}-profiles.svg\" \
                     alt=\"profiles of job {0}\">",
                    j.job_id
                );
            }
            for n in &pics.notes {
                let _ = writeln!(h, "<p>{}</p>", esc(n));
            }
        }
        let _ = writeln!(
            h,
            "<p>Again from the database: <code>wetgran show --db {} {} --snapshot \
             snapshot.xyz --profiles profiles.svg</code></p>",
            esc(input.db),
            &j.job_id[..12.min(j.job_id.len())]
        );
        if let Some(&k) = line_of_job.get(j.job_id.as_str())
            && !lines_shown.contains(&k)
        {
            lines_shown.push(k);
        }
    }
    for k in lines_shown {
        let _ = writeln!(
            h,
            "<h2>Its line of constant Gamma</h2>\n<img src=\"../lines/gamma-{k}.svg\" \
             alt=\"order parameters along its line of constant Gamma\">"
        );
    }
    h.push_str("</body>\n</html>\n");
    h
}
