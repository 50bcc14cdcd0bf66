//! `wetgran sweep estimate`: sampled rates, stored results counted at their measured cost,
//! and the wall time replayed in the runner's claim order.

mod sweep_common;

use std::process::Output;
use sweep_common::*;
use wetgran::report::sweep_text::duration_text;
use wetgran::store::Store;

fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

const LINE: &str = "[sweep]\nname = \"line\"\nbase = \"tiny.toml\"\nperiods = 6\n\
                    [convergence]\nmax_periods = 24\n\
                    [[axis]]\nkey = \"gamma\"\nvalues = [3.0]\n\
                    [[axis]]\nkey = \"e_star\"\nlog = { from = 0.3, to = 10.0, steps = 4 }\n";

#[test]
fn stored_jobs_count_at_their_measured_cost() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "tiny.toml", TINY_SCENE);
    let sweep = write(dir.path(), "line.toml", LINE);
    let sweep_s = sweep.to_str().unwrap();
    let db = dir.path().join("w.sqlite");
    let db_s = db.to_str().unwrap();

    // Before any run: sampled rates only, the minimum and the cap.
    let est = wetgran()
        .args([
            "sweep",
            "estimate",
            sweep_s,
            "--samples",
            "2",
            "--periods",
            "1",
        ])
        .args(["--settle", "0", "--cores", "1"])
        .output()
        .unwrap();
    let out = text(&est);
    assert!(est.status.success(), "{out}");
    assert!(
        out.contains("4 job(s); sampling 2 for 1 driving period(s) each from the initial state"),
        "{out}"
    );
    assert!(
        out.contains("minimum (every job stationary at its first check)"),
        "{out}"
    );
    assert!(out.contains("cap (every job run to its cap)"), "{out}");
    assert!(
        !out.contains("likely"),
        "no stored runs, no likely figure: {out}"
    );
    assert!(!out.contains("stored:"), "{out}");

    let run = wetgran()
        .args(["sweep", "run", sweep_s, "--db", db_s, "--jobs", "1"])
        .output()
        .unwrap();
    assert!(run.status.success(), "{}", text(&run));
    let stored = Store::open_existing(&db)
        .unwrap()
        .finished_job_costs()
        .unwrap();
    assert_eq!(stored.len(), 4);
    let sum: f64 = stored.values().map(|c| c.wall_seconds).sum();

    // Every job stored: each counts what it cost, in every scenario; on one worker the wall
    // time is that sum, and nothing is left to run. No job is sampled again.
    let est = wetgran()
        .args(["sweep", "estimate", sweep_s, "--db", db_s, "--samples", "2"])
        .args(["--periods", "1", "--settle", "0", "--cores", "1"])
        .output()
        .unwrap();
    let out = text(&est);
    assert!(est.status.success(), "{out}");
    assert!(
        out.contains("stored: 4 of the 4 jobs finished in the database"),
        "{out}"
    );
    assert_eq!(
        out.matches("stored: ").count(),
        3,
        "two sampled lines and the summary: {out}"
    );
    assert!(out.contains("likely (the stored runs'"), "{out}");
    // The sum of the jobs' wall times is job time, not CPU (a job may run on several threads;
    // issue 45): the line says so.
    assert!(!out.contains("CPU"), "{out}");
    let expected = format!(
        "{} of job time (the jobs' wall times summed), {} wall",
        duration_text(sum),
        duration_text(sum)
    );
    assert_eq!(
        out.matches(&expected).count(),
        3,
        "{expected} in each scenario: {out}"
    );
    assert_eq!(out.matches("left: 0.0 s wall").count(), 3, "{out}");
}

#[test]
fn bad_options_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "tiny.toml", TINY_SCENE);
    let sweep = write(dir.path(), "line.toml", LINE);
    for (flag, value, says) in [
        ("--settle", "-1", "--settle must be >= 0"),
        ("--periods", "0", "--periods must be > 0"),
        ("--cores", "0", "--cores 0 is out of range"),
    ] {
        let o = wetgran()
            .args(["sweep", "estimate", sweep.to_str().unwrap()])
            .arg(format!("{flag}={value}"))
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(2), "{flag} {value}: {}", text(&o));
        assert!(text(&o).contains(says), "{}", text(&o));
    }
    let o = wetgran()
        .args(["sweep", "estimate", sweep.to_str().unwrap(), "--db"])
        .arg(dir.path().join("missing.sqlite"))
        .output()
        .unwrap();
    assert_ne!(o.status.code(), Some(0), "{}", text(&o));
}

