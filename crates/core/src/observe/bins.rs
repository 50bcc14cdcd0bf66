//! Lateral bins: cells of equal size that tile the lateral extent of the box. In 2D they are
//! slabs along `x` (the only lateral axis). In 3D they are, by default, square cells over the
//! lateral plane `(x, y)` (`observe.bins_3d = "plane"`), so that a drop- or strip-shaped region
//! is resolved in both lateral directions; `observe.bins_3d = "x_slabs"` keeps slabs along `x`
//! that span the whole depth `L_y` (for comparison with results binned that way).
//! Bins are numbered `ix + nx * iy`.

use crate::sim::Frame;

pub use crate::scene::observe_section::Bins3d;
use crate::scene::{ObserveSpec, Scene};

impl ObserveSpec {
    /// The lateral bins of a scene: `max(1, round(L_x / bin_width))` slabs along `x` in 2D; in
    /// 3D square-ish cells of `bin_width` over `(x, y)` (each axis rounded to a whole number of
    /// cells), or x-slabs with `bins_3d = "x_slabs"`.
    pub fn lateral_bins(&self, scene: &Scene) -> LateralBins {
        let lx = scene.container.size[0];
        let nx = ((lx / self.bin_width).round() as usize).max(1);
        if scene.dimension == 3 && self.bins_3d == Bins3d::Plane {
            let ly = scene.container.size[1];
            let ny = ((ly / self.bin_width).round() as usize).max(1);
            LateralBins::grid(nx, lx, ny, ly)
        } else {
            LateralBins::new(nx, lx)
        }
    }
}

/// `nx * ny` bins of size `width[0] x width[1]` over `[0, L_x) x [0, L_y)` (`ny = 1`,
/// `width[1] = 1` in 2D, where the lateral extent is `L_x` alone).
#[derive(Debug, Clone, PartialEq)]
pub struct LateralBins {
    /// Total number of bins, `nx * ny`.
    pub n: usize,
    pub nx: usize,
    pub ny: usize,
    /// Width along `x` (kept as `width` for the 2D callers).
    pub width: f64,
    pub(crate) width_y: f64,
    pub length: f64,
    pub(crate) length_y: f64,
}

impl LateralBins {
    /// `n` equal slabs over `[0, length)` along `x` (2D, or 3D x-slabs).
    pub fn new(n: usize, length: f64) -> Self {
        Self::grid(n, length, 1, 1.0)
    }

    /// `nx` by `ny` equal cells over `[0, length) x [0, length_y)`.
    pub fn grid(nx: usize, length: f64, ny: usize, length_y: f64) -> Self {
        assert!(
            nx >= 1 && ny >= 1 && length > 0.0 && length_y > 0.0,
            "at least one bin over a positive length"
        );
        Self {
            n: nx * ny,
            nx,
            ny,
            width: length / nx as f64,
            width_y: length_y / ny as f64,
            length,
            length_y,
        }
    }

    /// Whether the bins cut the `y` axis too (3D plane bins).
    pub(crate) fn is_plane(&self) -> bool {
        self.ny > 1
    }

    /// Index along one axis of a coordinate (wrapped into `[0, L)` first).
    fn index(x: f64, length: f64, width: f64, n: usize) -> usize {
        let w = x.rem_euclid(length);
        ((w / width) as usize).min(n - 1)
    }

    /// The bin of lateral coordinate `x` (slabs; the `y` index is 0).
    pub fn of(&self, x: f64) -> usize {
        Self::index(x, self.length, self.width, self.nx)
    }

    /// The bin of the lateral point `(x, y)` (`y` ignored for slabs).
    pub(crate) fn of_xy(&self, x: f64, y: f64) -> usize {
        let ix = self.of(x);
        if self.ny == 1 {
            return ix;
        }
        ix + self.nx * Self::index(y, self.length_y, self.width_y, self.ny)
    }

    /// The bin of particle `i` of a frame.
    pub(crate) fn of_particle(&self, frame: &Frame, i: usize) -> usize {
        let x = frame.x(i);
        if frame.dimension == 3 {
            self.of_xy(x[0], x[1])
        } else {
            self.of(x[0])
        }
    }

    /// Bin `x` centres, one per bin (in bin order).
    pub fn centres(&self) -> Vec<f64> {
        (0..self.n)
            .map(|b| ((b % self.nx) as f64 + 0.5) * self.width)
            .collect()
    }

    /// Bin `y` centres, one per bin (`None` for slabs).
    pub fn centres_y(&self) -> Option<Vec<f64>> {
        self.is_plane().then(|| {
            (0..self.n)
                .map(|b| ((b / self.nx) as f64 + 0.5) * self.width_y)
                .collect()
        })
    }

    /// Volume (area in 2D) of one bin in a box of edges `size` (height last): its lateral
    /// measure (width in 2D; width times `L_y` for 3D slabs; the cell's area for 3D plane bins)
    /// times the height.
    pub(crate) fn bin_volume(&self, size: &[f64]) -> f64 {
        let lateral = if size.len() == 2 {
            self.width
        } else if self.is_plane() {
            self.width * self.width_y
        } else {
            self.width * size[1]
        };
        lateral * size[size.len() - 1]
    }

    /// Bin of the midpoint of the pair `(i, j)` (nearest periodic image of `j` seen from `i`).
    pub(crate) fn of_pair(&self, frame: &Frame, i: usize, j: usize) -> usize {
        let (xi, xj) = (frame.x(i), frame.x(j));
        let mx = xi[0] + 0.5 * frame.min_image(0, xj[0] - xi[0]);
        if frame.dimension == 3 && self.is_plane() {
            let my = xi[1] + 0.5 * frame.min_image(1, xj[1] - xi[1]);
            self.of_xy(mx, my)
        } else {
            self.of(mx)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plane_bins_number_x_fastest_and_wrap() {
        let b = LateralBins::grid(4, 8.0, 3, 6.0);
        assert_eq!(b.n, 12);
        assert_eq!(b.of_xy(0.5, 0.5), 0);
        assert_eq!(b.of_xy(2.5, 0.5), 1);
        assert_eq!(b.of_xy(0.5, 2.5), 4);
        assert_eq!(b.of_xy(7.9, 5.9), 11);
        assert_eq!(b.of_xy(-0.1, -0.1), 11);
        assert_eq!(b.centres()[5], 3.0);
        assert_eq!(b.centres_y().unwrap()[5], 3.0);
    }

    #[test]
    fn slabs_ignore_y() {
        let b = LateralBins::new(4, 8.0);
        assert!(!b.is_plane());
        assert_eq!(b.of_xy(2.5, 100.0), 1);
        assert!(b.centres_y().is_none());
    }
}
