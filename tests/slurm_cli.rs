//! The cluster commands without a cluster: `job run` (result and error records, exit status),
//! `sweep submit --dry-run`, and `sweep submit` against stand-in `sbatch`/`scontrol` programs on
//! the PATH (the split at the cluster's MaxArraySize, the recorded Slurm ids, a refused sbatch),
//! and without any Slurm program at all.

mod sweep_common;

use std::path::Path;
use std::process::Output;
use sweep_common::*;
use wetgran::cluster::{Outcome, ResultRecord};
use wetgran::store::Store;

/// 2 x 2 jobs of the tiny wet scene; `run.max_events = 50` makes two of them fail.
fn sweep(dir: &Path) -> std::path::PathBuf {
    write(dir, "tiny.toml", TINY_SCENE);
    write(
        dir,
        "cl.toml",
        "[sweep]\nname = \"cl\"\nbase = \"tiny.toml\"\nperiods = 250\n\
         [[axis]]\nkey = \"gamma\"\nvalues = [2.0, 3.0]\n\
         [[axis]]\nkey = \"run.max_events\"\nvalues = [50, 100000000]\n",
    )
}

/// A folder with executable stand-ins: `name` -> shell script body.
fn stand_ins(dir: &Path, programs: &[(&str, &str)]) -> std::path::PathBuf {
    let bin = dir.join("bin");
    std::fs::create_dir_all(&bin).unwrap();
    for (name, body) in programs {
        let p = bin.join(name);
        std::fs::write(&p, format!("#!/bin/sh\n{body}\n")).unwrap();
        let mut perm = std::fs::metadata(&p).unwrap().permissions();
        std::os::unix::fs::PermissionsExt::set_mode(&mut perm, 0o755);
        std::fs::set_permissions(&p, perm).unwrap();
    }
    bin
}

/// `wetgran ARGS DB` with only `path` on the PATH (stand-ins or no Slurm at all).
fn on_path(path: &Path, args: &[&str], db: &Path) -> Output {
    wetgran()
        .args(args)
        .arg(db)
        .env("PATH", path)
        .output()
        .unwrap()
}

/// `wetgran sweep submit SWEEP --slurm --db DB` with only `path` on the PATH.
fn submit_on_path(path: &Path, sweep: &Path, db: &Path) -> Output {
    on_path(
        path,
        &[
            "sweep",
            "submit",
            sweep.to_str().unwrap(),
            "--slurm",
            "--db",
        ],
        db,
    )
}

/// `wetgran sweep submit SWEEP --slurm --dry-run OPTIONS`.
fn dry_run(sweep: &Path, options: &[&str]) -> Output {
    let mut args = vec![
        "sweep",
        "submit",
        sweep.to_str().unwrap(),
        "--slurm",
        "--dry-run",
    ];
    args.extend_from_slice(options);
    run(&args)
}

/// `wetgran job run SPEC --out RESULT`.
fn job_run(spec: &Path, result: &Path) -> Output {
    run(&[
        "job",
        "run",
        spec.to_str().unwrap(),
        "--out",
        result.to_str().unwrap(),
    ])
}

/// Asserts that `text` (a command's output) contains `want`, printing it where not.
fn assert_has(text: &str, want: &str) {
    assert!(text.contains(want), "no `{want}` in:\n{text}");
}

