//! Hertz contact with damping (MODEL.md 2.2, Eq. 2.7) and the minimal capillary force
//! (MODEL.md 3.1), as pure functions, plus two reference results the time-driven engine is tested
//! against: the analytic contact time of an elastic Hertz collision and the restitution of a
//! damped one by direct integration of the two-body equation.
//!
//! Eq. 2.7 with the corrected effective radius:
//!
//! ```text
//! F = k sqrt(R_eff) (xi^(3/2) + A_d sqrt(xi) dxi/dt),   k = 2 Y / (3 (1 - nu^2)),
//! R_eff = R_i R_j / (R_i + R_j)   (a wall: R_eff = R_i)
//! ```
//!
//! `xi = R_i + R_j - r_ij` is the overlap. `k` is the scene's `contact.stiffness`, `A_d` its
//! `contact.damping`. A pull (negative total force) is cut to zero: a damped contact never
//! attracts (the usual remedy, Pöschel & Schwager 2005, Sec. 2.1).

/// Effective radius of two spheres (corrected form of the text's Eq. 2.7):
/// `R_eff = R_i R_j / (R_i + R_j)`.
#[inline]
pub fn effective_radius(r_i: f64, r_j: f64) -> f64 {
    r_i * r_j / (r_i + r_j)
}

/// Normal repulsion of Eq. 2.7 for overlap `xi > 0` and overlap rate `xi_dot`, given the
/// combined prefactor `kr = k sqrt(R_eff)` and damping `a_d`. Never negative.
#[inline]
pub fn force(kr: f64, xi: f64, xi_dot: f64, a_d: f64) -> f64 {
    let sq = xi.sqrt();
    (kr * sq * (xi + a_d * xi_dot)).max(0.0)
}

/// Elastic energy stored in a Hertz contact, `(2/5) k sqrt(R_eff) xi^(5/2)`
/// (the integral of the elastic part of Eq. 2.7).
#[inline]
pub fn elastic_energy(kr: f64, xi: f64) -> f64 {
    0.4 * kr * xi * xi * xi.sqrt()
}

/// Largest overlap of an elastic head-on collision of reduced mass `mu` approaching at `v`:
/// `mu v^2 / 2 = (2/5) kr xi_max^(5/2)`.
pub fn max_overlap(kr: f64, mu: f64, v: f64) -> f64 {
    (1.25 * mu * v * v / kr).powf(0.4)
}

/// Duration of an elastic Hertz collision (analytic):
/// `t_c = 2 (xi_max / v) int_0^1 du / sqrt(1 - u^(5/2)) = (xi_max / v) (4/5) B(2/5, 1/2)`,
/// `B(2/5, 1/2) = Gamma(2/5) Gamma(1/2) / Gamma(9/10)`, so `t_c = 2.943 xi_max / v`.
pub fn contact_time(kr: f64, mu: f64, v: f64) -> f64 {
    // Gamma(0.4), Gamma(0.5) = sqrt(pi), Gamma(0.9) (Abramowitz & Stegun Table 6.1).
    const G04: f64 = 2.218_159_543_757_688;
    const G09: f64 = 1.068_628_702_119_319_4;
    let beta = G04 * std::f64::consts::PI.sqrt() / G09;
    0.8 * beta * max_overlap(kr, mu, v) / v
}

/// Outcome of a head-on collision integrated directly (see [`direct_collision`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Collision {
    /// Outgoing over incoming normal speed.
    pub restitution: f64,
    /// Time from first touch to separation.
    pub duration: f64,
    /// Largest overlap.
    pub max_overlap: f64,
}

