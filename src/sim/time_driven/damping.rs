//! The damping constants `A_d` of the time-driven engine (MODEL.md 2.2, Eq. 2.7), given directly
//! (`contact.damping`, `contact.wall_damping`) or derived from a coefficient of restitution
//! (`contact.restitution`, `contact.wall_restitution`) at a reference impact speed
//! (`contact.restitution_speed`, default [`DEFAULT_RESTITUTION_SPEED`]).
//!
//! The damped Hertz contact has no constant restitution: it falls with the impact speed, about
//! `1 - c v^(1/5)`. A restitution `e` is therefore converted once, at scene start, into the `A_d`
//! that gives exactly `e` for a head-on collision at the reference speed, by bisection on a
//! direct RK4 integration of that collision (`physics::hertz::damping_for_restitution`):
//! particle pairs with two mean-size particles (`R_eff = d/4`, reduced mass `m/2`), the wall with
//! one (`R_eff = d/2`, mass `m` against an infinitely heavy wall). This lets a sweep file switch
//! between engines with `engine.kind` alone; the speed dependence is the physical difference
//! between the two contact laws (docs/model-choices.md).

use crate::physics::hertz;
use crate::scene::{DEFAULT_STIFFNESS, Scene};

/// Reference impact speed of a restitution given to the time-driven engine, units of
/// `sqrt(g d)`.
pub const DEFAULT_RESTITUTION_SPEED: f64 = 1.0;

/// `(A_d pairs, A_d walls)` of a scene run by the time-driven engine.
pub fn contact_damping(scene: &Scene) -> (f64, f64) {
    let c = &scene.contact;
    let k = c.stiffness.unwrap_or(DEFAULT_STIFFNESS);
    let d = scene.particles.diameter;
    let m = scene.particles.mass;
    let v = c.restitution_speed.unwrap_or(DEFAULT_RESTITUTION_SPEED);
    let from = |e: f64, r_eff: f64, mu: f64| {
        if e >= 1.0 {
            0.0
        } else {
            hertz::damping_for_restitution(k * r_eff.sqrt(), mu, v, e)
        }
    };
    let pair = c
        .damping
        .unwrap_or_else(|| from(c.restitution, 0.25 * d, 0.5 * m));
    let wall = c
        .wall_damping
        .unwrap_or_else(|| from(c.wall_restitution, 0.5 * d, m));
    (pair, wall)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scene(contact: &str) -> Scene {
        Scene::from_toml_str(
            &format!(
                "dimension = 2\ngravity = 0.0\n[box]\nsize = [14.0, 14.0]\nboundary = [\"periodic\", \"wall\"]\n\
                 [particles]\ncount = 10\n[contact]\n{contact}\n[engine]\nkind = \"time\"\n\
                 [initial]\ntemperature = 1.0\nseed = 1\n[run]\nduration = 1.0\n"
            ),
            "test",
        )
        .unwrap_or_else(|e| panic!("{e}"))
    }

    #[test]
    fn restitution_gives_that_restitution_at_the_reference_speed() {
        for (e, v) in [(0.9, 1.0), (0.8, 2.5)] {
            let s = scene(&format!(
                "restitution = {e}\nwall_restitution = {e}\nrestitution_speed = {v}"
            ));
            let (pair, wall) = contact_damping(&s);
            assert!(pair > 0.0 && wall > 0.0);
            // An independent check of the bisection: integrate the collision with the result.
            for (a_d, r_eff, mu) in [(pair, 0.25, 0.5), (wall, 0.5, 1.0)] {
                let kr = DEFAULT_STIFFNESS * f64::sqrt(r_eff);
                let h = hertz::contact_time(kr, mu, v) / 8000.0;
                let got = hertz::direct_collision(kr, a_d, mu, v, h).restitution;
                assert!((got - e).abs() < 1e-4, "e = {e}, v = {v}: got {got}");
            }
        }
    }

    #[test]
    fn elastic_by_default_and_explicit_damping_wins() {
        assert_eq!(contact_damping(&scene("")), (0.0, 0.0));
        assert_eq!(
            contact_damping(&scene("damping = 2e-4\nwall_damping = 1e-4")),
            (2e-4, 1e-4)
        );
    }
}
