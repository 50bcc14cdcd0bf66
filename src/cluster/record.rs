//! The sweep directory a cluster works in, and the result record a task leaves in it.
//!
//! Layout (all on the shared filesystem; the database is never opened by a task):
//!
//! ```text
//! DIR/specs/<job id>.json     the canonical job spec (self-contained: `wetgran job run` input)
//! DIR/results/<job id>.json   the task's result record (written atomically: temp file + rename)
//! DIR/arrays/array-<n>.sbatch the sbatch script of submission n
//! DIR/arrays/array-<n>.tasks  its task list: line k + 1 is the job id of array task k
//! DIR/logs/<array>_<task>.out the task's standard output and error (Slurm's --output)
//! ```
//!
//! A result record is one JSON object: `format`, `job_id`, `outcome` (`{"done": JobResult}` or
//! `{"failed": "message"}`), `wall_seconds`, `finished_at`, `host` and `slurm_task`
//! (`ARRAYJOB_TASK` when run under Slurm). A file that does not parse, has another format, names
//! another job than its file name, or holds a result that is not one wetgran writes (times not
//! finite and >= 0, an unknown phase label, observables that are not an object) is corrupt.

use crate::sweep::{JobResult, JobSpec};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Version of the result-record layout.
pub const RECORD_FORMAT: u32 = 1;

/// The paths inside a sweep directory.
#[derive(Debug, Clone, PartialEq)]
pub struct SweepDir {
    pub root: PathBuf,
}

impl SweepDir {
    pub fn new(root: &Path) -> SweepDir {
        SweepDir {
            root: root.to_path_buf(),
        }
    }

    pub fn arrays(&self) -> PathBuf {
        self.root.join("arrays")
    }
    pub fn spec(&self, job_id: &str) -> PathBuf {
        self.root.join("specs").join(format!("{job_id}.json"))
    }
    pub fn result(&self, job_id: &str) -> PathBuf {
        self.root.join("results").join(format!("{job_id}.json"))
    }

    /// Creates the four folders.
    pub fn create(&self) -> std::io::Result<()> {
        for d in ["specs", "results", "arrays", "logs"] {
            std::fs::create_dir_all(self.root.join(d))?;
        }
        Ok(())
    }

    /// Writes a job's canonical spec (atomically; left alone when already there with the same
    /// text).
    pub fn write_spec(&self, spec: &JobSpec) -> std::io::Result<PathBuf> {
        let path = self.spec(&spec.id());
        let text = spec.canonical_json();
        if std::fs::read_to_string(&path).ok().as_deref() != Some(text.as_str()) {
            write_atomic(&path, text.as_bytes())?;
        }
        Ok(path)
    }
}

/// How a task ended.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Outcome {
    Done(JobResult),
    /// The error message (a simulation panic, a numerical guard, an unreadable spec).
    Failed(String),
}

/// What a task leaves in `results/<job id>.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ResultRecord {
    pub format: u32,
    pub job_id: String,
    pub outcome: Outcome,
    pub wall_seconds: f64,
    /// Seconds since the Unix epoch.
    pub finished_at: f64,
    pub host: String,
    /// `ARRAYJOB_TASK` under Slurm.
    pub slurm_task: Option<String>,
}

impl ResultRecord {
    /// A record of this process's environment (host name, Slurm array task).
    pub fn new(job_id: &str, outcome: Outcome, wall_seconds: f64) -> ResultRecord {
        let slurm_task = match (
            std::env::var("SLURM_ARRAY_JOB_ID"),
            std::env::var("SLURM_ARRAY_TASK_ID"),
        ) {
            (Ok(j), Ok(t)) => Some(format!("{j}_{t}")),
            _ => std::env::var("SLURM_JOB_ID").ok(),
        };
        ResultRecord {
            format: RECORD_FORMAT,
            job_id: job_id.to_string(),
            outcome,
            wall_seconds,
            finished_at: crate::store::now(),
            host: crate::store::host_name(),
            slurm_task,
        }
    }

    /// Who computed it, as stored in the database's `owner` columns: `slurm:TASK@host`, or
    /// `elsewhere@host` outside Slurm.
    pub fn owner(&self) -> String {
        match &self.slurm_task {
            Some(t) => format!("slurm:{t}@{}", self.host),
            None => format!("elsewhere@{}", self.host),
        }
    }

    /// Writes the record atomically (a reader sees no file or the whole file).
    pub fn write(&self, path: &Path) -> std::io::Result<()> {
        let text = serde_json::to_string_pretty(self).expect("a record serializes");
        write_atomic(path, format!("{text}\n").as_bytes())
    }

