//! The sweep commands: `sweep run|resume|status|expand|job|refine` (and `submit|collect`, in
//! `cluster_cmd`), `boundaries`, `plot`, `export`.
//! Exit codes: 0 ok, 2 bad input (sweep file, database that is not wetgran's or is damaged,
//! unknown sweep), 1 any other error.

use crate::boundary::{Extraction, Observation, PhaseMap, phase_map_with};
use crate::report::{export, plot_phase};
use crate::run::runner::{point_label, short};
use crate::run::{RunOptions, run_sweeps};
use crate::sim::event_driven::table_cache::DEFAULT_TABLE_CACHE_MIB;
use crate::store::{LeftOut, Store, StoreError, SweepRow};
use crate::sweep::{SweepFile, run_job};
use clap::{Subcommand, ValueEnum};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// Default database file, in the working directory.
pub const DEFAULT_DB: &str = "wetgran.sqlite";

/// `wetgran sweep ...`.
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
    /// Progress: bars on a terminal, one line per finished job otherwise.
    Run {
        /// The sweep file.
        file: PathBuf,
        /// Database file (created if missing).
        #[arg(long, default_value = DEFAULT_DB)]
        db: PathBuf,
        /// Worker threads, one simulation each: 1 to the available cores (default: all of them).
        #[arg(long)]
        jobs: Option<usize>,
        /// Allow --jobs above the available cores (several simulations share a core; each
        /// runs slower, the sweep no faster).
        #[arg(long)]
        oversubscribe: bool,
        /// Put the failed jobs of this sweep back in the queue first.
        #[arg(long)]
        retry_failed: bool,
        /// Allow a sweep name already in the database to get a different grid (its points not
        /// in the new grid leave the sweep; their results stay in the database).
        #[arg(long)]
        replace: bool,
        /// Cap of the wall-table cache in MiB (`table` wall solver): least recently used
        /// tables are dropped beyond it; about 27 MiB per drive at 128 x 128 cells; 0: no
        /// caching.
        #[arg(long, value_name = "MIB", default_value_t = DEFAULT_TABLE_CACHE_MIB)]
        table_cache_mib: usize,
    },
    /// Continue interrupted sweeps: re-queue the jobs of runners that died, run what is pending.
    ///
    /// Jobs that were running under a process that no longer exists (same host) or whose
    /// runner has not sent a heartbeat for 60 s are put back in the queue; finished jobs are
    /// never recomputed. Without NAME every sweep in the database is continued.
    Resume {
        /// The sweep to continue (default: all).
        name: Option<String>,
        #[arg(long, default_value = DEFAULT_DB)]
        db: PathBuf,
        /// Worker threads (default: the available cores).
        #[arg(long)]
        jobs: Option<usize>,
        /// Allow --jobs above the available cores (several simulations share a core; each
        /// runs slower, the sweep no faster).
        #[arg(long)]
        oversubscribe: bool,
        /// Put failed jobs back in the queue first.
        #[arg(long)]
        retry_failed: bool,
        /// Afterwards, run the unconverged finished jobs further from their checkpoints, up
        /// to this many driving periods of total run (docs/observables.md).
        #[arg(long, value_name = "MAX_PERIODS")]
        extend: Option<f64>,
        /// Cap of the wall-table cache in MiB (`table` wall solver): least recently used
        /// tables are dropped beyond it; about 27 MiB per drive at 128 x 128 cells; 0: no
        /// caching.
        #[arg(long, value_name = "MIB", default_value_t = DEFAULT_TABLE_CACHE_MIB)]
        table_cache_mib: usize,
    },
    /// Per sweep: jobs by state, failures with their message, time spent and time left.
    Status {
        #[arg(long, default_value = DEFAULT_DB)]
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
    /// Estimate what a sweep costs from a few sampled jobs.
    ///
    /// Runs a few of its jobs (spread over the grid) for a few driving periods each, one at a
    /// time, and scales the measured wall time per period to the sweep's run length and job
    /// count. Writes nothing to any database.
    Estimate {
        file: PathBuf,
        /// Driving periods to run per sampled job (after a transient of none).
        #[arg(long, default_value_t = 2.0)]
        periods: f64,
        /// Number of jobs to sample.
        #[arg(long, default_value_t = 6)]
        samples: usize,
        /// Cores the estimate is for (default: the available cores).
        #[arg(long)]
        cores: Option<usize>,
    },
    /// Refine a sweep's phase boundaries: add points where neighbours differ in phase.
    ///
    /// In rounds: the stored points are Delaunay-triangulated in the plane of the phase map
    /// (log axes in decades); every edge between two phases longer than the resolution is split
    /// at its midpoint, or, where the replicas of an end disagree, that end gets more replicas.
    /// The new jobs run with the same scheduler and store. Stops at the budget or when every
    /// boundary edge is resolved. Interrupted, `sweep resume` runs the jobs of the round it was
    /// in, and continues up to the budget of a `[refine]` table (`--budget` is what one call
    /// adds: a second call adds that many again).
    Refine {
        /// The sweep (default: the only one in the database).
        #[arg(long)]
        sweep: Option<String>,
        #[arg(long, default_value = DEFAULT_DB)]
        db: PathBuf,
        /// Jobs to add (default: what is left of the sweep file's `[refine]` budget).
        #[arg(long)]
        budget: Option<usize>,
        /// Rounds the budget is split into (default: the file's, else 4).
        #[arg(long)]
        rounds: Option<usize>,
        /// Stop when every boundary edge spans at most this fraction of each axis' range
        /// (default: the file's, else 0: the budget only).
        #[arg(long)]
        resolution: Option<f64>,
        /// Most replicas a point whose replicas disagree is raised to (default: the file's,
        /// else 3 x sweep.replicas).
        #[arg(long)]
        max_replicas: Option<u32>,
        /// Worker threads (default: the available cores).
        #[arg(long)]
        jobs: Option<usize>,
        /// Allow --jobs above the available cores (several simulations share a core; each
        /// runs slower, the sweep no faster).
        #[arg(long)]
        oversubscribe: bool,
    },
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
    Submit {
        /// The sweep file.
        file: PathBuf,
        /// Submit with Slurm's sbatch (the only cluster backend).
        #[arg(long)]
        slurm: bool,
        /// Slurm partition (default: the cluster's).
        #[arg(long)]
        partition: Option<String>,
        /// Wall-time limit per task, as sbatch takes it (`30`, `2:00:00`, `1-00:00:00`).
        #[arg(long)]
        time: Option<String>,
        /// CPUs per task (a job is one simulation on one thread).
        #[arg(long, default_value_t = 1)]
        cpus_per_task: u32,
        /// Most tasks per array (default 1000, and never more than the cluster's MaxArraySize).
        #[arg(long)]
        array_limit: Option<usize>,
        /// Print the array script(s) and submit nothing (nothing is written).
        #[arg(long)]
        dry_run: bool,
        /// Database file (created if missing).
        #[arg(long, default_value = DEFAULT_DB)]
        db: PathBuf,
        /// The sweep directory (default: `wetgran-slurm/<sweep name>` beside the database).
        #[arg(long)]
        dir: Option<PathBuf>,
        /// Allow a registered sweep name to get a different grid (as `sweep run --replace`).
        #[arg(long)]
        replace: bool,
    },
    /// Read the results of submitted Slurm tasks into the database.
    ///
    /// Idempotent: a result already stored is not stored again. Reports failed tasks (with the
    /// job's error), corrupt result files, and missing ones (no result and no longer queued:
    /// killed at a limit, node failure); `sweep submit` submits those again.
    Collect {
        #[arg(long, default_value = DEFAULT_DB)]
        db: PathBuf,
        /// Only this sweep (default: all).
        #[arg(long)]
        sweep: Option<String>,
    },
    /// Run one job spec and print its result as JSON.
    ///
    /// The spec is JSON as printed by `sweep expand --specs` (a whole line or its `spec`); the
    /// same function the workers call, for running a job on another machine.
    Job {
        /// A file with the job spec (`-` for standard input).
        spec: PathBuf,
    },
}

