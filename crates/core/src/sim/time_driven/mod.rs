//! Time-driven molecular dynamics of soft (Hertz) disks and spheres with the minimal capillary
//! model (docs/model.md 2.2, 3.1): the second, independent engine, chosen by `engine.kind = "time"`.
//! The engine and its three execution strategies are in `engine/` (see there); its parts:
//! the domain decomposition (`domains.rs`, run by a thread team, `team.rs`), the integrators
//! (`integrator.rs`), the Verlet list (`neighbours.rs`), the pair force (`pair_kernel.rs`), the
//! walls (`walls.rs`) and the shear body force (`shear.rs`); the damping constants are
//! `scene::damping` (the scene's validation needs them to bound the time step).

pub use crate::scene::damping;
mod domains;
pub(crate) mod engine;
pub(crate) mod integrator;
pub(crate) mod neighbours;
mod pair_kernel;
pub mod shear;
mod team;
mod walls;

pub use domains::DOMAIN_MIN_PARTICLES;
pub use engine::{BodyForce, Execution, NoBodyForce, TimeEngine};
