//! `wetgran reclassify`: re-labels stored results from their stored observables, without
//! simulating. The labels come from `run::relabel` (`observe::classify` per point, then the
//! fluid-gas line rule along lines of constant Gamma) with either each job's own `[classify]`
//! thresholds (those of the sweep that last registered it) or the thresholds of a
//! `--classify FILE`. `sweep run` calls the same relabelling after
//! registering a sweep, so a sweep that differs only in `[classify]` gets its labels at once.

use super::common::{Failure, exit, select};
use crate::observe::{Observables, Thresholds};
use crate::run::relabel::relabel;
use crate::store::{Store, SweepRow};
use std::collections::BTreeMap;
use std::path::Path;
use std::process::ExitCode;

/// What a relabelling changed: label transitions `(from, to)` with their counts, the number of
/// results re-labelled and of those left alone.
#[derive(Debug, Default, Clone, PartialEq)]
pub struct Relabelled {
    pub results: usize,
    /// Results whose stored observables this wetgran cannot read (left as they are).
    pub unreadable: usize,
    pub changes: BTreeMap<(String, String), usize>,
}

impl Relabelled {
    /// Number of results whose label changed.
    pub fn changed(&self) -> usize {
        self.changes.values().sum()
    }

    /// `n result(s) re-labelled: 3 label(s) changed: f -> g 2, s -> f 1` (or `no label
    /// changed`).
    pub fn text(&self) -> String {
        let mut text = self.changes_text();
        if self.unreadable > 0 {
            text.push_str(&format!(
                "; {} result(s) left as they were (observables not readable by this wetgran)",
                self.unreadable
            ));
        }
        text
    }

    fn changes_text(&self) -> String {
        if self.changes.is_empty() {
            return format!("{} result(s) re-labelled: no label changed", self.results);
        }
        let parts: Vec<String> = self
            .changes
            .iter()
            .map(|((from, to), n)| format!("{from} -> {to} {n}"))
            .collect();
        format!(
            "{} result(s) re-labelled: {} label(s) changed: {}",
            self.results,
            self.changed(),
            parts.join(", ")
        )
    }
}

/// Reads classifier thresholds from a TOML file: a `[classify]` table, or the keys at the top
/// level; missing keys take their defaults (docs/observables.md). Errors name the file.
pub fn thresholds_file(path: &Path) -> Result<Thresholds, String> {
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

/// Re-labels every stored result of `sweeps` from its stored observables with `thresholds`, or
/// with the job's own `[classify]` thresholds when `None`, the fluid-gas line rule included
/// (`run::relabel`, MODEL.md 7); writes only labels that changed or whose decision numbers
/// changed. A job shared by several of the given sweeps is counted once (the last sweep's
/// lines decide its label).
pub(super) fn relabel_sweeps(
    store: &Store,
    sweeps: &[SweepRow],
    thresholds: Option<&Thresholds>,
) -> Result<Relabelled, Failure> {
    let mut labels: BTreeMap<
        String,
        (
            Option<String>,
            Option<serde_json::Value>,
            String,
            serde_json::Value,
        ),
    > = BTreeMap::new();
    let mut out = Relabelled::default();
    let mut unreadable = std::collections::HashSet::new();
    for s in sweeps {
        let points = store.points(s.id)?;
        for p in &points {
            if let Some(o) = &p.observables
                && serde_json::from_value::<Observables>(o.clone()).is_err()
            {
                // Observables this wetgran cannot read (another version's layout) keep their
                // label.
                unreadable.insert(p.job_id.clone());
            }
        }
        let before: BTreeMap<&str, &crate::store::PointRow> =
            points.iter().map(|p| (p.job_id.as_str(), p)).collect();
        for l in relabel(&points, thresholds) {
            let p = before[l.job_id.as_str()];
            let phase = l.classification.phase.to_string();
            let decided_on =
                serde_json::to_value(&l.classification.decided_on).expect("decision serializes");
            labels.insert(
                l.job_id.clone(),
                (p.phase.clone(), p.decided_on.clone(), phase, decided_on),
            );
        }
    }
    out.unreadable = unreadable.len();
    let mut updates = Vec::new();
    for (job_id, (old_phase, old_decided, phase, decided_on)) in labels {
        out.results += 1;
        let old = old_phase.clone().unwrap_or_else(|| "-".to_string());
        if old != phase {
            *out.changes.entry((old, phase.clone())).or_insert(0) += 1;
        }
        if old_phase.as_deref() != Some(phase.as_str()) || old_decided.as_ref() != Some(&decided_on)
        {
            updates.push((job_id, phase, decided_on));
        }
    }
    store.relabel(&updates)?;
    Ok(out)
}

/// `wetgran reclassify [--sweep NAME] [--classify FILE] [--db PATH]`.
pub fn reclassify(db: &Path, sweep: Option<&str>, classify_file: Option<&Path>) -> ExitCode {
    exit((|| {
        let thresholds = classify_file
            .map(thresholds_file)
            .transpose()
            .map_err(Failure::BadInput)?;
        let store = Store::open_existing(db)?;
        let sweeps = select(&store, sweep)?;
        let r = relabel_sweeps(&store, &sweeps, thresholds.as_ref())?;
        println!("{}", r.text());
        Ok(())
    })())
}
