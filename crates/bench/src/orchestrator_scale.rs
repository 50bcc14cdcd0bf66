//! `wetgran-bench orchestrator --collect`, `--submit-dry-run` and `--two-runners`: the
//! orchestrator at cluster scale (issue 35, items 3 and 4), with the stand-in jobs of
//! [`crate::orchestrator`]; docs/orchestrator.md describes each run and its figures.
//!
//! - **collect** ([`time_collect`]): a submission of N tasks recorded without a Slurm job id (no
//!   queue is asked), each task's result record written (untimed), then `wetgran sweep collect`
//!   timed, process start included.
//! - **submit dry run** ([`time_submit_dry_run`]): `wetgran sweep submit FILE --slurm --dry-run`
//!   timed without a database and with the sweep registered in one; header and scripts checked.
//! - **two runners** ([`two_runners`]): two runner processes (the hidden `orchestrator-runner`)
//!   on one database, the first killed with SIGKILL after a sixth of the jobs, the rest resumed
//!   here and relabelled. Every stand-in start is logged, so the books must be exact
//!   (`check_books`: every job done with one result; run rows and attempts 1 per job, 2 for a
//!   job the killed runner held, which may show one more logged start); anything else is an error.

use crate::orchestrator::{
    Options, e, prepare, real_result, run_options, stand_in, stand_in_phase, temp_dir,
    time_command, timed, wetgran_binary,
};
use std::collections::{BTreeMap, BTreeSet, HashMap, HashSet};
use std::io::Write as _;
use std::path::Path;
use std::process::{Command, Stdio};
use std::sync::Mutex;
use std::time::{Duration, Instant};
use wetgran::cluster::{Outcome, ResultRecord, SweepDir};
use wetgran::run::{JobFn, run_sweeps_with};
use wetgran::store::{Durability, Store, SweepRow};
use wetgran::sweep::{JobError, JobSpec};

/// The stand-in job of a runner process: the first job of the sweep (`dir/first_job.json`) run
/// once for its shape, each start appended to `log` (one line, one `write`: a kill leaves whole
/// lines).
fn logged_stand_in(dir: &Path, log: &Path) -> Result<JobFn, String> {
    let spec: JobSpec =
        serde_json::from_str(&std::fs::read_to_string(dir.join("first_job.json")).map_err(e)?)
            .map_err(e)?;
    let log = Mutex::new(std::fs::File::create(log).map_err(e)?);
    Ok(stand_in(real_result(&spec)?, move |id| {
        let mut f = log.lock().expect("no panic holds it");
        f.write_all(format!("{id}\n").as_bytes())
            .map_err(|x| JobError::Panic(format!("start log: {x}")))
    }))
}

/// `wetgran sweep collect` of N tasks (module doc): `(seconds, tasks)`.
pub fn time_collect(n: usize, dir: &Path) -> Result<(f64, usize), String> {
    let (file, jobs) = prepare(n, dir)?;
    let real = real_result(&jobs[0].spec)?;
    let db = dir.join("collect.sqlite");
    let store = Store::open_as(&db, true, Durability::Synced).map_err(e)?;
    let sweep = store.register_sweep(&file, &jobs).map_err(e)?;
    let sd = SweepDir::new(&dir.join("slurm"));
    sd.create().map_err(e)?;
    let ids: BTreeSet<String> = jobs.iter().map(|j| j.spec.id()).collect();
    let ids: Vec<String> = ids.into_iter().collect();
    let root = sd.root.display().to_string();
    store
        .record_submission(sweep.id, &root, "#!/bin/sh\n# bench\n", &ids)
        .map_err(e)?;
    drop(store);
    let coords: HashMap<String, &[serde_json::Value]> = jobs
        .iter()
        .map(|j| (j.spec.id(), j.coords.as_slice()))
        .collect();
    for (k, id) in ids.iter().enumerate() {
        let mut r = real.clone();
        r.phase = Some(stand_in_phase(coords[id]).to_string());
        let mut rec = ResultRecord::new(id, Outcome::Done(r), 0.01);
        rec.slurm_task = Some(format!("1000_{k}"));
        let text = serde_json::to_string_pretty(&rec).map_err(e)?;
        std::fs::write(sd.result(id), text + "\n").map_err(e)?;
    }
    let d = db.display().to_string();
    let t = time_command(
        &wetgran_binary()?,
        &["sweep", "collect", "--db", &d],
        &dir.join("collect.txt"),
    )?;
    let store = Store::open_existing(&db).map_err(e)?;
    let c = store.counts(sweep.id).map_err(e)?;
    if c.done as usize != ids.len() {
        return Err(format!("collect: {} of {} jobs done", c.done, ids.len()));
    }
    Ok((t, ids.len()))
}

