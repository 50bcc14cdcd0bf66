//! `wetgran-bench orchestrator`: the sweep orchestrator alone (issue 35), on a file database;
//! what each figure means is in docs/performance.md, "Orchestrator".
//!
//! For each size N the benchmark sweep (`prepare`) is registered in a fresh database (timed)
//! and run with the real runner and store (`run::run_sweeps_with`) on `--workers` threads. Each
//! job is a `stand_in`: it returns at once the result of one real run of the first job (timed
//! and printed before) with a phase label made up from its point (`stand_in_phase`), so that
//! the run's wall time is the orchestration alone and the reports have boundaries to find. The
//! store commits as `sweep run` does (`Durability::Fast`), or with `--synced` as every other
//! command does. Then each report of `--reports` as the `wetgran` binary beside this one runs it
//! on that database (process start included), the median of `--repeat` runs.
//!
//! With `refine` among the reports: first the relabelling that ends `sweep run`
//! (`run::relabel::relabel_changed` on the sweep's results, every one of them new), timed; the
//! stand-in labels are then written back (`Store::relabel_and_clear`, untimed): the classifier
//! gives every stand-in result one label (their observables are one run's), which would leave
//! no boundary to plan on. Then one refinement round, in this process, as
//! `refine::driver::refine_sweep` makes it (reading the rows, planning, adding the jobs, running
//! them with the stand-in, and the relabelling of the lines of constant Gamma holding the new
//! results that follows each round's run), each part timed; its budget is a tenth of the sweep.
//! So that the map has boundaries to refine, the stand-in results are made stationary: every
//! stored trend test passes and none is unrelaxed, so any label's verdict (recomputed by every
//! relabelling) is stationary, which every report also sees.

use crate::quantile;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::{Arc, Mutex};
use std::time::Instant;
use wetgran::run::{JobFn, RunOptions, run_sweeps_with};
use wetgran::store::{Durability, Store};
use wetgran::sweep::{JobError, JobResult, JobSpec, SweepFile, SweepJob, run_job};

/// The options of `wetgran-bench orchestrator`.
#[derive(Debug, clap::Args)]
pub struct Options {
    /// Sweep sizes (jobs), comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "1000,10000")]
    pub sizes: Vec<usize>,
    /// Worker threads of the runner.
    #[arg(long, default_value_t = 2)]
    pub workers: usize,
    /// Runs of each report command (the median is printed).
    #[arg(long, default_value_t = 3)]
    pub repeat: usize,
    /// Folder for the databases (default: the system's temporary folder).
    #[arg(long)]
    pub dir: Option<PathBuf>,
    /// Sync every commit to disk (SQLite `synchronous = FULL`) instead of committing as
    /// `sweep run` does (`NORMAL`).
    #[arg(long)]
    pub synced: bool,
    /// Keep each size's folder and database (its path is printed) instead of removing it.
    #[arg(long)]
    pub keep: bool,
    /// Which reports to time, comma-separated (`status`, `boundaries`, `plot`, `export`,
    /// `reclassify`; `refine`: one refinement round, with stationary stand-in results).
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "status,boundaries,plot,export,reclassify"
    )]
    pub reports: Vec<String>,
    /// Instead of the run and the reports: time `sweep collect` of N task result records
    /// (a submission recorded without Slurm, the records written beforehand).
    #[arg(long)]
    pub collect: bool,
    /// Instead of the run and the reports: time `sweep submit --slurm --dry-run` of the
    /// N-job sweep (process start, expansion, split into arrays, scripts printed), without
    /// a database and with the sweep registered in one.
    #[arg(long)]
    pub submit_dry_run: bool,
    /// Instead of the run and the reports: two runner processes on one database, the first
    /// killed with SIGKILL after a sixth of the jobs, the rest resumed; checks that every
    /// job is done once and none lost (docs/reliability.md, "Two runners, one killed").
    #[arg(long)]
    pub two_runners: bool,
}

impl Options {
    fn durability(&self) -> Durability {
        match self.synced {
            true => Durability::Synced,
            false => Durability::Fast,
        }
    }
}

/// An error as its text.
pub(crate) fn e(x: impl std::fmt::Display) -> String {
    x.to_string()
}

/// What `f` returned and the wall seconds it took; its error as text.
pub(crate) fn timed<T, E: std::fmt::Display>(
    f: impl FnOnce() -> Result<T, E>,
) -> Result<(T, f64), String> {
    let t0 = Instant::now();
    let out = f().map_err(e)?;
    Ok((out, t0.elapsed().as_secs_f64()))
}

