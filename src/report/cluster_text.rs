//! The text of the cluster commands: what `sweep collect` did for a sweep, and the Slurm part
//! of `sweep status` (task states as recorded and in the queue). Pure functions of the stored
//! rows and the collection's outcome.

use crate::cluster::{Collected, QueueStates};
use crate::run::runner::point_label;
use crate::store::{PointRow, SweepRow, TaskRow};
use crate::terminal::escape;
use std::collections::HashMap;
use std::fmt::Write as _;

/// Counts one more `key` in a list of (key, count) kept in order of first appearance.
fn count(counts: &mut Vec<(String, usize)>, key: String) {
    match counts.iter_mut().find(|(k, _)| *k == key) {
        Some((_, n)) => *n += 1,
        None => counts.push((key, 1)),
    }
}

/// `3 running, 1 pending`: the counts in their order.
fn counts_text(counts: &[(String, usize)]) -> String {
    counts
        .iter()
        .map(|(s, n)| format!("{n} {s}"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The lines `sweep collect` prints for one sweep.
///
/// `points` are the sweep's stored points (their labels name the tasks).
pub fn collected_text(sweep: &SweepRow, points: &[PointRow], c: &Collected) -> String {
    let labels: HashMap<&str, String> = points
        .iter()
        .map(|p| (p.job_id.as_str(), point_label(sweep, &p.coords, p.replica)))
        .collect();
    let label = |id: &str| labels.get(id).cloned().unwrap_or_else(|| "?".to_string());
    let mut out = String::new();
    let mut by_state: Vec<(String, usize)> = Vec::new();
    for (_, s) in &c.waiting {
        let s = s.clone().unwrap_or_else(|| "state unknown".to_string());
        count(&mut by_state, s);
    }
    let _ = writeln!(
        out,
        "sweep {}: {} result(s) stored, {} already stored (not stored twice), {} failed, {} \
         corrupt, {} missing, {} waiting{}{}",
        escape(&sweep.name),
        c.stored.len(),
        c.duplicates.len(),
        c.failed.len(),
        c.corrupt.len(),
        c.missing.len(),
        c.waiting.len(),
        if by_state.is_empty() {
            String::new()
        } else {
            format!(" ({})", counts_text(&by_state))
        },
        if c.earlier > 0 {
            format!("; {} task(s) collected before", c.earlier)
        } else {
            String::new()
        }
    );
    for (what, list) in [
        ("failed ", &c.failed),
        ("corrupt", &c.corrupt),
        ("missing", &c.missing),
    ] {
        for t in list {
            let _ = writeln!(
                out,
                "  {what} {} (job {}, task {}_{}): {}",
                label(&t.job_id),
                t.job_id.get(..12).unwrap_or(&t.job_id),
                escape(t.slurm_job.as_deref().unwrap_or("?")),
                t.task,
                escape(t.message.as_deref().unwrap_or(""))
            );
        }
    }
    if let Some(note) = &c.queue_note {
        let _ = writeln!(
            out,
            "  (the Slurm queue could not be asked: {note}; tasks without a result count as \
             waiting)"
        );
    }
    let again = c.failed.len() + c.corrupt.len() + c.missing.len();
    if again > 0 {
        let _ = writeln!(
            out,
            "  `wetgran sweep submit {} --slurm` submits the {again} failed, corrupt or missing \
             job(s) again",
            escape(&sweep.file)
        );
    }
    out
}

/// The Slurm part of `sweep status` for one submitted sweep (`tasks` not empty): task states as
/// recorded, and for the tasks not yet collected their state in the queue (`queue`, from
/// `cluster::queue_states`).
pub fn slurm_status_text(tasks: &[TaskRow], queue: &QueueStates) -> String {
    let mut arrays: Vec<String> = Vec::new();
    let mut recorded: HashMap<&'static str, usize> = HashMap::new();
    for t in tasks {
        let j = t.slurm_job.clone().unwrap_or_else(|| "?".to_string());
        if !arrays.contains(&j) {
            arrays.push(j);
        }
        *recorded.entry(t.state.as_str()).or_default() += 1;
    }
    let mut queued: Vec<(String, usize)> = Vec::new();
    for state in &queue.states {
        count(&mut queued, state.clone());
    }
    let mut out = String::new();
    let order = [
        "submitted",
        "collected",
        "duplicate",
        "failed",
        "missing",
        "corrupt",
    ];
    let _ = writeln!(
        out,
        "  slurm  {} task(s) in {} array(s) (job {}): {}",
        tasks.len(),
        arrays.len(),
        arrays.join(", "),
        order
            .iter()
            .filter_map(|s| recorded.get(s).map(|n| format!("{n} {s}")))
            .collect::<Vec<_>>()
            .join(", ")
    );
    if !queued.is_empty() {
        let _ = writeln!(out, "         not collected yet: {}", counts_text(&queued));
    }
    if let Some(why) = &queue.unavailable {
        let _ = writeln!(out, "         (no Slurm queue to ask: {why})");
    }
    out
}
