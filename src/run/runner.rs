//! The scheduler: claims pending jobs from the store, runs them on worker threads (one
//! simulation per thread, synchronous), and commits each finished job on its own.
//!
//! Only the calling thread talks to the store; workers receive claimed specs over a channel and
//! send back progress and outcomes. Between messages the calling thread refreshes the heartbeat
//! of the running jobs every `store::HEARTBEAT_INTERVAL`.
//!
//! The runner owns the wall-table cache of its jobs (`table` wall solver): one bounded
//! [`TableCache`] per run, capped by [`RunOptions::table_cache_mib`], installed on every worker
//! thread and dropped with the run, so a sweep over many drives keeps at most the cap in
//! cached tables (plus the two tables each running job holds).
//!
//! The runner also shares the machine's cores among its jobs ([`CoreShare`], `sim::threads`):
//! each worker enters the run's share, and the runner tells it how many workers are busy and
//! whether the queue is empty. While jobs wait, each job gets `cores / workers` threads; once
//! the queue is empty, the jobs still running get the idle workers' cores (the time-driven
//! engine's steps are parallel, with the same numbers on any number of threads), so the tail
//! of a sweep does not leave cores idle.

use super::progress::Progress;
use crate::store::{Claim, HEARTBEAT_INTERVAL, Store, StoreError, SweepRow};
use crate::sweep::job::{JobError, JobResult, run_job, run_job_from};
use std::sync::{Arc, mpsc};
use std::thread;
use std::time::{Duration, Instant};
use wetgran_core::sim::event_driven::table_cache::TableCache;
use wetgran_core::sim::threads::{self, CoreShare};

/// How to run.
#[derive(Debug, Clone)]
pub struct RunOptions {
    /// Worker threads (at least 1).
    pub jobs: usize,
    /// Re-queue the failed jobs first.
    pub retry_failed: bool,
    /// Show progress (bars on a terminal, plain lines otherwise); `false`: silent.
    pub show_progress: bool,
    /// Cap of the run's wall-table cache in MiB (least recently used tables out first;
    /// default `table_cache::DEFAULT_TABLE_CACHE_MIB`; 0: no caching, each job builds its own).
    pub table_cache_mib: usize,
}

/// What a run did.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RunSummary {
    /// Jobs that were running under a dead or silent runner and were put back in the queue.
    pub requeued: usize,
    /// Failed jobs put back in the queue by `retry_failed`.
    pub retried: u64,
    pub done: u64,
    pub failed: u64,
    /// Results dropped because another runner had already finished the job.
    pub discarded: u64,
    pub wall_seconds: f64,
    /// Wall tables built by the run's cache, and the most bytes it held at once.
    pub tables_built: u64,
    pub table_cache_peak_bytes: usize,
}

enum Msg {
    Progress(usize, f64),
    Finished(usize, Box<Claim>, Result<JobResult, JobError>, f64),
}

/// `Gamma = 2, E* = 3 (replica 1)`.
pub fn point_label(sweep: &SweepRow, coords: &[serde_json::Value], replica: i64) -> String {
    let mut parts: Vec<String> = sweep
        .axes
        .iter()
        .zip(coords)
        .map(|(a, v)| match v.as_f64() {
            Some(x) => format!("{} = {}", a.label, short(x)),
            None => format!("{} = {v}", a.label),
        })
        .collect();
    if sweep.replicas > 1 {
        parts.push(format!("replica {replica}"));
    }
    if parts.is_empty() {
        "the base scene".to_string()
    } else {
        parts.join(", ")
    }
}

/// A number rounded to 4 significant digits, printed in its shortest form.
pub fn short(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    if x.abs() >= 1e5 || x.abs() < 1e-3 {
        return format!("{x:.3e}");
    }
    // Dividing by an exact power of ten rounds correctly, so the shortest text is the decimal.
    let digits = 3 - x.abs().log10().floor() as i32;
    if digits >= 0 {
        let scale = 10f64.powi(digits);
        format!("{}", (x * scale).round() / scale)
    } else {
        let scale = 10f64.powi(-digits);
        format!("{}", (x / scale).round() * scale)
    }
}

/// What a worker calls to run one claimed job (its spec, and a continuation job's start state
/// in `claim.start`), with a progress callback taking the fraction done.
pub type JobFn =
    Arc<dyn Fn(&Claim, &mut dyn FnMut(f64)) -> Result<JobResult, JobError> + Send + Sync>;

/// The simulation of a claimed job: `sweep::run_job`, or `run_job_from` its start state.
pub fn simulate(claim: &Claim, progress: &mut dyn FnMut(f64)) -> Result<JobResult, JobError> {
    match claim.start.as_deref() {
        Some(state) => run_job_from(&claim.spec, state, progress),
        None => run_job(&claim.spec, progress),
    }
}

