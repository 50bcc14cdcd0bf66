//! Granular temperature `T_g = m (<v^2> - <v>^2) / f_d` (docs/model.md Eq. 3.2, `k_B = 1`,
//! `f_d = D`) of the whole system, reported in units of `E_cb` (of `m g d` for dry scenes).
//! The per-bin temperatures are `observe::lateral`'s.

use crate::sim::Frame;

/// `T_g` of the particles `sel` (Eq. 3.2); `None` for fewer than two particles.
pub fn granular_temperature(frame: &Frame, sel: &[usize]) -> Option<f64> {
    if sel.len() < 2 {
        return None;
    }
    let d = frame.dimension;
    let mut mean = vec![0.0; d];
    let mut sq = 0.0;
    for &i in sel {
        for (k, &v) in frame.v(i).iter().enumerate() {
            mean[k] += v;
            sq += v * v;
        }
    }
    let n = sel.len() as f64;
    let mean_sq: f64 = mean.iter().map(|m| (m / n) * (m / n)).sum();
    Some(frame.mass * (sq / n - mean_sq) / d as f64)
}

/// Time series and window mean of the global temperature (the per-bin temperatures are
/// accumulated by [`super::lateral::LateralObserver`]).
#[derive(Debug, Clone)]
pub(crate) struct TemperatureObserver {
    /// `E_cb`, or `m g d` for dry scenes.
    unit: f64,
    /// `(t, T_g / unit)` at every sample.
    pub series: Vec<(f64, f64)>,
    window_sum: f64,
    window_samples: usize,
}

impl TemperatureObserver {
    pub(crate) fn new(unit: f64) -> Self {
        Self {
            unit,
            series: Vec::new(),
            window_sum: 0.0,
            window_samples: 0,
        }
    }

    /// Window mean of `T_g / unit` (NaN without samples).
    pub(crate) fn mean_reduced(&self) -> f64 {
        self.window_sum / self.window_samples as f64
    }

    /// Books one sample; `in_window`: whether its time lies in the stationary window.
    pub(crate) fn observe(&mut self, frame: &Frame, in_window: bool) {
        let all: Vec<usize> = (0..frame.len()).collect();
        let t = granular_temperature(frame, &all).unwrap_or(0.0) / self.unit;
        self.series.push((frame.time, t));
        if in_window {
            self.window_sum += t;
            self.window_samples += 1;
        }
    }
}