/// Output format of `boundaries`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum BoundaryFormat {
    Table,
    Json,
    Csv,
}

/// Output format of `export`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ExportFormat {
    Csv,
    Json,
}

pub(super) enum Failure {
    BadInput(String),
    Other(String),
}

impl From<StoreError> for Failure {
    fn from(e: StoreError) -> Self {
        match e {
            StoreError::NotSqlite { .. }
            | StoreError::NotWetgran { .. }
            | StoreError::Damaged { .. }
            | StoreError::Missing { .. }
            | StoreError::NoSuchSweep { .. } => Failure::BadInput(e.to_string()),
            _ => Failure::Other(e.to_string()),
        }
    }
}

pub(super) fn exit(r: Result<(), Failure>) -> ExitCode {
    match r {
        Ok(()) => ExitCode::SUCCESS,
        Err(Failure::BadInput(m)) => {
            eprintln!("error: {m}");
            ExitCode::from(2)
        }
        Err(Failure::Other(m)) => {
            eprintln!("error: {m}");
            ExitCode::from(1)
        }
    }
}

/// The cores this process may use (`std::thread::available_parallelism`, 1 if unknown).
pub fn available_cores() -> usize {
    std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(1)
}

/// Worker threads for `--jobs N`: the available cores by default; `N` must be in
/// `[1, available cores]` unless `oversubscribe` (`--oversubscribe`) allows more.
pub fn workers(jobs: Option<usize>, oversubscribe: bool) -> Result<usize, String> {
    let cores = available_cores();
    match jobs {
        None => Ok(cores),
        Some(0) => Err(format!(
            "--jobs 0 is out of range: must be in [1, {cores}] (the available cores)"
        )),
        Some(n) if n > cores && !oversubscribe => Err(format!(
            "--jobs {n} is out of range: must be in [1, {cores}] (the available cores; one \
             simulation per worker); add --oversubscribe to start more workers than cores"
        )),
        Some(n) => Ok(n),
    }
}

fn workers_or_fail(jobs: Option<usize>, oversubscribe: bool) -> Result<usize, Failure> {
    workers(jobs, oversubscribe).map_err(Failure::BadInput)
}

