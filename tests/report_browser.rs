//! The HTML report as a reader sees it (issue 45, item 4): a small real sweep's report opened in
//! headless Chromium. Screenshots of the index and of a point page at a laptop's window size
//! (they decode, have the size asked for, are not blank, and show the page's style sheet: the
//! dark bar at the top), the index printed to PDF (several pages), and the DOM the browser
//! rendered, parsed: the parameters table's rows (N, eps, s_crit, E_cb, box), the points table's
//! columns and values (against the database), the sort script run from the address
//! (`#sort=e_star`, `#sort=-T_g`: the rows come back in that order), and a point page's
//! decision section, figures and folded raw records.
//!
//! The browser is `$WETGRAN_CHROMIUM`, else `chromium`, `chromium-browser` or `google-chrome` on
//! the PATH (`scripts/chromium-local.sh install` puts Debian's there; `.ci/run` calls it).
//! Without one the test skips, saying so; under `CI=true` that is a failure.

mod sweep_common;

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};
use sweep_common::*;
use wetgran::store::Store;

/// The browser, as scripts/chromium-local.sh finds it.
fn browser() -> Option<PathBuf> {
    if let Some(p) = std::env::var_os("WETGRAN_CHROMIUM").map(PathBuf::from)
        && p.is_file()
    {
        return Some(p);
    }
    let path = std::env::var_os("PATH")?;
    ["chromium", "chromium-browser", "google-chrome"]
        .iter()
        .flat_map(|b| std::env::split_paths(&path).map(move |d| d.join(b)))
        .find(|p| p.is_file())
}

/// Runs the headless browser on `url` with `args` (a fresh profile each time) and returns its
/// standard output. A browser that has not ended after two minutes is killed (a hang, not a
/// measurement).
fn headless(browser: &Path, args: &[&str], url: &str) -> String {
    let profile = tempfile::tempdir().unwrap();
    let mut child = Command::new(browser)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-quic",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--hide-scrollbars",
        ])
        .arg(format!("--user-data-dir={}", profile.path().display()))
        .args(args)
        .arg(url)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start the browser");
    let start = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > Duration::from_secs(120) {
            child.kill().unwrap();
            panic!(
                "{} {args:?} {url}: still running after 120 s",
                browser.display()
            );
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    let out = child.wait_with_output().unwrap();
    assert!(
        out.status.success(),
        "{} {args:?} {url}: {}",
        browser.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).to_string()
}

fn url(path: &Path, hash: &str) -> String {
    format!("file://{}{hash}", path.display())
}

/// A decoded screenshot: its size, the RGB of the pixel at (x, y), how many colours it has and
/// the share of its pixels that are not white.
struct Picture {
    width: u32,
    height: u32,
    rgb: Vec<[u8; 3]>,
}

impl Picture {
    fn read(path: &Path) -> Picture {
        let decoder =
            png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
        let mut reader = decoder.read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size()];
        let info = reader.next_frame(&mut buf).unwrap();
        let step = match info.color_type {
            png::ColorType::Rgb => 3,
            png::ColorType::Rgba => 4,
            other => panic!("{}: colour type {other:?}", path.display()),
        };
        assert_eq!(info.bit_depth, png::BitDepth::Eight);
        let rgb = buf[..info.buffer_size()]
            .chunks(step)
            .map(|p| [p[0], p[1], p[2]])
            .collect();
        Picture {
            width: info.width,
            height: info.height,
            rgb,
        }
    }
    fn at(&self, x: u32, y: u32) -> [u8; 3] {
        self.rgb[(y * self.width + x) as usize]
    }
    fn colours(&self) -> usize {
        let mut c: Vec<[u8; 3]> = self.rgb.clone();
        c.sort();
        c.dedup();
        c.len()
    }
    fn inked(&self) -> f64 {
        let n = self.rgb.iter().filter(|p| **p != [255, 255, 255]).count();
        n as f64 / self.rgb.len() as f64
    }
}

