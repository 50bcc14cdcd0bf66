//! The sweep commands: `sweep run|resume|status|expand|job` (`refine` is in `refine_cmd`,
//! `submit|collect` in `cluster_cmd`), `boundaries` (`plot` is in `report_cmd`, `export` in
//! `export_cmd`).
//! Exit codes: 0 ok, 2 bad input (sweep file, database that is not wetgran's or is damaged,
//! unknown sweep), 1 any other error.

use super::common::{
    DEFAULT_DB, DbSweeps, Failure, Workers, available_cores, check_regrid, continue_refinement,
    load_sweep, note, print_json, read_spec, register, relabel_lines, select, show,
};
use crate::boundary::{Extraction, Observation, PhaseMap, phase_map_with};
use crate::report::boundaries_text::{boundaries_csv, boundaries_table};
use crate::report::cluster_text::slurm_status_text;
use crate::report::sensitivity::{sensitivity, sensitivity_csv, sensitivity_text};
use crate::report::sweep_text::extended_text;
use crate::report::sweep_text::{
    StatusInput, coords_text, estimate_failed_text, estimate_head_text, estimate_sample_text,
    estimate_stored_text, estimate_text, sweep_status_json, sweep_status_text,
};
use crate::run::extend::extend_unconverged;
use crate::run::{RunOptions, run_sweeps};
use crate::store::{Durability, PointSummary, Store, SweepRow};
use crate::sweep::job::ExtendTo;
use crate::sweep::run_job;
use crate::terminal::{escape, escape_lines};
use clap::{Args, Subcommand, ValueEnum};
use std::path::{Path, PathBuf};

#[derive(Debug, Subcommand)]
pub enum SweepCommand {
    /// Register a sweep file in the database and run its pending jobs.
    ///
    /// The sweep file (TOML) names a base scene, the axes (lists, linear or log ranges over any
    /// scene key, `box.size[0]` for an array entry; gamma, e_star, e_d_star, f_max, l_x are short names), replicas and the run length
    /// in driving periods; see sweeps/quickstart.toml. Every grid point and replica becomes a job
    /// whose id is the hash of its canonical spec: jobs already computed (by this or any other
    /// sweep in the database) are not run again. Each finished job is committed on its own, so
    /// an interrupted run loses at most the jobs that were running; `sweep resume` continues it.
    /// Progress: bars on a terminal, one line per finished job otherwise. Exit status 4 when the
    /// sweep ran to its end but some jobs failed (`sweep status` says why).
    Run(RunArgs),
    /// Continue interrupted sweeps: re-queue the jobs of runners that died, run what is pending.
    ///
    /// Jobs that were running under a process that no longer exists (same host) or whose
    /// runner has not sent a heartbeat for 60 s are put back in the queue; finished jobs are
    /// never recomputed. Without NAME every sweep in the database is continued.
    Resume(ResumeArgs),
    /// Per sweep: jobs by state, failures with their message, time spent and time left.
    ///
    /// A running job whose runner is gone (its process no longer exists on this host) or silent
    /// (no heartbeat for 60 s) is shown as stale, with its heartbeat's age: `sweep resume`
    /// runs it again.
    Status {
        /// Print JSON (an array, one object per sweep) instead of the text.
        #[arg(long)]
        json: bool,
        /// Database file; also from WETGRAN_DB (the flag wins).
        #[arg(long, env = "WETGRAN_DB", default_value = DEFAULT_DB)]
        db: PathBuf,
    },
    /// Print the jobs a sweep file expands to, without running anything.
    ///
    /// One JSON object per line: id, point, replica, coords, and with --specs the canonical job
    /// spec (what `sweep job` runs).
    Expand {
        file: PathBuf,
        /// Include each job's full canonical spec (what `sweep job` runs).
        #[arg(long)]
        specs: bool,
    },
    /// Estimate what a sweep costs from a few sampled jobs and the stored results.
    ///
    /// Runs a few of its jobs (spread over the grid) for a few driving periods each, one at a
    /// time, after some settling periods, and measures their wall time per simulated time
    /// unit. Each job then costs the rate of the nearest sampled (or stored) job times its run
    /// length: its first check (the minimum), its cap, and, when `--db` holds finished jobs of
    /// the sweep (same ids: a line of it run first), the run length those actually needed.
    /// The wall time on the cores replays the runner's claim order (chains wait for their
    /// predecessors; a lone long job at the end is a tail). Writes nothing to any database.
    Estimate(EstimateArgs),
    /// Refine a sweep's phase boundaries: add points where neighbours differ in phase.
    ///
    /// In rounds: the stored points are Delaunay-triangulated in the plane of the phase map
    /// (log axes in decades); every edge between two phases longer than the resolution is split
    /// at its midpoint, or, where the replicas of an end disagree, that end gets more replicas.
    /// The new jobs run with the same scheduler and store. Stops at the budget or when every
    /// boundary edge is resolved. Interrupted, `sweep resume` runs the jobs of the round it was
    /// in, and continues up to the budget of a `[refine]` table (`--budget` is what one call
    /// adds: a second call adds that many again).
    Refine(super::refine_cmd::RefineArgs),
    /// Submit a sweep to a Slurm cluster as job arrays.
    ///
    /// Registers the jobs in the database, writes their self-contained specs and an sbatch array
    /// script into the sweep directory (default: `wetgran-slurm/<sweep name>` beside the
    /// database; it must be on a filesystem the compute nodes share, as must the wetgran
    /// executable) and submits it with sbatch. Each task runs `wetgran job run SPEC --out RESULT`
    /// and never opens the database. More jobs than the array limit (the smaller of
    /// --array-limit and the cluster's MaxArraySize) are split into several arrays. Submitting
    /// again first collects what finished, then submits only the jobs that are not done and not
    /// queued: the failed, missing and corrupt ones.
    Submit(super::cluster_cmd::SubmitArgs),
    /// Read the results of submitted Slurm tasks into the database.
    ///
    /// Idempotent: a result already stored is not stored again. Reports failed tasks (with the
    /// job's error), corrupt result files, and missing ones (no result and no longer queued:
    /// killed at a limit, node failure); `sweep submit` submits those again. Exit status 4 when
    /// failed or lost jobs remain (tasks still queued are no failure).
    Collect(DbSweeps),
    /// Run one job spec and print its result as JSON.
    ///
    /// The spec is JSON as printed by `sweep expand --specs` (a whole line or its `spec`); the
    /// same function the workers call, for running a job on another machine.
    Job {
        /// A file with the job spec (`-` for standard input).
        spec: PathBuf,
    },
}