/// Runs a `sweep` subcommand.
pub fn sweep(cmd: SweepCommand) -> ExitCode {
    exit(match cmd {
        SweepCommand::Run {
            file,
            db,
            jobs,
            oversubscribe,
            retry_failed,
            replace,
            table_cache_mib,
        } => workers_or_fail(jobs, oversubscribe)
            .and_then(|n| sweep_run(&file, &db, n, retry_failed, replace, table_cache_mib)),
        SweepCommand::Resume {
            name,
            db,
            jobs,
            oversubscribe,
            retry_failed,
            extend,
            table_cache_mib,
        } => workers_or_fail(jobs, oversubscribe).and_then(|n| {
            sweep_resume(
                name.as_deref(),
                &db,
                n,
                retry_failed,
                extend,
                table_cache_mib,
            )
        }),
        SweepCommand::Status { db } => sweep_status(&db),
        SweepCommand::Expand { file, specs } => sweep_expand(&file, specs),
        SweepCommand::Job { spec } => sweep_job(&spec),
        SweepCommand::Submit {
            file,
            slurm,
            partition,
            time,
            cpus_per_task,
            array_limit,
            dry_run,
            db,
            dir,
            replace,
        } => {
            if slurm {
                super::cluster_cmd::submit(
                    &file,
                    &db,
                    &super::cluster_cmd::Submit {
                        options: crate::cluster::slurm::SbatchOptions {
                            partition,
                            time,
                            cpus_per_task,
                        },
                        array_limit,
                        dry_run,
                        dir,
                        replace,
                    },
                )
            } else {
                Err(Failure::BadInput(
                    "sweep submit: give --slurm (the only cluster backend so far)".to_string(),
                ))
            }
        }
        SweepCommand::Collect { db, sweep } => {
            super::cluster_cmd::collect_cmd(&db, sweep.as_deref())
        }
        SweepCommand::Refine {
            sweep,
            db,
            budget,
            rounds,
            resolution,
            max_replicas,
            jobs,
            oversubscribe,
        } => workers_or_fail(jobs, oversubscribe).and_then(|n| {
            super::refine_cmd::refine(
                &db,
                sweep.as_deref(),
                super::refine_cmd::Overrides {
                    budget,
                    rounds,
                    resolution,
                    max_replicas,
                },
                n,
            )
        }),
        SweepCommand::Estimate {
            file,
            periods,
            samples,
            cores,
        } => match cores {
            Some(0) => Err(Failure::BadInput(
                "--cores 0 is out of range: must be >= 1".to_string(),
            )),
            c => sweep_estimate(&file, periods, samples, c.unwrap_or_else(available_cores)),
        },
    })
}

pub(super) fn load_sweep(file: &Path) -> Result<(SweepFile, Vec<crate::sweep::SweepJob>), Failure> {
    let (sweep, jobs, _) = load_sweep_left_out(file)?;
    Ok((sweep, jobs))
}

/// Loads and expands a sweep file; also returns the grid points `skip_invalid` left out, each
/// with the scene constraint it fails, after listing them on stderr.
pub(super) fn load_sweep_left_out(
    file: &Path,
) -> Result<(SweepFile, Vec<crate::sweep::SweepJob>, Vec<LeftOut>), Failure> {
    let sweep = SweepFile::load(file).map_err(|e| Failure::BadInput(e.to_string()))?;
    let (jobs, skipped) = sweep
        .expand_with_skips()
        .map_err(|e| Failure::BadInput(e.to_string()))?;
    let left_out: Vec<LeftOut> = skipped
        .iter()
        .map(|k| LeftOut {
            coords: k.coords.clone(),
            constraint: k
                .reason
                .constraint
                .map(|c| c.reason().to_string())
                .unwrap_or_default(),
            reason: k.reason.to_string(),
        })
        .collect();
    if !left_out.is_empty() {
        eprintln!(
            "{}: left out {} grid point(s) (sweep.skip_invalid: the scene fails a constraint):",
            file.display(),
            left_out.len()
        );
        eprint!("{}", left_out_text(&sweep.axes, &left_out));
    }
    if jobs.is_empty() {
        return Err(Failure::BadInput(format!(
            "{}: the sweep has no valid grid point",
            file.display()
        )));
    }
    Ok((sweep, jobs, left_out))
}

/// One line per left-out point: its coordinates and the constraint it fails.
pub fn left_out_text(axes: &[crate::sweep::Axis], left_out: &[LeftOut]) -> String {
    let mut out = String::new();
    for k in left_out {
        let coords: Vec<String> = axes
            .iter()
            .zip(&k.coords)
            .map(|(a, v)| match v.as_f64() {
                Some(x) => format!("{} = {}", a.label, short(x)),
                None => format!("{} = {v}", a.label),
            })
            .collect();
        let _ = writeln!(out, "  left out {}: {}", coords.join(", "), k.constraint);
    }
    out
}

fn sweep_run(
    file: &Path,
    db: &Path,
    jobs: usize,
    retry: bool,
    replace: bool,
    table_cache_mib: usize,
) -> Result<(), Failure> {
    // The file is checked in full before the database is touched.
    let (sweep, expanded, left_out) = load_sweep_left_out(file)?;
    let store = Store::open(db)?;
    if let Ok(old) = store.sweep(&sweep.name) {
        check_regrid(&store, &old, &sweep, &expanded, replace)?;
    }
    let row = store.register_sweep(&sweep, &expanded)?;
    store.set_left_out(row.id, &left_out)?;
    // Results shared with an earlier registration get this file's `[classify]` thresholds.
    let relabelled =
        super::reclassify_cmd::relabel_sweeps(&store, std::slice::from_ref(&row), None)?;
    if relabelled.changed() > 0 {
        eprintln!("sweep {}: {}", row.name, relabelled.text());
    }
    run_and_report(
        &store,
        std::slice::from_ref(&row),
        jobs,
        retry,
        table_cache_mib,
    )?;
    super::refine_cmd::continue_refinement(&store, &[row], jobs)
}

