//! Phase-diagram sweeps: the sweep file, its expansion into content-hashed job specs, and the
//! job runner (`run_job`, the same on any machine). The scheduler that runs a sweep's pending
//! jobs against the store sits a layer up, in [`crate::run`].
//!
//! Data flow (ARCHITECTURE.md): sweep file --expand--> job specs --schedule--> workers
//! --run_job--> results --store--> SQLite.

pub mod estimate;
pub mod file;
pub mod job;
pub mod spec;

pub use file::{Axis, AxisKind, SweepError, SweepFile};
pub use job::{JobError, JobResult, run_job, run_job_from};
pub use spec::{JobSpec, Skipped, SweepJob};
