//! Running sweeps for real, as child processes on a database file: kill -9 in the middle and
//! resume (every job ends with exactly one result, finished jobs are not recomputed), two
//! runners on one database (no job runs twice), failures recorded and retried.

mod sweep_common;

use std::path::Path;
use std::process::Stdio;
use sweep_common::*;
use wetgran::store::Store;

/// 2 x 3 x `replicas` jobs of a 40-disk wet shaken system, ~0.1-0.4 s each.
fn tiny_sweep(dir: &Path, name: &str, replicas: u32, extra_axis: &str) -> std::path::PathBuf {
    write(dir, "tiny.toml", TINY_SCENE);
    write(
        dir,
        &format!("{name}_sweep.toml"),
        &format!(
            "[sweep]\nname = \"{name}\"\nbase = \"tiny.toml\"\nreplicas = {replicas}\nperiods = 250\n\
             [[axis]]\nkey = \"gamma\"\nvalues = [2.0, 3.0, 4.0]\n\
             [[axis]]\nkey = \"e_star\"\nvalues = [1.0, 2.0]\n{extra_axis}"
        ),
    )
}

#[test]
fn a_sweep_killed_midway_resumes_without_recomputing_finished_jobs() {
    let dir = tempfile::tempdir().unwrap();
    let sweep = tiny_sweep(dir.path(), "tiny", 2, "");
    let db = dir.path().join("w.sqlite");
    let (sweep_s, db_s) = (sweep.to_str().unwrap(), db.to_str().unwrap());
    let (mut child, mut lines) =
        spawn_merged(wetgran().args(["sweep", "run", sweep_s, "--db", db_s, "--jobs", "1"]));
    // A "done" line is printed after its job was committed: kill -9 after the third.
    let mut done = 0;
    let mut seen = String::new();
    while done < 3 {
        let line = lines
            .next()
            .unwrap_or_else(|| panic!("the runner stopped early:\n{seen}"))
            .unwrap();
        seen += &line;
        seen.push('\n');
        if line.contains("] done ") {
            done += 1;
        }
    }
    // ... once the next job is claimed, so that a job is running at the kill.
    let t0 = std::time::Instant::now();
    loop {
        let store = Store::open_existing(&db).unwrap();
        let s = store.sweep("tiny").unwrap();
        if store.counts(s.id).unwrap().running == 1 {
            break;
        }
        assert!(
            t0.elapsed().as_secs() < 30,
            "no job claimed after the third"
        );
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
    child.kill().unwrap(); // SIGKILL
    child.wait().unwrap(); // reap it, so that its pid is gone
    drop(lines);

    let (before, running_at_kill) = {
        let store = Store::open_existing(&db).unwrap();
        let s = store.sweep("tiny").unwrap();
        let c = store.counts(s.id).unwrap();
        assert!(c.done >= 3 && c.done < 12, "killed midway: {c:?}");
        assert_eq!(c.running, 1, "one worker: {c:?}");
        (store.points(s.id).unwrap(), c.running)
    };

    let out = run(&["sweep", "resume", "--db", db_s, "--jobs", "1"]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert_eq!(running_at_kill, 1);
    assert!(
        stderr(&out).contains("re-queued 1 job(s) left running"),
        "{}",
        stderr(&out)
    );
    let store = Store::open_existing(&db).unwrap();
    let s = store.sweep("tiny").unwrap();
    let after = store.points(s.id).unwrap();
    assert_eq!(after.len(), 12);
    let runs: std::collections::BTreeMap<String, i64> =
        store.runs_per_job().unwrap().into_iter().collect();
    for (b, a) in before.iter().zip(&after) {
        assert_eq!(a.job_id, b.job_id);
        assert_eq!(a.status, "done", "{a:?}");
        assert!(a.finished_at.is_some() && a.observables.is_some());
        match b.status.as_str() {
            // Finished before the kill: the same result, committed once, run once.
            "done" => {
                assert_eq!(a.finished_at, b.finished_at);
                assert_eq!(a.result_owner, b.result_owner);
                assert_eq!((a.attempts, runs[&a.job_id]), (1, 1));
            }
            // Running at the kill: re-queued and run again by the resume.
            "running" => assert_eq!((a.attempts, runs[&a.job_id]), (2, 2)),
            _ => assert_eq!((a.attempts, runs[&a.job_id]), (1, 1)),
        }
    }
    // The resumed and the killed runner are different owners.
    let owners: std::collections::BTreeSet<_> = after
        .iter()
        .map(|p| p.result_owner.clone().unwrap())
        .collect();
    assert_eq!(owners.len(), 2);
    // Running the sweep again computes nothing.
    drop(store);
    let out = run(&["sweep", "run", sweep_s, "--db", db_s]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("12 finished before, 0 to run"),
        "{}",
        stderr(&out)
    );
    let store = Store::open_existing(&db).unwrap();
    let runs_again: std::collections::BTreeMap<String, i64> =
        store.runs_per_job().unwrap().into_iter().collect();
    assert_eq!(runs, runs_again);
}

#[test]
fn two_runners_on_one_database_never_run_a_job_twice() {
    let dir = tempfile::tempdir().unwrap();
    let sweep = tiny_sweep(dir.path(), "pair", 3, "");
    let db = dir.path().join("w.sqlite");
    let (sweep_s, db_s) = (sweep.to_str().unwrap(), db.to_str().unwrap());
    let spawn = || {
        wetgran()
            .args(["sweep", "run", sweep_s, "--db", db_s, "--jobs", "1"])
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap()
    };
    let (a, b) = (spawn(), spawn());
    let (a, b) = (a.wait_with_output().unwrap(), b.wait_with_output().unwrap());
    assert!(a.status.success(), "{}", stderr(&a));
    assert!(b.status.success(), "{}", stderr(&b));
    let store = Store::open_existing(&db).unwrap();
    let s = store.sweep("pair").unwrap();
    let points = store.points(s.id).unwrap();
    assert_eq!(points.len(), 18);
    assert!(points.iter().all(|p| p.status == "done" && p.attempts == 1));
    let runs = store.runs_per_job().unwrap();
    assert_eq!(runs.len(), 18);
    assert!(runs.iter().all(|(_, n)| *n == 1), "{runs:?}");
    // Both runners worked, and their "done" lines add up to the sweep.
    let owners: std::collections::BTreeSet<_> = points
        .iter()
        .map(|p| p.result_owner.clone().unwrap())
        .collect();
    assert_eq!(owners.len(), 2, "both runners took jobs");
    let lines = |o: &std::process::Output| stdout(o).matches("] done ").count();
    assert_eq!(lines(&a) + lines(&b), 18);
}

#[test]
fn a_failing_job_is_recorded_and_the_sweep_goes_on() {
    let dir = tempfile::tempdir().unwrap();
    // run.max_events = 50 stops that point's runs long before the transient (a quarter of the
    // run) is over: no stationary sample, a numerical guard, a failed job.
    let sweep = tiny_sweep(
        dir.path(),
        "fails",
        1,
        "[[axis]]\nkey = \"run.max_events\"\nvalues = [50, 100000000]\n",
    );
    let db = dir.path().join("w.sqlite");
    let (sweep_s, db_s) = (sweep.to_str().unwrap(), db.to_str().unwrap());
    let out = run(&[
        "sweep",
        "run",
        sweep_s,
        "--db",
        db_s,
        "--jobs",
        "2",
        "--oversubscribe",
    ]);
    // The sweep runs to its end, and the exit status says that some jobs failed.
    assert_eq!(out.status.code(), Some(4), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("error: 6 job(s) failed (the others are stored)"),
        "{}",
        stderr(&out)
    );
    assert_eq!(
        stdout(&out).matches("FAILED").count(),
        6,
        "{}",
        stderr(&out)
    );
    let status = stdout(&run(&["sweep", "status", "--db", db_s]));
    assert!(
        status.contains("12 total: 6 done, 0 running, 0 pending, 6 failed"),
        "{status}"
    );
    assert_eq!(
        status.matches("no sample after the transient").count(),
        6,
        "{status}"
    );
    assert!(status.contains("run.max_events = 50"), "{status}");
    // --retry-failed runs exactly the failed ones again (they fail again: attempts = 2).
    let out = run(&["sweep", "resume", "fails", "--db", db_s, "--retry-failed"]);
    assert_eq!(out.status.code(), Some(4), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("re-queued 6 failed job(s)"),
        "{}",
        stderr(&out)
    );
    let store = Store::open_existing(&db).unwrap();
    let s = store.sweep("fails").unwrap();
    for p in store.points(s.id).unwrap() {
        let failing = p.coords[2] == serde_json::json!(50);
        assert_eq!(p.status, if failing { "failed" } else { "done" });
        assert_eq!(p.attempts, if failing { 2 } else { 1 });
    }
}