#[derive(Debug, Args)]
pub struct RunArgs {
    /// The sweep file.
    file: PathBuf,
    /// Database file (created if missing); also from WETGRAN_DB (the flag wins).
    #[arg(long, env = "WETGRAN_DB", default_value = DEFAULT_DB)]
    pub db: PathBuf,
    #[command(flatten)]
    workers: Workers,
    /// Put the failed jobs of this sweep back in the queue first.
    #[arg(long)]
    retry_failed: bool,
    /// Allow a sweep name already in the database to get a different grid (its points not
    /// in the new grid leave the sweep; their results stay in the database).
    #[arg(long)]
    replace: bool,
}

#[derive(Debug, Args)]
#[command(mut_arg("jobs", |a| a.help(
    "Worker threads, one simulation each, for the pending jobs, then the refinement of a \
     `[refine]` table and the runs of --extend: 1 to the available cores (default: all of them)"
)))]
pub struct ResumeArgs {
    /// The sweep to continue (default: all).
    name: Option<String>,
    /// Database file; also from WETGRAN_DB (the flag wins).
    #[arg(long, env = "WETGRAN_DB", default_value = DEFAULT_DB)]
    pub db: PathBuf,
    #[command(flatten)]
    workers: Workers,
    /// Put failed jobs back in the queue first.
    #[arg(long)]
    retry_failed: bool,
    /// Afterwards, run the unconverged finished jobs further from their checkpoints, up
    /// to this many driving periods of total run (docs/observables.md).
    #[arg(long, value_name = "MAX_PERIODS", conflicts_with = "extend_time")]
    extend: Option<f64>,
    /// The same with the total run in time units `sqrt(d/g)` (at high Gamma a period is
    /// short, and the run policy counts in time).
    #[arg(long, value_name = "MAX_TIME")]
    extend_time: Option<f64>,
}