/// The base scene of the benchmark sweep (the quickstart's).
pub(crate) const BASE_SCENE: &str = include_str!("../../../scenes/shaken_wet_2d.toml");

/// The benchmark sweep file over `n_gamma` x `n_e` points.
pub(crate) fn sweep_text(n_gamma: usize, n_e: usize) -> String {
    format!(
        "[sweep]\nname = \"bench\"\nbase = \"shaken_wet_2d.toml\"\nreplicas = 1\nperiods = 2\n\
         [scene]\nparticles.count = 20\nbox.size = [7.0, 9.0]\nengine.min_rebound_speed = 0.03\n\
         [observe]\ntransient_periods = 1\nsamples_per_period = 20\n\
         [[axis]]\nkey = \"gamma\"\nlog = {{ from = 0.5, to = 20.0, steps = {n_gamma} }}\n\
         [[axis]]\nkey = \"e_star\"\nlog = {{ from = 0.3, to = 4.755, steps = {n_e} }}\n"
    )
}

/// A grid of about `n` points: `(n_gamma, n_e)` with `n_gamma * n_e = n` where `n` allows.
pub(crate) fn grid(n: usize) -> (usize, usize) {
    let mut a = (n as f64).sqrt().floor() as usize;
    while a > 1 && !n.is_multiple_of(a) {
        a -= 1;
    }
    (a.max(1), n / a.max(1))
}

/// The benchmark sweep of about `n` points written into `dir` (its base scene beside it), and
/// its jobs.
pub(crate) fn prepare(n: usize, dir: &Path) -> Result<(SweepFile, Vec<SweepJob>), String> {
    let (n_gamma, n_e) = grid(n);
    std::fs::write(dir.join("shaken_wet_2d.toml"), BASE_SCENE).map_err(e)?;
    let path = dir.join("bench.toml");
    std::fs::write(&path, sweep_text(n_gamma, n_e)).map_err(e)?;
    let file = SweepFile::load(&path).map_err(e)?;
    let jobs = file.expand().map_err(e)?;
    Ok((file, jobs))
}

/// One real run of `spec`: the shape of every stand-in result.
pub(crate) fn real_result(spec: &JobSpec) -> Result<JobResult, String> {
    run_job(
        spec,
        &wetgran_core::sim::RunSettings::default(),
        &mut |_| {},
    )
    .map_err(e)
}

/// A stand-in job: `on_start(job id)`, then `result` with the point's made-up label.
pub(crate) fn stand_in(
    result: JobResult,
    on_start: impl Fn(&str) -> Result<(), JobError> + Send + Sync + 'static,
) -> JobFn {
    Arc::new(move |claim, _settings, _progress| {
        on_start(&claim.job_id)?;
        let mut r = result.clone();
        r.phase = Some(stand_in_phase(&claim.coords).to_string());
        Ok(r)
    })
}

/// How the benchmark runs a sweep: `workers` threads, silent, no wall-table cache.
pub(crate) fn run_options(workers: usize) -> RunOptions {
    RunOptions {
        jobs: workers,
        retry_failed: false,
        show_progress: false,
        table_cache_mib: 0,
        on_extend: None,
    }
}

/// A fresh folder under `dir` (default: the system's temporary folder).
pub(crate) fn temp_dir(dir: Option<&Path>) -> Result<tempfile::TempDir, String> {
    match dir {
        Some(d) => tempfile::tempdir_in(d),
        None => tempfile::tempdir(),
    }
    .map_err(|x| format!("cannot make a temporary folder: {x}"))
}

/// The `wetgran` binary beside this one.
pub(crate) fn wetgran_binary() -> Result<PathBuf, String> {
    let exe = std::env::current_exe().map_err(|e| format!("cannot find this binary: {e}"))?;
    let bin = exe.with_file_name("wetgran");
    if bin.exists() {
        Ok(bin)
    } else {
        Err(format!(
            "{}: not found; build it first (`cargo build --release`)",
            bin.display()
        ))
    }
}

