//! Trend states in the reports (issue 32, item 2): results prepared through the store with
//! synthetic observables (no simulation) carrying a trend state. The state lands in
//! `results.trend`, the verdict (in `decided_on.settling`) in `results.verdict`; `sweep status`
//! counts the states, `boundaries` marks `?` (not settled: the label may change) and `~` (label
//! kept) and rests boundaries on the stationary and the `~` points only, `plot` draws the two
//! kinds apart, `export` has the columns.

mod sweep_common;

use std::path::{Path, PathBuf};
use sweep_common::*;
use wetgran::store::Store;
use wetgran::sweep::{JobResult, SweepFile};
use wetgran_core::observe::trend::TrendState;

/// A line at Gamma = 2 over E* 1, 2, 4, 8, 16: f stationary, f undecided (label may change),
/// g heating (label kept), g stationary, g stationary.
fn prepared(dir: &Path) -> PathBuf {
    write(dir, "tiny.toml", TINY_SCENE);
    let file = write(
        dir,
        "line.toml",
        "[sweep]\nname = \"line\"\nbase = \"tiny.toml\"\nperiods = 6\n\
         [[axis]]\nkey = \"gamma\"\nvalues = [2.0]\n\
         [[axis]]\nkey = \"e_star\"\nvalues = [1.0, 2.0, 4.0, 8.0, 16.0]\n",
    );
    let sweep = SweepFile::load(&file).unwrap();
    let db = dir.join("line.sqlite");
    let store = Store::open(&db).unwrap();
    let row = store
        .register_sweep(&sweep, &sweep.expand().unwrap())
        .unwrap();
    while let Some(c) = store.claim(&[row.id]).expect("claim") {
        let e = c.coords[1].as_f64().unwrap();
        let (phase, state, verdict) = match e as i64 {
            1 => ("f", "stationary", "stationary"),
            2 => ("f", "undecided", "not_settled"),
            4 => ("g", "heating", "label_kept"),
            _ => ("g", "stationary", "stationary"),
        };
        let result = JobResult {
            checkpoint: None,
            phase: Some(phase.into()),
            decided_on: Some(serde_json::json!({
                "synthetic": true,
                "settling": {"verdict": verdict, "regions": []},
            })),
            observables: serde_json::json!({"trend": {"state": state}}),
            simulated_time: 1.0,
            wall_seconds: 0.01,
            events: 10,
        };
        assert!(store.finish(&c, &result).expect("finish"));
    }
    db
}

fn ok_stdout(args: &[&str]) -> String {
    let o = run(args);
    assert!(o.status.success(), "{args:?}: {}", stderr(&o));
    stdout(&o)
}

#[test]
fn the_trend_state_is_stored_and_shown_by_every_report() {
    let dir = tempfile::tempdir().unwrap();
    let db_path = prepared(dir.path());
    let db = db_path.to_str().unwrap();

    // Stored in its column at insert time, from the observables.
    let store = Store::open_existing(&db_path).unwrap();
    let s = store.sweep("line").unwrap();
    let trends: Vec<Option<TrendState>> = store
        .points(s.id)
        .unwrap()
        .iter()
        .map(|p| p.trend)
        .collect();
    assert_eq!(
        trends,
        [
            Some(TrendState::Stationary),
            Some(TrendState::Undecided),
            Some(TrendState::Heating),
            Some(TrendState::Stationary),
            Some(TrendState::Stationary),
        ]
    );
    drop(store);

    let status = ok_stdout(&["sweep", "status", "--db", db]);
    assert!(
        status.contains("trend  3 stationary, 1 heating, 1 undecided"),
        "{status}"
    );
    assert!(
        status.contains("2 of 5 result(s) not stationary: 1 not settled"),
        "{status}"
    );

    // The map marks both kinds; the boundary rests on the stationary f at E* = 1 and the
    // heating g at E* = 4 (the undecided f at E* = 2 is left out): halfway in log10 E*, at 2.
    let table = ok_stdout(&["boundaries", "--db", db]);
    assert!(table.contains("f?") && table.contains("g~"), "{table}");
    assert!(
        table.contains("label may change") && table.contains("label kept"),
        "{table}"
    );
    let json: serde_json::Value =
        serde_json::from_str(&ok_stdout(&["boundaries", "--db", db, "--format", "json"])).unwrap();
    let fg = json[0]["map"]["slices"][0]["boundaries"]["f|g"]
        .as_array()
        .unwrap()
        .clone();
    assert_eq!(fg.len(), 1, "{json}");
    assert_eq!(fg[0]["x_range"], serde_json::json!([1.0, 4.0]), "{fg:?}");
    assert!((fg[0]["x"].as_f64().unwrap() - 2.0).abs() < 1e-9, "{fg:?}");

    // (Were the heating gas left out too, the edge would run from E* = 1 to 8.)
    let svg_path = dir.path().join("map.svg");
    let o = run(&["plot", "--db", db, "-o", svg_path.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let svg = std::fs::read_to_string(&svg_path).unwrap();
    assert!(svg.contains("hollow: label may change"), "legend for ?");
    assert!(svg.contains("white centre: label kept"), "legend for ~");

    let csv = ok_stdout(&["export", "--db", db]);
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (trend, trust) = (col("trend"), col("trust"));
    let rows: Vec<Vec<&str>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    let got: Vec<(&str, &str)> = rows.iter().map(|r| (r[trend], r[trust])).collect();
    assert_eq!(
        got,
        [
            ("stationary", ""),
            ("undecided", "?"),
            ("heating", "~"),
            ("stationary", ""),
            ("stationary", ""),
        ]
    );
}