#[derive(Debug, Args)]
pub struct EstimateArgs {
    file: PathBuf,
    /// Driving periods timed per sampled job.
    #[arg(long, default_value_t = 2.0)]
    periods: f64,
    /// Simulated time units `sqrt(d/g)` each sampled job runs untimed first: a hot start
    /// cools and a bed settles, and the cost per period changes (0: time from the start).
    #[arg(long, default_value_t = 20.0)]
    settle: f64,
    /// Number of jobs to sample; a sweep with several start modes (`initial.start` axis)
    /// shares them out among the modes, at least one each.
    #[arg(long, default_value_t = 6)]
    samples: usize,
    /// Cores the estimate is for (default: the available cores).
    #[arg(long)]
    cores: Option<usize>,
    /// A database whose finished jobs of this sweep count with their measured cost and run
    /// length (any sweep's jobs with the same ids); may be given more than once.
    #[arg(long)]
    pub db: Vec<PathBuf>,
}

/// Output format of `boundaries`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum BoundaryFormat {
    Table,
    Json,
    Csv,
}

pub(super) fn sweep_run(a: RunArgs, hooks: &super::Hooks) -> Result<(), Failure> {
    let (opts, db) = (a.workers.options_with(hooks)?, &a.db);
    // The file is checked in full before the database is touched.
    let (sweep, expanded, left_out) = load_sweep(&a.file)?;
    // A local run commits without a sync per transaction (docs/reliability.md, "Commits without
    // a sync"): everything it writes can be made again from the sweep file.
    let store = Store::open_as(db, true, Durability::Fast)?.with_write_hook(hooks.write.clone());
    if let Ok(old) = store.sweep(&sweep.name) {
        check_regrid(&store, &old, &sweep, &expanded, a.replace)?;
    }
    // Until it is registered there is nothing to resume: Ctrl-C rolls the registration back.
    let row = register(&store, &sweep, &expanded)?;
    super::interrupt::resume_hint_on_interrupt(Some(&sweep.name), db);
    store.set_left_out(row.id, &left_out)?;
    // Results shared with an earlier registration get this file's `[classify]` thresholds.
    let relabelled = crate::run::relabel::relabel_stored(&store, std::slice::from_ref(&row), None)?;
    if relabelled.changed() > 0 {
        show(&format!(
            "sweep {}: {}\n",
            escape(&row.name),
            relabelled.text()
        ));
    }
    let rows = [row];
    run_and_report(&store, &rows, &opts, a.retry_failed)?;
    continue_refinement(&store, &rows, &opts)?;
    fail_if_jobs_failed(&store, &rows)
}

/// After a run: `Failure::JobsFailed` (exit status 4) when any job of `sweeps` is stored as
/// failed, so that a script (`sweep run F && boundaries`) does not take a partial diagram for
/// a whole one. The finished jobs are stored either way.
fn fail_if_jobs_failed(store: &Store, sweeps: &[SweepRow]) -> Result<(), Failure> {
    let mut failed = 0;
    for s in sweeps {
        failed += store.counts(s.id)?.failed;
    }
    if failed == 0 {
        return Ok(());
    }
    Err(Failure::JobsFailed(format!(
        "{failed} job(s) failed (the others are stored): `wetgran sweep status --db {}` shows \
         why, `wetgran sweep resume --retry-failed` runs them again",
        store.path().display()
    )))
}

pub(super) fn sweep_resume(a: ResumeArgs, hooks: &super::Hooks) -> Result<(), Failure> {
    let (opts, db) = (a.workers.options_with(hooks)?, &a.db);
    let extend = a
        .extend
        .map(ExtendTo::Periods)
        .or(a.extend_time.map(ExtendTo::Time));
    let store = Store::open_as(db, false, Durability::Fast)?.with_write_hook(hooks.write.clone());
    super::interrupt::resume_hint_on_interrupt(a.name.as_deref(), db);
    let sweeps = select(&store, a.name.as_deref())?;
    if sweeps.is_empty() {
        return Err(Failure::BadInput(format!(
            "{}: no sweep in this database: start one with `wetgran sweep run FILE`",
            db.display()
        )));
    }
    run_and_report(&store, &sweeps, &opts, a.retry_failed)?;
    continue_refinement(&store, &sweeps, &opts)?;
    if let Some(cap) = extend {
        extend_and_report(&store, &sweeps, cap, &opts)?;
        for s in &sweeps {
            relabel_lines(&store, s)?;
        }
    }
    fail_if_jobs_failed(&store, &sweeps)
}

