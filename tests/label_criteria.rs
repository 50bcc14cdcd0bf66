//! Which criterion decided each label, in every report, and how far a boundary moves with the
//! thresholds (`boundaries --sensitivity`), on a sweep prepared through the store with synthetic
//! observables (no simulation but one short template run).
//!
//! The sweep: Gamma 2 and 3 by E* 0.5, 1, 2, 4, 8 (a factor 2 apart: 0.30103 decades), every
//! point homogeneous at `T_g / E_cb = 0.5` with `D_lat = 1e-3 E* / 1.4` (diffusing, no cage):
//! solid at E* 0.5 and 1, fluid above, so the f|s boundary lies between E* 1 and 2 on both
//! lines. The fluid points are too few on their line (3 < 4) for the line rule: the
//! gas-temperature fallback decides them. The point Gamma = 3, E* = 8 stored no mobility, so
//! the temperature fallback decided it mobile. Doubling `solid_diffusion` makes E* 2 solid and
//! moves the boundary by exactly one grid spacing, log10(2) decades; halving it makes E* 1 fluid
//! and moves it back one spacing. `gas_temperature` halved (1) or doubled (4) leaves every
//! fluid at 0.5 fluid: the boundary does not move.

mod sweep_common;

use serde_json::{Value, json};
use std::path::{Path, PathBuf};
use sweep_common::*;
use wetgran::store::Store;
use wetgran::sweep::{JobResult, SweepFile};
use wetgran_core::observe::{Observables, classify, run_observed};
use wetgran_core::scene::Scene;

/// A short wet scene whose observer measures the mobility over a lag its window holds.
const SCENE: &str = r#"
dimension = 2
gravity = 1.0
[box]
size = [20.0, 9.0]
boundary = ["periodic", "wall"]
[particles]
count = 20
[contact]
restitution = 0.9
[capillary]
model = "thin_thread"
s_crit = 0.0711
e_cb = 0.2844
[drive]
kind = "sine"
gamma = 2.0
e_star = 1.0
[engine]
min_rebound_speed = 0.03
[initial]
temperature_over_ecb = 20.0
seed = 1
[run]
duration = 2.0
[observe]
mobility_lag = 0.5
"#;

/// The synthetic observables of a point at `E*` (module doc), from a template run's record.
fn observables(template: &Value, e_star: f64, mobility: bool) -> Value {
    let mut o = template.clone();
    let d = 1e-3 * e_star / 1.4;
    o["granular_temperature_reduced"] = json!(0.5);
    if mobility {
        o["mobility"]["diffusion"] = json!(d);
        o["mobility"]["diffusion_short"] = json!(d);
    } else {
        o["mobility"] = Value::Null;
    }
    let bins = o["profiles"]["n_cb"].as_array().unwrap().len();
    o["profiles"]["n_cb"] = json!(vec![1.0; bins]);
    o["profiles"]["packing"] = json!(vec![0.5; bins]);
    o["profiles"]["diffusion"] = json!(vec![Value::Null; bins]);
    o["profiles"]["delta_n_cb"] = json!(0.0);
    o["profiles"]["delta_n_area"] = json!(0.0);
    // A fixed-length record whose history tested flat in everything: its label is stationary.
    o["trend"]["tests"] = json!([]);
    o["trend"]["region_tests"] = json!([]);
    o["trend"]["unrelaxed"] = json!([]);
    o["trend"]["policy"] = Value::Null;
    o
}

/// The prepared database (module doc), labelled by `wetgran reclassify` as a run leaves it.
fn prepared(dir: &Path) -> PathBuf {
    write(dir, "base.toml", SCENE);
    let file = write(
        dir,
        "grid.toml",
        "[sweep]\nname = \"grid\"\nbase = \"base.toml\"\n\
         [[axis]]\nkey = \"gamma\"\nvalues = [2.0, 3.0]\n\
         [[axis]]\nkey = \"e_star\"\nvalues = [0.5, 1.0, 2.0, 4.0, 8.0]\n",
    );
    let scene = Scene::from_toml_str(SCENE, "template").unwrap();
    let template =
        serde_json::to_value(run_observed(&scene, &Default::default(), &mut |_| {}).observables)
            .unwrap();
    let sweep = SweepFile::load(&file).unwrap();
    let db = dir.join("grid.sqlite");
    let store = Store::open(&db).unwrap();
    let row = store
        .register_sweep(&sweep, &sweep.expand().unwrap())
        .unwrap();
    while let Some(c) = store.claim(&[row.id]).expect("claim") {
        let (gamma, e) = (c.coords[0].as_f64().unwrap(), c.coords[1].as_f64().unwrap());
        let o = observables(&template, e, !(gamma == 3.0 && e == 8.0));
        let parsed: Observables = serde_json::from_value(o.clone()).unwrap();
        let label = classify(&parsed, &c.spec.scene.classify);
        let result = JobResult {
            checkpoint: None,
            phase: Some(label.phase.to_string()),
            decided_on: Some(serde_json::to_value(&label.decided_on).unwrap()),
            observables: o,
            simulated_time: 2.0,
            wall_seconds: 0.01,
            events: 10,
        };
        assert!(store.finish(&c, &result).expect("finish"));
    }
    drop(store);
    let db_text = db.to_str().unwrap();
    ok_stdout(&["reclassify", "--db", db_text]);
    db
}

