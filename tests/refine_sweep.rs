//! Refinement through the store and the scheduler, on a real tiny sweep (40 disks, jobs of
//! ~0.1-0.3 s): a `[refine]` table honoured by `sweep run`, the same points from the same inputs,
//! and a refinement interrupted after a round was registered continuing under `sweep resume`.

mod sweep_common;

use std::path::Path;
use sweep_common::*;
use wetgran::refine::Settings;
use wetgran::refine::driver::{plan_jobs, refined_jobs};
use wetgran::run::{RunOptions, run_sweeps};
use wetgran::store::{REFINED_FROM, Store};
use wetgran::sweep::SweepFile;

/// 2 x 3 grid (fluid at low E*, gas at high E*), 4 refinement jobs in 2 rounds.
fn sweep_file(dir: &Path) -> std::path::PathBuf {
    write(dir, "tiny.toml", TINY_SCENE);
    write(
        dir,
        "refine.toml",
        "[sweep]\nname = \"r\"\nbase = \"tiny.toml\"\nperiods = 60\n\
         [[axis]]\nkey = \"gamma\"\nvalues = [2.0, 6.0]\n\
         [[axis]]\nkey = \"e_star\"\nlog = { from = 0.5, to = 4.0, steps = 3 }\n\
         [refine]\nbudget = 4\nrounds = 2\n",
    )
}

/// (point, replica, coords, job id) of every stored job.
fn rows(db: &Path) -> Vec<(i64, i64, String, String)> {
    let store = Store::open_existing(db).unwrap();
    let s = store.sweep("r").unwrap();
    store
        .points(s.id)
        .unwrap()
        .into_iter()
        .map(|p| {
            assert_eq!(p.status, "done", "{p:?}");
            (
                p.point,
                p.replica,
                serde_json::to_string(&p.coords).unwrap(),
                p.job_id,
            )
        })
        .collect()
}

fn run_ok(args: &[&str]) -> String {
    let o = run(args);
    assert!(o.status.success(), "{args:?}: {}", stderr(&o));
    both(&o)
}

#[test]
fn sweep_run_refines_deterministically_and_an_interrupted_refinement_resumes() {
    let dir = tempfile::tempdir().unwrap();
    let file = sweep_file(dir.path());
    let f = file.to_str().unwrap();
    let (a, b, c) = (
        dir.path().join("a.sqlite"),
        dir.path().join("b.sqlite"),
        dir.path().join("c.sqlite"),
    );
    let log = run_ok(&[
        "sweep",
        "run",
        f,
        "--db",
        a.to_str().unwrap(),
        "--jobs",
        "2",
    ]);
    let ra = rows(&a);
    // 6 grid jobs, then 4 refined ones (2 rounds of 2) at new points between grid points.
    assert_eq!(ra.len(), 10, "{log}");
    let refined: Vec<_> = ra.iter().filter(|r| r.0 >= REFINED_FROM).collect();
    assert_eq!(refined.len(), 4, "{ra:?}");
    let first = REFINED_FROM;
    assert_eq!(
        refined.iter().map(|r| r.0).collect::<Vec<_>>(),
        (first..first + 4).collect::<Vec<_>>()
    );
    let grid: Vec<&String> = ra
        .iter()
        .filter(|r| r.0 < REFINED_FROM)
        .map(|r| &r.2)
        .collect();
    for r in &refined {
        assert!(
            !grid.contains(&&r.2),
            "a refined point repeats a grid point: {r:?}"
        );
    }
    assert!(
        log.contains("refinement added 4 job(s) in 2 round(s)"),
        "{log}"
    );

    // Same inputs, another database: the same points, the same jobs.
    run_ok(&[
        "sweep",
        "run",
        f,
        "--db",
        b.to_str().unwrap(),
        "--jobs",
        "1",
    ]);
    assert_eq!(rows(&b), ra);

    // Running the file again adds nothing (the budget is spent) and keeps the refined points.
    let again = run_ok(&[
        "sweep",
        "run",
        f,
        "--db",
        a.to_str().unwrap(),
        "--jobs",
        "1",
    ]);
    assert!(!again.contains("refinement added"), "{again}");
    assert_eq!(rows(&a), ra);

    // Interrupted: the grid ran and the first round was registered, none of it ran.
    {
        let sweep = SweepFile::load(&file).unwrap();
        let store = Store::open(&c).unwrap();
        let row = store
            .register_sweep(&sweep, &sweep.expand().unwrap())
            .unwrap();
        let opts = RunOptions {
            jobs: 2,
            retry_failed: false,
            show_progress: false,
            table_cache_mib: 256,
            on_extend: None,
        };
        run_sweeps(&store, std::slice::from_ref(&row), &opts).unwrap();
        let section = sweep.refine.unwrap();
        let settings = Settings {
            replicas: 1,
            max_replicas: section.max_replicas,
            resolution: section.resolution,
        };
        let stored = store.point_summaries(&row).unwrap();
        let round = plan_jobs(&sweep, &row, &stored, 2, &settings).unwrap();
        assert_eq!(round.len(), 2);
        store.add_jobs(row.id, &round).unwrap();
        let stored = store.point_summaries(&row).unwrap();
        assert_eq!(refined_jobs(&stored, 1), 2);
        assert_eq!(store.counts(row.id).unwrap().pending, 2);
    }
    let log = run_ok(&[
        "sweep",
        "resume",
        "--db",
        c.to_str().unwrap(),
        "--jobs",
        "2",
    ]);
    assert!(
        log.contains("refinement added 2 job(s) in 1 round(s)"),
        "{log}"
    );
    assert_eq!(rows(&c), ra);
}