#[test]
fn job_run_writes_a_result_or_an_error_record() {
    let dir = tempfile::tempdir().unwrap();
    let s = sweep(dir.path());
    let out = run(&["sweep", "expand", s.to_str().unwrap(), "--specs"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let lines: Vec<serde_json::Value> = stdout(&out)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(lines.len(), 4);
    // Point 0: max_events 50 (fails); point 1: a full run.
    for (k, want_code) in [(0, 1), (1, 0)] {
        let id = lines[k]["id"].as_str().unwrap();
        let spec = write(
            dir.path(),
            &format!("{id}.json"),
            &lines[k]["spec"].to_string(),
        );
        let res = dir.path().join(format!("r{k}.json"));
        let out = job_run(&spec, &res);
        assert_eq!(out.status.code(), Some(want_code), "{}", stderr(&out));
        let rec = ResultRecord::read(&res, id).unwrap().unwrap();
        match (&rec.outcome, want_code) {
            (Outcome::Failed(m), 1) => assert!(m.contains("no sample after the transient"), "{m}"),
            (Outcome::Done(r), 0) => {
                // The same numbers as `sweep job` (the local path) gives for this spec.
                let local = run(&["sweep", "job", spec.to_str().unwrap()]);
                let v: serde_json::Value = serde_json::from_str(&stdout(&local)).unwrap();
                assert_eq!(v["id"], id);
                assert_eq!(v["result"]["observables"], r.observables);
                assert_eq!(v["result"]["events"], r.events);
            }
            other => panic!("unexpected {other:?}"),
        }
    }
    // A spec that does not parse: exit 2, and an error record under the file's name.
    let bad = write(dir.path(), "deadbeef.json", "{\"format\": 1, \"scene\": ");
    let res = dir.path().join("bad.json");
    let out = job_run(&bad, &res);
    assert_eq!(out.status.code(), Some(2));
    let rec = ResultRecord::read(&res, "deadbeef").unwrap().unwrap();
    assert!(matches!(rec.outcome, Outcome::Failed(ref m) if m.contains("cannot be read")));
}

#[test]
fn a_dry_run_prints_the_arrays_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let s = sweep(dir.path());
    let db = dir.path().join("w.sqlite");
    let out = dry_run(
        &s,
        &[
            "--array-limit",
            "3",
            "--partition",
            "short",
            "--db",
            db.to_str().unwrap(),
        ],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let text = stdout(&out);
    assert!(text.contains("4 job(s) to submit as 2 array(s)"), "{text}");
    assert_eq!(text.matches("#!/bin/bash").count(), 2, "{text}");
    assert!(text.contains("#SBATCH --array=0-2\n"), "{text}");
    assert!(text.contains("#SBATCH --array=0-0\n"), "{text}");
    assert_eq!(text.matches("#SBATCH --partition=short\n").count(), 2);
    assert!(!db.exists(), "a dry run creates no database");
    assert!(!dir.path().join("wetgran-slurm").exists());
    // A value that cannot go on an #SBATCH line is refused as bad input.
    let out = dry_run(&s, &["--time", "1 day"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("--time `1 day`"), "{}", stderr(&out));
    // Without --slurm there is no backend to submit to.
    let out = run(&["sweep", "submit", s.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("--slurm"));
}

#[test]
fn submit_splits_at_max_array_size_and_records_the_slurm_ids() {
    let dir = tempfile::tempdir().unwrap();
    let s = sweep(dir.path());
    let db = dir.path().join("w.sqlite");
    // A cluster that takes arrays of 2 tasks and numbers its jobs from the script's task count.
    let bin = stand_ins(
        dir.path(),
        &[
            (
                "scontrol",
                "echo 'Configuration data'; echo 'MaxArraySize            = 2'",
            ),
            ("sbatch", "echo \"$$;test\""),
            ("squeue", "exit 0"),
        ],
    );
    let out = submit_on_path(&bin, &s, &db);
    assert!(out.status.success(), "{}", stderr(&out));
    assert_has(
        &stderr(&out),
        "4 job(s) submitted as 2 array(s) of at most 2 task(s)",
    );
    let store = Store::open_existing(&db).unwrap();
    let id = store.sweep("cl").unwrap().id;
    let tasks = store.tasks(id).unwrap();
    assert_eq!(tasks.len(), 4);
    let ids: Vec<String> = tasks.iter().map(|t| t.slurm_job.clone().unwrap()).collect();
    // The id sbatch printed (before the `;cluster`), one per array.
    assert!(ids.iter().all(|j| j.parse::<u32>().is_ok()), "{ids:?}");
    assert_eq!(ids[0], ids[1]);
    assert_eq!(ids[2], ids[3]);
    assert_ne!(ids[0], ids[2]);
    // The task lists name the four jobs, each once, and the specs are there.
    let sd = dir.path().join("wetgran-slurm/cl");
    let mut listed: Vec<String> = ["array-0001.tasks", "array-0002.tasks"]
        .iter()
        .flat_map(|f| {
            std::fs::read_to_string(sd.join("arrays").join(f))
                .unwrap()
                .lines()
                .map(str::to_string)
                .collect::<Vec<_>>()
        })
        .collect();
    for t in &tasks {
        assert!(sd.join("specs").join(format!("{}.json", t.job_id)).exists());
    }
    listed.sort();
    let mut want: Vec<String> = tasks.iter().map(|t| t.job_id.clone()).collect();
    want.sort();
    assert_eq!(listed, want);
    // Tasks still in the queue are no failure: a collect stores nothing and exits with 0.
    std::fs::write(
        bin.join("squeue"),
        "#!/bin/sh\nfor t in 0 1; do echo \"${6}_$t PENDING\"; done\n",
    )
    .unwrap();
    let out = on_path(&bin, &["sweep", "collect", "--db"], &db);
    assert!(out.status.success(), "{}", stderr(&out));
    assert_has(&stdout(&out), "0 failed, 0 corrupt, 0 missing");
    std::fs::write(bin.join("squeue"), "#!/bin/sh\nexit 0\n").unwrap();
    // One task wrote an error record; the queue (empty) no longer has the others and no result
    // came: submitting again collects 1 failed and 3 missing and submits all four again.
    let failed = sd.join("results").join(format!("{}.json", tasks[0].job_id));
    ResultRecord::new(&tasks[0].job_id, Outcome::Failed("boom".to_string()), 0.1)
        .write(&failed)
        .unwrap();
    let out = submit_on_path(&bin, &s, &db);
    assert!(out.status.success(), "{}", stderr(&out));
    assert_has(&stderr(&out), "1 failed, 0 corrupt, 3 missing");
    assert_has(&stderr(&out), "4 job(s) submitted");
    assert_eq!(store.tasks(id).unwrap().len(), 8);
    // The old error record is gone, so it cannot pass for the new task's outcome: a collect
    // now finds the new tasks missing (the stand-in ran nothing), none failed.
    assert!(!failed.exists());
    let out = on_path(&bin, &["sweep", "collect", "--db"], &db);
    assert_has(&stdout(&out), "0 failed, 0 corrupt, 4 missing");
    // Lost tasks make a partial diagram: exit status 4, as `sweep run` with failed jobs.
    assert_eq!(out.status.code(), Some(4), "{}", stderr(&out));
    assert_has(&stderr(&out), "4 lost");
}

#[test]
fn submit_without_slurm_fails_cleanly() {
    let dir = tempfile::tempdir().unwrap();
    let s = sweep(dir.path());
    let db = dir.path().join("w.sqlite");
    let empty = dir.path().join("nothing");
    std::fs::create_dir_all(&empty).unwrap();
    let out = submit_on_path(&empty, &s, &db);
    assert_eq!(out.status.code(), Some(1));
    assert_has(&stderr(&out), "cannot run sbatch");
    // No submission is on record; the jobs are registered and pending.
    let store = Store::open_existing(&db).unwrap();
    let id = store.sweep("cl").unwrap().id;
    assert!(store.tasks(id).unwrap().is_empty());
    assert_eq!(store.counts(id).unwrap().pending, 4);
    // A refusing sbatch is reported with its message.
    let bin = stand_ins(
        dir.path(),
        &[(
            "sbatch",
            "echo 'sbatch: error: invalid partition' >&2; exit 1",
        )],
    );
    let out = submit_on_path(&bin, &s, &db);
    assert_eq!(out.status.code(), Some(1));
    assert_has(&stderr(&out), "invalid partition");
    assert!(store.tasks(id).unwrap().is_empty());
}
