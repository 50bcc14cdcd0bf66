//! Test-only pause points, for the crash-torture tests (`tests/crash_torture.rs`, and
//! `tests/safe_stores.rs`): they make a child `wetgran` stop at a named point so that the test
//! can kill or interrupt it exactly there.
//!
//! With `WETGRAN_TEST_PAUSE_AT=NAME` (or `NAME:N`) in the environment, the `N`-th time (default
//! the first) this process passes the point `NAME`, it prints `wetgran-test-pause: NAME N` to
//! standard error and sleeps `WETGRAN_TEST_PAUSE_SECS` seconds (default 30), then goes on.
//! Without the variable (always, outside those tests) [`pause_at`] compares one value read once
//! and returns. The points:
//!
//! | point | where | state at the pause |
//! |---|---|---|
//! | `checkpoint` | `Store::insert_result` (a job finished, or extended) | result and checkpoint rows written, transaction not committed |
//! | `extend` | `Store::replace_result` (`sweep resume --extend`) | the job's old result deleted, the new one not yet written |
//! | `refine` | `Store::add_jobs` (a refinement round) | the round's jobs inserted, transaction not committed |
//! | `register` | `Store::register_sweep_watched`, after each thousand jobs | a sweep's jobs inserted so far, its registration not committed |
//! | `window` | `observe`'s run-length policy | a job's run about to be extended by one more window |

use std::sync::OnceLock;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Duration;

/// The environment variable naming the point (`NAME` or `NAME:N`).
pub const PAUSE_AT_VAR: &str = "WETGRAN_TEST_PAUSE_AT";
/// The environment variable with the length of the pause in seconds.
pub const PAUSE_SECS_VAR: &str = "WETGRAN_TEST_PAUSE_SECS";
/// What is printed to standard error at the pause, before the point's name and hit count.
pub const MARKER: &str = "wetgran-test-pause:";

#[derive(Debug)]
struct Target {
    point: String,
    nth: u64,
    pause: Duration,
}

static TARGET: OnceLock<Option<Target>> = OnceLock::new();
static HITS: AtomicU64 = AtomicU64::new(0);

fn target_from_env() -> Option<Target> {
    let spec = std::env::var(PAUSE_AT_VAR).ok()?;
    let (point, nth) = match spec.split_once(':') {
        Some((p, n)) => (p.to_string(), n.trim().parse().unwrap_or(1)),
        None => (spec.clone(), 1),
    };
    let secs = std::env::var(PAUSE_SECS_VAR)
        .ok()
        .and_then(|s| s.trim().parse::<f64>().ok())
        .filter(|s| s.is_finite() && *s >= 0.0)
        .unwrap_or(30.0);
    Some(Target {
        point,
        nth: nth.max(1),
        pause: Duration::from_secs_f64(secs),
    })
}

/// Passes the pause point `point` (see the module doc); inert unless [`PAUSE_AT_VAR`] names it.
pub fn pause_at(point: &str) {
    let Some(t) = TARGET.get_or_init(target_from_env) else {
        return;
    };
    if t.point != point {
        return;
    }
    let n = HITS.fetch_add(1, Ordering::SeqCst) + 1;
    if n == t.nth {
        eprintln!("{MARKER} {point} {n}");
        std::thread::sleep(t.pause);
    }
}
