//! Validation of the engine kind: keys that belong to one engine only are rejected with the
//! other, and the time-driven engine's restitution, damping, time step and Verlet cells are
//! range-checked (docs/model-choices.md, "Time-driven engine").

use super::drive::table_keys_given;
use super::{Check, Constraint, SceneError, num};
use crate::scene::{self, Boundary, Scene};

impl Scene {
    /// Keys that belong to one engine only are rejected with the other, and the time-driven
    /// knobs are range-checked (docs/model-choices.md, "Time-driven engine"). Event-engine keys
    /// with plain-number defaults count as set when they differ from their default.
    pub(super) fn validate_engine_kind(&self, c: &Check<'_>) -> Result<(), SceneError> {
        match self.engine.kind {
            scene::EngineKind::Event => self.reject_time_keys(c),
            scene::EngineKind::Time => {
                self.reject_event_keys(c)?;
                self.validate_time_contact(c)?;
                self.validate_time_numbers(c)?;
                self.validate_verlet_cells(c)
            }
        }
    }

    /// With the event engine: no key of the time-driven engine.
    fn reject_time_keys(&self, c: &Check<'_>) -> Result<(), SceneError> {
        let e = &self.engine;
        let ct = &self.contact;
        let time_only = [
            ("engine.dt", e.dt.is_some()),
            ("engine.integrator", e.integrator.is_some()),
            ("engine.skin", e.skin.is_some()),
            ("contact.stiffness", ct.stiffness.is_some()),
            ("contact.damping", ct.damping.is_some()),
            ("contact.wall_damping", ct.wall_damping.is_some()),
            ("contact.restitution_speed", ct.restitution_speed.is_some()),
            (
                "contact.restitution_temperature",
                ct.restitution_temperature.is_some(),
            ),
        ];
        c.none_given(
            &time_only,
            "belongs to the time-driven engine: set engine.kind = \"time\" or remove the key",
        )
    }

    /// With the time-driven engine: no key of the event engine (those with plain-number
    /// defaults count as set when they differ from their default).
    fn reject_event_keys(&self, c: &Check<'_>) -> Result<(), SceneError> {
        let (e, d) = (&self.engine, &self.drive);
        let default = scene::EngineSpec::default();
        let event_only = [
            ("engine.tc", e.tc != default.tc),
            (
                "engine.min_rebound_speed",
                e.min_rebound_speed != default.min_rebound_speed,
            ),
            (
                "engine.overlap_tolerance",
                e.overlap_tolerance != default.overlap_tolerance,
            ),
            ("engine.cell_size", e.cell_size != 0.0),
            (
                "capillary.rupture_rule",
                self.capillary.rupture_rule.is_some(),
            ),
            (
                "drive.wall_solver",
                d.wall_solver != scene::WallSolverKind::Exact,
            ),
            ("drive.root_tolerance", d.root_tolerance.is_some()),
            ("drive.t_min", d.t_min.is_some()),
            ("drive.slab_width", d.slab_width.is_some()),
            ("run.max_events", self.run.max_events.is_some()),
        ];
        c.none_given(
            event_only.iter().chain(&table_keys_given(d)),
            "belongs to the event-driven engine: remove it or set engine.kind = \"event\"",
        )
    }

    /// With the time-driven engine: restitution or damping (not both), the restitution speed
    /// or temperature.
    fn validate_time_contact(&self, c: &Check<'_>) -> Result<(), SceneError> {
        let ct = &self.contact;
        // A restitution is converted into a damping constant at scene start
        // (`scene::damping`); giving both is ambiguous.
        for (key, e_r, other, a_d) in [
            (
                "contact.restitution",
                ct.restitution,
                "contact.damping",
                ct.damping,
            ),
            (
                "contact.wall_restitution",
                ct.wall_restitution,
                "contact.wall_damping",
                ct.wall_damping,
            ),
        ] {
            if e_r < 1.0 && a_d.is_some() {
                return Err(c.err(
                    key,
                    format!(
                        "and {other} are both given: the time-driven engine derives the \
                         damping from the restitution; give one of them"
                    ),
                ));
            }
            if e_r < 0.1 {
                return Err(c.out_of_range(
                    key,
                    e_r,
                    "in [0.1, 1] with the time-driven engine (converted into a Hertz \
                     damping constant, contact.restitution_speed)",
                ));
            }
        }
        if let Some(scene::RestitutionSpeed::Speed(v)) = ct.restitution_speed {
            let ok = v.is_finite() && v > 0.0 && v <= 100.0;
            let must = "in (0, 100] (units of sqrt(g d)), or \"auto\"";
            c.within("contact.restitution_speed", v, ok, must)?;
            if ct.restitution_temperature.is_some() {
                return Err(c.err(
                    "contact.restitution_temperature",
                    "is the temperature of restitution_speed = \"auto\", but \
                     contact.restitution_speed is a number: give one of them",
                ));
            }
        }
        if let Some(t) = ct.restitution_temperature {
            let ok = t.is_finite() && t > 0.0 && t <= 1e6;
            let must = "in (0, 1e6] (a granular temperature, units of m g d)";
            c.within("contact.restitution_temperature", t, ok, must)?;
        }
        Ok(())
    }

