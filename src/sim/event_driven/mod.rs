//! Event-driven molecular dynamics of hard disks and spheres with thin-thread bridges.

pub mod cells;
pub mod engine;
pub mod queue;
pub mod shear;
pub mod table_cache;

pub use engine::{EnergyLedger, Engine, EventCounts, Vector};
