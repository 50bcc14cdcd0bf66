//! Observers, order parameters and the phase classification (MODEL.md 7).
//!
//! [`run_observed`] runs a scene and hands a [`Frame`] to every observer the scene's `[observe]`
//! section asks for, `samples_per_period` times per period (the driving period `2 pi / omega`,
//! or one time unit without a drive). Each observer keeps a time series over the whole run and
//! averages over the stationary window `[transient_periods * period, run.duration]`:
//!
//! | module | observable |
//! |---|---|
//! | [`temperature`] | `T_g / E_cb`, global and per lateral bin (Eq. 3.2) |
//! | [`profiles`] | lateral profiles of `n_cb` and of the packing fraction; `Delta n_cb` (Eq. 3.3), `Delta n_area` |
//! | [`location_changes`] | `f_lc` (Delaunay in 2D, neighbour shells in 3D) |
//! | [`diffusion`] | per-layer lateral MSD and diffusion coefficient |
//! | [`stationarity`] | first versus second half of the window |
//! | [`shear`](mod@shear) | shear drive: `E_par`, `E_perp`, their window means and extrema per cycle |
//! | [`classify`](mod@classify) | the phase from the observables and the `[classify]` thresholds |
//! | [`line`](mod@line) | the fluid-gas inflection point along a line of constant Gamma |
//!
//! Collision counts (pair, wall), bridge formations and ruptures over the window come from the
//! engine's event counters at the window's first and last sample. Observers only read copies of
//! the state: observing never changes a trajectory.

pub mod bins;
pub mod classify;
pub mod convergence;
pub mod diffusion;
pub mod line;
pub mod location_changes;
pub mod policy;
pub mod profiles;
pub mod shear;
pub mod spec;
pub mod stationarity;
pub mod temperature;

pub use classify::{
    Classification, DecisionInputs, Mobility, Phase, RegionInputs, Thresholds, classify,
};
pub use diffusion::{Diffusion, LayerDiffusion};
pub use line::{Inflection, fluid_gas_inflection};
pub use policy::ConvergenceSpec;
pub use spec::{ObserveSpec, period_of};
pub use stationarity::{Stationarity, StationarityCheck};

use crate::scene::Scene;
use crate::sim::{Frame, RunReport};
use bins::LateralBins;
use location_changes::{LocationChangeCounter, Method};
use profiles::ProfileObserver;
use serde::{Deserialize, Serialize};
use temperature::TemperatureObserver;

/// Something that looks at sampled frames. `in_window` says whether the frame's time lies in the
/// stationary window.
pub trait Observer {
    fn observe(&mut self, frame: &Frame, in_window: bool);
}

/// Stationarity floors (see [`stationarity`]): below these magnitudes a change is judged
/// against the floor instead of the value itself.
pub const FLOOR_TEMPERATURE: f64 = 0.05;
/// Floor for bridges per particle.
pub const FLOOR_BRIDGES_PER_PARTICLE: f64 = 0.1;
/// Floor for `f_lc` (location changes per particle per period).
pub const FLOOR_FLC: f64 = 0.05;
/// Floor for `E_par` in units of `E_cb` (`m g d` dry): the default solid threshold.
pub const FLOOR_E_PAR: f64 = 0.1;

/// `f_lc` over the window.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LocationChanges {
    /// "delaunay" (2D) or "neighbour_shell" (3D).
    pub method: String,
    /// Location changes counted in the window.
    pub count: u64,
    /// `f_lc`: changes per particle per period.
    pub per_particle_per_period: f64,
    /// Interval between the samples the count was taken from.
    pub sample_interval: f64,
}

/// Lateral profiles, time-averaged over the window (bins along `x`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Profiles {
    pub bin_width: f64,
    pub centres: Vec<f64>,
    /// Mean particle number per bin.
    pub particles: Vec<f64>,
    /// Packing fraction (areal in 2D, volume in 3D).
    pub packing: Vec<f64>,
    /// Bridge density, bridges per lateral length (2D) or area (3D), units `d^-(D-1)`.
    pub n_cb: Vec<f64>,
    /// `T_g / E_cb` per bin (`None` where a bin never held two particles).
    pub temperature_reduced: Vec<Option<f64>>,
    /// `f_lc` per bin (`None` without the location-change observer).
    pub flc: Option<Vec<f64>>,
    /// `max n_cb - min n_cb` (Eq. 3.3), units `d^-(D-1)`.
    pub delta_n_cb: f64,
    /// `max - min` of the packing fraction.
    pub delta_n_area: f64,
}