/// Seconds one run of `wetgran ARGS` takes (standard output to `out`); an error with its
/// standard error if it fails.
pub(crate) fn time_command(bin: &Path, args: &[&str], out: &Path) -> Result<f64, String> {
    let file = std::fs::File::create(out).map_err(|x| format!("{}: {x}", out.display()))?;
    let t0 = Instant::now();
    let run = Command::new(bin)
        .args(args)
        .stdout(Stdio::from(file))
        .stderr(Stdio::piped())
        .output()
        .map_err(|x| format!("wetgran {}: {x}", args.join(" ")))?;
    let t = t0.elapsed().as_secs_f64();
    if !run.status.success() {
        return Err(format!(
            "wetgran {} failed ({}): {}",
            args.join(" "),
            run.status,
            String::from_utf8_lossy(&run.stderr)
        ));
    }
    Ok(t)
}

/// Bytes of a file, 0 if it is not there.
fn size(p: &Path) -> u64 {
    std::fs::metadata(p).map(|m| m.len()).unwrap_or(0)
}

/// The figures of one size.
#[derive(Debug, Clone)]
pub struct Figures {
    pub jobs: usize,
    pub(crate) register_s: f64,
    pub(crate) run_s: f64,
    /// Median and 99th percentile of the time between job starts (ms), first and last tenth.
    pub(crate) gap_first_ms: (f64, f64),
    pub(crate) gap_last_ms: (f64, f64),
    pub(crate) db_bytes_per_result: f64,
    /// `(command, median seconds)`.
    pub reports: Vec<(String, f64)>,
    /// One refinement round (`refine` among the reports).
    pub refine: Option<RefineRound>,
    /// Seconds of the relabelling that ends `sweep run` (`refine` among the reports).
    pub(crate) end_of_run_relabel_s: Option<f64>,
}

/// The parts of one refinement round, seconds.
#[derive(Debug, Clone)]
pub struct RefineRound {
    pub(crate) relabel_s: f64,
    /// Reading every row (`Store::points`) and planning the round.
    pub(crate) plan_s: f64,
    pub(crate) add_s: f64,
    pub(crate) run_s: f64,
    pub added: usize,
}

/// Times one refinement round of the sweep `row` of `store` (module doc), with `job` as its
/// jobs.
fn refine_round(
    store: &Store,
    file: &SweepFile,
    row: &wetgran::store::SweepRow,
    job: JobFn,
    opts: &RunOptions,
) -> Result<RefineRound, String> {
    use wetgran::refine::driver::plan_jobs;
    let rows_of = std::slice::from_ref(row);
    let (jobs, plan_s) = timed(|| {
        let rows = store.point_summaries(row).map_err(e)?;
        let settings = wetgran::refine::Settings {
            replicas: row.replicas,
            max_replicas: 3 * row.replicas,
            resolution: 0.0,
        };
        plan_jobs(file, row, &rows, (rows.len() / 10).max(1), &settings).map_err(e)
    })?;
    let ((), add_s) = timed(|| store.add_jobs(row.id, &jobs))?;
    let (summary, run_s) = timed(|| run_sweeps_with(store, rows_of, opts, job))?;
    if summary.done as usize != jobs.len() {
        return Err(format!(
            "refinement: {} of {} jobs done",
            summary.done,
            jobs.len()
        ));
    }
    let (_, relabel_s) = timed(|| wetgran::run::relabel::relabel_changed(store, row))?;
    Ok(RefineRound {
        relabel_s,
        plan_s,
        add_s,
        run_s,
        added: jobs.len(),
    })
}

/// The stand-in label of a point: a made-up map with two boundaries, solid at low Gamma, gas at
/// high E* Gamma.
pub(crate) fn stand_in_phase(coords: &[serde_json::Value]) -> &'static str {
    let gamma = coords.first().and_then(|v| v.as_f64()).unwrap_or(1.0);
    let e_star = coords.get(1).and_then(|v| v.as_f64()).unwrap_or(1.0);
    if gamma < 1.5 {
        "s"
    } else if gamma * e_star > 10.0 {
        "g"
    } else {
        "f"
    }
}

/// Times the relabelling that ends `sweep run` on the sweep `row`, then writes the stand-in
/// labels back (module doc).
fn end_of_run_relabel(
    store: &Store,
    row: &wetgran::store::SweepRow,
    decided_on: &Option<serde_json::Value>,
) -> Result<f64, String> {
    let (_, t) = timed(|| wetgran::run::relabel::relabel_changed(store, row))?;
    let decided_on = decided_on.clone().unwrap_or(serde_json::Value::Null);
    let labels: Vec<(String, String, serde_json::Value)> = store
        .points(row.id)
        .map_err(e)?
        .into_iter()
        .map(|p| {
            (
                p.job_id,
                stand_in_phase(&p.coords).to_string(),
                decided_on.clone(),
            )
        })
        .collect();
    store.relabel_and_clear(&labels, &[]).map_err(e)?;
    Ok(t)
}

