//! Hysteresis of stored results: the phase labels of one grid point by start mode
//! (`initial.start`: hot, cold, or continued from the neighbouring point along
//! `[sweep.continuation]`) and whether they disagree. A sweep compares starts by an axis
//! `key = "initial.start"`, e.g. `values = ["hot", "cold"]` or `["hot", "continue"]`; the points
//! are grouped by their other coordinates. The first point of a continuation chain runs as its
//! `continuation.first` start (hot or cold) and counts as that.

use super::PointSummary;
use crate::sweep::file::Axis;
use std::collections::{BTreeMap, HashMap};
use wetgran_core::scene::StartMode;

/// The labels of one grid point (coordinates without the start axis) by start mode.
#[derive(Debug, Clone, PartialEq)]
pub struct StartLabels {
    pub coords: Vec<serde_json::Value>,
    /// The labels of the results of each start mode (replicas' labels, sorted, deduplicated).
    pub by_start: BTreeMap<StartMode, Vec<String>>,
    /// At least two starts have results and their label sets differ.
    pub hysteretic: bool,
}

/// Groups the finished results of a sweep (the reports' summaries) by grid point and start
/// mode, the groups in the order of their first result. A group is found by its coordinates'
/// JSON text in a hash map (a search of the groups would make the grouping quadratic).
pub fn by_start(axes: &[Axis], points: &[PointSummary]) -> Vec<StartLabels> {
    let keep: Vec<bool> = axes.iter().map(|a| a.key != "initial.start").collect();
    let mut out: Vec<StartLabels> = Vec::new();
    let mut index: HashMap<String, usize> = HashMap::new();
    for p in points {
        let Some(phase) = &p.phase else { continue };
        let coords: Vec<serde_json::Value> = p
            .coords
            .iter()
            .zip(&keep)
            .filter(|(_, k)| **k)
            .map(|(c, _)| c.clone())
            .collect();
        let key = serde_json::Value::from(coords.clone()).to_string();
        let i = *index.entry(key).or_insert_with(|| {
            out.push(StartLabels {
                coords,
                by_start: BTreeMap::new(),
                hysteretic: false,
            });
            out.len() - 1
        });
        out[i]
            .by_start
            .entry(p.start)
            .or_default()
            .push(phase.clone());
    }
    for g in &mut out {
        for labels in g.by_start.values_mut() {
            labels.sort();
            labels.dedup();
        }
        let mut sets = g.by_start.values();
        let first = sets.next();
        g.hysteretic = sets.any(|s| Some(s) != first);
    }
    out
}

impl StartLabels {
    /// Whether more than one start mode has results here (the point is compared).
    pub fn compared(&self) -> bool {
        self.by_start.len() > 1
    }
}
