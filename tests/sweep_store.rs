//! The SQLite store against real database files: atomic claims under concurrent claimers,
//! jobs shared between sweeps, foreign and damaged files refused without a byte changed, and the
//! phase map, boundaries, plot and export on synthetic results with a known straight boundary.

mod sweep_common;

use std::path::Path;
use sweep_common::*;
use wetgran::store::{Store, StoreError};
use wetgran::sweep::SweepFile;

/// A synthetic sweep: Gamma 1..10 (linear, 10 values) x E* 0.1..100 (log, 10 values), with
/// `E_cb` small enough that every point is a valid scene. Never simulated.
fn synthetic_sweep(dir: &Path, name: &str, replicas: u32) -> std::path::PathBuf {
    write(dir, "tiny.toml", TINY_SCENE);
    write(
        dir,
        &format!("{name}.toml"),
        &format!(
            "[sweep]\nname = \"{name}\"\nbase = \"tiny.toml\"\nreplicas = {replicas}\n\
             [scene]\ncapillary.e_cb = 0.002\n\
             [[axis]]\nkey = \"gamma\"\nlinear = {{ from = 1.0, to = 10.0, steps = 10 }}\n\
             [[axis]]\nkey = \"e_star\"\nlog = {{ from = 0.1, to = 100.0, steps = 10 }}\n"
        ),
    )
}

fn register(store: &Store, path: &Path) -> wetgran::store::SweepRow {
    let s = SweepFile::load(path).unwrap();
    let jobs = s.expand().unwrap();
    store.register_sweep(&s, &jobs).unwrap()
}

/// The known boundary: Gamma_b(E*) = 4.3 + 2 log10(E*); gas above, fluid below.
fn gamma_b(e_star: f64) -> f64 {
    4.3 + 2.0 * e_star.log10()
}

fn true_phase(coords: &[serde_json::Value]) -> &'static str {
    let (g, e) = (coords[0].as_f64().unwrap(), coords[1].as_f64().unwrap());
    if g > gamma_b(e) { "g" } else { "f" }
}

#[test]
fn concurrent_claimers_never_get_the_same_job() {
    let dir = tempfile::tempdir().unwrap();
    let db = dir.path().join("w.sqlite");
    let sweep = {
        let store = Store::open(&db).unwrap();
        register(&store, &synthetic_sweep(dir.path(), "grid", 1))
    };
    let id = sweep.id;
    // Four threads, each with its own connection, claim until the queue is empty.
    let handles: Vec<_> = (0..4)
        .map(|_| {
            let db = db.clone();
            std::thread::spawn(move || {
                let store = Store::open(&db).unwrap();
                let mut got = Vec::new();
                while let Some(c) = store.claim(&[id]).unwrap() {
                    got.push(c.job_id);
                }
                got
            })
        })
        .collect();
    let mut all: Vec<String> = handles
        .into_iter()
        .flat_map(|h| h.join().unwrap())
        .collect();
    assert_eq!(all.len(), 100);
    all.sort();
    all.dedup();
    assert_eq!(all.len(), 100, "a job was claimed twice");
    let store = Store::open_existing(&db).unwrap();
    assert!(store.runs_per_job().unwrap().iter().all(|(_, n)| *n == 1));
    assert_eq!(store.counts(sweep.id).unwrap().running, 100);
}

#[test]
fn an_identical_job_is_shared_between_sweeps_and_computed_once() {
    let dir = tempfile::tempdir().unwrap();
    let db = dir.path().join("w.sqlite");
    let store = Store::open(&db).unwrap();
    let a = register(&store, &synthetic_sweep(dir.path(), "a", 1));
    assert_eq!(
        finish_synthetic(&store, a.id, |c, _| Some(true_phase(c).into())),
        100
    );
    // A second sweep over a sub-grid plus one new Gamma value.
    let b_path = write(
        dir.path(),
        "b.toml",
        "[sweep]\nname = \"b\"\nbase = \"tiny.toml\"\n[scene]\ncapillary.e_cb = 0.002\n\
         [[axis]]\nkey = \"gamma\"\nvalues = [1.0, 2.0, 10.5]\n\
         [[axis]]\nkey = \"e_star\"\nlog = { from = 0.1, to = 100.0, steps = 10 }\n",
    );
    let b = register(&store, &b_path);
    let c = store.counts(b.id).unwrap();
    assert_eq!(
        (c.done, c.pending),
        (20, 10),
        "the Gamma = 1, 2 rows are already done"
    );
    assert_eq!(
        finish_synthetic(&store, b.id, |c, _| Some(true_phase(c).into())),
        10
    );
    assert!(store.runs_per_job().unwrap().iter().all(|(_, n)| *n == 1));
    // Registering a sweep again changes nothing that was computed.
    let a2 = register(&store, &dir.path().join("a.toml"));
    assert_eq!(a2.id, a.id);
    assert_eq!(store.counts(a.id).unwrap().done, 100);
}

