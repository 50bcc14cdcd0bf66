//! `wetgran-bench`: engine speed on the reference systems of docs/performance.md.
//!
//! `wetgran-bench engine [--repeat R] [--scale S]` builds each reference system as a [`Scene`]
//! in code, runs a warm-up (10 % of the measured events, not timed), then times a fixed number of
//! events with `Engine::run_until(f64::INFINITY, Some(cap))`. Every repetition starts from a
//! fresh engine built from the same scene (same seed), so the repetitions time the same work and
//! their spread is machine noise. Reported: events/s and collisions/s (pair + wall collisions)
//! as median, minimum and maximum over the repetitions, the simulated time one repetition covers
//! and the events per unit of simulated time.
//!
//! The reference systems (a) 3D bulk, (b) 3D gravity, (c) 2D standard wet and (c') the same
//! dry are those of [`wetgran_testkit::reference`].

pub(crate) mod barrier;
pub(crate) mod engines;
pub(crate) mod jobs;
pub(crate) mod memory;
pub(crate) mod observer;
pub mod orchestrator;
pub mod orchestrator_scale;
pub(crate) mod shake;
pub(crate) mod slab;
pub mod stress;
pub mod stress_text;
pub(crate) mod tdmd;
pub(crate) mod wall;

use std::fmt::Write as _;
use std::hint::black_box;
use std::time::Instant;
use wetgran_core::scene::{Scene, lattice};
use wetgran_core::sim::event_driven::Engine;
use wetgran_testkit::reference::{system_a, system_b, system_c, system_c_dry};

/// Fewest events timed per repetition, whatever `scale` says (keeps tiny scales meaningful).
const MIN_EVENTS: u64 = 5_000;
/// Fewest warm-up events.
const MIN_WARMUP: u64 = 500;

/// The table of the benchmark `which`: `engine` (all reference systems) or `engine:LABELS` with
/// a comma-separated subset of `a,b,c,c'` (e.g. `engine:a` to profile one system), `wall`
/// (its error-against-cost plot also written to `svg` if given), `tdmd` (once per thread count
/// of `threads`, on its system widened `n_factor` times; the others are single-threaded), ...
pub fn run(
    which: &str,
    repeat: usize,
    scale: f64,
    svg: Option<&std::path::Path>,
    threads: &[usize],
    n_factor: usize,
    baseline: Option<&std::path::Path>,
) -> Result<String, String> {
    if !(scale.is_finite() && scale > 0.0) {
        return Err(format!("--scale = {scale} must be a finite number > 0"));
    }
    let (name, arg) = match which.split_once(':') {
        Some((name, arg)) => (name, Some(arg)),
        None => (which, None),
    };
    Ok(match (name, arg) {
        ("wall", None) => {
            let rows = wall::measure(repeat, scale);
            let mut text = wall::report(&rows);
            if let Some(path) = svg {
                // Whole or not at all, never over a database (`wetgran::output`).
                wetgran::output::write_file(
                    path,
                    wall::svg(&rows),
                    &wetgran::output::Protected::none(),
                )
                .map_err(|e| e.to_string())?;
                let _ = writeln!(text, "plot written to {}", path.display());
            }
            text
        }
        ("tdmd", None) => tdmd::report(&tdmd::measure_threads(repeat, scale, threads, n_factor)),
        ("slab", None) => slab::report(&slab::measure(repeat, scale), repeat, scale),
        ("memory", None) => memory::report(&memory::measure(scale)?),
        ("memory", Some(n)) => {
            // The child process of `memory` (one size).
            let n: usize = n
                .parse()
                .map_err(|_| format!("`{which}`: expected memory:N with a particle count N"))?;
            memory::child_text(&memory::measure_here(n)?)
        }
        ("observer", points) => {
            let only: Vec<&str> = points.map_or(vec![], |p| p.split(',').map(str::trim).collect());
            if let Some(bad) = only
                .iter()
                .find(|l| !observer::POINTS.iter().any(|p| p.0 == **l))
            {
                return Err(format!(
                    "unknown observer point `{bad}`: use gas, fluid, coexistence"
                ));
            }
            observer::report(&observer::measure(400, scale, &only))
        }
        ("engines", None) => engines::report(&engines::measure(repeat, scale), repeat, scale),
        ("barrier", None) => barrier::report(&barrier::measure(repeat, scale), repeat),
        ("jobs", None) => {
            let (rows, perf) = jobs::measure(repeat, scale, baseline)?;
            jobs::report(&rows, perf, jobs::bulk_rate(repeat, scale)?)
        }
        ("shake", None) => shake::report(&shake::measure(40, scale)),
        ("engine", labels) => {
            let only: Option<Vec<&str>> = labels.map(|l| l.split(',').map(str::trim).collect());
            engine_report(
                &engine_bench_only(repeat, scale, only.as_deref())?,
                repeat,
                scale,
            )
        }
        _ => {
            return Err(format!(
                "unknown benchmark `{which}`: use `engine`, `engine:LABELS` (LABELS from a,b,c,c'), `wall`, `shake`, `tdmd`, `slab`, `memory`, `engines`, `barrier`, `jobs`, `observer` or `observer:POINTS` (POINTS from gas,fluid,coexistence)"
            ));
        }
    })
}

