//! `wetgran sweep refine` and the refinement that `sweep run` / `sweep resume` continue for a
//! sweep file with a `[refine]` table (rounds in `crate::refine::driver`).

use super::sweep_cmd::Failure;
use crate::refine::Settings;
use crate::refine::driver::{RefineError, refine_sweep, refined_jobs};
use crate::run::RunOptions;
use crate::store::{Store, SweepRow};
use crate::sweep::SweepFile;
use std::path::Path;

/// Command-line overrides of the `[refine]` table.
#[derive(Debug, Clone, Copy, Default)]
pub struct Overrides {
    pub budget: Option<usize>,
    pub rounds: Option<usize>,
    pub resolution: Option<f64>,
    pub max_replicas: Option<u32>,
}

impl From<RefineError> for Failure {
    fn from(e: RefineError) -> Self {
        match e {
            RefineError::Store(e) => e.into(),
            RefineError::Bad(m) => Failure::BadInput(m),
        }
    }
}

/// The registered sweep file of a stored sweep (its text as registered; the base scene is
/// read again, relative to the file's path as registered).
fn registered_file(store: &Store, row: &SweepRow) -> Result<SweepFile, Failure> {
    let source = store.sweep_source(row.id)?;
    SweepFile::parse(&source, Path::new(&row.file)).map_err(|e| {
        Failure::BadInput(format!(
            "sweep {}: its registered file cannot be read again: {e}",
            row.name
        ))
    })
}

fn opts(jobs: usize) -> RunOptions {
    RunOptions {
        jobs,
        retry_failed: false,
        show_progress: true,
        table_cache_mib: crate::sim::event_driven::table_cache::DEFAULT_TABLE_CACHE_MIB,
    }
}

fn report(row: &SweepRow, o: &crate::refine::driver::Outcome) {
    eprintln!(
        "sweep {}: refinement added {} job(s) in {} round(s){}",
        row.name,
        o.added,
        o.rounds,
        if o.resolved {
            "; every boundary edge is resolved"
        } else {
            ""
        }
    );
}

/// `wetgran sweep refine`: `budget` more jobs (default: what is left of the file's `[refine]`
/// budget).
pub fn refine(db: &Path, name: Option<&str>, over: Overrides, jobs: usize) -> Result<(), Failure> {
    let store = Store::open_existing(db)?;
    let row = match name {
        Some(n) => store.sweep(n)?,
        None => {
            let mut all = store.sweeps()?;
            if all.len() != 1 {
                return Err(Failure::BadInput(format!(
                    "{}: {} sweeps in this database: name one with --sweep",
                    db.display(),
                    all.len()
                )));
            }
            all.remove(0)
        }
    };
    let file = registered_file(&store, &row)?;
    let section = file.refine;
    let bad = |flag: &str, msg: String| Failure::BadInput(format!("{flag}: {msg}"));
    let budget = match (over.budget, section) {
        (Some(b), _) => b,
        (None, Some(s)) => s
            .budget
            .saturating_sub(refined_jobs(&store.points(row.id)?, row.replicas)),
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
        &opts(jobs),
    )?;
    report(&row, &o);
    Ok(())
}

/// After `sweep run` / `sweep resume`: continues the refinement of every given sweep whose file
/// has a `[refine]` table, up to its budget.
pub fn continue_refinement(store: &Store, rows: &[SweepRow], jobs: usize) -> Result<(), Failure> {
    for row in rows {
        let source = store.sweep_source(row.id)?;
        let has_refine = toml::from_str::<toml::Table>(&source)
            .map(|t| t.contains_key("refine"))
            .unwrap_or(false);
        if !has_refine {
            continue;
        }
        let file = registered_file(store, row)?;
        let Some(s) = file.refine else {
            continue;
        };
        let left = s
            .budget
            .saturating_sub(refined_jobs(&store.points(row.id)?, row.replicas));
        if left == 0 {
            continue;
        }
        let settings = Settings {
            replicas: row.replicas,
            max_replicas: s.max_replicas,
            resolution: s.resolution,
        };
        let o = refine_sweep(
            store,
            &file,
            row,
            left,
            s.budget.div_ceil(s.rounds),
            &settings,
            &opts(jobs),
        )?;
        report(row, &o);
    }
    Ok(())
}
