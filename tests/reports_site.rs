//! From results to understanding (issue 33, items 3-6): `wetgran lines` (order parameters along
//! lines of constant Gamma, per branch, with errors, run states and label changes), `wetgran
//! report` (a static HTML site: every point has a page, every link and image resolves; its
//! boundaries as tables read from the phase map), the
//! tidy `export` (axes first, informative columns, JSON with the CSV's fields, numeric series)
//! and the SQL of the pandas example in docs/reports.md, run against a real database file.

mod sweep_common;

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use sweep_common::*;
use wetgran::store::Store;
use wetgran::sweep::{JobResult, SweepFile};

/// `T_g / E_cb` of the synthetic result at `E*` on branch `branch` (hot: a gas from E* = 2 on;
/// continuation: from E* = 1 on).
fn temperature(e: f64, continued: bool) -> f64 {
    let gas_from = if continued { 1.0 } else { 2.0 };
    if e >= gas_from { 5.0 * e } else { 0.1 * e }
}

/// A (Gamma 1, 2) x (E* 0.5, 1, 2, 4) x (hot, continue) sweep with synthetic observables: the
/// phase from [`temperature`], E* = 4 on Gamma = 1 heating (label kept), E* = 0.5 on Gamma = 2
/// undecided (label may change). Returns the database.
fn prepared(dir: &Path) -> PathBuf {
    write(dir, "tiny.toml", TINY_SCENE);
    let file = write(
        dir,
        "lines.toml",
        "[sweep]\nname = \"lines\"\nbase = \"tiny.toml\"\nperiods = 6\n\
         [sweep.continuation]\naxis = \"e_star\"\ndirection = \"descending\"\n\
         [[axis]]\nkey = \"gamma\"\nvalues = [1.0, 2.0]\n\
         [[axis]]\nkey = \"e_star\"\nvalues = [0.5, 1.0, 2.0, 4.0]\n\
         [[axis]]\nkey = \"initial.start\"\nvalues = [\"hot\", \"continue\"]\n",
    );
    let sweep = SweepFile::load(&file).unwrap();
    let db = dir.join("lines.sqlite");
    let store = Store::open(&db).unwrap();
    let row = store
        .register_sweep(&sweep, &sweep.expand().unwrap())
        .unwrap();
    let mut n = 0;
    while let Some(c) = store.claim(&[row.id]).expect("claim") {
        let (g, e) = (c.coords[0].as_f64().unwrap(), c.coords[1].as_f64().unwrap());
        let continued = c.coords[2] == "continue";
        let t = temperature(e, continued);
        let phase = if t > 1.0 { "g" } else { "f" };
        let state = match (g as i64, e) {
            (1, 4.0) => "heating",
            (2, 0.5) => "undecided",
            _ => "stationary",
        };
        let test = |q: &str, se: f64| serde_json::json!({"quantity": q, "standard_error": se});
        let result = JobResult {
            checkpoint: None,
            phase: Some(phase.into()),
            decided_on: Some(serde_json::json!({"synthetic": true, "t": t, "settling": {
                "verdict": match state {
                    "stationary" => "stationary",
                    "heating" => "label_kept",
                    _ => "not_settled",
                },
                "regions": []}})),
            observables: serde_json::json!({
                "granular_temperature_reduced": t,
                "bridges_per_particle": 2.0 / (1.0 + t),
                "temperature_unit_name": "E_cb",
                "profiles": {"delta_n_cb": 0.5 / (1.0 + t), "n_cb": [1.0, 2.0 + t, 3.0]},
                "trend": {"state": state, "tests": [
                    test("temperature_reduced", 0.01 * t),
                    test("bridges_per_particle", 0.02),
                    test("delta_n_cb", 0.03)]},
                "checks": [{"quantity": "T_g", "ok": true}],
                // Text entries enough to overflow the export's 8 KiB file buffer mid-run.
                "notes": (0..40).map(|i| format!("note {i} of this job")).collect::<Vec<_>>(),
            }),
            simulated_time: 1.0,
            wall_seconds: 0.01,
            events: 10,
        };
        assert!(store.finish(&c, &result).expect("finish"));
        n += 1;
    }
    // 16 grid points, 14 jobs: the continuation starts at E* = 4 from a hot start, the hot
    // branch's job there (one spec, one job).
    assert_eq!(n, 14);
    db
}

