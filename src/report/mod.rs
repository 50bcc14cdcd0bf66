//! Reports of results, as text and pictures: pure functions of plain data (a
//! [`Frame`](wetgran_core::sim::Frame), [`Observables`](wetgran_core::observe::Observables),
//! stored rows), so a stored sweep point draws as well as a fresh run. Text, which the CLI
//! prints: `run_text` (`simulate`), `sweep_text` (`sweep status`, `sweep estimate`, left-out
//! points, refinements), `boundaries_text`, `cluster_text` (`sweep collect`, Slurm status),
//! `point_text` (`show`, `inflection`). Pictures and exports: `snapshot` (extended XYZ, SVG),
//! `profile_plot`, `series_plot` (one run's time series), `plot_phase` (the phase map), `lines` and `lines_plot` (lines of constant
//! Gamma), `site` (the HTML report), `export` (tidy CSV/JSON), `sensitivity` (how far each
//! boundary moves with the thresholds, relabelled from the stored observables), with `trust`
//! (the trust mark of a stored result), `chart` and `svg` (shared drawing helpers), `ticks` (an
//! axis's ticks), `regions` (the tessellation of a map), `typeset`
//! (the names of quantities as symbols) and `figure` (a figure written as SVG, PDF or PNG).

pub mod boundaries_text;
mod chart;
pub mod cluster_text;
pub mod export;
pub(crate) mod figure;
#[cfg(test)]
mod figure_read;
#[cfg(test)]
mod lean_reports_tests;
pub mod lines;
pub mod lines_plot;
pub mod plot_phase;
pub mod point_text;
pub mod profile_plot;
mod regions;
pub mod run_text;
pub mod sensitivity;
pub mod series_plot;
pub mod site;
pub mod snapshot;
mod svg;
pub mod sweep_text;
mod ticks;
pub mod trust;
pub(crate) mod typeset;

pub use profile_plot::profiles_svg;
pub use snapshot::{ColourBy, snapshot_svg, snapshot_xyz, write_snapshot};
