//! Running one job: `run_job(spec) -> result`, the same function for the local worker pool and
//! for a job shipped elsewhere. A panic or a tripped numerical guard becomes a [`JobError`] with
//! its message; it never takes the worker down.

use super::spec::JobSpec;
use serde::{Deserialize, Serialize};
use std::fmt;
use wetgran_core::sim::RunContext;

/// What one finished job produced.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct JobResult {
    /// The phase label (`s`, `f`, `g`, `sfc`, `sgc`, `fgc`), `None` until a classifier runs.
    pub phase: Option<String>,
    /// The numbers and thresholds the phase was decided on (JSON), `None` without a classifier.
    pub decided_on: Option<serde_json::Value>,
    /// The stationary observables (JSON object).
    pub observables: serde_json::Value,
    pub simulated_time: f64,
    pub wall_seconds: f64,
    pub events: u64,
    /// The final state, stored as the job's checkpoint with the result (not part of the
    /// result's JSON: cluster records carry no checkpoint).
    #[serde(skip)]
    pub checkpoint: Option<Box<wetgran_core::sim::EngineState>>,
}

/// Why a job produced no result.
#[derive(Debug, Clone, PartialEq)]
pub enum JobError {
    /// The simulation panicked; the panic message.
    Panic(String),
    /// A numerical guard tripped (broken engine invariant, non-finite observable).
    Numerical(String),
}

impl fmt::Display for JobError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            JobError::Panic(m) => write!(f, "panicked: {m}"),
            JobError::Numerical(m) => write!(f, "numerical guard: {m}"),
        }
    }
}

impl std::error::Error for JobError {}

/// Runs a job spec in the caller's context `ctx` (threads, hook); `progress` gets the
/// completed fraction of the simulated time, in `[0, 1]`. The observers and thresholds are the
/// scene's `[observe]` and `[classify]` sections.
pub fn run_job(
    spec: &JobSpec,
    ctx: &RunContext,
    progress: &mut dyn FnMut(f64),
) -> Result<JobResult, JobError> {
    guarded_run(|| wetgran_core::observe::run_observed(&spec.scene, ctx, progress))
}

/// Runs a continuation job (`spec.start_from`) from `start`, its predecessor's final state
/// already carried into its container (`EngineState::continued`): a fresh run of the spec's
/// length and window from `t = 0`, as [`run_job`] but from that state.
pub fn run_job_from(
    spec: &JobSpec,
    start: &wetgran_core::sim::EngineState,
    ctx: &RunContext,
    progress: &mut dyn FnMut(f64),
) -> Result<JobResult, JobError> {
    guarded_run(|| {
        wetgran_core::observe::run_observed_from(&spec.scene, Some(start), ctx, progress).0
    })
}

/// Runs `run` with panics caught, checks its guards and turns it into a [`JobResult`] (the
/// one path of a fresh job and of an extension).
fn guarded_run(
    run: impl FnOnce() -> wetgran_core::observe::ObservedRun,
) -> Result<JobResult, JobError> {
    let run = std::panic::catch_unwind(std::panic::AssertUnwindSafe(run))
        .map_err(|payload| JobError::Panic(panic_message(payload.as_ref())))?;
    check_guards(&run)?;
    Ok(JobResult {
        phase: Some(run.classification.phase.to_string()),
        decided_on: Some(
            serde_json::to_value(&run.classification.decided_on).expect("decision serializes"),
        ),
        observables: serde_json::to_value(&run.observables).expect("observables serialize"),
        simulated_time: run.report.simulated_time,
        wall_seconds: run.report.wall_seconds,
        events: run.report.events_total,
        checkpoint: run.report.final_state.clone().map(Box::new),
    })
}

/// Extends a finished job from its checkpoint `state` (its final state) on the same
/// trajectory, under its `[convergence]` policy (a job without one gets the default policy)
/// with the cap raised to `max_periods` periods of total run. The observers were not saved, so
/// the continuation starts a fresh window at the checkpoint, with no transient (the run so far
/// was the transient): windows of the job's window length `W` follow one another until one is
/// stationary or the next would pass the cap. `Ok(None)`: the cap leaves no room for one more
/// window. The result replaces the job's old one (`Store::replace_result`).
pub fn extend_job(
    spec: &JobSpec,
    state: &wetgran_core::sim::EngineState,
    cap: ExtendTo,
    ctx: &RunContext,
    progress: &mut dyn FnMut(f64),
) -> Result<Option<JobResult>, JobError> {
    let scene = &spec.scene;
    let period = scene.driving_period();
    let policy = scene.convergence.clone().unwrap_or_default();
    let window = policy.schedule(scene).window;
    let room = cap.time(period) - state.time;
    if room < window * (1.0 - 1e-9) {
        return Ok(None);
    }
    let mut ext = scene.clone();
    ext.run.duration = window;
    // The run so far was the transient: the new window starts at the checkpoint.
    ext.observe.transient_periods = 0.0;
    ext.observe.transient_time = 0.0;
    ext.convergence = Some(wetgran_core::observe::ConvergenceSpec {
        min_periods: 0.0,
        min_time: 0.0,
        max_periods: Some(room / period),
        // The cap is `--extend`'s alone.
        max_time: None,
        ..policy
    });
    guarded_run(|| wetgran_core::observe::run_observed_from(&ext, Some(state), ctx, progress).0)
        .map(Some)
}