/// Times each report command named in `reports` on the database `db`, `repeat` times each:
/// (name, median seconds).
fn time_reports(
    db: &Path,
    dir: &Path,
    reports: &[String],
    repeat: usize,
    jobs_n: usize,
) -> Result<Vec<(String, f64)>, String> {
    let bin = wetgran_binary()?;
    let d = db.display().to_string();
    let svg = dir.join("plot.svg").display().to_string();
    let csv = dir.join("export.csv").display().to_string();
    // `wetgran CMD --db DB --sweep bench EXTRA...`
    let on_sweep = |cmd, extra| [vec![cmd, "--db", &d, "--sweep", "bench"], extra].concat();
    let commands: Vec<(&str, Vec<&str>)> = vec![
        ("sweep status", vec!["sweep", "status", "--db", &d]),
        ("boundaries", on_sweep("boundaries", vec![])),
        ("plot", on_sweep("plot", vec!["-o", &svg])),
        (
            "export (CSV to a file)",
            on_sweep("export", vec!["-o", &csv]),
        ),
        ("reclassify", on_sweep("reclassify", vec![])),
    ];
    let out = dir.join("stdout.txt");
    let mut timed = Vec::new();
    for (name, args) in &commands {
        if !reports.iter().any(|r| name.contains(r.as_str())) {
            continue;
        }
        let mut times = Vec::new();
        for _ in 0..repeat {
            times.push(time_command(&bin, args, &out)?);
        }
        let t = quantile(&times, 0.5);
        eprintln!("N = {jobs_n}: {name} {t:.3} s");
        timed.push((name.to_string(), t));
    }
    Ok(timed)
}

/// Runs the benchmark at one size in `dir`.
pub(crate) fn measure(n: usize, o: &Options, dir: &Path) -> Result<Figures, String> {
    let (reports, durability) = (&o.reports, o.durability());
    let (file, jobs) = prepare(n, dir)?;
    let jobs_n = jobs.len();
    let (real, real_s) = timed(|| real_result(&jobs[0].spec))?;
    let real_decided_on = real.decided_on.clone();
    let obs_bytes = real.observables.to_string().len();
    let state_bytes = real
        .checkpoint
        .as_ref()
        .map_or(0, |s| serde_json::to_string(s).map_or(0, |t| t.len()));
    eprintln!(
        "N = {jobs_n}: one real job {:.1} ms, observables {obs_bytes} B, final state \
         {state_bytes} B",
        real_s * 1e3
    );

    let db = dir.join("bench.sqlite");
    let store = Store::open_as(&db, true, durability).map_err(e)?;
    let (sweep, register_s) = timed(|| store.register_sweep(&file, &jobs))?;

    let refine = reports.iter().any(|r| r == "refine");
    let mut observables = real.observables.clone();
    if refine && let Some(trend) = observables.get_mut("trend") {
        trend["unrelaxed"] = serde_json::json!([]);
        for key in ["tests", "region_tests"] {
            for t in trend[key].as_array_mut().into_iter().flatten() {
                t["agree"] = true.into();
                t["no_trend"] = true.into();
                t["drift"] = 0.0.into();
                t["block_means"] = serde_json::json!([0.0, 0.0]);
            }
        }
    }
    let starts = Arc::new(Mutex::new(Vec::with_capacity(jobs_n)));
    let job = {
        let starts = starts.clone();
        let result = JobResult {
            observables,
            wall_seconds: 0.0,
            ..real
        };
        stand_in(result, move |_| {
            starts
                .lock()
                .expect("no panic holds it")
                .push(Instant::now());
            Ok(())
        })
    };
    let opts = run_options(o.workers.max(1));
    let sweeps = std::slice::from_ref(&sweep);
    let (summary, run_s) = timed(|| run_sweeps_with(&store, sweeps, &opts, job.clone()))?;
    if summary.done as usize != jobs_n {
        return Err(format!("{} of {jobs_n} jobs done", summary.done));
    }
    let db_bytes = size(&db) + size(&dir.join("bench.sqlite-wal"));
    let end_of_run_relabel_s = if refine {
        let t = end_of_run_relabel(&store, &sweep, &real_decided_on)?;
        eprintln!("N = {jobs_n}: relabelling at the end of the run {t:.3} s");
        Some(t)
    } else {
        None
    };
    drop(store);

    let starts = starts.lock().expect("no panic holds it").clone();
    let gaps: Vec<f64> = starts
        .windows(2)
        .map(|w| (w[1] - w[0]).as_secs_f64() * 1e3)
        .collect();
    let tenth = (gaps.len() / 10).max(1).min(gaps.len());
    let (first, last) = (&gaps[..tenth], &gaps[gaps.len() - tenth..]);

    let timed = time_reports(&db, dir, reports, o.repeat.max(1), jobs_n)?;
    let refine = if refine {
        let store = Store::open_as(&db, false, durability).map_err(e)?;
        let r = refine_round(&store, &file, &sweep, job, &opts)?;
        eprintln!("N = {jobs_n}: refinement round {r:?}");
        Some(r)
    } else {
        None
    };
    Ok(Figures {
        jobs: jobs_n,
        register_s,
        run_s,
        gap_first_ms: (quantile(first, 0.5), quantile(first, 0.99)),
        gap_last_ms: (quantile(last, 0.5), quantile(last, 0.99)),
        db_bytes_per_result: db_bytes as f64 / jobs_n as f64,
        reports: timed,
        refine,
        end_of_run_relabel_s,
    })
}