#[test]
fn a_file_that_is_not_a_wetgran_database_is_refused_and_left_unchanged() {
    let dir = tempfile::tempdir().unwrap();
    // A text file.
    let text = write(
        dir.path(),
        "notes.sqlite",
        "my notes, not a database\n".repeat(10).as_str(),
    );
    let before = std::fs::read(&text).unwrap();
    match Store::open(&text) {
        Err(StoreError::NotSqlite { .. }) => {}
        other => panic!("expected NotSqlite, got {other:?}"),
    }
    assert_eq!(std::fs::read(&text).unwrap(), before);
    // Another program's SQLite database.
    let foreign = dir.path().join("foreign.sqlite");
    {
        use sqlx::sqlite::SqliteConnectOptions;
        let rt = tokio::runtime::Builder::new_current_thread()
            .enable_all()
            .build()
            .unwrap();
        rt.block_on(async {
            let mut conn = sqlx::ConnectOptions::connect(
                &SqliteConnectOptions::new()
                    .filename(&foreign)
                    .create_if_missing(true),
            )
            .await
            .unwrap();
            sqlx::query("CREATE TABLE customers (id INTEGER PRIMARY KEY, name TEXT)")
                .execute(&mut conn)
                .await
                .unwrap();
            sqlx::query("INSERT INTO customers (name) VALUES ('ada')")
                .execute(&mut conn)
                .await
                .unwrap();
            sqlx::Connection::close(conn).await.unwrap();
        });
    }
    let before = std::fs::read(&foreign).unwrap();
    let err = Store::open(&foreign).unwrap_err();
    assert!(matches!(err, StoreError::NotWetgran { .. }), "{err:?}");
    assert!(err.to_string().contains("customers"), "{err}");
    assert_eq!(std::fs::read(&foreign).unwrap(), before);
    // Through the command line: exit status 2, the path in the message, file unchanged.
    write(dir.path(), "tiny.toml", TINY_SCENE);
    let sweep = write(
        dir.path(),
        "s.toml",
        "[sweep]\nname = \"s\"\nbase = \"tiny.toml\"\n",
    );
    for path in [&text, &foreign] {
        let before = std::fs::read(path).unwrap();
        for args in [
            vec![
                "sweep",
                "run",
                sweep.to_str().unwrap(),
                "--db",
                path.to_str().unwrap(),
            ],
            vec!["sweep", "status", "--db", path.to_str().unwrap()],
            vec!["boundaries", "--db", path.to_str().unwrap()],
        ] {
            let out = run(&args);
            assert_eq!(out.status.code(), Some(2), "{args:?}: {}", stderr(&out));
            let e = stderr(&out);
            assert!(
                e.contains(path.to_str().unwrap()) && e.contains("not a wetgran database"),
                "{e}"
            );
        }
        assert_eq!(std::fs::read(path).unwrap(), before);
    }
}

