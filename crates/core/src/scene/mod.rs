//! The declarative scene: what a user writes in a scene file (TOML) to describe one simulation.
//!
//! A scene names the dimension, the box and its boundaries, the particles, the contact and
//! capillary laws, gravity, the drive, the initial state, the run length and the engine's accuracy
//! knobs. [`Scene::from_toml_str`] parses and validates; every rejected value produces a
//! [`SceneError`] that names the file, the key and the allowed range (see `validate/`).
//!
//! Conventions (docs/model.md section 1): units of mean diameter `d`, particle mass `m`, gravity `g`.
//! The last axis is vertical (`z`; in 2D the axes are `x, z`); gravity points along `-z`.

pub(crate) mod convergence;
pub mod damping;
pub mod lattice;
pub(crate) mod observe_section;
pub(crate) mod thresholds;
mod validate;

pub use validate::parse_error_key;

use serde::{Deserialize, Serialize};
use std::path::Path;

pub use convergence::ConvergenceSpec;
pub use observe_section::ObserveSpec;
pub use thresholds::Thresholds;
pub(crate) use validate::MIN_PERIODIC_CELLS;
pub use validate::{Constraint, SceneError};

/// One simulation, as read from a scene file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Spatial dimension: 2 (disks) or 3 (spheres).
    pub dimension: usize,
    /// Gravitational acceleration along `-z` (0 switches gravity off: straight flights).
    #[serde(default = "one")]
    pub gravity: f64,
    #[serde(rename = "box")]
    pub container: BoxSpec,
    pub particles: ParticleSpec,
    #[serde(default)]
    pub contact: ContactSpec,
    #[serde(default)]
    pub capillary: CapillarySpec,
    #[serde(default)]
    pub drive: DriveSpec,
    pub initial: InitialSpec,
    pub run: RunSpec,
    #[serde(default)]
    pub engine: EngineSpec,
    /// Observers, sampling and the stationary window (`[observe]`).
    #[serde(default)]
    pub observe: ObserveSpec,
    /// Thresholds of the phase classification (`[classify]`).
    #[serde(default)]
    pub classify: Thresholds,
    /// Run to stationarity (`[convergence]`); `None`: the fixed length `run.duration`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub convergence: Option<ConvergenceSpec>,
}

/// The simulation box: one size and one boundary kind per axis, the vertical axis last.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BoxSpec {
    /// Edge lengths, one per axis (`[L_x, H]` in 2D, `[L_x, L_y, H]` in 3D), in units of `d`.
    pub size: Vec<f64>,
    /// Boundary per axis; default: periodic laterally, walls (floor and lid) vertically.
    pub boundary: Option<Vec<Boundary>>,
}

/// What happens at the two faces of the box perpendicular to one axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Boundary {
    Periodic,
    Wall,
}

/// The grains.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ParticleSpec {
    pub count: usize,
    /// Mean diameter (1 in the standard units).
    #[serde(default = "one")]
    pub diameter: f64,
    /// `sigma_p` of docs/model.md Eq. 2.22: diameters uniform on `d (1 +- sqrt(3) sigma_p)`.
    #[serde(default)]
    pub polydispersity: f64,
    /// Mass of every particle, whatever its size.
    #[serde(default = "one")]
    pub mass: f64,
}

/// Hard-core contact law (docs/model.md 2.1).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ContactSpec {
    /// Particle-particle coefficient of normal restitution `eps`.
    pub restitution: f64,
    /// Particle-wall coefficient of normal restitution `e_w`.
    pub wall_restitution: f64,
    /// Time-driven engine: Hertz prefactor `k = 2 Y / (3 (1 - nu^2))` of docs/model.md Eq. 2.7, in
    /// units of `m g / d^2` (default [`DEFAULT_STIFFNESS`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stiffness: Option<f64>,
    /// Time-driven engine: particle-particle damping `A_d` of Eq. 2.7, units of time (default 0,
    /// elastic).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub damping: Option<f64>,
    /// Time-driven engine: particle-wall damping `A_d` (default 0, elastic walls).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub wall_damping: Option<f64>,
    /// Time-driven engine: how `restitution` and `wall_restitution` are converted into damping
    /// constants (`scene::damping`): `"auto"` (the default) matches the mean energy
    /// loss over the impact speeds of a Maxwellian gas at the scene's characteristic temperature;
    /// a number (units of `sqrt(g d)`) gives exactly the restitution at that one impact speed.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub restitution_speed: Option<RestitutionSpeed>,
    /// Time-driven engine: the granular temperature (units of `m g d`, absolute without gravity)
    /// of the `"auto"` calibration, in place of the scene's characteristic temperature.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub restitution_temperature: Option<f64>,
}

