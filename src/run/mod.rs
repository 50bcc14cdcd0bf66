//! Running sweeps against the store, the layer above it: the worker pool every run goes through
//! ([`pool`]), the scheduler that claims pending jobs for it ([`runner`]), the extension of
//! unconverged results from their checkpoints ([`extend`]), the progress display
//! ([`progress`]) and the sweep-level relabelling of stored results by lines of constant Gamma
//! ([`relabel`]).

pub mod extend;
mod pool;
pub mod progress;
pub mod relabel;
pub mod runner;

pub use runner::{JobFn, RunOptions, RunSummary, run_sweeps, run_sweeps_with};