/// `sweep resume --extend MAX_PERIODS` (or `--extend-time MAX_TIME`): checks the cap, extends
/// every unconverged job of `sweeps` that has a checkpoint to at most `cap` of total run through
/// the worker pool of every run (`run::extend`) and prints a summary.
fn extend_and_report(
    store: &Store,
    sweeps: &[SweepRow],
    cap: ExtendTo,
    opts: &RunOptions,
) -> Result<(), Failure> {
    let v = cap.value();
    if !(v.is_finite() && v > 0.0) {
        let (flag, unit) = match cap {
            ExtendTo::Periods(_) => ("--extend", "periods"),
            ExtendTo::Time(_) => ("--extend-time", "time units"),
        };
        return Err(Failure::BadInput(format!(
            "{flag} = {v} is out of range: must be a finite number of {unit} > 0"
        )));
    }
    let s = extend_unconverged(store, sweeps, cap, opts)?;
    print!(
        "{}",
        escape_lines(&extended_text(
            s.extended,
            s.converged,
            s.skipped,
            &cap.describe(),
            &s.failed
        ))
    );
    if s.failed.is_empty() {
        Ok(())
    } else {
        // The extensions that worked are stored; the exit status says that some did not.
        Err(Failure::JobsFailed(format!(
            "{} extension(s) failed (the others are stored)",
            s.failed.len()
        )))
    }
}

fn run_and_report(
    store: &Store,
    sweeps: &[SweepRow],
    opts: &RunOptions,
    retry: bool,
) -> Result<(), Failure> {
    let opts = RunOptions {
        retry_failed: retry,
        ..opts.clone()
    };
    let summary = run_sweeps(store, sweeps, &opts)?;
    // A result, on stdout with the job lines (`run::progress`).
    println!(
        "finished: {} job(s) done, {} failed{} in {:.1} s",
        summary.done,
        summary.failed,
        if summary.discarded > 0 {
            format!(", {} dropped (finished elsewhere first)", summary.discarded)
        } else {
            String::new()
        },
        summary.wall_seconds
    );
    for s in sweeps {
        relabel_lines(store, s)?;
        let c = store.counts(s.id)?;
        if c.failed > 0 {
            note(&format!(
                "sweep {}: {} failed job(s): see `wetgran sweep status --db {}`; \
                 `--retry-failed` runs them again",
                escape(&s.name),
                c.failed,
                store.path().display()
            ));
        }
    }
    Ok(())
}

/// `sweep status` of every sweep of the database: the text (without the Slurm part), or with
/// `json` one JSON array of the sweeps (`sweep_status_json`, each with its Slurm tasks' text
/// under `slurm`).
pub(super) fn sweep_status(db: &Path, json: bool) -> Result<(), Failure> {
    let store = Store::open_read_only(db)?;
    let sweeps = store.sweeps()?;
    if sweeps.is_empty() && !json {
        show(&format!("{}: no sweeps yet\n", store.path().display()));
    }
    let cores = available_cores();
    let now = crate::store::now();
    let mut all = Vec::new();
    for s in &sweeps {
        let (points, spent) = store.status_summaries(s)?;
        let running = store.running_jobs(s.id)?;
        let input = StatusInput {
            sweep: s,
            counts: crate::store::StateCounts::of_summaries(&points),
            points: &points,
            spent,
            cores,
            running: &running,
            now,
        };
        let tasks = store.tasks(s.id)?;
        let slurm = (!tasks.is_empty()).then(|| {
            let queue = crate::cluster::queue_states(&tasks, &mut crate::cluster::slurm::squeue);
            slurm_status_text(&tasks, &queue)
        });
        if json {
            let mut v = sweep_status_json(&input);
            v["slurm"] = slurm.into();
            all.push(v);
        } else {
            show(&sweep_status_text(&input));
            if let Some(slurm) = slurm {
                show(&format!("sweep {} on Slurm\n", escape(&s.name)));
                show(&slurm);
            }
        }
    }
    if json {
        print_json(&all);
    }
    Ok(())
}

