//! Plots and exports.