/// `contact.restitution_speed`: `"auto"` or an impact speed.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(untagged)]
pub enum RestitutionSpeed {
    /// One impact speed (units of `sqrt(g d)`).
    Speed(f64),
    /// The word `"auto"`.
    Word(AutoWord),
}

impl<'de> Deserialize<'de> for RestitutionSpeed {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl serde::de::Visitor<'_> for V {
            type Value = RestitutionSpeed;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("an impact speed (a number, units of sqrt(g d)) or \"auto\"")
            }
            fn visit_f64<E: serde::de::Error>(self, v: f64) -> Result<Self::Value, E> {
                Ok(RestitutionSpeed::Speed(v))
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<Self::Value, E> {
                Ok(RestitutionSpeed::Speed(v as f64))
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<Self::Value, E> {
                Ok(RestitutionSpeed::Speed(v as f64))
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<Self::Value, E> {
                if v == "auto" {
                    Ok(RestitutionSpeed::Word(AutoWord::Auto))
                } else {
                    Err(E::invalid_value(serde::de::Unexpected::Str(v), &self))
                }
            }
        }
        d.deserialize_any(V)
    }
}

/// The only word `contact.restitution_speed` accepts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum AutoWord {
    /// The Maxwellian calibration at the characteristic temperature.
    Auto,
}

impl Default for ContactSpec {
    fn default() -> Self {
        Self {
            restitution: 1.0,
            wall_restitution: 1.0,
            stiffness: None,
            damping: None,
            wall_damping: None,
            restitution_speed: None,
            restitution_temperature: None,
        }
    }
}

/// Default Hertz prefactor `k` of the time-driven engine (chosen in docs/accuracy.md: the largest
/// overlap of the shaken standard systems stays below 1 % of `d`).
pub const DEFAULT_STIFFNESS: f64 = 1e7;
/// Default time step of the time-driven engine.
pub const DEFAULT_DT: f64 = 1e-4;
/// Default Verlet-list skin of the time-driven engine, in units of `d`.
pub const DEFAULT_SKIN: f64 = 0.1;
/// Largest time step of the time-driven engine, whatever the stiffness.
pub(crate) const MAX_DT: f64 = 1e-2;
/// Impact speed, in units of `sqrt(g d)` (absolute without gravity), whose Hertz contact the
/// time step must resolve ([`Scene::largest_time_step`]).
pub(crate) const DT_REFERENCE_SPEED: f64 = 10.0;
/// Time steps per Hertz contact at [`DT_REFERENCE_SPEED`] at the least
/// ([`Scene::largest_time_step`]).
pub(crate) const STEPS_PER_CONTACT: f64 = 8.0;
/// Weight of the damping rate against the contact frequency in the time-step bound of the Gear
/// integrator ([`Scene::largest_time_step`]); its velocity-dependent force makes the predictor-
/// corrector far less stable under damping than Verlet (docs/reliability.md, "Time step and
/// damping").
pub(crate) const GEAR_DAMPING_WEIGHT: f64 = 2.0;
/// Weight of the damping rate in the time-step bound of velocity Verlet
/// ([`Scene::largest_time_step`]).
pub(crate) const VERLET_DAMPING_WEIGHT: f64 = 0.5;

/// Capillary bridges (docs/model.md 3).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CapillarySpec {
    pub model: CapillaryModel,
    /// Rupture separation of the surfaces, `s_crit` (thin-thread default 0.0711 d).
    pub s_crit: Option<f64>,
    /// Bridge rupture energy `E_cb` (default `F_B s_crit` with `F_B = 4 m g`).
    pub e_cb: Option<f64>,
    /// Which kinetic energy pays for a rupture (docs/model.md 3.2); default `reduced_mass`.
    pub rupture_rule: Option<RuptureRule>,
}

