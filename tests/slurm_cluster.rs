//! A sweep on a real Slurm: submitted as job arrays to the single-node cluster of
//! `scripts/slurm-local.sh` (started by `.ci/run`, or by this test when it runs as root and no
//! controller answers), collected, resubmitted after failed and missing tasks, and compared with
//! a local `sweep run` of the same sweep: the same jobs give the same numbers.
//!
//! Skips, with a message saying why, only where the machine cannot run a cluster: no Slurm
//! controller answers and either this is not root or the packages cannot be installed. Under
//! `CI=true` (where `.ci/run` starts the cluster) that is a failure instead.

mod slurm_common;
mod sweep_common;

use slurm_common::{slurm, wait_for};
use std::collections::HashMap;
use std::path::Path;
use std::time::{Duration, Instant};
use sweep_common::*;
use wetgran::store::{PointRow, Store, TaskState};

fn ok(o: &std::process::Output) -> String {
    assert!(o.status.success(), "{}\n{}", stdout(o), stderr(o));
    format!("{}{}", stdout(o), stderr(o))
}

/// The output of a `sweep collect` that found failed or lost jobs (exit status 4).
fn partial(o: &std::process::Output) -> String {
    assert_eq!(o.status.code(), Some(4), "{}\n{}", stdout(o), stderr(o));
    format!("{}{}", stdout(o), stderr(o))
}

/// The numbers of a stored job that must not depend on where it ran.
fn numbers(
    p: &PointRow,
) -> (
    String,
    Option<String>,
    String,
    String,
    String,
    Option<String>,
) {
    (
        p.status.clone(),
        p.phase.clone(),
        format!("{:?}", p.observables),
        format!("{:?}", p.decided_on),
        format!("{:?} {:?}", p.simulated_time, p.events),
        p.last_error.clone(),
    )
}

/// `sweep status` shows the Slurm queue of the sweep `cl` (4 tasks in 2 arrays), each task in
/// a state Slurm or the collector names.
fn check_status_shows_queue(db_s: &str) {
    let status = stdout(&run(&["sweep", "status", "--db", db_s]));
    assert!(status.contains("sweep cl on Slurm"), "{status}");
    assert!(status.contains("4 task(s) in 2 array(s)"), "{status}");
    let queued = status
        .lines()
        .find_map(|l| l.trim().strip_prefix("not collected yet: "))
        .unwrap_or_else(|| panic!("{status}"));
    for part in queued.split(", ") {
        let state = part.split_once(' ').unwrap().1;
        assert!(
            [
                "PENDING",
                "RUNNING",
                "COMPLETING",
                "finished, not collected"
            ]
            .contains(&state),
            "{status}"
        );
    }
}

