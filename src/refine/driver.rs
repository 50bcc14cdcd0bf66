//! Refinement rounds against the store: run what is pending, read the sweep's phase map, plan a
//! round per slice ([`super::plan_round`]), add its jobs to the sweep (new points numbered from
//! [`REFINED_FROM`], more replicas of existing points), run them with the same scheduler, again.
//!
//! The budget is split into rounds of `ceil(budget / rounds)` jobs (fixed by the whole budget,
//! so that an interrupted refinement continues with rounds of the same size); a round's budget is shared
//! by the slices in order. Refinement stops when the budget is spent or a round plans nothing
//! (every boundary edge resolved). Everything is decided from the stored results (relabelled by
//! the line rule after each round's run, `run::relabel::relabel_changed`), so a run
//! interrupted at any point continues with the same plan: `sweep resume` (or `sweep refine`
//! again) runs the pending jobs of the interrupted round first, and two refinements from the
//! same results add the same points.

use super::{Sample, Settings, Step, plan_round};
use crate::boundary::{Observation, PlaneAxis, phase_map};
use crate::run::relabel::relabel_changed;
use crate::run::{RunOptions, run_sweeps};
use crate::store::{PointSummary, REFINED_FROM, Store, StoreError, SweepRow};
use crate::sweep::{SweepFile, SweepJob};
use std::collections::BTreeMap;

/// What a refinement did.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Outcome {
    /// Rounds that added jobs.
    pub rounds: usize,
    /// Jobs added.
    pub added: usize,
    /// Whether it stopped because nothing was left to refine (rather than at the budget).
    pub resolved: bool,
}

/// Why refinement cannot go on.
#[derive(Debug)]
pub enum RefineError {
    Store(StoreError),
    /// The sweep cannot be refined (named sweep, what is wrong).
    Bad(String),
}

impl From<StoreError> for RefineError {
    fn from(e: StoreError) -> Self {
        RefineError::Store(e)
    }
}

impl std::fmt::Display for RefineError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            RefineError::Store(e) => e.fmt(f),
            RefineError::Bad(m) => f.write_str(m),
        }
    }
}

impl std::error::Error for RefineError {}

/// Jobs refinement has added to a sweep so far: rows of refined points and replicas beyond the
/// sweep's own.
pub fn refined_jobs(rows: &[PointSummary], replicas: u32) -> usize {
    rows.iter()
        .filter(|r| r.point >= REFINED_FROM || r.replica >= replicas as i64)
        .count()
}

/// Runs up to `budget` more jobs of refinement on a registered sweep (`file` is its sweep file,
/// as registered), at most `per_round` per round.
pub fn refine_sweep(
    store: &Store,
    file: &SweepFile,
    row: &SweepRow,
    budget: usize,
    per_round: usize,
    settings: &Settings,
    opts: &RunOptions,
) -> Result<Outcome, RefineError> {
    let per_round = per_round.max(1);
    let mut left = budget;
    let mut out = Outcome::default();
    loop {
        run_sweeps(store, std::slice::from_ref(row), opts)?;
        // The plan reads the labels: the line rule's, from every stored result, as after any
        // run, so that a refinement interrupted anywhere plans the same round again.
        let relabelled = relabel_changed(store, row)?;
        if opts.show_progress && relabelled.changed() > 0 {
            eprintln!(
                "sweep {}: labels along lines of constant Gamma (docs/model.md 7): {}",
                crate::terminal::escape(&row.name),
                relabelled.text()
            );
        }
        if left == 0 {
            return Ok(out);
        }
        let rows = store.point_summaries(row)?;
        let jobs = plan_jobs(file, row, &rows, per_round.min(left), settings)?;
        if jobs.is_empty() {
            out.resolved = true;
            return Ok(out);
        }
        store.add_jobs(row.id, &jobs)?;
        left = left.saturating_sub(jobs.len());
        out.added += jobs.len();
        out.rounds += 1;
        if opts.show_progress {
            eprintln!(
                "sweep {}: refinement round {}: {} job(s) added, {left} left of the budget",
                crate::terminal::escape(&row.name),
                out.rounds,
                jobs.len()
            );
        }
    }
}

