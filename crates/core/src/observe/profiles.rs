//! Lateral profiles of the capillary-bridge density `n_cb` and of the packing fraction
//! (areal in 2D, volume in 3D), time-averaged over the window, with
//! `Delta n_cb = max n_cb - min n_cb` (docs/model.md Eq. 3.3) and `Delta n_area` likewise.
//!
//! - `n_cb(bin)` = bridges whose midpoint (nearest periodic image) lies in the bin, divided by
//!   the bin's lateral measure (its width in 2D, its area in 3D) and by the box height `H`:
//!   bridges per lateral area averaged over the height, as docs/model.md 7 defines it. Reported in
//!   units of `d^-D` (multiplied by `d^D`). (Before this normalisation the height was summed
//!   over, not averaged: stored results of that kind are converted by `reclassify`.)
//! - packing fraction(bin) = summed disk areas `pi r^2` (sphere volumes `4/3 pi r^3`) of the
//!   particles whose centre lies in the bin, over the bin's area `width * H` (volume
//!   `width * L_y * H`). A grain straddling a bin edge is counted whole in its centre's bin.
//! - [`CageCounts`]: per bin, how many cluster members stayed within given mobilities of their
//!   cage over the long lag (`observe::lateral` counts them).

use super::bins::LateralBins;
use crate::sim::Frame;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// `n_cb` per bin of one frame, in units of `d^-D` for mean diameter `d`: bridges (each counted
/// at its midpoint) per lateral measure of the bin and per unit height (docs/model.md 7).
pub fn bridge_density(frame: &Frame, bins: &LateralBins, d: f64) -> Vec<f64> {
    let scale = d.powi(frame.dimension as i32) / bins.bin_volume(&frame.box_size);
    let mut c = vec![0usize; bins.n];
    for &(i, j) in &frame.bridges {
        c[bins.of_pair(frame, i, j)] += 1;
    }
    c.iter().map(|&c| c as f64 * scale).collect()
}

/// Volume (area in 2D) of a particle of radius `r`.
pub(crate) fn particle_volume(dimension: usize, r: f64) -> f64 {
    if dimension == 2 {
        PI * r * r
    } else {
        4.0 / 3.0 * PI * r * r * r
    }
}

/// `max - min` of a profile (0 for an empty one).
pub fn spread(profile: &[f64]) -> f64 {
    if profile.is_empty() {
        return 0.0;
    }
    let max = profile.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let min = profile.iter().copied().fold(f64::INFINITY, f64::min);
    max - min
}

/// The number of bridges per particle at every sample (the profiles themselves are
/// accumulated by [`super::lateral::LateralObserver`]).
#[derive(Debug, Clone, Default)]
pub(crate) struct ProfileObserver {
    /// `(t, bridges per particle)` at every sample.
    pub series: Vec<(f64, f64)>,
}

impl ProfileObserver {
    /// Books one sample.
    pub(crate) fn observe(&mut self, frame: &Frame) {
        let n = frame.len().max(1) as f64;
        self.series
            .push((frame.time, frame.bridges.len() as f64 / n));
    }
}

/// How far cluster members move relative to their own cage (the grains they were bonded to at
/// the lag's origin) over the long lag: per bin, how many member displacements were measured
/// and how many stayed within each edge (`observe::lateral`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CageCounts {
    /// Mobilities `d^2 / (2 n_lat tau)`, `d^2` per time unit, ascending.
    pub edges: Vec<f64>,
    /// Per bin: member displacements measured (members at both ends holding a lasting bond
    /// at the origin).
    pub measured: Vec<f64>,
    /// Per bin, per edge: of those, how many had a cage-relative mobility at most the edge.
    pub within: Vec<Vec<f64>>,
}

impl CageCounts {
    /// The fraction of the member displacements of the bins `sel` whose cage-relative mobility
    /// is at most `threshold`, interpolated linearly in `ln` between the edges around it;
    /// `None` without any displacement or with `threshold` outside the edges.
    pub fn fraction_within(&self, sel: &[usize], threshold: f64) -> Option<f64> {
        let total: f64 = sel.iter().filter_map(|&b| self.measured.get(b)).sum();
        let at = |k: usize| -> f64 {
            sel.iter()
                .filter_map(|&b| self.within.get(b).and_then(|w| w.get(k)))
                .sum::<f64>()
                / total
        };
        if total <= 0.0 || threshold.is_nan() || threshold <= 0.0 {
            return None;
        }
        let k = self.edges.iter().position(|&e| e >= threshold)?;
        if k == 0 {
            return (threshold == self.edges[0]).then(|| at(0));
        }
        let (lo, hi) = (self.edges[k - 1], self.edges[k]);
        let w = (threshold / lo).ln() / (hi / lo).ln();
        Some(at(k - 1) + w * (at(k) - at(k - 1)))
    }
}

#[cfg(test)]
mod cage_tests {
    use super::CageCounts;

    #[test]
    fn fractions_interpolate_between_edges_in_log() {
        // Two bins: 10 displacements each; within 1e-3: 4 + 6 of 20, within 1e-2: 8 + 10.
        let c = CageCounts {
            edges: vec![1e-4, 1e-3, 1e-2],
            measured: vec![10.0, 10.0],
            within: vec![vec![0.0, 4.0, 8.0], vec![2.0, 6.0, 10.0]],
        };
        assert_eq!(c.fraction_within(&[0, 1], 1e-3), Some(0.5));
        assert_eq!(c.fraction_within(&[1], 1e-3), Some(0.6));
        // Half-way in ln between 1e-3 and 1e-2: half-way between 0.5 and 0.9.
        let mid = c.fraction_within(&[0, 1], 10f64.powf(-2.5)).unwrap();
        assert!((mid - 0.7).abs() < 1e-12, "{mid}");
        assert_eq!(c.fraction_within(&[0, 1], 1e-4), Some(0.1));
        // Outside the edges, or nothing measured: no answer.
        assert_eq!(c.fraction_within(&[0, 1], 5e-5), None);
        assert_eq!(c.fraction_within(&[0, 1], 0.1), None);
        assert_eq!(c.fraction_within(&[], 1e-3), None);
    }
}
