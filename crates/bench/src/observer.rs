//! `wetgran-bench observer`: what the location-change observer costs in a shaken run of the 2D
//! standard wet system (docs/model.md 1: N = 1200, 400 x 9, eps = 1, the base scene of
//! `sweeps/shaken_2d_elastic.toml`): the counter triangulates every sample from scratch
//! (spade), and a run that asks for `f_lc` (`observe.location_changes`) pays for it.
//!
//! At each of three points (gas Gamma 2 E* 3, fluid Gamma 30 E* 0.7, coexistence Gamma 30
//! E* 2.6) the run goes `warm-up` time units unobserved (the hot start cools), then
//! `samples * scale` samples at 20 per period; at every sample the same frame goes to the other
//! observers (`ObserverSet` without location changes) and to the location-change counter, each
//! timed on its own. Engine time = wall time between samples outside the observers (frame copy
//! included). Reported per point: milliseconds per sample of each part, the share of the
//! location-change observer in the observed run `lc / (engine + other observers + lc)`, and the
//! changes counted.

use super::tdmd::thread_cpu_seconds;
use std::fmt::Write as _;
use std::time::Instant;
use wetgran_core::observe::ObserverSet;
use wetgran_core::observe::location_changes::{LocationChangeCounter, Method};
use wetgran_core::scene::{CapillaryModel, CapillarySpec, Scene, WallSolverKind};
use wetgran_core::sim::{Frame, RunSettings, run_scene_observed};
use wetgran_testkit::reference::shaken_standard;

/// Samples per driving period (the default of `[observe]`).
pub(crate) const SAMPLES_PER_PERIOD: f64 = 20.0;
/// Time units run before the measured samples.
pub(crate) const WARM_UP: f64 = 20.0;

/// The 2D standard wet system shaken at `(gamma, e_star)` with particle restitution `eps`
/// (`min_rebound`: `engine.min_rebound_speed`), running `duration` time units, hot start
/// `T_g / E_cb = 20`, seed 1, the box's boundaries and the bridges' `s_crit` and `E_cb` left to
/// their defaults.
pub(crate) fn standard_shaken(
    gamma: f64,
    e_star: f64,
    eps: f64,
    min_rebound: Option<f64>,
    duration: f64,
) -> Scene {
    let mut s = shaken_standard(gamma, e_star, WallSolverKind::Exact);
    s.container.boundary = None;
    s.contact.restitution = eps;
    s.capillary = CapillarySpec {
        model: CapillaryModel::ThinThread,
        ..CapillarySpec::default()
    };
    if let Some(v) = min_rebound {
        s.engine.min_rebound_speed = v;
    }
    s.run.duration = duration;
    s.resolve_observers();
    s
}

/// The three points: label, Gamma, E*.
pub(crate) const POINTS: [(&str, f64, f64); 3] = [
    ("gas", 2.0, 3.0),
    ("fluid", 30.0, 0.7),
    ("coexistence", 30.0, 2.6),
];

/// One point's figures (seconds summed over the measured samples).
#[derive(Debug, Clone, PartialEq, Default)]
pub(crate) struct ObserverRow {
    pub label: &'static str,
    pub gamma: f64,
    pub e_star: f64,
    pub samples: usize,
    pub engine: f64,
    pub others: f64,
    /// The location-change counter.
    pub counter: f64,
    /// CPU seconds of the whole measured part (engine and all observers), when known.
    pub cpu: Option<f64>,
    pub changes: u64,
}

/// Measures the points labelled in `only` (every point when empty).
pub(crate) fn measure(samples: usize, scale: f64, only: &[&str]) -> Vec<ObserverRow> {
    let samples = ((samples as f64 * scale).round() as usize).max(10);
    POINTS
        .iter()
        .filter(|p| only.is_empty() || only.contains(&p.0))
        .map(|&(label, gamma, e_star)| measure_point(label, gamma, e_star, samples))
        .collect()
}

/// The counter's sample (its own function, so that a profile tells it apart).
#[inline(never)]
fn observe_counter(counter: &mut LocationChangeCounter, frame: &Frame) {
    counter.observe(frame, std::hint::black_box(true));
}

fn measure_point(label: &'static str, gamma: f64, e_star: f64, samples: usize) -> ObserverRow {
    // The scene runs the warm-up and then `samples` samples, the first timed one at `first`.
    let probe = standard_shaken(gamma, e_star, 1.0, Some(0.03), 1.0);
    let interval = probe.driving_period() / SAMPLES_PER_PERIOD;
    let first = (WARM_UP / interval).ceil();
    let duration = (first + samples as f64 - 1.0) * interval;
    let mut scene = standard_shaken(gamma, e_star, 1.0, Some(0.03), duration);
    scene.observe.samples_per_period = SAMPLES_PER_PERIOD;
    scene.observe.location_changes = Some(false);
    scene.observe.transient_periods = 0.0;
    let bins = scene.observe.lateral_bins(&scene);
    let method = Method::Delaunay {
        max_edge: scene.observe.lc_max_edge * scene.particles.diameter,
        margin: scene.observe.lc_flip_margin,
    };
    let period = scene.driving_period();
    let mut others = ObserverSet::new(&scene);
    let mut counter = LocationChangeCounter::new(method, bins, period);
    let mut row = ObserverRow {
        label,
        gamma,
        e_star,
        ..ObserverRow::default()
    };
    let mut last: Option<Instant> = None;
    let mut cpu_start = None;
    let t_first = first * interval - 0.5 * interval;
    run_scene_observed(
        &scene,
        &RunSettings::default(),
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
            observe_counter(&mut counter, f);
            let t2 = Instant::now();
            row.others += (t1 - t0).as_secs_f64();
            row.counter += (t2 - t1).as_secs_f64();
            last = Some(Instant::now());
        },
        &mut |_| {},
    );
    row.cpu = cpu_start.zip(thread_cpu_seconds()).map(|(a, b)| b - a);
    row.changes = counter.window_count;
    row
}

/// The table.
pub(crate) fn report(rows: &[ObserverRow]) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "location-change observer, 2D standard wet system (N 1200, 400x9, eps 1), {SAMPLES_PER_PERIOD} samples/period after {WARM_UP} time units"
    );
    s.push_str("point        Gamma    E* samples engine ms others ms     lc ms lc share  changes  thread CPU / wall\n");
    for r in rows {
        let n = r.samples.max(1) as f64;
        let wall = r.engine + r.others + r.counter;
        let _ = writeln!(
            s,
            "{:<12} {:>5} {:>5} {:>7} {:>9.3} {:>9.3} {:>9.3} {:>7.1}% {:>8}  {}",
            r.label,
            r.gamma,
            r.e_star,
            r.samples,
            1e3 * r.engine / n,
            1e3 * r.others / n,
            1e3 * r.counter / n,
            100.0 * r.counter / wall,
            r.changes,
            r.cpu
                .map(|c| format!("{c:.2} s / {wall:.2} s"))
                .unwrap_or_else(|| "-".into())
        );
    }
    s
}
