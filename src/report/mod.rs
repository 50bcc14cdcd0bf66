//! Reports of results, as text and pictures. Text (pure functions returning `String`, which the
//! CLI prints): the run summary of `simulate` (`run_text`), `sweep status`, `sweep estimate`,
//! left-out points and refinement lines (`sweep_text`), the phase maps and boundary points of
//! `boundaries` (`boundaries_text`), the hard-case table of `stress`
//! (`stress_text`), `sweep collect` and the Slurm part of `sweep status`
//! (`cluster_text`), `show` and `inflection` (`point_text`). Pictures and exports: snapshots of a
//! configuration (extended XYZ for OVITO, SVG coloured by kinetic energy or bridge count, with
//! the bridges drawn), the lateral-profile plot (SVG), the phase-diagram plot of a sweep database
//! (SVG, `plot_phase`), the order parameters along lines of constant Gamma (`lines`, drawn by
//! `lines_plot`), the static HTML report of a sweep (`site`), the tidy export of all results (CSV
//! or JSON with the same columns, long-format series files; `export`) and the trust mark of a
//! stored result (`trust`); `chart` holds the plotters helpers the pictures share (ticks at
//! chosen values, a legend outside the plot). Everything takes plain data (a
//! [`Frame`](wetgran_core::sim::Frame), [`Observables`](wetgran_core::observe::Observables), stored results),
//! so a stored sweep point can be drawn as well as a fresh run.

pub mod boundaries_text;
mod chart;
pub mod cluster_text;
pub mod export;
#[cfg(test)]
mod lean_reports_tests;
pub mod lines;
pub mod lines_plot;
pub mod plot_phase;
pub mod point_text;
pub mod profile_plot;
pub mod run_text;
pub mod site;
pub mod snapshot;
mod svg;
pub mod sweep_text;
pub mod trust;

pub use profile_plot::profiles_svg;
pub use snapshot::{ColourBy, snapshot_svg, snapshot_xyz, write_snapshot};