/// One reference system of the engine benchmark.
#[derive(Debug, Clone)]
pub(crate) struct System {
    /// Short label used in the table: `a`, `b`, `c`, `c'`.
    pub label: &'static str,
    /// One line saying what the system is.
    pub description: &'static str,
    pub scene: Scene,
    /// Events timed per repetition at `scale = 1`.
    pub(crate) base_events: u64,
}

/// What one repetition measured.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Repetition {
    pub wall_seconds: f64,
    /// Events processed in the timed part (`EventCounts::total`).
    pub events: u64,
    /// Pair plus wall collisions in the timed part.
    pub collisions: u64,
    /// Simulated time covered by the timed part.
    pub simulated_time: f64,
}

/// All repetitions of one system.
#[derive(Debug, Clone)]
pub struct Row {
    pub label: &'static str,
    pub description: String,
    pub particles: usize,
    pub(crate) warmup_events: u64,
    pub(crate) reps: Vec<Repetition>,
}

/// Median, minimum and maximum.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Spread {
    pub median: f64,
    pub min: f64,
    pub max: f64,
}

impl Spread {
    pub(crate) fn of(values: impl IntoIterator<Item = f64>) -> Spread {
        let mut v: Vec<f64> = values.into_iter().collect();
        assert!(!v.is_empty(), "spread of no values");
        v.sort_by(f64::total_cmp);
        Spread {
            median: median(&v),
            min: v[0],
            max: v[v.len() - 1],
        }
    }
}

/// The median (the mean of the middle two for an even count); NaN for no values.
pub(crate) fn median(v: &[f64]) -> f64 {
    let mut v = v.to_vec();
    v.sort_by(f64::total_cmp);
    match v.len() {
        0 => f64::NAN,
        n if n % 2 == 1 => v[n / 2],
        n => 0.5 * (v[n / 2 - 1] + v[n / 2]),
    }
}

/// The `q` quantile of a sample, the nearest rank (`q = 0.5`: the upper of the middle two for
/// an even count); 0 for no values.
pub(crate) fn quantile(v: &[f64], q: f64) -> f64 {
    let mut v = v.to_vec();
    v.sort_by(f64::total_cmp);
    if v.is_empty() {
        return 0.0;
    }
    v[((v.len() - 1) as f64 * q).round() as usize]
}

impl Row {
    /// Events, or with `collisions` pair plus wall collisions, per wall-clock second.
    pub(crate) fn rate(&self, collisions: bool) -> Spread {
        Spread::of(self.reps.iter().map(|r| {
            let n = if collisions { r.collisions } else { r.events };
            n as f64 / r.wall_seconds.max(1e-12)
        }))
    }
}

/// How the initial lattice of a scene is filled, e.g. `39x39 sites per layer, 21.04 layers`.
fn lattice_fill(scene: &Scene) -> String {
    let (_, d_max) = scene.diameter_range();
    let a = scene.initial.lattice_spacing * d_max;
    let n = lattice::sites_per_axis(&scene.container.size, a);
    let d = scene.dimension;
    let per_layer: usize = n[..d - 1].iter().product();
    let lateral: Vec<String> = n[..d - 1].iter().map(|k| k.to_string()).collect();
    format!(
        "lattice spacing {a:.4}: {} sites per layer, {:.2} of {} layers filled",
        lateral.join("x"),
        scene.particles.count as f64 / per_layer as f64,
        n[d - 1]
    )
}