/// A sweep name registered before with another grid (axes or replicas) is refused unless
/// `--replace`: the error says what would be replaced.
pub(super) fn check_regrid(
    store: &Store,
    old: &SweepRow,
    sweep: &SweepFile,
    expanded: &[crate::sweep::SweepJob],
    replace: bool,
) -> Result<(), Failure> {
    let grid = |axes: &[crate::sweep::Axis], replicas: u32| {
        let mut parts: Vec<String> = axes
            .iter()
            .map(|a| {
                let v: Vec<String> = a.values.iter().map(|v| v.to_string()).collect();
                format!("{} = [{}]", a.label, v.join(", "))
            })
            .collect();
        parts.push(format!("{replicas} replica(s)"));
        parts.join("; ")
    };
    let same_axes = old.axes.len() == sweep.axes.len()
        && old
            .axes
            .iter()
            .zip(&sweep.axes)
            .all(|(a, b)| a.key == b.key && a.values == b.values);
    if (same_axes && old.replicas == sweep.replicas) || replace {
        return Ok(());
    }
    let new_ids: std::collections::HashSet<&str> = expanded.iter().map(|j| j.id.as_str()).collect();
    let points = store.points(old.id)?;
    let leaving: Vec<_> = points
        .iter()
        .filter(|p| !new_ids.contains(p.job_id.as_str()))
        .collect();
    let with_result = leaving.iter().filter(|p| p.observables.is_some()).count();
    Err(Failure::BadInput(format!(
        "{}: sweep `{}` is already in {} with another grid (registered from {}):\n  \
         old grid: {} ({} job(s))\n  new grid: {} ({} job(s))\n  {} job(s) of the old grid, \
         {with_result} of them with a result, would no longer be in the sweep (their results \
         stay in the database); run again with --replace to replace the grid, or give the \
         sweep another name",
        sweep.path.display(),
        sweep.name,
        store.path().display(),
        old.file,
        grid(&old.axes, old.replicas),
        points.len(),
        grid(&sweep.axes, sweep.replicas),
        expanded.len(),
        leaving.len(),
    )))
}

fn sweep_resume(
    name: Option<&str>,
    db: &Path,
    jobs: usize,
    retry: bool,
    extend: Option<f64>,
    table_cache_mib: usize,
) -> Result<(), Failure> {
    let store = Store::open_existing(db)?;
    let sweeps = match name {
        Some(n) => vec![store.sweep(n)?],
        None => store.sweeps()?,
    };
    if sweeps.is_empty() {
        return Err(Failure::BadInput(format!(
            "{}: no sweep in this database: start one with `wetgran sweep run FILE`",
            db.display()
        )));
    }
    run_and_report(&store, &sweeps, jobs, retry, table_cache_mib)?;
    super::refine_cmd::continue_refinement(&store, &sweeps, jobs)?;
    match extend {
        Some(max_periods) => {
            super::extend_cmd::extend_unconverged(&store, &sweeps, max_periods, jobs)
        }
        None => Ok(()),
    }
}

fn run_and_report(
    store: &Store,
    sweeps: &[SweepRow],
    jobs: usize,
    retry: bool,
    table_cache_mib: usize,
) -> Result<(), Failure> {
    let summary = run_sweeps(
        store,
        sweeps,
        &RunOptions {
            jobs,
            retry_failed: retry,
            show_progress: true,
            table_cache_mib,
        },
    )?;
    eprintln!(
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
        let relabelled =
            super::reclassify_cmd::relabel_sweeps(store, std::slice::from_ref(s), None)?;
        if relabelled.changed() > 0 {
            eprintln!(
                "sweep {}: labels along lines of constant Gamma (MODEL.md 7): {}",
                s.name,
                relabelled.text()
            );
        }
        let c = store.counts(s.id)?;
        if c.failed > 0 {
            eprintln!(
                "sweep {}: {} failed job(s): see `wetgran sweep status --db {}`; \
                 `--retry-failed` runs them again",
                s.name,
                c.failed,
                store.path().display()
            );
        }
    }
    Ok(())
}

fn duration_text(s: f64) -> String {
    if s < 120.0 {
        format!("{s:.1} s")
    } else if s < 7200.0 {
        format!("{:.1} min", s / 60.0)
    } else if s < 3.0 * 86400.0 {
        format!("{:.1} h", s / 3600.0)
    } else {
        format!("{:.1} days", s / 86400.0)
    }
}

