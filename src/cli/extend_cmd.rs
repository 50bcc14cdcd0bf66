//! `sweep resume --extend MAX_PERIODS` (or `--extend-time MAX_TIME`): checks the cap, runs the
//! extension of the unconverged finished jobs through the worker pool of every run
//! (`run::extend`) and prints its summary.

use super::common::Failure;
use crate::report::sweep_text::extended_text;
use crate::run::RunOptions;
use crate::run::extend::extend_unconverged;
use crate::store::{Store, SweepRow};
use crate::sweep::job::ExtendTo;

/// Extends every unconverged job of `sweeps` that has a checkpoint to at most `cap` of total
/// run; prints a summary.
pub(super) fn extend_and_report(
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
    let s = extend_unconverged(store, sweeps, cap, opts.jobs, opts.table_cache_mib, true)?;
    eprint!(
        "{}",
        extended_text(
            s.extended,
            s.converged,
            s.skipped,
            &cap.describe(),
            &s.failed
        )
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