/// `(jobs, arrays, limit, source)` of the dry run's header line
/// `# dry run: N job(s) to submit as K array(s) of at most L task(s) (SOURCE); ...`.
fn parse_dry_header(text: &str) -> Option<(usize, usize, usize, String)> {
    let line = text.lines().next()?.strip_prefix("# dry run: ")?;
    let (jobs, rest) = line.split_once(" job(s) to submit as ")?;
    let (arrays, rest) = rest.split_once(" array(s) of at most ")?;
    let (limit, rest) = rest.split_once(" task(s) (")?;
    let source = rest.split_once(')')?.0.to_string();
    Some((
        jobs.parse().ok()?,
        arrays.parse().ok()?,
        limit.parse().ok()?,
        source,
    ))
}

/// One timed `sweep submit --slurm --dry-run` of the benchmark sweep; checks its header.
fn dry_run_once(
    bin: &Path,
    dir: &Path,
    db: &Path,
    jobs: usize,
) -> Result<(f64, usize, usize, String), String> {
    let (sweep, db) = (dir.join("bench.toml"), db.display().to_string());
    let args = [
        "sweep",
        "submit",
        &sweep.display().to_string(),
        "--slurm",
        "--dry-run",
    ];
    let out_path = dir.join("dry-run.txt");
    let t = time_command(bin, &[&args[..], &["--db", &db]].concat(), &out_path)?;
    let text = std::fs::read_to_string(&out_path).map_err(e)?;
    let (n, arrays, limit, source) = parse_dry_header(&text)
        .ok_or_else(|| format!("dry run: unexpected header {:?}", text.lines().next()))?;
    // Tasks of the printed array scripts (`#SBATCH --array=0-K`: K + 1 tasks each).
    let sizes: Vec<usize> = text
        .lines()
        .filter_map(|l| l.strip_prefix("#SBATCH --array=0-"))
        .filter_map(|k| k.trim().parse::<usize>().ok())
        .map(|k| k + 1)
        .collect();
    let in_scripts: usize = sizes.iter().sum();
    if n != jobs
        || limit == 0
        || arrays != jobs.div_ceil(limit)
        || sizes.len() != arrays
        || in_scripts != jobs
        || sizes.iter().any(|&k| k > limit)
    {
        return Err(format!(
            "dry run of {jobs} jobs printed {n} jobs in {arrays} arrays of at most {limit} \
             (scripts of {sizes:?} tasks)"
        ));
    }
    Ok((t, arrays, limit, source))
}

/// `sweep submit --slurm --dry-run` of N jobs, without and with a database (module doc): the
/// printed line.
pub fn time_submit_dry_run(n: usize, dir: &Path) -> Result<String, String> {
    let (file, jobs) = prepare(n, dir)?;
    let n_ids = jobs
        .iter()
        .map(|j| j.spec.id())
        .collect::<HashSet<_>>()
        .len();
    let bin = wetgran_binary()?;
    let db = dir.join("dry.sqlite");
    let (fresh_s, arrays, limit, source) = dry_run_once(&bin, dir, &db, n_ids)?;
    if db.exists() {
        return Err("the dry run created the database".to_string());
    }
    let store = Store::open_as(&db, true, Durability::Synced).map_err(e)?;
    store.register_sweep(&file, &jobs).map_err(e)?;
    drop(store);
    let (registered_s, ..) = dry_run_once(&bin, dir, &db, n_ids)?;
    if dir.join("wetgran-slurm").exists() {
        return Err("the dry run wrote a sweep directory".to_string());
    }
    Ok(format!(
        "{n_ids:>8} jobs: `sweep submit --slurm --dry-run` {fresh_s:.2} s without a database, \
         {registered_s:.2} s with the sweep registered ({arrays} array(s) of at most {limit}, \
         {source})"
    ))
}

