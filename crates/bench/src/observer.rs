//! `wetgran-bench observer`: what the location-change observer costs in a shaken run of the 2D
//! standard wet system (MODEL.md 1: N = 1200, 400 x 9, eps = 1, the base scene of
//! `sweeps/shaken_2d_elastic.toml`), triangulating every sample from scratch (the reference,
//! spade) against keeping the triangulation and repairing it by flips
//! (`observe::kinetic_delaunay`).
//!
//! At each of three points (gas Gamma 2 E* 3, fluid Gamma 30 E* 0.7, coexistence Gamma 30
//! E* 2.6) the run goes `warm-up` time units unobserved (the hot start cools), then
//! `samples * scale` samples at 20 per period; at every sample the same frame goes to the other
//! observers (`ObserverSet` without location changes), to the rebuilding counter and to the
//! incremental one, each timed on its own. Engine time = wall time between samples outside the
//! observers (frame copy included). Reported per point: milliseconds per sample of each part,
//! the share of the location-change observer in the observed run
//! `lc / (engine + other observers + lc)` for each method, whether both methods counted the
//! same changes (total and per bin), and how the incremental triangulation was updated.

use super::tdmd::thread_cpu_seconds;
use std::fmt::Write as _;
use std::time::Instant;
use wetgran_core::observe::flat_check::FlatCheck;
use wetgran_core::observe::kinetic_delaunay::KineticStats;
use wetgran_core::observe::location_changes::{LocationChangeCounter, Method};
use wetgran_core::observe::{Observer, ObserverSet};
use wetgran_core::scene::Scene;
use wetgran_core::sim::{Frame, run_scene_observed};

/// Samples per driving period (the default of `[observe]`).
pub const SAMPLES_PER_PERIOD: f64 = 20.0;
/// Time units run before the measured samples.
pub const WARM_UP: f64 = 20.0;

/// The 2D standard wet system shaken at `(gamma, e_star)` with particle restitution `eps`
/// (`min_rebound`: `engine.min_rebound_speed`), running `duration` time units, hot start
/// `T_g / E_cb = 20`, seed 1.
pub fn standard_shaken(
    gamma: f64,
    e_star: f64,
    eps: f64,
    min_rebound: Option<f64>,
    duration: f64,
) -> Scene {
    let engine = min_rebound
        .map(|v| format!("[engine]\nmin_rebound_speed = {v:?}\n"))
        .unwrap_or_default();
    let text = format!(
        r#"
dimension = 2
[box]
size = [400.0, 9.0]
[particles]
count = 1200
polydispersity = 0.06
[contact]
restitution = {eps:?}
[capillary]
model = "thin_thread"
[drive]
kind = "sine"
gamma = {gamma:?}
e_star = {e_star:?}
[initial]
temperature_over_ecb = 20.0
seed = 1
[run]
duration = {duration:?}
{engine}"#
    );
    Scene::from_toml_str(&text, "bench standard shaken").expect("bench scene is valid")
}

/// The three points: label, Gamma, E*.
pub const POINTS: [(&str, f64, f64); 3] = [
    ("gas", 2.0, 3.0),
    ("fluid", 30.0, 0.7),
    ("coexistence", 30.0, 2.6),
];

/// One point's figures (seconds summed over the measured samples).
#[derive(Debug, Clone, PartialEq)]
pub struct ObserverRow {
    pub label: &'static str,
    pub gamma: f64,
    pub e_star: f64,
    pub samples: usize,
    pub engine: f64,
    pub others: f64,
    pub rebuilt: f64,
    pub incremental: f64,
    /// CPU seconds of the whole measured part (engine and all observers), when known.
    pub cpu: Option<f64>,
    pub changes: u64,
    pub same_counts: bool,
    pub stats: KineticStats,
}

/// Measures the points labelled in `only` (every point when empty).
pub fn measure(samples: usize, scale: f64, only: &[&str]) -> Vec<ObserverRow> {
    let samples = ((samples as f64 * scale).round() as usize).max(10);
    POINTS
        .iter()
        .filter(|p| only.is_empty() || only.contains(&p.0))
        .map(|&(label, gamma, e_star)| measure_point(label, gamma, e_star, samples))
        .collect()
}