    /// Reads the record at `path`, which must be `expected_job`'s. `Ok(None)`: no file.
    /// `Err(reason)`: the file is corrupt.
    pub fn read(path: &Path, expected_job: &str) -> Result<Option<ResultRecord>, String> {
        let text = match std::fs::read_to_string(path) {
            Ok(t) => t,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
            Err(e) => return Err(format!("cannot read it: {e}")),
        };
        let r: ResultRecord =
            serde_json::from_str(&text).map_err(|e| format!("not a result record: {e}"))?;
        if r.format != RECORD_FORMAT {
            return Err(format!(
                "record format {} (this wetgran reads {RECORD_FORMAT})",
                r.format
            ));
        }
        if r.job_id != expected_job {
            return Err(format!(
                "the record is job {}'s, not this file's job {expected_job}",
                r.job_id
            ));
        }
        if let Outcome::Done(res) = &r.outcome {
            check_result(res)?;
        }
        Ok(Some(r))
    }
}

/// What a result from elsewhere must be before it is stored: finite non-negative times, a
/// phase label this wetgran knows (or none), observables and decision numbers that are JSON
/// objects (or no decision). A record of another program or version that happens to parse is
/// refused here.
fn check_result(res: &JobResult) -> Result<(), String> {
    let time_ok = |t: f64| t.is_finite() && t >= 0.0;
    if !(time_ok(res.simulated_time) && time_ok(res.wall_seconds)) {
        return Err(format!(
            "a result with times that are not finite non-negative numbers (simulated {}, wall \
             {})",
            res.simulated_time, res.wall_seconds
        ));
    }
    if let Some(p) = &res.phase
        && p.parse::<wetgran_core::observe::Phase>().is_err()
    {
        return Err(format!("a result with an unknown phase label `{p}`"));
    }
    if !res.observables.is_object() {
        return Err("a result whose observables are not a JSON object".to_string());
    }
    if res.decided_on.as_ref().is_some_and(|d| !d.is_object()) {
        return Err("a result whose decision numbers are not a JSON object".to_string());
    }
    Ok(())
}

/// Writes `bytes` whole to `path` (`output::write_file`: a temporary file beside it, synced and
/// renamed over it): on a POSIX filesystem (NFS and Lustre included) a reader sees the old file
/// or the whole new one. A database at `path` is refused.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    Ok(crate::output::write_file(
        path,
        bytes,
        &crate::output::Protected::none(),
    )?)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn result() -> JobResult {
        JobResult {
            checkpoint: None,
            phase: Some("g".to_string()),
            decided_on: Some(serde_json::json!({"a": 1})),
            observables: serde_json::json!({"granular_temperature_reduced": 0.25}),
            simulated_time: 3.5,
            wall_seconds: 0.5,
            events: 1234,
        }
    }

    /// Regression: serde_json's default float parser may miss the nearest double by one ulp
    /// (CI saw `finished_at` 1795370055.8602185 read back as ...2183), so a record did not
    /// read back equal to what was written. The crate enables serde_json's `float_roundtrip`.
    #[test]
    fn floats_read_back_bit_exactly() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(7);
        let mut values = vec![1795370055.8602185f64, 1795370055.8602183, 0.1, 1.0 / 3.0];
        values.extend((0..20000).map(|_| rng.gen_range(1.0e9..2.0e9) + rng.r#gen::<f64>()));
        values.extend((0..20000).map(|_| f64::from_bits(rng.r#gen::<u64>() >> 2)));
        for x in values.into_iter().filter(|x| x.is_finite()) {
            let text = serde_json::to_string(&x).unwrap();
            let back: f64 = serde_json::from_str(&text).unwrap();
            assert_eq!(back.to_bits(), x.to_bits(), "{x:e} -> {text} -> {back:e}");
        }
    }

    /// The corrupt files (cut, another job's, another format, a result wetgran never writes)
    /// are `collect`'s test `truncated_and_foreign_result_files_are_reported_never_stored`.
    #[test]
    fn result_and_failure_records_read_back() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("abc.json");
        assert_eq!(ResultRecord::read(&path, "abc"), Ok(None));
        for outcome in [
            Outcome::Done(result()),
            Outcome::Failed("numerical guard: x".to_string()),
        ] {
            let r = ResultRecord::new("abc", outcome, 0.5);
            r.write(&path).unwrap();
            assert_eq!(ResultRecord::read(&path, "abc"), Ok(Some(r.clone())));
            assert!(r.owner().ends_with(&format!("@{}", r.host)));
            // No temporary file is left beside it.
            let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
            assert_eq!(names.len(), 1);
        }
    }
}
