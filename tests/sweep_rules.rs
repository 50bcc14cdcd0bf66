//! A sweep does what its file says (issue 18): the whole plane of the shipped sweeps is valid,
//! `skip_invalid` leaves out only points failing a scene constraint, every error names the sweep
//! file and line, `--jobs` stays within the cores, a grid is replaced only when asked, a changed
//! `[classify]` re-labels without simulating, and the exports and tables show the stationarity
//! verdict with scalar CSV columns.

mod sweep_common;

use std::path::Path;
use sweep_common::*;
use wetgran::store::Store;
use wetgran::sweep::SweepFile;
use wetgran_core::observe::{Observables, Thresholds, classify};

fn sweep_file(dir: &Path, name: &str, body: &str) -> std::path::PathBuf {
    write(dir, "tiny.toml", TINY_SCENE);
    write(
        dir,
        &format!("{name}.toml"),
        &format!("[sweep]\nname = \"{name}\"\nbase = \"tiny.toml\"\n{body}"),
    )
}

fn expand_err(path: &Path) -> String {
    match SweepFile::load(path).and_then(|s| s.expand().map(|_| ())) {
        Ok(()) => panic!("expected an error for {}", path.display()),
        Err(e) => e.to_string(),
    }
}

#[test]
fn every_point_of_the_shipped_shaking_sweeps_is_valid() {
    // Before issue 18 the stroke limit `H > 2 A + d_max` left out 35 of these 156 points. The
    // elastic sweep runs each point from the hot start, continued along E* and from the cold
    // start: 468 jobs, the 12 chain heads the hot jobs of their points (456 distinct).
    for (file, points) in [
        ("sweeps/shaken_2d_elastic.toml", 468),
        ("sweeps/shaken_2d_eps09.toml", 156),
    ] {
        let s = SweepFile::load(Path::new(file)).unwrap_or_else(|e| panic!("{e}"));
        let (jobs, skipped) = s.expand_with_skips().unwrap_or_else(|e| panic!("{e}"));
        assert!(skipped.is_empty(), "{file}: {:?}", skipped[0].reason);
        assert_eq!(jobs.len(), points, "{file}");
        // The large-amplitude corner is in: some job has a stroke longer than its box.
        assert!(
            jobs.iter().any(|j| {
                let (a, _) = j.spec.scene.drive_motion().unwrap();
                2.0 * a > j.spec.scene.container.size[1]
            }),
            "{file}"
        );
    }
}

