//! Pictures and exports of results: snapshots of a configuration (extended XYZ for OVITO, SVG
//! coloured by kinetic energy or bridge count, with the bridges drawn) and the lateral-profile
//! plot (SVG). Hand-written SVG, no plotting dependency. Everything takes plain data (a
//! [`Frame`](crate::sim::Frame), [`Observables`](crate::observe::Observables)), so a stored
//! sweep point can be drawn as well as a fresh run.

pub mod profile_plot;
pub mod snapshot;
mod svg;

pub use profile_plot::profiles_svg;
pub use snapshot::{ColourBy, snapshot_svg, snapshot_xyz, write_snapshot};
