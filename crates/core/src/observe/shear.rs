//! Order parameters of the shear drive (docs/model.md 4.2 and 7): `E_par`, the mean kinetic energy
//! along `y` (the direction of the force), and `E_perp`, along `x` (the direction of the force's
//! variation),
//!
//! ```text
//! E_par = (1/N) sum_i m v_{i,y}^2 / 2,     E_perp = (1/N) sum_i m v_{i,x}^2 / 2,
//! ```
//!
//! (the mean flow is included: the Kolmogorov flow profile is what the drive creates), reported
//! in units of the scene's energy unit (`E_cb`, or `m g d` for dry scenes), over time, as window
//! means, and as extrema per *cycle* for Poincare sections.
//!
//! Cycle: the stationary window's `E_par` series is cut at its upward crossings of the window
//! mean of `E_par`; each cycle runs from one upward crossing to the next (a sample at or above
//! the mean following one below it starts a cycle). A cycle records the minimum and maximum of
//! `E_par` and of `E_perp` over its samples. A stationary series without oscillation has few or
//! no complete cycles; the list is then short or empty.

use crate::sim::Frame;
use serde::{Deserialize, Serialize};

/// Extrema of one cycle (module doc), energies in the scene's energy unit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Cycle {
    pub start: f64,
    pub end: f64,
    pub(crate) e_par_min: f64,
    pub(crate) e_par_max: f64,
    pub(crate) e_perp_min: f64,
    pub(crate) e_perp_max: f64,
}

/// The shear observables of one run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ShearObservables {
    /// Window mean of `E_par / unit`.
    pub e_par: f64,
    /// Window mean of `E_perp / unit`.
    pub e_perp: f64,
    /// Extrema per complete cycle in the window.
    pub cycles: Vec<Cycle>,
    /// `(t, E_par / unit, E_perp / unit)` at every sample (empty unless `observe.time_series`).
    pub series: Vec<(f64, f64, f64)>,
}

/// `(E_par, E_perp)` of one frame, absolute units.
pub fn shear_energies(frame: &Frame) -> (f64, f64) {
    let n = frame.len().max(1) as f64;
    let (mut par, mut perp) = (0.0, 0.0);
    for i in 0..frame.len() {
        let v = frame.v(i);
        perp += v[0] * v[0];
        par += v[1] * v[1];
    }
    (0.5 * frame.mass * par / n, 0.5 * frame.mass * perp / n)
}

/// Collects `E_par` and `E_perp` at every sample.
#[derive(Debug, Clone)]
pub(crate) struct ShearObserver {
    unit: f64,
    /// `(t, E_par / unit, E_perp / unit, in_window)`.
    samples: Vec<(f64, f64, f64, bool)>,
}

impl ShearObserver {
    /// Observer reporting energies in units of `unit`.
    pub(crate) fn new(unit: f64) -> Self {
        Self {
            unit,
            samples: Vec::new(),
        }
    }

    /// `E_par / unit` of the latest sample (the run policy monitors it).
    pub(crate) fn last_e_par(&self) -> Option<f64> {
        self.samples.last().map(|s| s.1)
    }

    /// Window means, cycles and (if `keep_series`) the series.
    pub(crate) fn finish(&self, keep_series: bool) -> ShearObservables {
        let window: Vec<&(f64, f64, f64, bool)> = self.samples.iter().filter(|s| s.3).collect();
        let n = window.len().max(1) as f64;
        let e_par = window.iter().map(|s| s.1).sum::<f64>() / n;
        let e_perp = window.iter().map(|s| s.2).sum::<f64>() / n;
        let series: Vec<(f64, f64, f64)> = window.iter().map(|s| (s.0, s.1, s.2)).collect();
        ShearObservables {
            e_par,
            e_perp,
            cycles: cycles(&series, e_par),
            series: if keep_series {
                self.samples.iter().map(|s| (s.0, s.1, s.2)).collect()
            } else {
                Vec::new()
            },
        }
    }

    /// Books one sample; `in_window`: whether its time lies in the stationary window.
    pub(crate) fn observe(&mut self, frame: &Frame, in_window: bool) {
        let (par, perp) = shear_energies(frame);
        self.samples
            .push((frame.time, par / self.unit, perp / self.unit, in_window));
    }
}

/// The complete cycles of `(t, E_par, E_perp)` cut at upward crossings of `level` by `E_par`
/// (module doc).
pub fn cycles(series: &[(f64, f64, f64)], level: f64) -> Vec<Cycle> {
    let starts: Vec<usize> = (1..series.len())
        .filter(|&k| series[k - 1].1 < level && series[k].1 >= level)
        .collect();
    starts
        .windows(2)
        .map(|w| {
            let part = &series[w[0]..w[1]];
            let range = |f: fn(&(f64, f64, f64)) -> f64| {
                let extremes = (f64::INFINITY, f64::NEG_INFINITY);
                part.iter()
                    .map(f)
                    .fold(extremes, |(lo, hi), x| (lo.min(x), hi.max(x)))
            };
            let (e_par_min, e_par_max) = range(|s| s.1);
            let (e_perp_min, e_perp_max) = range(|s| s.2);
            Cycle {
                start: series[w[0]].0,
                end: series[w[1]].0,
                e_par_min,
                e_par_max,
                e_perp_min,
                e_perp_max,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cycles_of_a_sine_are_its_periods() {
        // E_par = 1 + sin(2 pi t / 5), E_perp = 2 + cos(...), sampled finely over 4 periods.
        let series: Vec<(f64, f64, f64)> = (0..2000)
            .map(|k| {
                let t = k as f64 * 0.01;
                let ph = 2.0 * std::f64::consts::PI * t / 5.0;
                (t, 1.0 + ph.sin(), 2.0 + ph.cos())
            })
            .collect();
        let c = cycles(&series, 1.0);
        // Upward crossings at t = 5, 10, 15 (t = 0 has no sample before it): two cycles.
        assert_eq!(c.len(), 2, "{c:?}");
        for cy in &c {
            assert!((cy.end - cy.start - 5.0).abs() < 0.02);
            assert!((cy.e_par_max - 2.0).abs() < 1e-3 && cy.e_par_min.abs() < 1e-3);
            assert!((cy.e_perp_max - 3.0).abs() < 1e-3 && (cy.e_perp_min - 1.0).abs() < 1e-3);
        }
    }
}