/// Which capillary model acts between the grains.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CapillaryModel {
    /// Dry grains.
    #[default]
    None,
    /// The hysteretic square well of docs/model.md 3.2 (event-driven engine).
    ThinThread,
}

/// The energy criterion at `s = s_crit` (docs/model.md 3.2): defined with the physics it selects.
pub use crate::physics::capillary::RuptureRule;

/// Driving of the container (docs/model.md 4.1): floor and lid move together as
/// `z_w(t) = A sin(omega t)`. Give either `amplitude` and `omega`, or `gamma` and `e_star`
/// (`E*` for wet scenes, `E_d*` for dry ones), converted as in docs/model.md 4.1.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct DriveSpec {
    pub kind: DriveKind,
    /// Amplitude `A` of the container motion.
    pub amplitude: Option<f64>,
    /// Angular frequency `omega`.
    pub omega: Option<f64>,
    /// Peak acceleration `Gamma = A omega^2 / g`.
    pub gamma: Option<f64>,
    /// Driving energy `E* = m (A omega)^2 / (2 E_cb)` (wet) or `E_d* = m (A omega)^2 / (2 m g d)`
    /// (dry).
    pub e_star: Option<f64>,
    /// How wall collision times are found.
    pub wall_solver: WallSolverKind,
    /// Gap tolerance of the wall-root solver, in units of `d` (default 1e-10).
    pub root_tolerance: Option<f64>,
    /// Step of the `bracket` solver (docs/model.md 6, B.3), default a thousandth of a period.
    pub t_min: Option<f64>,
    /// `table` solver: cells along the phase (or height) and along the mapped velocity
    /// (default `[128, 128]`).
    pub table_cells: Option<[usize; 2]>,
    /// `table` solver: where the velocity map turns from linear to logarithmic, in units of the
    /// wall's peak speed `A omega` (default 0.05).
    pub table_v_min: Option<f64>,
    /// `table` solver: speed cut-off in units of `A omega`; faster flights go to the exact
    /// solver (default 50).
    pub table_v_max: Option<f64>,
    /// `table` solver: check each cell's linear model at its corners and let the exact solver
    /// answer for cells that fail (default true; false is the thesis's table as printed).
    pub table_corner_check: Option<bool>,
    /// `table` solver: the corner check's tolerance on root times, in units of the period
    /// (default 1e-3).
    pub table_corner_tolerance: Option<f64>,
    /// `shear`: peak body force `F_max` of `F_s(x) = F_max cos(2 pi x / L_x)` along `y`
    /// (docs/model.md 4.2, Eq. 2.20), in units of `m g` (absolute force units without gravity).
    pub f_max: Option<f64>,
    /// `shear`: requested width of the slabs of constant force (event-driven engine), in units
    /// of `d` (default 1 mean diameter); rounded so that a whole number of slabs tiles `L_x`.
    pub slab_width: Option<f64>,
}

/// The kind of drive.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DriveKind {
    /// Static floor and lid.
    #[default]
    None,
    /// Floor and lid shaken sinusoidally along the vertical axis.
    Sine,
    /// Kolmogorov flow (docs/model.md 4.2): the body force `F_max cos(2 pi x / L_x)` along `y`,
    /// static floor and lid; 3D only (a 2D box has no axis `y` across the force's variation).
    Shear,
}

/// The slabs of constant force of a shear drive (event-driven engine, docs/model.md 4.2).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShearSlabs {
    /// Peak force `F_max`.
    pub f_max: f64,
    /// Number of slabs along `x`.
    pub count: usize,
    /// Slab width `L_x / count`.
    pub width: f64,
}

impl ShearSlabs {
    /// Force in slab `k`: the field at the slab centre, `F_max cos(2 pi (k + 1/2) w / L_x)`
    /// (Eq. 2.20 made piecewise constant).
    pub fn force(&self, k: usize) -> f64 {
        let phase = 2.0 * std::f64::consts::PI * (k as f64 + 0.5) / self.count as f64;
        self.f_max * phase.cos()
    }
}

/// Wall-collision solver for the shaken container (docs/model.md 6).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum WallSolverKind {
    /// Conservative advancement with the curvature bound `g + A omega^2`: cannot skip a root.
    #[default]
    Exact,
    /// The thesis's reference algorithm: march by `t_min`, refine by safeguarded Newton.
    Bracket,
    /// The thesis's tabulated method (B.4-B.5), one table per wall motion shared by all jobs.
    Table,
}

