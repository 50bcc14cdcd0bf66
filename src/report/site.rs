//! The static HTML report of a sweep (`wetgran report`): plain HTML and SVG files that open
//! offline in any browser. [`site`] turns the sweep's data and pictures into the files (path
//! relative to the report's folder, content); the CLI gathers the data and writes them. One
//! small script (`sort.js`, the points table's sorting) is the only script; every page reads
//! in full without it.
//!
//! Layout:
//! - `index.html`: a summary of the labels; the phase map (`map.svg`) with every drawn point a
//!   link (an HTML image map, `<map>`/`<area>`); the points table (`site::points_table`: one
//!   row per job, sortable); the boundaries as tables (`site::boundaries`, from the phase map);
//!   their sensitivity to the thresholds; the order parameters along the lines (`lines.svg`,
//!   `lines.csv`); the table of the physical parameters (`site::parameters`, from the jobs'
//!   scenes) with the scene of the first job (`scene.toml`); the sweep file (`sweep.toml`) and
//!   the command lines that reproduce the report;
//! - `points/point-N.html`: one page per grid position (N: the lowest point index there; the
//!   branches of an `initial.start` axis share a page): per job its facts (id, status, cost),
//!   the decision section ([`decision_section`]: the decision summary of `wetgran show`,
//!   `point_text::decision_text`), its time series (`points/JOB-series.svg`, `series_plot`, as
//!   `show --series` draws them), its snapshot (`points/JOB-snapshot.svg`, from the stored final state) and
//!   lateral profiles (`points/JOB-profiles.svg`) side by side, and, folded away
//!   (`<details>`), the stored decision and observables as JSON and the job's scene as TOML;
//!   then the curves of its line of constant Gamma (`lines/gamma-K.svg`);
//! - `style.css` (readable on a laptop, a print layout) and `sort.js`.

mod boundaries;
mod parameters;
mod points_table;

use super::lines::Lines;
use super::plot_phase::DrawnMap;
use super::point_text::decision_text;
use crate::boundary::{Extraction, PhaseMap, START_AXIS};
use crate::store::{PointRow, PointSummary, SweepRow};
use std::collections::{BTreeMap, HashMap};
use std::fmt::Write as _;
use wetgran_core::observe::criterion::DecidedBy;

