//! Simulation engines and the one entry point that runs a scene: [`run_scene`].
//!
//! `run_scene` picks the engine (`engine.kind`: event-driven or time-driven) and its concrete
//! type once from the scene (dimension, gravity on or off, bridges or none, shear drive or not),
//! so that a scene pays only for the effects it asks for. Both engines implement [`Simulation`],
//! so the sampling loop, the observers and the report are the same for both.
//! [`run_scene_observed`] runs the same loop and also hands a read-only [`Frame`] (a copy of the
//! configuration in scene order) to an observer at fixed intervals; `crate::observe` builds on it.
//! [`run_scene_watched`] is the general form: it can start from a saved [`EngineState`] instead
//! of the scene's initial state, and its [`Watcher`] may extend the run on the same trajectory
//! when it reaches its end (run to stationarity, `crate::scene::convergence`). Every run reports
//! its final state ([`RunReport::final_state`]) for checkpoints. What the caller gives a run
//! besides the scene (how often the invariants are checked, the wall-table cache) is its
//! [`RunSettings`] ([`checks`]), which also names the [`threads::Threads`] it runs on and a
//! hook called at each extension of the run ([`ExtendHook`]).

pub mod books;
pub mod checks;
pub mod event_driven;
pub(crate) mod frame;
pub mod initial;
pub(crate) mod state;
pub mod threads;
pub mod time_driven;

pub use books::{EnergyLedger, EventCounts};
pub use checks::{CheckPolicy, RunSettings, RunTiming};
pub use frame::Frame;
pub use state::EngineState;

use crate::scene::{EngineKind, Scene};
use checks::CheckCadence;
use event_driven::Engine;
use event_driven::queue::EventQueue;
use event_driven::table_cache::TableCache;
use serde::Serialize;
use std::fmt;
use std::sync::Arc;
use std::time::Instant;
use time_driven::{BodyForce, TimeEngine};

/// The function a run calls when its watcher extends it (the crash tests stop a process
/// there, between two windows of the run-length policy).
#[derive(Clone)]
pub struct ExtendHook(Arc<dyn Fn() + Send + Sync>);

impl ExtendHook {
    pub fn new(f: impl Fn() + Send + Sync + 'static) -> Self {
        Self(Arc::new(f))
    }
}

impl fmt::Debug for ExtendHook {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("ExtendHook")
    }
}

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
    /// The first broken invariant (the checks of [`RunSettings::checks`] at the samples, the
    /// full check at the end), if any; the run stops there.
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
    /// Where the wall time went (not part of the run's numbers).
    pub timing: RunTiming,
    /// The state at the end of the run (for checkpoints; not part of the JSON report).
    #[serde(skip)]
    pub final_state: Option<EngineState>,
}

/// Runs a validated scene to the end and reports, with the full invariant check at every
/// sample ([`RunSettings::every_sample`]).
pub fn run_scene(scene: &Scene) -> RunReport {
    run_dispatch(scene, None, &RunSettings::every_sample(), &mut |_| {}, None)
}

/// Runs a validated scene and hands a [`Frame`] to `observer` at every time `k * interval`
/// (`k = 0, 1, ...`, up to `run.duration`), besides the report's own samples. The observer only
/// reads copies of the state, so the trajectory is the same as with [`run_scene`].
pub fn run_scene_observed(
    scene: &Scene,
    settings: &RunSettings,
    interval: f64,
    observer: &mut dyn FnMut(&Frame),
    progress: &mut dyn FnMut(&Sample),
) -> RunReport {
    let mut watcher = FnWatcher(observer);
    run_scene_watched(scene, None, settings, interval, &mut watcher, progress)
}

/// What the sampling loop hands frames to, and asks whether to go on at the end of the run.
pub trait Watcher {
    /// Sees the frame at every observer time.
    fn observe(&mut self, frame: &Frame);
    /// Called when the run reaches its end `t_end` (after the frame at `t_end` was observed):
    /// a later end time continues the same trajectory to it, `None` stops. Default `None`.
    fn extend(&mut self, _t_end: f64) -> Option<f64> {
        None
    }
}

/// A closure as a [`Watcher`] that never extends.
struct FnWatcher<'a>(&'a mut dyn FnMut(&Frame));

impl Watcher for FnWatcher<'_> {
    fn observe(&mut self, frame: &Frame) {
        (self.0)(frame)
    }
}

