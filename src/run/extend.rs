//! `sweep resume --extend MAX_PERIODS` (or `--extend-time MAX_TIME`): the unconverged finished
//! jobs of sweeps run further from their checkpoints (`sweep::job::extend_job`) on the worker
//! pool of every run (`pool`), and each result and checkpoint is replaced as it finishes
//! (`Store::replace_result`, one transaction: a crash or Ctrl-C keeps either the old result or
//! the new one).
//!
//! An extension is not a claim of the store's queue: the job stays `done` while it runs, so a
//! run interrupted here leaves nothing to re-queue, and the next `--extend` finds the jobs it
//! did not reach still unconverged.

use super::pool::{Queue, run_queue};
use super::progress::Progress;
use super::runner::point_label;
use crate::store::{PointRow, Store, StoreError, SweepRow};
use crate::sweep::job::{ExtendTo, JobError, JobResult, extend_job};
use std::sync::Arc;
use wetgran_core::sim::{EngineState, RunSettings};

/// What an extension run did.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ExtendSummary {
    /// Results replaced by their extension.
    pub extended: usize,
    /// Of those, the ones that now reach a stationary window.
    pub converged: usize,
    /// Jobs left as they were: no checkpoint, or no room for one more window under the cap.
    pub skipped: usize,
    /// What went wrong, one line per job that could not be extended or stored.
    pub failed: Vec<String>,
}

/// A finished job to extend, with its checkpoint.
pub(crate) struct Extension {
    point: PointRow,
    state: EngineState,
    /// The job's grid point in words (`runner::point_label`).
    label: String,
}

/// The unconverged jobs left to extend (each job once, with the index of its sweep for
/// labels), and what became of those taken.
struct ExtendQueue<'a> {
    sweeps: &'a [SweepRow],
    todo: std::vec::IntoIter<(usize, PointRow)>,
    summary: ExtendSummary,
}

/// Extends every unconverged finished job of `sweeps` that has a checkpoint to at most `cap` of
/// total run, with the workers, wall-table cache, hook and progress of `opts` (its
/// `retry_failed` does not apply).
pub fn extend_unconverged(
    store: &Store,
    sweeps: &[SweepRow],
    cap: ExtendTo,
    opts: &super::RunOptions,
) -> Result<ExtendSummary, StoreError> {
    let (workers, show_progress) = (opts.jobs, opts.show_progress);
    let mut todo = Vec::new();
    let mut seen = std::collections::BTreeSet::new();
    for (k, s) in sweeps.iter().enumerate() {
        for p in store.points(s.id)? {
            let unconverged = p.status == "done"
                && p.verdict() != Some(wetgran_core::observe::Verdict::Stationary);
            if unconverged && seen.insert(p.job_id.clone()) {
                todo.push((k, p));
            }
        }
    }
    let workers = workers.max(1);
    let mut progress = Progress::auto(show_progress, todo.len() as u64, 0, workers);
    let names: Vec<&str> = sweeps.iter().map(|s| s.name.as_str()).collect();
    progress.note(&format!(
        "sweep {}: extending {} job(s) left unconverged to at most {} on {workers} worker{}",
        names.join(", "),
        todo.len(),
        cap.describe(),
        if workers == 1 { "" } else { "s" },
    ));
    let mut queue = ExtendQueue {
        sweeps,
        todo: todo.into_iter(),
        summary: ExtendSummary::default(),
    };
    let work = Arc::new(
        move |x: &Extension, settings: &RunSettings, report: &mut dyn FnMut(f64)| {
            extend_job(&x.point.spec, &x.state, cap, settings, report)
        },
    );
    run_queue(
        store,
        &mut queue,
        workers,
        opts.table_cache_mib,
        opts.on_extend.clone(),
        &mut progress,
        work,
    )?;
    Ok(queue.summary)
}

impl Queue for ExtendQueue<'_> {
    type Job = Extension;
    type Outcome = Result<Option<JobResult>, JobError>;

    /// The next job with a readable checkpoint; a job without one is skipped, one whose
    /// checkpoint cannot be read is a failure of its own (the others go on).
    fn claim(
        &mut self,
        store: &Store,
        _progress: &mut Progress,
    ) -> Result<Option<(Extension, String)>, StoreError> {
        for (k, point) in self.todo.by_ref() {
            match store.checkpoint(&point.job_id) {
                Ok(Some(state)) => {
                    let label = point_label(&self.sweeps[k], &point.coords, point.replica);
                    let x = Extension {
                        point,
                        state,
                        label: label.clone(),
                    };
                    return Ok(Some((x, label)));
                }
                Ok(None) => self.summary.skipped += 1,
                Err(e) => self.summary.failed.push(e.to_string()),
            }
        }
        Ok(None)
    }

    /// Replaces the job's result and checkpoint by its extension; a failed extension or a
    /// failed write is counted and the run goes on.
    fn commit(
        &mut self,
        store: &Store,
        x: Extension,
        outcome: Result<Option<JobResult>, JobError>,
        wall: f64,
    ) -> Result<String, StoreError> {
        let (label, short_id) = (&x.label, &x.point.job_id[..12]);
        let s = &mut self.summary;
        let why = match outcome {
            Ok(Some(r)) => {
                let verdict = r
                    .decided_on
                    .as_ref()
                    .and_then(|d| d.pointer("/settling/verdict"))
                    .and_then(serde_json::Value::as_str)
                    .and_then(wetgran_core::observe::Verdict::parse);
                let ok = verdict == Some(wetgran_core::observe::Verdict::Stationary);
                match store.replace_result(&x.point.job_id, &r) {
                    Ok(()) => {
                        s.extended += 1;
                        s.converged += usize::from(ok);
                        let verdict = verdict.map_or("no verdict", |v| v.name());
                        return Ok(format!(
                            "extended {label}: {verdict} at t = {:.4}, {wall:.1} s (job {short_id})",
                            r.simulated_time
                        ));
                    }
                    Err(e) => e.to_string(),
                }
            }
            Ok(None) => {
                s.skipped += 1;
                return Ok(format!(
                    "kept    {label}: the cap leaves no room for another window (job {short_id})"
                ));
            }
            Err(e) => format!("job {short_id}: {e}"),
        };
        let line = format!("FAILED  {why}");
        s.failed.push(why);
        Ok(line)
    }
}
