//! Per-layer lateral mean-square displacement and diffusion coefficient (docs/model.md 7, surface
//! melting).
//!
//! At the first sample of the window the particles are sorted by height and cut into `layers`
//! groups of equal size (the lowest layers take one extra particle where `N` does not divide);
//! a particle keeps its layer for the whole window. Lateral displacements (`x` in 2D, `x, y`
//! in 3D) are unwrapped sample by sample with the nearest periodic image, so a grain must not
//! move more than half the box between two samples. `MSD_l(t)` is the mean of `|Delta r_lat|^2`
//! over layer `l` since the window start, and `D_l = slope / (2 n_lat)` (`n_lat` lateral axes),
//! the slope fitted by least squares to `MSD_l(t)` over the second half of the window (the first
//! half holds the ballistic start).

use crate::sim::Frame;
use serde::{Deserialize, Serialize};

/// One layer's result.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LayerDiffusion {
    /// Mean height of the layer's particles when the layers were assigned.
    pub mean_height: f64,
    pub particles: usize,
    /// Lateral mean-square displacement at the end of the window.
    pub msd_end: f64,
    /// Lateral diffusion coefficient `D = slope / (2 n_lat)`.
    pub coefficient: f64,
}

/// The per-layer results, bottom layer first.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Diffusion {
    pub layers: Vec<LayerDiffusion>,
    /// Times since the window start at which the MSD was sampled.
    pub times: Vec<f64>,
    /// `msd[l][k]`: MSD of layer `l` at `times[k]`.
    pub(crate) msd: Vec<Vec<f64>>,
}

/// Layer of every particle: ranks by height, `layers` groups of equal size.
pub(crate) fn assign_layers(frame: &Frame, layers: usize) -> Vec<usize> {
    let n = frame.len();
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| frame.height(a).total_cmp(&frame.height(b)).then(a.cmp(&b)));
    let mut layer = vec![0; n];
    let (base, extra) = (n / layers, n % layers);
    let mut start = 0;
    for l in 0..layers {
        let size = base + usize::from(l < extra);
        for &i in &order[start..start + size] {
            layer[i] = l;
        }
        start += size;
    }
    layer
}

/// Least-squares slope of `y` against `x` (0 for fewer than two points).
pub(crate) fn slope(x: &[f64], y: &[f64]) -> f64 {
    let n = x.len() as f64;
    if x.len() < 2 {
        return 0.0;
    }
    let mx = x.iter().sum::<f64>() / n;
    let my = y.iter().sum::<f64>() / n;
    let sxy: f64 = x.iter().zip(y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: f64 = x.iter().map(|a| (a - mx) * (a - mx)).sum();
    if sxx > 0.0 { sxy / sxx } else { 0.0 }
}

/// Tracks unwrapped lateral displacements per layer over the window.
#[derive(Debug, Clone)]
pub(crate) struct DiffusionObserver {
    layers: usize,
    layer_of: Vec<usize>,
    layer_size: Vec<usize>,
    mean_height: Vec<f64>,
    last: Vec<f64>,
    disp: Vec<f64>,
    t0: f64,
    times: Vec<f64>,
    msd: Vec<Vec<f64>>,
}

impl DiffusionObserver {
    pub(crate) fn new(layers: usize) -> Self {
        Self {
            layers,
            layer_of: Vec::new(),
            layer_size: Vec::new(),
            mean_height: Vec::new(),
            last: Vec::new(),
            disp: Vec::new(),
            t0: 0.0,
            times: Vec::new(),
            msd: vec![Vec::new(); layers],
        }
    }

    /// The per-layer results (`None` before the window's first sample).
    pub(crate) fn finish(&self, dimension: usize) -> Option<Diffusion> {
        if self.layer_of.is_empty() {
            return None;
        }
        let n_lat = (dimension - 1) as f64;
        let half = self.times.len() / 2;
        let layers = (0..self.layers)
            .map(|l| LayerDiffusion {
                mean_height: self.mean_height[l],
                particles: self.layer_size[l],
                msd_end: *self.msd[l].last().unwrap_or(&0.0),
                coefficient: slope(&self.times[half..], &self.msd[l][half..]) / (2.0 * n_lat),
            })
            .collect();
        Some(Diffusion {
            layers,
            times: self.times.clone(),
            msd: self.msd.clone(),
        })
    }

    /// Books one sample; `in_window`: whether its time lies in the stationary window.
    pub(crate) fn observe(&mut self, frame: &Frame, in_window: bool) {
        if !in_window {
            return;
        }
        let d = frame.dimension;
        let n_lat = d - 1;
        if self.layer_of.is_empty() {
            self.layer_of = assign_layers(frame, self.layers);
            self.layer_size = vec![0; self.layers];
            self.mean_height = vec![0.0; self.layers];
            for i in 0..frame.len() {
                self.layer_size[self.layer_of[i]] += 1;
                self.mean_height[self.layer_of[i]] += frame.height(i);
            }
            for l in 0..self.layers {
                self.mean_height[l] /= self.layer_size[l].max(1) as f64;
            }
            self.last = (0..frame.len())
                .flat_map(|i| frame.x(i)[..n_lat].to_vec())
                .collect();
            self.disp = vec![0.0; frame.len() * n_lat];
            self.t0 = frame.time;
        } else {
            for i in 0..frame.len() {
                for k in 0..n_lat {
                    let x = frame.x(i)[k];
                    self.disp[i * n_lat + k] += frame.min_image(k, x - self.last[i * n_lat + k]);
                    self.last[i * n_lat + k] = x;
                }
            }
        }
        let mut sum = vec![0.0; self.layers];
        for i in 0..frame.len() {
            let r2: f64 = self.disp[i * n_lat..(i + 1) * n_lat]
                .iter()
                .map(|x| x * x)
                .sum();
            sum[self.layer_of[i]] += r2;
        }
        self.times.push(frame.time - self.t0);
        for l in 0..self.layers {
            self.msd[l].push(sum[l] / self.layer_size[l].max(1) as f64);
        }
    }
}
