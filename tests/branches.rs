//! Both starts of a diagram (issue 32, item 3): sweeps with an `initial.start` axis (`["hot",
//! "cold"]`, `["hot", "continue"]`), their results prepared through the store (synthetic
//! phases, no simulation).
//! `boundaries` extracts and names each branch's boundaries separately (table, JSON, CSV), and
//! `plot` draws the two branches as one map that marks the bistable points (split discs with
//! both labels) only where the starts disagree.

mod sweep_common;

use std::path::{Path, PathBuf};
use sweep_common::*;
use wetgran::store::Store;
use wetgran::sweep::SweepFile;

/// A (Gamma 2, 3) x (E* 1, 2, 4) x (hot, cold) sweep with synthetic phases: the hot branch is
/// a gas from E* = 2 on; the cold branch too when `bistable` is false, else only from E* = 4
/// (the bonded bed stays a fluid at E* = 2: two bistable points). Returns the database.
fn prepared(dir: &Path, bistable: bool) -> PathBuf {
    write(dir, "tiny.toml", TINY_SCENE);
    let file = write(
        dir,
        "both.toml",
        "[sweep]\nname = \"both\"\nbase = \"tiny.toml\"\nperiods = 6\n\
         [[axis]]\nkey = \"gamma\"\nvalues = [2.0, 3.0]\n\
         [[axis]]\nkey = \"e_star\"\nvalues = [1.0, 2.0, 4.0]\n\
         [[axis]]\nkey = \"initial.start\"\nvalues = [\"hot\", \"cold\"]\n",
    );
    let sweep = SweepFile::load(&file).unwrap();
    let db = dir.join("both.sqlite");
    let store = Store::open(&db).unwrap();
    let row = store
        .register_sweep(&sweep, &sweep.expand().unwrap())
        .unwrap();
    let phase = move |c: &[serde_json::Value], _: i64| {
        let e = c[1].as_f64().unwrap();
        let gas_from = if bistable && c[2] == "cold" { 3.0 } else { 1.5 };
        Some(if e < gas_from { "f" } else { "g" }.to_string())
    };
    assert_eq!(finish_synthetic(&store, row.id, phase), 12);
    db
}

fn ok_stdout(args: &[&str]) -> String {
    let o = run(args);
    assert!(o.status.success(), "{args:?}: {}", stderr(&o));
    stdout(&o)
}

#[test]
fn each_branch_has_its_own_named_boundaries() {
    let dir = tempfile::tempdir().unwrap();
    let db = prepared(dir.path(), true);
    let db = db.to_str().unwrap();

    let json: serde_json::Value =
        serde_json::from_str(&ok_stdout(&["boundaries", "--db", db, "--format", "json"])).unwrap();
    let slices = json[0]["map"]["slices"].as_array().unwrap();
    assert_eq!(slices.len(), 2, "{json}");
    // Per branch: the f|g boundary on every Delaunay edge from the last fluid to the first gas
    // column (both Gamma rows and the cell's diagonal: 3 points), halfway in log10 E*:
    // E* = sqrt(2) hot, sqrt(8) cold.
    for (slice, branch, e) in [
        (&slices[0], "hot", 2f64.sqrt()),
        (&slices[1], "cold", 8f64.sqrt()),
    ] {
        assert_eq!(slice["branch"], branch, "{slice}");
        assert_eq!(slice["points"].as_array().unwrap().len(), 6);
        let list = slice["boundaries"]["f|g"].as_array().unwrap();
        assert_eq!(list.len(), 3, "{slice}");
        for b in list {
            assert_eq!(b["branch"], branch, "{b}");
            let x = b["x"].as_f64().unwrap();
            assert!((x - e).abs() < 1e-9, "{branch}: {x} against {e}");
        }
    }

    let table = ok_stdout(&["boundaries", "--db", db]);
    assert!(
        table.contains("boundary f|g (3 point(s)), branch: hot start"),
        "{table}"
    );
    assert!(
        table.contains("boundary f|g (3 point(s)), branch: cold start"),
        "{table}"
    );

    let csv = ok_stdout(&["boundaries", "--db", db, "--format", "csv"]);
    // The branch column, then `decided_by` (empty on a boundary row).
    let boundary_rows: Vec<&str> = csv.lines().filter(|l| l.contains(",boundary,")).collect();
    assert_eq!(boundary_rows.len(), 6, "{csv}");
    assert_eq!(
        boundary_rows
            .iter()
            .filter(|l| l.ends_with(",hot,"))
            .count(),
        3
    );
    assert_eq!(
        boundary_rows
            .iter()
            .filter(|l| l.ends_with(",cold,"))
            .count(),
        3
    );

    // `sweep status` counts the two bistable points.
    let status = ok_stdout(&["sweep", "status", "--db", db]);
    assert!(status.contains("2 of 6 point(s) hysteretic"), "{status}");
}