#[test]
fn a_sweep_submitted_to_slurm_equals_a_local_run() {
    let _slurm = match slurm() {
        Ok(s) => s,
        Err(why) => {
            skip_unless_ci("a_sweep_submitted_to_slurm_equals_a_local_run", &why);
            return;
        }
    };
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "tiny.toml", TINY_SCENE);
    // 2 x 2 jobs, well under a second each; run.max_events = 50 stops two of them before any
    // stationary sample: a numerical guard, failed tasks that write an error record.
    let sweep = write(
        dir.path(),
        "cl.toml",
        "[sweep]\nname = \"cl\"\nbase = \"tiny.toml\"\nperiods = 250\n\
         [[axis]]\nkey = \"gamma\"\nvalues = [2.0, 3.0]\n\
         [[axis]]\nkey = \"run.max_events\"\nvalues = [50, 100000000]\n",
    );
    let db = dir.path().join("cluster.sqlite");
    let (sweep_s, db_s) = (sweep.to_str().unwrap(), db.to_str().unwrap());

    // Submit with at most 3 tasks per array: 4 jobs make two arrays.
    let t0 = Instant::now();
    let out = ok(&run(&[
        "sweep",
        "submit",
        sweep_s,
        "--slurm",
        "--db",
        db_s,
        "--array-limit",
        "3",
        "--time",
        "5",
    ]));
    assert!(
        out.contains("4 job(s) submitted as 2 array(s) of at most 3 task(s)"),
        "{out}"
    );
    let store = Store::open_existing(&db).unwrap();
    let id = store.sweep("cl").unwrap().id;
    let tasks = store.tasks(id).unwrap();
    assert_eq!(tasks.len(), 4);
    let arrays: std::collections::BTreeSet<_> = tasks.iter().map(|t| t.slurm_job.clone()).collect();
    assert_eq!(arrays.len(), 2, "{tasks:?}");
    assert!(arrays.iter().all(Option::is_some));
    // The default sweep directory is beside the database.
    let sd = dir.path().join("wetgran-slurm/cl");
    assert!(tasks.iter().all(|t| Path::new(&t.dir) == sd));
    // Nothing is in the database's job rows before collection.
    assert_eq!(store.counts(id).unwrap().pending, 4);
    check_status_shows_queue(db_s);

    wait_for(&store, id, Duration::from_secs(120));
    let first_round = t0.elapsed().as_secs_f64();
    // One task's result is lost (as if it was killed before writing it).
    let lost = tasks
        .iter()
        .find(|t| {
            let r = sd.join("results").join(format!("{}.json", t.job_id));
            std::fs::read_to_string(&r).is_ok_and(|s| s.contains("\"done\""))
        })
        .expect("a successful task")
        .clone();
    std::fs::remove_file(sd.join("results").join(format!("{}.json", lost.job_id))).unwrap();
    let out = partial(&run(&["sweep", "collect", "--db", db_s]));
    assert!(out.contains("2 job(s) failed and 1 lost"), "{out}");
    assert!(
        out.contains("1 result(s) stored, 0 already stored (not stored twice), 2 failed, 0 corrupt, 1 missing"),
        "{out}"
    );
    assert_eq!(
        out.matches("no sample after the transient").count(),
        2,
        "{out}"
    );
    // Collecting again stores nothing more.
    let out = partial(&run(&["sweep", "collect", "--db", db_s]));
    assert!(out.contains("0 result(s) stored"), "{out}");
    assert!(out.contains("4 task(s) collected before"), "{out}");

    // Submitting again submits the failed and the missing jobs only.
    let out = ok(&run(&["sweep", "submit", sweep_s, "--slurm", "--db", db_s]));
    assert!(out.contains("3 job(s) submitted as 1 array(s)"), "{out}");
    wait_for(&store, id, Duration::from_secs(120));
    let out = partial(&run(&["sweep", "collect", "--db", db_s]));
    assert!(out.contains("1 result(s) stored"), "{out}");
    assert!(out.contains("2 failed"), "{out}");
    assert!(out.contains("2 job(s) failed and 0 lost"), "{out}");
    let c = store.counts(id).unwrap();
    assert_eq!((c.done, c.failed, c.pending), (2, 2, 0));
    let states: Vec<TaskState> = store.tasks(id).unwrap().iter().map(|t| t.state).collect();
    assert_eq!(states.len(), 7);
    assert!(!states.contains(&TaskState::Submitted));
    let cluster_secs = t0.elapsed().as_secs_f64();

    // The same sweep run locally: the same numbers for every job.
    let local = dir.path().join("local.sqlite");
    let out = run(&[
        "sweep",
        "run",
        sweep_s,
        "--db",
        local.to_str().unwrap(),
        "--jobs",
        "2",
    ]);
    // Two jobs fail here too: the run ends with exit status 4, everything else stored.
    assert_eq!(out.status.code(), Some(4), "{}", stderr(&out));
    let local = Store::open_existing(&local).unwrap();
    let lid = local.sweep("cl").unwrap().id;
    let here: HashMap<String, PointRow> = local
        .points(lid)
        .unwrap()
        .into_iter()
        .map(|p| (p.job_id.clone(), p))
        .collect();
    let there = store.points(id).unwrap();
    assert_eq!(there.len(), 4);
    for p in &there {
        let l = &here[&p.job_id];
        assert_eq!(numbers(p), numbers(l), "job {} differs", p.job_id);
        if p.status == "done" {
            assert!(p.result_owner.as_deref().unwrap().starts_with("slurm:"));
            assert!(p.observables.is_some());
        } else {
            // Failed twice on the cluster: two attempts.
            assert_eq!(p.attempts, 2);
        }
    }
    println!(
        "slurm sweep: first round (submit to all tasks finished) {first_round:.1} s, whole \
         cluster part {cluster_secs:.1} s"
    );
}
