//! `wetgran show` (one stored point, by job id or by `--at` coordinates: phase, decision
//! summary, profiles and time series from the stored observables, a snapshot of the stored
//! final state) and `wetgran inflection` on a real database.

mod sweep_common;

use std::process::Output;
use sweep_common::*;

fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

#[test]
fn show_redraws_a_stored_point_and_inflection_reads_the_lines() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "tiny.toml", TINY_SCENE);
    let sweep = write(
        dir.path(),
        "line_sweep.toml",
        "[sweep]\nname = \"line\"\nbase = \"tiny.toml\"\nperiods = 30\n\
         [[axis]]\nkey = \"gamma\"\nvalues = [3.0]\n\
         [[axis]]\nkey = \"e_star\"\nlog = { from = 0.3, to = 10.0, steps = 5 }\n",
    );
    let db = dir.path().join("w.sqlite");
    let db_s = db.to_str().unwrap();
    let run = wetgran()
        .args(["sweep", "run", sweep.to_str().unwrap(), "--db", db_s])
        .output()
        .unwrap();
    assert!(run.status.success(), "{}", text(&run));

    // The first job's id from the export.
    let export = wetgran().args(["export", "--db", db_s]).output().unwrap();
    let csv = String::from_utf8(export.stdout).unwrap();
    let row = csv.lines().nth(1).expect("a finished job");
    let column = |name: &str| {
        csv.lines()
            .next()
            .unwrap()
            .split(',')
            .position(|c| c == name)
    };
    let id = row
        .split(',')
        .nth(column("job_id").unwrap())
        .unwrap()
        .to_string();
    let phase_col = column("phase");
    let stored_phase = row.split(',').nth(phase_col.unwrap()).unwrap().to_string();

    let svg = dir.path().join("snap.svg");
    let xyz = dir.path().join("snap.xyz");
    let prof = dir.path().join("prof.svg");
    let series = dir.path().join("series.svg");
    let show = wetgran()
        .args(["show", "--db", db_s, &id[..10]])
        .args(["--snapshot", svg.to_str().unwrap()])
        .args(["--snapshot", xyz.to_str().unwrap()])
        .args(["--profiles", prof.to_str().unwrap()])
        .args(["--series", series.to_str().unwrap()])
        .output()
        .unwrap();
    let out = text(&show);
    assert!(show.status.success(), "{out}");
    check_summary(&out, &id, &stored_phase);
    assert!(std::fs::read_to_string(&svg).unwrap().starts_with("<svg"));
    check_series(dir.path(), &db, db_s, &id, &stored_phase, &series);
    check_at(db_s);
    assert!(std::fs::read_to_string(&prof).unwrap().starts_with("<svg"));
    // Extended XYZ: the particle count, then one line per particle.
    let x = std::fs::read_to_string(&xyz).unwrap();
    let n: usize = x.lines().next().unwrap().trim().parse().unwrap();
    assert_eq!(x.lines().count(), n + 2);

    // Bad job references are bad input (exit 2), named in the message.
    for bad in ["12", "zzzzzzzz", "ffffffffff"] {
        let o = wetgran()
            .args(["show", "--db", db_s, bad])
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(2), "{}", text(&o));
        assert!(text(&o).contains(bad), "{}", text(&o));
    }

    // A reader that stops early (`wetgran export | head`) ends the export quietly with the
    // SIGPIPE status, not with a panic report.
    {
        use std::io::{BufRead, BufReader};
        let mut child = wetgran()
            .args(["export", "--db", db_s, "--format", "json"])
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        let mut first = String::new();
        BufReader::new(child.stdout.take().unwrap())
            .read_line(&mut first)
            .unwrap();
        assert_eq!(first.trim(), "[");
        let out = child.wait_with_output().unwrap();
        assert_eq!(out.status.code(), Some(141), "{}", text(&out));
        assert!(!text(&out).contains("panicked"), "{}", text(&out));
    }

    // The job is found by its prefix in any case; a prefix no job has is a usage error.
    let upper = wetgran()
        .args(["show", "--db", db_s, &id[..8].to_ascii_uppercase()])
        .output()
        .unwrap();
    assert!(upper.status.success(), "{}", text(&upper));
    assert!(text(&upper).contains(&id), "{}", text(&upper));
    let absent = if id.starts_with('0') {
        "ffffff"
    } else {
        "000000"
    };
    let none = wetgran()
        .args(["show", "--db", db_s, absent])
        .output()
        .unwrap();
    assert_eq!(none.status.code(), Some(2), "{}", text(&none));
    assert!(
        text(&none).contains("no job id starts with"),
        "{}",
        text(&none)
    );

    // One line of constant Gamma with five E*: the analysis reports it.
    let inf = wetgran()
        .args(["inflection", "--db", db_s])
        .output()
        .unwrap();
    let out = text(&inf);
    assert!(inf.status.success(), "{out}");
    let line = out
        .lines()
        .find(|l| l.trim_start().starts_with("3.0000"))
        .unwrap_or_else(|| panic!("{out}"));
    assert_eq!(line.split_whitespace().nth(1), Some("5"), "{line}");
}