fn ok_stdout(args: &[&str]) -> String {
    let o = run(args);
    assert!(o.status.success(), "{args:?}: {}", stderr(&o));
    stdout(&o)
}

#[test]
fn every_report_says_which_criterion_decided_each_label() {
    let dir = tempfile::tempdir().unwrap();
    let db_path = prepared(dir.path());
    let db = db_path.to_str().unwrap();

    // The phase map: a letter per cell, and the legend with the number of fallback labels.
    let table = ok_stdout(&["boundaries", "--db", db]);
    for cell in ["sD", "fG", "fT"] {
        assert!(table.contains(cell), "no {cell} in:\n{table}");
    }
    assert!(
        table.contains("T = temperature fallback") && table.contains("G = gas-temperature"),
        "{table}"
    );
    assert!(
        table.contains("6 of 10 label(s) rest on a fallback"),
        "{table}"
    );

    // Per point in csv and json.
    let csv = ok_stdout(&["boundaries", "--db", db, "--format", "csv"]);
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let col = header.iter().position(|h| *h == "decided_by").unwrap();
    let mut criteria: Vec<&str> = csv
        .lines()
        .filter(|l| l.contains(",point,"))
        .map(|l| l.split(',').nth(col).unwrap())
        .collect();
    criteria.sort();
    assert_eq!(
        criteria,
        [
            "displacement",
            "displacement",
            "displacement",
            "displacement",
            "gas_temperature_fallback",
            "gas_temperature_fallback",
            "gas_temperature_fallback",
            "gas_temperature_fallback",
            "gas_temperature_fallback",
            "temperature_fallback"
        ]
    );
    let json: Value =
        serde_json::from_str(&ok_stdout(&["boundaries", "--db", db, "--json"])).unwrap();
    let points = json[0]["map"]["slices"][0]["points"].as_array().unwrap();
    let fallback = points
        .iter()
        .filter(|p| p["decided_by"]["fallback"] == json!(true))
        .count();
    assert_eq!(fallback, 6);

    // show: the criterion and its numbers.
    let export = ok_stdout(&["export", "--db", db, "--format", "json"]);
    let rows: Vec<Value> = serde_json::from_str(&export).unwrap();
    let solid = rows
        .iter()
        .find(|r| r["drive.e_star"] == json!(0.5) && r["drive.gamma"] == json!(2.0))
        .unwrap();
    assert_eq!(solid["decided_by"], json!("displacement"));
    assert_eq!(solid["decided_by_fallback"], json!(false));
    let hot = rows
        .iter()
        .find(|r| r["drive.e_star"] == json!(8.0) && r["drive.gamma"] == json!(3.0))
        .unwrap();
    assert_eq!(hot["decided_by"], json!("temperature_fallback"));
    let job = solid["job_id"].as_str().unwrap();
    let show = ok_stdout(&["show", "--db", db, &job[..12]]);
    assert!(
        show.contains("decided by  s by displacement: D_lat 3.57e-4 <= solid_diffusion 0.001\n"),
        "{show}"
    );
    let job = hot["job_id"].as_str().unwrap();
    let show = ok_stdout(&["show", "--db", db, &job[..12]]);
    let line = show
        .lines()
        .find(|l| l.starts_with("decided by  "))
        .unwrap_or_else(|| panic!("{show}"));
    assert!(
        line.contains(" by temperature fallback: ") && line.ends_with("(a fallback decided it)"),
        "{show}"
    );
    let show: Value =
        serde_json::from_str(&ok_stdout(&["show", "--db", db, &job[..12], "--json"])).unwrap();
    assert_eq!(
        show["decided_by"]["criterion"],
        json!("temperature_fallback")
    );
    assert_eq!(show["decided_by"]["fallback"], json!(true));

    // plot: fallback points drawn in a square, with a legend entry.
    let svg = dir.path().join("map.svg");
    ok_stdout(&["plot", "--db", db, "-o", svg.to_str().unwrap()]);
    let svg = std::fs::read_to_string(svg).unwrap();
    assert!(
        svg.contains("square: decided by a fallback"),
        "no legend entry"
    );

    // The report: a column in the points table, and the sensitivity table.
    let site = dir.path().join("site");
    ok_stdout(&[
        "report",
        "--db",
        db,
        "-o",
        site.to_str().unwrap(),
        "--no-snapshots",
    ]);
    let index = std::fs::read_to_string(site.join("index.html")).unwrap();
    assert!(index.contains("data-key=\"decided_by\""));
    // A fallback in red, by its name (`temperature fallback`).
    assert!(index.contains("<span class=\"untrusted\" title=\""));
    assert!(index.contains("\">temperature fallback</span>"));
    assert!(index.contains("id=\"sensitivity\""));
    assert!(
        index.contains("solid_diffusion 0.001 -&gt; 0.002 (x2): 2 label(s) changed (f -&gt; s 2)")
    );
}

