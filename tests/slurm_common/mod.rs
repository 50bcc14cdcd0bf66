//! Shared helpers of the tests on a real Slurm (`tests/slurm_cluster.rs`,
//! `tests/slurm_scale.rs`): a running single-node cluster (the one `.ci/run` started, or one
//! started here through `scripts/slurm-local.sh` when this is root), or the reason there
//! cannot be one; and a wait for a sweep's arrays to leave the queue.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};
use wetgran::store::Store;

/// Stops the daemons at the end if this test started them.
pub(crate) struct Started(Option<PathBuf>);

impl Drop for Started {
    fn drop(&mut self) {
        if let Some(script) = &self.0 {
            let _ = Command::new("bash").arg(script).arg("stop").status();
        }
    }
}

fn controller_answers() -> bool {
    Command::new("scontrol")
        .arg("ping")
        .output()
        .is_ok_and(|o| o.status.success() && String::from_utf8_lossy(&o.stdout).contains("UP"))
}

/// A running Slurm, or why there cannot be one here: no controller answers and either this is
/// not root or the packages cannot be installed. Any other failure to start one panics.
pub(crate) fn slurm() -> Result<Started, String> {
    if controller_answers() {
        return Ok(Started(None));
    }
    let root = Command::new("id")
        .arg("-u")
        .output()
        .is_ok_and(|o| String::from_utf8_lossy(&o.stdout).trim() == "0");
    if !root {
        return Err(
            "no Slurm controller answers and this is not root (scripts/slurm-local.sh \
                    start needs root)"
                .to_string(),
        );
    }
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/slurm-local.sh");
    let out = Command::new("bash")
        .arg(&script)
        .arg("start")
        .output()
        .expect("run scripts/slurm-local.sh");
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    match out.status.code() {
        Some(0) => Ok(Started(Some(script))),
        Some(4) => Err(format!("slurm-wlm and munge cannot be installed:\n{text}")),
        _ => panic!("scripts/slurm-local.sh start failed on a root machine:\n{text}"),
    }
}

/// Waits until no task of the sweep's arrays is queued; panics after `limit`.
pub(crate) fn wait_for(store: &Store, sweep: i64, limit: Duration) {
    let jobs: Vec<String> = {
        let mut j: Vec<String> = store
            .tasks(sweep)
            .unwrap()
            .into_iter()
            .filter_map(|t| t.slurm_job)
            .collect();
        j.sort();
        j.dedup();
        j
    };
    let t0 = Instant::now();
    loop {
        let out = Command::new("squeue")
            .args(["-h", "-r", "-o", "%i %T", "-j", &jobs.join(",")])
            .output()
            .expect("squeue");
        let text = String::from_utf8_lossy(&out.stdout).to_string();
        if text.trim().is_empty() {
            return;
        }
        assert!(
            t0.elapsed() < limit,
            "tasks still queued after {} s:\n{text}",
            limit.as_secs()
        );
        std::thread::sleep(Duration::from_millis(250));
    }
}