/// Events inside the window.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct WindowCounts {
    pub pair_collisions: u64,
    pub wall_collisions: u64,
    pub bridge_formations: u64,
    pub bridge_ruptures: u64,
    /// Pair collisions per wall collision (`None` without wall collisions).
    pub pair_per_wall: Option<f64>,
}

/// The time series sampled over the whole run (observer samples).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TimeSeries {
    pub time: Vec<f64>,
    /// `T_g / E_cb`.
    pub temperature_reduced: Vec<f64>,
    pub bridges_per_particle: Vec<f64>,
    /// `(t, f_lc)` over each sample interval ending at `t` (empty without the observer).
    pub location_changes: Vec<(f64, f64)>,
}

/// Stationary averages, the stationarity check and the counts of one run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Observables {
    pub dimension: usize,
    pub particles: usize,
    /// The period time is counted in (driving period, or 1 without a drive).
    pub period: f64,
    pub window_start: f64,
    pub window_end: f64,
    /// Observer samples inside the window.
    pub window_samples: usize,
    pub sample_interval: f64,
    /// The energy unit of the reduced temperatures: `E_cb`, or `m g d` for dry scenes.
    pub temperature_unit: f64,
    /// "E_cb" or "m g d".
    pub temperature_unit_name: String,
    /// Window mean of `T_g / temperature_unit` (`T_g / E_cb` for wet scenes).
    pub granular_temperature_reduced: f64,
    /// Window mean of the number of bridges per particle.
    pub bridges_per_particle: f64,
    pub location_changes: Option<LocationChanges>,
    pub profiles: Profiles,
    pub diffusion: Option<Diffusion>,
    pub counts: WindowCounts,
    pub stationarity: Stationarity,
    pub series: Option<TimeSeries>,
    /// Shear drive only: `E_par`, `E_perp` and their cycles ([`shear`](mod@shear)).
    #[serde(default)]
    pub shear: Option<shear::ShearObservables>,
    /// Run to stationarity (`[convergence]`): the verdict, the window and the block
    /// statistics ([`convergence`](mod@convergence)); `None` for a fixed-length run.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub convergence: Option<convergence::Convergence>,
}

impl Observables {
    /// Whether the run reached a stationary window: the `[convergence]` verdict where the
    /// run had a policy, else the first-half/second-half check ([`stationarity`]).
    pub fn converged(&self) -> bool {
        self.convergence
            .as_ref()
            .map_or(self.stationarity.stationary, |c| c.converged)
    }
}

/// [`Observables::converged`] of a stored observables JSON object (`None` if it has neither
/// a convergence verdict nor a stationarity check).
pub fn converged_in_json(observables: &serde_json::Value) -> Option<bool> {
    observables
        .get("convergence")
        .and_then(|c| c.get("converged"))
        .or_else(|| {
            observables
                .get("stationarity")
                .and_then(|s| s.get("stationary"))
        })
        .and_then(serde_json::Value::as_bool)
}

/// What [`run_observed`] returns.
#[derive(Debug, Clone, Serialize)]
pub struct ObservedRun {
    pub report: RunReport,
    pub observables: Observables,
    pub classification: Classification,
}

/// Runs a validated scene with the observers of its `[observe]` section and classifies it with
/// its `[classify]` thresholds; `progress` gets the completed fraction in `[0, 1]`.
pub fn run_observed(scene: &Scene, progress: &mut dyn FnMut(f64)) -> ObservedRun {
    run_observed_with_frame(scene, progress).0
}

/// Like [`run_observed`], and also returns the last sampled configuration (for pictures).
pub fn run_observed_with_frame(
    scene: &Scene,
    progress: &mut dyn FnMut(f64),
) -> (ObservedRun, Frame) {
    run_observed_from(scene, None, progress)
}

/// The observers of one window (rebuilt when the run-length policy starts a new window).
struct ObserverSet {
    temperature: TemperatureObserver,
    profiles: ProfileObserver,
    lc: Option<LocationChangeCounter>,
    diffusion: Option<diffusion::DiffusionObserver>,
    shear_obs: Option<shear::ShearObserver>,
}