/// The reference counter's sample (its own function, so that a profile tells it apart).
#[inline(never)]
fn observe_rebuilding(counter: &mut LocationChangeCounter, frame: &Frame) {
    counter.observe(frame, std::hint::black_box(true));
}

/// The kept counter's sample (its own function, so that a profile tells it apart).
#[inline(never)]
fn observe_incremental(counter: &mut LocationChangeCounter, frame: &Frame) {
    counter.observe(frame, true);
}

/// The lower-bound kernel ([`wetgran_core::observe::flat_check`]) at the points labelled in `only`:
/// at every sample after the first the kept triangulation of the previous sample is copied into
/// flat lists (`flat_lists`) and tested at the new positions (`FlatCheck::verify`), then the
/// kept counter advances as in [`measure`]. Per point: samples, triangles, edges and hull tests
/// tested per sample, and the failed tests summed over the samples. Profile with callgrind:
/// `verify`'s inclusive instructions over its calls is the kernel's cost per sample.
pub fn measure_kernel(samples: usize, scale: f64, only: &[&str]) -> String {
    let samples = ((samples as f64 * scale).round() as usize).max(10);
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{:<12} {:>7} {:>9} {:>7} {:>6} {:>9} {:>9}",
        "point", "samples", "triangles", "edges", "hull", "inverted", "conflicts"
    );
    for &(label, gamma, e_star) in POINTS
        .iter()
        .filter(|p| only.is_empty() || only.contains(&p.0))
    {
        let BenchPoint {
            scene,
            interval,
            first,
            method,
            bins,
        } = bench_point(gamma, e_star, samples);
        let mut incremental = LocationChangeCounter::new(method, bins, scene.driving_period());
        let t_first = first * interval - 0.5 * interval;
        let (mut n, mut sizes, mut failed) = (0usize, [0usize; 3], [0usize; 2]);
        run_scene_observed(
            &scene,
            interval,
            &mut |f: &Frame| {
                if f.time < t_first {
                    return;
                }
                if let Some(tri) = incremental.kept_triangulation()
                    && n > 0
                {
                    let mut flat = flat_lists(tri);
                    sizes = flat.sizes();
                    let (a, b) = flat.verify(f);
                    failed[0] += a;
                    failed[1] += b;
                }
                n += 1;
                observe_incremental(&mut incremental, f);
            },
            &mut |_| {},
        );
        let _ = writeln!(
            s,
            "{label:<12} {n:>7} {:>9} {:>7} {:>6} {:>9} {:>9}",
            sizes[0], sizes[1], sizes[2], failed[0], failed[1]
        );
    }
    s
}

/// The flat lists of the kernel (its own function, so that a profile tells it apart).
#[inline(never)]
fn flat_lists(tri: &wetgran_core::observe::kinetic_delaunay::KineticDelaunay) -> FlatCheck {
    tri.flat_check()
}

/// The scene of a bench point, run long enough for the warm-up and `samples` samples, with
/// the sampling interval, the index of the first timed sample and the observer's settings.
struct BenchPoint {
    scene: Scene,
    interval: f64,
    first: f64,
    method: Method,
    bins: wetgran_core::observe::bins::LateralBins,
}

fn bench_point(gamma: f64, e_star: f64, samples: usize) -> BenchPoint {
    let probe = standard_shaken(gamma, e_star, 1.0, Some(0.03), 1.0);
    let interval = probe.driving_period() / SAMPLES_PER_PERIOD;
    let first = (WARM_UP / interval).ceil();
    let duration = (first + samples as f64 - 1.0) * interval;
    let mut scene = standard_shaken(gamma, e_star, 1.0, Some(0.03), duration);
    scene.observe.samples_per_period = SAMPLES_PER_PERIOD;
    scene.observe.location_changes = false;
    scene.observe.transient_periods = 0.0;
    let bins = scene.observe.lateral_bins(&scene);
    let method = Method::Delaunay {
        max_edge: scene.observe.lc_max_edge * scene.particles.diameter,
        margin: scene.observe.lc_flip_margin,
    };
    BenchPoint {
        scene,
        interval,
        first,
        method,
        bins,
    }
}

