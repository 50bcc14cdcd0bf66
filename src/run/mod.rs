//! Running sweeps against the store, the layer above it: the scheduler that claims pending
//! jobs and runs them on worker threads ([`runner`]), its progress display ([`progress`]) and
//! the sweep-level relabelling of stored results by lines of constant Gamma ([`relabel`]).

pub mod progress;
pub mod relabel;
pub mod runner;

pub use runner::{JobFn, RunOptions, RunSummary, run_sweeps, run_sweeps_with};