/// The job ids of a start log, one per line (a line cut by the kill is dropped: it has no
/// newline).
fn read_log(path: &Path) -> Result<Vec<String>, String> {
    let text = std::fs::read_to_string(path).map_err(|x| format!("{}: {x}", path.display()))?;
    let whole = text.rfind('\n').map_or("", |at| &text[..at]);
    Ok(whole.lines().map(str::to_string).collect())
}

fn lines_in(path: &Path) -> usize {
    std::fs::read(path).map_or(0, |b| b.iter().filter(|&&c| c == b'\n').count())
}

/// Two runners on one database of N jobs, the first killed with SIGKILL mid-way (module doc):
/// the printed line. `both` is from the start of the first runner to the end of the second.
pub fn two_runners(n: usize, dir: &Path) -> Result<String, String> {
    let (file, jobs) = prepare(n, dir)?;
    let spec = serde_json::to_string(&jobs[0].spec).map_err(e)?;
    std::fs::write(dir.join("first_job.json"), spec).map_err(e)?;
    let db = dir.join("two.sqlite");
    let store = Store::open_as(&db, true, Durability::Fast).map_err(e)?;
    let sweep = store.register_sweep(&file, &jobs).map_err(e)?;
    drop(store);
    let total = jobs.len();
    let kill_after = (total / 6).max(1);
    let exe = std::env::current_exe().map_err(e)?;
    let logs = [dir.join("a.log"), dir.join("b.log"), dir.join("r.log")];
    let spawn = |log: &Path| {
        Command::new(&exe)
            .args(["orchestrator-runner", "--db"])
            .arg(&db)
            .arg("--dir")
            .arg(dir)
            .arg("--log")
            .arg(log)
            .stdout(Stdio::null())
            .spawn()
            .map_err(e)
    };
    let t0 = Instant::now();
    let mut a = spawn(&logs[0])?;
    let b = spawn(&logs[1])?;
    while lines_in(&logs[0]) < kill_after {
        if let Some(status) = a.try_wait().map_err(e)? {
            return Err(format!("runner A ended ({status}) before the kill"));
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    a.kill().map_err(e)?;
    a.wait().map_err(e)?;
    let b = b.wait_with_output().map_err(e)?;
    if !b.status.success() {
        return Err(format!("runner B failed ({})", b.status));
    }
    let runners_s = t0.elapsed().as_secs_f64();

    let store = Store::open_as(&db, false, Durability::Fast).map_err(e)?;
    let held: HashSet<String> = store
        .point_summaries(&sweep)
        .map_err(e)?
        .into_iter()
        .filter(|p| p.status == "running")
        .map(|p| p.job_id)
        .collect();
    let (_, resume_s) = timed(|| {
        let job = logged_stand_in(dir, &logs[2])?;
        run_sweeps_with(&store, std::slice::from_ref(&sweep), &run_options(1), job).map_err(e)
    })?;
    let (_, relabel_s) = timed(|| wetgran::run::relabel::relabel_changed(&store, &sweep))?;
    let started = [
        read_log(&logs[0])?,
        read_log(&logs[1])?,
        read_log(&logs[2])?,
    ];
    check_books(&store, &sweep, total, &held, &started)?;
    let [a, b, r] = started.map(|s| s.len());
    Ok(format!(
        "{total:>8} jobs, two runners, the first killed after {a} starts: both {runners_s:.1} s; \
         starts A {a} / B {b} / resume {r}, {} job(s) held at the kill; resume {resume_s:.2} s, \
         relabel {relabel_s:.2} s; books exact (every job done once, none lost)",
        held.len()
    ))
}

/// The exact bookkeeping of [`two_runners`] (module doc); an error names what is off.
fn check_books(
    store: &Store,
    sweep: &SweepRow,
    total: usize,
    held: &HashSet<String>,
    started: &[Vec<String>; 3],
) -> Result<(), String> {
    let c = store.counts(sweep.id).map_err(e)?;
    if c.done as usize != total || c.total() as usize != total {
        return Err(format!("not every job done: {c:?} of {total}"));
    }
    let summaries = store.point_summaries(sweep).map_err(e)?;
    let runs: BTreeMap<String, i64> = store.runs_per_job().map_err(e)?.into_iter().collect();
    if summaries.len() != total || runs.len() != total {
        return Err(format!(
            "{} rows, {} jobs with run rows, of {total}",
            summaries.len(),
            runs.len()
        ));
    }
    let mut starts: HashMap<&str, usize> = HashMap::new();
    for id in started.iter().flatten() {
        *starts.entry(id.as_str()).or_default() += 1;
    }
    for p in &summaries {
        if p.status != "done" || p.wall_seconds.is_none() {
            return Err(format!("job {}: {} without a result", p.job_id, p.status));
        }
        let want: i64 = if held.contains(&p.job_id) { 2 } else { 1 };
        let s = starts.get(p.job_id.as_str()).copied().unwrap_or(0) as i64;
        let starts_ok = s == want || (want == 2 && s == 1);
        if runs[&p.job_id] != want || p.attempts != want || !starts_ok {
            return Err(format!(
                "job {}: {} run row(s), {} attempt(s), {s} start(s); want {want}",
                p.job_id, runs[&p.job_id], p.attempts
            ));
        }
    }
    if starts.len() != total {
        return Err(format!("{} distinct jobs started of {total}", starts.len()));
    }
    Ok(())
}

/// The hidden `orchestrator-runner`: runs the benchmark sweep of `db` to the end with one
/// worker and the stand-in job (the spec `dir/first_job.json` run once for its shape), each
/// start appended to `log`.
pub fn runner(db: &Path, dir: &Path, log: &Path) -> Result<(), String> {
    let job = logged_stand_in(dir, log)?;
    let store = Store::open_as(db, false, Durability::Fast).map_err(e)?;
    let sweep = store.sweep("bench").map_err(e)?;
    run_sweeps_with(&store, &[sweep], &run_options(1), job).map_err(e)?;
    Ok(())
}

/// Runs the asked scale figures at every size, each in a fresh folder under `dir`, and prints
/// each figure's line to standard output as soon as it is measured.
pub fn run(o: &Options) -> Result<(), String> {
    for &n in &o.sizes {
        let tmp = temp_dir(o.dir.as_deref())?;
        if o.collect {
            let (t, tasks) = time_collect(n, tmp.path())?;
            println!(
                "{tasks:>8} tasks: `sweep collect` {t:.2} s ({:.3} ms per task)",
                t / tasks as f64 * 1e3
            );
        }
        if o.submit_dry_run {
            println!("{}", time_submit_dry_run(n, tmp.path())?);
        }
        if o.two_runners {
            println!("{}", two_runners(n, tmp.path())?);
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::parse_dry_header;

    #[test]
    fn the_dry_run_header_parses() {
        let text = "# dry run: 10000 job(s) to submit as 10 array(s) of at most 1000 task(s) \
                    (cluster MaxArraySize 1001); sweep directory /x/wetgran-slurm/bench\n# ----";
        assert_eq!(
            parse_dry_header(text),
            Some((10000, 10, 1000, "cluster MaxArraySize 1001".to_string()))
        );
        assert_eq!(parse_dry_header("sweep bench: nothing"), None);
    }
}
