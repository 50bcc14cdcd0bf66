//! How often the sampling loop checks an engine's invariants, and what a run is given by its
//! caller besides the scene ([`RunSettings`]: the check policy, the wall-table cache, the
//! threads it runs on and the hook called when its watcher extends it).
//!
//! An engine has two checks (`Simulation::quick_check`, `Simulation::sanity_check`): the
//! per-particle invariants in `O(N)` (finite state, inside the box, in its cell, no event in
//! the past) and the full check, which adds the pair scan (no overlap, no over-stretched bond),
//! `O(N x neighbours)`. The quick check runs at every report sample. The full check runs under
//! a [`CheckPolicy`]: at every sample ([`CheckPolicy::EverySample`], what tests and the stress
//! cases construct), or within a share of the run's wall time ([`CheckPolicy::WallShare`], the
//! product's default): at the first sample, then at a sample only while the time spent in full
//! checks is at most that share of the wall time since the run began; and in both policies at
//! the end of every stretch of the run (before a watcher extends it) and at the end of the run,
//! whatever stopped it, so the state a checkpoint stores has always passed the full check.

use super::event_driven::table_cache::{DEFAULT_TABLE_CACHE_MIB, TableCache};
use super::threads::Threads;
use super::{ExtendHook, Simulation};
use std::time::Instant;

/// The product's share of a run's wall time for the full invariant check: 1 %, half the 2 %
/// a job may spend on it, so that the one check that crosses the share stays inside.
pub const DEFAULT_CHECK_SHARE: f64 = 0.01;

/// When the sampling loop runs the engine's full invariant check (the quick check runs at
/// every report sample under any policy).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum CheckPolicy {
    /// The full check at every report sample.
    EverySample,
    /// The full check while its time stays within this share (in `(0, 1]`) of the run's wall
    /// time, and at the end of every stretch and of the run.
    WallShare(f64),
}

impl Default for CheckPolicy {
    fn default() -> Self {
        CheckPolicy::WallShare(DEFAULT_CHECK_SHARE)
    }
}

/// What a run is given by its caller besides the scene: how often it checks the engine's
/// invariants, the cache the `table` wall solver takes its tables from (shared by the jobs
/// of a sweep run), the threads the engine steps on, and a hook called each time its
/// `Watcher` extends it (before the next stretch starts).
#[derive(Debug, Clone)]
pub struct RunSettings {
    pub checks: CheckPolicy,
    pub tables: TableCache,
    pub threads: Threads,
    pub on_extend: Option<ExtendHook>,
}

impl RunSettings {
    /// The product's settings: the full check within [`DEFAULT_CHECK_SHARE`] of the run, the
    /// given table cache.
    pub fn new(tables: TableCache) -> Self {
        Self {
            checks: CheckPolicy::default(),
            tables,
            threads: Threads::default(),
            on_extend: None,
        }
    }

    /// The product's settings on `threads`, a table cache of its own, no hook.
    pub fn on(threads: Threads) -> Self {
        Self {
            threads,
            ..Self::default()
        }
    }

    /// The full check at every sample, a table cache of its own (default cap).
    pub fn every_sample() -> Self {
        Self {
            checks: CheckPolicy::EverySample,
            ..Self::default()
        }
    }
}

impl Default for RunSettings {
    /// The product's settings with a table cache of its own (default cap).
    fn default() -> Self {
        Self::new(TableCache::with_cap_mib(DEFAULT_TABLE_CACHE_MIB))
    }
}

/// Where a run's wall time went, in seconds (measured around each part by the sampling loop;
/// not part of a run's numbers: two runs of one scene differ here and nowhere else).
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct RunTiming {
    /// Advancing the engine between samples.
    pub engine: f64,
    /// The quick and the full invariant checks.
    pub checks: f64,
    /// Building frames and feeding them to the watcher (the observers).
    pub observers: f64,
    /// The report's own samples (energy, temperature, bridges).
    pub samples: f64,
    /// Full invariant checks run.
    pub full_checks: u64,
}

/// The sampling loop's check schedule under a [`CheckPolicy`], and the run's timing books.
#[derive(Debug)]
pub(crate) struct CheckCadence {
    policy: CheckPolicy,
    start: Instant,
    /// Seconds spent in full checks so far.
    full_seconds: f64,
    /// The engine's work done (`Simulation::work_done`) at the last full check.
    last_full: Option<u64>,
    pub(crate) timing: RunTiming,
}

impl CheckCadence {
    pub(crate) fn new(policy: CheckPolicy) -> Self {
        if let CheckPolicy::WallShare(share) = policy {
            assert!(
                share > 0.0 && share <= 1.0,
                "check share must lie in (0, 1], got {share}"
            );
        }
        Self {
            policy,
            start: Instant::now(),
            full_seconds: 0.0,
            last_full: None,
            timing: RunTiming::default(),
        }
    }

    /// The engine's work done when the last full check ran (`None` before the first).
    pub(crate) fn last_full_at(&self) -> Option<u64> {
        self.last_full
    }

    /// Whether a full check is due at a report sample: always under `EverySample`; under
    /// `WallShare(s)` while the full checks so far took at most `s` of the run's wall time.
    fn full_due(&self) -> bool {
        match self.policy {
            CheckPolicy::EverySample => true,
            CheckPolicy::WallShare(share) => {
                self.full_seconds <= share * self.start.elapsed().as_secs_f64()
            }
        }
    }

    /// The checks of a report sample: the quick check, then the full check when due.
    pub(crate) fn at_sample<S: Simulation>(&mut self, engine: &S) -> Result<(), String> {
        if self.full_due() {
            return self.full(engine);
        }
        let t0 = Instant::now();
        let out = engine.quick_check();
        self.timing.checks += t0.elapsed().as_secs_f64();
        out
    }

    /// The full check, whatever the policy (ends of stretches, the end of the run).
    pub(crate) fn full<S: Simulation>(&mut self, engine: &S) -> Result<(), String> {
        let t0 = Instant::now();
        let out = engine.sanity_check();
        let dt = t0.elapsed().as_secs_f64();
        self.full_seconds += dt;
        self.timing.checks += dt;
        self.timing.full_checks += 1;
        self.last_full = Some(engine.work_done());
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_sample_is_always_due_and_a_share_waits_for_the_run_to_catch_up() {
        let every = CheckCadence::new(CheckPolicy::EverySample);
        assert!(every.full_due());
        let mut shared = CheckCadence::new(CheckPolicy::WallShare(0.01));
        assert!(shared.full_due(), "the first sample gets the full check");
        // A full check that took as long as the run so far is not repeated until the run has
        // lasted 100 times as long.
        shared.full_seconds = 10.0;
        assert!(!shared.full_due(), "a share says no while it is spent");
        shared.full_seconds = 0.0;
        assert!(shared.full_due());
    }

    #[test]
    #[should_panic(expected = "check share must lie in (0, 1]")]
    fn a_share_outside_the_unit_interval_is_refused() {
        let _ = CheckCadence::new(CheckPolicy::WallShare(0.0));
    }
}
