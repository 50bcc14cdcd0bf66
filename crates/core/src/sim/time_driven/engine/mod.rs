//! The time-driven engine: soft disks (`D = 2`) and spheres (`D = 3`) with damped Hertz contacts
//! (docs/model.md 2.2, Eq. 2.7), the minimal capillary model (docs/model.md 3.1), gravity, periodic lateral
//! axes, static or sinusoidally shaken Hertz floor and lid (docs/model.md 4.1) and an optional body
//! force per particle ([`BodyForce`]).
//!
//! Effects are compile-time parameters, chosen once at scene start: `GRAV` (gravity), `WET`
//! (bridges and their bookkeeping) and the body force type `B` ([`NoBodyForce`] compiles to
//! nothing).
//!
//! State: structure of arrays, every coordinate axis-major (`x[k * n + i]`). With the Gear
//! integrator `r[k]` holds the scaled `k`-th derivative (`integrator.rs`); with velocity Verlet
//! `r[0]` is the position and `r[1]` the velocity. Between Gear steps `r` holds the prediction
//! for the next step; the current (corrected) position and velocity are recovered on demand by
//! inverting the predictor (round-off equal to the corrector's output), not stored each step.
//! Forces come from the Verlet list of `neighbours.rs` with Newton's third law (each pair once),
//! visiting only non-empty rows. The list's displacement test runs only when a bound summed
//! from the integrator loops' largest moves says it might fire ([`TimeEngine`]'s
//! `update_list`); the builds happen at the same steps as with a test every step (up to the
//! rebuilds a test every step triggers when a particle crosses a periodic face), and the
//! trajectories are bit-identical (a build changes only which non-interacting pairs are
//! listed). Nothing is allocated inside a step once the neighbour list has reached its working
//! size.
//!
//! Energy bookkeeping ([`EnergyLedger`], same fields as the event engine):
//! - `potential`: gravity `m g z`, Hertz elastic energy of pairs and walls (`(2/5) k sqrt(R_eff)
//!   xi^(5/2)`), and the bridge energy `F_B s` of every bonded pair (docs/model.md 3.1: zero at
//!   contact, `E_cb` at rupture);
//! - `dissipated_restitution`: work of the damping part of Eq. 2.7, `sum F_damp xi_dot dt`;
//! - `dissipated_ruptures`: the bridge energy `F_B s` removed at each rupture (about `E_cb`),
//!   minus the (small, negative) `F_B s` a bridge starts with when it forms at overlap `-s`;
//! - `work_by_drive`: work of the moving walls on the particles, `sum F_wall v_wall dt`, plus the
//!   work of the body force, `sum F . v dt`.
//!
//! The sums over `dt` are rectangle rules at the force evaluations, so the ledger closes to the
//! integrator's accuracy (exactly in the limit `dt -> 0`), not to round-off as in the event engine.

use super::domains::{
    DOMAIN_MIN_PARTICLES, DOMAINS, Decomposition, EngineArrays, RegionEnd, StepConstants, TeamBuild,
};
use super::integrator::{
    GEAR_FLUSH_EVERY, GEAR5, GEAR5_C0_VELOCITY_DEPENDENT, gear_correct_predict_axis, gear_predict,
    gear_unpredict, verlet_drift, verlet_kick,
};
use super::neighbours::{BOND, EXACT_CHECK_EVERY, NeighbourList};
use super::pair_kernel::{ENTRY_CHUNK, PairBooks, PairConstants, pair_chunk, pair_forces_serial};
use super::walls::{WallAxis, WallBooks, wall_forces};
use crate::physics::hertz;
use crate::scene::{Boundary, DEFAULT_SKIN, DEFAULT_STIFFNESS, IntegratorKind, Scene};
use crate::sim::books::{EnergyLedger, EventCounts};
use crate::sim::initial::initial_state;
use rayon::prelude::*;
use std::borrow::Cow;

#[cfg(test)]
mod domain_tests;
mod measures;
mod stepping;

use stepping::{ChunkBooks, Then};

/// A force per particle that depends on its position and the time (hook for driving by a body
/// force, e.g. the shear force of docs/model.md 4.2). Its work is booked in `work_by_drive`.
pub trait BodyForce<const D: usize>: Send + Sync {
    /// Whether the force exists (false compiles the call away).
    const ACTIVE: bool;
    /// The force on a particle at `x` at time `t`.
    fn force(&self, x: &[f64; D], t: f64) -> [f64; D];
}

