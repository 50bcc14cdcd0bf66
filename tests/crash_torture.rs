//! Crash torture (issue 17, docs/reliability.md "Crash torture"): `wetgran sweep run` / `sweep
//! resume --extend` as child processes, killed with SIGKILL again and again at instants drawn
//! from a seeded RNG (after a random delay, or at a pause point: inside the transaction that
//! writes a result and its checkpoint, inside the replacement of an extended result, inside the
//! transaction that adds a refinement round, at the start of a run-length window), resumed each
//! time. After every kill the database passes SQLite's full
//! integrity check and every row is whole and consistent (`store_inspect::snapshot`); at the end
//! every job has exactly one result and the stored numbers equal, bit for bit, those of an
//! uninterrupted run of the same sweep.
//!
//! In CI: one episode of five kills, one at each kind of instant (a few seconds). The full
//! torture is opt-in: `cargo test --release --test crash_torture -- --ignored --nocapture`.
//!
//! The killed child is this test binary itself (its own harness, `harness = false`; the pause
//! points and the child's environment are `paused_child`).

mod paused_child;
mod store_inspect;
mod sweep_common;

use paused_child::{MARKER, child, run_child};
use rand::{Rng, SeedableRng};
use std::io::{BufRead, BufReader};
use std::os::unix::process::ExitStatusExt;
use std::path::{Path, PathBuf};
use std::process::{ExitCode, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};
use store_inspect::{Snapshot, differences, integrity, snapshot};
use sweep_common::*;
use wetgran::store::{REFINED_FROM, Store};

fn main() -> ExitCode {
    if let Some(code) = run_child() {
        return code;
    }
    let args = libtest_mimic::Arguments::from_args();
    let trial = |name: &str, f: fn()| {
        libtest_mimic::Trial::test(name, move || {
            f();
            Ok(())
        })
    };
    let trials = vec![
        trial(
            "killed_at_each_kind_of_instant_the_sweep_resumes_to_the_uninterrupted_numbers",
            killed_at_each_kind_of_instant_the_sweep_resumes_to_the_uninterrupted_numbers,
        ),
        trial(
            "regression_a_kill_in_the_grid_leaves_the_labels_of_the_uninterrupted_run",
            regression_a_kill_in_the_grid_leaves_the_labels_of_the_uninterrupted_run,
        ),
        trial(
            "regression_labels_are_the_line_rules_after_refinement_and_extension",
            regression_labels_are_the_line_rules_after_refinement_and_extension,
        ),
        trial(
            "ctrl_c_during_an_extension_keeps_every_result_and_the_next_extend_finishes",
            ctrl_c_during_an_extension_keeps_every_result_and_the_next_extend_finishes,
        ),
        // The full crash torture, ~1 min: `-- --ignored`.
        trial(
            "at_least_32_kills_20_after_random_delays_lose_and_change_nothing",
            at_least_32_kills_20_after_random_delays_lose_and_change_nothing,
        )
        .with_ignored_flag(true),
    ];
    libtest_mimic::run(&args, trials).exit_code()
}

/// Periods of total run `sweep resume --extend` takes the unconverged jobs to.
const EXTEND_TO: &str = "240";
/// The sweep's refinement budget (jobs).
const REFINE_BUDGET: usize = 4;

/// 2 x 3 grid of the tiny wet shaken system, a `[convergence]` policy that leaves some jobs
/// unconverged at its cap (so that jobs run several windows and `--extend` has work), and a
/// `[refine]` table of 4 jobs in 2 rounds: 10 jobs of ~0.1-0.3 s.
fn sweep_file(dir: &Path) -> PathBuf {
    write(dir, "tiny.toml", TINY_SCENE);
    write(
        dir,
        "torture.toml",
        &format!(
            "[sweep]\nname = \"torture\"\nbase = \"tiny.toml\"\nperiods = 40\n\
             [convergence]\nmax_periods = 80\n\
             [[axis]]\nkey = \"gamma\"\nvalues = [2.0, 6.0]\n\
             [[axis]]\nkey = \"e_star\"\nlog = {{ from = 0.5, to = 4.0, steps = 3 }}\n\
             [refine]\nbudget = {REFINE_BUDGET}\nrounds = 2\n"
        ),
    )
}

/// Where the pipeline (grid, refinement rounds, extension) stands, read from the database.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
enum Stage {
    /// No sweep registered yet.
    Start,
    /// Grid jobs left to run.
    Grid,
    /// Refinement rounds left (jobs to add or to run).
    Refine,
    /// Everything run; unconverged results left to extend (or the extension done).
    Extend,
}

