//! Reports of a sweep database: the phase-diagram plot (SVG) and the export of all results
//! (CSV, JSON).

pub mod export;
pub mod plot_phase;
