//! `wetgran-bench tdmd`: speed of the time-driven engine on the dry shaken 2D system of issue 6.
//!
//! The system is [`dry_shaken_time_driven_widened`] (N = 1200 disks in 400 x 9, shaken at
//! `A = 0.05`, `Gamma = 15`, `dt = 1e-4`, damping for restitution 0.9 at impact speed 1).
//!
//! Each repetition builds a fresh engine (same seed), runs one time unit untimed (the bed leaves
//! the lattice), then times `scale` simulated time units (at least 0.1). Reported per integrator:
//! particle-steps per second and wall seconds per simulated time unit (median, min, max over the
//! repetitions), the ratio of the median to the 0.38 s per time unit a widely used C++ granular
//! code needs for this system (issue 6; goal: at least 3x faster, i.e. <= 0.127 s), the largest
//! overlap over the whole run and the neighbour-list builds per step.
//!
//! With `--threads 1,2` each repetition runs once per thread count (a rayon pool of that size
//! installed around it; the counts alternate within a repetition, so slow phases of a shared
//! machine hit them alike), one row per integrator and count, and the speed-up of the median
//! wall time against the first count. The trajectory is the same bits for every count
//! (`crates/core/tests/time_driven_pins.rs`), so the work is identical. CPU time is that of the whole
//! process (every thread, from `/proc/self/task/*/schedstat`), so it includes the time the
//! pool's threads spend waiting for work.

use crate::{Spread, median};
use std::fmt::Write as _;
use std::time::Instant;
use wetgran_core::scene::DEFAULT_STIFFNESS;
use wetgran_core::sim::time_driven::TimeEngine;
use wetgran_testkit::reference::dry_shaken_time_driven_widened;

/// Wall seconds per simulated time unit of the C++ reference code (issue 6).
pub(crate) const BASELINE_SECONDS_PER_TIME_UNIT: f64 = 0.38;

/// CPU time of the calling thread in seconds (Linux `/proc/thread-self/schedstat`, first field:
/// nanoseconds on a CPU), `None` elsewhere. On a loaded machine it separates the engine's cost
/// from the time spent waiting for a core.
pub(crate) fn thread_cpu_seconds() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    let ns: f64 = text.split_whitespace().next()?.parse().ok()?;
    Some(ns * 1e-9)
}

/// CPU time of the whole process (every thread) in seconds, from `/proc/self/task/*/schedstat`
/// (threads that ended are not counted); `None` without `/proc`.
pub(crate) fn process_cpu_seconds() -> Option<f64> {
    let mut ns = 0.0;
    for task in std::fs::read_dir("/proc/self/task").ok()? {
        let path = task.ok()?.path().join("schedstat");
        let Ok(text) = std::fs::read_to_string(path) else {
            continue;
        };
        ns += text.split_whitespace().next()?.parse::<f64>().ok()?;
    }
    Some(ns * 1e-9)
}

/// One integrator's figures.
#[derive(Debug, Clone, PartialEq, Default)]
pub(crate) struct TdmdRow {
    pub integrator: &'static str,
    /// Threads of the pool the runs were made on.
    pub threads: usize,
    /// Wall seconds per simulated time unit, one per repetition.
    pub seconds_per_time: Vec<f64>,
    /// CPU seconds per simulated time unit, one per repetition (empty without `/proc`).
    pub(crate) cpu_per_time: Vec<f64>,
    /// Verlet-list entries per particle at the end of the last repetition.
    pub(crate) pairs_per_particle: f64,
    pub particles: usize,
    pub dt: f64,
    pub max_overlap: f64,
    pub(crate) builds_per_step: f64,
    pub damping: f64,
}