/// Runs the pending jobs of the given sweeps until none is left.
pub fn run_sweeps(
    store: &Store,
    sweeps: &[SweepRow],
    opts: &RunOptions,
) -> Result<RunSummary, StoreError> {
    run_sweeps_with(store, sweeps, opts, Arc::new(simulate))
}

/// [`run_sweeps`] with another job function in place of the simulation: the orchestrator
/// benchmark (`wetgran-bench orchestrator`) times the claims, commits and heartbeats around a
/// stand-in job that returns a result of the real shape at once.
pub fn run_sweeps_with(
    store: &Store,
    sweeps: &[SweepRow],
    opts: &RunOptions,
    job: JobFn,
) -> Result<RunSummary, StoreError> {
    let start = Instant::now();
    let ids: Vec<i64> = sweeps.iter().map(|s| s.id).collect();
    let mut summary = RunSummary {
        requeued: store.requeue_orphans()?.len(),
        ..Default::default()
    };
    if opts.retry_failed {
        summary.retried = store.retry_failed(&ids)?;
    }
    let (mut total, mut done_before) = (0, 0);
    for s in sweeps {
        let c = store.counts(s.id)?;
        total += c.total();
        done_before += c.done + c.failed;
    }
    let n_workers = opts.jobs.max(1);
    let mut progress = if opts.show_progress {
        Progress::auto(total, done_before, n_workers)
    } else {
        Progress::Quiet
    };
    let names: Vec<&str> = sweeps.iter().map(|s| s.name.as_str()).collect();
    progress.note(&format!(
        "sweep {}: {total} jobs, {done_before} finished before, {} to run on {n_workers} worker{} \
         (database {})",
        names.join(", "),
        total - done_before,
        if n_workers == 1 { "" } else { "s" },
        store.path().display()
    ));
    if summary.requeued > 0 {
        progress.note(&format!(
            "re-queued {} job(s) left running by a runner that stopped",
            summary.requeued
        ));
    }
    if summary.retried > 0 {
        progress.note(&format!("re-queued {} failed job(s)", summary.retried));
    }

    let (msg_tx, msg_rx) = mpsc::channel::<Msg>();
    let tables = TableCache::with_cap_mib(opts.table_cache_mib);
    let cores = CoreShare::new(threads::available_cores(), n_workers);
    let (job_tx, handles) = spawn_workers(n_workers, &msg_tx, &tables, &cores, &job);
    drop(msg_tx);

    let mut idle: Vec<usize> = (0..n_workers).rev().collect();
    let mut busy = 0usize;
    // Whether the last claim found the queue empty (a continuation job may become claimable
    // later, when its predecessor ends).
    let mut drained = false;
    let mut last_beat = Instant::now();
    let outcome = (|| -> Result<(), StoreError> {
        loop {
            while let Some(&w) = idle.last() {
                let Some(mut claim) = store.claim(&ids)? else {
                    drained = true;
                    break;
                };
                drained = false;
                let sweep = sweeps
                    .iter()
                    .find(|s| s.name == claim.sweep)
                    .expect("claimed from one of these sweeps");
                if let Some(prev) = claim.spec.start_from.clone() {
                    match continuation_start(store, &prev)? {
                        Ok(state) => claim.start = Some(Box::new(state)),
                        Err(why) => {
                            store.fail(&claim, &why, 0.0)?;
                            summary.failed += 1;
                            let label = point_label(sweep, &claim.coords, claim.replica);
                            progress.note(&format!(
                                "FAILED  {label}: {why} (job {})",
                                &claim.job_id[..12]
                            ));
                            continue;
                        }
                    }
                }
                idle.pop();
                progress.start(w, &point_label(sweep, &claim.coords, claim.replica));
                job_tx[w].send(claim).expect("worker alive");
                busy += 1;
            }
            if busy == 0 {
                return Ok(());
            }
            cores.set(busy, drained);
            let wait = HEARTBEAT_INTERVAL.saturating_sub(last_beat.elapsed());
            match msg_rx.recv_timeout(wait.max(Duration::from_millis(10))) {
                Ok(Msg::Progress(w, f)) => progress.update(w, f),
                Ok(Msg::Finished(w, claim, result, wall)) => {
                    let line = record_finished(store, sweeps, &claim, &result, wall, &mut summary)?;
                    progress.finish(w, &line);
                    idle.push(w);
                    busy -= 1;
                }
                Err(mpsc::RecvTimeoutError::Timeout) => {}
                Err(mpsc::RecvTimeoutError::Disconnected) => {
                    return Err(StoreError::Db {
                        path: store.path().display().to_string(),
                        detail: "all worker threads stopped".to_string(),
                    });
                }
            }
            if last_beat.elapsed() >= HEARTBEAT_INTERVAL {
                store.heartbeat()?;
                last_beat = Instant::now();
            }
        }
    })();
    drop(job_tx);
    if outcome.is_ok() {
        for h in handles {
            let _ = h.join();
        }
    }
    progress.close();
    outcome?;
    summary.wall_seconds = start.elapsed().as_secs_f64();
    summary.tables_built = tables.builds();
    summary.table_cache_peak_bytes = tables.peak_bytes();
    Ok(summary)
}