fn ok_stdout(args: &[&str]) -> String {
    let o = run(args);
    assert!(o.status.success(), "{args:?}: {}", stderr(&o));
    stdout(&o)
}

#[test]
fn lines_follow_each_branch_with_errors_states_and_label_changes() {
    let dir = tempfile::tempdir().unwrap();
    let db = prepared(dir.path());
    let db = db.to_str().unwrap();
    let svg = dir.path().join("lines.svg");
    let csv = dir.path().join("lines.csv");
    let json: serde_json::Value = serde_json::from_str(&ok_stdout(&[
        "lines",
        "--db",
        db,
        "-o",
        svg.to_str().unwrap(),
        "--csv",
        csv.to_str().unwrap(),
        "--json",
    ]))
    .unwrap();
    let lines = json["lines"].as_array().unwrap();
    // Two Gamma, two branches each, hot first.
    let keys: Vec<(f64, &str)> = lines
        .iter()
        .map(|l| (l["gamma"].as_f64().unwrap(), l["branch"].as_str().unwrap()))
        .collect();
    assert_eq!(
        keys,
        [
            (1.0, "hot"),
            (1.0, "continue"),
            (2.0, "hot"),
            (2.0, "continue")
        ]
    );
    // Hot: f up to E* = 1, g from 2 (boundary at sqrt(2)); continued: g from 1, but on Gamma = 2
    // its f at E* = 0.5 is undecided, so no trusted label change there.
    let changes = |k: usize| -> Vec<(String, f64)> {
        lines[k]["boundaries"]
            .as_array()
            .unwrap()
            .iter()
            .map(|b| {
                (
                    b["pair"].as_str().unwrap().to_string(),
                    b["e_star"].as_f64().unwrap(),
                )
            })
            .collect()
    };
    assert_eq!(changes(0).len(), 1);
    assert_eq!(changes(0)[0].0, "f|g");
    assert!((changes(0)[0].1 - 2f64.sqrt()).abs() < 1e-12);
    assert!((changes(1)[0].1 - 0.5f64.sqrt()).abs() < 1e-12);
    assert_eq!(changes(2).len(), 1);
    assert!(changes(3).is_empty(), "{:?}", changes(3));
    // Every point with its value, error, state and trust.
    let p = &lines[0]["points"][3];
    assert_eq!(p["e_star"], 4.0);
    assert_eq!(p["temperature"], 20.0);
    assert!((p["temperature_error"].as_f64().unwrap() - 0.2).abs() < 1e-12);
    assert_eq!(p["trend"], "heating");
    assert_eq!(p["trust"], "~");
    assert_eq!(lines[2]["points"][0]["trust"], "?");
    assert_eq!(lines[2]["points"][0]["trusted"], false);
    // The CSV: a row per job with the errors.
    let csv = std::fs::read_to_string(&csv).unwrap();
    let mut rows = csv.lines();
    assert_eq!(
        rows.next().unwrap(),
        "sweep,branch,gamma,e_star,point,replica,job_id,phase,trend,trust,T_g_reduced,\
         T_g_reduced_se,bridges_per_grain,bridges_per_grain_se,delta_n_cb,delta_n_cb_se"
    );
    let rows: Vec<Vec<&str>> = rows.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 16);
    assert!(
        rows.iter()
            .all(|r| r[11].parse::<f64>().is_ok() && r[15] == "0.03"),
        "{csv}"
    );
    // The SVG: a row of panels per Gamma, each branch named, the run states in the legend, a
    // marker for every job.
    let svg = std::fs::read_to_string(&svg).unwrap();
    let texts = svg_texts(&svg);
    for text in ["Γ = 1", "Γ = 2", "Tg / Ecb", "Δncb", "bridges per grain"] {
        assert!(texts.iter().any(|t| t == text), "missing {text}: {texts:?}");
    }
    for text in [
        "hot start: mean over replicas",
        "continuation: mean over replicas",
        "undecided",
        "hollow: label may still change",
        "f|g",
    ] {
        assert!(svg.contains(text), "missing {text}");
    }
    // -o by extension writes the CSV; another extension is a usage error.
    let other = dir.path().join("l.csv");
    ok_stdout(&["lines", "--db", db, "-o", other.to_str().unwrap()]);
    assert_eq!(std::fs::read_to_string(&other).unwrap(), csv);
    let bad = run(&["lines", "--db", db, "-o", "x.jpg"]);
    assert_eq!(bad.status.code(), Some(2), "{}", stderr(&bad));
    assert!(
        stderr(&bad).contains(".svg, .pdf or .png (a figure) or .csv"),
        "{}",
        stderr(&bad)
    );
    figures_read_back(dir.path(), db);
}