/// The jobs of the next round from the stored rows (see the module doc).
pub fn plan_jobs(
    file: &SweepFile,
    row: &SweepRow,
    rows: &[PointSummary],
    budget: usize,
    settings: &Settings,
) -> Result<Vec<SweepJob>, RefineError> {
    let bad = |m: String| RefineError::Bad(format!("sweep {}: {m}", row.name));
    // Unconverged points carry no boundary, so refinement does not chase them.
    let obs: Vec<Observation> = rows.iter().map(Observation::of_summary).collect();
    let map = phase_map(&row.axes, &obs).map_err(|e| bad(e.to_string()))?;
    let (Some(xa), Some(ya)) = (&map.x, &map.y) else {
        return Err(bad(
            "refinement needs two numeric axes (the plane of the phase map)".to_string(),
        ));
    };
    // Point index and replica count of every stored point, by its coordinates.
    let mut index: BTreeMap<String, (i64, i64)> = BTreeMap::new();
    for r in rows {
        let e = index.entry(key(&r.coords)).or_insert((r.point, 0));
        e.1 = e.1.max(r.replica + 1);
    }
    let mut next_point = rows
        .iter()
        .map(|r| r.point + 1)
        .filter(|&p| p > REFINED_FROM)
        .max()
        .unwrap_or(REFINED_FROM);
    let plane = |c: &[serde_json::Value], a: &PlaneAxis| c[a.index].as_f64().map(|v| a.scale(v));
    let n_slices = map.slices.len().max(1);
    let mut jobs = Vec::new();
    let mut spent = 0;
    for slice in &map.slices {
        let Some(template) = slice.points.first() else {
            continue;
        };
        let same_slice = |c: &[serde_json::Value]| {
            (0..c.len())
                .filter(|&i| i != xa.index && i != ya.index)
                .all(|i| c[i] == template.coords[i])
        };
        let samples: Vec<Sample> = slice
            .points
            .iter()
            .map(|p| Sample {
                x: xa.scale(p.x),
                y: ya.scale(p.y),
                votes: p.votes.clone(),
            })
            .collect();
        // Stored points without a vote (pending, failed) are not proposed again.
        let mut blocked: Vec<(f64, f64)> = rows
            .iter()
            .filter(|r| same_slice(&r.coords))
            .filter_map(|r| Some((plane(&r.coords, xa)?, plane(&r.coords, ya)?)))
            .collect();
        let slice_budget = budget.div_ceil(n_slices).min(budget - spent);
        'plan: loop {
            let plan = plan_round(&samples, settings, slice_budget, &blocked);
            let mut slice_jobs = Vec::new();
            let mut point = next_point;
            for step in &plan.steps {
                let (p, coords, from, to) = match *step {
                    Step::Point { x, y } => {
                        let mut c = template.coords.clone();
                        c[xa.index] = value(&row.axes[xa.index], xa.unscale(x));
                        c[ya.index] = value(&row.axes[ya.index], ya.unscale(y));
                        if index.contains_key(&key(&c))
                            || slice_jobs.iter().any(|j: &SweepJob| j.coords == c)
                        {
                            // An integer axis rounded it onto a point there is already.
                            blocked.push((x, y));
                            continue 'plan;
                        }
                        point += 1;
                        (point - 1, c, 0, settings.replicas.max(1))
                    }
                    Step::Replicas { sample, add } => {
                        let c = slice.points[sample].coords.clone();
                        let (p, have) = index[&key(&c)];
                        (p, c, have as u32, have as u32 + add)
                    }
                };
                let made = file
                    .jobs_at(p as usize, &coords, from..to)
                    .map_err(|e| bad(e.to_string()))?;
                match (made, step) {
                    (Ok(j), _) => slice_jobs.extend(j),
                    (Err(_), &Step::Point { x, y }) => {
                        // Outside the valid region (a scene constraint fails): never
                        // proposed again, plan the slice anew.
                        blocked.push((x, y));
                        continue 'plan;
                    }
                    (Err(e), Step::Replicas { .. }) => return Err(bad(e.to_string())),
                }
            }
            next_point = point;
            spent += slice_jobs.len();
            jobs.extend(slice_jobs);
            break;
        }
    }
    Ok(jobs)
}

/// A new value on an axis: rounded to an integer where every grid value is an integer (a count,
/// a seed), else the number itself.
fn value(axis: &crate::sweep::Axis, v: f64) -> serde_json::Value {
    if axis.values.iter().all(|g| g.is_i64() || g.is_u64()) {
        serde_json::json!(v.round() as i64)
    } else {
        serde_json::json!(v)
    }
}

fn key(c: &[serde_json::Value]) -> String {
    serde_json::to_string(c).expect("serializes")
}

/// The registered sweep file of a stored sweep (its text as registered; the base scene is
/// read again, relative to the file's path as registered).
pub fn registered_file(store: &Store, row: &SweepRow) -> Result<SweepFile, RefineError> {
    let source = store.sweep_source(row.id)?;
    SweepFile::parse(&source, std::path::Path::new(&row.file)).map_err(|e| {
        RefineError::Bad(format!(
            "sweep {}: its registered file cannot be read again: {e}",
            row.name
        ))
    })
}

/// After `sweep run` / `sweep resume`: continues the refinement of every given sweep whose file
/// has a `[refine]` table, up to its budget; `done` hears of each sweep refined.
pub fn continue_refinement(
    store: &Store,
    rows: &[SweepRow],
    opts: &RunOptions,
    done: &mut dyn FnMut(&SweepRow, &Outcome),
) -> Result<(), RefineError> {
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
            .saturating_sub(refined_jobs(&store.point_summaries(row)?, row.replicas));
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
            opts,
        )?;
        done(row, &o);
    }
    Ok(())
}