/// The start state of a continuation job whose predecessor is job `prev`: its checkpoint
/// carried into the next container (`EngineState::continued`). `Ok(Err(why))`: the predecessor
/// ended without a final state (it failed), so the job cannot run.
fn continuation_start(
    store: &Store,
    prev: &str,
) -> Result<Result<wetgran_core::sim::EngineState, String>, StoreError> {
    let short = &prev[..prev.len().min(12)];
    let Some(spec) = store.job_spec(prev)? else {
        return Ok(Err(format!(
            "its predecessor job {short} is not in the database"
        )));
    };
    let Some(state) = store.checkpoint(prev)? else {
        return Ok(Err(format!(
            "its predecessor job {short} has no final state (it failed; `sweep resume \
             --retry-failed` runs both again)"
        )));
    };
    Ok(Ok(state.continued(&spec.scene)))
}

/// Stores a finished job's result (or its failure), counts it in `summary`, and returns the
/// line the progress display prints for it.
fn record_finished(
    store: &Store,
    sweeps: &[SweepRow],
    claim: &Claim,
    result: &Result<JobResult, JobError>,
    wall: f64,
    summary: &mut RunSummary,
) -> Result<String, StoreError> {
    let sweep = sweeps
        .iter()
        .find(|s| s.name == claim.sweep)
        .expect("claimed from one of these sweeps");
    let label = point_label(sweep, &claim.coords, claim.replica);
    let short_id = &claim.job_id[..12];
    let line = match result {
        Ok(r) => {
            if store.finish(claim, r)? {
                summary.done += 1;
                format!(
                    "done    {label}: phase {}, {:.1} s (job {short_id})",
                    r.phase.as_deref().unwrap_or("-"),
                    r.wall_seconds
                )
            } else {
                summary.discarded += 1;
                format!(
                    "dropped {label}: another runner finished it first (job \
                     {short_id})"
                )
            }
        }
        Err(e) => {
            store.fail(claim, &e.to_string(), wall)?;
            summary.failed += 1;
            format!("FAILED  {label}: {e} (job {short_id})")
        }
    };
    Ok(line)
}

/// Starts `n_workers` worker threads, each in the wall-table cache `tables` and its share of
/// `cores`; returns the channel that hands each its claims and their handles.
fn spawn_workers(
    n_workers: usize,
    msg_tx: &mpsc::Sender<Msg>,
    tables: &TableCache,
    cores: &Arc<CoreShare>,
    job: &JobFn,
) -> (Vec<mpsc::Sender<Claim>>, Vec<thread::JoinHandle<()>>) {
    let mut job_tx = Vec::new();
    let mut handles = Vec::new();
    for w in 0..n_workers {
        let (tx, rx) = mpsc::channel::<Claim>();
        job_tx.push(tx);
        let out = msg_tx.clone();
        let tables = tables.clone();
        let cores = cores.clone();
        let job = job.clone();
        handles.push(
            thread::Builder::new()
                .name(format!("wetgran-worker-{w}"))
                .spawn(move || {
                    let _tables = tables.enter();
                    let _cores = threads::enter(&cores, w);
                    worker(w, rx, out, job)
                })
                .expect("spawn a worker thread"),
        );
    }
    (job_tx, handles)
}

/// A worker: runs every claim it receives and reports back.
fn worker(w: usize, jobs: mpsc::Receiver<Claim>, out: mpsc::Sender<Msg>, job: JobFn) {
    while let Ok(claim) = jobs.recv() {
        let t0 = Instant::now();
        let mut last = -1.0;
        let mut report = |f: f64| {
            // At most one message per percent.
            if f - last >= 0.01 || f >= 1.0 {
                last = f;
                let _ = out.send(Msg::Progress(w, f));
            }
        };
        let result = job(&claim, &mut report);
        let wall = t0.elapsed().as_secs_f64();
        if out
            .send(Msg::Finished(w, Box::new(claim), result, wall))
            .is_err()
        {
            return;
        }
    }
}
