//! Stationarity check reported with every result: the window is cut in two halves at its
//! midpoint in time, and each monitored quantity's mean over the first half is compared with
//! its mean over the second. The relative change is `|b - a| / max(|a|, |b|, floor)`; the
//! `floor` (one per quantity) keeps quantities that are nearly zero from failing on noise. The
//! run is stationary when every change is at most the tolerance (`observe.stationarity_tolerance`).

use serde::{Deserialize, Serialize};

/// One monitored quantity.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StationarityCheck {
    pub quantity: String,
    pub first_half: f64,
    pub second_half: f64,
    pub relative_change: f64,
    pub ok: bool,
}

/// All checks of a run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Stationarity {
    pub tolerance: f64,
    pub checks: Vec<StationarityCheck>,
    /// Every check passed (false too when the window held fewer than two samples per half).
    pub stationary: bool,
}

/// Compares the means of `(t, value)` samples with `t0 <= t < mid` and `mid <= t <= t1`,
/// `mid = (t0 + t1) / 2`. A half without samples gives NaN and a failed check.
pub(crate) fn check(
    quantity: &str,
    series: &[(f64, f64)],
    window: (f64, f64),
    floor: f64,
    tolerance: f64,
) -> StationarityCheck {
    let (t0, t1) = window;
    let mid = 0.5 * (t0 + t1);
    let eps = 1e-9 * t1.abs().max(1.0);
    let mean = |lo: f64, hi: f64, last: bool| {
        let v: Vec<f64> = series
            .iter()
            .filter(|(t, _)| *t >= lo - eps && (*t < hi - eps || (last && *t <= hi + eps)))
            .map(|&(_, x)| x)
            .collect();
        if v.is_empty() {
            f64::NAN
        } else {
            v.iter().sum::<f64>() / v.len() as f64
        }
    };
    let a = mean(t0, mid, false);
    let b = mean(mid, t1, true);
    let relative_change = (b - a).abs() / a.abs().max(b.abs()).max(floor);
    StationarityCheck {
        quantity: quantity.to_string(),
        first_half: a,
        second_half: b,
        relative_change,
        ok: relative_change <= tolerance,
    }
}

/// Collects checks into a verdict.
pub(crate) fn verdict(tolerance: f64, checks: Vec<StationarityCheck>) -> Stationarity {
    let stationary = !checks.is_empty() && checks.iter().all(|c| c.ok);
    Stationarity {
        tolerance,
        checks,
        stationary,
    }
}