/// The text of `sweep status`.
pub fn status_text(store: &Store) -> Result<String, StoreError> {
    let mut out = String::new();
    let sweeps = store.sweeps()?;
    if sweeps.is_empty() {
        let _ = writeln!(out, "{}: no sweeps yet", store.path().display());
    }
    let cores = available_cores();
    for s in &sweeps {
        let c = store.counts(s.id)?;
        let points = store.points(s.id)?;
        let _ = writeln!(
            out,
            "sweep {}  ({}; {} point(s) x {} replica(s))",
            s.name,
            s.file,
            points.len() as u64 / s.replicas.max(1) as u64,
            s.replicas
        );
        if let Some(d) = &s.description {
            let _ = writeln!(out, "  {d}");
        }
        if let Some(cost) = &s.cost {
            let _ = writeln!(out, "  cost: {cost}");
        }
        let _ = writeln!(
            out,
            "  jobs   {} total: {} done, {} running, {} pending, {} failed",
            c.total(),
            c.done,
            c.running,
            c.pending,
            c.failed
        );
        let (unconverged, checked) = crate::store::unconverged_count(&points);
        if checked > 0 {
            let _ = writeln!(
                out,
                "  stationary  {} of {checked} result(s) converged, {unconverged} unconverged \
                 (`sweep resume --extend` runs those further)",
                checked - unconverged
            );
        }
        let starts = crate::store::hysteresis::by_start(&s.axes, &points);
        let compared = starts.iter().filter(|g| g.compared()).count();
        if compared > 0 {
            let _ = writeln!(
                out,
                "  hysteresis  {} of {compared} point(s) hysteretic (their start modes disagree)",
                starts.iter().filter(|g| g.hysteretic).count()
            );
            for g in starts.iter().filter(|g| g.hysteretic) {
                let labels: Vec<String> = g
                    .by_start
                    .iter()
                    .map(|(mode, l)| format!("{mode} {}", l.join("/")))
                    .collect();
                let at: Vec<String> = s
                    .axes
                    .iter()
                    .filter(|a| a.key != "initial.start")
                    .zip(&g.coords)
                    .map(|(a, v)| format!("{} = {v}", a.label))
                    .collect();
                let at = if at.is_empty() {
                    "the base scene".to_string()
                } else {
                    at.join(", ")
                };
                let _ = writeln!(out, "    {at}: {}", labels.join(", "));
            }
        }
        let spent = store.time_spent(s.id)?;
        let done_walls: Vec<f64> = points
            .iter()
            .filter(|p| p.status == "done")
            .filter_map(|p| p.wall_seconds)
            .collect();
        let left = c.pending + c.running;
        let estimate = if left == 0 {
            "nothing left".to_string()
        } else if done_walls.is_empty() {
            "time left unknown until a job finishes".to_string()
        } else {
            let mean = done_walls.iter().sum::<f64>() / done_walls.len() as f64;
            format!(
                "about {} left on {cores} core(s) ({left} job(s) x {} mean)",
                duration_text(mean * left as f64 / cores as f64),
                duration_text(mean)
            )
        };
        let _ = writeln!(
            out,
            "  time   {} spent in finished jobs; {estimate}",
            duration_text(spent)
        );
        let untrusted: Vec<String> = points
            .iter()
            .filter_map(|p| p.observables.as_ref())
            .filter_map(|o| crate::report::trust::trust_mark(o).map(|m| m.to_string()))
            .collect();
        if !untrusted.is_empty() {
            let _ = writeln!(
                out,
                "  trust  {} of {} result(s) not stationary ({} in `boundaries`; see `show JOB`)",
                untrusted.len(),
                c.done,
                crate::report::trust::NOT_STATIONARY
            );
        }
        if !s.left_out.is_empty() {
            let _ = writeln!(
                out,
                "  left out {} grid point(s) (sweep.skip_invalid):",
                s.left_out.len()
            );
            out.push_str(&left_out_text(&s.axes, &s.left_out));
        }
        for p in points.iter().filter(|p| p.status == "failed") {
            let _ = writeln!(
                out,
                "  failed {} (job {}, {} attempt(s)): {}",
                point_label(s, &p.coords, p.replica),
                &p.job_id[..12],
                p.attempts,
                p.last_error.as_deref().unwrap_or("no message")
            );
        }
    }
    Ok(out)
}

fn sweep_status(db: &Path) -> Result<(), Failure> {
    let store = Store::open_existing(db)?;
    print!("{}", status_text(&store)?);
    for s in store.sweeps()? {
        let text =
            super::cluster_cmd::slurm_status_text(&store, &s, &mut crate::cluster::slurm::squeue)?;
        if !text.is_empty() {
            println!("sweep {} on Slurm", s.name);
            print!("{text}");
        }
    }
    Ok(())
}