    /// With the time-driven engine: time step, skin, stiffness and damping in range, and a time
    /// step that resolves a Hertz contact ([`Scene::largest_time_step`]).
    fn validate_time_numbers(&self, c: &Check<'_>) -> Result<(), SceneError> {
        let e = &self.engine;
        let ct = &self.contact;
        if let Some(dt) = e.dt {
            let ok = dt.is_finite() && dt > 0.0 && dt <= scene::MAX_DT;
            c.within("engine.dt", dt, ok, "in (0, 0.01]")?;
        }
        if let Some(skin) = e.skin {
            let ok = skin.is_finite() && skin > 0.0 && skin <= 1.0;
            c.within("engine.skin", skin, ok, "in (0, 1] (units of d)")?;
        }
        if let Some(k) = ct.stiffness {
            let ok = k.is_finite() && (1e2..=1e12).contains(&k);
            c.within("contact.stiffness", k, ok, "in [1e2, 1e12]")?;
        }
        for (key, v) in [
            ("contact.damping", ct.damping),
            ("contact.wall_damping", ct.wall_damping),
        ] {
            if let Some(a) = v {
                let ok = a.is_finite() && (0.0..=1.0).contains(&a);
                c.within(key, a, ok, "in [0, 1] (a time)")?;
            }
        }
        self.validate_derived_damping(c)?;
        // A step that does not resolve a Hertz contact lets the integrator blow up (found by
        // `wetgran-bench stress time_largest_dt`: dt = 0.01 at the default stiffness), and so does one
        // that does not resolve its damping (found by the input fuzzer: restitution 0.3 at
        // dt = 3.1e-4, Gear). Without `engine.dt` the step is the largest allowed where that is
        // shorter than the default (`Scene::time_step`).
        let dt_max = self.largest_time_step();
        if let Some(dt) = e.dt
            && dt > dt_max
        {
            let (a_pair, a_wall) = scene::damping::contact_damping(self);
            let damping = if a_pair > 0.0 || a_wall > 0.0 {
                format!(
                    ", shortened for the damping A_d = {} (pairs), {} (walls) of contact.{}",
                    num(a_pair),
                    num(a_wall),
                    if ct.damping.is_some() || ct.wall_damping.is_some() {
                        "damping and wall_damping"
                    } else {
                        "restitution and wall_restitution"
                    }
                )
            } else {
                String::new()
            };
            return Err(c.out_of_range(
                "engine.dt",
                dt,
                &format!(
                    "<= {dt_max:.3e} (an eighth of the Hertz contact time at impact speed 10 \
                     sqrt(g d) for contact.stiffness = {}{damping}: a longer step does not \
                     resolve the contact and the integrator blows up; leave engine.dt out to \
                     get the largest allowed step)",
                    num(self.contact.stiffness.unwrap_or(scene::DEFAULT_STIFFNESS))
                ),
            ));
        }
        Ok(())
    }

    /// With the time-driven engine: a damping derived from a restitution (`scene::damping`) lies
    /// in the range a given `contact.damping` must (`[0, 1]`). A calibration at a vanishing
    /// temperature or speed gives an enormous one (`A_d ~ T^(-1/10)`; found by the input fuzzer:
    /// a hot start at `initial.temperature = 1e-300` gave `A_d = 1.9e27`), which no time step
    /// resolves.
    fn validate_derived_damping(&self, c: &Check<'_>) -> Result<(), SceneError> {
        let ct = &self.contact;
        if ct.damping.is_some() && ct.wall_damping.is_some() {
            return Ok(());
        }
        let (a_pair, a_wall) = scene::damping::contact_damping(self);
        let at = match scene::damping::calibration(self) {
            scene::damping::Calibration::Speed(v) => {
                format!("at the impact speed contact.restitution_speed = {}", num(v))
            }
            scene::damping::Calibration::Maxwellian(t) => format!(
                "at the granular temperature {} ({})",
                num(t),
                if ct.restitution_temperature.is_some() {
                    "contact.restitution_temperature"
                } else {
                    "the initial temperature of a hot start, else the drive's scale"
                }
            ),
        };
        for (key, given, a, e) in [
            ("contact.restitution", ct.damping, a_pair, ct.restitution),
            (
                "contact.wall_restitution",
                ct.wall_damping,
                a_wall,
                ct.wall_restitution,
            ),
        ] {
            if given.is_none() && !(a.is_finite() && a <= 1.0) {
                return Err(c.err(
                    key,
                    format!(
                        "= {} calibrated {at} gives the damping A_d = {} of the time-driven \
                         engine, out of range: must be in [0, 1] (a time); calibrate at a \
                         representative scale with contact.restitution_temperature or \
                         contact.restitution_speed, or give contact.damping",
                        num(e),
                        num(a)
                    ),
                ));
            }
        }
        Ok(())
    }

    /// With the time-driven engine: a periodic axis holds three Verlet-list ranges.
    fn validate_verlet_cells(&self, c: &Check<'_>) -> Result<(), SceneError> {
        let e = &self.engine;
        // The time engine's neighbour cells hold the Verlet-list range.
        let dim = self.dimension;
        let (_, d_max) = self.diameter_range();
        let range = d_max + self.s_crit() + e.skin.unwrap_or(scene::DEFAULT_SKIN);
        let boundaries = self.boundaries();
        for k in 0..dim {
            let l = self.container.size[k];
            if boundaries[k] == Boundary::Periodic && (l / range).floor() < 3.0 {
                return Err(c
                    .err(
                        &format!("box.size[{k}]"),
                        format!(
                            "= {l} is out of range: the time-driven engine needs a periodic \
                         axis >= 3 (d_max + s_crit + skin) = {:.4}",
                            3.0 * range
                        ),
                    )
                    .failing(Constraint::PeriodicAxisTooShort));
            }
        }
        Ok(())
    }
}
