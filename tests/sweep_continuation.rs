//! Continuation sweeps (`[sweep.continuation]`): chains along one axis, each point starting
//! from its neighbour's final state carried into its own container; the runner's ordering, the
//! failure of a chain whose head failed, the refusal of Slurm arrays, and hysteresis between a
//! hot and a continued start.

mod sweep_common;

use std::path::Path;
use sweep_common::*;
use wetgran::store::Store;
use wetgran::sweep::{SweepFile, run_job_from};
use wetgran_core::scene::StartMode;

/// A tiny wet shaken sweep over E* (3 values) and Gamma (2 values), continued along E*.
fn sweep_text(continuation: &str, extra_axis: &str) -> String {
    format!(
        "[sweep]\nname = \"cont\"\nbase = \"tiny.toml\"\nperiods = 3\n{continuation}\n\
         [observe]\ntransient_periods = 1.0\nmobility_lag = 0.5\n\
         [[axis]]\nkey = \"gamma\"\nvalues = [3.0, 4.0]\n\
         [[axis]]\nkey = \"e_star\"\nvalues = [1.0, 2.0, 1.5]\n{extra_axis}"
    )
}

/// The continued tiny sweep written into `dir`: its file and a database path beside it.
fn continued_sweep(dir: &Path) -> (std::path::PathBuf, std::path::PathBuf) {
    write(dir, "tiny.toml", TINY_SCENE);
    let sweep = write(
        dir,
        "cont.toml",
        &sweep_text("[sweep.continuation]\naxis = \"e_star\"", ""),
    );
    (sweep, dir.join("w.sqlite"))
}

fn parse(dir: &Path, text: &str) -> Result<SweepFile, String> {
    write(dir, "tiny.toml", TINY_SCENE);
    let p = write(dir, "cont.toml", text);
    SweepFile::load(&p).map_err(|e| e.to_string())
}

#[test]
fn chains_link_each_point_to_its_neighbour_along_the_axis() {
    let dir = tempfile::tempdir().unwrap();
    for (direction, order) in [("", [1.0, 1.5, 2.0]), ("descending", [2.0, 1.5, 1.0])] {
        let c = if direction.is_empty() {
            "[sweep.continuation]\naxis = \"e_star\"".to_string()
        } else {
            format!("[sweep.continuation]\naxis = \"e_star\"\ndirection = \"{direction}\"")
        };
        let jobs = parse(dir.path(), &sweep_text(&c, ""))
            .unwrap()
            .expand()
            .unwrap();
        assert_eq!(jobs.len(), 6);
        for gamma in [3.0, 4.0] {
            let chain: Vec<_> = order
                .iter()
                .map(|e| {
                    jobs.iter()
                        .find(|j| j.coords[0] == gamma && j.coords[1] == *e)
                        .unwrap()
                })
                .collect();
            // The head starts hot (the default `first`), the others from their predecessor.
            assert_eq!(chain[0].spec.scene.initial.start, StartMode::Hot);
            assert_eq!(chain[0].spec.start_from, None);
            for w in chain.windows(2) {
                assert_eq!(w[1].spec.scene.initial.start, StartMode::Continue);
                assert_eq!(w[1].spec.start_from.as_deref(), Some(w[0].id.as_str()));
                // The id covers the predecessor: it is the hash of the spec as linked.
                assert_eq!(w[1].id, w[1].spec.id());
            }
        }
    }
    // Without the table the same grid has no links, and its ids differ from the chained ones.
    let plain = parse(dir.path(), &sweep_text("", ""))
        .unwrap()
        .expand()
        .unwrap();
    assert!(plain.iter().all(|j| j.spec.start_from.is_none()));
    // `first = "cold"`: the heads start cold.
    let cold = parse(
        dir.path(),
        &sweep_text(
            "[sweep.continuation]\naxis = \"e_star\"\nfirst = \"cold\"",
            "",
        ),
    )
    .unwrap()
    .expand()
    .unwrap();
    let heads: Vec<_> = cold
        .iter()
        .filter(|j| j.spec.start_from.is_none())
        .collect();
    assert_eq!(heads.len(), 2);
    assert!(
        heads
            .iter()
            .all(|j| j.spec.scene.initial.start == StartMode::Cold)
    );
}