impl ObserverSet {
    fn new(scene: &Scene, bins: &LateralBins, unit: f64, period: f64) -> Self {
        let spec = &scene.observe;
        let temperature = TemperatureObserver::new(bins.clone(), unit);
        let profiles = ProfileObserver::new(bins.clone(), scene.particles.diameter);
        let lc = spec.location_changes.then(|| {
            let method = if scene.dimension == 2 {
                Method::Delaunay {
                    max_edge: spec.lc_max_edge * scene.particles.diameter,
                    margin: spec.lc_flip_margin,
                }
            } else {
                Method::NeighbourShell {
                    enter: spec.lc_enter_factor,
                    leave: spec.lc_leave_factor,
                }
            };
            LocationChangeCounter::new(method, bins.clone(), period)
        });
        let diffusion = spec
            .diffusion
            .then(|| diffusion::DiffusionObserver::new(spec.layers.min(scene.particles.count)));
        let shear_obs = scene
            .shear_slabs()
            .is_some()
            .then(|| shear::ShearObserver::new(unit));
        Self {
            temperature,
            profiles,
            lc,
            diffusion,
            shear_obs,
        }
    }

    fn observe(&mut self, frame: &Frame, in_window: bool) {
        self.temperature.observe(frame, in_window);
        self.profiles.observe(frame, in_window);
        if let Some(o) = self.lc.as_mut() {
            o.observe(frame, in_window);
        }
        if let Some(o) = self.diffusion.as_mut() {
            o.observe(frame, in_window);
        }
        if let Some(o) = self.shear_obs.as_mut() {
            o.observe(frame, in_window);
        }
    }
}

/// The monitored quantities of one observer sample (the convergence test's input):
/// `T_g / unit`, bridges per particle, `Delta n_cb` of the sample (Eq. 3.3 on one frame).
#[derive(Debug, Clone, Copy)]
struct Monitored {
    time: f64,
    values: [f64; 3],
}

/// The observers, the window and the run-length policy, seen by the sampling loop.
struct Watch<'a> {
    scene: &'a Scene,
    bins: LateralBins,
    unit: f64,
    period: f64,
    set: ObserverSet,
    /// Start of the current window.
    t_start: f64,
    eps: f64,
    first_counts: Option<crate::sim::event_driven::EventCounts>,
    last: Option<Frame>,
    window_samples: usize,
    monitored: Vec<Monitored>,
    /// The policy in absolute times (`None`: fixed length).
    schedule: Option<policy::Schedule>,
    checks: usize,
    tests: Vec<convergence::BlockTest>,
    converged: bool,
    /// End of the whole run so far (for progress).
    progress_end: f64,
    progress: &'a mut dyn FnMut(f64),
}

impl Watch<'_> {
    /// The tests of the current window `[t_start, t_end]`.
    fn block_tests(&self, spec: &ConvergenceSpec) -> Vec<convergence::BlockTest> {
        let names = ["temperature_reduced", "bridges_per_particle", "delta_n_cb"];
        let floors = [
            FLOOR_TEMPERATURE,
            FLOOR_BRIDGES_PER_PARTICLE,
            convergence::FLOOR_DELTA_N_CB,
        ];
        let quantities = if self.scene.is_wet() { 3 } else { 1 };
        (0..quantities)
            .map(|q| {
                let x: Vec<f64> = self
                    .monitored
                    .iter()
                    .filter(|m| m.time >= self.t_start - self.eps)
                    .map(|m| m.values[q])
                    .collect();
                convergence::block_test(
                    names[q],
                    &x,
                    spec.blocks,
                    spec.sigmas,
                    spec.rel_tolerance,
                    floors[q],
                )
            })
            .collect()
    }
}