/// The four reference systems, validated.
pub(crate) fn systems() -> Result<Vec<System>, String> {
    let list = vec![
        System {
            label: "a",
            description: "3D bulk: 32000 elastic spheres, density 0.5, periodic cube 40^3, \
                          g = 0, T = 1",
            scene: system_a(),
            base_events: 2_000_000,
        },
        System {
            label: "b",
            description: "3D gravity: 32000 elastic spheres, g = 1, box 80x80x40 periodic in x,y, \
                          floor and lid, T = 1",
            scene: system_b(),
            base_events: 2_000_000,
        },
        System {
            label: "c",
            description: "2D standard wet: 1200 disks, 400x9, sigma_p 0.06, thin thread s_crit \
                          0.0711, E_cb 0.2844, eps 0.9, e_w 1, T/E_cb = 20",
            scene: system_c(),
            base_events: 1_000_000,
        },
        System {
            label: "c'",
            description: "2D standard dry: as (c) without bridges, T = 20 * 0.2844",
            scene: system_c_dry(),
            base_events: 1_000_000,
        },
    ];
    for s in &list {
        s.scene
            .validate(&format!("bench system ({})", s.label))
            .map_err(|e| e.to_string())?;
    }
    Ok(list)
}

// ----- measurement -------------------------------------------------------------------------

/// Warm-up, then `events` timed events, on a fresh engine of type `Engine<D, G, W>`.
fn measure_once<const D: usize, const G: bool, const W: bool>(
    scene: &Scene,
    warmup: u64,
    events: u64,
) -> Repetition {
    let mut engine = Engine::<D, G, W>::new(scene);
    engine.run_until(f64::INFINITY, Some(warmup));
    let c0 = engine.counts().clone();
    let t0 = engine.time();
    let cap = c0.total() + events;
    let start = Instant::now();
    let stopped_on_cap = !black_box(&mut engine).run_until(f64::INFINITY, Some(cap));
    let wall_seconds = start.elapsed().as_secs_f64();
    black_box(stopped_on_cap);
    let c1 = engine.counts();
    Repetition {
        wall_seconds,
        events: c1.total() - c0.total(),
        collisions: (c1.pair_collisions + c1.wall_collisions)
            - (c0.pair_collisions + c0.wall_collisions),
        simulated_time: engine.time() - t0,
    }
}

/// Picks the engine type the scene needs (only the combinations of the reference systems).
fn measure(scene: &Scene, warmup: u64, events: u64) -> Result<Repetition, String> {
    let grav = scene.gravity > 0.0;
    let wet = scene.is_wet();
    Ok(match (scene.dimension, grav, wet) {
        (3, false, false) => measure_once::<3, false, false>(scene, warmup, events),
        (3, true, false) => measure_once::<3, true, false>(scene, warmup, events),
        (2, true, true) => measure_once::<2, true, true>(scene, warmup, events),
        (2, true, false) => measure_once::<2, true, false>(scene, warmup, events),
        (d, g, w) => {
            return Err(format!(
                "no benchmark engine for dimension {d}, gravity {g}, bridges {w}"
            ));
        }
    })
}

/// Events timed per repetition and warm-up events for a base count and a scale.
pub(crate) fn event_budget(base_events: u64, scale: f64) -> (u64, u64) {
    let events = ((base_events as f64 * scale).round() as u64).max(MIN_EVENTS);
    let warmup = (events / 10).max(MIN_WARMUP);
    (events, warmup)
}

/// Runs the reference systems whose labels are in `only` (all if `None`) `repeat` times.
pub(crate) fn engine_bench_only(
    repeat: usize,
    scale: f64,
    only: Option<&[&str]>,
) -> Result<Vec<Row>, String> {
    let all = systems()?;
    if let Some(bad) = only
        .unwrap_or(&[])
        .iter()
        .find(|l| !all.iter().any(|s| s.label == **l))
    {
        return Err(format!(
            "unknown system `{bad}`: the systems are a, b, c, c'"
        ));
    }
    let mut rows = Vec::new();
    for sys in all {
        if only.is_some_and(|o| !o.contains(&sys.label)) {
            continue;
        }
        let (events, warmup) = event_budget(sys.base_events, scale);
        let reps = (0..repeat)
            .map(|_| measure(&sys.scene, warmup, events))
            .collect::<Result<_, _>>()?;
        rows.push(Row {
            label: sys.label,
            description: format!("{}; {}", sys.description, lattice_fill(&sys.scene)),
            particles: sys.scene.particles.count,
            warmup_events: warmup,
            reps,
        });
    }
    Ok(rows)
}

