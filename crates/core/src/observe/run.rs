//! Running a scene with its observers: [`run_observed`] and its forms, and the run-length
//! policy that extends a run on the same trajectory until its label settles
//! (docs/observables.md "Run to a settled label"): at each check the run is classified, the
//! whole history is tested (`observe::trend`) and the verdict on the label
//! (`observe::settling`) decides whether it stops.

use super::lateral::LateralObserver;
use super::{
    Classification, Ending, FLOOR_BRIDGES_PER_PARTICLE, FLOOR_E_PAR, FLOOR_TEMPERATURE,
    Observables, ObserverSet, Phase, Verdict, classify, convergence, lateral_observer, profiles,
    settling, trend,
};
use crate::scene::Scene;
use crate::sim::threads::Threads;
use crate::sim::{Frame, RunReport, RunSettings};
use serde::Serialize;

/// What [`run_observed`] returns.
#[derive(Debug, Clone, Serialize)]
pub struct ObservedRun {
    pub report: RunReport,
    pub observables: Observables,
    pub classification: Classification,
}

/// Runs a validated scene with the observers of its `[observe]` section and classifies it with
/// its `[classify]` thresholds, with the caller's `settings` (threads, hook); `progress` gets
/// the completed fraction in `[0, 1]`.
pub fn run_observed(
    scene: &Scene,
    settings: &RunSettings,
    progress: &mut dyn FnMut(f64),
) -> ObservedRun {
    run_observed_with_frame(scene, settings, progress).0
}

/// Like [`run_observed`], and also returns the last sampled configuration (for pictures).
pub fn run_observed_with_frame(
    scene: &Scene,
    settings: &RunSettings,
    progress: &mut dyn FnMut(f64),
) -> (ObservedRun, Frame) {
    run_observed_from(scene, None, settings, progress)
}

/// The monitored quantities of one observer sample (the trend test's input): `T_g / unit`,
/// bridges per particle, `Delta n_cb` of the sample (Eq. 3.3 on one frame), and `E_par / unit`
/// of a sheared scene (NaN otherwise).
#[derive(Debug, Clone, Copy)]
struct Monitored {
    time: f64,
    values: [f64; 4],
}

/// The observers, the window and the run-length policy, seen by the sampling loop.
struct Watch<'a> {
    scene: &'a Scene,
    set: ObserverSet,
    /// The run's threads (the location-change counter runs beside the other observers).
    threads: &'a Threads,
    monitored: Vec<Monitored>,
    /// The regions' lateral observer over the whole history from `t_floor` on
    /// (`observe::settling`): never restarted with the windows.
    regions: LateralObserver,
    /// The policy in absolute times (`None`: fixed length).
    schedule: Option<crate::scene::convergence::Schedule>,
    /// The shortest transient the scene allows, in absolute time: the history the trend looks
    /// at starts here.
    t_floor: f64,
    checks: usize,
    /// The trend at the latest check.
    trend: Option<trend::Trend>,
    /// The label kept at the latest check (its verdict `label_kept`), if it was.
    kept: Option<Phase>,
    ending: Option<Ending>,
    /// End of the whole run so far (for progress).
    progress_end: f64,
    progress: &'a mut dyn FnMut(f64),
}

impl Watch<'_> {
    /// The trend of the run so far: the monitored history from `t_floor` on, the current
    /// window starting at the observers' window start, and the regions' quantities.
    fn assess(&self) -> trend::Trend {
        let spec = self.scene.convergence.clone().unwrap_or_default();
        let names = [
            trend::TEMPERATURE,
            trend::BRIDGES,
            trend::DELTA_N_CB,
            trend::E_PAR,
        ];
        let floors = [
            FLOOR_TEMPERATURE,
            FLOOR_BRIDGES_PER_PARTICLE,
            convergence::FLOOR_DELTA_N_CB,
            FLOOR_E_PAR,
        ];
        let wet = self.scene.is_wet();
        let sheared = self.scene.shear_slabs().is_some();
        let used: Vec<usize> = (0..4)
            .filter(|&q| q == 0 || (q < 3 && wet) || (q == 3 && sheared))
            .collect();
        let time: Vec<f64> = self.monitored.iter().map(|m| m.time).collect();
        let series: Vec<Vec<f64>> = used
            .iter()
            .map(|&q| self.monitored.iter().map(|m| m.values[q]).collect())
            .collect();
        let monitored: Vec<trend::Monitored<'_>> = used
            .iter()
            .enumerate()
            .map(|(k, &q)| trend::Monitored {
                name: names[q],
                floor: floors[q],
                values: &series[k],
            })
            .collect();
        let test = trend::TrendTest {
            blocks: spec.blocks,
            sigmas: spec.sigmas,
            rel_tolerance: spec.rel_tolerance,
        };
        let window_start = self.set.window_start();
        let mut t = trend::assess(&time, &monitored, self.t_floor, window_start, test);
        let blocks = settling::region_series(
            &self.regions,
            self.scene.dimension,
            self.scene.classify.solid_diffusion,
            FLOOR_TEMPERATURE,
        );
        let (tests, unrelaxed) = trend::assess_regions(&blocks, self.t_floor, window_start, test);
        t.region_tests = tests;
        t.unrelaxed.extend(unrelaxed);
        t
    }

    /// The label of the current window and its verdict under the trend `t`.
    fn label(&self, t: &trend::Trend) -> Classification {
        let mut obs = self.set.finish(self.scene);
        obs.trend = Some(t.clone());
        classify(&obs, &self.scene.classify)
    }
}