/// `lines` as PDF and, with --overlay, as PNG: read back, not only written.
fn figures_read_back(dir: &Path, db: &str) {
    // The figure as PDF: one page with the panels' text; as PNG, the overlay: three times the
    // SVG's size (480 px wide), not blank.
    let pdf = dir.join("l.pdf");
    ok_stdout(&["lines", "--db", db, "-o", pdf.to_str().unwrap()]);
    let doc = lopdf::Document::load(&pdf).unwrap();
    assert_eq!(doc.get_pages().len(), 1);
    let text = doc.extract_text(&[1]).unwrap().replace('\n', "");
    assert!(
        text.contains("bridgespergrain") || text.contains("bridges per grain"),
        "{text}"
    );
    let png = dir.join("o.png");
    ok_stdout(&[
        "lines",
        "--db",
        db,
        "--overlay",
        "-o",
        png.to_str().unwrap(),
    ]);
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&png).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!(info.width, 3 * 480);
    let dark = buf[..info.buffer_size()]
        .chunks(4)
        .filter(|p| p[0] < 80 && p[1] < 80 && p[2] < 80)
        .count();
    assert!(dark > 10_000, "{dark} dark pixels: axes, text and lines");
}

/// The values of every `attr="..."` in an HTML text.
fn attrs(html: &str, attr: &str) -> Vec<String> {
    let key = format!(" {attr}=\"");
    html.match_indices(&key)
        .map(|(k, _)| {
            let rest = &html[k + key.len()..];
            rest[..rest.find('"').unwrap()].to_string()
        })
        .collect()
}

/// Every `href` and `src` of every HTML file under `root` resolves to a file (`#` anchors to an
/// `id` on the page); returns the pages reached from `index.html` by links.
fn check_links(root: &Path) -> BTreeSet<PathBuf> {
    let mut seen = BTreeSet::new();
    let mut todo = vec![root.join("index.html")];
    while let Some(page) = todo.pop() {
        if !seen.insert(page.clone()) {
            continue;
        }
        let html = std::fs::read_to_string(&page).unwrap();
        // One script, the report's own file (no inline code, nothing fetched).
        for (k, _) in html.match_indices("<script") {
            let tag = &html[k..k + html[k..].find('>').unwrap()];
            assert!(
                tag.contains("src=\"sort.js\""),
                "{}: a script other than sort.js: {tag}",
                page.display()
            );
        }
        for link in attrs(&html, "href").into_iter().chain(attrs(&html, "src")) {
            if let Some(anchor) = link.strip_prefix('#') {
                assert!(
                    html.contains(&format!("id=\"{anchor}\"")),
                    "{}: anchor {link}",
                    page.display()
                );
                continue;
            }
            assert!(
                !link.contains("://"),
                "{}: not offline: {link}",
                page.display()
            );
            // A link to another page's anchor: the page, then the anchor's id on it.
            let (file, anchor) = link.split_once('#').unwrap_or((&link, ""));
            let target = page.parent().unwrap().join(file);
            assert!(
                target.is_file(),
                "{}: {link} does not resolve",
                page.display()
            );
            if !anchor.is_empty() {
                let there = std::fs::read_to_string(&target).unwrap();
                assert!(
                    there.contains(&format!("id=\"{anchor}\"")),
                    "{}: anchor {link}",
                    page.display()
                );
            }
            if file.ends_with(".html") {
                todo.push(target.canonicalize().unwrap());
            }
        }
    }
    seen
}