/// [`run_scene_observed`] with a [`Watcher`] that may extend the run, starting from `start`
/// (a saved state, continued at its time with its counts and ledger) or, with `None`, from
/// the scene's initial state. `run.duration` is then the end time of the first stretch, in
/// absolute time (a state saved at `t0` runs from `t0` to `run.duration`).
pub fn run_scene_watched(
    scene: &Scene,
    start: Option<&EngineState>,
    settings: &RunSettings,
    interval: f64,
    watcher: &mut dyn Watcher,
    progress: &mut dyn FnMut(&Sample),
) -> RunReport {
    assert!(
        interval > 0.0 && interval.is_finite(),
        "observer interval must be > 0"
    );
    run_dispatch(scene, start, settings, progress, Some((interval, watcher)))
}

type Observer<'a> = Option<(f64, &'a mut dyn Watcher)>;

fn run_dispatch(
    scene: &Scene,
    start: Option<&EngineState>,
    settings: &RunSettings,
    p: &mut dyn FnMut(&Sample),
    o: Observer<'_>,
) -> RunReport {
    if let Some(Err(e)) = start.map(|st| st.check_fits(scene)) {
        panic!("{e}");
    }
    assert!(
        start.is_some() || scene.initial.start != crate::scene::StartMode::Continue,
        "initial.start = \"continue\" starts from the final state of a neighbouring sweep point \
         (`[sweep.continuation]`); a scene run on its own has none: use \"hot\" or \"cold\""
    );
    let cold = (start.is_none() && scene.initial.start == crate::scene::StartMode::Cold)
        .then(|| initial::cold_state(scene));
    let st = start.or(cold.as_ref());
    with_engine(
        scene,
        st,
        &settings.tables,
        RunVisitor {
            scene,
            settings,
            progress: p,
            observer: o,
        },
    )
}

/// What [`with_engine`] hands the engine it built to: one generic method, monomorphised for
/// every engine type a scene can ask for.
pub trait EngineVisitor {
    type Output;
    fn visit<S: Simulation>(self, engine: S) -> Self::Output;
}

/// The sampling loop of [`run_scene_watched`] as an [`EngineVisitor`].
struct RunVisitor<'a, 'b> {
    scene: &'a Scene,
    settings: &'a RunSettings,
    progress: &'a mut dyn FnMut(&Sample),
    observer: Observer<'b>,
}

impl EngineVisitor for RunVisitor<'_, '_> {
    type Output = RunReport;
    fn visit<S: Simulation>(self, engine: S) -> RunReport {
        run_engine(
            engine,
            self.scene,
            self.settings,
            self.progress,
            self.observer,
        )
    }
}

/// Builds the engine a validated scene asks for (engine kind, dimension, gravity on or off,
/// bridges or none, shear drive or not), from the saved state `start` or, with `None`, from the
/// scene's initial state (a `"cold"` start is the caller's: pass `initial::cold_state`), and
/// hands it to `v`. A `table` wall solver takes its tables from `tables`.
pub fn with_engine<V: EngineVisitor>(
    scene: &Scene,
    st: Option<&EngineState>,
    tables: &TableCache,
    v: V,
) -> V::Output {
    let grav = scene.gravity > 0.0;
    let wet = scene.is_wet();
    if scene.engine.kind == EngineKind::Time {
        if let Some(field) = time_driven::shear::CosineShear::of_scene(scene) {
            // Validation admits the shear drive in 3D only.
            return match (grav, wet) {
                (false, false) => {
                    v.visit(TimeEngine::<3, false, false, _>::start(scene, st, field))
                }
                (false, true) => v.visit(TimeEngine::<3, false, true, _>::start(scene, st, field)),
                (true, false) => v.visit(TimeEngine::<3, true, false, _>::start(scene, st, field)),
                (true, true) => v.visit(TimeEngine::<3, true, true, _>::start(scene, st, field)),
            };
        }
        return match (scene.dimension, grav, wet) {
            (2, false, false) => v.visit(TimeEngine::<2, false, false>::from_state(scene, st)),
            (2, false, true) => v.visit(TimeEngine::<2, false, true>::from_state(scene, st)),
            (2, true, false) => v.visit(TimeEngine::<2, true, false>::from_state(scene, st)),
            (2, true, true) => v.visit(TimeEngine::<2, true, true>::from_state(scene, st)),
            (3, false, false) => v.visit(TimeEngine::<3, false, false>::from_state(scene, st)),
            (3, false, true) => v.visit(TimeEngine::<3, false, true>::from_state(scene, st)),
            (3, true, false) => v.visit(TimeEngine::<3, true, false>::from_state(scene, st)),
            (3, true, true) => v.visit(TimeEngine::<3, true, true>::from_state(scene, st)),
            (d, _, _) => panic!("dimension {d} passed validation"),
        };
    }
    if scene.shear_slabs().is_some() {
        // Validation admits the shear drive in 3D only.
        return match (grav, wet) {
            (false, false) => v.visit(Engine::<3, false, false, true>::from_state(
                scene, st, tables,
            )),
            (false, true) => v.visit(Engine::<3, false, true, true>::from_state(
                scene, st, tables,
            )),
            (true, false) => v.visit(Engine::<3, true, false, true>::from_state(
                scene, st, tables,
            )),
            (true, true) => v.visit(Engine::<3, true, true, true>::from_state(scene, st, tables)),
        };
    }
    match (scene.dimension, grav, wet) {
        (2, false, false) => v.visit(Engine::<2, false, false>::from_state(scene, st, tables)),
        (2, false, true) => v.visit(Engine::<2, false, true>::from_state(scene, st, tables)),
        (2, true, false) => v.visit(Engine::<2, true, false>::from_state(scene, st, tables)),
        (2, true, true) => v.visit(Engine::<2, true, true>::from_state(scene, st, tables)),
        (3, false, false) => v.visit(Engine::<3, false, false>::from_state(scene, st, tables)),
        (3, false, true) => v.visit(Engine::<3, false, true>::from_state(scene, st, tables)),
        (3, true, false) => v.visit(Engine::<3, true, false>::from_state(scene, st, tables)),
        (3, true, true) => v.visit(Engine::<3, true, true>::from_state(scene, st, tables)),
        (d, _, _) => panic!("dimension {d} passed validation"),
    }
}

