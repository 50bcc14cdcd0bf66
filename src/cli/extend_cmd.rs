//! `sweep resume --extend MAX_PERIODS` (or `--extend-time MAX_TIME`): runs the unconverged finished jobs of sweeps further
//! from their checkpoints (`sweep::job::extend_job`), on worker threads, and replaces each
//! result (and checkpoint) as it finishes.

use super::common::Failure;
use crate::report::sweep_text::extended_text;
use crate::store::{PointRow, Store, SweepRow};
use crate::sweep::job::ExtendTo;
use std::sync::Mutex;

/// Extends every unconverged job of `sweeps` that has a checkpoint to at most `cap` of total
/// run; prints a summary.
pub fn extend_unconverged(
    store: &Store,
    sweeps: &[SweepRow],
    cap: ExtendTo,
    workers: usize,
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
    let mut todo: Vec<PointRow> = Vec::new();
    let mut seen = std::collections::BTreeSet::new();
    for s in sweeps {
        for p in store.points(s.id)? {
            let unconverged = p.status == "done"
                && p.observables
                    .as_ref()
                    .and_then(wetgran_core::observe::converged_in_json)
                    == Some(false);
            if unconverged && seen.insert(p.job_id.clone()) {
                todo.push(p);
            }
        }
    }
    let queue = Mutex::new(todo.into_iter());
    let (extended, converged, skipped, failed) = (
        Mutex::new(0usize),
        Mutex::new(0usize),
        Mutex::new(0usize),
        Mutex::new(Vec::new()),
    );
    std::thread::scope(|scope| {
        for _ in 0..workers.max(1) {
            scope.spawn(|| {
                loop {
                    let Some(p) = queue.lock().expect("queue").next() else {
                        return;
                    };
                    let state = match store.checkpoint(&p.job_id) {
                        Ok(Some(s)) => s,
                        Ok(None) => {
                            *skipped.lock().expect("count") += 1;
                            continue;
                        }
                        Err(e) => {
                            failed.lock().expect("list").push(e.to_string());
                            continue;
                        }
                    };
                    match crate::sweep::job::extend_job(&p.spec, &state, cap, &mut |_| {}) {
                        Ok(Some(r)) => {
                            let ok = r
                                .observables
                                .get("convergence")
                                .and_then(|c| c.get("converged"))
                                .and_then(serde_json::Value::as_bool)
                                == Some(true);
                            match store.replace_result(&p.job_id, &r) {
                                Ok(()) => {
                                    *extended.lock().expect("count") += 1;
                                    *converged.lock().expect("count") += usize::from(ok);
                                }
                                Err(e) => failed.lock().expect("list").push(e.to_string()),
                            }
                        }
                        Ok(None) => *skipped.lock().expect("count") += 1,
                        Err(e) => failed
                            .lock()
                            .expect("list")
                            .push(format!("job {}: {e}", &p.job_id[..12])),
                    }
                }
            });
        }
    });
    let failed = failed.into_inner().expect("list");
    eprint!(
        "{}",
        extended_text(
            extended.into_inner().expect("count"),
            converged.into_inner().expect("count"),
            skipped.into_inner().expect("count"),
            &cap.describe(),
            &failed
        )
    );
    if failed.is_empty() {
        Ok(())
    } else {
        // The extensions that worked are stored; the exit status says that some did not.
        Err(Failure::JobsFailed(format!(
            "{} extension(s) failed (the others are stored)",
            failed.len()
        )))
    }
}