/// The time series figure of `show --series` (written to `series`) and the regions panel of a
/// coexistence; the same figure as PNG and PDF, and any other extension refused.
fn check_series(
    dir: &std::path::Path,
    db: &std::path::Path,
    db_s: &str,
    id: &str,
    stored_phase: &str,
    series: &std::path::Path,
) {
    // The time series: three panels (a wet scene, homogeneous or not split: no regions panel
    // unless its label is a coexistence), each time panel with the window and the ending
    // marked; the temperature curve has one vertex per stored sample.
    let fig = std::fs::read_to_string(series).unwrap();
    let panels: Vec<&str> = fig
        .match_indices("<g class=\"panel\" data-quantity=\"")
        .map(|(k, m)| {
            let rest = &fig[k + m.len()..];
            &rest[..rest.find('"').unwrap()]
        })
        .collect();
    let coexistence = stored_phase.len() == 3;
    let mut expected = vec!["temperature", "bridges", "delta_n_cb"];
    if coexistence {
        expected.push("regions");
    }
    assert_eq!(panels, expected, "{fig}");
    assert_eq!(fig.matches("class=\"window\"").count(), 3, "{fig}");
    assert_eq!(fig.matches("class=\"ending\"").count(), 3, "{fig}");
    assert!(fig.contains("ended at t = "), "{fig}");
    let samples = fig.split("class=\"samples\" d=\"").nth(1).unwrap();
    let vertices = samples[..samples.find('"').unwrap()]
        .matches(['M', 'L'])
        .count();
    let ts = wetgran()
        .args(["export", "--db", db_s, "--series"])
        .arg(dir.join("series.csv"))
        .output()
        .unwrap();
    assert!(ts.status.success(), "{}", text(&ts));
    let long = std::fs::read_to_string(dir.join("series.csv")).unwrap();
    let stored = long
        .lines()
        .filter(|l| l.starts_with(id) && l.contains(",obs.series.temperature_reduced,"))
        .count();
    assert!(stored > 10, "{long}");
    assert_eq!(vertices, stored, "one vertex per stored sample");
    // A coexistence adds its regions' panel: the members' and the other grains' temperatures,
    // block means against block number (their tested histories' starts are not stored).
    {
        let store = wetgran::store::Store::open_existing(db).unwrap();
        let sweep = store.sweep("line").unwrap();
        let row = store
            .points(sweep.id)
            .unwrap()
            .into_iter()
            .find(|r| r.job_id == id)
            .unwrap();
        let mut obs = row.observables.clone().unwrap();
        let test = |q: &str, means: [f64; 4]| {
            serde_json::json!({"quantity": q, "mean": 1.0, "standard_error": 0.1,
                "block_means": means, "block_errors": [0.1, 0.1, 0.1, 0.1],
                "max_pair_sigmas": 1.0, "drift": 0.0, "drift_error": 0.1, "tolerance": 0.02,
                "agree": true, "no_trend": true})
        };
        obs["trend"]["region_tests"] = serde_json::json!([
            test("member_temperature", [0.2, 0.21, 0.19, 0.2]),
            test("unbonded_temperature", [3.0, 3.1, 2.9, 3.0]),
        ]);
        let obs: wetgran_core::observe::Observables = serde_json::from_value(obs).unwrap();
        let coexistence = wetgran::report::series_plot::series_svg(&obs, "t", Some("fgc"));
        assert_eq!(coexistence.matches("<g class=\"panel\"").count(), 4);
        let regions = &coexistence[coexistence.find("data-quantity=\"regions\"").unwrap()..];
        for q in ["member_temperature", "unbonded_temperature"] {
            let path = regions
                .split(&format!("class=\"blocks\" data-quantity=\"{q}\" d=\""))
                .nth(1)
                .unwrap_or_else(|| panic!("no {q}: {regions}"));
            // Four steps, each with its error bar.
            assert_eq!(
                path[..path.find('"').unwrap()].matches('M').count(),
                8,
                "{q}"
            );
        }
        let homogeneous = wetgran::report::series_plot::series_svg(&obs, "t", Some("f"));
        assert_eq!(homogeneous.matches("<g class=\"panel\"").count(), 3);
    }
    // The same figure as PNG and PDF (by the extension): the PNG decodes at three times the
    // SVG's width, and the PDF's one page carries the panels' quantity names.
    let png = dir.join("series.png");
    let pdf = dir.join("series.pdf");
    let o = wetgran()
        .args(["show", "--db", db_s, &id[..10], "--series"])
        .arg(&png)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", text(&o));
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&png).unwrap()));
    let info = decoder.read_info().unwrap().info().clone();
    let svg_width: f64 = {
        let doc = roxmltree::Document::parse(&fig).unwrap();
        doc.root_element()
            .attribute("width")
            .unwrap()
            .parse()
            .unwrap()
    };
    assert_eq!(
        info.width as f64,
        (3.0 * svg_width).round(),
        "PNG at 3 px per SVG px"
    );
    let o = wetgran()
        .args(["show", "--db", db_s, &id[..10], "--series"])
        .arg(&pdf)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", text(&o));
    let doc = lopdf::Document::load(&pdf).unwrap();
    assert_eq!(doc.get_pages().len(), 1, "one page");
    // Anything else is refused, naming the figure formats, and nothing is written.
    let bad = dir.join("series.txt");
    let o = wetgran()
        .args(["show", "--db", db_s, &id[..10], "--series"])
        .arg(&bad)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains(".svg, .pdf or .png"), "{}", text(&o));
    assert!(!bad.exists());
}

