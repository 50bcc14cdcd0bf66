//! Line analyses over a set of results: the fluid-gas boundary along a line of constant Gamma
//! (docs/model.md 7) and the relabelling of the line's points by it ([`classify_line`]). For elastic
//! grains the boundary is the jump of `T_g / E_cb(E*)` ([`largest_jump`]); for inelastic ones
//! the inflection point ([`fluid_gas_inflection`]). Only the line's *mobile* points (not solid
//! by rule 1 as a whole) enter: the step from a solid to a fluid is not the fluid-gas jump.
//!
//! `T_g / E_cb` spans decades and grows roughly like `E*` deep in the gas, so the curve is read
//! on log-log axes: with `x = ln E*`, `y = ln(T_g / E_cb)`, the inflection point is where the
//! slope `dy/dx` is largest (the second derivative changes sign there). The slopes of
//! consecutive points are taken at their midpoints; the largest one and its two neighbours are
//! fitted by a parabola whose vertex is the inflection point. A largest slope at either end of
//! the line means the inflection lies outside the sampled range, and no point is returned.

use super::Observables;
use super::classify::{Classification, FluidGasFrom, Phase, Thresholds, classify, classify_with};
use serde::{Deserialize, Serialize};

/// The result of [`fluid_gas_inflection`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Inflection {
    /// `E*` of the inflection point.
    pub e_star: f64,
    /// The largest log-log slope `d ln(T_g/E_cb) / d ln E*` found.
    pub max_slope: f64,
    /// `E*` of the two sampled points that bracket it.
    pub bracket: (f64, f64),
}

/// Inflection point of `T_g / E_cb` against `E*` along one line of constant Gamma, from points
/// `(E*, T_g / E_cb)` in any order. `None` with fewer than four usable points (positive, finite,
/// distinct `E*`) or when the steepest part is at an end of the line.
pub fn fluid_gas_inflection(points: &[(f64, f64)]) -> Option<Inflection> {
    let mut p: Vec<(f64, f64)> = points
        .iter()
        .copied()
        .filter(|&(e, t)| e > 0.0 && t > 0.0 && e.is_finite() && t.is_finite())
        .map(|(e, t)| (e.ln(), t.ln()))
        .collect();
    p.sort_by(|a, b| a.0.total_cmp(&b.0));
    p.dedup_by(|a, b| a.0 == b.0);
    if p.len() < 4 {
        return None;
    }
    let mids: Vec<(f64, f64)> = p
        .windows(2)
        .map(|w| {
            (
                0.5 * (w[0].0 + w[1].0),
                (w[1].1 - w[0].1) / (w[1].0 - w[0].0),
            )
        })
        .collect();
    let k = (0..mids.len()).max_by(|&a, &b| mids[a].1.total_cmp(&mids[b].1))?;
    if k == 0 || k == mids.len() - 1 {
        return None;
    }
    let (x0, y0) = mids[k - 1];
    let (x1, y1) = mids[k];
    let (x2, y2) = mids[k + 1];
    // Vertex of the parabola through three points (divided differences).
    let d01 = (y1 - y0) / (x1 - x0);
    let d12 = (y2 - y1) / (x2 - x1);
    let a = (d12 - d01) / (x2 - x0);
    let x = if a < 0.0 {
        (0.5 * (x0 + x1) - d01 / (2.0 * a)).clamp(x0, x2)
    } else {
        x1
    };
    Some(Inflection {
        e_star: x.exp(),
        max_slope: y1,
        bracket: (p[k].0.exp(), p[k + 1].0.exp()),
    })
}

/// The jump of `T_g / E_cb` between neighbouring points of a line.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Jump {
    /// The boundary: the geometric mean of the bracketing `E*`.
    pub e_star: f64,
    /// `T_g / E_cb` ratio across the jump.
    pub ratio: f64,
    pub bracket: (f64, f64),
}