#[test]
fn sweep_refine_adds_its_budget_and_boundaries_carry_the_uncertainty() {
    let dir = tempfile::tempdir().unwrap();
    let file = sweep_file(dir.path());
    let text = std::fs::read_to_string(&file)
        .unwrap()
        .replace("[refine]\nbudget = 4\nrounds = 2\n", "");
    std::fs::write(&file, text).unwrap();
    let db = dir.path().join("w.sqlite");
    let d = db.to_str().unwrap();
    run_ok(&[
        "sweep",
        "run",
        file.to_str().unwrap(),
        "--db",
        d,
        "--jobs",
        "2",
    ]);
    // No [refine] table and no --budget: refused, naming what to give.
    let o = run(&["sweep", "refine", "--db", d]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("--budget"), "{}", stderr(&o));
    let o = run(&[
        "sweep",
        "refine",
        "--db",
        d,
        "--budget",
        "2",
        "--resolution",
        "1.5",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("--resolution: = 1.5 is out of range"),
        "{}",
        stderr(&o)
    );
    run_ok(&[
        "sweep", "refine", "--db", d, "--budget", "3", "--rounds", "1", "--jobs", "2",
    ]);
    assert_eq!(rows(&db).len(), 9);

    // Each boundary point lies in the interval spanned by its edge, half of which is its
    // uncertainty (decades on the log E* axis); every replica agrees here (one each). These
    // runs are too short for their regions to settle: the boundaries are drawn on every point.
    let o = run(&[
        "boundaries",
        "--db",
        d,
        "--format",
        "json",
        "--include-unconverged",
    ]);
    assert!(o.status.success());
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    let slice = &v[0]["map"]["slices"][0];
    let pts = slice["points"].as_array().unwrap();
    let mut n = 0;
    for list in slice["boundaries"].as_object().unwrap().values() {
        for b in list.as_array().unwrap() {
            let f = |k: &str| b[k].as_f64().unwrap();
            let [i, j] = [0, 1].map(|k| b["between"][k].as_u64().unwrap() as usize);
            let (xi, xj) = (pts[i]["x"].as_f64().unwrap(), pts[j]["x"].as_f64().unwrap());
            let (yi, yj) = (pts[i]["y"].as_f64().unwrap(), pts[j]["y"].as_f64().unwrap());
            assert_eq!(f("confidence"), 1.0);
            assert_eq!(b["x_range"][0].as_f64().unwrap(), xi.min(xj));
            assert_eq!(b["x_range"][1].as_f64().unwrap(), xi.max(xj));
            assert!((f("x_half") - 0.5 * (xi / xj).log10().abs()).abs() < 1e-12);
            assert!((f("y_half") - 0.5 * (yi - yj).abs()).abs() < 1e-12);
            n += 1;
        }
    }
    assert!(n > 0, "no boundary in {slice}");
    let csv = stdout(&run(&["boundaries", "--db", d, "--format", "csv"]));
    assert!(csv.starts_with(
        "sweep,slice,kind,phase,x_axis,x,y_axis,y,amplitude,omega,x_lo,x_hi,y_lo,y_hi,confidence,branch,\
         decided_by\n"
    ));
}

#[test]
fn a_point_whose_replicas_disagree_gets_more_replicas_through_the_store() {
    // Synthetic phases (no simulation): gas at E* = 2 except replica 1 of (Gamma 2, E* 2).
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "tiny.toml", TINY_SCENE);
    let file = write(
        dir.path(),
        "noisy.toml",
        "[sweep]\nname = \"n\"\nbase = \"tiny.toml\"\nreplicas = 2\nperiods = 60\n\
         [[axis]]\nkey = \"gamma\"\nvalues = [2.0, 3.0]\n\
         [[axis]]\nkey = \"e_star\"\nvalues = [1.0, 2.0]\n",
    );
    let sweep = SweepFile::load(&file).unwrap();
    let store = Store::open(&dir.path().join("n.sqlite")).unwrap();
    let row = store
        .register_sweep(&sweep, &sweep.expand().unwrap())
        .unwrap();
    let phase = |c: &[serde_json::Value], r: i64| {
        let (g, e) = (c[0].as_f64().unwrap(), c[1].as_f64().unwrap());
        Some(
            if e < 1.5 || (g == 2.0 && r == 1) {
                "f"
            } else {
                "g"
            }
            .to_string(),
        )
    };
    assert_eq!(finish_synthetic(&store, row.id, phase), 8);
    let settings = Settings {
        replicas: 2,
        max_replicas: 4,
        resolution: 0.0,
    };
    // Replicas come first: a budget of 2 buys the two next replicas of point 1 (Gamma 2, E* 2).
    let round = plan_jobs(
        &sweep,
        &row,
        &store.point_summaries(&row).unwrap(),
        2,
        &settings,
    )
    .unwrap();
    let got: Vec<(usize, u32, u64)> = round
        .iter()
        .map(|j| (j.point, j.replica, j.spec.scene.initial.seed))
        .collect();
    assert_eq!(got, vec![(1, 2, 9), (1, 3, 10)]);
    assert_eq!(
        round[0].coords,
        vec![serde_json::json!(2.0), serde_json::json!(2.0)]
    );
    store.add_jobs(row.id, &round).unwrap();
    assert_eq!(finish_synthetic(&store, row.id, phase), 2);
    // At max_replicas the majority (g, 3 of 4) stands: only new points now, each with 2
    // replicas, numbered from REFINED_FROM, between the grid points.
    let stored = store.point_summaries(&row).unwrap();
    assert_eq!(refined_jobs(&stored, 2), 2);
    let round = plan_jobs(&sweep, &row, &stored, 100, &settings).unwrap();
    assert!(!round.is_empty());
    for (k, j) in round.iter().enumerate() {
        assert_eq!(j.point as i64, REFINED_FROM + (k / 2) as i64, "{j:?}");
        assert_eq!(j.replica as usize, k % 2);
        let (g, e) = (j.coords[0].as_f64().unwrap(), j.coords[1].as_f64().unwrap());
        assert!(
            (2.0..=3.0).contains(&g) && (1.0..=2.0).contains(&e),
            "{j:?}"
        );
    }
}

