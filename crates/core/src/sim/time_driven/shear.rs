//! The continuous Kolmogorov shear force of the time-driven engine (docs/model.md 4.2, Eq. 2.20):
//! `F_s(x) = F_max cos(2 pi x / L_x)` along `y`, the same on every particle (equal masses).
//! The event-driven engine uses the slab-constant version of the same field
//! (`sim::event_driven::shear`); this one is what the slabs approximate.

use super::BodyForce;
use crate::scene::Scene;

/// `F_max cos(2 pi x / L_x)` along `y` (axis 1) of a 3D box.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CosineShear {
    /// Peak force `F_max`.
    pub f_max: f64,
    /// Wave number `2 pi / L_x`.
    pub(crate) wave_number: f64,
}

impl CosineShear {
    /// The field of a scene with `drive.kind = "shear"` (`None` otherwise).
    pub fn of_scene(scene: &Scene) -> Option<Self> {
        let slabs = scene.shear_slabs()?;
        Some(Self {
            f_max: slabs.f_max,
            wave_number: 2.0 * std::f64::consts::PI / scene.container.size[0],
        })
    }
}

impl BodyForce<3> for CosineShear {
    const ACTIVE: bool = true;
    /// Eq. 2.20: `(0, F_max cos(k x), 0)`, periodic in `x` with period `L_x`, so wrapped and
    /// unwrapped positions give the same force.
    #[inline]
    fn force(&self, x: &[f64; 3], _t: f64) -> [f64; 3] {
        [0.0, self.f_max * (self.wave_number * x[0]).cos(), 0.0]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cosine_field_has_its_extrema_and_zeros_where_eq_2_20_puts_them() {
        let s = CosineShear {
            f_max: 0.5,
            wave_number: 2.0 * std::f64::consts::PI / 60.0,
        };
        let f = |x: f64| s.force(&[x, 3.0, 1.0], 0.0);
        assert_eq!(f(0.0), [0.0, 0.5, 0.0]);
        assert!((f(30.0)[1] + 0.5).abs() < 1e-15);
        assert!(f(15.0)[1].abs() < 1e-15 && f(45.0)[1].abs() < 1e-14);
        // Periodic in L_x.
        assert!((f(7.0)[1] - f(67.0)[1]).abs() < 1e-14);
    }
}