/// Text without its tags, entities decoded, spaces joined.
fn text(html: &str) -> String {
    let mut out = String::new();
    let mut in_tag = false;
    for c in html.chars() {
        match c {
            '<' => in_tag = true,
            '>' => in_tag = false,
            c if !in_tag => out.push(c),
            _ => {}
        }
    }
    let out = out
        .replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&quot;", "\"")
        .replace("&#39;", "'")
        .replace("&nbsp;", " ")
        .replace("&amp;", "&");
    out.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// The value of attribute `name` in the opening tag `tag` (`<td class="num" data-v="1">`).
fn attr(tag: &str, name: &str) -> Option<String> {
    let key = format!(" {name}=\"");
    let k = tag.find(&key)? + key.len();
    Some(tag[k..k + tag[k..].find('"')?].to_string())
}

/// The HTML of the element that starts at the first `<{tag}` whose opening tag contains `has`,
/// up to its closing tag (no nesting of the same tag inside).
fn element<'a>(html: &'a str, tag: &str, has: &str) -> Option<&'a str> {
    let open = format!("<{tag}");
    let close = format!("</{tag}>");
    let mut from = 0;
    while let Some(k) = html[from..].find(&open) {
        let start = from + k;
        let head_end = start + html[start..].find('>')?;
        if html[start..head_end].contains(has) {
            let end = head_end + html[head_end..].find(&close)? + close.len();
            return Some(&html[start..end]);
        }
        from = head_end;
    }
    None
}

/// The cells of each row of a table: (opening tag, inner HTML), header row included.
fn rows(table: &str) -> Vec<Vec<(String, String)>> {
    let mut out = Vec::new();
    for tr in table.split("<tr").skip(1) {
        let tr = &tr[..tr.find("</tr>").unwrap_or(tr.len())];
        let mut cells = Vec::new();
        let mut rest = tr;
        while let Some(k) = rest.find("<t") {
            let c = &rest[k..];
            let is_cell = c.starts_with("<td") || c.starts_with("<th");
            if !is_cell {
                rest = &c[2..];
                continue;
            }
            let head_end = c.find('>').unwrap();
            let close = if c.starts_with("<td") {
                "</td>"
            } else {
                "</th>"
            };
            let end = c.find(close).unwrap();
            cells.push((
                c[..head_end + 1].to_string(),
                c[head_end + 1..end].to_string(),
            ));
            rest = &c[end + close.len()..];
        }
        out.push(cells);
    }
    out
}

/// The points table of a rendered index: its header keys and, per body row, the `data-v` of
/// each cell.
fn points_table(dom: &str) -> (Vec<String>, Vec<Vec<String>>) {
    let table = element(dom, "table", "id=\"points-table\"").expect("a points table");
    let mut all = rows(table);
    let head = all.remove(0);
    let keys = head
        .iter()
        .map(|(tag, _)| attr(tag, "data-key").expect("a sort key"))
        .collect();
    let body = all
        .iter()
        .map(|r| {
            r.iter()
                .map(|(tag, _)| attr(tag, "data-v").unwrap_or_default())
                .collect()
        })
        .collect();
    (keys, body)
}

fn column(keys: &[String], key: &str) -> usize {
    keys.iter()
        .position(|k| k == key)
        .unwrap_or_else(|| panic!("no column {key}: {keys:?}"))
}

fn numbers(body: &[Vec<String>], k: usize) -> Vec<f64> {
    body.iter().map(|r| r[k].parse::<f64>().unwrap()).collect()
}

/// The screenshots of the index and a point page at a laptop's window size (module doc).
fn check_screenshots(browser: &Path, dir: &Path, index: &Path, point: &Path) {
    // Screenshots at a laptop's window size: decoded, of that size, not blank, the style
    // sheet applied (the dark bar at the top, #18324a).
    for (page, name) in [(index, "index.png"), (point, "point.png")] {
        let shot = dir.join(name);
        headless(
            browser,
            &[
                &format!("--screenshot={}", shot.display()),
                "--window-size=1280,900",
            ],
            &url(page, ""),
        );
        let pic = Picture::read(&shot);
        assert_eq!((pic.width, pic.height), (1280, 900), "{name}");
        assert!(pic.colours() > 64, "{name}: {} colours", pic.colours());
        let inked = pic.inked();
        assert!((0.03..0.9).contains(&inked), "{name}: {inked} of it inked");
        assert_eq!(pic.at(640, 8), [0x18, 0x32, 0x4a], "{name}: no top bar");
        if let Some(keep) = std::env::var_os("WETGRAN_KEEP_SCREENSHOTS") {
            std::fs::copy(&shot, Path::new(&keep).join(name)).unwrap();
        }
    }
}

