//! Running one job: `run_job(spec) -> result`, the same function for the local worker pool and
//! for a job shipped elsewhere. A panic or a tripped numerical guard becomes a [`JobError`] with
//! its message; it never takes the worker down.

use super::spec::JobSpec;
use crate::sim::{RunReport, run_scene_with_progress};
use serde::{Deserialize, Serialize};
use std::fmt;

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

/// Stationary averages of the run report's samples (used until the observers are merged).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BasicObservables {
    /// Start and end of the stationary window `[transient, duration]`.
    pub window: [f64; 2],
    /// Samples inside the window.
    pub samples: usize,
    /// Time average of the granular temperature `T_g` (MODEL.md Eq. 3.2) over the window.
    pub granular_temperature: f64,
    /// The same in units of `E_cb` (wet scenes).
    pub granular_temperature_over_ecb: Option<f64>,
    /// Time average of the number of capillary bridges over the window.
    pub bridges: f64,
    /// Event counts of the whole run.
    pub events: crate::sim::event_driven::EventCounts,
    pub stopped_on_event_cap: bool,
    pub energy_bookkeeping_error: f64,
}

/// Runs a job spec; `progress` gets the completed fraction of the simulated time, in `[0, 1]`.
pub fn run_job(spec: &JobSpec, progress: &mut dyn FnMut(f64)) -> Result<JobResult, JobError> {
    let duration = spec.scene.run.duration;
    let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        // INTEGRATION: replace this block with
        //   let run = crate::observe::run_observed(&spec.scene, progress);
        //   let classification = crate::observe::classify(&run.observables, &thresholds);
        // and fill `phase = Some(classification.phase.to_string())`,
        // `decided_on = Some(serde_json::to_value(&classification.decided_on))`,
        // `observables = serde_json::to_value(&run.observables)` below.
        let report = run_scene_with_progress(&spec.scene, &mut |s| {
            progress((s.time / duration).clamp(0.0, 1.0))
        });
        let observables = basic_observables(spec, &report)?;
        Ok::<_, JobError>((report, observables, None::<String>, None))
    }));
    let (report, observables, phase, decided_on) = match outcome {
        Ok(r) => r?,
        Err(payload) => return Err(JobError::Panic(panic_message(payload.as_ref()))),
    };
    Ok(JobResult {
        phase,
        decided_on,
        observables: serde_json::to_value(observables).expect("observables serialize"),
        simulated_time: report.simulated_time,
        wall_seconds: report.wall_seconds,
        events: report.events_total,
    })
}

/// Averages the samples of the stationary window and applies the numerical guards.
fn basic_observables(spec: &JobSpec, report: &RunReport) -> Result<BasicObservables, JobError> {
    if let Some(v) = &report.invariant_violation {
        return Err(JobError::Numerical(format!(
            "engine invariant broken at t = {:.6}: {v}",
            report.simulated_time
        )));
    }
    let t0 = spec.observe.transient_periods * spec.period();
    let window: Vec<_> = report.samples.iter().filter(|s| s.time >= t0).collect();
    if window.is_empty() {
        return Err(JobError::Numerical(format!(
            "no sample after the transient (t >= {t0:.6}; the run stopped at t = {:.6})",
            report.simulated_time
        )));
    }
    let n = window.len() as f64;
    let t_g = window.iter().map(|s| s.granular_temperature).sum::<f64>() / n;
    let bridges = window.iter().map(|s| s.bridges as f64).sum::<f64>() / n;
    if !t_g.is_finite() {
        return Err(JobError::Numerical(format!(
            "granular temperature is not finite ({t_g})"
        )));
    }
    let e_cb = spec.scene.e_cb();
    Ok(BasicObservables {
        window: [t0, report.simulated_time],
        samples: window.len(),
        granular_temperature: t_g,
        granular_temperature_over_ecb: (e_cb > 0.0).then(|| t_g / e_cb),
        bridges,
        events: report.events.clone(),
        stopped_on_event_cap: report.stopped_on_event_cap,
        energy_bookkeeping_error: report.energy_bookkeeping_error,
    })
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
        match run_job(&spec, &mut |_| {}) {
            Err(JobError::Panic(m)) => assert!(m.contains("dimension 4"), "{m}"),
            other => panic!("expected a panic error, got {other:?}"),
        }
    }

    #[test]
    fn averages_cover_the_samples_after_the_transient() {
        let spec = tiny_spec();
        let mut fractions = Vec::new();
        let r = run_job(&spec, &mut |f| fractions.push(f)).unwrap();
        assert!(r.phase.is_none(), "no classifier yet");
        // Elastic disks, no gravity, fully periodic: kinetic energy and momentum (zero) are
        // conserved, so T_g stays the initial 1.0 at every sample.
        let o = &r.observables;
        assert!(
            (o["granular_temperature"].as_f64().unwrap() - 1.0).abs() < 1e-9,
            "{o}"
        );
        // Transient a quarter of the 2-unit run, 4 samples per unit: samples at 0.5 .. 2.0.
        assert_eq!(o["samples"], 7);
        assert_eq!(o["window"][0], 0.5);
        assert_eq!(fractions.last().copied(), Some(1.0));
        assert!(fractions.windows(2).all(|w| w[0] <= w[1]));
    }
}
