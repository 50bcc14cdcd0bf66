//! Under load, nothing lost (issue 35, item 4): two runners share one database of a few hundred
//! short jobs, one is killed with SIGKILL mid-way, the other goes on, and `sweep resume` picks
//! up what the killed one held. Checked against exact bookkeeping: every job ends done with
//! exactly one result, the results of each runner are exactly the jobs its `done` lines name,
//! and only a job running at the kill has a second run row (the first one closed as interrupted).

mod sweep_common;

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;
use std::process::Stdio;
use sweep_common::*;
use wetgran::store::Store;

/// Grid of the sweep: 12 x 20 = 240 jobs of 20 grains over 2 periods (~5-30 ms each), or
/// `N_GAMMA x N_E` from `WETGRAN_TWO_RUNNERS_GRID` (`100x100`: the figure of
/// docs/reliability.md, "Two runners, one killed").
fn grid() -> (usize, usize) {
    std::env::var("WETGRAN_TWO_RUNNERS_GRID")
        .ok()
        .and_then(|g| {
            let (a, b) = g.split_once('x')?;
            Some((a.trim().parse().ok()?, b.trim().parse().ok()?))
        })
        .unwrap_or((12, 20))
}

fn quick_sweep(dir: &Path) -> std::path::PathBuf {
    let (n_gamma, n_e) = grid();
    let scene = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/shaken_wet_2d.toml"),
    )
    .unwrap();
    write(dir, "shaken_wet_2d.toml", &scene);
    write(
        dir,
        "quick.toml",
        &format!(
            "[sweep]\nname = \"quick\"\nbase = \"shaken_wet_2d.toml\"\nperiods = 2\n\
             [scene]\nparticles.count = 20\nbox.size = [7.0, 9.0]\n\
             engine.min_rebound_speed = 0.03\n\
             [observe]\ntransient_periods = 1\nsamples_per_period = 20\n\
             [[axis]]\nkey = \"gamma\"\nlog = {{ from = 0.5, to = 20.0, steps = {n_gamma} }}\n\
             [[axis]]\nkey = \"e_star\"\nlog = {{ from = 0.3, to = 4.755, steps = {n_e} }}\n"
        ),
    )
}

/// The 12-character job ids of the `done` lines of a runner's standard error.
fn done_ids(text: &str) -> Vec<String> {
    text.lines()
        .filter(|l| l.contains("] done "))
        .filter_map(|l| {
            let at = l.rfind("(job ")?;
            Some(l[at + 5..at + 17].to_string())
        })
        .collect()
}

#[test]
fn two_runners_one_killed_midway_every_job_done_once_none_lost() {
    let dir = tempfile::tempdir().unwrap();
    let sweep = quick_sweep(dir.path());
    let db = dir.path().join("w.sqlite");
    let (sweep_s, db_s) = (sweep.to_str().unwrap(), db.to_str().unwrap());
    let total = grid().0 * grid().1;
    // A is killed after a sixth of the sweep's jobs, at least its 40th.
    let kill_after = (total / 6).max(40);
    let spawn = |args: &[&str]| {
        wetgran()
            .args(args)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap()
    };
    let run_args = ["sweep", "run", sweep_s, "--db", db_s, "--jobs", "1"];
    let (mut a, a_lines) = spawn_merged(wetgran().args(run_args));
    // B starts once A has registered the sweep (B registers it again, unchanged).
    let t0 = std::time::Instant::now();
    while Store::open_existing(&db)
        .ok()
        .and_then(|s| s.sweep("quick").ok())
        .is_none()
    {
        assert!(t0.elapsed().as_secs() < 60, "the sweep was not registered");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    let b = spawn(&run_args);

    // Kill A with SIGKILL after its `kill_after`-th committed job.
    let mut lines = a_lines;
    let mut a_text = String::new();
    let mut a_done = 0;
    while a_done < kill_after {
        let line = lines
            .next()
            .unwrap_or_else(|| panic!("runner A stopped early:\n{a_text}"))
            .unwrap();
        a_done += usize::from(!done_ids(&line).is_empty());
        a_text += &line;
        a_text.push('\n');
    }
    a.kill().unwrap();
    a.wait().unwrap();
    // What A printed before it died (its lines are written after each commit).
    for line in lines {
        match line {
            Ok(l) => {
                a_text += &l;
                a_text.push('\n');
            }
            Err(_) => break,
        }
    }
    let b = b.wait_with_output().unwrap();
    assert!(b.status.success(), "{}", stderr(&b));
    let b_text = both(&b);

    let store = Store::open_existing(&db).unwrap();
    let s = store.sweep("quick").unwrap();
    let c = store.counts(s.id).unwrap();
    assert!(c.running <= 1, "only A's job can be left running: {c:?}");
    assert_eq!(c.failed, 0, "{c:?}");
    let running_at_kill: Vec<String> = store
        .points(s.id)
        .unwrap()
        .into_iter()
        .filter(|p| p.status == "running")
        .map(|p| p.job_id)
        .collect();
    drop(store);
    let out = run(&["sweep", "resume", "--db", db_s, "--jobs", "1"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let r_text = both(&out);

    let store = Store::open_existing(&db).unwrap();
    let points = store.points(s.id).unwrap();
    assert_eq!(points.len(), total);
    for p in &points {
        assert_eq!(p.status, "done", "{p:?}");
        assert!(p.observables.is_some(), "{p:?}");
    }
    // Exactly one result per job: the three runners' done lines name every job once.
    let mut named: Vec<String> = Vec::new();
    for text in [&a_text, &b_text, &r_text] {
        named.extend(done_ids(text));
    }
    let named_set: BTreeSet<&String> = named.iter().collect();
    assert_eq!(named.len(), total, "done lines: {}", named.len());
    assert_eq!(named_set.len(), total, "a job named done twice");
    let ids: BTreeSet<String> = points.iter().map(|p| p.job_id[..12].to_string()).collect();
    assert_eq!(named_set.into_iter().cloned().collect::<BTreeSet<_>>(), ids);
    // Each runner's results are the jobs its lines name.
    let mut by_owner: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for p in &points {
        by_owner
            .entry(p.result_owner.clone().unwrap())
            .or_default()
            .insert(p.job_id[..12].to_string());
    }
    let mut from_lines: Vec<BTreeSet<String>> = [&a_text, &b_text, &r_text]
        .iter()
        .map(|t| done_ids(t).into_iter().collect::<BTreeSet<_>>())
        .filter(|s| !s.is_empty())
        .collect();
    let mut from_db: Vec<BTreeSet<String>> = by_owner.into_values().collect();
    from_lines.sort();
    from_db.sort();
    assert_eq!(from_lines, from_db);
    assert!(
        done_ids(&b_text).len() > 40,
        "both runners worked: B did {}",
        done_ids(&b_text).len()
    );
    // Run rows: one per job, two for a job that was running at the kill.
    let runs: BTreeMap<String, i64> = store.runs_per_job().unwrap().into_iter().collect();
    assert_eq!(runs.len(), total);
    for p in &points {
        let want = if running_at_kill.contains(&p.job_id) {
            2
        } else {
            1
        };
        assert_eq!(runs[&p.job_id], want, "{}", p.job_id);
        assert_eq!(p.attempts, want, "{}", p.job_id);
    }
}