#[test]
fn a_damaged_database_is_refused_and_left_unchanged() {
    let dir = tempfile::tempdir().unwrap();
    let db = dir.path().join("w.sqlite");
    {
        let store = Store::open(&db).unwrap();
        let s = register(&store, &synthetic_sweep(dir.path(), "grid", 1));
        finish_synthetic(&store, s.id, |c, _| Some(true_phase(c).into()));
    } // closed: the WAL is checkpointed into the main file
    let mut bytes = std::fs::read(&db).unwrap();
    let page = u16::from_be_bytes([bytes[16], bytes[17]]) as usize;
    assert!(bytes.len() >= 4 * page, "the database has several pages");
    // Overwrite the b-tree page headers of pages 2 and 3 with garbage.
    for p in [1, 2] {
        for b in &mut bytes[p * page..p * page + 64] {
            *b = 0xA5;
        }
    }
    std::fs::write(&db, &bytes).unwrap();
    let err = Store::open(&db).unwrap_err();
    assert!(matches!(err, StoreError::Damaged { .. }), "{err:?}");
    assert!(err.to_string().contains("damaged"), "{err}");
    assert_eq!(std::fs::read(&db).unwrap(), bytes);
    let out = run(&["sweep", "status", "--db", db.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(stderr(&out).contains("damaged"), "{}", stderr(&out));
    assert_eq!(std::fs::read(&db).unwrap(), bytes);
}

#[test]
fn boundary_points_of_a_straight_synthetic_boundary_lie_on_it() {
    let dir = tempfile::tempdir().unwrap();
    let db = dir.path().join("w.sqlite");
    {
        let store = Store::open(&db).unwrap();
        // Three replicas; replica 2 votes wrongly at every third point: the majority recovers
        // the true map.
        let s = register(&store, &synthetic_sweep(dir.path(), "line", 3));
        finish_synthetic(&store, s.id, |c, r| {
            let p = true_phase(c);
            let flip = r == 2 && (c[0].as_f64().unwrap() as i64) % 3 == 0;
            Some(
                if flip {
                    if p == "g" { "f" } else { "g" }
                } else {
                    p
                }
                .to_string(),
            )
        });
    }
    let out = run(&[
        "boundaries",
        "--db",
        db.to_str().unwrap(),
        "--format",
        "json",
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let v: serde_json::Value = serde_json::from_str(&stdout(&out)).unwrap();
    let map = &v[0]["map"];
    assert_eq!(map["x"]["label"], "E*");
    assert_eq!(map["x"]["log"], true);
    assert_eq!(map["y"]["label"], "Gamma");
    let slice = &map["slices"][0];
    let points = slice["points"].as_array().unwrap();
    assert_eq!(points.len(), 100);
    for p in points {
        assert_eq!(
            p["phase"],
            true_phase(p["coords"].as_array().unwrap()),
            "{p}"
        );
    }
    let bounds = slice["boundaries"].as_object().unwrap();
    assert_eq!(bounds.keys().collect::<Vec<_>>(), vec!["f|g"]);
    let list = bounds["f|g"].as_array().unwrap();
    // Grid steps: 1 in Gamma, 1/3 in log10 E*. A midpoint of an edge that crosses the line is
    // at most half a step (in Gamma, with the slope 2 per decade) from it.
    let half = 0.5 * (1.0 + 2.0 / 3.0) + 1e-9;
    for b in list {
        let (e, g) = (b["x"].as_f64().unwrap(), b["y"].as_f64().unwrap());
        assert!(
            (g - gamma_b(e)).abs() <= half,
            "{b} is {} off",
            g - gamma_b(e)
        );
        // Physical units from docs/model.md 4.1 with E_cb = 0.002.
        let v_w = (2.0 * e * 0.002_f64).sqrt();
        let (a, w) = (
            b["amplitude"].as_f64().unwrap(),
            b["omega"].as_f64().unwrap(),
        );
        assert!(
            (w - g / v_w).abs() < 1e-9 * w && (a - v_w * v_w / g).abs() < 1e-9 * a,
            "{b}"
        );
    }
    // Independent expectation: in every E* column the line passes between Gamma = floor(Gamma_b)
    // and floor + 1, so that vertical edge gives a point at exactly (E*, floor + 1/2).
    for k in 0..10 {
        let e = 10f64.powf(-1.0 + k as f64 / 3.0);
        let want = gamma_b(e).floor() + 0.5;
        assert!(
            list.iter()
                .any(|b| (b["x"].as_f64().unwrap() / e - 1.0).abs() < 1e-9
                    && (b["y"].as_f64().unwrap() - want).abs() < 1e-9),
            "no boundary point at E* = {e}, Gamma = {want}"
        );
    }
    // The table and CSV forms carry the same points.
    let csv = stdout(&run(&[
        "boundaries",
        "--db",
        db.to_str().unwrap(),
        "--format",
        "csv",
    ]));
    assert_eq!(
        csv.lines().filter(|l| l.contains(",boundary,f|g,")).count(),
        list.len()
    );
    let table = stdout(&run(&["boundaries", "--db", db.to_str().unwrap()]));
    assert!(
        table.contains(&format!("boundary f|g ({} point(s))", list.len())),
        "{table}"
    );
}

#[test]
fn plot_and_export_show_every_result() {
    let dir = tempfile::tempdir().unwrap();
    let db = dir.path().join("w.sqlite");
    {
        let store = Store::open(&db).unwrap();
        let s = register(&store, &synthetic_sweep(dir.path(), "grid", 1));
        finish_synthetic(&store, s.id, |c, _| Some(true_phase(c).into()));
    }
    let svg = dir.path().join("map.svg");
    let out = run(&[
        "plot",
        "--db",
        db.to_str().unwrap(),
        "-o",
        svg.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = std::fs::read_to_string(&svg).unwrap();
    assert!(text.starts_with("<svg"));
    // 100 points + one legend marker per phase (f, g), filled in the phase's colour.
    let doc = roxmltree::Document::parse(&text).unwrap();
    let dots = doc
        .descendants()
        .filter(|n| n.has_tag_name("circle"))
        .filter(|n| matches!(n.attribute("fill"), Some("#2CA02C" | "#D62728")))
        .count();
    assert_eq!(dots, 102);
    // The legend and axis names, typeset (s_crit with a subscript, Γ_C).
    let texts: Vec<String> = doc
        .descendants()
        .filter(|n| n.has_tag_name("text"))
        .map(|n| {
            let t: String = n
                .descendants()
                .filter_map(|d| d.is_text().then(|| d.text()).flatten())
                .collect();
            t.trim().to_string()
        })
        .collect();
    for label in [
        "A = d",
        "A = scrit",
        "Eq. 4.15, ΓC (caption)",
        "phase boundary",
        "E*",
        "fluid",
        "gas",
    ] {
        assert!(
            texts.iter().any(|t| t == label),
            "missing {label}: {texts:?}"
        );
    }

    // --all: decided_on.synthetic is the same in every row, left out by default.
    let csv = stdout(&run(&["export", "--db", db.to_str().unwrap(), "--all"]));
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |n: &str| {
        header
            .iter()
            .position(|h| *h == n)
            .unwrap_or_else(|| panic!("{n}"))
    };
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 100);
    for r in &rows {
        let coords = [
            serde_json::json!(r[col("drive.gamma")].parse::<f64>().unwrap()),
            serde_json::json!(r[col("drive.e_star")].parse::<f64>().unwrap()),
        ];
        assert_eq!(r[col("phase")], true_phase(&coords));
        assert_eq!(r[col("obs.n")], r[col("point")]);
        assert_eq!(r[col("decided_on.synthetic")], "true");
    }
    let json = stdout(&run(&[
        "export",
        "--db",
        db.to_str().unwrap(),
        "--format",
        "json",
    ]));
    let v: serde_json::Value = serde_json::from_str(&json).unwrap();
    assert_eq!(v.as_array().unwrap().len(), 100);
    assert_eq!(v[0]["drive.gamma"], 1.0);
}

#[test]
fn a_bad_sweep_file_leaves_the_database_untouched() {
    let dir = tempfile::tempdir().unwrap();
    let db = dir.path().join("w.sqlite");
    {
        let store = Store::open(&db).unwrap();
        let s = register(&store, &synthetic_sweep(dir.path(), "grid", 1));
        finish_synthetic(&store, s.id, |c, _| Some(true_phase(c).into()));
    }
    let before = std::fs::read(&db).unwrap();
    let bad = write(
        dir.path(),
        "bad.toml",
        "[sweep]\nname = \"grid\"\nbase = \"tiny.toml\"\n[[axis]]\nkey = \"gamma\"\nvalues = [0.0]\n",
    );
    let out = run(&[
        "sweep",
        "run",
        bad.to_str().unwrap(),
        "--db",
        db.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(2));
    let e = stderr(&out);
    assert!(
        e.contains(&format!("{}:5: key `drive.gamma`", bad.display())),
        "{e}"
    );
    assert_eq!(std::fs::read(&db).unwrap(), before);
    // Nor is a database created for it.
    let fresh = dir.path().join("fresh.sqlite");
    let out = run(&[
        "sweep",
        "run",
        bad.to_str().unwrap(),
        "--db",
        fresh.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(!fresh.exists());
}

#[test]
fn runners_opening_a_new_database_at_once_all_succeed() {
    for round in 0..5 {
        let dir = tempfile::tempdir().unwrap();
        let db = dir.path().join("new.sqlite");
        let barrier = std::sync::Arc::new(std::sync::Barrier::new(4));
        let handles: Vec<_> = (0..4)
            .map(|_| {
                let (db, barrier) = (db.clone(), barrier.clone());
                std::thread::spawn(move || {
                    barrier.wait();
                    Store::open(&db).map(|s| s.sweeps().unwrap().len())
                })
            })
            .collect();
        for h in handles {
            assert_eq!(h.join().unwrap(), Ok(0), "round {round}");
        }
    }
}

/// A `--db` in a folder that does not exist is named as such (exit 2, nothing created), not
/// reported as a read-only folder.
#[test]
fn a_database_in_a_missing_folder_is_named_as_such() {
    let dir = tempfile::tempdir().unwrap();
    let sweep = synthetic_sweep(dir.path(), "nofolder", 1);
    let db = dir.path().join("no/such/folder/w.sqlite");
    let o = run(&[
        "sweep",
        "run",
        sweep.to_str().unwrap(),
        "--db",
        db.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("no/such/folder does not exist: create it"),
        "{}",
        stderr(&o)
    );
    assert!(!stderr(&o).contains("read-only"), "{}", stderr(&o));
    assert!(!dir.path().join("no").exists());
}
