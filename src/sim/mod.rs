//! Simulation engines and the one entry point that runs a scene: [`run_scene`].
//!
//! `run_scene` picks the engine (`engine.kind`: event-driven or time-driven) and its concrete
//! type once from the scene (dimension, gravity on or off, bridges or none, shear drive or not),
//! so that a scene pays only for the effects it asks for. Both engines implement [`Simulation`],
//! so the sampling loop, the observers and the report are the same for both.
//! [`run_scene_observed`] runs the same loop and also hands a read-only [`Frame`] (a copy of the
//! configuration in scene order) to an observer at fixed intervals; `crate::observe` builds on it.

pub mod event_driven;
pub mod frame;
pub mod initial;
pub mod time_driven;

pub use frame::Frame;

use crate::scene::{EngineKind, Scene};
use event_driven::{EnergyLedger, Engine, EventCounts};
use serde::Serialize;
use std::time::Instant;
use time_driven::{BodyForce, TimeEngine};

/// One sample of the global observables.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Sample {
    pub time: f64,
    pub granular_temperature: f64,
    pub bridges: usize,
    pub kinetic: f64,
    pub potential: f64,
}

/// What one run of a scene produced.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RunReport {
    /// `"event"` or `"time"` (`engine.kind`).
    pub engine: String,
    pub dimension: usize,
    pub particles: usize,
    pub simulated_time: f64,
    pub wall_seconds: f64,
    /// Event engine: events by kind. Time engine: contact onsets (pair, wall), bridge formations
    /// and ruptures; the other counters stay 0.
    pub events: EventCounts,
    /// Time steps taken (time engine; 0 for the event engine).
    pub steps: u64,
    /// Largest pair or wall overlap seen, in units of `d` (time engine; `None` for the event
    /// engine, whose overlaps are round-off).
    pub max_overlap: Option<f64>,
    pub events_total: u64,
    /// Whether the run stopped on `run.max_events` before `run.duration`.
    pub stopped_on_event_cap: bool,
    /// The first broken invariant (`Engine::sanity_check`, run at every sample), if any; the run
    /// stops there.
    pub invariant_violation: Option<String>,
    pub granular_temperature: f64,
    /// `T_g / E_cb` where bridges exist.
    pub granular_temperature_over_ecb: Option<f64>,
    pub bridges: usize,
    pub energy_initial: EnergyLedger,
    pub energy_final: EnergyLedger,
    /// `(accounted_final - accounted_initial) / accounted_initial`: round-off only.
    pub energy_bookkeeping_error: f64,
    pub samples: Vec<Sample>,
}

/// Runs a validated scene to the end and reports.
pub fn run_scene(scene: &Scene) -> RunReport {
    run_scene_with_progress(scene, &mut |_| {})
}

/// Runs a validated scene, calling `progress` after every sample (for progress displays).
pub fn run_scene_with_progress(scene: &Scene, progress: &mut dyn FnMut(&Sample)) -> RunReport {
    run_dispatch(scene, progress, None)
}

/// Runs a validated scene and hands a [`Frame`] to `observer` at every time `k * interval`
/// (`k = 0, 1, ...`, up to `run.duration`), besides the report's own samples. The observer only
/// reads copies of the state, so the trajectory is the same as with [`run_scene`].
pub fn run_scene_observed(
    scene: &Scene,
    interval: f64,
    observer: &mut dyn FnMut(&Frame),
    progress: &mut dyn FnMut(&Sample),
) -> RunReport {
    assert!(
        interval > 0.0 && interval.is_finite(),
        "observer interval must be > 0"
    );
    run_dispatch(scene, progress, Some((interval, observer)))
}

type Observer<'a> = Option<(f64, &'a mut dyn FnMut(&Frame))>;

