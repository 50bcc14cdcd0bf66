//! Time-driven molecular dynamics of soft (Hertz) disks and spheres with the minimal capillary
//! model (docs/model.md 2.2, 3.1): the second, independent engine, chosen by `engine.kind = "time"`.
//!
//! - `damping`: damping constants, given or derived from a restitution (`scene::damping`: the
//!   scene's validation needs them to bound the time step);
//! - `domains.rs`: the spatial decomposition the domain strategy steps on (two domains,
//!   threads exchange only a halo);
//! - `engine/`: the engine: construction and state I/O (`build.rs`), the [`Strategy`]
//!   trait and the step every strategy shares (`stepping.rs`), the three strategies (`serial.rs`,
//!   `rayon_split.rs`, `domain_step.rs`), what it reports (`measures.rs`);
//! - `integrator.rs`: Gear 5th-order predictor-corrector and velocity Verlet;
//! - `neighbours.rs`: linked cells and the Verlet list with skin;
//! - `pair_kernel.rs`: the force of one pair, and the three loops over pairs that call it;
//! - `shear.rs`: the continuous Kolmogorov shear force (a [`BodyForce`]);
//! - `team.rs`: a team of threads that runs many steps with one barrier per step;
//! - `walls.rs`: the Hertz floor, lid and side walls (a screened pass over the particles).

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