/// No body force.
#[derive(Debug, Clone, Copy, Default)]
pub struct NoBodyForce;

impl<const D: usize> BodyForce<D> for NoBodyForce {
    const ACTIVE: bool = false;
    #[inline]
    fn force(&self, _: &[f64; D], _: f64) -> [f64; D] {
        [0.0; D]
    }
}

/// Coordinates per chunk of the per-particle phase of a step (and of Verlet's drift): the
/// unit of work of a thread, and the unit over which the booked sums are taken before they are
/// added up in chunk order (fixed, so the numbers do not depend on the number of threads).
pub const PARTICLE_CHUNK: usize = 128;

/// Below this many particles (the default of [`TimeEngine::set_parallel_min_particles`]) the
/// loops of a step run on the calling thread (same chunks, same numbers): a parallel loop costs
/// a few microseconds of hand-over per step. On a quiet 2-core machine two threads made the
/// N = 1200 bench 0.69x as fast, 4 800 disks about even, 19 200 at most 1.37x
/// (docs/performance-history.md, "Quiet-machine figures after the third round").
pub const PARALLEL_MIN_PARTICLES: usize = 16_384;

/// Which Gear steps run on the spatial domains (`domains.rs`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum DomainMode {
    /// From [`DOMAIN_MIN_PARTICLES`] particles on (the default).
    #[default]
    Auto,
    /// Always (tests of small systems).
    Always,
    /// Never: the serial (or rayon-split) step (tests and benches comparing the paths).
    Never,
}

/// The spatial decomposition in use (`domains.rs`), if any; a clone carries it (its partition
/// was made at an earlier build and sets the round-off of the steps that follow).
#[derive(Debug, Default, Clone)]
struct DomainCache<const D: usize>(Option<Box<Decomposition<D>>>);

/// Largest overlap, in units of the mean diameter, that [`TimeEngine::sanity_check`] tolerates
/// (five times the 1 % the default stiffness is chosen for).
pub const SANITY_OVERLAP: f64 = 0.05;

/// Runtime parameters derived once from the scene.
#[derive(Debug, Clone)]
struct Params<const D: usize> {
    size: [f64; D],
    periodic: [bool; D],
    gravity: f64,
    mass: f64,
    dt: f64,
    integrator: IntegratorKind,
    gear: [f64; 6],
    /// Hertz prefactor `k` of Eq. 2.7.
    stiffness: f64,
    damping: f64,
    wall_damping: f64,
    s_crit: f64,
    /// `F_B = E_cb / s_crit` (docs/model.md 3.1).
    bridge_force: f64,
    /// `(A, omega)` of the shaken floor and lid.
    drive: Option<(f64, f64)>,
    diameter: f64,
    /// The largest particle radius.
    max_radius: f64,
}

/// The time-driven simulation state.
#[derive(Debug, Clone)]
pub struct TimeEngine<const D: usize, const GRAV: bool, const WET: bool, B = NoBodyForce> {
    p: Params<D>,
    n: usize,
    steps: u64,
    /// Scaled derivatives (Gear) or position, velocity (Verlet); axis-major.
    r: [Vec<f64>; 6],
    /// Gear: whether `r` holds the prediction for the next step (then the corrected position
    /// and velocity of the current step are recovered on demand by inverting the predictor,
    /// [`gear_unpredict`], instead of being stored every step).
    predicted: bool,
    /// Acceleration of the last force evaluation, axis-major; or, when `acc_is_start`, the
    /// value every coordinate's force starts from ([`Self::force_start`]).
    acc: Vec<f64>,
    /// Whether `acc` holds the force start values, written by the last integrator pass (Gear's
    /// corrector-predictor, Verlet's drift) as it read the accelerations: the next force
    /// evaluation then needs no pass of its own to initialise the forces.
    acc_is_start: bool,
    radius: Vec<f64>,
    /// `k sqrt(R_i)`: the wall prefactor of each particle (`R_eff = R_i`).
    wall_kr: Vec<f64>,
    /// Per coordinate (axis-major): bit 0 touching the lower wall, bit 1 the upper wall of
    /// that axis.
    wall_contact: Vec<u8>,
    /// Pair force of each Verlet-list entry on its row's particle, `D` values per entry.
    pair_f: Vec<f64>,
    /// Body force per particle, particle-major (empty without one).
    body_f: Vec<f64>,
    /// Reused result buffers of the parallel phases (per chunk).
    pair_books: Vec<PairBooks>,
    chunk_books: Vec<ChunkBooks<D>>,
    body_work: Vec<f64>,
    list: NeighbourList<D>,
    /// Upper bound on the displacement of every particle since the last neighbour-list build
    /// (or exact check): the sum over steps of `sqrt(sum_k m_k^2)`, `m_k` the largest move along
    /// axis `k` in that step (returned by the integrator loops). See [`Self::update_list`].
    moved_bound: f64,
    /// Steps since the last exact displacement check.
    since_check: u32,
    counts: EventCounts,
    dissipated_damping: f64,
    dissipated_bridges: f64,
    work_by_drive: f64,
    max_overlap: f64,
    body: B,
    domain_mode: DomainMode,
    domains: DomainCache<D>,
    /// Gear steps run on the domains with a team of more than one thread.
    team_steps: u64,
    /// Partitions made (`domains.rs`).
    partitions: u64,
    /// Regions of domain steps run (`domain_region`; a region goes on through list builds).
    regions: u64,
    /// How long a region waits for the pool's threads to join its team (`team::DOOR_WAIT`;
    /// tests lengthen it so that a loaded machine still runs two members).
    team_door: std::time::Duration,
    /// The fewest particles for which a step is split over threads.
    parallel_min: usize,
}

