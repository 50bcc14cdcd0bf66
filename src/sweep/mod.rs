//! Phase-diagram sweeps: the sweep file, its expansion into content-hashed job specs, the job
//! runner (`run_job`, the same on any machine) and the scheduler that runs a sweep's pending jobs
//! on worker threads against the store.
//!
//! Data flow (DESIGN.md): sweep file --expand--> job specs --schedule--> workers --run_job-->
//! results --store--> SQLite.

pub mod file;
pub mod job;
pub mod progress;
pub mod relabel;
pub mod runner;
pub mod spec;

pub use file::{Axis, AxisKind, SweepError, SweepFile};
pub use job::{JobError, JobResult, run_job, run_job_from};
pub use runner::{RunOptions, RunSummary, run_sweeps};
pub use spec::{JobSpec, Skipped, SweepJob};
