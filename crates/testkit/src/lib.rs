//! What the tests and benchmarks of wetgran share, kept out of the product crates (a
//! dev-dependency of `wetgran-core` and `wetgran`, a dependency of `wetgran-bench`): scene
//! construction and a run loop that checks the engine's invariants (`sanity_check`) as it goes
//! (here), the 2D standard wet system ([`standard`]), the reference systems of the benchmarks
//! ([`reference`]), the reference event queue ([`NaiveQueue`]) and the reading of a written
//! figure's text ([`figures`]).

pub mod figures;
mod queues;
pub mod reference;
pub mod standard;

pub use queues::NaiveQueue;

use wetgran_core::scene::Scene;
use wetgran_core::sim::event_driven::Engine;

/// Parses and validates a scene written inline in a test.
pub fn scene(text: &str) -> Scene {
    Scene::from_toml_str(text, "<test scene>").unwrap_or_else(|e| panic!("{e}"))
}

/// A scene with the given header lines; `[run]` and `[initial]` are added if missing.
pub fn scene_with(
    dimension: usize,
    gravity: f64,
    size: &[f64],
    boundary: &[&str],
    count: usize,
    extra: &str,
) -> Scene {
    let size = size
        .iter()
        .map(|x| format!("{x:?}"))
        .collect::<Vec<_>>()
        .join(", ");
    let boundary = boundary
        .iter()
        .map(|b| format!("\"{b}\""))
        .collect::<Vec<_>>()
        .join(", ");
    let mut text = format!(
        "dimension = {dimension}\ngravity = {gravity:?}\n[box]\nsize = [{size}]\nboundary = [{boundary}]\n\
         [particles]\ncount = {count}\n{extra}\n"
    );
    if !text.contains("[initial]") {
        text += "[initial]\ntemperature = 1.0\nseed = 1\n";
    }
    if !text.contains("[run]") {
        text += "[run]\nduration = 1.0\n";
    }
    scene(&text)
}

/// Runs the engine in `chunks` steps up to `t_end`, checking invariants after each chunk.
pub fn run_checked<const D: usize, const G: bool, const W: bool, const S: bool>(
    e: &mut Engine<D, G, W, S>,
    t_end: f64,
    chunks: usize,
    max_events: Option<u64>,
) {
    let t0 = e.time();
    for k in 1..=chunks {
        let t = t0 + (t_end - t0) * k as f64 / chunks as f64;
        let reached = e.run_until(t, max_events);
        e.sanity_check()
            .unwrap_or_else(|m| panic!("sanity check failed: {m}"));
        if !reached {
            return;
        }
    }
}

/// Runs until at least `events` more events have been processed, checking invariants every
/// `every` events.
pub fn run_events<const D: usize, const G: bool, const W: bool, const S: bool>(
    e: &mut Engine<D, G, W, S>,
    events: u64,
    every: u64,
) {
    let target = e.counts().total() + events;
    while e.counts().total() < target {
        let cap = (e.counts().total() + every).min(target);
        e.run_until(f64::INFINITY, Some(cap));
        e.sanity_check()
            .unwrap_or_else(|m| panic!("sanity check failed: {m}"));
    }
}