/// The table of figures.
pub fn text(rows: &[Figures], workers: usize, durability: Durability) -> String {
    use std::fmt::Write as _;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "orchestrator: stand-in jobs of the real result shape, {workers} worker(s), file \
         database, commits {}",
        match durability {
            Durability::Synced => "synced (synchronous = FULL)",
            Durability::Fast => "without a sync (synchronous = NORMAL, as `sweep run`)",
        }
    );
    s.push_str("    jobs register s     run s   claims/s  ms per job gap first med/p99  gap last med/p99   kB/result\n");
    for r in rows {
        let _ = writeln!(
            s,
            "{:>8} {:>10.2} {:>9.2} {:>10.0} {:>11.3} {:>8.3}/{:<8.3} {:>8.3}/{:<8.3} {:>11.1}",
            r.jobs,
            r.register_s,
            r.run_s,
            r.jobs as f64 / r.run_s,
            r.run_s / r.jobs as f64 * 1e3,
            r.gap_first_ms.0,
            r.gap_first_ms.1,
            r.gap_last_ms.0,
            r.gap_last_ms.1,
            r.db_bytes_per_result / 1e3
        );
    }
    let _ = writeln!(s, "reports (median seconds, `wetgran` process included):");
    for r in rows {
        let parts: Vec<String> = r
            .reports
            .iter()
            .map(|(name, t)| format!("{name} {t:.3}"))
            .collect();
        let _ = writeln!(s, "{:>8}  {}", r.jobs, parts.join(", "));
    }
    for r in rows {
        if let Some(t) = r.end_of_run_relabel_s {
            let _ = writeln!(
                s,
                "{:>8}  relabelling at the end of `sweep run` (every result new): {t:.3} s",
                r.jobs
            );
        }
        if let Some(f) = &r.refine {
            let _ = writeln!(
                s,
                "{:>8}  refinement round: {} job(s) added; relabel the lines of the new results {:.3} s, read rows and plan \
                 {:.3} s, add jobs {:.3} s, run them {:.3} s; {:.3} s in all",
                r.jobs,
                f.added,
                f.relabel_s,
                f.plan_s,
                f.add_s,
                f.run_s,
                f.relabel_s + f.plan_s + f.add_s + f.run_s
            );
        }
    }
    s
}

/// Runs every size, each in a fresh folder under `dir` (default: the system's temporary folder),
/// removed afterwards unless `keep` (then its path is printed, for profiling a report on it).
pub fn run(o: &Options) -> Result<String, String> {
    let mut rows = Vec::new();
    for &n in &o.sizes {
        let tmp = temp_dir(o.dir.as_deref())?;
        rows.push(measure(n, o, tmp.path())?);
        if o.keep {
            eprintln!("N = {n}: database kept in {}", tmp.keep().display());
        }
    }
    Ok(text(&rows, o.workers.max(1), o.durability()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grids_have_the_asked_size_where_it_factors() {
        assert_eq!(grid(1000), (25, 40));
        assert_eq!(grid(10_000), (100, 100));
        assert_eq!(grid(100_000), (250, 400));
        assert_eq!(grid(7), (1, 7));
    }
}
