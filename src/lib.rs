//! wetgran: phase diagrams of wet granular matter (the application crate).
//!
//! Layers, dependencies pointing one way (ARCHITECTURE.md), above the simulation library
//! `wetgran_core` (physics, scene, sim, observe): [`sweep`] (sweep files, job specs, `run_job`)
//! -> [`store`] (which stores those types) -> [`run`] (the scheduler that claims jobs,
//! relabelling), [`boundary`], [`cluster`] -> [`refine`], [`report`] -> `cli`. Two leaves every
//! layer may use: [`output`] (every file a command writes) and [`terminal`] (stored text made
//! inert before it is printed).
//! The physics follows docs/model.md (K. Röller, "Numerical simulations of wet granular
//! matter", Göttingen 2010); choices where the text is silent or wrong are listed in
//! docs/model-choices.md.

pub mod boundary;
pub mod cli;
pub mod cluster;
pub mod output;
pub mod refine;
pub mod report;
pub mod run;
pub mod store;
pub mod sweep;
pub mod terminal;
