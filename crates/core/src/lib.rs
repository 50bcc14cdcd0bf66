//! wetgran-core: the simulation library of wetgran.
//!
//! Layers, dependencies pointing one way (ARCHITECTURE.md): [`physics`] -> [`scene`] (with its
//! plain-data `[observe]`, `[classify]` and `[convergence]` sections) -> [`sim`] -> [`observe`]
//! (observers, the run loop to stationarity, classification). The application crate `wetgran`
//! (sweeps, store, scheduler, reports, the CLI) builds on it; the crate `wetgran-bench` holds the
//! benchmarks and the stress cases.
//! The physics follows docs/model.md (K. Röller, "Numerical simulations of wet granular
//! matter", Göttingen 2010); choices where the text is silent or wrong are listed in
//! docs/model-choices.md.

pub mod observe;
pub mod physics;
pub mod scene;
pub mod sim;
