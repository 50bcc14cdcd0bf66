//! Event-driven molecular dynamics of hard disks and spheres with thin-thread bridges.
//!
//! One role per module (the structure is described in ARCHITECTURE.md, "Event engine"):
//! - `engine`: the scheduler (clock, bodies, queue, books: pop, validate, dispatch);
//! - `event`: the `Copy` event value and the sources' compact predictions;
//! - `queue`: the `EventQueue` trait and the calendar queue; `reference_queues` (tests only):
//!   the naive reference queue;
//! - `bodies`: delayed particle states and free flight;
//! - `pairs`, `cell_source`, `walls`, `slabs`: the event sources;
//! - `cells`: the neighbour grid; `shear`: the shear field and the sheared pair quartics;
//! - `table_cache`: the bounded cache of the `table` wall solver's tables;
//! - `ledger`: the running sums of the energy exchanged at events.

pub(crate) mod bodies;
pub(crate) mod cell_source;
pub mod cells;
pub(crate) mod engine;
pub(crate) mod event;
pub(crate) mod ledger;
pub mod pairs;
pub mod queue;
#[cfg(any(test, feature = "testing"))]
pub mod reference_queues;
pub(crate) mod shear;
pub(crate) mod slabs;
pub mod table_cache;
pub(crate) mod walls;

pub use engine::{Engine, Vector};
