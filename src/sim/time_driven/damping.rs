//! The damping constants `A_d` of the time-driven engine (MODEL.md 2.2, Eq. 2.7), given directly
//! (`contact.damping`, `contact.wall_damping`) or derived from a coefficient of restitution
//! (`contact.restitution`, `contact.wall_restitution`), by default over the impact speeds of a
//! Maxwellian gas at the scene's characteristic temperature, or at one impact speed
//! (`contact.restitution_speed`).
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
use crate::scene::{AutoWord, DEFAULT_STIFFNESS, RestitutionSpeed, Scene, StartMode};

/// How a restitution is turned into `A_d`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Calibration {
    /// Exactly the restitution at one impact speed (`contact.restitution_speed = v`).
    Speed(f64),
    /// The same mean energy loss over the impact speeds of a Maxwellian gas at this granular
    /// temperature (`"auto"`, the default; [`hertz::maxwellian_loss`]).
    Maxwellian(f64),
}

/// The calibration a scene asks for: an explicit speed wins; otherwise the Maxwellian one at
/// `contact.restitution_temperature` or, without it, at [`characteristic_temperature`].
pub fn calibration(scene: &Scene) -> Calibration {
    let c = &scene.contact;
    match c.restitution_speed {
        Some(RestitutionSpeed::Speed(v)) => Calibration::Speed(v),
        None | Some(RestitutionSpeed::Word(AutoWord::Auto)) => Calibration::Maxwellian(
            c.restitution_temperature
                .unwrap_or_else(|| characteristic_temperature(scene)),
        ),
    }
}

/// The granular temperature scale of a scene (absolute units) for the `"auto"` calibration:
/// the initial temperature of a hot start; a scene without one (cold start, zero temperature)
/// falls back to `m g d` (units of `m g d`; 1 without gravity).
pub fn characteristic_temperature(scene: &Scene) -> f64 {
    let t0 = scene.initial_temperature();
    if scene.initial.start == StartMode::Hot && t0 > 0.0 {
        return t0;
    }
    let g = if scene.gravity > 0.0 {
        scene.gravity
    } else {
        1.0
    };
    scene.particles.mass * g * scene.particles.diameter
}

/// `(A_d pairs, A_d walls)` of a scene run by the time-driven engine.
pub fn contact_damping(scene: &Scene) -> (f64, f64) {
    let c = &scene.contact;
    let k = c.stiffness.unwrap_or(DEFAULT_STIFFNESS);
    let d = scene.particles.diameter;
    let m = scene.particles.mass;
    let cal = calibration(scene);
    let from = |e: f64, r_eff: f64, mu: f64| {
        if e >= 1.0 {
            0.0
        } else {
            let kr = k * r_eff.sqrt();
            match cal {
                Calibration::Speed(v) => hertz::damping_for_restitution(kr, mu, v, e),
                Calibration::Maxwellian(t) => {
                    hertz::damping_for_maxwellian_restitution(kr, mu, t, e)
                }
            }
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

    #[test]
    fn auto_is_the_default_and_uses_the_characteristic_temperature() {
        let auto = scene("restitution = 0.9\nrestitution_speed = \"auto\"");
        let plain = scene("restitution = 0.9");
        let t = characteristic_temperature(&plain);
        assert_eq!(calibration(&plain), Calibration::Maxwellian(t));
        assert_eq!(contact_damping(&auto), contact_damping(&plain));
        let given = scene(&format!("restitution = 0.9\nrestitution_temperature = {t}"));
        assert_eq!(contact_damping(&given), contact_damping(&plain));
        // Elastic walls stay undamped; the pair damping gives the Maxwellian mean loss.
        let (pair, wall) = contact_damping(&plain);
        assert_eq!(wall, 0.0);
        let kr = DEFAULT_STIFFNESS * 0.25f64.sqrt();
        let loss = hertz::maxwellian_loss(kr, pair, 0.5, t);
        assert!((loss / (1.0 - 0.81) - 1.0).abs() < 1e-6, "{loss}");
        // A hotter calibration temperature means faster impacts, hence less damping.
        let hot = scene(&format!(
            "restitution = 0.9\nrestitution_temperature = {}",
            10.0 * t
        ));
        assert!(contact_damping(&hot).0 < pair);
    }
}
