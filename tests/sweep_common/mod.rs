//! Shared helpers of the sweep tests: sweep files written into temporary folders, the wetgran
//! binary, and synthetic results committed through the store's own claim/finish path.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use wetgran::store::Store;
use wetgran::sweep::JobResult;

/// A small 2D wet shaken scene: 40 disks in a 20 d x 9 d box. One driving period at
/// (Gamma, E*) = (3, 2) is T = 2 pi v_w / Gamma with v_w = sqrt(2 E* E_cb).
pub(crate) const TINY_SCENE: &str = r#"
dimension = 2
[box]
size = [20.0, 9.0]
[particles]
count = 40
polydispersity = 0.06
[contact]
restitution = 0.9
[capillary]
model = "thin_thread"
[drive]
kind = "sine"
gamma = 3.0
e_star = 2.0
[initial]
temperature_over_ecb = 20.0
seed = 7
[run]
duration = 10.0
"#;

/// Writes `text` to `dir/name` and returns the path.
pub(crate) fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).expect("write a test file");
    p
}

/// The wetgran binary built for these tests.
pub(crate) fn wetgran() -> Command {
    Command::new(env!("CARGO_BIN_EXE_wetgran"))
}

/// Runs wetgran with `args` and returns its output.
pub(crate) fn run(args: &[&str]) -> Output {
    wetgran().args(args).output().expect("start wetgran")
}

pub(crate) fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).to_string()
}

pub(crate) fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).to_string()
}

/// Standard output then standard error of `o` (`sweep run` prints its job lines on stdout and
/// its messages on stderr).
pub(crate) fn both(o: &Output) -> String {
    stdout(o) + &stderr(o)
}

/// Starts `cmd` with its standard output and standard error written into one pipe, in the
/// order written (the job lines of `sweep run` on stdout, its messages and pause markers on
/// stderr), and returns the child with the lines of that pipe.
pub(crate) fn spawn_merged(
    cmd: &mut Command,
) -> (
    std::process::Child,
    std::io::Lines<std::io::BufReader<std::io::PipeReader>>,
) {
    use std::io::BufRead;
    let (reader, writer) = std::io::pipe().expect("a pipe");
    let child = cmd
        .stdout(writer.try_clone().expect("a pipe"))
        .stderr(writer)
        .spawn()
        .expect("start wetgran");
    // The command holds the pipe's writing end: drop it, so the lines end with the child.
    cmd.stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null());
    (child, std::io::BufReader::new(reader).lines())
}

/// Claims every pending job of the sweep and finishes it with the phase `phase(coords,
/// replica)`, as a runner would (no simulation).
pub(crate) fn finish_synthetic(
    store: &Store,
    sweep_id: i64,
    phase: impl Fn(&[serde_json::Value], i64) -> Option<String>,
) -> usize {
    let mut n = 0;
    while let Some(c) = store.claim(&[sweep_id]).expect("claim") {
        let result = JobResult {
            checkpoint: None,
            phase: phase(&c.coords, c.replica),
            // Settled, so that every synthetic point carries boundaries.
            decided_on: Some(serde_json::json!({
                "synthetic": true,
                "settling": {"verdict": "stationary", "regions": []}
            })),
            observables: serde_json::json!({"granular_temperature": 1.5, "n": c.point}),
            simulated_time: 1.0,
            wall_seconds: 0.01,
            events: 10,
        };
        assert!(store.finish(&c, &result).expect("finish"));
        n += 1;
    }
    n
}

/// A test that cannot run here for `why` (a service or a system facility is missing): under CI
/// (`CI=true`, where `.ci/run` provides it) that is a failure, elsewhere the test says it skips.
pub(crate) fn skip_unless_ci(test: &str, why: &str) {
    if std::env::var("CI").is_ok_and(|v| v == "true") {
        panic!("{test}: {why}; under CI=true this must not be missing");
    }
    eprintln!("SKIPPED {test}: {why}");
}