#[test]
fn the_report_gives_every_point_a_page_and_every_link_resolves() {
    // A real sweep (2 x 2 points, a few seconds): observables, final states and labels as a run
    // stores them.
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "tiny.toml", TINY_SCENE);
    let sweep = write(
        dir.path(),
        "grid.toml",
        "[sweep]\nname = \"grid\"\nbase = \"tiny.toml\"\nperiods = 6\n\
         [[axis]]\nkey = \"gamma\"\nlog = { from = 1.5, to = 3.0, steps = 2 }\n\
         [[axis]]\nkey = \"e_star\"\nvalues = [1.0, 4.0]\n",
    );
    let db = dir.path().join("w.sqlite");
    let db_s = db.to_str().unwrap();
    ok_stdout(&["sweep", "run", sweep.to_str().unwrap(), "--db", db_s]);
    let out = dir.path().join("site");
    let o = run(&["report", "--db", db_s, "-o", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));

    let root = out.canonicalize().unwrap();
    let pages = check_links(&root);
    // Every grid position has its page, linked from the map and from the table.
    let index = std::fs::read_to_string(root.join("index.html")).unwrap();
    let store = Store::open_existing(&db).unwrap();
    let s = store.sweep("grid").unwrap();
    let points = store.points(s.id).unwrap();
    assert_eq!(points.len(), 4);
    let areas: Vec<String> = index
        .match_indices("<area ")
        .map(|(k, _)| {
            let rest = &index[k..];
            attrs(&rest[..rest.find('>').unwrap()], "href")[0].clone()
        })
        .collect();
    assert_eq!(areas.len(), 4, "{index}");
    for p in &points {
        let page = format!("points/point-{}.html", p.point);
        assert!(areas.contains(&page), "map has no link to {page}");
        assert!(pages.contains(&root.join(&page)), "{page} not reached");
        let html = std::fs::read_to_string(root.join(&page)).unwrap();
        // Label, its decision and run state, snapshot, profiles, its line.
        assert!(html.contains(&p.job_id), "{page}");
        assert!(html.contains("decided by  "), "{page}");
        assert!(html.contains("trend"), "{page}");
        for img in [
            format!("{}-snapshot.svg", p.job_id),
            format!("{}-profiles.svg", p.job_id),
            format!("{}-series.svg", p.job_id),
            "../lines/gamma-".to_string(),
        ] {
            assert!(html.contains(&img), "{page}: no {img}");
        }
        let snapshot =
            std::fs::read_to_string(root.join(format!("points/{}-snapshot.svg", p.job_id)))
                .unwrap();
        assert!(snapshot.matches("<circle").count() >= 40, "40 grains");
        // The time series figure: T_g, bridges, Delta n_cb (and the regions of a coexistence).
        let series =
            std::fs::read_to_string(root.join(format!("points/{}-series.svg", p.job_id))).unwrap();
        let panels = series.matches("<g class=\"panel\"").count();
        let coexistence = p.phase.as_deref().is_some_and(|l| l.len() == 3);
        assert_eq!(panels, if coexistence { 4 } else { 3 }, "{series}");
        assert!(series.contains("T_g / E_cb, whole system"), "{series}");
        // One final configuration per job: `show --snapshot` draws the report's.
        let mine = dir.path().join(format!("{}.svg", p.job_id));
        let o = run(&[
            "show",
            "--db",
            db_s,
            &p.job_id,
            "--snapshot",
            mine.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        assert_eq!(
            std::fs::read_to_string(&mine).unwrap(),
            snapshot,
            "{}",
            p.job_id
        );
    }
    // The boundaries table, the sweep file, the commands that reproduce it.
    assert!(index.contains("Gamma"), "{index}");
    assert_eq!(
        std::fs::read_to_string(root.join("sweep.toml")).unwrap(),
        std::fs::read_to_string(&sweep).unwrap()
    );
    assert!(index.contains(&format!(
        "wetgran sweep run {} --db {db_s}",
        sweep.display()
    )));
    assert!(index.contains("wetgran report --db"), "{index}");
    // The map's Gamma axis is logarithmic, as the sweep's is; every link sits on its point's
    // disc.
    let map = std::fs::read_to_string(root.join("map.svg")).unwrap();
    // (typeset Γ; a log axis under a decade labels 1, 2 and 5 of it, "2" here, where a linear
    // one would label steps with one decimal, "2.0").
    let texts = svg_texts(&map);
    assert!(texts.iter().any(|t| t == "Γ"), "{texts:?}");
    assert!(texts.iter().any(|t| t == "2"), "{texts:?}");
    assert!(!texts.iter().any(|t| t == "2.0"), "{texts:?}");
    for coords in attrs(&index, "coords") {
        let c: Vec<&str> = coords.split(',').collect();
        assert!(
            map.contains(&format!("<circle cx=\"{}\" cy=\"{}\"", c[0], c[1])),
            "no point under the link at {coords}"
        );
    }
}

#[test]
fn the_export_is_tidy() {
    let dir = tempfile::tempdir().unwrap();
    let db = prepared(dir.path());
    let db = db.to_str().unwrap();
    let series = dir.path().join("series.csv");
    let text = dir.path().join("text.csv");
    let csv = ok_stdout(&[
        "export",
        "--db",
        db,
        "--series",
        series.to_str().unwrap(),
        "--text",
        text.to_str().unwrap(),
    ]);
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    // Axes first, in the sweep's order (not alphabetical).
    assert_eq!(
        header[..4],
        ["drive.gamma", "drive.e_star", "initial.start", "sweep"]
    );
    // Informative columns only: obs.temperature_unit_name and decided_on.synthetic are the
    // same in every row.
    assert!(header.contains(&"obs.granular_temperature_reduced"));
    assert!(header.contains(&"decided_on.t"));
    for constant in ["obs.temperature_unit_name", "decided_on.synthetic"] {
        assert!(!header.contains(&constant), "{constant}: {header:?}");
    }
    let all = ok_stdout(&["export", "--db", db, "--all"]);
    let all_header: Vec<&str> = all.lines().next().unwrap().split(',').collect();
    assert!(all_header.contains(&"decided_on.synthetic"));
    assert!(all_header.len() > header.len());
    // JSON: the same fields, in the same order, typed.
    let json = ok_stdout(&["export", "--db", db, "--format", "json"]);
    let rows: Vec<serde_json::Map<String, serde_json::Value>> =
        serde_json::from_str(&json).unwrap();
    assert_eq!(rows.len(), 16);
    assert_eq!(rows.len() + 1, csv.lines().count());
    for r in &rows {
        let mut keys: Vec<&str> = r.keys().map(String::as_str).collect();
        let mut want = header.clone();
        keys.sort();
        want.sort();
        assert_eq!(keys, want);
    }
    assert!(rows[0]["drive.gamma"].is_number() && rows[0]["verdict"].is_string());
    // Series: numbers only; the text entries in their own file.
    let series = std::fs::read_to_string(&series).unwrap();
    assert!(series.lines().count() > 16);
    for line in series.lines().skip(1) {
        let v = line.rsplit(',').next().unwrap();
        assert!(v.is_empty() || v.parse::<f64>().is_ok(), "{line}");
    }
    let text = std::fs::read_to_string(&text).unwrap();
    assert!(text.contains(",obs.checks.quantity,0,T_g"), "{text}");
    assert!(text.contains(",obs.trend.tests.quantity,2,delta_n_cb"));
    // A write that fails in the middle of the run names the file it failed on: the text file
    // overflows its buffer before the end, so this error comes from a row, not the last flush.
    assert!(text.len() > 2 * 8192, "{} bytes", text.len());
    let full = run(&[
        "export",
        "--db",
        db,
        "--series",
        dir.path().join("series2.csv").to_str().unwrap(),
        "--text",
        "/dev/full",
    ]);
    assert!(!full.status.success());
    assert!(
        stderr(&full).contains("/dev/full: cannot write"),
        "{}",
        stderr(&full)
    );
}

/// The ```sql blocks of docs/reports.md.
fn doc_sql() -> Vec<&'static str> {
    let doc: &'static str = include_str!("../docs/reports.md");
    doc.split("```sql\n")
        .skip(1)
        .map(|b| &b[..b.find("```").unwrap()])
        .collect()
}