#[test]
fn every_start_mode_is_sampled_and_priced() {
    // Two points x (hot, cold): one sample would once have been the middle job (a hot one);
    // now each start mode gets one and the CPU time is split by start.
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "tiny.toml", TINY_SCENE);
    let sweep = write(
        dir.path(),
        "both.toml",
        "[sweep]\nname = \"both\"\nbase = \"tiny.toml\"\nperiods = 6\n\
         [[axis]]\nkey = \"gamma\"\nvalues = [3.0]\n\
         [[axis]]\nkey = \"e_star\"\nvalues = [0.3, 10.0]\n\
         [[axis]]\nkey = \"initial.start\"\nvalues = [\"hot\", \"cold\"]\n",
    );
    let est = wetgran()
        .args(["sweep", "estimate", sweep.to_str().unwrap()])
        .args([
            "--samples",
            "1",
            "--periods",
            "1",
            "--settle",
            "0",
            "--cores",
            "1",
        ])
        .output()
        .unwrap();
    let out = text(&est);
    assert!(est.status.success(), "{out}");
    assert!(out.contains("4 job(s); sampling 2"), "{out}");
    assert!(out.contains("initial.start = \"hot\""), "{out}");
    assert!(out.contains("initial.start = \"cold\""), "{out}");
    assert!(
        out.contains("by start: hot start 2 job(s)") && out.contains("cold start 2 job(s)"),
        "{out}"
    );
}

#[test]
fn a_chain_head_that_is_the_hot_job_counts_once() {
    // Hot start and continuation down in E* over two points: the chain's head (E* = 10,
    // "continue") runs hot, the same job as the hot one there: 3 jobs, as the store has them.
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "tiny.toml", TINY_SCENE);
    let sweep = write(
        dir.path(),
        "chain.toml",
        "[sweep]\nname = \"chain\"\nbase = \"tiny.toml\"\nperiods = 6\n\
         [sweep.continuation]\naxis = \"e_star\"\ndirection = \"descending\"\n\
         [[axis]]\nkey = \"gamma\"\nvalues = [3.0]\n\
         [[axis]]\nkey = \"e_star\"\nvalues = [0.3, 10.0]\n\
         [[axis]]\nkey = \"initial.start\"\nvalues = [\"hot\", \"continue\"]\n",
    );
    let est = wetgran()
        .args(["sweep", "estimate", sweep.to_str().unwrap()])
        .args([
            "--samples",
            "2",
            "--periods",
            "1",
            "--settle",
            "0",
            "--cores",
            "1",
        ])
        .output()
        .unwrap();
    let out = text(&est);
    assert!(est.status.success(), "{out}");
    assert!(out.contains("3 job(s); sampling 2"), "{out}");
    assert!(
        out.contains("by start: hot start 2 job(s)") && out.contains("continuation 1 job(s)"),
        "{out}"
    );
}

/// A transient and a sample spacing in time units longer than the timed stretch (the shipped
/// 3D sweeps: 10 time units and 0.25 against one period of a fraction of a unit) are the job's,
/// not the estimate's: every sampled job still yields a rate.
#[test]
fn a_transient_in_time_units_longer_than_the_timed_stretch_is_not_the_estimates() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "tiny.toml", TINY_SCENE);
    let sweep = write(
        dir.path(),
        "line.toml",
        &LINE.replace(
            "[convergence]",
            "[observe]\ntransient_time = 10.0\nmin_sample_interval = 1.0\n[convergence]\nmin_time = 20.0",
        ),
    );
    let est = wetgran()
        .args(["sweep", "estimate", sweep.to_str().unwrap()])
        .args(["--samples", "2", "--periods", "1", "--settle", "0"])
        .args(["--cores", "1"])
        .output()
        .unwrap();
    let out = text(&est);
    assert!(est.status.success(), "{out}");
    assert!(!out.contains("failed"), "{out}");
    assert!(out.contains("s per time unit"), "{out}");
}