/// What the sampling loop needs from an engine (both engines implement it).
pub trait Simulation: Send {
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
    /// The report's sample now: the energies of [`Self::energy`], the temperature and the
    /// bridges.
    fn sample(&self) -> Sample {
        let energy = self.energy();
        Sample {
            time: self.time(),
            granular_temperature: self.granular_temperature(),
            bridges: self.bridge_count(),
            kinetic: energy.kinetic,
            potential: energy.potential,
        }
    }
    /// Every invariant; the first violation.
    fn sanity_check(&self) -> Result<(), String>;
    /// The invariants of each particle on its own, `O(N)` (the per-sample check of
    /// [`CheckPolicy::WallShare`]).
    fn quick_check(&self) -> Result<(), String>;
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
    /// The engine's units of work done so far: events (event engine) or time steps (time
    /// engine).
    fn work_done(&self) -> u64;
}

impl<const D: usize, const G: bool, const W: bool, const S: bool, Q: EventQueue + Send> Simulation
    for Engine<D, G, W, S, Q>
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
    fn sample(&self) -> Sample {
        // One pass over the particles (a sample may come every few hundred events).
        let (kinetic, potential, granular_temperature) = self.sample_energies();
        Sample {
            time: self.time(),
            granular_temperature,
            bridges: self.bridge_count(),
            kinetic,
            potential,
        }
    }
    fn sanity_check(&self) -> Result<(), String> {
        Engine::sanity_check(self)
    }
    fn quick_check(&self) -> Result<(), String> {
        Engine::quick_check(self)
    }
    fn counts(&self) -> &EventCounts {
        Engine::counts(self)
    }
    fn frame(&self, scene: &Scene) -> Frame {
        Frame::of_engine(self, scene)
    }
    fn work_done(&self) -> u64 {
        Engine::counts(self).total()
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
    fn quick_check(&self) -> Result<(), String> {
        TimeEngine::quick_check(self)
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
    fn work_done(&self) -> u64 {
        TimeEngine::steps(self)
    }
}

/// Seconds since `t0`.
fn since(t0: Instant) -> f64 {
    t0.elapsed().as_secs_f64()
}

fn run_engine<S: Simulation>(
    mut engine: S,
    scene: &Scene,
    settings: &RunSettings,
    progress: &mut dyn FnMut(&Sample),
    mut observer: Observer<'_>,
) -> RunReport {
    let mut cadence = CheckCadence::new(settings.checks);
    let start = Instant::now();
    let energy_initial = engine.energy();
    let mut samples = vec![engine.sample()];
    let (stopped_on_cap, violation) = sample_loop(
        &mut engine,
        scene,
        settings,
        &mut cadence,
        &mut samples,
        progress,
        &mut observer,
    );
    // The end of the run, whatever stopped it: the full check (the final state is the job's
    // checkpoint), unless the last sample just ran it on this state.
    let violation = violation.or_else(|| {
        (cadence.last_full_at() != Some(engine.work_done()))
            .then(|| cadence.full(&engine).err())
            .flatten()
    });
    let energy_final = engine.energy();
    let final_state = Some(EngineState::of_frame(
        S::KIND,
        engine.frame(scene),
        energy_final.clone(),
    ));
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
        granular_temperature_over_ecb: (e_cb > 0.0).then(|| t_g / e_cb),
        bridges: engine.bridge_count(),
        energy_initial,
        energy_final,
        energy_bookkeeping_error: (a1 - a0) / if a0 != 0.0 { a0.abs() } else { 1.0 },
        samples,
        timing: cadence.timing,
        final_state,
    }
}