/// Head-on collision of reduced mass `mu` approaching at `v`, integrated with classical RK4 of
/// step `h` on `mu xi'' = -F(xi, xi')` from `xi = 0, xi' = v` until `xi` returns to 0 (the last
/// step is cut at the root by linear interpolation). Independent of the engine's integrators;
/// used to choose `A_d` for a wanted restitution and to test the engine.
pub fn direct_collision(kr: f64, a_d: f64, mu: f64, v: f64, h: f64) -> Collision {
    let acc = |xi: f64, u: f64| {
        if xi > 0.0 {
            -force(kr, xi, u, a_d) / mu
        } else {
            0.0
        }
    };
    let (mut xi, mut u, mut t, mut xi_max) = (0.0f64, v, 0.0f64, 0.0f64);
    loop {
        let (k1x, k1u) = (u, acc(xi, u));
        let (k2x, k2u) = (
            u + 0.5 * h * k1u,
            acc(xi + 0.5 * h * k1x, u + 0.5 * h * k1u),
        );
        let (k3x, k3u) = (
            u + 0.5 * h * k2u,
            acc(xi + 0.5 * h * k2x, u + 0.5 * h * k2u),
        );
        let (k4x, k4u) = (u + h * k3u, acc(xi + h * k3x, u + h * k3u));
        let xi1 = xi + h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x);
        let u1 = u + h / 6.0 * (k1u + 2.0 * k2u + 2.0 * k3u + k4u);
        if xi1 <= 0.0 && t > 0.0 {
            let f = xi / (xi - xi1);
            return Collision {
                restitution: -(u + f * (u1 - u)) / v,
                duration: t + f * h,
                max_overlap: xi_max,
            };
        }
        xi = xi1;
        u = u1;
        t += h;
        xi_max = xi_max.max(xi);
    }
}

/// The damping `A_d` that gives restitution `e` (in (0, 1)) at approach speed `v`, by bisection
/// on [`direct_collision`] (restitution falls monotonically with `A_d`).
pub fn damping_for_restitution(kr: f64, mu: f64, v: f64, e: f64) -> f64 {
    let h = contact_time(kr, mu, v) / 4000.0;
    let (mut lo, mut hi) = (0.0f64, 1e-2f64);
    while direct_collision(kr, hi, mu, v, h).restitution > e {
        hi *= 2.0;
    }
    for _ in 0..50 {
        let mid = 0.5 * (lo + hi);
        if direct_collision(kr, mid, mu, v, h).restitution > e {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// Minimal capillary model (MODEL.md 3.1): the constant attraction `F_B = E_cb / s_crit` that
/// acts along the line of centres while a bridge exists (`s <= s_crit`, also during overlap).
#[inline]
pub fn bridge_force(e_cb: f64, s_crit: f64) -> f64 {
    e_cb / s_crit
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn effective_radius_is_the_corrected_form() {
        // Equal spheres of radius 1/2: R_eff = 1/4 (the printed form would give 4).
        assert!((effective_radius(0.5, 0.5) - 0.25).abs() < 1e-15);
        assert!((effective_radius(1.0, 3.0) - 0.75).abs() < 1e-15);
    }

    #[test]
    fn elastic_direct_collision_matches_the_analytic_contact_time() {
        let (kr, mu, v) = (1e6, 0.5, 1.3);
        let c = direct_collision(kr, 0.0, mu, v, contact_time(kr, mu, v) / 20000.0);
        assert!((c.restitution - 1.0).abs() < 1e-6, "{c:?}");
        let rel = (c.duration / contact_time(kr, mu, v) - 1.0).abs();
        assert!(rel < 1e-4, "duration {c:?} vs {}", contact_time(kr, mu, v));
        assert!((c.max_overlap / max_overlap(kr, mu, v) - 1.0).abs() < 1e-6);
    }

    #[test]
    fn damping_for_restitution_inverts_direct_collision() {
        let (kr, mu, v) = (1e6, 0.5, 1.0);
        let a = damping_for_restitution(kr, mu, v, 0.9);
        let h = contact_time(kr, mu, v) / 4000.0;
        let e = direct_collision(kr, a, mu, v, h).restitution;
        assert!((e - 0.9).abs() < 1e-6, "A_d {a} gives e {e}");
        // Restitution of damped Hertz falls with impact speed (Kuwabara & Kono).
        assert!(direct_collision(kr, a, mu, 3.0, h).restitution < e);
    }
}
