//! wetgran-core: the simulation library of wetgran.
//!
//! Layers, dependencies pointing one way (ARCHITECTURE.md): [`physics`] -> [`scene`] (with its
//! plain-data `[observe]`, `[classify]` and `[convergence]` sections) -> [`sim`] -> [`observe`]
//! (observers, the run loop to stationarity, classification). The application crate `wetgran`
//! (sweeps, store, scheduler, reports, the CLI) builds on it; the crate `wetgran-bench` holds the
//! benchmarks and the stress cases.
//! The physics follows docs/model.md (K. Röller, "Numerical simulations of wet granular
//! matter", Göttingen 2010); choices where the text is silent or wrong are listed in
//! docs/model-choices.md. [`test_pause`] (a leaf, used by `observe` here and by the store of the
//! application crate) holds the pause points of the crash-torture tests, inert unless their
//! environment variable is set.

pub mod observe;
pub mod physics;
pub mod scene;
pub mod sim;
pub mod test_pause;