/// The printed table.
pub(crate) fn engine_report(rows: &[Row], repeat: usize, scale: f64) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "wetgran-bench engine: repeat = {repeat}, scale = {scale}; each repetition: fresh engine, \
         untimed warm-up, then the timed events"
    );
    let _ = writeln!(s, "systems:");
    for r in rows {
        let _ = writeln!(s, "  ({}) {}", r.label, r.description);
    }
    let _ = writeln!(
        s,
        "collisions = pair + wall collisions; events = all processed events (collisions, cell \
         crossings, well events, stale re-predictions)"
    );
    let _ = writeln!(
        s,
        "rates in millions per wall-clock second: median [min, max] over {repeat} repetition(s)"
    );
    let _ = writeln!(s);
    s.push_str("sys       N    events  warm-up               events/s [M]           collisions/s [M]  sim. time    events/t  coll.%\n");
    for r in rows {
        // Events and simulated time are the same in every repetition (same seed, same cap).
        let (events, t) = (r.reps[0].events, r.reps[0].simulated_time);
        let mega = |x: Spread| {
            format!(
                "{:.3} [{:.3}, {:.3}]",
                x.median / 1e6,
                x.min / 1e6,
                x.max / 1e6
            )
        };
        let _ = writeln!(
            s,
            "{:<4} {:>6} {:>9} {:>8} {:>26} {:>26} {:>10.4} {:>11.4e} {:>7.1}",
            format!("({})", r.label),
            r.particles,
            events,
            r.warmup_events,
            mega(r.rate(false)),
            mega(r.rate(true)),
            t,
            events as f64 / t,
            100.0 * r.reps[0].collisions as f64 / events.max(1) as f64,
        );
    }
    let wet = rows.iter().find(|r| r.label == "c");
    let dry = rows.iter().find(|r| r.label == "c'");
    if let (Some(wet), Some(dry)) = (wet, dry) {
        let _ = writeln!(s);
        let _ = writeln!(
            s,
            "dry/wet events-per-second ratio (c')/(c): {:.3} (collisions per second: {:.3})",
            dry.rate(false).median / wet.rate(false).median,
            dry.rate(true).median / wet.rate(true).median,
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tiny_engine_bench_runs_every_system() {
        let rows = engine_bench_only(1, 0.001, None).expect("bench runs");
        assert_eq!(rows.len(), 4);
        for r in &rows {
            assert_eq!(r.reps.len(), 1);
            let rep = r.reps[0];
            assert!(
                rep.events >= MIN_EVENTS,
                "({}) timed {} events",
                r.label,
                rep.events
            );
            assert!(rep.collisions > 0 && rep.collisions <= rep.events);
            assert!(rep.simulated_time > 0.0 && rep.wall_seconds > 0.0);
        }
        let text = engine_report(&rows, 1, 0.001);
        assert!(text.contains("dry/wet events-per-second ratio"));
        let run = |which| run(which, 1, 0.001, None, &[1], 1, None);
        assert!(run("engine:c'").is_ok());
        assert!(run("nonsense").is_err() && run("engine:x").is_err() && run("wall:").is_err());
        assert_eq!(engine_bench_only(1, 0.001, Some(&["c'"])).unwrap().len(), 1);
        assert!(super::run("wall", 1, 0.0, None, &[1], 1, None).is_err());
    }

    #[test]
    fn spread_quantiles_and_budget() {
        let s = Spread::of([3.0, 1.0, 2.0]);
        assert_eq!((s.median, s.min, s.max), (2.0, 1.0, 3.0));
        assert_eq!(Spread::of([1.0, 4.0]).median, 2.5);
        assert!(median(&[]).is_nan());
        let v: Vec<f64> = (1..=101).map(f64::from).collect();
        assert_eq!((quantile(&v, 0.5), quantile(&v, 0.99)), (51.0, 100.0));
        assert_eq!(quantile(&[1.0, 4.0], 0.5), 4.0);
        assert_eq!(quantile(&[], 0.5), 0.0);
        assert_eq!(event_budget(2_000_000, 1.0), (2_000_000, 200_000));
        assert_eq!(event_budget(2_000_000, 0.001), (MIN_EVENTS, MIN_WARMUP));
    }
}
