//! A test binary that is also the child process it stops: started with [`CHILD_VAR`] set, the
//! binary is the `wetgran` command line (`wetgran::cli::main_with`) with hooks that pause it at
//! the point [`PAUSE_AT_VAR`] names (`point` or `point:n`, the `n`-th pass): it prints
//! [`MARKER`], the point and the pass to standard error, then sleeps [`PAUSE_SECS_VAR`] seconds
//! (default 30), so that the test can kill or interrupt it exactly there. The points are the
//! store's write points (`checkpoint`, `extend`, `refine`, `register`:
//! `wetgran::store::WritePoint`) and `window`, the run's extension by one more window
//! (`wetgran_core::sim::RunSettings::on_extend`). A binary using this module has its own
//! harness (`harness = false` in Cargo.toml) and starts its `main` with [`run_child`].

// Each binary uses part of the module.
#![allow(dead_code)]

use std::process::{Command, ExitCode};
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Duration;
use wetgran::cli::Hooks;
use wetgran::store::WriteHook;
use wetgran_core::sim::ExtendHook;

/// Set in the environment of a child: this binary is then the command line.
pub(crate) const CHILD_VAR: &str = "WETGRAN_CRASH_CHILD";
/// The point a child pauses at: `point` or `point:n`.
pub(crate) const PAUSE_AT_VAR: &str = "WETGRAN_CRASH_PAUSE_AT";
/// How long a child pauses, in seconds.
pub(crate) const PAUSE_SECS_VAR: &str = "WETGRAN_CRASH_PAUSE_SECS";
/// What a child prints to standard error at its pause, before the point and the pass.
pub(crate) const MARKER: &str = "wetgran-pause:";

/// The command line's exit code when this process is a child, `None` when it is the tests.
pub(crate) fn run_child() -> Option<ExitCode> {
    std::env::var_os(CHILD_VAR).map(|_| wetgran::cli::main_with(&child_hooks()))
}

/// The pause a child makes: at the `nth` pass of `point`, for `pause`.
struct Pause {
    point: String,
    nth: u64,
    pause: Duration,
    passes: AtomicU64,
}

impl Pause {
    fn pass(&self, point: &str) {
        if point != self.point {
            return;
        }
        let n = self.passes.fetch_add(1, Ordering::SeqCst) + 1;
        if n == self.nth {
            eprintln!("{MARKER} {point} {n}");
            std::thread::sleep(self.pause);
        }
    }
}

/// A child's hooks: the pause [`PAUSE_AT_VAR`] names, none without it.
fn child_hooks() -> Hooks {
    let Ok(spec) = std::env::var(PAUSE_AT_VAR) else {
        return Hooks::default();
    };
    let (point, nth) = match spec.split_once(':') {
        Some((p, n)) => (p.to_string(), n.trim().parse().expect("a pass number")),
        None => (spec, 1),
    };
    let secs: f64 = std::env::var(PAUSE_SECS_VAR).map_or(30.0, |s| s.parse().expect("seconds"));
    let pause = Arc::new(Pause {
        point,
        nth,
        pause: Duration::from_secs_f64(secs),
        passes: AtomicU64::new(0),
    });
    let at_window = pause.clone();
    Hooks {
        write: Some(WriteHook::new(move |p| pause.pass(p.name()))),
        extend: Some(ExtendHook::new(move || at_window.pass("window"))),
    }
}

/// This binary as a child (the command line), pausing `secs` seconds at `pause` (`point:n`)
/// if given.
pub(crate) fn child(pause: Option<(&str, &str)>) -> Command {
    let mut cmd = Command::new(std::env::current_exe().expect("the test binary"));
    cmd.env(CHILD_VAR, "1")
        .env_remove(PAUSE_AT_VAR)
        .env_remove(PAUSE_SECS_VAR);
    if let Some((at, secs)) = pause {
        cmd.env(PAUSE_AT_VAR, at).env(PAUSE_SECS_VAR, secs);
    }
    cmd
}