/// The sampling loop of [`run_engine`]: advances the engine to each report sample and observer
/// time, feeds the watcher, records the samples and runs the checks; returns whether it
/// stopped on the event cap and the first broken invariant.
fn sample_loop<S: Simulation>(
    engine: &mut S,
    scene: &Scene,
    settings: &RunSettings,
    cadence: &mut CheckCadence,
    samples: &mut Vec<Sample>,
    progress: &mut dyn FnMut(&Sample),
    observer: &mut Observer<'_>,
) -> (bool, Option<String>) {
    let mut duration = scene.run.duration;
    let interval = if scene.run.sample_interval > 0.0 {
        scene.run.sample_interval
    } else {
        duration
    };
    // Observer times `j * dt` for `j = j0 ..= last_obs` (none without an observer); a run from
    // a saved state at `t0` starts at the first `j0` with `j0 * dt >= t0` (up to round-off).
    let t0 = engine.time();
    let last_obs_of = |duration: f64, dt: f64| (duration / dt * (1.0 + 1e-12)).floor() as u64;
    let (obs_dt, mut last_obs) = match &observer {
        Some((dt, _)) => (*dt, last_obs_of(duration, *dt)),
        None => (f64::INFINITY, 0),
    };
    let mut j = 0u64;
    if let Some((dt, obs)) = observer.as_mut() {
        let t = Instant::now();
        obs.observe(&engine.frame(scene));
        cadence.timing.observers += since(t);
        j = (t0 / *dt * (1.0 - 1e-12)).floor() as u64 + 1;
    }
    // Report samples at `k * interval`, the first after `t0`.
    let mut k = (t0 / interval * (1.0 - 1e-12)).floor() as u64 + 1;
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
        let t = Instant::now();
        let cap = scene.run.max_events;
        let reached = settings.threads.install(|| engine.run_until(target, cap));
        cadence.timing.engine += since(t);
        if !reached {
            samples.push(engine.sample());
            return (true, None);
        }
        if target == target_obs {
            if let Some((_, obs)) = observer.as_mut() {
                let t = Instant::now();
                let frame = engine.frame(scene);
                // A blown-up state between two samples stops the run as a broken invariant
                // before it reaches the observers.
                if let Some(bad) = frame.non_finite() {
                    samples.push(engine.sample());
                    return (false, Some(engine.sanity_check().err().unwrap_or(bad)));
                }
                obs.observe(&frame);
                cadence.timing.observers += since(t);
            }
            j += 1;
        }
        if target < target_report {
            continue;
        }
        let t = Instant::now();
        samples.push(engine.sample());
        cadence.timing.samples += since(t);
        progress(samples.last().expect("just pushed"));
        // The end of a stretch gets the full check before the watcher may extend the run.
        let stretch_end = target >= duration;
        let checked = if stretch_end {
            cadence.full(engine)
        } else {
            cadence.at_sample(engine)
        };
        if let Err(e) = checked {
            return (false, Some(e));
        }
        if stretch_end {
            // The watcher may continue the same trajectory to a later end.
            let t = Instant::now();
            let extended = observer.as_mut().and_then(|(_, obs)| obs.extend(duration));
            cadence.timing.observers += since(t);
            match extended {
                Some(end) if end > duration => {
                    if let Some(hook) = &settings.on_extend {
                        (hook.0)();
                    }
                    duration = end;
                    last_obs = last_obs_of(duration, obs_dt);
                }
                _ => return (false, None),
            }
        }
        k += 1;
    }
}
