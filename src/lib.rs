//! wetgran: phase diagrams of wet granular matter.
//!
//! Layers, dependencies pointing one way: [`scene`] and [`physics`] -> [`sim`] -> [`observe`]
//! (observers, classification) -> [`sweep`] (sweep files, job specs, `run_job`) -> [`store`]
//! (which stores those types) -> [`boundary`], [`report`] -> `cli`; [`refine`] plans new
//! points in [`boundary`]'s plane and runs them through the scheduler and the store. The scene
//! holds the plain-data `[observe]` and `[classify]` sections; the exceptions to the direction
//! are the scheduler, `sweep::runner`, and the refinement rounds, `refine::driver`, which drive
//! the store they sit below.
//! The physics follows MODEL.md (K. Röller, "Numerical simulations of wet granular matter",
//! Göttingen 2010); choices where the text is silent or wrong are listed in
//! docs/model-choices.md.

pub mod bench;
pub mod boundary;
pub mod cli;
pub mod cluster;
pub mod observe;
pub mod physics;
pub mod refine;
pub mod report;
pub mod scene;
pub mod sim;
pub mod store;
pub mod sweep;