/// Default gap tolerance of the wall-root solver.
pub const DEFAULT_ROOT_TOLERANCE: f64 = 1e-10;
/// Steps per driving period of the `bracket` wall solver by default (`drive.t_min = T / 1000`).
pub(crate) const BRACKET_STEPS_PER_PERIOD: f64 = 1000.0;

/// Initial state: a regular lattice filled from the floor up, Gaussian velocities.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InitialSpec {
    /// Granular temperature `T_g` in units of `m g d` (or absolute units without gravity).
    pub temperature: Option<f64>,
    /// Granular temperature in units of `E_cb` (needs capillary bridges).
    pub temperature_over_ecb: Option<f64>,
    /// Lattice spacing in units of the largest diameter (>= 1; default 1.01).
    #[serde(default = "default_lattice_spacing")]
    pub lattice_spacing: f64,
    /// Seed of the random number generator (sizes and velocities).
    #[serde(default)]
    pub seed: u64,
    /// `"hot"` (default): the lattice with Gaussian velocities and no bridges (docs/model.md 1).
    /// `"cold"`: a bonded bed at rest, the same lattice with zero velocities (the temperature
    /// keys are ignored) and a bridge between every pair of grains closer than `s_crit`
    /// (`sim::initial::cold_state`). `"continue"` (sweeps with `[sweep.continuation]` only):
    /// the final state of the neighbouring point along the continuation axis
    /// (`sim::EngineState::continued`); the first point of each chain starts as
    /// `sweep.continuation.first` says.
    #[serde(default, skip_serializing_if = "StartMode::is_hot")]
    pub start: StartMode,
}

/// How a run starts (`initial.start`); two start modes that end in different phases at one
/// point mark it hysteretic (`store::hysteresis`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum StartMode {
    #[default]
    Hot,
    Cold,
    /// From the final state of the neighbouring sweep point (a continuation chain).
    Continue,
}

impl std::fmt::Display for StartMode {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            StartMode::Hot => "hot",
            StartMode::Cold => "cold",
            StartMode::Continue => "continue",
        })
    }
}

impl StartMode {
    pub(crate) fn is_hot(&self) -> bool {
        *self == StartMode::Hot
    }
}

/// How long to run and how often to sample.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RunSpec {
    /// Simulated time, in units of `sqrt(d/g)` (or of the scene's own time unit).
    pub duration: f64,
    /// Interval between samples of the observables (0: only at the end).
    #[serde(default)]
    pub sample_interval: f64,
    /// Optional cap on the number of processed events.
    pub max_events: Option<u64>,
}

/// Which engine runs the scene (`engine.kind`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum EngineKind {
    /// Event-driven hard spheres with thin-thread bridges (`sim::event_driven`).
    #[default]
    Event,
    /// Time-driven soft spheres (Hertz) with the minimal capillary model (`sim::time_driven`).
    Time,
}

impl EngineKind {
    fn is_event(&self) -> bool {
        *self == EngineKind::Event
    }
}

/// Integrator of the time-driven engine (`engine.integrator`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum IntegratorKind {
    /// Gear predictor-corrector of 5th order (six values per coordinate).
    #[default]
    Gear5,
    /// Velocity Verlet.
    Verlet,
}

/// The engine and its accuracy and safety knobs. `tc`, `min_rebound_speed`, `overlap_tolerance`
/// and `cell_size` belong to the event-driven engine; `dt`, `integrator` and `skin` to the
/// time-driven one.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct EngineSpec {
    /// `"event"` (default) or `"time"`.
    #[serde(skip_serializing_if = "EngineKind::is_event")]
    pub kind: EngineKind,
    /// Time-driven: the time step (default [`DEFAULT_DT`], or [`Scene::largest_time_step`] where
    /// that is shorter: [`Scene::time_step`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dt: Option<f64>,
    /// Time-driven: `"gear5"` (default) or `"verlet"`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub integrator: Option<IntegratorKind>,
    /// Time-driven: Verlet-list skin in units of `d` (default [`DEFAULT_SKIN`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub skin: Option<f64>,
    /// TC model (Luding & McNamara 1998): a collision within `tc` of either particle's previous
    /// collision is elastic. 0 (default) disables it.
    pub tc: f64,
    /// Rebound floor: an inelastic collision never separates slower than this (collapse remedy
    /// for beds resting on a floor; the energy it adds is booked). 0 disables it.
    pub min_rebound_speed: f64,
    /// Largest overlap (in units of `d`) that the sanity check tolerates.
    pub(crate) overlap_tolerance: f64,
    /// Cell edge of the neighbour grid; 0 chooses the smallest legal one automatically.
    pub(crate) cell_size: f64,
}

