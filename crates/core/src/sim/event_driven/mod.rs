//! Event-driven molecular dynamics of hard disks and spheres with thin-thread bridges: the
//! scheduler (`engine`) over its event sources (`pairs`, `cell_source`, `walls`, `slabs`), one
//! role per module as ARCHITECTURE.md, "Event engine", describes.

pub(crate) mod bodies;
pub(crate) mod cell_source;
pub mod cells;
pub(crate) mod engine;
pub(crate) mod event;
pub mod pairs;
pub mod queue;
pub(crate) mod shear;
pub(crate) mod slabs;
pub mod table_cache;
pub(crate) mod walls;

pub use engine::{Engine, Vector};
