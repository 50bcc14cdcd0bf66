//! `wetgran reclassify`: re-labels stored results from their stored observables, without
//! simulating. The labels come from `run::relabel` (`observe::classify` per point, then the
//! fluid-gas line rule along lines of constant Gamma) with either each job's own `[classify]`
//! thresholds (those of the sweep that last registered it) or the thresholds of a
//! `--classify FILE` (`run::relabel::relabel_stored`). `sweep run` calls the same relabelling
//! after registering a sweep, so a sweep that differs only in `[classify]` gets its labels at
//! once.

use super::common::{Failure, select};
use crate::run::relabel::relabel_stored;
use crate::store::Store;
use clap::Args;
use std::path::{Path, PathBuf};
use wetgran_core::observe::Thresholds;

/// Reads classifier thresholds from a TOML file: a `[classify]` table, or the keys at the top
/// level; missing keys take their defaults (docs/observables.md). Errors name the file.
pub(super) fn thresholds_file(path: &Path) -> Result<Thresholds, String> {
    let origin = path.display().to_string();
    let text = std::fs::read_to_string(path)
        .map_err(|e| format!("{origin}: cannot read the thresholds file: {e}"))?;
    let table: toml::Table = toml::from_str(&text).map_err(|e| format!("{origin}: {e}"))?;
    let body = match table.get("classify") {
        Some(toml::Value::Table(t)) if table.len() == 1 => t.clone(),
        Some(_) => {
            return Err(format!(
                "{origin}: give the thresholds as one [classify] table or as top-level keys, \
                 not both"
            ));
        }
        None => table,
    };
    let th: Thresholds = toml::Value::Table(body)
        .try_into()
        .map_err(|e: toml::de::Error| format!("{origin}: [classify]: {}", e.message()))?;
    th.validate(&origin).map_err(|e| e.to_string())?;
    Ok(th)
}

#[derive(Debug, Args)]
pub struct ReclassifyArgs {
    /// Only this sweep's results (default: every sweep's).
    #[arg(long)]
    sweep: Option<String>,
    /// Thresholds file (TOML).
    #[arg(long, value_name = "FILE")]
    classify: Option<PathBuf>,
    /// Database file; also from WETGRAN_DB (the flag wins).
    #[arg(long, env = "WETGRAN_DB", default_value = super::common::DEFAULT_DB)]
    pub db: PathBuf,
}

pub(super) fn reclassify(a: ReclassifyArgs) -> Result<(), Failure> {
    let thresholds = a
        .classify
        .as_deref()
        .map(thresholds_file)
        .transpose()
        .map_err(Failure::BadInput)?;
    let store = Store::open_existing(&a.db)?;
    let sweeps = select(&store, a.sweep.as_deref())?;
    let r = relabel_stored(&store, &sweeps, thresholds.as_ref())?;
    super::common::show(&format!("{}\n", r.text()));
    Ok(())
}
