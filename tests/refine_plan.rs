//! Adaptive refinement on a synthetic classifier with a known curved boundary (no simulation):
//! plan a round, "evaluate" the new points with the closure, plan again; the extracted boundary
//! (midpoints of Delaunay edges between phases, as `wetgran boundaries` takes them) is compared
//! with the true curve and with a uniform grid of the same number of evaluations.

use wetgran::boundary::delaunay_pairs;
use wetgran::refine::{Sample, Settings, Step, plan_round};

/// The plane: x = log10 E* in [-1, 1], y = Gamma in [0, 5]; the true boundary is the parabola
/// y = 1 + 2 x^2 (phase "g" above, "s" below).
const X: (f64, f64) = (-1.0, 1.0);
const Y: (f64, f64) = (0.0, 5.0);

fn truth(x: f64) -> f64 {
    1.0 + 2.0 * x * x
}

fn phase_of(x: f64, y: f64) -> String {
    if y > truth(x) { "g" } else { "s" }.to_string()
}

fn sample(x: f64, y: f64, replicas: usize, phase: &dyn Fn(f64, f64, usize) -> String) -> Sample {
    Sample {
        x,
        y,
        votes: (0..replicas).map(|r| Some(phase(x, y, r))).collect(),
    }
}

fn grid(n: usize, replicas: usize, phase: &dyn Fn(f64, f64, usize) -> String) -> Vec<Sample> {
    let at = |r: (f64, f64), k: usize| r.0 + (r.1 - r.0) * k as f64 / (n - 1) as f64;
    let mut out = Vec::new();
    for i in 0..n {
        for j in 0..n {
            out.push(sample(at(X, i), at(Y, j), replicas, phase));
        }
    }
    out
}

/// Distance, in units of the axis spans, from (x, y) to the true curve (dense search).
fn distance_to_truth(x: f64, y: f64) -> f64 {
    let (sx, sy) = (X.1 - X.0, Y.1 - Y.0);
    (0..=20_000)
        .map(|k| {
            let cx = X.0 + sx * k as f64 / 20_000.0;
            ((cx - x) / sx).hypot((truth(cx) - y) / sy)
        })
        .fold(f64::INFINITY, f64::min)
}

/// Boundary points (midpoints of edges between majority phases) and their worst and mean
/// distance to the true curve.
fn boundary_error(samples: &[Sample]) -> (usize, f64, f64) {
    let (sx, sy) = (X.1 - X.0, Y.1 - Y.0);
    let pos: Vec<(f64, f64)> = samples.iter().map(|s| (s.x / sx, s.y / sy)).collect();
    let phase: Vec<String> = samples
        .iter()
        .map(|s| wetgran::boundary::majority(&s.votes).unwrap().0)
        .collect();
    let d: Vec<f64> = delaunay_pairs(&pos)
        .unwrap()
        .into_iter()
        .filter(|&(a, b)| phase[a] != phase[b])
        .map(|(a, b)| {
            let (p, q) = (&samples[a], &samples[b]);
            distance_to_truth(0.5 * (p.x + q.x), 0.5 * (p.y + q.y))
        })
        .collect();
    let max = d.iter().copied().fold(0.0, f64::max);
    (d.len(), max, d.iter().sum::<f64>() / d.len() as f64)
}

/// Refines `samples` in `rounds` rounds of `budget / rounds` evaluations; returns the
/// evaluations spent.
fn refine(
    samples: &mut Vec<Sample>,
    settings: &Settings,
    budget: usize,
    rounds: usize,
    phase: &dyn Fn(f64, f64, usize) -> String,
) -> usize {
    let per_round = budget.div_ceil(rounds);
    let mut spent = 0;
    while spent < budget {
        let plan = plan_round(samples, settings, per_round.min(budget - spent), &[]);
        if plan.steps.is_empty() {
            break;
        }
        for step in plan.steps {
            match step {
                Step::Point { x, y } => {
                    samples.push(sample(x, y, settings.replicas as usize, phase))
                }
                Step::Replicas { sample: i, add } => {
                    let s = &mut samples[i];
                    for _ in 0..add {
                        let r = s.votes.len();
                        s.votes.push(Some(phase(s.x, s.y, r)));
                    }
                }
            }
        }
        spent += plan.cost;
    }
    spent
}

