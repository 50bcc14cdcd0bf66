//! wetgran: phase diagrams of wet granular matter.
//!
//! Layers, dependencies pointing one way: [`scene`] and [`physics`] -> [`sim`] -> [`observe`]
//! (observers, classification) -> [`sweep`] (sweep files, job specs, `run_job`) -> [`store`]
//! (which stores those types) -> [`boundary`], [`report`] -> `cli`. The scene holds the
//! plain-data `[observe]` and `[classify]` sections; the one exception to the direction is the
//! scheduler, `sweep::runner`, which drives the store it sits below.
//! The physics follows MODEL.md (K. Röller, "Numerical simulations of wet granular matter",
//! Göttingen 2010); choices where the text is silent or wrong are listed in
//! docs/model-choices.md.

pub mod bench;
pub mod boundary;
pub mod cli;
pub mod observe;
pub mod physics;
pub mod refine;
pub mod report;
pub mod scene;
pub mod sim;
pub mod store;
pub mod sweep;
