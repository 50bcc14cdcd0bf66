//! Adaptive refinement of phase boundaries: where to spend the next jobs of a sweep.
//!
//! [`plan_round`] is pure: given the points of one slice of a phase map (their position in the
//! scaled plane of [`crate::boundary`] and their replicas' phases) it returns the next jobs.
//! [`driver`] runs rounds of it against the store and the scheduler.
//!
//! One round (docs/model-choices.md, "Adaptive refinement"):
//! 1. Each point takes the majority phase of its replicas ([`crate::boundary::majority`]); a
//!    point is *noisy* when its votes disagree.
//! 2. The points are Delaunay-triangulated in the plane, each axis divided by the span of the
//!    points along it (so both axes count alike whatever their units; log axes in decades).
//!    An edge between two majority phases is a *boundary edge*; it is *resolved* when its
//!    extent along each axis is at most `resolution` times that axis' span.
//! 3. For every unresolved boundary edge: an end that is noisy and has fewer than
//!    `max_replicas` votes gets more replicas (`replicas` more, up to `max_replicas`): the
//!    phase there is uncertain, and a new point beside it would not settle it. Otherwise the
//!    edge is split at its midpoint (a new point with `replicas` replicas).
//! 4. Costs are counted in jobs. Replicas come first (in point order), then new points, the
//!    longest edges first (ties by position); the round stops at its budget. Midpoints shared by
//!    two edges or on an existing point are taken once or not at all.
//!
//! Nothing is planned when every boundary edge is resolved: refinement stops there, or at the
//! budget.

pub mod driver;

use crate::boundary::{delaunay_pairs, majority};

/// Two positions closer than this fraction of the axis spans are the same point.
const SAME: f64 = 1e-9;

/// How to refine.
#[derive(Debug, Clone, PartialEq)]
pub struct Settings {
    /// Replicas of a new point (the sweep's `replicas`).
    pub replicas: u32,
    /// Most replicas a noisy point is raised to.
    pub max_replicas: u32,
    /// A boundary edge is resolved when it spans at most this fraction of each axis' range
    /// (0: never, refinement stops at the budget).
    pub resolution: f64,
}

/// A point of the plane (scaled coordinates) with its replicas' phases.
#[derive(Debug, Clone, PartialEq)]
pub struct Sample {
    pub x: f64,
    pub y: f64,
    /// Replica order; `None`: no result.
    pub votes: Vec<Option<String>>,
}

/// One planned step.
#[derive(Debug, Clone, PartialEq)]
pub enum Step {
    /// A new point at `(x, y)` (scaled coordinates) with `Settings::replicas` replicas.
    Point { x: f64, y: f64 },
    /// `add` more replicas of the sample with this index.
    Replicas { sample: usize, add: u32 },
}

/// What a round plans.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Plan {
    pub steps: Vec<Step>,
    /// Jobs the steps cost.
    pub cost: usize,
    /// Boundary edges longer than the resolution before this round.
    pub unresolved: usize,
}

/// Whether the votes of a point disagree.
pub fn noisy(votes: &[Option<String>]) -> bool {
    let mut phases = votes.iter().flatten();
    match phases.next() {
        Some(first) => phases.any(|p| p != first),
        None => false,
    }
}