fn run_dispatch(scene: &Scene, p: &mut dyn FnMut(&Sample), o: Observer<'_>) -> RunReport {
    let grav = scene.gravity > 0.0;
    let wet = scene.is_wet();
    if scene.engine.kind == EngineKind::Time {
        if let Some(field) = time_driven::shear::CosineShear::of_scene(scene) {
            // Validation admits the shear drive in 3D only.
            return match (grav, wet) {
                (false, false) => run_engine(
                    TimeEngine::<3, false, false, _>::with_body_force(scene, field),
                    scene,
                    p,
                    o,
                ),
                (false, true) => run_engine(
                    TimeEngine::<3, false, true, _>::with_body_force(scene, field),
                    scene,
                    p,
                    o,
                ),
                (true, false) => run_engine(
                    TimeEngine::<3, true, false, _>::with_body_force(scene, field),
                    scene,
                    p,
                    o,
                ),
                (true, true) => run_engine(
                    TimeEngine::<3, true, true, _>::with_body_force(scene, field),
                    scene,
                    p,
                    o,
                ),
            };
        }
        return match (scene.dimension, grav, wet) {
            (2, false, false) => run_engine(TimeEngine::<2, false, false>::new(scene), scene, p, o),
            (2, false, true) => run_engine(TimeEngine::<2, false, true>::new(scene), scene, p, o),
            (2, true, false) => run_engine(TimeEngine::<2, true, false>::new(scene), scene, p, o),
            (2, true, true) => run_engine(TimeEngine::<2, true, true>::new(scene), scene, p, o),
            (3, false, false) => run_engine(TimeEngine::<3, false, false>::new(scene), scene, p, o),
            (3, false, true) => run_engine(TimeEngine::<3, false, true>::new(scene), scene, p, o),
            (3, true, false) => run_engine(TimeEngine::<3, true, false>::new(scene), scene, p, o),
            (3, true, true) => run_engine(TimeEngine::<3, true, true>::new(scene), scene, p, o),
            (d, _, _) => panic!("dimension {d} passed validation"),
        };
    }
    if scene.shear_slabs().is_some() {
        // Validation admits the shear drive in 3D only.
        return match (grav, wet) {
            (false, false) => run_engine(Engine::<3, false, false, true>::new(scene), scene, p, o),
            (false, true) => run_engine(Engine::<3, false, true, true>::new(scene), scene, p, o),
            (true, false) => run_engine(Engine::<3, true, false, true>::new(scene), scene, p, o),
            (true, true) => run_engine(Engine::<3, true, true, true>::new(scene), scene, p, o),
        };
    }
    match (scene.dimension, grav, wet) {
        (2, false, false) => run_engine(Engine::<2, false, false>::new(scene), scene, p, o),
        (2, false, true) => run_engine(Engine::<2, false, true>::new(scene), scene, p, o),
        (2, true, false) => run_engine(Engine::<2, true, false>::new(scene), scene, p, o),
        (2, true, true) => run_engine(Engine::<2, true, true>::new(scene), scene, p, o),
        (3, false, false) => run_engine(Engine::<3, false, false>::new(scene), scene, p, o),
        (3, false, true) => run_engine(Engine::<3, false, true>::new(scene), scene, p, o),
        (3, true, false) => run_engine(Engine::<3, true, false>::new(scene), scene, p, o),
        (3, true, true) => run_engine(Engine::<3, true, true>::new(scene), scene, p, o),
        (d, _, _) => panic!("dimension {d} passed validation"),
    }
}

/// What the sampling loop needs from an engine (both engines implement it).
pub trait Simulation {
    /// `"event"` or `"time"`.
    const KIND: &'static str;
    fn time(&self) -> f64;
    fn len(&self) -> usize;
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Advances to `t_end`; false when stopped on the event cap first.
    fn run_until(&mut self, t_end: f64, max_events: Option<u64>) -> bool;
    fn energy(&self) -> EnergyLedger;
    fn granular_temperature(&self) -> f64;
    fn bridge_count(&self) -> usize;
    fn sanity_check(&self) -> Result<(), String>;
    fn counts(&self) -> &EventCounts;
    fn frame(&self, scene: &Scene) -> Frame;
    /// Time steps taken (0 for the event engine).
    fn steps(&self) -> u64 {
        0
    }
    /// Largest overlap seen, units of `d` (`None` for the event engine).
    fn max_overlap(&self) -> Option<f64> {
        None
    }
}

impl<const D: usize, const G: bool, const W: bool, const S: bool> Simulation
    for Engine<D, G, W, S>
{
    const KIND: &'static str = "event";
    fn time(&self) -> f64 {
        Engine::time(self)
    }
    fn len(&self) -> usize {
        Engine::len(self)
    }
    fn run_until(&mut self, t_end: f64, max_events: Option<u64>) -> bool {
        Engine::run_until(self, t_end, max_events)
    }
    fn energy(&self) -> EnergyLedger {
        Engine::energy(self)
    }
    fn granular_temperature(&self) -> f64 {
        Engine::granular_temperature(self)
    }
    fn bridge_count(&self) -> usize {
        Engine::bridge_count(self)
    }
    fn sanity_check(&self) -> Result<(), String> {
        Engine::sanity_check(self)
    }
    fn counts(&self) -> &EventCounts {
        Engine::counts(self)
    }
    fn frame(&self, scene: &Scene) -> Frame {
        Frame::of_engine(self, scene)
    }
}