#[test]
fn a_bad_continuation_table_is_an_error_naming_the_key() {
    let dir = tempfile::tempdir().unwrap();
    for (table, key, needle) in [
        (
            "[sweep.continuation]\naxis = \"omega\"",
            "sweep.continuation.axis",
            "not an axis of this sweep",
        ),
        (
            "[sweep.continuation]\naxis = \"e_star\"\ndirection = \"up\"",
            "sweep.continuation.direction",
            "\"ascending\" or \"descending\"",
        ),
        (
            "[sweep.continuation]\naxis = \"e_star\"\nfirst = \"warm\"",
            "sweep.continuation.first",
            "\"hot\" or \"cold\"",
        ),
    ] {
        let e = parse(dir.path(), &sweep_text(table, "")).unwrap_err();
        assert!(
            e.contains(key) && e.contains(needle) && e.contains("cont.toml:"),
            "{e}"
        );
    }
    // "continue" without the table.
    let e = parse(
        dir.path(),
        &sweep_text(
            "",
            "[[axis]]\nkey = \"initial.start\"\nvalues = [\"hot\", \"continue\"]\n",
        ),
    )
    .unwrap()
    .expand()
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("initial.start") && e.contains("[sweep.continuation]"),
        "{e}"
    );
    // An axis that changes the particles cannot be continued along.
    let text = "[sweep]\nname = \"n\"\nbase = \"tiny.toml\"\n[sweep.continuation]\naxis = \"particles.count\"\n\
                [[axis]]\nkey = \"particles.count\"\nvalues = [30, 40]\n";
    let e = parse(dir.path(), text)
        .unwrap()
        .expand()
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("sweep.continuation.axis") && e.contains("cannot be continued"),
        "{e}"
    );
}