#[test]
fn new_points_on_an_integer_axis_are_whole_numbers() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "tiny.toml", TINY_SCENE);
    let file = write(
        dir.path(),
        "count.toml",
        "[sweep]\nname = \"c\"\nbase = \"tiny.toml\"\nperiods = 60\n\
         [[axis]]\nkey = \"particles.count\"\nvalues = [20, 25]\n\
         [[axis]]\nkey = \"gamma\"\nvalues = [2.0, 3.0]\n",
    );
    let sweep = SweepFile::load(&file).unwrap();
    let store = Store::open(&dir.path().join("c.sqlite")).unwrap();
    let row = store
        .register_sweep(&sweep, &sweep.expand().unwrap())
        .unwrap();
    // The phase changes between 20 and 25 particles.
    let phase = |c: &[serde_json::Value], _: i64| {
        Some(
            if c[0].as_i64().unwrap() < 22 {
                "f"
            } else {
                "g"
            }
            .to_string(),
        )
    };
    finish_synthetic(&store, row.id, phase);
    let settings = Settings {
        replicas: 1,
        max_replicas: 1,
        resolution: 0.0,
    };
    let mut counts = Vec::new();
    for _ in 0..4 {
        let stored = store.point_summaries(&row).unwrap();
        let round = plan_jobs(&sweep, &row, &stored, 2, &settings).unwrap();
        for j in &round {
            let n = j.coords[0]
                .as_i64()
                .unwrap_or_else(|| panic!("{:?}", j.coords));
            assert_eq!(j.spec.scene.particles.count as i64, n);
            counts.push(n);
        }
        store.add_jobs(row.id, &round).unwrap();
        finish_synthetic(&store, row.id, phase);
    }
    // Bisection on whole numbers down to 21 | 22, and no point twice.
    assert!(counts.contains(&21) && counts.contains(&22), "{counts:?}");
    let stored = store.point_summaries(&row).unwrap();
    let mut coords: Vec<String> = stored
        .iter()
        .map(|p| serde_json::to_string(&p.coords).unwrap())
        .collect();
    let n = coords.len();
    coords.sort();
    coords.dedup();
    assert_eq!(coords.len(), n);
}
