//! The damping constants `A_d` of the time-driven engine (docs/model.md 2.2, Eq. 2.7), given directly
//! (`contact.damping`, `contact.wall_damping`) or derived from a coefficient of restitution
//! (`contact.restitution`, `contact.wall_restitution`), so that a sweep file switches engines by
//! `engine.kind` alone and the scene keeps its phases (docs/model-choices.md, "Engines like for
//! like"; docs/accuracy.md has the evidence).
//!
//! The damped Hertz contact has no constant restitution. Scaling the two-body equation
//! `mu xi'' = -k sqrt(R_eff) (xi^(3/2) + A_d sqrt(xi) xi')` by the elastic overlap
//! `xi_0 = (mu v^2 / (k sqrt(R_eff)))^(2/5)` and the time `xi_0 / v` leaves one parameter,
//! `beta = A_d (k sqrt(R_eff) / mu)^(2/5) v^(1/5)`: the restitution is a function `e(beta)` only,
//! `1 - c beta + ...`, and falls with the impact speed as `1 - c' v^(1/5)`. One `A_d` cannot give a
//! constant `eps` at every speed; it is chosen once, at scene start, in one of two ways:
//!
//! - **`"auto"` (default): the Maxwellian mean energy loss.** In a gas at granular temperature
//!   `T` the impact speeds are distributed as `p(v) ∝ v exp(-mu v^2 / 2T)` (collision rate
//!   proportional to the approach speed), a collision removes `(1/2) mu v^2 (1 - e(v)^2)`
//!   (docs/model.md 2.1: `E_normal (1 - eps^2)`), so the rate of collisional loss is proportional to
//!   `∫ v^3 exp(-mu v^2 / 2T) (1 - e(v)^2) dv`. `A_d` is chosen so that this equals the hard-sphere
//!   value with `e = eps` (`physics::hertz::maxwellian_loss`, `damping_for_maxwellian_restitution`):
//!
//!   ```text
//!   ∫_0^∞ x e^(-x) (1 - e(sqrt(2 T x / mu))^2) dx = 1 - eps^2,    x = mu v^2 / (2 T)
//!   ```
//!
//!   A gas at `T` then cools by collisions at the hard-sphere rate. `T` is
//!   `contact.restitution_temperature` or [`characteristic_temperature`] (the initial
//!   temperature of a hot start: chosen by measurement, docs/model-choices.md).
//! - **`contact.restitution_speed = v`: one impact speed.** `e(v) = eps` exactly
//!   (`physics::hertz::damping_for_restitution`).
//!
//! Both by bisection on direct RK4 integrations of head-on collisions: particle pairs with two
//! mean-size particles (`R_eff = d/4`, reduced mass `m/2`), the wall with one (`R_eff = d/2`,
//! mass `m` against an infinitely heavy wall, the same `T`). A restitution of 1 gives `A_d = 0`
//! (the elastic walls of docs/model.md 1 stay undamped whatever the calibration).

use super::{AutoWord, DEFAULT_STIFFNESS, DriveKind, RestitutionSpeed, Scene, StartMode};
use crate::physics::hertz;

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
/// the initial temperature `T_0` of a hot start (`initial.temperature` or
/// `temperature_over_ecb * E_cb`). Measured on the 2D standard wet system (docs/accuracy.md,
/// "Engines like for like"), this keeps the phases and `T_g / E_cb` within 3.4 % at a gas, a
/// fluid and a coexistence (eps = 0.96; their stationary temperatures are 1.6 to 16 times lower
/// than `T_0`). Calibrating at the event run's own stationary temperature instead left the
/// time-driven fluid of eps = 0.9 27 % cooler (the one at `T_0`: 11 %): the wet, shaken beds
/// evidently collide faster than a Maxwellian at their mean temperature; the loss depends on
/// `T` only as `T^(1/10)`.
///
/// A scene without a hot-start temperature (cold start, or none given) takes the scale of its
/// drive: `m (A omega)^2` for shaking (docs/model.md 4.1), `F_max d` for shear (docs/model.md 4.2), else
/// `m g d` (`g = 1` without gravity). These fallbacks are not measured.
pub(crate) fn characteristic_temperature(scene: &Scene) -> f64 {
    let t0 = scene.initial_temperature();
    // A member of a continuation chain (`"continue"`) is calibrated as its point would be with a
    // hot start, as the chain's first job usually is: the contact law must be the same for every
    // job of the chain, so none of them may fall back to the drive's scale.
    if matches!(scene.initial.start, StartMode::Hot | StartMode::Continue) && t0 > 0.0 {
        return t0;
    }
    let m = scene.particles.mass;
    let d = scene.particles.diameter;
    if let Some((a, w)) = scene.drive_motion()
        && a * w > 0.0
    {
        return m * (a * w).powi(2);
    }
    if let Some(f) = scene.drive.f_max
        && scene.drive.kind == DriveKind::Shear
        && f > 0.0
    {
        return f * d;
    }
    let g = if scene.gravity > 0.0 {
        scene.gravity
    } else {
        1.0
    };
    m * g * d
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

    #[test]
    fn characteristic_temperature_of_hot_and_cold_starts() {
        // Hot start: the initial temperature (here 1 m g d... gravity 0: absolute units).
        assert_eq!(characteristic_temperature(&scene("restitution = 0.9")), 1.0);
        let shaken = |start: &str| {
            Scene::from_toml_str(
                &format!(
                    "dimension = 2\n[box]\nsize = [14.0, 9.0]\n[particles]\ncount = 10\n\
                     [contact]\nrestitution = 0.9\n[capillary]\nmodel = \"thin_thread\"\n\
                     [drive]\nkind = \"sine\"\ngamma = 2.0\ne_star = 3.0\n[engine]\nkind = \"time\"\n\
                     [initial]\ntemperature_over_ecb = 20.0\nstart = \"{start}\"\n[run]\nduration = 1.0\n"
                ),
                "test",
            )
            .unwrap_or_else(|e| panic!("{e}"))
        };
        let hot = shaken("hot");
        assert!((characteristic_temperature(&hot) - 20.0 * hot.e_cb()).abs() < 1e-12);
        // Cold start: m v_w^2 = 2 E* E_cb (docs/model.md 4.1).
        let cold = shaken("cold");
        let want = 2.0 * 3.0 * cold.e_cb();
        assert!((characteristic_temperature(&cold) - want).abs() < 1e-9 * want);
    }
}