impl Default for EngineSpec {
    fn default() -> Self {
        Self {
            kind: EngineKind::Event,
            dt: None,
            integrator: None,
            skin: None,
            tc: 0.0,
            min_rebound_speed: 1e-3,
            overlap_tolerance: 1e-6,
            cell_size: 0.0,
        }
    }
}

fn one() -> f64 {
    1.0
}
fn default_lattice_spacing() -> f64 {
    1.01
}

/// Thin-thread default rupture separation (docs/model.md 1).
pub(crate) const DEFAULT_S_CRIT: f64 = 0.0711;
/// Default bridge force in units of `m g` (docs/model.md 1): `E_cb = F_B s_crit`.
pub(crate) const DEFAULT_BRIDGE_FORCE_OVER_MG: f64 = 4.0;

impl Scene {
    /// Parses and validates a scene; `origin` names the file in error messages.
    pub fn from_toml_str(text: &str, origin: &str) -> Result<Scene, SceneError> {
        let mut scene: Scene = toml::from_str(text).map_err(|e| SceneError::parse(origin, e))?;
        if let Some(v) = scene.observe.removed_stationarity_tolerance {
            SceneError::unless(
                false,
                origin,
                "observe.stationarity_tolerance",
                v,
                "left out: the key was removed, a run's label is now held to the history of \
                 each region it names (docs/observables.md, \"Run to a settled label\")",
            )?;
        }
        scene.resolve_observers();
        scene.validate(origin)?;
        Ok(scene)
    }

    /// Fills in the observers left to their default by what the rest of the scene needs:
    /// `observe.location_changes` becomes `Some(on)`, on where `[classify]` reads `f_lc`
    /// ([`ObserveSpec::counts_location_changes`]). A job spec then names every observer it
    /// runs, so its id tells a result with `f_lc` from one without.
    pub fn resolve_observers(&mut self) {
        let on = self.observe.counts_location_changes(&self.classify);
        self.observe.location_changes = Some(on);
    }