#[test]
fn refinement_beats_a_uniform_grid_of_equal_cost_on_a_curved_boundary() {
    let exact = |x: f64, y: f64, _: usize| phase_of(x, y);
    let settings = Settings {
        replicas: 1,
        max_replicas: 1,
        resolution: 0.0,
    };
    // 8 x 8 start + 192 refined evaluations = 256 = a uniform 16 x 16 grid.
    let mut refined = grid(8, 1, &exact);
    let spent = refine(&mut refined, &settings, 192, 6, &exact);
    assert_eq!(spent, 192);
    assert_eq!(refined.len(), 256);
    let uniform = grid(16, 1, &exact);
    let (nr, max_r, mean_r) = boundary_error(&refined);
    let (nu, max_u, mean_u) = boundary_error(&uniform);
    eprintln!(
        "refined: {nr} boundary points, max {max_r:.4}, mean {mean_r:.4}; \
         uniform: {nu} points, max {max_u:.4}, mean {mean_u:.4} (fractions of the axis spans)"
    );
    // A midpoint lies within half its edge of the curve; refinement shortens the edges there.
    assert!(max_r < 0.6 * max_u, "max {max_r} vs uniform {max_u}");
    assert!(mean_r < 0.6 * mean_u, "mean {mean_r} vs uniform {mean_u}");
    assert!(max_r < 0.03, "max distance {max_r}");
}

#[test]
fn refinement_stops_at_the_resolution_and_replicates_noisy_points() {
    // Noise: within 0.15 of the curve (in Gamma) replica 1 (of 0, 1, 2, 3) gets it wrong.
    let noisy = |x: f64, y: f64, r: usize| {
        if (y - truth(x)).abs() < 0.15 && r % 4 == 1 {
            if y > truth(x) { "s" } else { "g" }.to_string()
        } else {
            phase_of(x, y)
        }
    };
    let settings = Settings {
        replicas: 2,
        max_replicas: 4,
        resolution: 0.05,
    };
    let mut samples = grid(6, 2, &noisy);
    let spent = refine(&mut samples, &settings, 100_000, 1, &noisy);
    assert!(spent < 100_000);
    // Every boundary edge now spans at most 5 % of each axis: nothing left to plan.
    let last = plan_round(&samples, &settings, 100, &[]);
    assert_eq!((last.unresolved, last.cost), (0, 0), "{last:?}");
    // Points whose replicas disagree were raised to 4 replicas; the others kept 2.
    let raised = samples.iter().filter(|s| s.votes.len() == 4).count();
    assert!(raised > 0);
    for s in &samples {
        assert!(s.votes.len() == 2 || s.votes.len() == 4, "{s:?}");
        if s.votes.len() == 4 {
            assert!(
                (s.y - truth(s.x)).abs() < 0.15,
                "replicated far from the curve: {s:?}"
            );
        }
    }
    let (_, max, _) = boundary_error(&samples);
    eprintln!(
        "resolution 0.05: {} points, {raised} with 4 replicas, max distance {max:.4}",
        samples.len()
    );
    assert!(max < 0.05, "max distance {max}");
}

#[test]
fn the_same_inputs_give_the_same_points() {
    let exact = |x: f64, y: f64, _: usize| phase_of(x, y);
    let settings = Settings {
        replicas: 2,
        max_replicas: 2,
        resolution: 0.0,
    };
    let run = || {
        let mut s = grid(5, 2, &exact);
        refine(&mut s, &settings, 60, 3, &exact);
        s.iter().map(|s| (s.x, s.y)).collect::<Vec<_>>()
    };
    let a = run();
    assert_eq!(a.len(), 25 + 30);
    assert_eq!(a, run());
}