#[test]
fn the_pandas_example_reads_the_database() {
    use sqlx::Row;
    let dir = tempfile::tempdir().unwrap();
    let db = prepared(dir.path());
    let blocks = doc_sql();
    assert_eq!(blocks.len(), 2, "the table and the profile query");
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .unwrap();
    rt.block_on(async {
        let url = format!("sqlite://{}?mode=ro", db.display());
        let pool = sqlx::SqlitePool::connect(&url).await.unwrap();
        // The results table: one row per job, the axis values and the observables by name.
        let rows = sqlx::query(blocks[0])
            .bind("lines")
            .fetch_all(&pool)
            .await
            .unwrap();
        assert_eq!(rows.len(), 16);
        for r in &rows {
            let e: f64 = r.get("e_star");
            let start: String = r.get("start");
            let t: f64 = r.get("T_g");
            assert_eq!(t, temperature(e, start == "continue"));
            let phase: String = r.get("phase");
            assert_eq!(phase, if t > 1.0 { "g" } else { "f" });
            let _: f64 = r.get("gamma");
            let _: f64 = r.get("delta_n_cb");
            let _: String = r.get("trend");
        }
        // A profile in long form: one row per bin.
        let rows = sqlx::query(blocks[1])
            .bind("lines")
            .fetch_all(&pool)
            .await
            .unwrap();
        assert_eq!(rows.len(), 16 * 3);
        assert!(rows.iter().all(|r| {
            let bin: i64 = r.get("bin");
            let v: f64 = r.get("n_cb");
            (0..3).contains(&bin) && v > 0.0
        }));
    });
}