pub(super) fn sweep_expand(file: &Path, specs: bool) -> Result<(), Failure> {
    let (_, jobs, _) = load_sweep(file)?;
    for j in &jobs {
        let mut line = serde_json::json!({
            "id": j.id, "point": j.point, "replica": j.replica, "coords": j.coords,
        });
        if let Some(prev) = &j.spec.start_from {
            // A continuation job: the job whose final state it starts from.
            line["continues"] = serde_json::json!(prev);
        }
        if specs {
            line["spec"] = serde_json::from_str(&j.spec.canonical_json()).expect("valid JSON");
        }
        println!("{line}");
    }
    Ok(())
}

pub(super) fn sweep_estimate(a: EstimateArgs) -> Result<(), Failure> {
    use crate::sweep::estimate::{
        RateSample, cost_lines, measured_runs, planned_jobs, sample_picks, sample_spec, time_sample,
    };
    let (file, periods, settle, samples) = (&a.file, a.periods, a.settle, a.samples);
    let cores = match a.cores {
        Some(0) => {
            return Err(Failure::BadInput(
                "--cores 0 is out of range: must be >= 1".to_string(),
            ));
        }
        c => c.unwrap_or_else(available_cores),
    };
    if !(periods.is_finite() && periods > 0.0) || samples == 0 {
        return Err(Failure::BadInput(
            "--periods must be > 0 and --samples >= 1".to_string(),
        ));
    }
    if !(settle.is_finite() && settle >= 0.0) {
        return Err(Failure::BadInput("--settle must be >= 0".to_string()));
    }
    let (sweep, mut jobs, _) = load_sweep(file)?;
    // One job per id, as the store registers them: a continuation chain's head is the hot job
    // of its point when the sweep also has the hot start (same spec, same id).
    let mut seen = std::collections::HashSet::new();
    jobs.retain(|j| seen.insert(j.id.clone()));
    let mut stored = std::collections::HashMap::new();
    for path in &a.db {
        stored.extend(Store::open_read_only(path)?.finished_job_costs()?);
    }
    let planned = planned_jobs(&sweep, &jobs, &stored);
    // Every start mode is sampled (a hot and a cold branch cost different rates).
    let starts: Vec<String> = planned.iter().map(|j| j.start.clone()).collect();
    let picks = sample_picks(&starts, samples);
    show(&estimate_head_text(
        &file.display().to_string(),
        jobs.len(),
        picks.len(),
        periods,
        settle,
    ));
    let labels: Vec<&str> = sweep.axes.iter().map(|a| a.label.as_str()).collect();
    let mut rates = Vec::new();
    for &k in &picks {
        let coords = coords_text(&labels, &jobs[k].coords);
        if let Some(m) = planned[k].measured {
            // The database has its run: its rate is known, nothing to sample.
            show(&estimate_stored_text(
                &coords,
                m.wall_seconds / m.simulated_time,
            ));
            continue;
        }
        let spec = sample_spec(&sweep, &jobs[k], settle, periods);
        match time_sample(&spec, settle, &super::common::all_cores()) {
            Ok(r) => {
                let rate = r.seconds_per_time;
                rates.push(RateSample {
                    position: planned[k].position.clone(),
                    seconds_per_time: rate,
                    start: planned[k].start.clone(),
                });
                show(&estimate_sample_text(
                    &coords,
                    rate * spec.period(),
                    rate,
                    r.events,
                ));
            }
            Err(e) => show(&estimate_failed_text(&coords, &e.to_string())),
        }
    }
    let measured = measured_runs(&planned);
    if rates.is_empty() && measured.is_none() {
        return Err(Failure::Other("every sampled job failed".to_string()));
    }
    let policy = jobs.iter().any(|j| j.spec.scene.convergence.is_some());
    let (lines, by_start) = cost_lines(&planned, &rates, measured.as_ref(), policy, cores);
    show(&estimate_text(
        jobs.len(),
        cores,
        measured.as_ref(),
        &lines,
        &by_start,
        settle,
        periods,
    ));
    Ok(())
}

pub(super) fn sweep_job(path: &Path) -> Result<(), Failure> {
    let spec = read_spec(path)?;
    let result = run_job(&spec, &super::common::all_cores(), &mut |_| {})
        .map_err(|e| Failure::Other(e.to_string()))?;
    let out = serde_json::json!({ "id": spec.id(), "result": result });
    print_json(&out);
    Ok(())
}

