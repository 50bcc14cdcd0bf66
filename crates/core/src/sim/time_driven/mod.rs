//! Time-driven molecular dynamics of soft (Hertz) disks and spheres with the minimal capillary
//! model (docs/model.md 2.2, 3.1), chosen by `engine.kind = "time"`: the engine and its two
//! execution strategies in `engine/`, the parts as ARCHITECTURE.md, "Time engine", describes;
//! the damping constants are `scene::damping` (validation needs them to bound the time step).

pub use crate::scene::damping;
mod domains;
pub(crate) mod engine;
pub(crate) mod integrator;
pub(crate) mod neighbours;
mod pair_kernel;
pub mod shear;
mod team;
mod walls;

pub use engine::{BodyForce, NoBodyForce, TimeEngine};