impl<const D: usize, const G: bool, const W: bool, B: BodyForce<D>> Simulation
    for TimeEngine<D, G, W, B>
{
    const KIND: &'static str = "time";
    fn time(&self) -> f64 {
        TimeEngine::time(self)
    }
    fn len(&self) -> usize {
        TimeEngine::len(self)
    }
    fn run_until(&mut self, t_end: f64, _max_events: Option<u64>) -> bool {
        TimeEngine::run_until(self, t_end)
    }
    fn energy(&self) -> EnergyLedger {
        TimeEngine::energy(self)
    }
    fn granular_temperature(&self) -> f64 {
        TimeEngine::granular_temperature(self)
    }
    fn bridge_count(&self) -> usize {
        TimeEngine::bridge_count(self)
    }
    fn sanity_check(&self) -> Result<(), String> {
        TimeEngine::sanity_check(self)
    }
    fn counts(&self) -> &EventCounts {
        TimeEngine::counts(self)
    }
    fn frame(&self, scene: &Scene) -> Frame {
        Frame::of_time_engine(self, scene)
    }
    fn steps(&self) -> u64 {
        TimeEngine::steps(self)
    }
    fn max_overlap(&self) -> Option<f64> {
        Some(TimeEngine::max_overlap(self))
    }
}

fn sample<S: Simulation>(e: &S) -> Sample {
    let energy = e.energy();
    Sample {
        time: e.time(),
        granular_temperature: e.granular_temperature(),
        bridges: e.bridge_count(),
        kinetic: energy.kinetic,
        potential: energy.potential,
    }
}

fn run_engine<S: Simulation>(
    mut engine: S,
    scene: &Scene,
    progress: &mut dyn FnMut(&Sample),
    mut observer: Observer<'_>,
) -> RunReport {
    let start = Instant::now();
    let energy_initial = engine.energy();
    let mut samples = vec![sample(&engine)];
    let duration = scene.run.duration;
    let interval = if scene.run.sample_interval > 0.0 {
        scene.run.sample_interval
    } else {
        duration
    };
    let mut stopped_on_cap = false;
    let mut violation = None;
    // Observer times `j * dt` for `j = 0 ..= last_obs` (none without an observer).
    let (obs_dt, last_obs) = match &observer {
        Some((dt, _)) => (*dt, (duration / dt * (1.0 + 1e-12)).floor() as u64),
        None => (f64::INFINITY, 0),
    };
    let mut j = 0u64;
    if let Some((_, obs)) = observer.as_mut() {
        obs(&engine.frame(scene));
        j = 1;
    }
    let mut k = 1u64;
    loop {
        let target_report = (k as f64 * interval).min(duration);
        let target_obs = if observer.is_some() && j <= last_obs {
            let t = j as f64 * obs_dt;
            // The last sample lands on `duration` exactly when round-off alone separates them.
            if j == last_obs && (duration - t).abs() <= 1e-9 * duration {
                duration
            } else {
                t.min(duration)
            }
        } else {
            f64::INFINITY
        };
        let target = target_report.min(target_obs);
        if !engine.run_until(target, scene.run.max_events) {
            stopped_on_cap = true;
            samples.push(sample(&engine));
            break;
        }
        if target == target_obs {
            if let Some((_, obs)) = observer.as_mut() {
                obs(&engine.frame(scene));
            }
            j += 1;
        }
        if target < target_report {
            continue;
        }
        samples.push(sample(&engine));
        progress(samples.last().expect("just pushed"));
        if let Err(e) = engine.sanity_check() {
            violation = Some(e);
            break;
        }
        if target >= duration {
            break;
        }
        k += 1;
    }
    let energy_final = engine.energy();
    let t_g = engine.granular_temperature();
    let e_cb = scene.e_cb();
    let a0 = energy_initial.total_accounted();
    let a1 = energy_final.total_accounted();
    RunReport {
        engine: S::KIND.to_string(),
        dimension: scene.dimension,
        particles: engine.len(),
        simulated_time: engine.time(),
        wall_seconds: start.elapsed().as_secs_f64(),
        events: engine.counts().clone(),
        events_total: engine.counts().total(),
        steps: engine.steps(),
        max_overlap: engine.max_overlap(),
        stopped_on_event_cap: stopped_on_cap,
        invariant_violation: violation,
        granular_temperature: t_g,
        granular_temperature_over_ecb: if e_cb > 0.0 { Some(t_g / e_cb) } else { None },
        bridges: engine.bridge_count(),
        energy_initial,
        energy_final,
        energy_bookkeeping_error: if a0 != 0.0 {
            (a1 - a0) / a0.abs()
        } else {
            a1 - a0
        },
        samples,
    }
}
