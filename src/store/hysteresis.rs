//! Hysteresis of stored results: the phase labels of one grid point by start mode
//! (`initial.start`, hot or cold) and whether they disagree. A sweep compares the two starts by
//! an axis `key = "initial.start"`, `values = ["hot", "cold"]`; the points are grouped by their
//! other coordinates.

use super::PointRow;
use crate::scene::StartMode;
use crate::sweep::file::Axis;

/// The labels of one grid point (coordinates without the start axis) by start mode.
#[derive(Debug, Clone, PartialEq)]
pub struct StartLabels {
    pub coords: Vec<serde_json::Value>,
    /// Labels of the hot-start results (one per replica), sorted.
    pub hot: Vec<String>,
    /// Labels of the cold-start results, sorted.
    pub cold: Vec<String>,
    /// Both starts have results and their label sets differ.
    pub hysteretic: bool,
}

/// Groups the finished results of a sweep by grid point and start mode.
pub fn by_start(axes: &[Axis], points: &[PointRow]) -> Vec<StartLabels> {
    let keep: Vec<bool> = axes.iter().map(|a| a.key != "initial.start").collect();
    let mut out: Vec<StartLabels> = Vec::new();
    for p in points {
        let Some(phase) = &p.phase else { continue };
        let coords: Vec<serde_json::Value> = p
            .coords
            .iter()
            .zip(&keep)
            .filter(|(_, k)| **k)
            .map(|(c, _)| c.clone())
            .collect();
        let i = match out.iter().position(|g| g.coords == coords) {
            Some(i) => i,
            None => {
                out.push(StartLabels {
                    coords,
                    hot: Vec::new(),
                    cold: Vec::new(),
                    hysteretic: false,
                });
                out.len() - 1
            }
        };
        match p.spec.scene.initial.start {
            StartMode::Hot => out[i].hot.push(phase.clone()),
            StartMode::Cold => out[i].cold.push(phase.clone()),
        }
    }
    for g in &mut out {
        g.hot.sort();
        g.hot.dedup();
        g.cold.sort();
        g.cold.dedup();
        g.hysteretic = !g.hot.is_empty() && !g.cold.is_empty() && g.hot != g.cold;
    }
    out
}