impl crate::sim::Watcher for Watch<'_> {
    fn observe(&mut self, frame: &Frame) {
        let set = &mut self.set;
        match self.threads.count() {
            1 => set.observe(frame),
            _ => self.threads.install(|| set.observe(frame)),
        }
        if frame.time >= self.t_floor - 1e-9 * self.t_floor.abs().max(1.0) {
            self.regions.observe(frame);
        }
        let n = frame.len().max(1) as f64;
        let t_g = self.set.temperature.series.last().map_or(f64::NAN, |s| s.1);
        let delta = profiles::spread(&profiles::bridge_density(
            frame,
            self.set.lateral.bins(),
            self.scene.particles.diameter,
        ));
        let e_par = self
            .set
            .shear
            .as_ref()
            .and_then(|o| o.last_e_par())
            .unwrap_or(f64::NAN);
        self.monitored.push(Monitored {
            time: frame.time,
            values: [t_g, frame.bridges.len() as f64 / n, delta, e_par],
        });
        let t0 = self.progress_end;
        (self.progress)((frame.time / t0).clamp(0.0, 1.0));
    }

    /// The run-length policy (docs/observables.md "Run to a settled label"): assess the history
    /// and label the window; stop if the label's verdict is stationary, if it was kept (every
    /// region settled) at this check and the one before with the same label, or if the next
    /// window would pass the cap; else start a new window here and run one more.
    fn extend(&mut self, t_end: f64) -> Option<f64> {
        let schedule = self.schedule?;
        self.checks += 1;
        let now = self.assess();
        let label = self.label(&now);
        self.trend = Some(now);
        let kept = (label.verdict() == Verdict::LabelKept).then_some(label.phase);
        let kept_twice = kept.is_some() && self.kept == kept;
        self.kept = kept;
        let next = t_end + schedule.window;
        self.ending = if label.verdict() == Verdict::Stationary {
            Some(Ending::Stationary)
        } else if kept_twice {
            Some(Ending::Settled)
        } else if next > schedule.cap * (1.0 + 1e-12) {
            Some(Ending::Cap)
        } else {
            None
        };
        if self.ending.is_some() {
            return None;
        }
        // The run so far is transient to the window's observers: fresh ones from the frame at
        // `t_end` on (the monitored series and the regions' observer go on).
        let last = self.set.last.take().expect("the end frame was observed");
        self.set = ObserverSet::with_window_start(self.scene, t_end);
        self.set.observe(&last);
        self.progress_end = schedule.cap;
        Some(next)
    }
}

/// Like [`run_observed_with_frame`], starting from a saved state at `t0` (or the scene's
/// initial state): the run, its transient and its windows are those of a fresh run shifted
/// by `t0` (`[t0 + transient, t0 + duration]`, and so on). With a `[convergence]` section the
/// run is extended on the same trajectory until its label settles (docs/observables.md).
/// `settings`: the invariant checks, the wall-table cache and the threads of the run.
pub fn run_observed_from(
    scene: &Scene,
    start: Option<&crate::sim::EngineState>,
    settings: &crate::sim::RunSettings,
    progress: &mut dyn FnMut(f64),
) -> (ObservedRun, Frame) {
    let spec = &scene.observe;
    let t0 = start.map_or(0.0, |s| s.time);
    let schedule = scene.convergence.as_ref().map(|c| {
        let s = c.schedule(scene);
        crate::scene::convergence::Schedule {
            first_check: t0 + s.first_check,
            cap: t0 + s.cap,
            ..s
        }
    });
    let duration = schedule.map_or(t0 + scene.run.duration, |s| s.first_check);
    let set = ObserverSet::with_window_start(scene, t0 + spec.window_start(scene));
    let dt = set.sample_interval();
    let mut watch = Watch {
        scene,
        set,
        threads: &settings.threads,
        monitored: Vec::new(),
        regions: lateral_observer(
            scene,
            settling::block_time(
                scene.driving_period(),
                duration - (t0 + spec.window_start(scene)),
            ),
        ),
        schedule,
        t_floor: t0 + spec.window_start(scene),
        checks: 0,
        trend: None,
        kept: None,
        ending: None,
        progress_end: duration,
        progress,
    };
    let mut run_scene = scene.clone();
    run_scene.run.duration = duration;
    let report =
        crate::sim::run_scene_watched(&run_scene, start, settings, dt, &mut watch, &mut |_| {});
    // A policy run that stopped before its cap reports its end as complete.
    if watch
        .set
        .last
        .as_ref()
        .is_some_and(|f| f.time < watch.progress_end)
    {
        (watch.progress)(1.0);
    }
    let mut observables = watch.set.finish(scene);
    let last = watch
        .set
        .last
        .take()
        .expect("the observer sees at least the initial frame");
    // The time series span the whole run, all windows.
    if let Some(series) = observables.series.as_mut() {
        let m = &watch.monitored;
        series.time = m.iter().map(|x| x.time).collect();
        series.temperature_reduced = m.iter().map(|x| x.values[0]).collect();
        series.bridges_per_particle = m.iter().map(|x| x.values[1]).collect();
    }
    // A fixed-length run is assessed once, at its end; a policy run keeps its last check's.
    let mut trend = watch.trend.take().unwrap_or_else(|| watch.assess());
    trend.policy = match (schedule, watch.ending) {
        (Some(s), Some(ending)) => Some(trend::PolicyEnd {
            ending,
            checks: watch.checks,
            first_check: s.first_check,
            cap: s.cap,
        }),
        _ => None,
    };
    observables.trend = Some(trend);
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