fn stage(db: &Path) -> Stage {
    if !db.exists() {
        return Stage::Start;
    }
    let store = Store::open_existing(db).unwrap();
    let Ok(s) = store.sweep("torture") else {
        return Stage::Start;
    };
    let points = store.point_summaries(&s).unwrap();
    if points
        .iter()
        .any(|p| p.point < REFINED_FROM && p.status != "done")
    {
        return Stage::Grid;
    }
    let refined = wetgran::refine::driver::refined_jobs(&points, s.replicas);
    if refined < REFINE_BUDGET || points.iter().any(|p| p.status != "done") {
        return Stage::Refine;
    }
    Stage::Extend
}

/// How one attempt is killed.
#[derive(Debug, Clone)]
enum Kill {
    /// SIGKILL this long after the start.
    After(Duration),
    /// SIGKILL at the `n`-th pass of a pause point (`paused_child::PAUSE_AT_VAR` `point:n`).
    At(&'static str, u64),
}

/// What one kill hit.
#[derive(Debug, Clone)]
struct Landed {
    kill: Kill,
    /// The stage read from the database right after the kill.
    stage: Stage,
}

/// The command that continues the pipeline: `sweep run` until the sweep is registered, then
/// `sweep resume --extend`.
fn command(file: &Path, db: &Path, stage: Stage) -> Vec<String> {
    let db = db.to_str().unwrap().to_string();
    let mut args: Vec<String> = if stage == Stage::Start {
        vec!["sweep".into(), "run".into(), file.to_str().unwrap().into()]
    } else {
        ["sweep", "resume", "--extend", EXTEND_TO]
            .map(String::from)
            .to_vec()
    };
    args.extend(["--db".into(), db, "--jobs".into(), "1".into()]);
    args
}

/// The uninterrupted run: `sweep run`, then `sweep resume --extend`.
fn reference(dir: &Path, file: &Path) -> Snapshot {
    let db = dir.join("reference.sqlite");
    for stage in [Stage::Start, Stage::Extend] {
        let args = command(file, &db, stage);
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let o = run(&args);
        assert!(o.status.success(), "{}", stderr(&o));
    }
    assert_eq!(integrity(&db), ["ok"]);
    snapshot(&db)
}

/// Starts an attempt and kills it as `kill` says. `Some(stage)`: it was killed (the stage read
/// after the kill); `None`: it ended by itself first (its exit status checked: success).
fn attempt(args: &[String], kill: &Kill, db: &Path) -> Option<Stage> {
    let pause = match kill {
        Kill::At(point, n) => Some(format!("{point}:{n}")),
        Kill::After(_) => None,
    };
    let mut cmd = child(pause.as_deref().map(|at| (at, "60")));
    cmd.args(args).stdout(Stdio::null()).stderr(Stdio::piped());
    let t0 = Instant::now();
    let mut child = cmd.spawn().unwrap();
    let (tx, rx) = mpsc::channel::<String>();
    let err = child.stderr.take().unwrap();
    let reader = std::thread::spawn(move || {
        for line in BufReader::new(err).lines() {
            let Ok(line) = line else { break };
            if tx.send(line).is_err() {
                break;
            }
        }
    });
    let mut seen = String::new();
    let killed = loop {
        if let Some(status) = child.try_wait().unwrap() {
            // Ended by itself (a pause point not reached, or a delay past its end).
            reader.join().unwrap();
            seen.extend(rx.try_iter().map(|l| l + "\n"));
            assert!(status.success(), "{args:?} failed: {status}\n{seen}");
            break false;
        }
        let due = match kill {
            Kill::After(d) => t0.elapsed() >= *d,
            Kill::At(point, n) => {
                let marker = format!("{MARKER} {point} {n}");
                let mut hit = false;
                for line in rx.try_iter() {
                    hit |= line == marker;
                    seen += &line;
                    seen.push('\n');
                }
                hit
            }
        };
        if due {
            child.kill().unwrap(); // SIGKILL
            let status = child.wait().unwrap();
            reader.join().unwrap();
            // A child that exited between the check and the kill was not killed.
            break status.signal() == Some(9);
        }
        assert!(
            t0.elapsed() < Duration::from_secs(120),
            "{args:?} neither ended nor reached {kill:?}:\n{seen}"
        );
        std::thread::sleep(Duration::from_millis(2));
    };
    killed.then(|| {
        // After every kill: a sound file with whole, consistent rows.
        assert_eq!(integrity(db), ["ok"], "after {kill:?}");
        snapshot(db);
        stage(db)
    })
}

/// One episode: a fresh database, the pipeline run with kills chosen by `plan(stage, rng)`
/// until `max_kills` landed, then run to its end; returns what the kills hit.
fn episode(
    dir: &Path,
    file: &Path,
    name: &str,
    seed: u64,
    max_kills: usize,
    plan: &dyn Fn(Stage, usize, &mut rand_xoshiro::Xoshiro256PlusPlus) -> Kill,
    want: &Snapshot,
) -> Vec<Landed> {
    let db = dir.join(format!("{name}.sqlite"));
    let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(seed);
    let mut landed = Vec::new();
    let mut attempts = 0;
    loop {
        let now = stage(&db);
        let args = command(file, &db, now);
        if landed.len() == max_kills {
            let args: Vec<&str> = args.iter().map(String::as_str).collect();
            let o = run(&args);
            assert!(o.status.success(), "{}", stderr(&o));
            if now != Stage::Start {
                break;
            }
            continue;
        }
        let kill = plan(now, landed.len(), &mut rng);
        attempts += 1;
        assert!(attempts < 20 * max_kills + 20, "the pipeline does not end");
        match attempt(&args, &kill, &db) {
            Some(stage) => landed.push(Landed { kill, stage }),
            // `sweep resume --extend` ended by itself: the pipeline is through.
            None if now != Stage::Start => break,
            None => {}
        }
    }
    assert_eq!(integrity(&db), ["ok"]);
    let got = snapshot(&db);
    assert_eq!(got.points, want.points, "{name}: the same sweep points");
    assert_eq!(
        got.jobs.keys().collect::<Vec<_>>(),
        want.jobs.keys().collect::<Vec<_>>(),
        "{name}: the same jobs"
    );
    let mut differ = Vec::new();
    for (id, job) in &want.jobs {
        assert_eq!(job.status, "done", "reference job {id}");
        let d = differences(&got.jobs[id], job);
        if !d.is_empty() {
            differ.push(format!("job {}: {d}", &id[..12]));
        }
    }
    assert!(
        differ.is_empty(),
        "{name}: results differ from the uninterrupted run after kills {landed:?}:\n{}",
        differ.join("\n")
    );
    landed
}

/// A kill at a random pass of a pause point that a process started at `stage` reaches: `sweep
/// resume --extend` runs the grid, then the refinement rounds, then the extension, and jobs
/// (refined and extended ones too) run windows of the run-length policy.
fn pause_point_for(stage: Stage, rng: &mut impl Rng) -> Kill {
    let points: &[(&str, u64)] = match stage {
        Stage::Start | Stage::Grid | Stage::Refine => &[
            ("checkpoint", 3),
            ("window", 3),
            ("refine", 1),
            ("extend", 3),
        ],
        Stage::Extend => &[("checkpoint", 3), ("window", 2), ("extend", 3)],
    };
    let (p, most) = points[rng.gen_range(0..points.len())];
    Kill::At(p, rng.gen_range(1..=most))
}

fn summary(landed: &[Landed]) -> String {
    let mut by = std::collections::BTreeMap::<String, usize>::new();
    for l in landed {
        let what = match &l.kill {
            Kill::After(_) => format!("random instant, {:?} stage", l.stage),
            Kill::At(p, _) => format!("pause point `{p}`, {:?} stage", l.stage),
        };
        *by.entry(what).or_default() += 1;
    }
    by.iter()
        .map(|(k, n)| format!("  {n:3}  {k}"))
        .collect::<Vec<_>>()
        .join("\n")
}

/// CI: five kills, one at each kind of instant, in pipeline order.
fn killed_at_each_kind_of_instant_the_sweep_resumes_to_the_uninterrupted_numbers() {
    let dir = tempfile::tempdir().unwrap();
    let file = sweep_file(dir.path());
    let want = reference(dir.path(), &file);
    // Each pause point is reached from any stage before it: `sweep resume` runs the grid,
    // then the refinement rounds, then the extension.
    let plan = |_: Stage, k: usize, _: &mut rand_xoshiro::Xoshiro256PlusPlus| match k {
        0 => Kill::At("checkpoint", 2),
        1 => Kill::At("window", 1),
        // Early enough that the refinement's and the extension's pause points are still ahead
        // of it on a fast host (at 300 ms the resumed sweep could be past its last round).
        2 => Kill::After(Duration::from_millis(100)),
        3 => Kill::At("refine", 1),
        _ => Kill::At("extend", 2),
    };
    let landed = episode(dir.path(), &file, "ci", 1, 5, &plan, &want);
    eprintln!("{} kills:\n{}", landed.len(), summary(&landed));
    assert_eq!(landed.len(), 5, "{landed:?}");
    for point in ["checkpoint", "window", "refine", "extend"] {
        assert!(
            landed
                .iter()
                .any(|l| matches!(l.kill, Kill::At(p, _) if p == point)),
            "no kill at `{point}`: {landed:?}"
        );
    }
}

/// Regression (found by the torture): a sweep killed once in its grid ended with other labels
/// (phase and decision numbers) than the uninterrupted run, though every number agreed.
/// Refinement rounds ran without the line-rule relabelling that follows every other run, so the
/// labels of refined points, and the plan of the next round, depended on whether a resume had
/// relabelled them; extended results kept their per-point labels until some later resume
/// relabelled them. Now every run, refinement round and extension ends with the relabelling
/// of the lines holding its new results (`run::relabel::relabel_changed`).
fn regression_a_kill_in_the_grid_leaves_the_labels_of_the_uninterrupted_run() {
    let dir = tempfile::tempdir().unwrap();
    let file = sweep_file(dir.path());
    let want = reference(dir.path(), &file);
    let plan =
        |_: Stage, _: usize, _: &mut rand_xoshiro::Xoshiro256PlusPlus| Kill::At("checkpoint", 2);
    let landed = episode(dir.path(), &file, "regression", 1, 1, &plan, &want);
    assert_eq!(landed.len(), 1, "{landed:?}");
    assert_eq!(landed[0].stage, Stage::Grid, "{landed:?}");
}

/// The cause of the regression above, without kills: after `sweep run` (whose refinement rounds
/// end it) and after `sweep resume --extend`, every stored label is already the line rule's, so
/// `wetgran reclassify` (the same relabelling) changes no row.
fn regression_labels_are_the_line_rules_after_refinement_and_extension() {
    let dir = tempfile::tempdir().unwrap();
    let file = sweep_file(dir.path());
    let db = dir.path().join("labels.sqlite");
    for stage in [Stage::Start, Stage::Extend] {
        let args = command(&file, &db, stage);
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let o = run(&args);
        assert!(o.status.success(), "{}", stderr(&o));
        let before = snapshot(&db);
        let o = run(&["reclassify", "--db", db.to_str().unwrap()]);
        assert!(o.status.success(), "{}", stderr(&o));
        let after = snapshot(&db);
        for (id, job) in &before.jobs {
            let d = differences(&after.jobs[id], job);
            assert!(d.is_empty(), "after {args:?}: job {}: {d}", &id[..12]);
        }
    }
}

/// A wet 2D gas cooling without a drive (the standard `s_crit`, `E_cb`, eps 0.9), `duration`
/// time units: `T_g` drifts down for the whole run.
const COOLING: &str = "dimension = 2\n[box]\nsize = [30.0, 9.0]\n[particles]\ncount = 60\n\
    polydispersity = 0.06\n[contact]\nrestitution = 0.9\n[capillary]\nmodel = \"thin_thread\"\n\
    [initial]\ntemperature_over_ecb = 20.0\nseed = 2\n[run]\nduration = 4.0\n";

/// The sweep `cool` of two cooling gases that never settle, capped at 8 periods, written to
/// `dir` and run with one worker; returns its database.
fn cool_sweep_run(dir: &Path) -> PathBuf {
    write(dir, "cool.toml", COOLING);
    let sweep = write(
        dir,
        "cool_sweep.toml",
        "[sweep]\nname = \"cool\"\nbase = \"cool.toml\"\n[observe]\ntransient_periods = 0.0\nmobility_lag = 1.0\n\
         [convergence]\nmax_periods = 8.0\n\
         [[axis]]\nkey = \"contact.restitution\"\nvalues = [0.8, 0.9]\n",
    );
    let db = dir.join("w.sqlite");
    let (sweep_s, db_s) = (sweep.to_str().unwrap(), db.to_str().unwrap());
    let o = run(&["sweep", "run", sweep_s, "--db", db_s, "--jobs", "1"]);
    assert!(o.status.success(), "{}", stderr(&o));
    db
}

/// Ctrl-C while `sweep resume --extend` replaces a result (the `extend` pause point: the old
/// result deleted, the new one not written): the process says how to resume and exits with
/// 130, the extension committed before stays, the interrupted job keeps its old result, and the
/// next `--extend` extends it.
fn ctrl_c_during_an_extension_keeps_every_result_and_the_next_extend_finishes() {
    let dir = tempfile::tempdir().unwrap();
    let db = cool_sweep_run(dir.path());
    let db_s = db.to_str().unwrap();
    let points = |db: &std::path::Path| {
        let store = wetgran::store::Store::open_existing(db).unwrap();
        let s = store.sweep("cool").unwrap();
        assert_eq!(store_inspect::integrity(db), ["ok"]);
        store.points(s.id).unwrap()
    };
    let before = points(&db);
    assert!(before.iter().all(|p| p.simulated_time == Some(8.0)));

    // One worker takes the jobs in grid order: the second replacement pauses.
    let mut child = child(Some(("extend:2", "60")))
        .args(["sweep", "resume", "cool", "--db", db_s, "--extend", "16"])
        .args(["--jobs", "1"])
        .stderr(std::process::Stdio::piped())
        .stdout(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let mut lines = BufReader::new(child.stderr.take().unwrap()).lines();
    let mut seen = String::new();
    while !seen.contains(MARKER) {
        let line = lines
            .next()
            .unwrap_or_else(|| panic!("the extension ended before its pause:\n{seen}"))
            .unwrap();
        seen += &line;
        seen.push('\n');
    }
    let pid = child.id().to_string();
    let kill = std::process::Command::new("kill")
        .args(["-INT", &pid])
        .status()
        .unwrap();
    assert!(kill.success());
    let rest: Vec<String> = lines.map_while(Result::ok).collect();
    let status = child.wait().unwrap();
    let err = rest.join("\n");
    assert_eq!(status.code(), Some(130), "{seen}{err}");
    let hint = format!("wetgran sweep resume cool --db {db_s}");
    assert!(err.contains(&hint), "no `{hint}` in:\n{seen}{err}");

    let mid = points(&db);
    let t: Vec<f64> = mid.iter().map(|p| p.simulated_time.unwrap()).collect();
    assert!(
        t[0] > 8.0 && t[0] <= 16.0 + 1e-9,
        "the first extension is stored: {t:?}"
    );
    assert_eq!(
        mid[1].simulated_time,
        Some(8.0),
        "the second job keeps its old result"
    );
    assert_eq!(mid[1].observables, before[1].observables);

    let o = run(&["sweep", "resume", "cool", "--db", db_s, "--extend", "16"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let after = points(&db);
    assert_eq!(after[0].observables, mid[0].observables, "{}", stderr(&o));
    let t = after[1].simulated_time.unwrap();
    assert!(
        t > 8.0 && t <= 16.0 + 1e-9,
        "the second job is extended now: {t}"
    );
}

/// The full torture (opt-in): episodes of up to 10 kills (seeds 1, 2, ...) until at least 32
/// kills landed, at least 20 of them after a random delay; each kill after a random delay of 0.05-1.5 s (half of them) or at a random
/// pass of a random pause point (`pause_point_for`). An episode ends early when a `sweep
/// resume --extend` ends by itself (its pause point was not reached, or its delay was past
/// its end).
fn at_least_32_kills_20_after_random_delays_lose_and_change_nothing() {
    let t0 = Instant::now();
    let dir = tempfile::tempdir().unwrap();
    let file = sweep_file(dir.path());
    let want = reference(dir.path(), &file);
    let plan = |stage: Stage, _: usize, rng: &mut rand_xoshiro::Xoshiro256PlusPlus| {
        if rng.gen_bool(0.5) {
            Kill::After(Duration::from_secs_f64(rng.gen_range(0.05..1.5)))
        } else {
            pause_point_for(stage, rng)
        }
    };
    let mut all: Vec<Landed> = Vec::new();
    let mut episodes = 0;
    let after_delay = |all: &[Landed]| {
        all.iter()
            .filter(|l| matches!(l.kill, Kill::After(_)))
            .count()
    };
    while all.len() < 32 || after_delay(&all) < 20 {
        episodes += 1;
        assert!(episodes <= 20, "too few kills land: {all:?}");
        all.extend(episode(
            dir.path(),
            &file,
            &format!("full{episodes}"),
            episodes,
            10,
            &plan,
            &want,
        ));
    }
    eprintln!(
        "crash torture: {} kills survived in {episodes} episodes, {:.1} s; every job one \
         result, numbers equal to the uninterrupted run ({} jobs):\n{}",
        all.len(),
        t0.elapsed().as_secs_f64(),
        want.jobs.len(),
        summary(&all)
    );
    for point in ["checkpoint", "window", "refine", "extend"] {
        assert!(
            all.iter()
                .any(|l| matches!(l.kill, Kill::At(p, _) if p == point)),
            "no kill at `{point}`"
        );
    }
}