impl<const D: usize, const GRAV: bool, const WET: bool> TimeEngine<D, GRAV, WET, NoBodyForce> {
    /// Builds the engine for a validated scene with `engine.kind = "time"`.
    pub fn new(scene: &Scene) -> Self {
        Self::with_body_force(scene, NoBodyForce)
    }

    /// Rebuilds the engine from a saved state ([`Self::from_state_with_body_force`]).
    pub fn from_state(scene: &Scene, state: &crate::sim::EngineState) -> Self {
        Self::from_state_with_body_force(scene, state, NoBodyForce)
    }
}

impl<const D: usize, const GRAV: bool, const WET: bool, B: BodyForce<D>>
    TimeEngine<D, GRAV, WET, B>
{
    /// Builds the engine with a body force.
    pub fn with_body_force(scene: &Scene, body: B) -> Self {
        Self::assemble(scene, initial_state(scene), None, body)
    }

    /// Rebuilds the engine from a saved state (`sim::state`): positions, velocities, radii and
    /// the bridges (flagged bonded in the neighbour list) at the state's time, rounded to a
    /// whole number of steps; event counts and energy ledger continued. The Gear derivatives
    /// beyond the velocity are re-initialised as at a start (`r_2` from the forces, higher
    /// ones zero), so the continuation is physically continuous (same positions, velocities,
    /// bridges and energy) but not identical to an uninterrupted run; contacts overlapping at
    /// the state count as new contact onsets.
    pub fn from_state_with_body_force(
        scene: &Scene,
        state: &crate::sim::EngineState,
        body: B,
    ) -> Self {
        let d = scene.dimension;
        let init = crate::sim::initial::InitialState {
            radius: state.radii.clone(),
            position: state.positions.chunks(d).map(<[f64]>::to_vec).collect(),
            velocity: state.velocities.chunks(d).map(<[f64]>::to_vec).collect(),
        };
        Self::assemble(scene, init, Some(state), body)
    }

    fn assemble(
        scene: &Scene,
        init: crate::sim::initial::InitialState,
        start: Option<&crate::sim::EngineState>,
        body: B,
    ) -> Self {
        assert_eq!(scene.dimension, D, "scene dimension does not match");
        assert_eq!(GRAV, scene.gravity > 0.0, "gravity flag does not match");
        assert_eq!(WET, scene.is_wet(), "capillary flag does not match");
        let n = init.radius.len();
        let boundaries = scene.boundaries();
        let mut size = [0.0; D];
        let mut periodic = [false; D];
        for k in 0..D {
            size[k] = scene.container.size[k];
            periodic[k] = boundaries[k] == Boundary::Periodic;
        }
        let e = &scene.engine;
        let c = &scene.contact;
        let (damping, wall_damping) = super::damping::contact_damping(scene);
        let mut gear = GEAR5;
        if damping > 0.0 || wall_damping > 0.0 {
            gear[0] = GEAR5_C0_VELOCITY_DEPENDENT;
        }
        let stiffness = c.stiffness.unwrap_or(DEFAULT_STIFFNESS);
        let s_crit = scene.s_crit();
        let p = Params {
            size,
            periodic,
            gravity: scene.gravity,
            mass: scene.particles.mass,
            dt: scene.time_step(),
            integrator: e.integrator.unwrap_or_default(),
            gear,
            stiffness,
            damping,
            wall_damping,
            s_crit,
            bridge_force: if WET {
                hertz::bridge_force(scene.e_cb(), s_crit)
            } else {
                0.0
            },
            drive: scene.drive_motion(),
            diameter: scene.particles.diameter,
            max_radius: init.radius.iter().fold(0.0, |a: f64, &r| a.max(r)),
        };
        let skin = e.skin.unwrap_or(DEFAULT_SKIN) * scene.particles.diameter;
        let (_, d_max) = scene.diameter_range();
        let amp = p.drive.map_or(0.0, |(a, _)| a.abs());
        let mut lower = [0.0; D];
        let mut upper = size;
        for k in 0..D {
            if !periodic[k] {
                lower[k] = -amp - d_max;
                upper[k] = size[k] + amp + d_max;
            }
        }
        let list = NeighbourList::new(
            n,
            size,
            periodic,
            lower,
            upper,
            s_crit + skin,
            skin,
            d_max + s_crit + skin,
        );
        let mut r: [Vec<f64>; 6] = std::array::from_fn(|_| vec![0.0; D * n]);
        for i in 0..n {
            for k in 0..D {
                r[0][k * n + i] = init.position[i][k];
                r[1][k * n + i] = init.velocity[i][k];
            }
        }
        let wall_kr = init
            .radius
            .iter()
            .map(|&ri| stiffness * ri.sqrt())
            .collect();
        let mut engine = Self {
            p,
            n,
            steps: 0,
            r,
            predicted: false,
            acc: vec![0.0; D * n],
            acc_is_start: false,
            radius: init.radius,
            wall_kr,
            wall_contact: vec![0; D * n],
            pair_f: Vec::new(),
            body_f: Vec::new(),
            pair_books: Vec::new(),
            chunk_books: Vec::new(),
            body_work: Vec::new(),
            list,
            moved_bound: 0.0,
            since_check: 0,
            counts: EventCounts::default(),
            dissipated_damping: 0.0,
            dissipated_bridges: 0.0,
            work_by_drive: 0.0,
            max_overlap: 0.0,
            body,
            domain_mode: DomainMode::Auto,
            domains: DomainCache::default(),
            team_steps: 0,
            partitions: 0,
            regions: 0,
            team_door: super::team::DOOR_WAIT,
            parallel_min: PARALLEL_MIN_PARTICLES,
        };
        engine.list.build(&engine.r[0], &engine.radius);
        let mut t0 = 0.0;
        if let Some(st) = start {
            engine.steps = (st.time / engine.p.dt).round() as u64;
            t0 = engine.time();
            if WET {
                for &(i, j) in &st.bridges {
                    assert!(
                        engine.list.set_flag(i, j, BOND),
                        "saved bridge {i}-{j} is beyond the interaction range"
                    );
                }
            }
            engine.counts = st.counts.clone();
            engine.dissipated_damping = st.ledger.dissipated_restitution;
            engine.dissipated_bridges = st.ledger.dissipated_ruptures;
            engine.work_by_drive = st.ledger.work_by_drive;
        }
        // Initial accelerations; the bookkeeping of this evaluation is not a step (dt = 0).
        engine.forces_then(t0, 1.0, 0.0, Then::Nothing);
        if engine.p.integrator == IntegratorKind::Gear5 {
            let dt = engine.p.dt;
            for e in 0..D * n {
                engine.r[1][e] *= dt;
                engine.r[2][e] = 0.5 * dt * dt * engine.acc[e];
            }
        }
        engine
    }

    /// Position and scaled velocity (`r_0`, `r_1`) of the current step at flat index `e`. For
    /// Gear between steps `r` holds the prediction for the next step, and the corrected values
    /// are recovered by [`gear_unpredict`] (equal to the corrector's output up to round-off),
    /// the position wrapped into the box on periodic axes.
    fn now_at(&self, e: usize) -> (f64, f64) {
        if !self.predicted {
            return (self.r[0][e], self.r[1][e]);
        }
        let a = gear_unpredict(std::array::from_fn(|k| self.r[k][e]));
        let k = e / self.n;
        let mut x = a[0];
        if self.p.periodic[k] {
            let l = self.p.size[k];
            if x < 0.0 {
                x += l;
            } else if x >= l {
                x -= l;
            }
        }
        (x, a[1])
    }

    /// Positions of the current step, axis-major.
    fn x_now(&self) -> Cow<'_, [f64]> {
        if self.predicted {
            Cow::Owned((0..D * self.n).map(|e| self.now_at(e).0).collect())
        } else {
            Cow::Borrowed(&self.r[0])
        }
    }

    /// Velocities of the current step (times [`Self::velocity_scale`]), axis-major.
    fn v_now(&self) -> Cow<'_, [f64]> {
        if self.predicted {
            Cow::Owned((0..D * self.n).map(|e| self.now_at(e).1).collect())
        } else {
            Cow::Borrowed(&self.r[1])
        }
    }

    /// Number of particles.
    pub fn len(&self) -> usize {
        self.n
    }

    /// Whether the engine holds no particle.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// Current time, `steps * dt`.
    pub fn time(&self) -> f64 {
        self.steps as f64 * self.p.dt
    }

    /// Steps taken.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// The time step.
    pub fn dt(&self) -> f64 {
        self.p.dt
    }

    /// Neighbour-list builds so far.
    pub fn list_builds(&self) -> u64 {
        self.list.builds
    }

    /// Entries of the Verlet list.
    pub fn list_entries(&self) -> usize {
        self.list.partner.len()
    }

    /// Contact onsets (pair, wall), bridge formations and ruptures so far.
    pub fn counts(&self) -> &EventCounts {
        &self.counts
    }

    /// Largest pair or wall overlap seen at any force evaluation, in units of `d`.
    pub fn max_overlap(&self) -> f64 {
        self.max_overlap / self.p.diameter
    }

    /// Factor turning `r[1]` into a velocity.
    fn velocity_scale(&self) -> f64 {
        match self.p.integrator {
            IntegratorKind::Gear5 => 1.0 / self.p.dt,
            IntegratorKind::Verlet => 1.0,
        }
    }

    /// Position of particle `i` (scene order).
    pub fn position(&self, i: usize) -> [f64; D] {
        std::array::from_fn(|k| self.now_at(k * self.n + i).0)
    }

    /// Velocity of particle `i`.
    pub fn velocity(&self, i: usize) -> [f64; D] {
        let s = self.velocity_scale();
        std::array::from_fn(|k| self.now_at(k * self.n + i).1 * s)
    }

    /// Particle radii.
    pub fn radii(&self) -> &[f64] {
        &self.radius
    }

    /// Overwrites position and velocity of particle `i` (tests and set-ups); the higher Gear
    /// derivatives are reset to zero and the neighbour list rebuilt.
    pub fn set_state(&mut self, i: usize, x: [f64; D], v: [f64; D]) {
        let n = self.n;
        let dt = self.p.dt;
        if self.predicted {
            // Back to the corrected state of the current step: the inverse of the predictor.
            for e in 0..D * n {
                let (x, _) = self.now_at(e);
                let a = gear_unpredict(std::array::from_fn(|k| self.r[k][e]));
                for (k, ak) in a.into_iter().enumerate() {
                    self.r[k][e] = ak;
                }
                self.r[0][e] = x;
            }
            self.predicted = false;
        }
        for k in 0..D {
            self.r[0][k * n + i] = x[k];
            self.r[1][k * n + i] = match self.p.integrator {
                IntegratorKind::Gear5 => v[k] * dt,
                IntegratorKind::Verlet => v[k],
            };
            for r in &mut self.r[2..] {
                r[k * n + i] = 0.0;
            }
        }
        self.list.build(&self.r[0], &self.radius);
        self.domains.0 = None;
        self.moved_bound = 0.0;
        let t = self.time();
        self.forces_then(t, self.velocity_scale(), 0.0, Then::Nothing);
        if self.p.integrator == IntegratorKind::Gear5 {
            for e in 0..D * n {
                self.r[2][e] = 0.5 * dt * dt * self.acc[e];
            }
        }
    }

    /// Capillary bridges as pairs `(i, j)`, `i < j`, sorted.
    pub fn bridges(&self) -> Vec<(usize, usize)> {
        if WET {
            self.list.flagged(BOND)
        } else {
            Vec::new()
        }
    }

    /// Number of capillary bridges.
    pub fn bridge_count(&self) -> usize {
        if WET { self.list.count(BOND) } else { 0 }
    }

    /// Splits a step over the threads of the current rayon pool from `n` particles on
    /// (default [`PARALLEL_MIN_PARTICLES`]): tests and `wetgran-bench tdmd --threads` lower it
    /// to run the parallel path on small systems. The numbers do not depend on it.
    pub fn set_parallel_min_particles(&mut self, n: usize) {
        self.parallel_min = n;
    }
}