/// Plans one round with at most `budget` jobs (see the module doc). Samples without a vote are
/// ignored; `blocked` positions (scaled) are never proposed as new points (e.g. whose scene
/// is invalid).
pub fn plan_round(
    samples: &[Sample],
    settings: &Settings,
    budget: usize,
    blocked: &[(f64, f64)],
) -> Plan {
    let voted: Vec<usize> = (0..samples.len())
        .filter(|&i| samples[i].votes.iter().any(Option::is_some))
        .collect();
    if voted.len() < 2 {
        return Plan::default();
    }
    let phase: Vec<String> = voted
        .iter()
        .map(|&i| majority(&samples[i].votes).expect("has a vote").0)
        .collect();
    let span = |f: &dyn Fn(&Sample) -> f64| {
        let (lo, hi) = voted
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |a, &i| {
                (a.0.min(f(&samples[i])), a.1.max(f(&samples[i])))
            });
        if hi > lo { hi - lo } else { 1.0 }
    };
    let (sx, sy) = (span(&|s| s.x), span(&|s| s.y));
    let pos: Vec<(f64, f64)> = voted
        .iter()
        .map(|&i| (samples[i].x / sx, samples[i].y / sy))
        .collect();
    let Ok(edges) = delaunay_pairs(&pos) else {
        return Plan::default();
    };

    let mut plan = Plan::default();
    let mut more: Vec<usize> = Vec::new(); // indices into `voted`
    let mut splits: Vec<(f64, f64, f64)> = Vec::new(); // (normalized length, x, y) scaled
    for (a, b) in edges {
        if phase[a] == phase[b] {
            continue;
        }
        let (dx, dy) = ((pos[a].0 - pos[b].0).abs(), (pos[a].1 - pos[b].1).abs());
        if dx <= settings.resolution && dy <= settings.resolution {
            continue;
        }
        plan.unresolved += 1;
        let uncertain = |k: usize| {
            let s = &samples[voted[k]];
            noisy(&s.votes) && (s.votes.len() as u32) < settings.max_replicas
        };
        let ends: Vec<usize> = [a, b].into_iter().filter(|&k| uncertain(k)).collect();
        if ends.is_empty() {
            let (sa, sb) = (&samples[voted[a]], &samples[voted[b]]);
            splits.push((dx.hypot(dy), 0.5 * (sa.x + sb.x), 0.5 * (sa.y + sb.y)));
        } else {
            more.extend(ends);
        }
    }
    more.sort_unstable();
    more.dedup();
    let mut left = budget;
    for k in more {
        let have = samples[voted[k]].votes.len() as u32;
        let add = settings
            .replicas
            .max(1)
            .min(settings.max_replicas.saturating_sub(have));
        if add == 0 || add as usize > left {
            continue;
        }
        left -= add as usize;
        plan.cost += add as usize;
        plan.steps.push(Step::Replicas {
            sample: voted[k],
            add,
        });
    }
    splits.sort_by(|p, q| {
        q.0.total_cmp(&p.0)
            .then(p.1.total_cmp(&q.1))
            .then(p.2.total_cmp(&q.2))
    });
    let per_point = settings.replicas.max(1) as usize;
    let mut taken: Vec<(f64, f64)> = Vec::new();
    for (_, x, y) in splits {
        if per_point > left {
            break;
        }
        // Positions read back from the store may differ in the last digits (10^x, then log10).
        let at =
            |&(px, py): &(f64, f64)| ((px - x) / sx).abs() < SAME && ((py - y) / sy).abs() < SAME;
        if taken.iter().any(at) || blocked.iter().any(at) || samples.iter().any(|s| at(&(s.x, s.y)))
        {
            continue;
        }
        taken.push((x, y));
        left -= per_point;
        plan.cost += per_point;
        plan.steps.push(Step::Point { x, y });
    }
    plan
}

#[cfg(test)]
mod tests {
    use super::*;

    fn s(x: f64, y: f64, v: &[&str]) -> Sample {
        Sample {
            x,
            y,
            votes: v.iter().map(|p| Some(p.to_string())).collect(),
        }
    }

    const SET: Settings = Settings {
        replicas: 1,
        max_replicas: 3,
        resolution: 0.0,
    };

    #[test]
    fn a_clean_boundary_edge_is_split_at_its_midpoint() {
        // Two points, one edge across phases: one new point halfway.
        let plan = plan_round(&[s(0.0, 0.0, &["a"]), s(2.0, 4.0, &["b"])], &SET, 10, &[]);
        assert_eq!(plan.steps, vec![Step::Point { x: 1.0, y: 2.0 }]);
        assert_eq!((plan.cost, plan.unresolved), (1, 1));
        // Blocked, nothing left to do on that edge.
        let plan = plan_round(
            &[s(0.0, 0.0, &["a"]), s(2.0, 4.0, &["b"])],
            &SET,
            10,
            &[(1.0, 2.0)],
        );
        assert!(plan.steps.is_empty());
    }

    #[test]
    fn a_noisy_end_gets_replicas_instead_of_a_new_point_until_max_replicas() {
        let pts = [s(0.0, 0.0, &["a", "b", "a"]), s(1.0, 0.0, &["b"])];
        let three = Settings {
            max_replicas: 4,
            ..SET
        };
        let plan = plan_round(&pts, &three, 10, &[]);
        assert_eq!(plan.steps, vec![Step::Replicas { sample: 0, add: 1 }]);
        // At the cap the majority stands and the edge is split.
        let plan = plan_round(&pts, &SET, 10, &[]);
        assert_eq!(plan.steps, vec![Step::Point { x: 0.5, y: 0.0 }]);
    }

    #[test]
    fn resolved_edges_and_the_budget_stop_refinement() {
        // 3 x 3 grid, phase b for x > 0.5: two columns of boundary edges.
        let mut pts = Vec::new();
        for i in 0..3 {
            for j in 0..3 {
                let x = i as f64 * 0.5;
                pts.push(s(x, j as f64 * 0.5, &[if x > 0.6 { "b" } else { "a" }]));
            }
        }
        let all = plan_round(&pts, &SET, 100, &[]);
        assert!(all.unresolved >= 3, "{all:?}");
        assert_eq!(all.cost, all.steps.len());
        let two = plan_round(&pts, &SET, 2, &[]);
        assert_eq!(two.cost, 2);
        assert_eq!(two.steps[..], all.steps[..2]);
        // Edges spanning half the range are resolved at resolution 0.5.
        let coarse = Settings {
            resolution: 0.5,
            ..SET
        };
        assert_eq!(plan_round(&pts, &coarse, 100, &[]), Plan::default());
    }
}