/// The phase map of a sweep from its stored results (`points`: its
/// `Store::point_summaries`), each point with the criterion that decided its label.
pub(super) fn sweep_map(
    store: &Store,
    sweep: &SweepRow,
    points: &[PointSummary],
    how: Extraction,
) -> Result<PhaseMap, Failure> {
    let decided = store.decisions(sweep.id)?;
    let obs: Vec<Observation> = points
        .iter()
        .map(|p| Observation {
            decided_by: decided.get(&p.job_id).cloned(),
            ..Observation::of_summary(p)
        })
        .collect();
    phase_map_with(&sweep.axes, &obs, how)
        .map_err(|e| Failure::BadInput(format!("sweep {}: {e}", escape(&sweep.name))))
}

#[derive(Debug, Args)]
pub struct BoundariesArgs {
    #[command(flatten)]
    pub from: super::common::DbPick,
    /// Print JSON (every sweep's map: points, labels, boundaries) instead of the table.
    #[arg(long, conflicts_with = "format")]
    json: bool,
    /// `table`, or `csv` (one row per boundary point); `json` is `--json`.
    #[arg(long, value_enum, default_value = "table")]
    format: BoundaryFormat,
    /// Let unconverged points (marked `?`) carry boundaries too; by default a boundary
    /// rests only on converged points.
    #[arg(long)]
    include_unconverged: bool,
    /// Instead of the map: relabel the sweep from its stored observables with each
    /// label-deciding threshold varied by 0.5 and by 2, one at a time, and print how far each
    /// boundary moves (docs/classification.md, "Sensitivity to the thresholds").
    #[arg(long)]
    sensitivity: bool,
}

pub(super) fn boundaries(a: BoundariesArgs) -> Result<(), Failure> {
    let how = Extraction {
        include_unconverged: a.include_unconverged,
    };
    let store = Store::open_read_only(&a.from.db)?;
    let sweeps = a.from.select(&store)?;
    let format = if a.json {
        BoundaryFormat::Json
    } else {
        a.format
    };
    if a.sensitivity {
        return boundaries_sensitivity(&store, &sweeps, how, format);
    }
    let mut maps = Vec::new();
    let mut points = Vec::new();
    for s in &sweeps {
        let p = store.point_summaries(s)?;
        maps.push((s, sweep_map(&store, s, &p, how)?));
        points.push(p);
    }
    match format {
        BoundaryFormat::Json => {
            let v: Vec<_> = maps
                .iter()
                .map(|(s, m)| serde_json::json!({"sweep": s.name, "map": m}))
                .collect();
            print_json(&v);
        }
        BoundaryFormat::Csv => print!("{}", boundaries_csv(&maps)),
        BoundaryFormat::Table => show(&boundaries_table(&maps, &points, how)),
    }
    Ok(())
}

/// `wetgran upgrade`: applies this wetgran's migrations and job-id rule to a database written by
/// an older one (`Store::upgrade`) and says what it did.
pub(super) fn upgrade(db: &Path) -> Result<(), Failure> {
    match Store::upgrade(db)? {
        None => show(&format!(
            "{}: up to date (written by this wetgran's schema); nothing was changed\n",
            db.display()
        )),
        Some(what) => show(&format!("{}: upgraded ({what} before)\n", db.display())),
    }
    Ok(())
}

/// `boundaries --sensitivity` (`report::sensitivity`).
fn boundaries_sensitivity(
    store: &Store,
    sweeps: &[SweepRow],
    how: Extraction,
    format: BoundaryFormat,
) -> Result<(), Failure> {
    let mut all = Vec::new();
    for s in sweeps {
        let (rows, summaries) = (store.points(s.id)?, store.point_summaries(s)?);
        all.push(sensitivity(s, &rows, &summaries, how).map_err(Failure::BadInput)?);
    }
    match format {
        BoundaryFormat::Json => print_json(&all),
        BoundaryFormat::Csv => print!("{}", sensitivity_csv(&all)),
        BoundaryFormat::Table => {
            for s in &all {
                println!("{}", sensitivity_text(s));
            }
        }
    }
    Ok(())
}