/// The rows of the `<table class="boundary">` whose caption starts with `caption`: its cells'
/// text, the header row first.
fn boundary_table(html: &str, caption: &str) -> Option<Vec<Vec<String>>> {
    let strip = |c: &str| {
        let mut out = String::new();
        let mut tag = false;
        for ch in c.chars() {
            match ch {
                '<' => tag = true,
                '>' => tag = false,
                ch if !tag => out.push(ch),
                _ => {}
            }
        }
        out.replace("&amp;", "&").trim().to_string()
    };
    html.split("<table class=\"boundary\">")
        .skip(1)
        .find_map(|t| {
            let t = &t[..t.find("</table>").unwrap()];
            let cap = strip(&t[t.find("<caption>")?..t.find("</caption>")?]);
            if !cap.starts_with(caption) {
                return None;
            }
            Some(
                t.split("<tr>")
                    .skip(1)
                    .map(|tr| {
                        // Each cell from its opening tag to its closing one (links inside).
                        let mut cells = Vec::new();
                        let mut rest = tr;
                        while let Some(k) = rest.find("<t") {
                            let c = &rest[k..];
                            if !["<td", "<th>", "<th "].iter().any(|t| c.starts_with(t)) {
                                rest = &c[2..];
                                continue;
                            }
                            let close = if c.starts_with("<td") {
                                "</td>"
                            } else {
                                "</th>"
                            };
                            let end = c.find(close).unwrap();
                            cells.push(c[c.find('>').unwrap() + 1..end].to_string());
                            rest = &c[end + close.len()..];
                        }
                        cells
                    })
                    .map(|cells| cells.iter().map(|c| strip(c)).collect())
                    .collect(),
            )
        })
}