#[test]
fn an_axis_value_outside_its_range_is_an_error_even_with_skip_invalid() {
    let dir = tempfile::tempdir().unwrap();
    let p = sweep_file(
        dir.path(),
        "typo",
        "skip_invalid = true\n[[axis]]\nkey = \"gamma\"\nvalues = [5, -2, 0]\n",
    );
    let e = expand_err(&p);
    assert!(
        e.starts_with(&format!("{}:6: key `drive.gamma`", p.display())),
        "{e}"
    );
    // `sweep expand` refuses it too, with status 2.
    let out = run(&["sweep", "expand", p.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(stderr(&out).contains("drive.gamma"), "{}", stderr(&out));
}

#[test]
fn sweep_expand_lists_the_left_out_points_and_why() {
    let dir = tempfile::tempdir().unwrap();
    let p = sweep_file(
        dir.path(),
        "crowded",
        "skip_invalid = true\n[[axis]]\nkey = \"particles.count\"\nvalues = [40, 5000]\n",
    );
    let out = run(&["sweep", "expand", p.to_str().unwrap()]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert_eq!(stdout(&out).lines().count(), 1);
    let err = stderr(&out);
    assert!(err.contains("left out 1 grid point(s)"), "{err}");
    let line = err
        .lines()
        .find(|l| l.contains("left out particles.count = "))
        .unwrap_or_else(|| panic!("{err}"));
    assert!(line.contains("5"), "{line}");
    assert!(
        line.ends_with("more particles than fit on the initial lattice"),
        "{line}"
    );
    // `sweep status` lists them from the database.
    let db = dir.path().join("w.sqlite");
    let db_s = db.to_str().unwrap();
    let out = run(&[
        "sweep",
        "run",
        p.to_str().unwrap(),
        "--db",
        db_s,
        "--jobs",
        "1",
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let status = stdout(&run(&["sweep", "status", "--db", db_s]));
    assert!(
        status.contains("left out 1 grid point(s) (sweep.skip_invalid):"),
        "{status}"
    );
    assert!(
        status.contains("more particles than fit on the initial lattice"),
        "{status}"
    );
}

#[test]
fn a_range_of_one_step_between_two_values_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    for kind in ["linear", "log"] {
        let p = sweep_file(
            dir.path(),
            "one",
            &format!("[[axis]]\nkey = \"gamma\"\n{kind} = {{ from = 5, to = 8, steps = 1 }}\n"),
        );
        let e = expand_err(&p);
        assert!(
            e.starts_with(&format!("{}:6: key `drive.gamma`", p.display())),
            "{e}"
        );
        assert!(e.contains("steps = 1 with from = 5 != to = 8"), "{e}");
    }
    // from = to with one step is one value.
    let p = sweep_file(
        dir.path(),
        "same",
        "[[axis]]\nkey = \"gamma\"\nlinear = { from = 5, to = 5, steps = 1 }\n",
    );
    assert_eq!(SweepFile::load(&p).unwrap().axes[0].values.len(), 1);
}

#[test]
fn errors_in_observe_and_classify_name_the_sweep_file_and_line() {
    let dir = tempfile::tempdir().unwrap();
    for (table, line, key) in [
        (
            "[classify]\nmobility = \"location_changes\"\ngas_temperature = -1.0\n",
            7,
            "classify.gas_temperature",
        ),
        (
            "[observe]\nsamples_per_period = 10\nbogus = 1\n",
            7,
            "observe.bogus",
        ),
    ] {
        let p = sweep_file(
            dir.path(),
            "bad",
            &format!("periods = 20\n{table}[[axis]]\nkey = \"gamma\"\nvalues = [2.0]\n"),
        );
        let e = expand_err(&p);
        assert!(
            e.starts_with(&format!("{}:{line}: key `{key}`", p.display())),
            "{e}"
        );
    }
}

#[test]
fn jobs_must_be_between_one_and_the_available_cores() {
    let dir = tempfile::tempdir().unwrap();
    let p = sweep_file(
        dir.path(),
        "j",
        "[[axis]]\nkey = \"gamma\"\nvalues = [2.0]\n",
    );
    let db = dir.path().join("w.sqlite");
    let cores = std::thread::available_parallelism().unwrap().get();
    let many = (cores + 1).to_string();
    for jobs in ["0", many.as_str()] {
        let out = run(&[
            "sweep",
            "run",
            p.to_str().unwrap(),
            "--db",
            db.to_str().unwrap(),
            "--jobs",
            jobs,
        ]);
        assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
        let err = stderr(&out);
        assert!(
            err.contains(&format!(
                "--jobs {jobs} is out of range: must be in [1, {cores}]"
            )),
            "{err}"
        );
        assert!(!db.exists(), "nothing may be written");
    }
    let out = run(&[
        "sweep",
        "run",
        p.to_str().unwrap(),
        "--db",
        db.to_str().unwrap(),
        "--jobs",
        &many,
    ]);
    assert!(stderr(&out).contains("--oversubscribe"), "{}", stderr(&out));
}

#[test]
fn a_new_grid_under_a_registered_name_needs_replace() {
    let dir = tempfile::tempdir().unwrap();
    let old = sweep_file(
        dir.path(),
        "grid",
        "[[axis]]\nkey = \"gamma\"\nvalues = [2.0, 3.0]\n",
    );
    let db = dir.path().join("w.sqlite");
    let store = Store::open(&db).unwrap();
    let s = SweepFile::load(&old).unwrap();
    let row = store.register_sweep(&s, &s.expand().unwrap()).unwrap();
    assert_eq!(finish_synthetic(&store, row.id, |_, _| Some("g".into())), 2);
    drop(store);
    let new = sweep_file(
        dir.path(),
        "grid",
        "[[axis]]\nkey = \"gamma\"\nvalues = [3.0, 4.0, 5.0]\n",
    );
    let out = run(&[
        "sweep",
        "run",
        new.to_str().unwrap(),
        "--db",
        db.to_str().unwrap(),
        "--jobs",
        "1",
    ]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    let err = stderr(&out);
    assert!(
        err.contains("old grid: Gamma = [2.0, 3.0]; 1 replica(s) (2 job(s))"),
        "{err}"
    );
    assert!(
        err.contains("new grid: Gamma = [3.0, 4.0, 5.0]; 1 replica(s) (3 job(s))"),
        "{err}"
    );
    assert!(
        err.contains("1 job(s) of the old grid, 1 of them with a result"),
        "{err}"
    );
    assert!(err.contains("--replace"), "{err}");
    // The grid in the database is unchanged.
    let store = Store::open_existing(&db).unwrap();
    assert_eq!(store.points(row.id).unwrap().len(), 2);
}

/// Runs `wetgran` and asserts success.
fn ok(args: &[&str]) -> String {
    let out = run(args);
    assert!(out.status.success(), "{args:?}: {}", stderr(&out));
    stdout(&out) + &stderr(&out)
}

/// Every stored label of the sweep equals the classifier's answer with `th`.
fn assert_labels_follow(store: &Store, sweep: &str, th: &Thresholds) -> usize {
    let s = store.sweep(sweep).unwrap();
    let mut n = 0;
    for p in store.points(s.id).unwrap() {
        let obs: Observables = serde_json::from_value(p.observables.unwrap()).unwrap();
        let c = classify(&obs, th);
        assert_eq!(p.phase.as_deref(), Some(c.phase.to_string().as_str()));
        assert_eq!(
            p.decided_on,
            Some(serde_json::to_value(&c.decided_on).unwrap())
        );
        n += 1;
    }
    n
}

/// `export` of the four results of the sweep in `db_s`: one row per result, scalar columns
/// only, the series in their own file indexed per job. Returns the job ids of the rows.
fn check_export(dir: &std::path::Path, db_s: &str) -> Vec<String> {
    // Export: one row per result, scalar columns only; the series go to their own file.
    let csv_path = dir.join("r.csv");
    let series_path = dir.join("series.csv");
    ok(&[
        "export",
        "--db",
        db_s,
        "-o",
        csv_path.to_str().unwrap(),
        "--series",
        series_path.to_str().unwrap(),
    ]);
    let csv = std::fs::read_to_string(&csv_path).unwrap();
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    assert!(header.len() < 100, "{} columns: {header:?}", header.len());
    assert!(header.contains(&"verdict") && header.contains(&"trust"));
    assert!(
        !header
            .iter()
            .any(|h| h.rsplit('.').next().unwrap().parse::<usize>().is_ok()),
        "an array element became a column: {header:?}"
    );
    assert_eq!(csv.lines().count(), 5);
    let series = std::fs::read_to_string(&series_path).unwrap();
    let mut lines = series.lines();
    assert_eq!(lines.next(), Some("job_id,series,index,value"));
    let id_col = header.iter().position(|h| *h == "job_id").unwrap();
    let ids: Vec<String> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(id_col).unwrap().to_string())
        .collect();
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert!(rows.len() > 4 * 10, "{} series rows", rows.len());
    for r in &rows {
        assert_eq!(r.len(), 4, "{r:?}");
        assert!(ids.iter().any(|i| i == r[0]), "{r:?}");
        assert!(r[2].parse::<usize>().is_ok(), "{r:?}");
    }
    // A series' indices count 0, 1, 2, ... per job.
    let first = &rows[0];
    let idx: Vec<usize> = rows
        .iter()
        .filter(|r| r[0] == first[0] && r[1] == first[1])
        .map(|r| r[2].parse().unwrap())
        .collect();
    assert_eq!(idx, (0..idx.len()).collect::<Vec<_>>());
    ids
}

/// Rows of the `runs` table (simulations started, ever), read with plain SQL.
fn runs_started(db: &Path) -> i64 {
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .unwrap();
    rt.block_on(async {
        let url = format!("sqlite://{}?mode=ro", db.display());
        let pool = sqlx::SqlitePool::connect(&url).await.unwrap();
        let n = sqlx::query_scalar("SELECT count(*) FROM runs")
            .fetch_one(&pool)
            .await
            .unwrap();
        pool.close().await;
        n
    })
}

#[test]
fn a_changed_classify_relabels_without_simulating_and_exports_stay_scalar() {
    let dir = tempfile::tempdir().unwrap();
    let body = |classify: &str| {
        format!(
            "periods = 4\n{classify}[[axis]]\nkey = \"gamma\"\nvalues = [1.5, 4.0]\n\
             [[axis]]\nkey = \"e_star\"\nvalues = [0.5, 4.0]\n"
        )
    };
    let first = sweep_file(dir.path(), "cls", &body(""));
    let db = dir.path().join("w.sqlite");
    let db_s = db.to_str().unwrap();
    ok(&[
        "sweep",
        "run",
        first.to_str().unwrap(),
        "--db",
        db_s,
        "--jobs",
        "1",
    ]);
    let store = Store::open_existing(&db).unwrap();
    assert_eq!(runs_started(&db), 4);
    assert_labels_follow(&store, "cls", &Thresholds::default());
    drop(store);

    // Only [classify] changes: no simulation, the labels follow the new thresholds.
    let th = "[classify]\nmobility = \"temperature\"\nsolid_temperature = 1e-12\ngas_temperature = 1e-9\n";
    let second = sweep_file(dir.path(), "cls", &body(th));
    ok(&[
        "sweep",
        "run",
        second.to_str().unwrap(),
        "--db",
        db_s,
        "--jobs",
        "1",
    ]);
    let store = Store::open_existing(&db).unwrap();
    assert_eq!(runs_started(&db), 4, "nothing may be simulated again");
    let new: Thresholds = toml::from_str(&th.replace("[classify]\n", "")).unwrap();
    assert_eq!(assert_labels_follow(&store, "cls", &new), 4);

    // `reclassify --classify FILE` applies a thresholds file and counts the changes.
    let everything_solid = write(
        dir.path(),
        "solid.toml",
        "[classify]\nmobility = \"temperature\"\nsolid_temperature = 1e12\ngas_temperature = 2e12\n",
    );
    let before: Vec<Option<String>> = store
        .points(store.sweep("cls").unwrap().id)
        .unwrap()
        .into_iter()
        .map(|p| p.phase)
        .collect();
    let th_solid: Thresholds = toml::from_str(
        "mobility = \"temperature\"\nsolid_temperature = 1e12\ngas_temperature = 2e12\n",
    )
    .unwrap();
    drop(store);
    let reclassify_with = |file: &std::path::Path| {
        ok(&[
            "reclassify",
            "--sweep",
            "cls",
            "--classify",
            file.to_str().unwrap(),
            "--db",
            db_s,
        ])
    };
    let text = reclassify_with(&everything_solid);
    let store = Store::open_existing(&db).unwrap();
    assert_labels_follow(&store, "cls", &th_solid);
    let after: Vec<Option<String>> = store
        .points(store.sweep("cls").unwrap().id)
        .unwrap()
        .into_iter()
        .map(|p| p.phase)
        .collect();
    let changed = before.iter().zip(&after).filter(|(a, b)| a != b).count();
    assert!(
        changed > 0,
        "the extreme thresholds must change labels: {before:?} {after:?}"
    );
    assert!(
        text.contains(&format!(
            "4 result(s) re-labelled: {changed} label(s) changed"
        )),
        "{text}"
    );
    assert!(!text.contains("no f_lc"), "{text}");
    // Thresholds that decide mobility by f_lc, on results whose runs did not count location
    // changes (the counter is off by default): the fallback to T_g is said, with the remedy.
    let by_flc = write(
        dir.path(),
        "flc.toml",
        "[classify]\nmobility = \"location_changes\"\n",
    );
    drop(store);
    let flc_text = reclassify_with(&by_flc);
    assert!(
        flc_text.contains("4 result(s) have no f_lc")
            && flc_text.contains("location_changes = true"),
        "{flc_text}"
    );
    // Back to the thresholds the rest of this test checks.
    reclassify_with(&everything_solid);
    // No mobile label survives a solid threshold of 1e12 E_cb.
    assert!(
        after
            .iter()
            .all(|p| !matches!(p.as_deref(), Some("f" | "g" | "fgc"))),
        "{after:?}"
    );
    assert_eq!(runs_started(&db), 4);

    let ids = check_export(dir.path(), db_s);

    // `show` states the verdict on the label.
    let job = &ids[0];
    let shown = ok(&["show", "--db", db_s, job]);
    assert!(shown.contains("settled     "), "{shown}");
}

#[test]
fn non_stationary_results_are_counted_and_marked() {
    let dir = tempfile::tempdir().unwrap();
    let p = sweep_file(
        dir.path(),
        "marks",
        "[[axis]]\nkey = \"gamma\"\nvalues = [2.0, 3.0]\n[[axis]]\nkey = \"e_star\"\nvalues = [1.0, 2.0]\n",
    );
    let db = dir.path().join("w.sqlite");
    let store = Store::open(&db).unwrap();
    let s = SweepFile::load(&p).unwrap();
    let row = store.register_sweep(&s, &s.expand().unwrap()).unwrap();
    // Gamma = 3 drifts (not stationary), Gamma = 2 settled.
    while let Some(c) = store.claim(&[row.id]).unwrap() {
        let drifting = c.coords[0] == serde_json::json!(3.0);
        let result = wetgran::sweep::JobResult {
            phase: Some("g".into()),
            decided_on: Some(serde_json::json!({"settling": {
                "verdict": if drifting { "not_settled" } else { "stationary" },
                "regions": []}})),
            observables: serde_json::json!({}),
            simulated_time: 1.0,
            wall_seconds: 0.01,
            events: 10,
            checkpoint: None,
        };
        assert!(store.finish(&c, &result).unwrap());
    }
    drop(store);
    let db_s = db.to_str().unwrap();
    let status = ok(&["sweep", "status", "--db", db_s]);
    assert!(
        status.contains("trust  2 of 4 result(s) not stationary"),
        "{status}"
    );
    let map = ok(&["boundaries", "--db", db_s]);
    assert!(map.contains("? = not settled"), "{map}");
    assert_eq!(map.matches("g?").count(), 2, "{map}");
    let csv = stdout(&run(&["export", "--db", db_s]));
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let col = header.iter().position(|h| *h == "verdict").unwrap();
    let unsettled = csv
        .lines()
        .skip(1)
        .filter(|l| l.split(',').nth(col) == Some("not_settled"))
        .count();
    assert_eq!(unsettled, 2, "{csv}");
}

/// Every sweep file shipped under `sweeps/` (the validation sweeps in `sweeps/validation/`
/// included) parses and expands.
#[test]
fn every_shipped_sweep_file_expands() {
    fn walk(dir: &Path, out: &mut Vec<std::path::PathBuf>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                walk(&p, out);
            } else if p.extension().is_some_and(|x| x == "toml") {
                out.push(p);
            }
        }
    }
    let mut files = Vec::new();
    walk(Path::new("sweeps"), &mut files);
    assert!(files.len() >= 17, "{files:?}");
    for f in files {
        let s = SweepFile::load(&f).unwrap_or_else(|e| panic!("{e}"));
        let jobs = s.expand().unwrap_or_else(|e| panic!("{e}"));
        assert!(!jobs.is_empty(), "{}", f.display());
    }
}