/// The total run length `sweep resume --extend` / `--extend-time` allows an unconverged job.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ExtendTo {
    /// At most this many driving periods.
    Periods(f64),
    /// At most this many time units (the clock of the run policy at high frequency).
    Time(f64),
}

impl ExtendTo {
    /// The cap in time units for a job of driving period `period`.
    pub fn time(self, period: f64) -> f64 {
        match self {
            ExtendTo::Periods(p) => p * period,
            ExtendTo::Time(t) => t,
        }
    }

    /// The cap in words (`800 periods`, `400 time units`).
    pub fn describe(self) -> String {
        match self {
            ExtendTo::Periods(p) => format!("{p} periods"),
            ExtendTo::Time(t) => format!("{t} time units"),
        }
    }

    /// The cap's value, for range checks.
    pub fn value(self) -> f64 {
        match self {
            ExtendTo::Periods(v) | ExtendTo::Time(v) => v,
        }
    }
}

/// The numerical guards: a broken engine invariant, or a stationary temperature that is not a
/// finite number (no sample in the window, or a blown-up run), fails the job.
fn check_guards(run: &wetgran_core::observe::ObservedRun) -> Result<(), JobError> {
    let report = &run.report;
    if let Some(v) = &report.invariant_violation {
        return Err(JobError::Numerical(format!(
            "engine invariant broken at t = {:.6}: {v}",
            report.simulated_time
        )));
    }
    let t_g = run.observables.granular_temperature_reduced;
    if !t_g.is_finite() {
        return Err(JobError::Numerical(format!(
            "stationary granular temperature is not finite ({t_g}): no sample after the \
             transient, or a blown-up run (stopped at t = {:.6})",
            report.simulated_time
        )));
    }
    Ok(())
}

/// The text of a panic payload.
pub fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = payload.downcast_ref::<&str>() {
        s.to_string()
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else {
        "unknown panic payload".to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sweep::SweepFile;

    fn tiny_spec() -> JobSpec {
        let text = "[sweep]\nname = \"t\"\n[scene]\ndimension = 2\ngravity = 0.0\n[scene.box]\n\
                    size = [8.0, 8.0]\nboundary = [\"periodic\", \"periodic\"]\n\
                    [scene.particles]\ncount = 4\n[scene.initial]\ntemperature = 1.0\n\
                    [scene.run]\nduration = 2.0\n";
        let file = SweepFile::parse(text, std::path::Path::new("t.toml")).unwrap();
        file.expand().unwrap().remove(0).spec
    }

    #[test]
    fn a_panicking_simulation_becomes_a_job_error() {
        let mut spec = tiny_spec();
        // Bypasses validation: the engine refuses a dimension it has no type for.
        spec.scene.dimension = 4;
        match run_job(&spec, &Default::default(), &mut |_| {}) {
            Err(JobError::Panic(m)) => assert!(m.contains("dimension 4"), "{m}"),
            other => panic!("expected a panic error, got {other:?}"),
        }
    }

    #[test]
    fn averages_cover_the_samples_after_the_transient() {
        let spec = tiny_spec();
        let mut fractions = Vec::new();
        let r = run_job(&spec, &Default::default(), &mut |f| fractions.push(f)).unwrap();
        // The classifier ran and kept the numbers it decided on.
        let phase: wetgran_core::observe::Phase = r.phase.as_deref().unwrap().parse().unwrap();
        assert!(wetgran_core::observe::Phase::ALL.contains(&phase));
        assert!(r.decided_on.is_some());
        // Elastic disks, no gravity, fully periodic: kinetic energy and momentum (zero) are
        // conserved, so T_g stays the initial 1.0 (unit 1 without gravity) at every sample.
        let o = &r.observables;
        assert_eq!(o["temperature_unit"], 1.0);
        assert!(
            (o["granular_temperature_reduced"].as_f64().unwrap() - 1.0).abs() < 1e-9,
            "{o}"
        );
        // Transient a quarter of the 2-unit run, 20 samples per unit: samples at 0.5 .. 2.0.
        assert_eq!(o["window_start"], 0.5);
        assert_eq!(o["window_samples"], 31);
        assert_eq!(fractions.last().copied(), Some(1.0));
        assert!(fractions.windows(2).all(|w| w[0] <= w[1]));
    }
}