impl crate::sim::Watcher for Watch<'_> {
    fn observe(&mut self, frame: &Frame) {
        let in_window = frame.time >= self.t_start - self.eps;
        self.set.observe(frame, in_window);
        let n = frame.len().max(1) as f64;
        let t_g = self.set.temperature.series.last().map_or(f64::NAN, |s| s.1);
        let delta = profiles::spread(&profiles::bridge_density(
            frame,
            &self.bins,
            self.scene.particles.diameter,
        ));
        self.monitored.push(Monitored {
            time: frame.time,
            values: [t_g, frame.bridges.len() as f64 / n, delta],
        });
        if in_window {
            self.window_samples += 1;
            if self.first_counts.is_none() {
                self.first_counts = Some(frame.counts.clone());
            }
        }
        let t0 = self.progress_end;
        (self.progress)((frame.time / t0).clamp(0.0, 1.0));
        self.last = Some(frame.clone());
    }

    /// The run-length policy (`policy`): test the window; stop if it is stationary or the
    /// next window would pass the cap, else start a new window here and run one more.
    fn extend(&mut self, t_end: f64) -> Option<f64> {
        let schedule = self.schedule?;
        let spec = self.scene.convergence.as_ref()?;
        self.checks += 1;
        self.tests = self.block_tests(spec);
        self.converged = convergence::Convergence::verdict(&self.tests);
        let next = t_end + schedule.window;
        if self.converged || next > schedule.cap * (1.0 + 1e-12) {
            return None;
        }
        // The run so far is transient: fresh observers from the frame at `t_end` on.
        self.set = ObserverSet::new(self.scene, &self.bins, self.unit, self.period);
        self.t_start = t_end;
        self.window_samples = 0;
        self.first_counts = None;
        let last = self.last.take().expect("the end frame was observed");
        self.monitored.pop();
        self.progress_end = schedule.cap;
        crate::sim::Watcher::observe(self, &last);
        Some(next)
    }
}

