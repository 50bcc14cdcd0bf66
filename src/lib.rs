//! wetgran: phase diagrams of wet granular matter.
//!
//! Layers, dependencies pointing one way: [`scene`] and [`physics`] -> [`sim`] -> [`observe`]
//! -> [`report`] -> `cli` (the scene holds the plain-data `[observe]` and `[classify]` sections).
//! The physics follows MODEL.md (K. Röller, "Numerical simulations of wet granular matter",
//! Göttingen 2010); choices where the text is silent or wrong are listed in
//! docs/model-choices.md.

pub mod bench;
pub mod cli;
pub mod observe;
pub mod physics;
pub mod report;
pub mod scene;
pub mod sim;