    /// Reads, parses and validates a scene file.
    pub fn load(path: &Path) -> Result<Scene, SceneError> {
        let origin = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| SceneError::io(&origin, e))?;
        Self::from_toml_str(&text, &origin)
    }

    /// Boundary per axis, with the default filled in.
    pub fn boundaries(&self) -> Vec<Boundary> {
        match &self.container.boundary {
            Some(b) => b.clone(),
            None => {
                let mut b = vec![Boundary::Periodic; self.dimension];
                b[self.dimension - 1] = Boundary::Wall;
                b
            }
        }
    }

    /// Whether capillary bridges exist in this scene.
    pub fn is_wet(&self) -> bool {
        self.capillary.model != CapillaryModel::None
    }

    /// Rupture separation `s_crit` (0 for dry scenes).
    pub fn s_crit(&self) -> f64 {
        if !self.is_wet() {
            return 0.0;
        }
        self.capillary
            .s_crit
            .unwrap_or(DEFAULT_S_CRIT * self.particles.diameter)
    }

    /// The rupture rule in force (default `reduced_mass`).
    pub fn rupture_rule(&self) -> RuptureRule {
        self.capillary.rupture_rule.unwrap_or_default()
    }

    /// Bridge energy `E_cb` (0 for dry scenes); default `F_B s_crit`, `F_B = 4 m g`.
    pub fn e_cb(&self) -> f64 {
        if !self.is_wet() {
            return 0.0;
        }
        self.capillary.e_cb.unwrap_or(
            DEFAULT_BRIDGE_FORCE_OVER_MG * self.particles.mass * self.gravity * self.s_crit(),
        )
    }

    /// Smallest and largest diameter (docs/model.md Eq. 2.22: `d (1 -+ sqrt(3) sigma_p)`).
    pub fn diameter_range(&self) -> (f64, f64) {
        crate::physics::size::diameter_range(self.particles.diameter, self.particles.polydispersity)
    }

    /// The slabs of a shear drive (`None` for other drives): `count = max(1, round(L_x / w))`
    /// for the requested width `w` (`drive.slab_width`, default one mean diameter), so the slabs
    /// tile `L_x` exactly with width `L_x / count`.
    pub fn shear_slabs(&self) -> Option<ShearSlabs> {
        if self.drive.kind != DriveKind::Shear {
            return None;
        }
        let l_x = self.container.size[0];
        let w = self.drive.slab_width.unwrap_or(self.particles.diameter);
        let count = ((l_x / w).round() as usize).max(1);
        Some(ShearSlabs {
            f_max: self.drive.f_max.unwrap_or(0.0),
            count,
            width: l_x / count as f64,
        })
    }

    /// The period everything "in periods" is counted in (the one definition: `sweep.periods`,
    /// `observe.transient_periods`, `observe.samples_per_period`, `[convergence]`): one driving
    /// period `T = 2 pi / omega` of a shaken scene (docs/model.md 4.1), else the scene's time unit
    /// `sqrt(d/g)`, or 1 without gravity.
    pub fn driving_period(&self) -> f64 {
        match self.drive_motion() {
            Some((_, omega)) if omega > 0.0 => 2.0 * std::f64::consts::PI / omega,
            _ if self.gravity > 0.0 => (self.particles.diameter / self.gravity).sqrt(),
            _ => 1.0,
        }
    }

    /// Container motion `(A, omega)` of a shaken scene, converted from `(Gamma, E*)` where those
    /// are given (docs/model.md 4.1): `v_w = sqrt(2 E* E_cb / m)` (dry: `sqrt(2 E_d* g d)`),
    /// `omega = Gamma g / v_w`, `A = v_w^2 / (Gamma g)`. `None` without a drive.
    pub fn drive_motion(&self) -> Option<(f64, f64)> {
        let d = &self.drive;
        if d.kind != DriveKind::Sine {
            return None;
        }
        if let (Some(a), Some(w)) = (d.amplitude, d.omega) {
            return Some((a, w));
        }
        let (gamma, e_star) = (d.gamma?, d.e_star?);
        let energy_unit = if self.is_wet() && self.e_cb() > 0.0 {
            self.e_cb()
        } else {
            self.particles.mass * self.gravity * self.particles.diameter
        };
        let v_w = (2.0 * e_star * energy_unit / self.particles.mass).sqrt();
        let omega = gamma * self.gravity / v_w;
        let amplitude = v_w * v_w / (gamma * self.gravity);
        Some((amplitude, omega))
    }

    /// Resolution, velocity map and corner check of the `table` wall solver for a drive
    /// `(A, omega)`, with the defaults filled in.
    pub fn wall_table_spec(
        &self,
        amplitude: f64,
        omega: f64,
    ) -> crate::physics::wall_table::TableSpec {
        use crate::physics::wall_table as wt;
        let d = &self.drive;
        let [phase_cells, velocity_cells] = d
            .table_cells
            .unwrap_or([wt::DEFAULT_PHASE_CELLS, wt::DEFAULT_VELOCITY_CELLS]);
        let v_wall = amplitude * omega;
        wt::TableSpec {
            phase_cells,
            velocity_cells,
            v_min: d.table_v_min.unwrap_or(wt::DEFAULT_V_MIN_OVER_WALL_SPEED) * v_wall,
            v_max: d.table_v_max.unwrap_or(wt::DEFAULT_V_MAX_OVER_WALL_SPEED) * v_wall,
            corner_tolerance: if d.table_corner_check.unwrap_or(true) {
                Some(
                    d.table_corner_tolerance
                        .unwrap_or(wt::DEFAULT_CORNER_TOLERANCE),
                )
            } else {
                None
            },
        }
    }

    /// Step of the `bracket` wall solver at angular frequency `omega`: `drive.t_min`, by default
    /// a thousandth of the driving period `T = 2 pi / omega` (docs/model.md 6).
    pub fn bracket_step(&self, omega: f64) -> f64 {
        self.drive
            .t_min
            .unwrap_or(2.0 * std::f64::consts::PI / omega / BRACKET_STEPS_PER_PERIOD)
    }

    /// The largest `engine.dt` the time-driven engine is allowed: the smallest of [`MAX_DT`], an
    /// eighth ([`STEPS_PER_CONTACT`]) of the duration of an elastic Hertz contact between two of
    /// the largest grains at the impact speed `v = 10 sqrt(g d)` ([`DT_REFERENCE_SPEED`]), and,
    /// with damping, that eighth shrunk so that the damping is resolved too.
    ///
    /// Elastic part: `t_c = 2.943 xi_max / v`, `xi_max = (5 mu v^2 / (4 k sqrt(R_eff)))^(2/5)`,
    /// `mu = m/2`, `R_eff = d_max / 4` (docs/model.md Eq. 2.7; `physics::hertz::contact_time`). At the
    /// default stiffness this is 4.0e-4; a longer step lets the integrator blow up
    /// (docs/reliability.md, "Hard cases at length").
    ///
    /// Damping: linearised at the overlap `xi_max` of that contact, Eq. 2.7 is an oscillator of
    /// angular frequency `omega^2 = (3/2) k sqrt(R_eff) sqrt(xi_max) / mu` and damping rate
    /// `gamma = A_d k sqrt(R_eff) sqrt(xi_max) / mu` (the larger of the pair contact and of the
    /// wall contact, `R_eff = d_max / 2`, `mu = m`, with their `A_d`, [`damping::contact_damping`]).
    /// The elastic bound is `omega dt <= 0.504`; with damping it becomes
    /// `(omega + c gamma) dt <= 0.504`, `c` = [`GEAR_DAMPING_WEIGHT`] for Gear and
    /// [`VERLET_DAMPING_WEIGHT`] for Verlet: measured limits of stability on shaken and resting
    /// beds (docs/reliability.md, "Time step and damping") lie 1.5 to 4 times above it.
    pub fn largest_time_step(&self) -> f64 {
        use crate::physics::hertz;
        let (_, d_max) = self.diameter_range();
        let k = self.contact.stiffness.unwrap_or(DEFAULT_STIFFNESS);
        let m = self.particles.mass;
        let unit = if self.gravity > 0.0 {
            (self.gravity * self.particles.diameter).sqrt()
        } else {
            1.0
        };
        let v = DT_REFERENCE_SPEED * unit;
        let r = 0.5 * d_max;
        let kr = k * hertz::effective_radius(r, r).sqrt();
        let t_c = hertz::contact_time(kr, 0.5 * m, v);
        if !(t_c.is_finite() && t_c > 0.0) {
            return MAX_DT;
        }
        let elastic = t_c / STEPS_PER_CONTACT;
        // Damping rate at the reference contact, per unit `A_d`: `k sqrt(R_eff) sqrt(xi_max) / mu`.
        let rate = |kr: f64, mu: f64| kr * hertz::max_overlap(kr, mu, v).sqrt() / mu;
        let omega = (1.5 * rate(kr, 0.5 * m)).sqrt();
        let (a_pair, a_wall) = damping::contact_damping(self);
        let gamma = (a_pair * rate(kr, 0.5 * m)).max(a_wall * rate(k * r.sqrt(), m));
        let weight = match self.engine.integrator.unwrap_or_default() {
            IntegratorKind::Gear5 => GEAR_DAMPING_WEIGHT,
            IntegratorKind::Verlet => VERLET_DAMPING_WEIGHT,
        };
        let damped = elastic * omega / (omega + weight * gamma);
        let dt = elastic.min(damped);
        if dt.is_finite() && dt > 0.0 {
            MAX_DT.min(dt)
        } else {
            0.0
        }
    }

    /// The time step of the time-driven engine: `engine.dt`, or [`DEFAULT_DT`] where that is no
    /// longer than [`Scene::largest_time_step`], else that largest step (a stiff or strongly
    /// damped scene gets a step it resolves without having to name one).
    pub fn time_step(&self) -> f64 {
        self.engine
            .dt
            .unwrap_or_else(|| DEFAULT_DT.min(self.largest_time_step()))
    }

    /// Initial granular temperature in absolute units.
    pub fn initial_temperature(&self) -> f64 {
        match (self.initial.temperature, self.initial.temperature_over_ecb) {
            (Some(t), _) => t,
            (None, Some(r)) => r * self.e_cb(),
            (None, None) => 0.0,
        }
    }
}