/// Runs the benchmark for both integrators and each thread count of `threads` (alternating
/// within each repetition); rows in the order integrator, then thread count. `n_factor`: the
/// system widened ([`dry_shaken_time_driven_widened`]); the timed span is divided by it (at least 0.02 time
/// units), so that a repetition costs about the same.
pub(crate) fn measure_threads(
    repeat: usize,
    scale: f64,
    threads: &[usize],
    n_factor: usize,
) -> Vec<TdmdRow> {
    let timed = (scale.max(0.1) / n_factor.max(1) as f64).max(0.02);
    let pools: Vec<rayon::ThreadPool> = threads
        .iter()
        .map(|&t| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(t.max(1))
                .build()
                .expect("a thread pool")
        })
        .collect();
    let mut rows = Vec::new();
    // Each integrator on its default path: Gear on the spatial domains (`domains.rs`, a team
    // of the pool's threads), Verlet serially.
    for integ in ["gear5", "verlet"] {
        let s = dry_shaken_time_driven_widened(integ, n_factor.max(1));
        let first = rows.len();
        for &t in threads {
            rows.push(TdmdRow {
                integrator: integ,
                threads: t.max(1),
                particles: s.particles.count,
                dt: s.engine.dt.unwrap_or(1e-4),
                damping: s.contact.damping.unwrap_or(0.0),
                ..TdmdRow::default()
            });
        }
        for _ in 0..repeat.max(1) {
            for (pool, row) in pools.iter().zip(&mut rows[first..]) {
                pool.install(|| {
                    let mut e = TimeEngine::<2, true, false>::new(&s);
                    e.run_until(1.0);
                    let (b0, s0) = (e.list_builds(), e.steps());
                    let cpu0 = process_cpu_seconds();
                    let start = Instant::now();
                    timed_run(&mut e, 1.0 + timed);
                    let secs = start.elapsed().as_secs_f64();
                    if let (Some(c0), Some(c1)) = (cpu0, process_cpu_seconds()) {
                        row.cpu_per_time.push((c1 - c0) / timed);
                    }
                    row.seconds_per_time.push(secs / timed);
                    row.pairs_per_particle = e.list_entries() as f64 / e.len() as f64;
                    row.max_overlap = row.max_overlap.max(e.max_overlap());
                    row.builds_per_step =
                        (e.list_builds() - b0) as f64 / (e.steps() - s0).max(1) as f64;
                    e.sanity_check().expect("bench run keeps its invariants");
                });
            }
        }
    }
    rows
}

/// The timed part of a repetition, a function of its own so that a profiler can select it
/// (`valgrind --tool=callgrind --toggle-collect='*tdmd*timed_run*'`).
#[inline(never)]
pub(crate) fn timed_run(e: &mut TimeEngine<2, true, false>, t_end: f64) {
    e.run_until(t_end);
}

/// The table.
pub(crate) fn report(rows: &[TdmdRow]) -> String {
    let mut s = String::new();
    let n = rows.first().map_or(1200, |r| r.particles);
    let _ = writeln!(
        s,
        "time-driven engine, dry shaken 2D: N = {n}, sigma_p 0.06, box {} x 9, A = 0.05, Gamma = 15, dt = 1e-4",
        n / 3
    );
    s.push_str("integr.   thr    p-steps/s  s/time med       min       max  vs 0.38 s  cpu s/time cpu vs .38  max ovl/d  builds/st   pairs/p\n");
    for r in rows {
        let Spread {
            median: med,
            min,
            max,
        } = Spread::of(r.seconds_per_time.iter().copied());
        let psteps = r.particles as f64 / r.dt / med;
        let (cpu, cpu_ratio) = if r.cpu_per_time.is_empty() {
            ("n/a".to_string(), "n/a".to_string())
        } else {
            let c = median(&r.cpu_per_time);
            (
                format!("{c:.4}"),
                format!("{:.2}x", BASELINE_SECONDS_PER_TIME_UNIT / c),
            )
        };
        let _ = writeln!(
            s,
            "{:<9} {:>3} {:>12.3e} {:>11.4} {:>9.4} {:>9.4} {:>9.2}x {:>11} {:>10} {:>10.5} {:>10.4} {:>9.2}",
            r.integrator,
            r.threads,
            psteps,
            med,
            min,
            max,
            BASELINE_SECONDS_PER_TIME_UNIT / med,
            cpu,
            cpu_ratio,
            r.max_overlap,
            r.builds_per_step,
            r.pairs_per_particle
        );
    }
    for r in rows {
        let Some(base) = rows
            .iter()
            .find(|b| b.integrator == r.integrator && b.threads != r.threads)
            .filter(|_| r.threads > 1)
        else {
            continue;
        };
        let (m0, m1) = (median(&base.seconds_per_time), median(&r.seconds_per_time));
        let _ = writeln!(
            s,
            "{}: {} threads {:.2}x faster than {} (median wall time per time unit {:.4} s vs {:.4} s)",
            r.integrator,
            r.threads,
            m0 / m1,
            base.threads,
            m1,
            m0
        );
    }
    if let Some(r) = rows.first() {
        let _ = writeln!(
            s,
            "damping A_d = {:.4e} (restitution 0.9 at impact speed 1), stiffness {:e}; {} repetitions",
            r.damping,
            DEFAULT_STIFFNESS,
            r.seconds_per_time.len()
        );
    }
    s
}