/// The jump of `T_g / E_cb` along a line, from points `(E*, T_g / E_cb)` in any order: among
/// the neighbouring pairs whose ratio `T_{k+1} / T_k` is at least `min_ratio`, the steepest in
/// log-log, `ln(T_{k+1} / T_k) / ln(E*_{k+1} / E*_k)`. The slope, not the ratio, picks it: the
/// elastic gas keeps heating with `E*` (docs/validation.md), so on a coarse line a wide step deep
/// in the gas can have a larger ratio than the transition itself (Gamma = 30: 28 over
/// E* 1.6 -> 2.6 against 17 over 1.1 -> 1.6); a discontinuity is the steepest step however the
/// line is sampled.
pub fn largest_jump(points: &[(f64, f64)], min_ratio: f64) -> Option<Jump> {
    let mut p: Vec<(f64, f64)> = points
        .iter()
        .copied()
        .filter(|&(e, t)| e > 0.0 && t > 0.0 && e.is_finite() && t.is_finite())
        .collect();
    p.sort_by(|a, b| a.0.total_cmp(&b.0));
    p.dedup_by(|a, b| a.0 == b.0);
    let (k, ratio, _) = p
        .windows(2)
        .enumerate()
        .map(|(k, w)| {
            let ratio = w[1].1 / w[0].1;
            (k, ratio, ratio.ln() / (w[1].0 / w[0].0).ln())
        })
        .filter(|&(_, ratio, _)| ratio >= min_ratio)
        .max_by(|a, b| a.2.total_cmp(&b.2))?;
    Some(Jump {
        e_star: (p[k].0 * p[k + 1].0).sqrt(),
        ratio,
        bracket: (p[k].0, p[k + 1].0),
    })
}

/// The fluid-gas boundary `E*` on one line from its mobile points `(E*, T_g / E_cb)`: the
/// jump (elastic) or the inflection (inelastic); `None` where the line does not show one.
pub fn fluid_gas_boundary(
    points: &[(f64, f64)],
    elastic: bool,
    th: &Thresholds,
) -> Option<(f64, &'static str)> {
    if elastic {
        largest_jump(points, th.line_jump_ratio).map(|j| (j.e_star, "jump"))
    } else {
        fluid_gas_inflection(points).map(|i| (i.e_star, "inflection"))
    }
}

/// Classifies the points `(E*, observables)` of one line of constant `gamma`: each point by
/// [`classify`], then, where the line's mobile points give a fluid-gas boundary, every point
/// again with "gas" meaning `E* > E*_boundary` for a homogeneous system (the regions of a
/// coexistence are told apart by their own temperatures, `classify` rule 3). Points of a line
/// without a boundary keep the per-point fallback.
pub fn classify_line(
    gamma: f64,
    points: &[(f64, &Observables)],
    th: &Thresholds,
    elastic: bool,
) -> Vec<Classification> {
    let first: Vec<Classification> = points.iter().map(|(_, o)| classify(o, th)).collect();
    // Mobile points, replicas of one E* averaged.
    let mut mobile: Vec<(f64, f64, usize)> = Vec::new();
    for ((e, o), c) in points.iter().zip(&first) {
        if c.decided_on.whole.phase == Phase::S {
            continue;
        }
        match mobile.iter_mut().find(|m| m.0 == *e) {
            Some(m) => {
                m.1 += o.granular_temperature_reduced;
                m.2 += 1;
            }
            None => mobile.push((*e, o.granular_temperature_reduced, 1)),
        }
    }
    let mobile: Vec<(f64, f64)> = mobile
        .into_iter()
        .map(|(e, t, k)| (e, t / k as f64))
        .collect();
    let Some((boundary, method)) = fluid_gas_boundary(&mobile, elastic, th) else {
        return first;
    };
    points
        .iter()
        .map(|&(e, o)| {
            let from = FluidGasFrom::Line {
                gamma,
                method: method.to_string(),
                e_star_boundary: boundary,
            };
            classify_with(o, th, &|_| e > boundary, from)
        })
        .collect()
}
