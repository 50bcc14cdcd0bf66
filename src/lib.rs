//! wetgran: phase diagrams of wet granular matter.
//!
//! Layers, dependencies pointing one way (ARCHITECTURE.md): [`physics`] -> [`scene`] (with its
//! plain-data `[observe]`, `[classify]` and `[convergence]` sections) -> [`sim`] -> [`observe`]
//! (observers, classification) -> [`sweep`] (sweep files, job specs, `run_job`) -> [`store`]
//! (which stores those types) -> [`run`] (the scheduler that claims jobs, relabelling),
//! [`boundary`], [`cluster`] -> [`refine`], [`report`] -> `cli`.
//! The physics follows MODEL.md (K. Röller, "Numerical simulations of wet granular matter",
//! Göttingen 2010); choices where the text is silent or wrong are listed in
//! docs/model-choices.md. [`test_pause`] (a leaf, used by `observe` and `store`) holds the
//! pause points of the crash-torture tests, inert unless their environment variable is set.

pub mod bench;
pub mod boundary;
pub mod cli;
pub mod cluster;
pub mod observe;
pub mod physics;
pub mod refine;
pub mod report;
pub mod run;
pub mod scene;
pub mod sim;
pub mod store;
pub mod sweep;
pub mod test_pause;