#[test]
fn the_reports_boundaries_are_tables_of_the_phase_map() {
    // The synthetic sweep: on Gamma = 1, hot start, f up to E* = 1 and g from 2, so one f|g
    // boundary point at E* = sqrt(2), between the pages of E* = 1 and E* = 2.
    let dir = tempfile::tempdir().unwrap();
    let db = prepared(dir.path());
    let out = dir.path().join("site");
    let o = run(&[
        "report",
        "--db",
        db.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--no-snapshots",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    check_links(&out.canonicalize().unwrap());
    let index = std::fs::read_to_string(out.join("index.html")).unwrap();
    let boundaries = &index[index.find("id=\"boundaries\"").unwrap()..];
    let boundaries = &boundaries[..boundaries.find("</section>").unwrap()];
    assert!(!boundaries.contains("<pre>"), "a text dump: {boundaries}");
    // The hot branch of Gamma = 1 comes first (slices in the map's order).
    let table = boundary_table(boundaries, "boundary f|g").expect("an f|g table");
    assert_eq!(
        table[0],
        [
            "E*",
            "Gamma",
            "A",
            "ω",
            "± E* (decades)",
            "± Gamma",
            "between",
            "and",
            "agree"
        ]
    );
    let first: Vec<&str> = table[1].iter().map(String::as_str).collect();
    assert_eq!(first[0], "1.414", "{first:?}");
    assert!(
        first[6].starts_with("f at (1, ") && first[7].starts_with("g at (2, "),
        "{first:?}"
    );
    assert_eq!(first[8], "1.00");
    // The ends link to their grid positions' pages.
    let links = boundaries.matches("<td><a href=\"points/point-").count();
    let ends = 2 * (boundaries.matches("<tr>").count() - boundaries.matches("<caption>").count());
    assert_eq!(links, ends, "{boundaries}");
    // The points table has a row per job with its temperature.
    let points = &index[index.find("id=\"points-table\"").unwrap()..];
    let points = &points[..points.find("</table>").unwrap()];
    assert_eq!(
        points.matches("<tr>").count(),
        1 + 16,
        "a header and a row per job"
    );
    assert!(points.contains("data-v=\"2e1\""), "T_g = 20 at E* = 4");
}

#[test]
fn show_at_names_the_branches_and_redraws_a_job_without_a_stored_state() {
    let dir = tempfile::tempdir().unwrap();
    let db = prepared(dir.path());
    let db = db.to_str().unwrap();
    // Two branches at Gamma = 2, E* = 1: the first by point is shown, the other named.
    let out = ok_stdout(&["show", "--db", db, "--at", "gamma=2.1,e_star=0.9"]);
    let at = out.lines().find(|l| l.starts_with("at ")).unwrap();
    assert_eq!(
        at, "at          Gamma = 2, E* = 1, branch: hot start",
        "{out}"
    );
    let also = out.lines().find(|l| l.starts_with("also near")).unwrap();
    assert!(
        also.contains("branch: continuation") || also.contains("continuation, replica 0"),
        "{out}"
    );
    assert_eq!(also.matches(" replica ").count(), 1, "one other job: {out}");
    // A text value picks the branch.
    let out = ok_stdout(&[
        "show",
        "--db",
        db,
        "--at",
        "gamma=2,e_star=1,initial.start=continuation",
    ]);
    assert!(
        out.contains("at          Gamma = 2, E* = 1, branch: continuation\n"),
        "{out}"
    );
    assert!(!out.contains("also near"), "{out}");
    // No final state stored (these results carry none): the spec runs again, and says so.
    let snap = dir.path().join("s.xyz");
    let out = ok_stdout(&[
        "show",
        "--db",
        db,
        "--at",
        "gamma=1,e_star=0.5",
        "--snapshot",
        snap.to_str().unwrap(),
    ]);
    assert!(out.contains("final state no stored one: re-run"), "{out}");
    let xyz = std::fs::read_to_string(&snap).unwrap();
    assert_eq!(xyz.lines().next(), Some("40"), "the tiny scene's 40 grains");
}

use wetgran_testkit::figures::svg_texts;
