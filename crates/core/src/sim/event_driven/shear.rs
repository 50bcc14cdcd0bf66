//! The shear drive in the event-driven engine (docs/model.md 4.2): the slabs of constant body force
//! along `y`, their faces, and the pair predictions of two particles that feel different forces.
//!
//! The force `F_max cos(2 pi x / L_x)` (Eq. 2.20) is made piecewise constant over `n` slabs of
//! width `w = L_x / n` along `x`, with the value at each slab centre. Inside a slab a particle
//! flies on a parabola along `y` (acceleration `a_k = F_k / m`); its `x` motion is force-free,
//! so slab crossings happen at linear times. Two particles in the same slab share the
//! acceleration and their relative motion is a straight line (the engine's quadratic); in
//! different slabs the relative acceleration `a_i - a_j` along `y` makes the contact condition
//! the quartic of `physics::quartic`, solved only up to the first slab exit of either particle
//! (the engine re-predicts every pair of a particle that changes slab).

use crate::physics::quartic::{Poly, contact_quartic, earliest_entry};
use crate::scene::ShearSlabs;

/// Axis of the body force (`y`).
pub(crate) const FORCE_AXIS: usize = 1;

/// The slabs of one scene: width, count and the acceleration in each.
#[derive(Debug, Clone)]
pub struct ShearField {
    width: f64,
    l_x: f64,
    accel: Vec<f64>,
}

impl ShearField {
    /// Slabs of `slabs` for particles of mass `mass` in a box of length `l_x`.
    pub fn new(slabs: &ShearSlabs, mass: f64, l_x: f64) -> Self {
        Self {
            width: slabs.width,
            l_x,
            accel: (0..slabs.count).map(|k| slabs.force(k) / mass).collect(),
        }
    }

    pub fn count(&self) -> usize {
        self.accel.len()
    }

    /// Acceleration along `y` in slab `k`.
    #[inline]
    pub(crate) fn accel(&self, k: usize) -> f64 {
        self.accel[k]
    }

    /// The slab holding `x` (positions on `[0, L_x)`; round-off outside is clamped).
    pub(crate) fn slab_of(&self, x: f64) -> usize {
        let k = (x / self.width).floor();
        (k.max(0.0) as usize).min(self.count() - 1)
    }

    /// Faces `(lo, hi)` of slab `k` in the periodic image nearest to `x` (a particle's stored
    /// `x` may already be wrapped by its cell crossing while its slab index is not yet, or the
    /// other way round: both happen at the same time at `x = 0 = L_x`).
    #[inline]
    pub fn faces(&self, k: usize, x: f64) -> (f64, f64) {
        let lo = k as f64 * self.width;
        let centre = lo + 0.5 * self.width;
        let shift = if x - centre > 0.5 * self.l_x {
            self.l_x
        } else if centre - x > 0.5 * self.l_x {
            -self.l_x
        } else {
            0.0
        };
        (lo + shift, lo + self.width + shift)
    }

    /// Neighbouring slab index (`up`: towards larger `x`), periodic.
    #[inline]
    pub fn next(&self, k: usize, up: bool) -> usize {
        let n = self.count();
        if up { (k + 1) % n } else { (k + n - 1) % n }
    }
}

/// Pair events of two particles with relative position `r`, velocity `v` and relative
/// acceleration `da` along `y` (all `i` minus `j`), within `horizon`: the contact at distance
/// `sigma` (approaching), and, for a bonded pair, the well edge at `lambda = sigma + s_crit`
/// (separating). Times are relative to now.
pub(crate) fn pair_times<const D: usize>(
    r: &[f64; D],
    v: &[f64; D],
    da: f64,
    sigma: f64,
    lambda: Option<f64>,
    horizon: f64,
) -> (Option<f64>, Option<f64>) {
    let mut a = [0.0; D];
    a[FORCE_AXIS] = da;
    let contact = earliest_entry(&contact_quartic(r, v, &a, sigma), horizon);
    let well = lambda.and_then(|l| {
        let p: Poly = contact_quartic(r, v, &a, l).negated();
        earliest_entry(&p, horizon)
    });
    (contact, well)
}
