//! Granular temperature `T_g = m (<v^2> - <v>^2) / f_d` (docs/model.md Eq. 3.2, `k_B = 1`,
//! `f_d = D`), globally and per lateral bin, reported in units of `E_cb` (of `m g d` for dry
//! scenes). Each bin uses its own mean velocity; time averages over the window are
//! particle-weighted per bin (a bin's sample counts as often as it holds particles).

use super::Observer;
use super::bins::LateralBins;
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

/// Per-bin `T_g` of one frame (`None` where a bin holds fewer than two particles), and the
/// particle count of every bin.
pub fn temperature_profile(frame: &Frame, bins: &LateralBins) -> (Vec<Option<f64>>, Vec<usize>) {
    let mut members: Vec<Vec<usize>> = vec![Vec::new(); bins.n];
    for i in 0..frame.len() {
        members[bins.of_particle(frame, i)].push(i);
    }
    let t = members
        .iter()
        .map(|m| granular_temperature(frame, m))
        .collect();
    (t, members.iter().map(Vec::len).collect())
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
}

impl Observer for TemperatureObserver {
    fn observe(&mut self, frame: &Frame, in_window: bool) {
        let all: Vec<usize> = (0..frame.len()).collect();
        let t = granular_temperature(frame, &all).unwrap_or(0.0) / self.unit;
        self.series.push((frame.time, t));
        if in_window {
            self.window_sum += t;
            self.window_samples += 1;
        }
    }
}