/// The index printed to PDF.
fn check_print(browser: &Path, dir: &Path, index: &Path) {
    // Printed: a PDF of several pages.
    let pdf = dir.join("index.pdf");
    headless(
        browser,
        &[
            &format!("--print-to-pdf={}", pdf.display()),
            "--no-pdf-header-footer",
        ],
        &url(index, ""),
    );
    let pdf = std::fs::read(&pdf).unwrap();
    assert!(pdf.starts_with(b"%PDF-"), "not a PDF");
    let raw = String::from_utf8_lossy(&pdf);
    let pages = raw.matches("/Type /Page").count() - raw.matches("/Type /Pages").count();
    assert!(pages >= 2, "{pages} page(s) printed");
}

/// The rendered index against the database: returns the points table's keys and rows.
fn check_index(browser: &Path, db: &Path, index: &Path) -> (Vec<String>, Vec<Vec<String>>) {
    // The rendered index: the script ran (it marks the page), the parameters table holds the
    // scene's constants, the points table its columns and the database's values.
    let dom = headless(browser, &["--dump-dom"], &url(index, ""));
    assert!(
        dom.contains("<html lang=\"en\" class=\"js\">"),
        "the script did not run"
    );
    let params = element(&dom, "table", "class=\"parameters\"").expect("a parameters table");
    let value = |key: &str| -> String {
        let tr = element(params, "tr", &format!("data-key=\"{key}\""))
            .unwrap_or_else(|| panic!("no parameter {key}"));
        text(&rows(tr)[0][2].1)
    };
    assert_eq!(value("particles.count"), "40");
    assert_eq!(value("contact.restitution"), "0.9");
    assert_eq!(value("capillary.s_crit"), "0.0711");
    assert_eq!(value("capillary.e_cb"), "0.2844");
    assert_eq!(value("box.size"), "20 × 9");
    assert!(value("drive.gamma").starts_with("1.5 … 3 (2 values)"));
    let (keys, body) = points_table(&dom);
    assert_eq!(
        keys,
        [
            "point",
            "gamma",
            "e_star",
            "replica",
            "label",
            "T_g",
            "bridges",
            "D_lat",
            "trend",
            "decided_by",
            "sim_time",
            "wall_s"
        ]
    );
    let store = Store::open_existing(db).unwrap();
    let s = store.sweep("grid").unwrap();
    let stored = store.points(s.id).unwrap();
    assert_eq!(body.len(), stored.len());
    let t_g = column(&keys, "T_g");
    for (row, p) in body.iter().zip(&stored) {
        assert_eq!(row[0], p.point.to_string(), "point order without a sort");
        let want = p.observables.as_ref().unwrap()["granular_temperature_reduced"]
            .as_f64()
            .unwrap();
        let got: f64 = row[t_g].parse().unwrap();
        assert!((got - want).abs() <= 1e-12 * want.abs(), "{got} != {want}");
        assert!(
            row[column(&keys, "bridges")].parse::<f64>().is_ok(),
            "{row:?}"
        );
        assert!(!row[column(&keys, "decided_by")].is_empty(), "{row:?}");
    }
    let e_star = column(&keys, "e_star");
    let unsorted = numbers(&body, e_star);
    assert!(
        unsorted.windows(2).any(|w| w[0] > w[1]),
        "point order is already E* order: {unsorted:?}"
    );

    (keys, body)
}