fn sweep_expand(file: &Path, specs: bool) -> Result<(), Failure> {
    let (_, jobs) = load_sweep(file)?;
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

fn sweep_estimate(file: &Path, periods: f64, samples: usize, cores: usize) -> Result<(), Failure> {
    if !(periods.is_finite() && periods > 0.0) || samples == 0 {
        return Err(Failure::BadInput(
            "--periods must be > 0 and --samples >= 1".to_string(),
        ));
    }
    let (sweep, jobs) = load_sweep(file)?;
    let picks: Vec<usize> = if samples >= jobs.len() {
        (0..jobs.len()).collect()
    } else if samples == 1 {
        vec![jobs.len() / 2]
    } else {
        (0..samples)
            .map(|k| (k as f64 * (jobs.len() - 1) as f64 / (samples - 1) as f64).round() as usize)
            .collect()
    };
    println!(
        "{}: {} job(s); sampling {} for {periods} driving period(s) each, one at a time",
        file.display(),
        jobs.len(),
        picks.len()
    );
    let labels: Vec<&str> = sweep.axes.iter().map(|a| a.label.as_str()).collect();
    let mut per_period = Vec::new();
    let mut full_periods = Vec::new();
    // With a `[convergence]` policy: the minimum run (first check) and the cap, in periods.
    let mut cap_periods = Vec::new();
    for &k in &picks {
        let job = &jobs[k];
        let mut spec = job.spec.clone();
        let period = spec.period();
        match spec.scene.convergence.take() {
            Some(c) => {
                let s = c.schedule(&spec.scene);
                full_periods.push(s.first_check / period);
                cap_periods.push(s.cap / period);
            }
            None => full_periods.push(spec.scene.run.duration / period),
        }
        spec.scene.run.duration = periods * period;
        spec.scene.observe.transient_periods = 0.0;
        let t0 = std::time::Instant::now();
        let outcome = run_job(&spec, &mut |_| {});
        let wall = t0.elapsed().as_secs_f64();
        let coords: Vec<String> = labels
            .iter()
            .zip(&job.coords)
            .map(|(l, v)| match v.as_f64() {
                Some(x) => format!("{l} = {}", short(x)),
                None => format!("{l} = {v}"),
            })
            .collect();
        match outcome {
            Ok(r) => {
                per_period.push(wall / periods);
                println!(
                    "  {:<40} {:>9.3} s per period  ({} events)",
                    coords.join(", "),
                    wall / periods,
                    r.events
                );
            }
            Err(e) => println!("  {:<40} failed: {e}", coords.join(", ")),
        }
    }
    if per_period.is_empty() {
        return Err(Failure::Other("every sampled job failed".to_string()));
    }
    let mean = per_period.iter().sum::<f64>() / per_period.len() as f64;
    let max = per_period.iter().cloned().fold(0.0, f64::max);
    let run_periods = full_periods.iter().sum::<f64>() / full_periods.len() as f64;
    let total = mean * run_periods * jobs.len() as f64;
    println!(
        "estimate: {:.3} s per period on average (max {:.3}) x {} periods x {} jobs = {} of CPU, \
         about {} on {cores} core(s)",
        mean,
        max,
        short(run_periods),
        jobs.len(),
        duration_text(total),
        duration_text(total / cores as f64)
    );
    if !cap_periods.is_empty() {
        let cap = cap_periods.iter().sum::<f64>() / cap_periods.len() as f64;
        println!(
            "  run to stationarity: that is the minimum run; every job extended to its cap \
             ({} periods) would cost {} on {cores} core(s)",
            short(cap),
            duration_text(mean * cap * jobs.len() as f64 / cores as f64)
        );
    }
    println!(
        "  (measured on the first {periods} period(s) from the initial state; the cost per period \
         changes as a run settles, e.g. a bed resting on the plate gets dearer: sample more \
         periods for a closer figure)"
    );
    Ok(())
}

fn sweep_job(path: &Path) -> Result<(), Failure> {
    let spec = super::cluster_cmd::read_spec(path)?;
    let result = run_job(&spec, &mut |_| {}).map_err(|e| Failure::Other(e.to_string()))?;
    let out = serde_json::json!({ "id": spec.id(), "result": result });
    println!(
        "{}",
        serde_json::to_string_pretty(&out).expect("serializes")
    );
    Ok(())
}

/// The phase map of a sweep, from its stored results.
fn sweep_map(store: &Store, sweep: &SweepRow, how: Extraction) -> Result<PhaseMap, Failure> {
    let points = store.points(sweep.id)?;
    let obs: Vec<Observation> = points.iter().map(Observation::of_row).collect();
    phase_map_with(&sweep.axes, &obs, how)
        .map_err(|e| Failure::BadInput(format!("sweep {}: {e}", sweep.name)))
}

pub(super) fn select(store: &Store, name: Option<&str>) -> Result<Vec<SweepRow>, Failure> {
    Ok(match name {
        Some(n) => vec![store.sweep(n)?],
        None => store.sweeps()?,
    })
}

/// `wetgran boundaries`.
pub fn boundaries(
    db: &Path,
    name: Option<&str>,
    format: BoundaryFormat,
    how: Extraction,
) -> ExitCode {
    exit((|| {
        let store = Store::open_existing(db)?;
        let sweeps = select(&store, name)?;
        let mut maps = Vec::new();
        for s in &sweeps {
            maps.push((s, sweep_map(&store, s, how)?));
        }
        match format {
            BoundaryFormat::Json => {
                let v: Vec<_> = maps
                    .iter()
                    .map(|(s, m)| serde_json::json!({"sweep": s.name, "map": m}))
                    .collect();
                println!("{}", serde_json::to_string_pretty(&v).expect("serializes"));
            }
            BoundaryFormat::Csv => print!("{}", boundaries_csv(&maps)),
            BoundaryFormat::Table => {
                let mut notes = std::collections::HashMap::new();
                let mut untrusted = std::collections::HashMap::new();
                for s in &sweeps {
                    let points = store.points(s.id)?;
                    if let Some(n) = chain_model_note(&points) {
                        notes.insert(s.name.clone(), n);
                    }
                    untrusted.insert(s.name.clone(), untrusted_points(&points));
                }
                print!("{}", boundaries_table(&maps, &notes, &untrusted, how))
            }
        }
        Ok(())
    })())
}

fn opt_num(v: Option<f64>) -> String {
    v.map(short).unwrap_or_default()
}

fn fixed_text(fixed: &[(String, serde_json::Value)]) -> String {
    fixed
        .iter()
        .map(|(l, v)| format!("{l} = {v}"))
        .collect::<Vec<_>>()
        .join(", ")
}

fn boundaries_csv(maps: &[(&SweepRow, PhaseMap)]) -> String {
    let mut out = String::from(
        "sweep,slice,kind,phase,x_axis,x,y_axis,y,amplitude,omega,x_lo,x_hi,y_lo,y_hi,confidence\n",
    );
    for (s, m) in maps {
        let xl = m.x.as_ref().map(|a| a.key.clone()).unwrap_or_default();
        let yl = m.y.as_ref().map(|a| a.key.clone()).unwrap_or_default();
        for (k, slice) in m.slices.iter().enumerate() {
            for p in &slice.points {
                let _ = writeln!(
                    out,
                    "{},{k},point,{},{xl},{},{yl},{},{},{},,,,,",
                    s.name,
                    p.phase,
                    p.x,
                    p.y,
                    p.amplitude.map(|v| v.to_string()).unwrap_or_default(),
                    p.omega.map(|v| v.to_string()).unwrap_or_default()
                );
            }
            for b in slice.boundaries.values().flatten() {
                let _ = writeln!(
                    out,
                    "{},{k},boundary,{},{xl},{},{yl},{},{},{},{},{},{},{},{}",
                    s.name,
                    b.pair,
                    b.x,
                    b.y,
                    b.amplitude.map(|v| v.to_string()).unwrap_or_default(),
                    b.omega.map(|v| v.to_string()).unwrap_or_default(),
                    b.x_range[0],
                    b.x_range[1],
                    b.y_range[0],
                    b.y_range[1],
                    b.confidence
                );
            }
        }
    }
    out
}

/// For shear sweeps of wet scenes: the chain model's critical force (MODEL.md 8, Eq. 7.9),
/// `F_max = 0.9229 F_B d / L_x`, over the sweep's points (a range if the axes change it).
fn chain_model_note(points: &[crate::store::PointRow]) -> Option<String> {
    let values: Vec<f64> = points
        .iter()
        .filter(|p| p.spec.scene.shear_slabs().is_some())
        .filter_map(|p| plot_phase::chain_model_f_max(&p.spec.scene))
        .collect();
    let lo = values.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if values.is_empty() {
        return None;
    }
    let value = if hi - lo <= 1e-12 * hi.abs() {
        format!("F_max = {}", short(lo))
    } else {
        format!("F_max from {} to {} over the points", short(lo), short(hi))
    };
    Some(format!(
        "  chain model (MODEL.md 8, Eq. 7.9: solid while F_max L_x / (F_B d) <= {}): {value}",
        plot_phase::CHAIN_MODEL_CONSTANT
    ))
}

/// The grid points (their coordinates as JSON text) with a replica whose result carries a trust
/// mark (`report::trust`), with the mark.
fn untrusted_points(points: &[crate::store::PointRow]) -> std::collections::HashMap<String, char> {
    points
        .iter()
        .filter_map(|p| {
            let mark = crate::report::trust::trust_mark(p.observables.as_ref()?)?;
            Some((serde_json::Value::from(p.coords.clone()).to_string(), mark))
        })
        .collect()
}

fn boundaries_table(
    maps: &[(&SweepRow, PhaseMap)],
    notes: &std::collections::HashMap<String, String>,
    untrusted: &std::collections::HashMap<String, std::collections::HashMap<String, char>>,
    how: Extraction,
) -> String {
    let none = std::collections::HashMap::new();
    let mut out = String::new();
    for (s, m) in maps {
        let _ = writeln!(out, "sweep {}", s.name);
        if let Some(n) = notes.get(&s.name) {
            let _ = writeln!(out, "{n}");
        }
        let (Some(xa), ya) = (&m.x, &m.y) else {
            let _ = writeln!(out, "  no numeric axis: no phase map\n");
            continue;
        };
        let ylabel = ya.as_ref().map(|a| a.label.as_str()).unwrap_or("");
        for slice in &m.slices {
            if !slice.fixed.is_empty() {
                let _ = writeln!(out, "  slice {}", fixed_text(&slice.fixed));
            }
            if slice.points.is_empty() {
                let _ = writeln!(out, "  no classified point yet\n");
                continue;
            }
            // The map as a grid: rows = y (top: largest), columns = x.
            let mut xs: Vec<f64> = slice.points.iter().map(|p| p.x).collect();
            let mut ys: Vec<f64> = slice.points.iter().map(|p| p.y).collect();
            xs.sort_by(f64::total_cmp);
            xs.dedup();
            ys.sort_by(f64::total_cmp);
            ys.dedup();
            if xs.len() > 24 || ys.len() > 60 {
                // A refined map is no grid: list counts only (the points are in csv/json).
                let _ = writeln!(
                    out,
                    "  phase map: {} points ({} x values, {} y values; see --format csv)",
                    slice.points.len(),
                    xs.len(),
                    ys.len()
                );
            } else {
                let marks = untrusted.get(&s.name).unwrap_or(&none);
                write_grid(&mut out, slice, xa, ya.as_ref(), &xs, &ys, marks);
            }
            let unconverged = slice.points.iter().filter(|p| !p.converged).count();
            if unconverged > 0 {
                let _ = writeln!(
                    out,
                    "  {unconverged} unconverged point(s): {}",
                    if how.include_unconverged {
                        "used for the boundaries as asked (--include-unconverged)"
                    } else {
                        "left out of the boundaries (--include-unconverged uses them)"
                    }
                );
            }
            if slice.boundaries.is_empty() {
                let carriers: Vec<&str> = slice
                    .points
                    .iter()
                    .filter(|p| how.include_unconverged || p.converged)
                    .map(|p| p.phase.as_str())
                    .collect();
                let why = if carriers.len() < 2 {
                    "fewer than two converged points"
                } else if carriers.iter().all(|p| *p == carriers[0]) {
                    "every point that carries one has the same phase"
                } else {
                    "no two neighbours differ"
                };
                let _ = writeln!(out, "  no boundary: {why}\n");
                continue;
            }
            for (pair, list) in &slice.boundaries {
                let _ = writeln!(out, "  boundary {pair} ({} point(s))", list.len());
                let _ = writeln!(
                    out,
                    "    {:>10} {:>10} {:>10} {:>10} {:>10} {:>10} {:>6}",
                    xa.label,
                    ylabel,
                    if m.shaking { "A" } else { "" },
                    if m.shaking { "omega" } else { "" },
                    format!("+-{}", if xa.log { "dec" } else { "x" }),
                    format!(
                        "+-{}",
                        if ya.as_ref().is_some_and(|a| a.log) {
                            "dec"
                        } else {
                            "y"
                        }
                    ),
                    "conf"
                );
                for b in list {
                    let _ = writeln!(
                        out,
                        "    {:>10} {:>10} {:>10} {:>10} {:>10} {:>10} {:>6}",
                        short(b.x),
                        if ya.is_some() {
                            short(b.y)
                        } else {
                            String::new()
                        },
                        opt_num(b.amplitude),
                        opt_num(b.omega),
                        short(b.x_half),
                        if ya.is_some() {
                            short(b.y_half)
                        } else {
                            String::new()
                        },
                        format!("{:.2}", b.confidence)
                    );
                }
            }
            let _ = writeln!(out);
        }
    }
    out
}

/// The phase map of a slice as a grid: rows = y (top: largest), columns = x.
fn write_grid(
    out: &mut String,
    slice: &crate::boundary::Slice,
    xa: &crate::boundary::PlaneAxis,
    ya: Option<&crate::boundary::PlaneAxis>,
    xs: &[f64],
    ys: &[f64],
    marks: &std::collections::HashMap<String, char>,
) {
    let ylabel = ya.map(|a| a.label.as_str()).unwrap_or("");
    let mark_of = |p: &crate::boundary::MapPoint| {
        marks
            .get(&serde_json::Value::from(p.coords.clone()).to_string())
            .copied()
    };
    let _ = writeln!(
        out,
        "  phase map ({} down, {} across{}{}):",
        if ylabel.is_empty() { "-" } else { ylabel },
        xa.label,
        if slice.points.iter().any(|p| p.tie) {
            "; * = replicas tied"
        } else {
            ""
        },
        if slice.points.iter().any(|p| mark_of(p).is_some()) {
            format!(
                "; {} = not stationary",
                crate::report::trust::NOT_STATIONARY
            )
        } else {
            String::new()
        }
    );
    for &yv in ys.iter().rev() {
        let mut row = format!(
            "  {:>9} |",
            if ya.is_some() {
                short(yv)
            } else {
                String::new()
            }
        );
        for &xv in xs {
            let cell = slice
                .points
                .iter()
                .find(|p| p.x == xv && p.y == yv)
                .map(|p| {
                    format!(
                        "{}{}{}",
                        p.phase,
                        if p.tie { "*" } else { "" },
                        mark_of(p).map(String::from).unwrap_or_default()
                    )
                })
                .unwrap_or_else(|| ".".to_string());
            let _ = write!(row, " {cell:>7}");
        }
        let _ = writeln!(out, "{row}");
    }
    let mut axis = format!("  {:>9} +", "");
    for _ in xs {
        axis.push_str("--------");
    }
    let _ = writeln!(out, "{axis}");
    let mut labels = format!("  {:>9}  ", xa.label);
    for &xv in xs {
        let _ = write!(labels, " {:>7}", short(xv));
    }
    let _ = writeln!(out, "{labels}");
}

/// `wetgran plot`.
pub fn plot(db: &Path, name: Option<&str>, output: &Path, how: Extraction) -> ExitCode {
    exit((|| {
        let store = Store::open_existing(db)?;
        let sweep = match name {
            Some(n) => store.sweep(n)?,
            None => {
                let mut all = store.sweeps()?;
                all.sort_by(|a, b| a.updated_at.total_cmp(&b.updated_at));
                let last = all.pop().ok_or_else(|| {
                    Failure::BadInput(format!("{}: no sweep in this database", db.display()))
                })?;
                if !all.is_empty() {
                    eprintln!(
                        "plotting sweep {} (the latest; choose with --sweep)",
                        last.name
                    );
                }
                last
            }
        };
        let map = sweep_map(&store, &sweep, how)?;
        let points = store.points(sweep.id)?;
        let landmarks = points
            .first()
            .and_then(|p| plot_phase::Landmarks::of(&p.spec.scene));
        let Some(slice) = map.slices.first() else {
            return Err(Failure::BadInput(format!(
                "sweep {}: no classified point to plot yet",
                sweep.name
            )));
        };
        if map.slices.len() > 1 {
            eprintln!(
                "sweep {} has {} slices (axes beyond the plane); plotting the first: {}",
                sweep.name,
                map.slices.len(),
                fixed_text(&slice.fixed)
            );
        }
        let title = format!("wetgran phase diagram: {}", sweep.name);
        let chain = plot_phase::chain_model_line(&map, slice, |coords| {
            points
                .iter()
                .find(|p| p.coords == coords)
                .map(|p| p.spec.scene.clone())
        });
        let svg = plot_phase::phase_svg(&map, slice, landmarks, chain, &title)
            .map_err(|e| Failure::BadInput(format!("sweep {}: {e}", sweep.name)))?;
        std::fs::write(output, svg)
            .map_err(|e| Failure::Other(format!("{}: cannot write: {e}", output.display())))?;
        eprintln!("wrote {}", output.display());
        Ok(())
    })())
}

/// `wetgran export`.
pub fn export(
    db: &Path,
    name: Option<&str>,
    format: ExportFormat,
    output: Option<&Path>,
    series: Option<&Path>,
) -> ExitCode {
    exit((|| {
        let store = Store::open_existing(db)?;
        let mut rows = Vec::new();
        for s in select(&store, name)? {
            rows.extend(export::rows(&s, &store.points(s.id)?));
        }
        let text = match format {
            ExportFormat::Csv => export::to_csv(&rows),
            ExportFormat::Json => export::to_json(&rows),
        };
        match output {
            Some(p) => std::fs::write(p, text)
                .map_err(|e| Failure::Other(format!("{}: cannot write: {e}", p.display())))?,
            None => print!("{text}"),
        }
        match (format, series) {
            (ExportFormat::Csv, Some(p)) => std::fs::write(p, export::series_csv(&rows))
                .map_err(|e| Failure::Other(format!("{}: cannot write: {e}", p.display())))?,
            (ExportFormat::Json, Some(_)) => {
                return Err(Failure::BadInput(
                    "--series goes with --format csv (the JSON export holds the series)"
                        .to_string(),
                ));
            }
            (ExportFormat::Csv, None) => eprintln!(
                "export: scalar columns only; the series (time series, profiles) go to \
                 --series FILE or --format json"
            ),
            (ExportFormat::Json, None) => {}
        }
        Ok(())
    })())
}
