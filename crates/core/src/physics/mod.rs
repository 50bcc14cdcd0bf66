//! Pure physics: contact laws, capillary bridge rules, free flight, size distributions.
//!
//! Everything here is a plain function of its arguments, shared by the engines and tested on its
//! own against the formulas of docs/model.md.

pub(crate) mod capillary;
pub(crate) mod contact;
pub(crate) mod flight;
pub mod hertz;
pub mod quartic;
pub mod shaken_wall;
pub(crate) mod size;
pub mod wall_table;
