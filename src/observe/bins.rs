//! Lateral bins: slabs of equal width along `x` that tile the (periodic) lateral axis. Every
//! profile observer bins by `x` only, in 2D and in 3D (a 3D slab spans the whole `y` depth).

use crate::sim::Frame;

/// `n` bins of width `L_x / n` over `[0, L_x)`.
#[derive(Debug, Clone, PartialEq)]
pub struct LateralBins {
    pub n: usize,
    pub width: f64,
    pub length: f64,
}

impl LateralBins {
    /// `n` equal bins over `[0, length)`.
    pub fn new(n: usize, length: f64) -> Self {
        assert!(
            n >= 1 && length > 0.0,
            "at least one bin over a positive length"
        );
        Self {
            n,
            width: length / n as f64,
            length,
        }
    }

    /// The bin of lateral coordinate `x` (wrapped into `[0, L_x)` first).
    pub fn of(&self, x: f64) -> usize {
        let w = x.rem_euclid(self.length);
        ((w / self.width) as usize).min(self.n - 1)
    }

    /// Bin centres.
    pub fn centres(&self) -> Vec<f64> {
        (0..self.n).map(|b| (b as f64 + 0.5) * self.width).collect()
    }

    /// Lateral measure of one bin: its width in 2D, width times `L_y` in 3D.
    pub fn lateral_measure(&self, frame: &Frame) -> f64 {
        let mut m = self.width;
        for k in 1..frame.dimension - 1 {
            m *= frame.box_size[k];
        }
        m
    }

    /// Bin of the midpoint of the pair `(i, j)` (nearest periodic image of `j` seen from `i`).
    pub fn of_pair(&self, frame: &Frame, i: usize, j: usize) -> usize {
        let (xi, xj) = (frame.x(i)[0], frame.x(j)[0]);
        self.of(xi + 0.5 * frame.min_image(0, xj - xi))
    }
}