/// The pictures of one job, as SVG text, and why one is missing.
#[derive(Debug, Clone, Default)]
pub struct JobPictures {
    pub snapshot: Option<String>,
    pub profiles: Option<String>,
    /// The time series (`series_plot`).
    pub series: Option<String>,
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
    /// The sweep's phase map and boundaries (`boundary::phase_map`), as `wetgran boundaries`
    /// makes them with `how`, and the summaries they were made of.
    pub phase_map: &'a PhaseMap,
    pub summaries: &'a [PointSummary],
    pub how: Extraction,
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

/// The style sheet of every page (`style.css`).
const STYLE: &str = include_str!("site/style.css");

/// The points table's sorting (`sort.js`, `site::points_table`).
const SORT_SCRIPT: &str = include_str!("site/sort.js");

/// The start of a page: its head (title, style sheet; `up`: the way to the report's folder)
/// and the bar at its top with the sweep's name and, on the index, the contents.
fn head(title: &str, up: &str, sweep: &str, contents: &[(&str, &str)]) -> String {
    let mut h = format!(
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
         <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n\
         <title>{}</title>\n<link rel=\"stylesheet\" href=\"{up}style.css\">\n</head>\n<body>\n\
         <header class=\"top\"><span class=\"title\"><a href=\"{up}index.html\">wetgran report: \
         sweep {}</a></span>",
        esc(title),
        esc(sweep)
    );
    if !contents.is_empty() {
        h.push_str("<nav>");
        for (id, text) in contents {
            let _ = write!(h, "<a href=\"#{id}\">{text}</a>");
        }
        h.push_str("</nav>");
    }
    h.push_str("</header>\n<main>\n");
    h
}

/// The end of a page; `script`: whether the sort script (on the index) is loaded.
fn foot(script: bool) -> String {
    let mut h = format!(
        "<p class=\"note\">Written by wetgran {} from the sweep's database; nothing was run.</p>\n\
         </main>\n",
        env!("CARGO_PKG_VERSION")
    );
    if script {
        h.push_str("<script src=\"sort.js\"></script>\n");
    }
    h.push_str("</body>\n</html>\n");
    h
}

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

/// The scene of a job as TOML (what `wetgran simulate` reads), or why it does not print.
fn scene_toml(r: &PointRow) -> String {
    toml::to_string(&r.spec.scene)
        .unwrap_or_else(|e| format!("# the scene does not print as TOML: {e}\n"))
}

/// The files of the report of `input` (module doc): `(path, content)`, paths relative to the
/// report's folder with `/` separators.
pub fn site(input: &SiteInput) -> Vec<(String, String)> {
    let sweep = input.sweep;
    let positions = positions(sweep, input.rows);
    let mut files: Vec<(String, String)> = vec![
        ("style.css".to_string(), STYLE.to_string()),
        ("sort.js".to_string(), SORT_SCRIPT.to_string()),
        ("sweep.toml".to_string(), input.source.to_string()),
    ];
    if let Some(first) = input.rows.first() {
        files.push(("scene.toml".to_string(), scene_toml(first)));
    }
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
                if let Some(s) = &pics.series {
                    files.push((format!("points/{}-series.svg", j.job_id), s.clone()));
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
    let _ = writeln!(h, "<section id=\"map\">\n<h2>Phase map</h2>");
    match (&input.map, input.plane) {
        (Ok(map), Some(plane)) => {
            let _ = writeln!(
                h,
                "<p class=\"lead\">One disc per grid point, coloured by its label; click one for \
                 its page.</p>\n<div class=\"mapbox\"><img src=\"map.svg\" usemap=\"#points\" \
                 width=\"{}\" height=\"{}\" alt=\"phase map of {}\"></div>\n<map name=\"points\">",
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
    h.push_str("</section>\n");
    h
}

/// The index's contents: (anchor, text).
const CONTENTS: &[(&str, &str)] = &[
    ("map", "phase map"),
    ("points", "points"),
    ("boundaries", "boundaries"),
    ("sensitivity", "sensitivity"),
    ("lines", "lines of constant Γ"),
    ("parameters", "parameters"),
    ("sweep", "sweep file"),
    ("reproduce", "reproduce"),
];

/// The parameters section of the index: the table and the first point's scene.
fn parameters_section(input: &SiteInput) -> String {
    let mut h = String::new();
    let scenes: Vec<&wetgran_core::scene::Scene> =
        input.rows.iter().map(|r| &r.spec.scene).collect();
    let _ = writeln!(
        h,
        "<section id=\"parameters\">\n<h2>Parameters</h2>\n<p class=\"lead\">The physical \
         constants of the jobs' scenes (units of the mean diameter <i>d</i>, the grain mass \
         <i>m</i> and gravity <i>g</i>, docs/model.md 1); a shaded row varies over the jobs \
         (an axis, or what follows from one).</p>\n<div class=\"scroll\">{}</div>",
        parameters::parameters_table(&scenes)
    );
    if let Some(first) = input.rows.first() {
        let _ = writeln!(
            h,
            "<details><summary>The scene of point {} (TOML, every default filled in; \
             <code>wetgran simulate</code> reads it)</summary>\n<p><a href=\"scene.toml\">\
             scene.toml</a>: the sweep's base scene with the axis values of this point.</p>\n\
             <pre>{}</pre></details>",
            first.point,
            esc(&scene_toml(first))
        );
    }
    h.push_str("</section>\n");
    h
}

/// The boundaries section of the index: the tables of `site::boundaries`.
fn boundaries_section(input: &SiteInput, positions: &[Position]) -> String {
    let mut h = String::new();
    // The page of a map point by its coordinates (every axis, the start axis included).
    let page_of_coords: HashMap<String, &str> = positions
        .iter()
        .flat_map(|p| {
            p.jobs.iter().map(|j| {
                (
                    serde_json::Value::from(j.coords.clone()).to_string(),
                    p.page.as_str(),
                )
            })
        })
        .collect();
    let _ = writeln!(
        h,
        "<section id=\"boundaries\">\n<h2>Boundaries</h2>\n<p class=\"lead\">The boundary \
         points between two phases, as <code>wetgran boundaries</code> finds them: each halfway \
         along an edge between neighbouring grid points of different phase, with half that \
         edge as its uncertainty (decades on a logarithmic axis) and the share of replicas at \
         its two ends that agree with their majority.</p>\n{}</section>",
        boundaries::boundaries_html(
            input.phase_map,
            input.summaries,
            input.how,
            &|coords: &[serde_json::Value]| page_of_coords
                .get(&serde_json::Value::from(coords.to_vec()).to_string())
                .map(|p| p.to_string())
        )
    );
    h
}

fn index(input: &SiteInput, positions: &[Position]) -> String {
    let sweep = input.sweep;
    let mut h = head(
        &format!("wetgran report: {}", sweep.name),
        "",
        &sweep.name,
        CONTENTS,
    );
    let _ = writeln!(h, "<h1>Sweep {}</h1>", esc(&sweep.name));
    if let Some(d) = &sweep.description {
        let _ = writeln!(h, "<p class=\"lead\">{}</p>", esc(d));
    }
    let done = input.rows.iter().filter(|r| r.status == "done").count();
    let mut labels: BTreeMap<String, usize> = BTreeMap::new();
    for r in input.rows.iter().filter(|r| r.status == "done") {
        *labels.entry(mark_label(r)).or_default() += 1;
    }
    let fallbacks = input
        .rows
        .iter()
        .filter_map(|r| r.decided_on.as_ref().and_then(DecidedBy::of_json))
        .filter(|by| by.fallback)
        .count();
    let _ = writeln!(
        h,
        "<p>{} jobs at {} grid positions, {done} finished; labels: {}; {fallbacks} label(s) \
         rest on a fallback criterion. A mark after a label: <code>?</code> the run did not \
         settle and its label may still change, <code>~</code> every region its label names \
         settled, some numbers still drift.</p>",
        input.rows.len(),
        positions.len(),
        labels
            .iter()
            .map(|(l, n)| format!("<b>{}</b> &times; {n}", esc(l)))
            .collect::<Vec<_>>()
            .join(", ")
    );
    h.push_str(&map_section(input, positions));
    let page_of_row: HashMap<&str, &str> = positions
        .iter()
        .flat_map(|p| p.jobs.iter().map(|j| (j.job_id.as_str(), p.page.as_str())))
        .collect();
    let _ = writeln!(
        h,
        "<section id=\"points\">\n<h2>Points</h2>\n<p class=\"lead\">One row per job. Click a \
         header to sort by it (again: the other way; the address keeps the order, \
         <code>#sort=T_g</code>). <i>decided by</i>: the criterion of the label \
         (docs/classification.md), red where a fallback decided it, the numbers compared in \
         its tooltip; <i>D_lat</i>: the lateral mobility (d² per time unit) over the long \
         lag.</p>\n<div class=\"scroll\">{}</div>\n</section>",
        points_table::points_table(
            sweep,
            input.rows,
            &|r: &PointRow| page_of_row
                .get(r.job_id.as_str())
                .map_or_else(String::new, |p| p.to_string()),
            &mark_label,
        )
    );
    h.push_str(&boundaries_section(input, positions));
    let _ = writeln!(
        h,
        "<section id=\"sensitivity\">\n<h2>Sensitivity to the thresholds</h2>\n<p \
         class=\"lead\">How far each boundary moves when one label-deciding threshold is varied \
         by 0.5 and by 2 (relabelled from the stored observables; docs/classification.md), as \
         <code>wetgran boundaries --sensitivity</code> prints it.</p>"
    );
    match &input.sensitivity {
        Ok(text) => {
            let _ = writeln!(h, "<pre>{}</pre>", esc(text));
        }
        Err(e) => {
            let _ = writeln!(h, "<p class=\"untrusted\">Not measured: {}</p>", esc(e));
        }
    }
    h.push_str("</section>\n<section id=\"lines\">\n<h2>Lines of constant Γ</h2>\n");
    if input.lines.is_some() {
        let _ = writeln!(
            h,
            "<p class=\"lead\">The order parameters against E* along each line \
             (<a href=\"lines.csv\">CSV</a>).</p>\n<figure><img src=\"lines.svg\" alt=\"order \
             parameters along lines of constant Gamma\"></figure>"
        );
    } else {
        let _ = writeln!(h, "<p>Not a shaking sweep: no lines of constant Gamma.</p>");
    }
    h.push_str("</section>\n");
    h.push_str(&parameters_section(input));
    let _ = writeln!(
        h,
        "<section id=\"sweep\">\n<h2>Sweep file</h2>\n<p><a href=\"sweep.toml\">\
         sweep.toml</a> (registered from <code>{}</code>; its <code>base</code> scene is found \
         relative to that file)</p>\n<pre>{}</pre>\n</section>",
        esc(&sweep.file),
        esc(input.source)
    );
    let _ = writeln!(
        h,
        "<section id=\"reproduce\">\n<h2>Reproduce</h2>\n<pre>{}</pre>\n</section>",
        esc(&commands(input))
    );
    h.push_str(&foot(true));
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

/// The decision section of a job's page: its label, its run state and the numbers it was
/// decided on.
///
/// The slot of `wetgran show`'s decision summary and time-series figure (issue 45): until they
/// arrive, the text of `show` without its JSON (which the page folds away below).
fn decision_section(j: &PointRow) -> String {
    let why = decision_text(j);
    let text: Vec<&str> = why
        .lines()
        .take_while(|l| !l.starts_with("decided on"))
        .collect();
    if text.is_empty() {
        return String::new();
    }
    format!(
        "<section class=\"decision\">\n<h3>Decision: label, criterion, regions, run state</h3>\n<pre>{}</pre>\n</section>\n",
        esc(&text.join("\n"))
    )
}

/// The stored records of a job, folded away: its decision and observables as JSON, its scene
/// as TOML.
fn raw_records(j: &PointRow) -> String {
    let mut h = String::new();
    let json = |v: &serde_json::Value| serde_json::to_string_pretty(v).expect("JSON prints");
    if let Some(d) = &j.decided_on {
        let _ = writeln!(
            h,
            "<details><summary>decided on (the stored decision, JSON)</summary>\n<pre>{}</pre>\
             </details>",
            esc(&json(d))
        );
    }
    if let Some(o) = &j.observables {
        let _ = writeln!(
            h,
            "<details><summary>observables (JSON)</summary>\n<pre>{}</pre></details>",
            esc(&json(o))
        );
    }
    let _ = writeln!(
        h,
        "<details><summary>the scene this job ran (TOML)</summary>\n<pre>{}</pre></details>",
        esc(&scene_toml(j))
    );
    h
}

/// The facts of a job in one line: id, status, cost.
fn facts(j: &PointRow) -> String {
    let mut h = format!(
        "<div class=\"facts\"><div><b>job</b><code>{}</code></div><div><b>status</b>{}</div>",
        j.job_id,
        esc(&j.status)
    );
    let num = |x: f64| crate::run::runner::short(x);
    if let Some(t) = j.simulated_time {
        let _ = write!(h, "<div><b>simulated</b>{} √(d/g)</div>", num(t));
    }
    if let Some(w) = j.wall_seconds {
        let _ = write!(h, "<div><b>wall time</b>{} s</div>", num(w));
    }
    if let Some(e) = j.events {
        let _ = write!(h, "<div><b>events</b>{e}</div>");
    }
    h.push_str("</div>\n");
    h
}

fn point_page(input: &SiteInput, p: &Position, line_of_job: &HashMap<&str, usize>) -> String {
    let sweep = input.sweep;
    let title = format!("{}: {}", sweep.name, coords_text(&p.coords));
    let mut h = head(&title, "../", &sweep.name, &[]);
    let _ = writeln!(
        h,
        "<p><a href=\"../index.html#points\">&larr; all points of sweep {}</a></p>\n<h1>{}</h1>\n\
         <p class=\"lead\">{} job(s): {}</p>",
        esc(&sweep.name),
        esc(&coords_text(&p.coords)),
        p.jobs.len(),
        esc(&p.labels(", "))
    );
    let mut lines_shown: Vec<usize> = Vec::new();
    for j in &p.jobs {
        let branch = branch_of(sweep, j)
            .map(|b| format!("{b}, "))
            .unwrap_or_default();
        let _ = writeln!(
            h,
            "<section class=\"job\" id=\"job-{}\">\n<h2>{}replica {}: {}</h2>",
            &j.job_id[..12.min(j.job_id.len())],
            esc(&branch),
            j.replica,
            esc(&mark_label(j))
        );
        h.push_str(&facts(j));
        if let Some(e) = &j.last_error {
            let _ = writeln!(h, "<p class=\"untrusted\">last error: {}</p>", esc(e));
        }
        h.push_str(&decision_section(j));
        if let Some(pics) = input.pictures.get(&j.job_id) {
            if pics.series.is_some() {
                let _ = writeln!(
                    h,
                    "<h3>Time series: did it settle?</h3>\n<img src=\"{0}-series.svg\" \
                     alt=\"time series of job {0}\">",
                    j.job_id
                );
            }
            let mut figures = String::new();
            if pics.snapshot.is_some() {
                let _ = writeln!(
                    figures,
                    "<figure><img src=\"{0}-snapshot.svg\" alt=\"snapshot of job {0}\">\
                     <figcaption>Final configuration, grains coloured by kinetic energy (from \
                     the stored final state).</figcaption></figure>",
                    j.job_id
                );
            }
            if pics.profiles.is_some() {
                let _ = writeln!(
                    figures,
                    "<figure><img src=\"{0}-profiles.svg\" alt=\"profiles of job {0}\">\
                     <figcaption>Lateral profiles over the stationary window.</figcaption>\
                     </figure>",
                    j.job_id
                );
            }
            if !figures.is_empty() {
                let _ = writeln!(h, "<div class=\"figures\">\n{figures}</div>");
            }
            for n in &pics.notes {
                let _ = writeln!(h, "<p class=\"note\">{}</p>", esc(n));
            }
        }
        h.push_str(&raw_records(j));
        let _ = writeln!(
            h,
            "<p class=\"note\">Again from the database: <code>wetgran show --db {} {} \
             --snapshot snapshot.xyz --profiles profiles.svg --series series.svg</code></p>\n</section>",
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
            "<section>\n<h2>Its line of constant Γ</h2>\n<figure><img src=\"../lines/gamma-{k}.svg\" \
             alt=\"order parameters along its line of constant Gamma\"></figure>\n</section>"
        );
    }
    h.push_str(&foot(false));
    h
}