/// `show --at`: the nearest job in the axes' own scale, by names, keys and labels; unknown axes
/// and a missing job refused.
fn check_at(db_s: &str) {
    // Found by its coordinates: E* = 0.5 lies nearer 0.721 than 0.3 on the log axis (on a
    // linear one it would be 0.3); axis names, keys and labels all work.
    for at in [
        "gamma=3,e_star=0.5",
        "Gamma=3.1,E*=0.5",
        "drive.gamma=2.9,e_star=0.5",
    ] {
        let o = wetgran()
            .args(["show", "--db", db_s, "--at", at])
            .output()
            .unwrap();
        assert!(o.status.success(), "{at}: {}", text(&o));
        assert!(
            text(&o).contains("at          Gamma = 3, E* = 0.721\n"),
            "{at}: {}",
            text(&o)
        );
    }
    let unknown = wetgran()
        .args(["show", "--db", db_s, "--at", "gama=3"])
        .output()
        .unwrap();
    assert_eq!(unknown.status.code(), Some(2), "{}", text(&unknown));
    assert!(
        text(&unknown).contains("unknown axis `gama`")
            && text(&unknown).contains("gamma (Gamma), e_star (E*)"),
        "{}",
        text(&unknown)
    );
    let neither = wetgran().args(["show", "--db", db_s]).output().unwrap();
    assert_eq!(neither.status.code(), Some(2), "{}", text(&neither));
}

/// The text of `show JOB --snapshot ...`: the decision summary and the stored final state.
fn check_summary(out: &str, id: &str, stored_phase: &str) {
    assert!(out.starts_with(&format!("job         {id}")), "{out}");
    // The phase line carries the verdict's mark after the label (none, `~` or `?`).
    assert!(
        out.lines().any(|l| l.starts_with("phase       ")
            && l["phase       ".len()..].trim_end_matches(['~', '?']) == stored_phase),
        "{out}"
    );
    // Labelled, rounded coordinates; one "decided by" line; the regions' table; no JSON.
    assert!(out.contains("at          Gamma = 3, E* = "), "{out}");
    assert_eq!(out.matches("decided by  ").count(), 1, "{out}");
    let table = out
        .lines()
        .position(|l| l == "regions")
        .unwrap_or_else(|| panic!("no regions table: {out}"));
    let head: Vec<&str> = out
        .lines()
        .nth(table + 1)
        .unwrap()
        .split_whitespace()
        .collect();
    assert_eq!(&head[..3], ["region", "phase", "grains"], "{out}");
    let whole = out.lines().nth(table + 2).unwrap();
    assert!(whole.trim_start().starts_with("whole "), "{out}");
    assert!(out.contains("\ntrend       "), "{out}");
    assert!(out.contains("\nsettled     "), "{out}");
    assert!(!out.contains('{'), "JSON in the text output: {out}");
    // The snapshot is the stored final state, as the report's (no re-run).
    assert!(out.contains("final state the stored one, t = "), "{out}");
    assert!(!out.contains("re-run"), "{out}");
}
