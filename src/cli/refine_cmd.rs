//! `wetgran sweep refine`: the flags over the sweep file's `[refine]` table, checked (rounds in
//! `crate::refine::driver`; the refinement that `sweep run` / `sweep resume` continue is
//! `common::continue_refinement`).

use super::common::{Failure, refinement_report};
use crate::refine::Settings;
use crate::refine::driver::{refine_sweep, refined_jobs, registered_file};
use crate::store::Store;
use clap::Args;
use std::path::PathBuf;

/// `sweep refine`: the command-line overrides of the `[refine]` table.
#[derive(Debug, Args)]
#[command(mut_arg("jobs", |a| a.help(
    "Worker threads, one simulation each, for the jobs each round adds: 1 to the available \
     cores (default: all of them)"
)))]
pub struct RefineArgs {
    #[arg(long, help = super::common::SWEEP_HELP)]
    sweep: Option<String>,
    /// Database file; also from WETGRAN_DB (the flag wins).
    #[arg(long, env = "WETGRAN_DB", default_value = super::common::DEFAULT_DB)]
    pub db: PathBuf,
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
    #[command(flatten)]
    workers: super::common::Workers,
}

/// `wetgran sweep refine`: `budget` more jobs (default: what is left of the file's `[refine]`
/// budget).
pub(super) fn refine(over: RefineArgs) -> Result<(), Failure> {
    let (opts, db) = (over.workers.options()?, &over.db);
    let store = Store::open_existing(db)?;
    let row = super::common::latest_sweep(&store, over.sweep.as_deref(), false)?;
    super::interrupt::resume_hint_on_interrupt(Some(&row.name), db);
    let file = registered_file(&store, &row)?;
    let section = file.refine;
    let bad = |flag: &str, msg: String| Failure::BadInput(format!("{flag}: {msg}"));
    let budget = match (over.budget, section) {
        (Some(b), _) => b,
        (None, Some(s)) => s
            .budget
            .saturating_sub(refined_jobs(&store.point_summaries(&row)?, row.replicas)),
        (None, None) => {
            return Err(Failure::BadInput(format!(
                "sweep {}: give --budget (jobs to add) or a [refine] table in its sweep file",
                row.name
            )));
        }
    };
    if budget == 0 && over.budget.is_some() {
        return Err(bad("--budget", "= 0 is out of range: must be >= 1".into()));
    }
    let rounds = over.rounds.or(section.map(|s| s.rounds)).unwrap_or(4);
    if rounds == 0 {
        return Err(bad("--rounds", "= 0 is out of range: must be >= 1".into()));
    }
    let resolution = over
        .resolution
        .or(section.map(|s| s.resolution))
        .unwrap_or(0.0);
    if !(0.0..1.0).contains(&resolution) {
        return Err(bad(
            "--resolution",
            format!("= {resolution} is out of range: must be in [0, 1)"),
        ));
    }
    let max_replicas = over
        .max_replicas
        .or(section.map(|s| s.max_replicas))
        .unwrap_or(3 * row.replicas);
    if max_replicas < row.replicas {
        return Err(bad(
            "--max-replicas",
            format!(
                "= {max_replicas} is out of range: must be >= sweep.replicas = {}",
                row.replicas
            ),
        ));
    }
    let settings = Settings {
        replicas: row.replicas,
        max_replicas,
        resolution,
    };
    let o = refine_sweep(
        &store,
        &file,
        &row,
        budget,
        budget.div_ceil(rounds),
        &settings,
        &opts,
    )?;
    refinement_report(&row, &o);
    Ok(())
}