/// Like [`run_observed_with_frame`], starting from a saved state at `t0` (or the scene's
/// initial state): the run, its transient and its windows are those of a fresh run shifted
/// by `t0` (`[t0 + transient, t0 + duration]`, and so on). With a `[convergence]` section the
/// run is extended on the same trajectory until the window is stationary ([`policy`]).
pub fn run_observed_from(
    scene: &Scene,
    start: Option<&crate::sim::EngineState>,
    progress: &mut dyn FnMut(f64),
) -> (ObservedRun, Frame) {
    let spec = &scene.observe;
    let period = period_of(scene);
    let dt = spec.sample_interval(scene);
    let t0 = start.map_or(0.0, |s| s.time);
    let schedule = scene.convergence.as_ref().map(|c| {
        let s = c.schedule(scene);
        policy::Schedule {
            first_check: t0 + s.first_check,
            cap: t0 + s.cap,
            ..s
        }
    });
    let duration = schedule.map_or(t0 + scene.run.duration, |s| s.first_check);
    let t_start = t0 + spec.window_start(scene);
    let (n_bins, _) = spec.bins(scene);
    let bins = LateralBins::new(n_bins, scene.container.size[0]);
    let e_cb = scene.e_cb();
    let (unit, unit_name) = if e_cb > 0.0 {
        (e_cb, "E_cb")
    } else {
        let u = scene.particles.mass * scene.gravity.max(0.0) * scene.particles.diameter;
        if u > 0.0 { (u, "m g d") } else { (1.0, "1") }
    };

    let set = ObserverSet::new(scene, &bins, unit, period);
    let mut watch = Watch {
        scene,
        bins: bins.clone(),
        unit,
        period,
        set,
        t_start,
        eps: 1e-9 * duration.max(1.0),
        first_counts: None,
        last: None,
        window_samples: 0,
        monitored: Vec::new(),
        schedule,
        checks: 0,
        tests: Vec::new(),
        converged: false,
        progress_end: duration,
        progress,
    };
    let mut run_scene = scene.clone();
    run_scene.run.duration = duration;
    let report = crate::sim::run_scene_watched(&run_scene, start, dt, &mut watch, &mut |_| {});
    // A policy run that stopped before its cap reports its end as complete.
    if watch
        .last
        .as_ref()
        .is_some_and(|f| f.time < watch.progress_end)
    {
        (watch.progress)(1.0);
    }
    let Watch {
        set:
            ObserverSet {
                temperature,
                profiles,
                lc,
                diffusion,
                shear_obs,
            },
        t_start,
        eps,
        first_counts,
        last,
        window_samples,
        monitored,
        checks,
        tests,
        converged,
        ..
    } = watch;
    let last = last.expect("the observer sees at least the initial frame");
    let window_end = last.time;
    let convergence = schedule.map(|s| {
        let c = scene
            .convergence
            .as_ref()
            .expect("a schedule comes from a policy");
        convergence::Convergence {
            converged,
            window_start: t_start,
            window_end,
            checks,
            first_check: s.first_check,
            cap: s.cap,
            blocks: c.blocks,
            sigmas: c.sigmas,
            rel_tolerance: c.rel_tolerance,
            tests,
        }
    });

    let particles_per_bin = profiles.particles();
    let n_cb = profiles.n_cb();
    let packing = profiles.packing();
    let flc_bins = lc.as_ref().map(|o| o.per_bin(&particles_per_bin));
    let profile = Profiles {
        bin_width: bins.width,
        centres: bins.centres(),
        delta_n_cb: profiles::spread(&n_cb),
        delta_n_area: profiles::spread(&packing),
        particles: particles_per_bin,
        packing,
        n_cb,
        temperature_reduced: temperature.profile_reduced(),
        flc: flc_bins,
    };
    let location_changes = lc.as_ref().map(|o| LocationChanges {
        method: o.method().name().to_string(),
        count: o.window_count,
        per_particle_per_period: o.per_particle_per_period(),
        sample_interval: dt,
    });

    let c0 = first_counts.unwrap_or_else(|| last.counts.clone());
    let c1 = &last.counts;
    let walls = c1.wall_collisions - c0.wall_collisions;
    let pairs = c1.pair_collisions - c0.pair_collisions;
    let counts = WindowCounts {
        pair_collisions: pairs,
        wall_collisions: walls,
        bridge_formations: c1.bridge_formations - c0.bridge_formations,
        bridge_ruptures: c1.bridge_ruptures - c0.bridge_ruptures,
        pair_per_wall: (walls > 0).then(|| pairs as f64 / walls as f64),
    };

    let window = (t_start, window_end);
    let tol = spec.stationarity_tolerance;
    let mut checks = vec![stationarity::check(
        "temperature_reduced",
        &temperature.series,
        window,
        FLOOR_TEMPERATURE,
        tol,
    )];
    if scene.is_wet() {
        checks.push(stationarity::check(
            "bridges_per_particle",
            &profiles.series,
            window,
            FLOOR_BRIDGES_PER_PARTICLE,
            tol,
        ));
    }
    if let Some(o) = &lc {
        checks.push(stationarity::check(
            "location_changes",
            &o.series,
            window,
            FLOOR_FLC,
            tol,
        ));
    }
    if let Some(o) = &shear_obs {
        checks.push(stationarity::check(
            "e_par",
            &o.e_par_series(),
            window,
            FLOOR_E_PAR,
            tol,
        ));
    }
    let in_window = |s: &[(f64, f64)]| -> Vec<f64> {
        s.iter()
            .filter(|(t, _)| *t >= t_start - eps)
            .map(|&(_, x)| x)
            .collect()
    };
    let mean = |v: Vec<f64>| v.iter().sum::<f64>() / v.len().max(1) as f64;
    let series = spec.time_series.then(|| TimeSeries {
        time: monitored.iter().map(|m| m.time).collect(),
        temperature_reduced: monitored.iter().map(|m| m.values[0]).collect(),
        bridges_per_particle: monitored.iter().map(|m| m.values[1]).collect(),
        location_changes: lc.as_ref().map_or_else(Vec::new, |o| o.series.clone()),
    });
    let observables = Observables {
        dimension: scene.dimension,
        particles: scene.particles.count,
        period,
        window_start: t_start,
        window_end,
        window_samples,
        sample_interval: dt,
        temperature_unit: unit,
        temperature_unit_name: unit_name.to_string(),
        granular_temperature_reduced: temperature.mean_reduced(),
        bridges_per_particle: mean(in_window(&profiles.series)),
        location_changes,
        profiles: profile,
        diffusion: diffusion.as_ref().and_then(|o| o.finish(scene.dimension)),
        counts,
        stationarity: stationarity::verdict(tol, checks),
        series,
        shear: shear_obs.as_ref().map(|o| o.finish(spec.time_series)),
        convergence,
    };
    let classification = classify(&observables, &scene.classify);
    (
        ObservedRun {
            report,
            observables,
            classification,
        },
        last,
    )
}
