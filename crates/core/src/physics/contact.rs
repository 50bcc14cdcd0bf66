//! Hard-core collisions with restitution (docs/model.md 2.1, Eqs. 2.2-2.6) and wall reflection.

/// Outgoing normal speed of a collision with incoming normal speed `u_in > 0` and coefficient
/// `e` (particle-particle `eps` or particle-wall `e_w`), including the collapse remedies of the
/// event-driven engine (docs/model.md 2.1, documented in docs/model-choices.md):
///
/// - TC model (Luding & McNamara 1998): if either partner collided less than `tc` ago, the
///   collision is elastic;
/// - rebound floor: restitution never slows a separation below `min_rebound`, and collisions
///   slower than that are elastic: `u_out = max(e u_in, min(u_in, min_rebound))`. Never
///   super-elastic. It stops inelastic collapse (relative speeds cannot shrink geometrically to
///   zero); the energy it keeps compared with plain restitution is booked separately.
///
/// Elastic coefficients (`e = 1`) bypass both remedies.
#[inline]
pub(crate) fn rebound_speed(u_in: f64, e: f64, since_last: f64, tc: f64, min_rebound: f64) -> f64 {
    if e >= 1.0 || since_last < tc {
        u_in
    } else {
        (e * u_in).max(u_in.min(min_rebound))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn remedies() {
        // Plain restitution far from both remedies.
        assert_eq!(rebound_speed(1.0, 0.8, 1.0, 1e-5, 1e-3), 0.8);
        // TC model: elastic within tc of the previous collision.
        assert_eq!(rebound_speed(1.0, 0.8, 1e-6, 1e-5, 1e-3), 1.0);
        // Rebound floor: slower collisions are elastic, faster ones keep at least the floor,
        // and nothing is super-elastic.
        assert_eq!(rebound_speed(1e-4, 0.8, 1.0, 0.0, 1e-3), 1e-4);
        assert_eq!(rebound_speed(1e-4, 0.0, 1.0, 0.0, 1e-3), 1e-4);
        assert_eq!(rebound_speed(1.1e-3, 0.5, 1.0, 0.0, 1e-3), 1e-3);
        assert_eq!(rebound_speed(1.1e-3, 0.0, 1.0, 0.0, 1e-3), 1e-3);
        for u in [1e-5, 1e-3, 0.1, 3.0] {
            assert!(rebound_speed(u, 0.3, 1.0, 0.0, 1e-3) <= u);
        }
        // Elastic bypasses the floor (no energy injected into elastic systems).
        assert_eq!(rebound_speed(1e-4, 1.0, 1.0, 0.0, 1e-3), 1e-4);
    }
}