fn measure_point(label: &'static str, gamma: f64, e_star: f64, samples: usize) -> ObserverRow {
    let BenchPoint {
        scene,
        interval,
        first,
        method,
        bins,
    } = bench_point(gamma, e_star, samples);
    let period = scene.driving_period();
    let mut others = ObserverSet::new(&scene);
    let mut rebuilt = LocationChangeCounter::rebuilding(method, bins.clone(), period);
    let mut incremental = LocationChangeCounter::new(method, bins, period);
    let mut row = ObserverRow {
        label,
        gamma,
        e_star,
        samples: 0,
        engine: 0.0,
        others: 0.0,
        rebuilt: 0.0,
        incremental: 0.0,
        cpu: None,
        changes: 0,
        same_counts: false,
        stats: KineticStats::default(),
    };
    let mut last: Option<Instant> = None;
    let mut cpu_start = None;
    let t_first = first * interval - 0.5 * interval;
    run_scene_observed(
        &scene,
        interval,
        &mut |f: &Frame| {
            if f.time < t_first {
                return;
            }
            let arrived = Instant::now();
            match last {
                Some(t) => row.engine += (arrived - t).as_secs_f64(),
                None => cpu_start = thread_cpu_seconds(),
            }
            row.samples += 1;
            let t0 = Instant::now();
            others.observe(f);
            let t1 = Instant::now();
            observe_rebuilding(&mut rebuilt, f);
            let t2 = Instant::now();
            observe_incremental(&mut incremental, f);
            let t3 = Instant::now();
            row.others += (t1 - t0).as_secs_f64();
            row.rebuilt += (t2 - t1).as_secs_f64();
            row.incremental += (t3 - t2).as_secs_f64();
            last = Some(Instant::now());
        },
        &mut |_| {},
    );
    row.cpu = cpu_start.zip(thread_cpu_seconds()).map(|(a, b)| b - a);
    row.changes = incremental.window_count;
    row.same_counts = incremental.window_count == rebuilt.window_count
        && incremental.bin_count == rebuilt.bin_count
        && incremental.series == rebuilt.series;
    row.stats = incremental.kinetic_stats().unwrap_or_default();
    row
}

/// The table.
pub fn report(rows: &[ObserverRow]) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "location-change observer, 2D standard wet system (N 1200, 400x9, eps 1), {SAMPLES_PER_PERIOD} samples/period after {WARM_UP} time units"
    );
    let _ = writeln!(
        s,
        "{:<12} {:>5} {:>5} {:>7} {:>9} {:>9} {:>9} {:>9} {:>8} {:>8} {:>8} {:>6}",
        "point",
        "Gamma",
        "E*",
        "samples",
        "engine ms",
        "others ms",
        "rebuild ms",
        "incr. ms",
        "share rb",
        "share inc",
        "changes",
        "equal"
    );
    for r in rows {
        let n = r.samples.max(1) as f64;
        let share = |lc: f64| lc / (r.engine + r.others + lc);
        let _ = writeln!(
            s,
            "{:<12} {:>5} {:>5} {:>7} {:>9.3} {:>9.3} {:>10.3} {:>9.3} {:>7.1}% {:>8.1}% {:>8} {:>6}",
            r.label,
            r.gamma,
            r.e_star,
            r.samples,
            1e3 * r.engine / n,
            1e3 * r.others / n,
            1e3 * r.rebuilt / n,
            1e3 * r.incremental / n,
            100.0 * share(r.rebuilt),
            100.0 * share(r.incremental),
            r.changes,
            if r.same_counts { "yes" } else { "NO" }
        );
    }
    let _ = writeln!(s, "incremental updates (per point):");
    for r in rows {
        let st = &r.stats;
        let _ = writeln!(
            s,
            "  {:<12} repaired {} | rebuilt {} (first {}, inverted {}, images {}, check {}, back-off {}) | degenerate {} | flips {} unfolds {} held {} halvings {} | images in {} out {}{}",
            r.label,
            st.incremental,
            st.rebuilds(),
            st.rebuild_start,
            st.rebuild_inverted,
            st.rebuild_images,
            st.rebuild_check,
            st.rebuild_backoff,
            st.degenerate,
            st.flips,
            st.unfolds,
            st.held,
            st.bisections,
            st.inserted,
            st.deleted,
            r.cpu
                .map(|c| format!(
                    " | thread CPU {c:.2} s of {:.2} s wall",
                    r.engine + r.others + r.rebuilt + r.incremental
                ))
                .unwrap_or_default()
        );
    }
    s
}