/// The displacements of the boundary `pair` under `threshold` varied by `factor`.
fn moved<'a>(s: &'a Value, threshold: &str, factor: f64, pair: &str) -> &'a Value {
    let v = s[0]["variations"]
        .as_array()
        .unwrap()
        .iter()
        .find(|v| v["threshold"] == json!(threshold) && v["factor"] == json!(factor))
        .unwrap();
    v["boundaries"]
        .as_array()
        .unwrap()
        .iter()
        .find(|b| b["pair"] == json!(pair))
        .unwrap()
}

#[test]
fn a_boundary_moves_by_one_grid_spacing_when_solid_diffusion_doubles() {
    let dir = tempfile::tempdir().unwrap();
    let db_path = prepared(dir.path());
    let db = db_path.to_str().unwrap();
    let s: Value = serde_json::from_str(&ok_stdout(&[
        "boundaries",
        "--db",
        db,
        "--sensitivity",
        "--json",
    ]))
    .unwrap();
    assert_eq!(s[0]["relabelled"], json!(10));
    assert_eq!(s[0]["differ_from_stored"], json!(0));
    let spacing = 2f64.log10();
    for factor in [0.5, 2.0] {
        let m = moved(&s, "solid_diffusion", factor, "f|s");
        assert_eq!(m["status"], json!("moved"));
        for key in ["x_median", "x_max"] {
            let x = m[key].as_f64().unwrap();
            assert!((x - spacing).abs() < 1e-12, "{key} {x} for x{factor}");
        }
        assert_eq!(m["y_max"], json!(0.0));
        assert_eq!(m["points"], json!([3, 3]));
    }
    // gas_temperature: no fluid is near it, nothing moves.
    for factor in [0.5, 2.0] {
        let m = moved(&s, "gas_temperature", factor, "f|s");
        assert_eq!(m["status"], json!("unchanged"), "{m}");
        assert_eq!(m["x_max"], json!(0.0));
    }
    let v = &s[0]["variations"];
    let gas = v
        .as_array()
        .unwrap()
        .iter()
        .find(|v| v["threshold"] == json!("gas_temperature") && v["factor"] == json!(2.0))
        .unwrap();
    assert_eq!(gas["labels_changed"], json!(0));
    assert_eq!(gas["from"], json!(2.0));
    assert_eq!(gas["to"], json!(4.0));
    // The text and csv forms say the same.
    let text = ok_stdout(&["boundaries", "--db", db, "--sensitivity"]);
    assert!(
        text.contains("f|s: 3 -> 3 points, E* median 0.301 max 0.301 dec, Gamma median 0 max 0"),
        "{text}"
    );
    let csv = ok_stdout(&["boundaries", "--db", db, "--sensitivity", "--format", "csv"]);
    assert!(
        csv.lines()
            .any(|l| l.starts_with("grid,solid_diffusion,value,2,0.001,0.002,2,,,f|s,moved,3,3,")),
        "{csv}"
    );
}
