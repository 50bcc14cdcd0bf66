//! The scheduler of sweep runs: claims pending jobs from the store ([`SweepQueue`]), runs
//! them on the worker pool (`pool`: worker threads, heartbeats, the wall-table cache and the
//! core share), and commits each finished job on its own.

use super::pool::{Queue, run_queue};
use super::progress::Progress;
use crate::store::{Claim, Store, StoreError, SweepRow};
use crate::sweep::job::{JobError, JobResult, run_job, run_job_from};
use std::sync::Arc;
use std::time::Instant;
use wetgran_core::sim::{ExtendHook, RunSettings};

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
    /// Called in a job's run each time the run-length policy extends it by a window
    /// (`RunSettings::on_extend`).
    pub on_extend: Option<ExtendHook>,
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
/// in `claim.start`) with the run's settings, with a progress callback taking the fraction
/// done.
pub type JobFn = Arc<
    dyn Fn(&Claim, &RunSettings, &mut dyn FnMut(f64)) -> Result<JobResult, JobError> + Send + Sync,
>;

/// The simulation of a claimed job: `sweep::run_job`, or `run_job_from` its start state.
pub fn simulate(
    claim: &Claim,
    settings: &RunSettings,
    progress: &mut dyn FnMut(f64),
) -> Result<JobResult, JobError> {
    match claim.start.as_deref() {
        Some(state) => run_job_from(&claim.spec, state, settings, progress),
        None => run_job(&claim.spec, settings, progress),
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
    let mut progress = Progress::auto(opts.show_progress, total, done_before, n_workers);
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

    let mut queue = SweepQueue {
        sweeps,
        ids,
        summary,
    };
    let tables = run_queue(
        store,
        &mut queue,
        n_workers,
        opts.table_cache_mib,
        opts.on_extend.clone(),
        &mut progress,
        job,
    )?;
    let mut summary = queue.summary;
    summary.wall_seconds = start.elapsed().as_secs_f64();
    summary.tables_built = tables.built;
    summary.table_cache_peak_bytes = tables.peak_bytes;
    Ok(summary)
}

/// The pending jobs of some sweeps, claimed from the store's queue, and what became of them.
struct SweepQueue<'a> {
    sweeps: &'a [SweepRow],
    ids: Vec<i64>,
    summary: RunSummary,
}

impl SweepQueue<'_> {
    /// The sweep a job was claimed from.
    fn sweep_of(&self, claim: &Claim) -> &SweepRow {
        self.sweeps
            .iter()
            .find(|s| s.name == claim.sweep)
            .expect("claimed from one of these sweeps")
    }
}

impl Queue for SweepQueue<'_> {
    type Job = Claim;
    type Outcome = Result<JobResult, JobError>;

    /// The next pending job whose run can start: a continuation job gets its predecessor's
    /// final state, or fails at once with the reason when there is none.
    fn claim(
        &mut self,
        store: &Store,
        progress: &mut Progress,
    ) -> Result<Option<(Claim, String)>, StoreError> {
        while let Some(mut claim) = store.claim(&self.ids)? {
            let label = point_label(self.sweep_of(&claim), &claim.coords, claim.replica);
            let Some(prev) = claim.spec.start_from.clone() else {
                return Ok(Some((claim, label)));
            };
            match continuation_start(store, &prev)? {
                Ok(state) => {
                    claim.start = Some(Box::new(state));
                    return Ok(Some((claim, label)));
                }
                Err(why) => {
                    store.fail(&claim, &why, 0.0)?;
                    self.summary.failed += 1;
                    progress.outcome(&format!(
                        "FAILED  {label}: {why} (job {})",
                        &claim.job_id[..12]
                    ));
                }
            }
        }
        Ok(None)
    }

    /// Stores a finished job's result (or its failure) and counts it.
    fn commit(
        &mut self,
        store: &Store,
        claim: Claim,
        result: Result<JobResult, JobError>,
        wall: f64,
    ) -> Result<String, StoreError> {
        let label = point_label(self.sweep_of(&claim), &claim.coords, claim.replica);
        let short_id = &claim.job_id[..12];
        let summary = &mut self.summary;
        let line = match result {
            Ok(r) => {
                if store.finish(&claim, &r)? {
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
                store.fail(&claim, &e.to_string(), wall)?;
                summary.failed += 1;
                format!("FAILED  {label}: {e} (job {short_id})")
            }
        };
        Ok(line)
    }
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