/// `plot` of the prepared store; the SVG text.
fn plot(dir: &Path, db: &Path) -> String {
    let svg = dir.join("map.svg");
    let o = run(&[
        "plot",
        "--db",
        db.to_str().unwrap(),
        "-o",
        svg.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    // One map of both branches: no note that a slice was left out.
    assert!(!stderr(&o).contains("slices"), "{}", stderr(&o));
    std::fs::read_to_string(svg).unwrap()
}

/// The polygons of an SVG filled with `colour` (`#RRGGBB`).
fn polygons(svg: &str, colour: &str) -> usize {
    let doc = roxmltree::Document::parse(svg).expect("the SVG parses");
    doc.descendants()
        .filter(|n| n.has_tag_name("polygon") && n.attribute("fill") == Some(colour))
        .count()
}

#[test]
fn the_map_marks_bistable_points_with_both_labels_only_where_the_starts_disagree() {
    let dir = tempfile::tempdir().unwrap();
    let db = prepared(dir.path(), true);
    let svg = plot(dir.path(), &db);
    assert!(
        svg.contains("split disc: bistable (left hot start, right cold start)")
            && svg.contains("text by the disc: phases hot/cold"),
        "{svg}"
    );
    // The two bistable points (E* = 2): hot gas, cold fluid, two half discs each in the full
    // colours of their phases (the regions are paler shades), and the legend's two in greys;
    // their label in branch order.
    let full = |svg: &str| polygons(svg, "#2CA02C") + polygons(svg, "#D62728");
    assert_eq!(full(&svg), 2 * 2, "{svg}");
    assert_eq!(polygons(&svg, "#3C3C3C"), 1, "{svg}");
    // Their regions grey: the branches disagree there.
    assert_eq!(polygons(&svg, "#D7D7D7"), 2, "{svg}");
    assert_eq!(svg.matches("\ng/f\n").count(), 2, "{svg}");
    // Each branch's boundary lines with their own legend entry.
    assert!(svg.contains("phase boundary, hot start"), "{svg}");
    assert!(svg.contains("phase boundary, cold start"), "{svg}");

    let dir = tempfile::tempdir().unwrap();
    let db = prepared(dir.path(), false);
    let svg = plot(dir.path(), &db);
    assert!(!svg.contains("bistable"), "{svg}");
    assert_eq!(full(&svg), 0, "{svg}");
    assert!(!svg.contains("\ng/f\n"), "{svg}");
    assert!(svg.contains("phase boundary, cold start"), "{svg}");
}

#[test]
fn a_continued_branch_is_named_as_such() {
    // Hot start and continuation down in E* (the shipped elastic diagrams' axes): the continued
    // branch stays a gas at E* = 1 where the hot start is a fluid.
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "tiny.toml", TINY_SCENE);
    let file = write(
        dir.path(),
        "chain.toml",
        "[sweep]\nname = \"chain\"\nbase = \"tiny.toml\"\nperiods = 6\n\
         [sweep.continuation]\naxis = \"e_star\"\ndirection = \"descending\"\n\
         [[axis]]\nkey = \"gamma\"\nvalues = [2.0, 3.0]\n\
         [[axis]]\nkey = \"e_star\"\nvalues = [1.0, 2.0, 4.0]\n\
         [[axis]]\nkey = \"initial.start\"\nvalues = [\"hot\", \"continue\"]\n",
    );
    let sweep = SweepFile::load(&file).unwrap();
    let db = dir.path().join("chain.sqlite");
    let store = Store::open(&db).unwrap();
    let row = store
        .register_sweep(&sweep, &sweep.expand().unwrap())
        .unwrap();
    let phase = |c: &[serde_json::Value], _: i64| {
        let e = c[1].as_f64().unwrap();
        let gas_from = if c[2] == "continue" { 0.5 } else { 1.5 };
        Some(if e < gas_from { "f" } else { "g" }.to_string())
    };
    // 12 grid entries, the two chain heads (E* = 4) the hot jobs there: 10 jobs.
    assert_eq!(finish_synthetic(&store, row.id, phase), 10);
    let json: serde_json::Value = serde_json::from_str(&ok_stdout(&[
        "boundaries",
        "--db",
        db.to_str().unwrap(),
        "--format",
        "json",
    ]))
    .unwrap();
    let slices = json[0]["map"]["slices"].as_array().unwrap();
    assert_eq!(slices[1]["branch"], "continue", "{json}");
    // The continued branch is all gas: no boundary of its own.
    assert!(slices[1]["boundaries"].as_object().unwrap().is_empty());
    let svg = plot(dir.path(), &db);
    assert!(
        svg.contains("split disc: bistable (left hot start, right continuation)")
            && svg.contains("text by the disc: phases hot/continue"),
        "{svg}"
    );
    assert_eq!(svg.matches("\nf/g\n").count(), 2, "{svg}");
}