#[test]
fn a_continued_sweep_runs_each_point_from_its_neighbours_final_state() {
    let dir = tempfile::tempdir().unwrap();
    let (sweep, db) = continued_sweep(dir.path());
    let (sweep_s, db_s) = (sweep.to_str().unwrap(), db.to_str().unwrap());
    // `sweep expand` names each continued job's predecessor.
    let o = run(&["sweep", "expand", sweep_s]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(
        stdout(&o).matches("\"continues\"").count(),
        4,
        "{}",
        stdout(&o)
    );
    let o = run(&["sweep", "run", sweep_s, "--db", db_s, "--jobs", "2"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let store = Store::open_existing(&db).unwrap();
    let s = store.sweep("cont").unwrap();
    let points = store.points(s.id).unwrap();
    assert_eq!(points.len(), 6);
    assert!(points.iter().all(|p| p.status == "done"), "{points:?}");
    // Every continued job ran from its predecessor's stored final state: running it again from
    // that state gives the stored numbers exactly (same spec and state, same numbers).
    let continued: Vec<_> = points
        .iter()
        .filter(|p| p.spec.start_from.is_some())
        .collect();
    assert_eq!(continued.len(), 4);
    for p in continued {
        let prev = p.spec.start_from.as_deref().unwrap();
        let prev_spec = store.job_spec(prev).unwrap().unwrap();
        let state = store
            .checkpoint(prev)
            .unwrap()
            .expect("the predecessor's final state")
            .continued(&prev_spec.scene);
        let again = run_job_from(
            &p.spec,
            &state,
            &wetgran_core::sim::RunSettings::every_sample(),
            &mut |_| {},
        )
        .unwrap();
        assert_eq!(Some(again.events as i64), p.events);
        assert_eq!(Some(&again.observables), p.observables.as_ref());
        // And not from a hot start: the stored run differs from one.
        let hot = wetgran::sweep::run_job(
            &wetgran::sweep::JobSpec {
                start_from: None,
                scene: {
                    let mut sc = p.spec.scene.clone();
                    sc.initial.start = StartMode::Hot;
                    sc
                },
                ..p.spec.clone()
            },
            &wetgran_core::sim::RunSettings::every_sample(),
            &mut |_| {},
        )
        .unwrap();
        assert_ne!(Some(hot.events as i64), p.events);
    }
}

#[test]
fn a_chain_whose_head_failed_fails_with_the_reason() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "tiny.toml", TINY_SCENE);
    let text = "[sweep]\nname = \"c1\"\nbase = \"tiny.toml\"\nperiods = 2\n\
                [sweep.continuation]\naxis = \"e_star\"\n[observe]\ntransient_periods = 1.0\n\
                [[axis]]\nkey = \"e_star\"\nvalues = [1.0, 2.0]\n";
    let sweep = write(dir.path(), "c1.toml", text);
    let db = dir.path().join("w.sqlite");
    let db_s = db.to_str().unwrap();
    {
        let store = Store::open(&db).unwrap();
        let file = SweepFile::load(&sweep).unwrap();
        let s = store
            .register_sweep(&file, &file.expand().unwrap())
            .unwrap();
        // The only claimable job is the head: its successor waits for it.
        let head = store.claim(&[s.id]).unwrap().unwrap();
        assert_eq!(head.spec.start_from, None);
        assert!(store.claim(&[s.id]).unwrap().is_none());
        store.fail(&head, "injected failure", 0.0).unwrap();
    }
    let o = run(&["sweep", "resume", "c1", "--db", db_s, "--jobs", "1"]);
    let err = both(&o);
    assert!(err.contains("has no final state"), "{err}");
    let store = Store::open_existing(&db).unwrap();
    let s = store.sweep("c1").unwrap();
    let points = store.points(s.id).unwrap();
    assert!(points.iter().all(|p| p.status == "failed"), "{points:?}");
    // Retried, both run, head first.
    let o = run(&[
        "sweep",
        "resume",
        "c1",
        "--db",
        db_s,
        "--jobs",
        "2",
        "--retry-failed",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let points = store.points(s.id).unwrap();
    assert!(points.iter().all(|p| p.status == "done"), "{points:?}");
}

#[test]
fn slurm_arrays_refuse_a_continued_sweep() {
    let dir = tempfile::tempdir().unwrap();
    let (sweep, db) = continued_sweep(dir.path());
    let o = run(&[
        "sweep",
        "submit",
        sweep.to_str().unwrap(),
        "--slurm",
        "--db",
        db.to_str().unwrap(),
        "--dry-run",
    ]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("[sweep.continuation]"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn hot_and_continued_starts_are_compared_for_hysteresis() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "tiny.toml", TINY_SCENE);
    let text = "[sweep]\nname = \"hc\"\nbase = \"tiny.toml\"\nperiods = 2\n\
                [sweep.continuation]\naxis = \"e_star\"\n[observe]\ntransient_periods = 1.0\n\
                [[axis]]\nkey = \"e_star\"\nvalues = [1.0, 2.0]\n\
                [[axis]]\nkey = \"initial.start\"\nvalues = [\"hot\", \"continue\"]\n";
    let sweep = write(dir.path(), "hc.toml", text);
    let db = dir.path().join("w.sqlite");
    let (sweep_s, db_s) = (sweep.to_str().unwrap(), db.to_str().unwrap());
    let o = run(&["sweep", "run", sweep_s, "--db", db_s, "--jobs", "2"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let store = Store::open_existing(&db).unwrap();
    let s = store.sweep("hc").unwrap();
    let points = store.points(s.id).unwrap();
    // The chain's head at E* = 1 is the hot job itself (one job, two grid points).
    let at = |e: f64, start: &str| {
        points
            .iter()
            .find(|p| p.coords[0] == e && p.coords[1] == start)
            .unwrap()
    };
    assert_eq!(at(1.0, "hot").job_id, at(1.0, "continue").job_id);
    assert_ne!(at(2.0, "hot").job_id, at(2.0, "continue").job_id);
    let summaries = store.point_summaries(&s).unwrap();
    let groups = wetgran::store::hysteresis::by_start(&s.axes, &summaries);
    assert_eq!(groups.len(), 2);
    let g2 = groups.iter().find(|g| g.coords[0] == 2.0).unwrap();
    assert!(g2.compared(), "{g2:?}");
    // Whether they disagree is the physics; the flag must say exactly that.
    let hot = &g2.by_start[&StartMode::Hot];
    let cont = &g2.by_start[&StartMode::Continue];
    assert_eq!(g2.hysteretic, hot != cont);
    let o = run(&["sweep", "status", "--db", db_s]);
    assert!(stdout(&o).contains("point(s) hysteretic"), "{}", stdout(&o));
}

/// `EngineState::continued` moves the grains into the next container's frame: at the end of
/// the first run the floor sits at `-A` (three quarters of a period), so grains resting on it are
/// below the next run's floor at `t = 0` unless shifted by `A sin(omega t)`. The shifted state
/// keeps every grain's gap to floor and lid exactly, and the next drive (other E*) runs from it
/// with the engine's invariants intact and its energy ledger closed.
#[test]
fn a_continued_state_keeps_the_grains_in_the_container() {
    let first = wetgran_core::scene::Scene::from_toml_str(TINY_SCENE, "tiny").unwrap();
    let (a, w) = first.drive_motion().unwrap();
    let period = 2.0 * std::f64::consts::PI / w;
    let mut s1 = first.clone();
    s1.run.duration = 20.75 * period;
    let (run1, _) = wetgran_core::observe::run_observed_from(
        &s1,
        None,
        &wetgran_core::sim::RunSettings::every_sample(),
        &mut |_| {},
    );
    let end = run1.report.final_state.expect("a final state");
    let floor = a * (w * end.time).sin();
    assert!((floor + a).abs() < 1e-6 * a, "floor at {floor}, A = {a}");
    let cont = end.continued(&s1);
    let h = first.container.size[1];
    let mut lowest_raw = f64::INFINITY;
    for i in 0..end.len() {
        let (z0, z1, r) = (
            end.positions[2 * i + 1],
            cont.positions[2 * i + 1],
            end.radii[i],
        );
        assert_eq!(z1, z0 - floor);
        assert_eq!(cont.positions[2 * i], end.positions[2 * i]);
        assert!(
            z1 - r >= -1e-9 && z1 + r <= h + 1e-9,
            "grain {i} outside: {z1}"
        );
        lowest_raw = lowest_raw.min(z0 - r);
    }
    // Without the shift a grain would start below the next floor (the safeguard matters).
    assert!(lowest_raw < -0.5 * a, "lowest gap {lowest_raw}, A = {a}");
    assert_eq!((cont.time, cont.counts.total()), (0.0, 0));
    assert_eq!(cont.bridges, end.bridges);
    let mut s2 = first.clone();
    s2.drive.e_star = Some(1.0);
    s2.run.duration = 5.0 * period;
    let (run2, _) = wetgran_core::observe::run_observed_from(
        &s2,
        Some(&cont),
        &wetgran_core::sim::RunSettings::every_sample(),
        &mut |_| {},
    );
    assert_eq!(run2.report.invariant_violation, None);
    assert!(
        run2.report.energy_bookkeeping_error < 1e-6,
        "ledger error {}",
        run2.report.energy_bookkeeping_error
    );
}

/// A chain's next link is claimed before grid order: in a descending chain with a hot start
/// beside it, the head (the largest E*, last in grid order) goes first, and each continued job
/// as soon as its predecessor is done, so the serial chain is not left to the end.
#[test]
fn the_jobs_a_chain_waits_for_are_claimed_first() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "tiny.toml", TINY_SCENE);
    let text = "[sweep]\nname = \"order\"\nbase = \"tiny.toml\"\n\
                [sweep.continuation]\naxis = \"e_star\"\ndirection = \"descending\"\n\
                [[axis]]\nkey = \"e_star\"\nvalues = [1.0, 2.0, 3.0]\n\
                [[axis]]\nkey = \"initial.start\"\nvalues = [\"hot\", \"continue\"]\n";
    let path = write(dir.path(), "order.toml", text);
    let store = Store::open(&dir.path().join("w.sqlite")).unwrap();
    let file = SweepFile::load(&path).unwrap();
    let s = store
        .register_sweep(&file, &file.expand().unwrap())
        .unwrap();
    let e_star = |c: &wetgran::store::Claim| c.coords[0].as_f64().unwrap();
    let finish = |c: &wetgran::store::Claim| {
        let r = wetgran::sweep::JobResult {
            checkpoint: None,
            phase: Some("g".into()),
            decided_on: None,
            observables: serde_json::json!({}),
            simulated_time: 1.0,
            wall_seconds: 0.0,
            events: 1,
        };
        assert!(store.finish(c, &r).unwrap());
    };
    // The head at E* = 3 first (grid order would start with the hot job at E* = 1).
    let head = store.claim(&[s.id]).unwrap().unwrap();
    assert_eq!(e_star(&head), 3.0);
    assert_eq!(head.spec.start_from, None);
    finish(&head);
    // Then the continued E* = 2, which the continued E* = 1 waits for.
    let next = store.claim(&[s.id]).unwrap().unwrap();
    assert_eq!(
        (e_star(&next), next.coords[1].as_str()),
        (2.0, Some("continue"))
    );
    finish(&next);
    // Then grid order: the hot job at E* = 1.
    let third = store.claim(&[s.id]).unwrap().unwrap();
    assert_eq!(
        (e_star(&third), third.coords[1].as_str()),
        (1.0, Some("hot"))
    );
}