/// The points table sorted from the address; `keys`, `body`: the table unsorted.
fn check_sorting(browser: &Path, index: &Path, keys: &[String], body: &[Vec<String>]) {
    let (t_g, e_star) = (column(keys, "T_g"), column(keys, "e_star"));
    // Sorted from the address: by E* up, by T_g down; the same rows, the header marked.
    let sorted = |hash: &str| {
        let dom = headless(browser, &["--dump-dom"], &url(index, hash));
        let (_, body) = points_table(&dom);
        let th = element(
            &dom,
            "th",
            &format!(
                "data-key=\"{}\"",
                hash.trim_start_matches("#sort=").trim_start_matches('-')
            ),
        )
        .unwrap()
        .to_string();
        (body, th)
    };
    let (by_e, th) = sorted("#sort=e_star");
    assert!(th.contains("aria-sort=\"ascending\""), "{th}");
    let e = numbers(&by_e, e_star);
    assert!(
        e.windows(2).all(|w| w[0] <= w[1]),
        "not sorted by E*: {e:?}"
    );
    let (by_t, th) = sorted("#sort=-T_g");
    assert!(th.contains("aria-sort=\"descending\""), "{th}");
    let t = numbers(&by_t, t_g);
    assert!(
        t.windows(2).all(|w| w[0] >= w[1]),
        "not sorted by T_g: {t:?}"
    );
    let mut a: Vec<&String> = by_t.iter().map(|r| &r[0]).collect();
    let mut b: Vec<&String> = body.iter().map(|r| &r[0]).collect();
    a.sort();
    b.sort();
    assert_eq!(a, b, "sorting lost or doubled rows");
}

/// A point page (module doc).
fn check_point_page(browser: &Path, point: &Path) {
    // A point page: the decision section, the snapshot and profiles side by side, the raw
    // records folded away (every JSON or TOML block inside a <details>).
    let dom = headless(browser, &["--dump-dom"], &url(point, ""));
    let decision = element(&dom, "section", "class=\"decision\"").expect("a decision section");
    assert!(text(decision).contains("decided by"), "{decision}");
    let figures = element(&dom, "div", "class=\"figures\"").expect("figures");
    assert!(figures.contains("-snapshot.svg") && figures.contains("-profiles.svg"));
    let details: Vec<&str> = dom.split("<details").skip(1).collect();
    let summaries: Vec<String> = details
        .iter()
        .map(|d| text(&d[d.find("<summary>").unwrap()..d.find("</summary>").unwrap()]))
        .collect();
    assert!(
        summaries.iter().any(|s| s.starts_with("decided on"))
            && summaries.iter().any(|s| s.starts_with("observables"))
            && summaries.iter().any(|s| s.contains("scene")),
        "{summaries:?}"
    );
    let outside: String = dom
        .split("<details")
        .enumerate()
        .map(|(k, part)| {
            if k == 0 {
                part
            } else {
                &part[part.find("</details>").unwrap()..]
            }
        })
        .collect();
    assert!(
        !outside.contains("\"granular_temperature_reduced\""),
        "raw observables outside <details>"
    );
}

#[test]
fn the_report_reads_as_a_results_page_in_a_browser() {
    let Some(browser) = browser() else {
        skip_unless_ci(
            "the_report_reads_as_a_results_page_in_a_browser",
            "no chromium (scripts/chromium-local.sh install, or WETGRAN_CHROMIUM)",
        );
        return;
    };
    // A real sweep (2 x 2 points, a second): observables, final states and labels as a run
    // stores them. Point order is Gamma first, so E* runs 1, 4, 1, 4 down the table.
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
    let o = run(&["sweep", "run", sweep.to_str().unwrap(), "--db", db_s]);
    assert!(o.status.success(), "{}", stderr(&o));
    let site = dir.path().join("site");
    let o = run(&["report", "--db", db_s, "-o", site.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let site = site.canonicalize().unwrap();
    let index = site.join("index.html");
    let point = site.join("points/point-0.html");

    check_screenshots(&browser, dir.path(), &index, &point);
    check_print(&browser, dir.path(), &index);
    let (keys, body) = check_index(&browser, &db, &index);
    check_sorting(&browser, &index, &keys, &body);
    check_point_page(&browser, &point);
}
