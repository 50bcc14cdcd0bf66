//! The time-driven engine: soft disks (`D = 2`) and spheres (`D = 3`) with damped Hertz contacts
//! (MODEL.md 2.2, Eq. 2.7), the minimal capillary model (MODEL.md 3.1), gravity, periodic lateral
//! axes, static or sinusoidally shaken Hertz floor and lid (MODEL.md 4.1) and an optional body
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
//!   xi^(5/2)`), and the bridge energy `F_B s` of every bonded pair (MODEL.md 3.1: zero at
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

/// A force per particle that depends on its position and the time (hook for driving by a body
/// force, e.g. the shear force of MODEL.md 4.2). Its work is booked in `work_by_drive`.
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

/// Below this many particles (the default of [`parallel_min_particles`]) the loops of a step
/// run on the calling thread (same chunks, same numbers): a parallel loop costs a few
/// microseconds of hand-over per step. Measured on a quiet 2-core machine (docs/performance.md,
/// "Quiet-machine figures"): two threads made the N = 1200 bench 0.69x as fast, 4 800 disks
/// about even, 19 200 at most 1.37x; 512 before that measurement.
pub const PARALLEL_MIN_PARTICLES: usize = 16_384;

static PARALLEL_MIN: std::sync::atomic::AtomicUsize =
    std::sync::atomic::AtomicUsize::new(PARALLEL_MIN_PARTICLES);

/// The fewest particles for which a step is split over threads (process-wide; default
/// [`PARALLEL_MIN_PARTICLES`]).
pub fn parallel_min_particles() -> usize {
    PARALLEL_MIN.load(std::sync::atomic::Ordering::Relaxed)
}

/// Sets [`parallel_min_particles`] for the whole process: tests and `bench tdmd --threads` use a
/// small value to run the parallel path on small systems (the numbers do not depend on it).
pub fn set_parallel_min_particles(n: usize) {
    PARALLEL_MIN.store(n, std::sync::atomic::Ordering::Relaxed);
}

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
    /// `F_B = E_cb / s_crit` (MODEL.md 3.1).
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

    /// Wraps periodic coordinates of `r[0]` into `[0, L)` (Verlet, and the first Gear
    /// prediction; afterwards the Gear loop wraps its own output).
    fn wrap(&mut self) {
        let n = self.n;
        for k in 0..D {
            if !self.p.periodic[k] {
                continue;
            }
            let l = self.p.size[k];
            for x in &mut self.r[0][k * n..(k + 1) * n] {
                if *x < 0.0 {
                    *x += l;
                } else if *x >= l {
                    *x -= l;
                }
            }
        }
    }

    /// Keeps the Verlet list valid: rebuilds it when some particle has moved more than
    /// `skin / 2` since the last build. The exact test (a pass over all positions,
    /// [`NeighbourList::needs_rebuild`]) runs only when the bound `moved_bound` reaches
    /// `skin / 2` (less a relative margin of `1e-6` for its round-off) or after
    /// [`EXACT_CHECK_EVERY`] steps; otherwise no particle can have moved that far (each
    /// particle's displacement is at most the sum of the per-step largest moves), so the
    /// decision is the one the exact test would take. After an exact test the bound restarts
    /// from the exact largest displacement.
    fn update_list(&mut self) {
        self.since_check += 1;
        let half_skin = 0.5 * self.list.skin();
        if self.moved_bound < half_skin * (1.0 - 1e-6) && self.since_check < EXACT_CHECK_EVERY {
            return;
        }
        self.since_check = 0;
        let worst = self.list.max_displacement_sq(&self.r[0]);
        if worst > half_skin * half_skin {
            self.list.build(&self.r[0], &self.radius);
            self.moved_bound = 0.0;
        } else {
            self.moved_bound = worst.sqrt();
        }
    }

    /// One time step of the scene's integrator.
    pub fn step(&mut self) {
        if self.predicted && self.uses_domains() {
            let target = self.steps + 1;
            self.domain_region(target);
            return;
        }
        self.step_alone();
    }

    /// One step of the serial (or rayon-split) path.
    fn step_alone(&mut self) {
        let dt = self.p.dt;
        let t1 = (self.steps + 1) as f64 * dt;
        match self.p.integrator {
            IntegratorKind::Gear5 => {
                if !self.predicted {
                    gear_predict(&mut self.r);
                    self.wrap();
                    // The predictor's moves are not tracked: force the exact test.
                    self.moved_bound = f64::INFINITY;
                }
                self.update_list();
                // Forces, then the corrector of this step, the predictor of the next, the wrap
                // of both positions and the largest move per axis, in one pass per chunk.
                let moved = self.forces_then(t1, 1.0 / dt, dt, Then::Gear);
                let mut moved2 = 0.0;
                for m in moved {
                    moved2 += m * m;
                }
                self.moved_bound += moved2.sqrt();
                self.predicted = true;
            }
            IntegratorKind::Verlet => {
                let moved = self.verlet_drift_wrap(dt);
                let mut moved2 = 0.0;
                for m in moved {
                    moved2 += m * m;
                }
                self.moved_bound += moved2.sqrt();
                self.update_list();
                self.forces_then(t1, 1.0, dt, Then::VerletKick);
            }
        }
        self.steps += 1;
    }

    /// Runs until the time is the multiple of `dt` nearest to `t_end`. Always returns true (the
    /// time engine has no event cap). Runs on the thread pool `sim::threads` chooses.
    pub fn run_until(&mut self, t_end: f64) -> bool {
        let target = (t_end / self.p.dt).round().max(0.0) as u64;
        if self.steps >= target {
            return true;
        }
        crate::sim::threads::install(|| {
            while self.steps < target {
                if self.predicted && self.uses_domains() {
                    self.domain_region(target);
                } else {
                    self.step_alone();
                }
            }
        });
        true
    }

    /// Chooses which Gear steps run on the spatial domains ([`DomainMode`]; tests and benches).
    pub fn set_domain_mode(&mut self, mode: DomainMode) {
        self.domain_mode = mode;
    }

    /// Gear steps so far that ran on the domains with a team of more than one thread (the
    /// others ran on one thread, which gives the same numbers).
    pub fn team_steps(&self) -> u64 {
        self.team_steps
    }

    /// Whether the Gear steps run on the spatial domains: Gear, no body force, and
    /// [`DOMAIN_MIN_PARTICLES`] particles or more (or as [`Self::set_domain_mode`] says). The
    /// number of threads plays no part, so the numbers do not depend on it.
    fn uses_domains(&self) -> bool {
        self.p.integrator == IntegratorKind::Gear5
            && !B::ACTIVE
            && self.n >= DOMAINS
            && match self.domain_mode {
                DomainMode::Auto => self.n >= DOMAIN_MIN_PARTICLES,
                DomainMode::Always => true,
                DomainMode::Never => false,
            }
    }

    /// The arrays the domains copy from and to, and the list flags.
    fn domain_arrays(&mut self) -> (EngineArrays<'_>, &mut [u8]) {
        (
            EngineArrays {
                r: &mut self.r,
                acc: &mut self.acc,
                wall_contact: &mut self.wall_contact,
                radius: &self.radius,
                wall_kr: &self.wall_kr,
            },
            &mut self.list.flags,
        )
    }

    /// Runs Gear steps on the spatial domains (`domains.rs`) until `target` or until a list
    /// build calls for a new partition: the list check of the first step, the decomposition
    /// (kept from the last region, or made from the positions of the current build), the
    /// state copied into the domains, the steps on a team of up to [`DOMAINS`] threads of the
    /// current pool (or on the calling thread alone; the team rebuilds the list itself where
    /// the check asks for it), the state and the books copied back (the books step by step,
    /// domains in order, as one sum per step).
    fn domain_region(&mut self, target: u64) {
        let first = self.steps;
        // The last region's domains did the list check of this step already (counting it
        // again would move the exact tests with the region ends).
        let checked = matches!(&self.domains.0, Some(d)
            if d.holds_step == Some(first) && d.checked_for == Some(first));
        if !checked {
            self.update_list();
        }
        let builds = self.list.builds;
        let kept = match self.domains.0.take() {
            Some(d)
                if d.holds_step == Some(first)
                    && (d.built_for() == builds || !d.wants_new_partition(builds)) =>
            {
                Some(d)
            }
            Some(mut old) => {
                // The engine's arrays must hold the whole state before a new partition (the
                // flags came back at the end of the last region; the list is new since).
                if old.partial {
                    let (mut arrays, _) = self.domain_arrays();
                    old.store(&mut arrays, None, true);
                }
                None
            }
            None => None,
        };
        let own_checks = checked && kept.is_some();
        let mut dec = match kept {
            Some(d) => d,
            None => {
                self.partitions += 1;
                let mut d = Box::new(Decomposition::new(
                    builds,
                    self.p.size,
                    self.list.built_at(),
                ));
                let acc_is_start = self.acc_is_start;
                let (arrays, _) = self.domain_arrays();
                d.load(&arrays, acc_is_start, first);
                d
            }
        };
        // A new decomposition has no lists yet; a kept one re-splits after a build.
        if dec.built_for() != builds {
            dec.split_lists(&self.list, &self.radius);
        }
        dec.begin(self.moved_bound, self.since_check, first, own_checks);
        let init = self.force_start();
        let p = &self.p;
        let dt = p.dt;
        let c = StepConstants {
            periodic: p.periodic,
            size: p.size,
            stiffness: p.stiffness,
            damping: p.damping,
            bridge_force: p.bridge_force,
            s_crit: p.s_crit,
            dt,
            inv_mass: (p.mass != 1.0).then(|| 1.0 / p.mass),
            init,
            gear: p.gear,
            half_skin: 0.5 * self.list.skin(),
        };
        let walls_at = |s: u64| wall_axes(p, s as f64 * dt, 1.0 / dt, dt);
        let flush_at = |s: u64| s.is_multiple_of(GEAR_FLUSH_EVERY);
        self.regions += 1;
        let dec_ref: &Decomposition<D> = &dec;
        // The team rebuilds the list itself (its threads stay awake) and goes on.
        let build = TeamBuild::new(&mut self.list, &mut self.r[0], &self.radius);
        let member = |slot: usize, members: usize, wait: &dyn Fn()| {
            dec_ref.run_member::<WET>(
                &c, &walls_at, &flush_at, &build, slot, members, first, target, wait,
            )
        };
        let ((done, end), members) = if rayon::current_num_threads() > 1 {
            let out = super::team::run_with_door(DOMAINS, self.team_door, |m| {
                (member(m.slot, m.members, &|| m.wait()), m.members)
            });
            out[0]
        } else {
            super::team::solo(|m| (member(0, 1, &|| m.wait()), 1))
        };
        drop(build);
        self.acc_is_start = true;
        self.steps += done;
        if members > 1 {
            self.team_steps += done;
        }
        // Between regions of one run only the positions (for the list build) and the flags
        // come back; at the end of the run everything does.
        let full = end == RegionEnd::Target || self.steps >= target;
        // After a build for a new partition the domains' lists are those of the build before:
        // their flags are in the list already.
        let lists_current = dec.built_for() == self.list.builds;
        let (mut arrays, flags) = self.domain_arrays();
        dec.store(&mut arrays, lists_current.then_some(flags), full);
        dec.partial = !full;
        dec.holds_step = Some(self.steps);
        dec.checked_for = (end != RegionEnd::Rebuild).then_some(self.steps);
        let (books, bound, since) = dec.books();
        self.domains.0 = Some(dec);
        for s in 0..done as usize {
            for (_, steps) in &books {
                let [diss, ledger, work] = steps[s];
                self.dissipated_damping += diss;
                self.dissipated_bridges += ledger;
                self.work_by_drive += work;
            }
        }
        for (b, _) in &books {
            self.max_overlap = self.max_overlap.max(b.max_overlap);
            self.counts.pair_collisions += b.pair_onsets;
            self.counts.wall_collisions += b.wall_onsets;
            self.counts.bridge_formations += b.formations;
            self.counts.bridge_ruptures += b.ruptures;
        }
        match end {
            // The check of the next step found a particle beyond half the skin: the next
            // `update_list` runs the exact test (and rebuilds).
            RegionEnd::Rebuild => self.moved_bound = f64::INFINITY,
            // The team built the list (as `update_list` would have); the next region makes
            // the new partition.
            RegionEnd::Repartition => {
                self.moved_bound = 0.0;
                self.since_check = 0;
            }
            RegionEnd::Target => {
                self.moved_bound = bound;
                self.since_check = since;
            }
        }
    }

    /// Whether the loops of a step are split over threads: on a pool of more than one thread
    /// and from [`parallel_min_particles`] particles on; otherwise the serial path runs on the
    /// calling thread, without the pool. The numbers are the same either way.
    fn parallel(&self) -> bool {
        self.n >= parallel_min_particles() && rayon::current_num_threads() > 1
    }

    /// The force every coordinate starts from: the weight `-m g` on the last axis (with
    /// gravity), 0 elsewhere.
    fn force_start(&self) -> [f64; D] {
        let mut start = [0.0; D];
        if GRAV {
            start[D - 1] = -self.p.mass * self.p.gravity;
        }
        start
    }

    /// Velocity Verlet's first half on every coordinate (`verlet_drift`), with the wrap of the
    /// periodic axes; returns the largest move per axis.
    fn verlet_drift_wrap(&mut self, dt: f64) -> [f64; D] {
        let n = self.n;
        let min_len = if self.parallel() { 1 } else { usize::MAX };
        let (periodic, size) = (self.p.periodic, self.p.size);
        let start = self.force_start();
        self.acc_is_start = true;
        let [x, v, ..] = &mut self.r;
        let drift = |e0: usize, x: &mut [f64], v: &mut [f64], acc: &mut [f64]| {
            let mut moved = [0.0; D];
            for_each_axis_segment(n, e0, x.len(), |k, o, m| {
                let (x, v, acc) = (&mut x[o..o + m], &mut v[o..o + m], &mut acc[o..o + m]);
                let step_move = verlet_drift(x, v, acc, start[k], dt);
                moved[k] = max_ignoring_nan(moved[k], step_move);
                if periodic[k] {
                    wrap_slice(x, size[k]);
                }
            });
            moved
        };
        (
            x.par_chunks_mut(PARTICLE_CHUNK),
            v.par_chunks_mut(PARTICLE_CHUNK),
            self.acc.par_chunks_mut(PARTICLE_CHUNK),
        )
            .into_par_iter()
            .enumerate()
            .with_min_len(min_len)
            .map(|(c, (x, v, acc))| drift(c * PARTICLE_CHUNK, x, v, acc))
            .reduce(
                || [0.0; D],
                |a, b| std::array::from_fn(|k| max_ignoring_nan(a[k], b[k])),
            )
    }

    /// Accelerations at positions `r[0]` and velocities `r[1] * vs` at time `t`, then `then`
    /// (the Gear corrector-predictor or Verlet's second half); books dissipation, drive work,
    /// contact onsets and bridge events with weight `dt` (0: a re-evaluation that is not a
    /// step). Returns the largest move per axis of the Gear update (zeros otherwise).
    ///
    /// Two parallel phases, each over fixed chunks whose results are combined in chunk order,
    /// so the numbers do not depend on the number of threads:
    ///
    /// 1. the pair forces of every Verlet-list entry (each pair once), into a buffer, with the
    ///    contact and bridge flags ([`pair_chunk`], chunks of [`ENTRY_CHUNK`] entries);
    /// 2. per chunk of [`PARTICLE_CHUNK`] coordinates: the weight, the pair forces gathered in
    ///    the order the half list's rows visit them (the partners' rows, ascending, then the
    ///    particle's own row), the walls, the body force, `1/m`, then `then`
    ///    ([`particle_chunk`]).
    ///
    /// The accelerations are the same bits as a single loop that scatters each pair force to
    /// both partners; the booked sums (dissipation, drive work, bridge energy) are summed per
    /// chunk, so they differ from a single running sum by round-off.
    fn forces_then(&mut self, t: f64, vs: f64, dt: f64, then: Then) -> [f64; D] {
        if self.parallel() {
            self.forces_then_parallel(t, vs, dt, then)
        } else {
            self.forces_then_serial(t, vs, dt, then)
        }
    }

    /// [`Self::forces_then`] on the calling thread, as one loop per kind of force: the pair
    /// loop scatters each pair force to both partners (rows ascending, so every particle
    /// receives its partners' forces in the order the parallel gather adds them), then walls,
    /// body force, `1/m` and `then` per axis. The booked sums are taken per chunk as in the
    /// parallel path, so both paths give the same bits (`crates/core/tests/time_driven_pins.rs` runs each
    /// pin on one thread, this path, and on two, the parallel one); this one does less work
    /// (no per-entry force buffer, no gather).
    fn forces_then_serial(&mut self, t: f64, vs: f64, dt: f64, then: Then) -> [f64; D] {
        let n = self.n;
        let init = self.force_start();
        let p = &self.p;
        let f = &mut self.acc;
        if !self.acc_is_start {
            for k in 0..D {
                f[k * n..(k + 1) * n].fill(init[k]);
            }
        }
        // The integrator pass below leaves the start values for the next evaluation.
        self.acc_is_start = then == Then::Gear;
        let pc = PairConstants {
            periodic: p.periodic,
            size: p.size,
            stiffness: p.stiffness,
            damping: p.damping,
            bridge_force: p.bridge_force,
            s_crit: p.s_crit,
            vs,
            dt,
        };
        let list = &mut self.list;
        let pb = pair_forces_serial::<D, WET>(
            &pc,
            &self.r[0],
            &self.r[1],
            f,
            &self.radius,
            &list.start,
            &list.rows,
            &list.partner,
            &mut list.flags,
        );
        self.counts.pair_collisions += pb.onsets;
        self.counts.bridge_formations += pb.formations;
        self.counts.bridge_ruptures += pb.ruptures;
        self.dissipated_bridges += pb.bridge_ledger;
        let mut diss = pb.dissipated;
        let mut max_ov = self.max_overlap.max(pb.max_overlap);
        // Walls per chunk of coordinates, the chunks of the parallel path, each chunk's
        // dissipation and work summed on its own and added in order (a chunk that booked
        // nothing adds +0 and changes nothing).
        let mut work = 0.0;
        let walls = wall_axes(p, t, vs, dt);
        let x = &self.r[0];
        let v = &self.r[1];
        if p.periodic.iter().any(|&periodic| !periodic) {
            for e0 in (0..D * n).step_by(PARTICLE_CHUNK) {
                let mut part = WallBooks::default();
                for_each_axis_segment(n, e0, PARTICLE_CHUNK.min(D * n - e0), |k, o, m| {
                    if p.periodic[k] {
                        return;
                    }
                    let (e, i) = (e0 + o, e0 + o - k * n);
                    wall_forces(
                        &walls[k],
                        &x[e..e + m],
                        &v[e..e + m],
                        &self.radius[i..i + m],
                        &self.wall_kr[i..i + m],
                        &mut self.wall_contact[e..e + m],
                        &mut f[e..e + m],
                        &mut part,
                    );
                });
                diss += part.dissipated;
                work += part.work;
                max_ov = max_ov.max(part.max_overlap);
                self.counts.wall_collisions += part.onsets;
            }
        }
        if B::ACTIVE {
            let (mut part, mut part_chunk) = (0.0, 0usize);
            for i in 0..n {
                let xi: [f64; D] = std::array::from_fn(|k| x[k * n + i]);
                let fb = self.body.force(&xi, t);
                if i / PARTICLE_CHUNK != part_chunk {
                    work += part;
                    (part, part_chunk) = (0.0, i / PARTICLE_CHUNK);
                }
                for k in 0..D {
                    f[k * n + i] += fb[k];
                    part += fb[k] * v[k * n + i] * vs * dt;
                }
            }
            work += part;
        }
        // a = F / m.
        if p.mass != 1.0 {
            let inv_m = 1.0 / p.mass;
            for e in f.iter_mut() {
                *e *= inv_m;
            }
        }
        self.dissipated_damping += diss;
        self.work_by_drive += work;
        self.max_overlap = max_ov;
        let mut moved = [0.0; D];
        let flush = self.steps.is_multiple_of(GEAR_FLUSH_EVERY);
        match then {
            Then::Nothing => {}
            Then::Gear => {
                let c = p.gear;
                let [r0, r1, r2, r3, r4, r5] = &mut self.r;
                for k in 0..D {
                    let a = k * n..(k + 1) * n;
                    moved[k] = gear_correct_predict_axis(
                        [
                            &mut r0[a.clone()],
                            &mut r1[a.clone()],
                            &mut r2[a.clone()],
                            &mut r3[a.clone()],
                            &mut r4[a.clone()],
                            &mut r5[a.clone()],
                        ],
                        &mut f[a],
                        init[k],
                        0.5 * p.dt * p.dt,
                        &c,
                        p.periodic[k].then_some(p.size[k]),
                        flush,
                    );
                }
            }
            Then::VerletKick => verlet_kick(&mut self.r[1], f, dt),
        }
        moved
    }

    /// [`Self::forces_then`] split over the pool's threads (see there).
    fn forces_then_parallel(&mut self, t: f64, vs: f64, dt: f64, then: Then) -> [f64; D] {
        self.list.ensure_transposed();
        let n = self.n;
        let min_len = 1;
        let p = &self.p;
        let entries = self.list.partner.len();
        self.pair_f.resize(D * entries, 0.0);
        let pc = PairConstants {
            periodic: p.periodic,
            size: p.size,
            stiffness: p.stiffness,
            damping: p.damping,
            bridge_force: p.bridge_force,
            s_crit: p.s_crit,
            vs,
            dt,
        };
        {
            let (x, v, radius) = (&self.r[0], &self.r[1], &self.radius);
            let (row_of, partner) = (&self.list.row_of, &self.list.partner);
            self.list
                .flags
                .par_chunks_mut(ENTRY_CHUNK)
                .zip(self.pair_f.par_chunks_mut(ENTRY_CHUNK * D))
                .enumerate()
                .with_min_len(min_len)
                .map(|(c, (flags, pf))| {
                    let q0 = c * ENTRY_CHUNK;
                    pair_chunk::<D, WET>(
                        &pc,
                        x,
                        v,
                        radius,
                        &row_of[q0..],
                        &partner[q0..],
                        flags,
                        pf,
                    )
                })
                .collect_into_vec(&mut self.pair_books);
        }
        let mut diss = 0.0;
        let mut ledger = 0.0;
        let mut max_ov = self.max_overlap;
        for b in &self.pair_books {
            diss += b.dissipated;
            ledger += b.bridge_ledger;
            max_ov = max_ov.max(b.max_overlap);
            self.counts.pair_collisions += b.onsets;
            self.counts.bridge_formations += b.formations;
            self.counts.bridge_ruptures += b.ruptures;
        }
        self.dissipated_bridges += ledger;
        // The body force per particle (all axes at once), particle-major, with its work.
        self.body_work.clear();
        if B::ACTIVE {
            self.body_f.resize(D * n, 0.0);
            let (x, v, body) = (&self.r[0], &self.r[1], &self.body);
            self.body_f
                .par_chunks_mut(PARTICLE_CHUNK * D)
                .enumerate()
                .with_min_len(min_len)
                .map(|(c, bf)| {
                    let i0 = c * PARTICLE_CHUNK;
                    let mut work = 0.0;
                    for (m, out) in bf.chunks_mut(D).enumerate() {
                        let i = i0 + m;
                        let xi: [f64; D] = std::array::from_fn(|k| x[k * n + i]);
                        let fb = body.force(&xi, t);
                        for k in 0..D {
                            out[k] = fb[k];
                            work += fb[k] * v[k * n + i] * vs * dt;
                        }
                    }
                    work
                })
                .collect_into_vec(&mut self.body_work);
        }
        let init = self.force_start();
        // The Gear pass leaves the start values for the next evaluation.
        self.acc_is_start = then == Then::Gear;
        let cx = ChunkContext::<D> {
            n,
            pf: &self.pair_f,
            start: &self.list.start,
            row_of: &self.list.row_of,
            partner: &self.list.partner,
            in_start: &self.list.in_start,
            in_entry: &self.list.in_entry,
            radius: &self.radius,
            wall_kr: &self.wall_kr,
            body_f: if B::ACTIVE { &self.body_f } else { &[] },
            init,
            periodic: p.periodic,
            size: p.size,
            walls: wall_axes(p, t, vs, dt),
            inv_mass: (p.mass != 1.0).then(|| 1.0 / p.mass),
            dt,
            then,
            gear: p.gear,
            half_dt2: 0.5 * p.dt * p.dt,
            flush: self.steps.is_multiple_of(GEAR_FLUSH_EVERY),
        };
        let [r0, r1, r2, r3, r4, r5] = &mut self.r;
        (
            self.acc.par_chunks_mut(PARTICLE_CHUNK),
            r0.par_chunks_mut(PARTICLE_CHUNK),
            r1.par_chunks_mut(PARTICLE_CHUNK),
            r2.par_chunks_mut(PARTICLE_CHUNK),
            r3.par_chunks_mut(PARTICLE_CHUNK),
            r4.par_chunks_mut(PARTICLE_CHUNK),
            r5.par_chunks_mut(PARTICLE_CHUNK),
            self.wall_contact.par_chunks_mut(PARTICLE_CHUNK),
        )
            .into_par_iter()
            .enumerate()
            .with_min_len(min_len)
            .map(|(c, (acc, r0, r1, r2, r3, r4, r5, touch))| {
                particle_chunk(
                    &cx,
                    c * PARTICLE_CHUNK,
                    acc,
                    [r0, r1, r2, r3, r4, r5],
                    touch,
                )
            })
            .collect_into_vec(&mut self.chunk_books);
        let mut work = 0.0;
        let mut moved = [0.0; D];
        for b in &self.chunk_books {
            diss += b.walls.dissipated;
            work += b.walls.work;
            max_ov = max_ov.max(b.walls.max_overlap);
            self.counts.wall_collisions += b.walls.onsets;
            for k in 0..D {
                moved[k] = max_ignoring_nan(moved[k], b.moved[k]);
            }
        }
        for w in &self.body_work {
            work += w;
        }
        self.dissipated_damping += diss;
        self.work_by_drive += work;
        self.max_overlap = max_ov;
        moved
    }

    /// Energy bookkeeping at the current time (see the module doc for the fields).
    pub fn energy(&self) -> EnergyLedger {
        let n = self.n;
        let p = &self.p;
        let vs = self.velocity_scale();
        let x = self.x_now();
        let v = self.v_now();
        let mut kinetic = 0.0;
        for e in 0..D * n {
            let ve = v[e] * vs;
            kinetic += 0.5 * p.mass * ve * ve;
        }
        let mut potential = 0.0;
        if GRAV {
            potential += x[(D - 1) * n..]
                .iter()
                .map(|z| p.mass * p.gravity * z)
                .sum::<f64>();
        }
        for i in 0..n {
            for q in self.list.start[i] as usize..self.list.start[i + 1] as usize {
                let j = self.list.partner[q] as usize;
                let r = self.distance(i, j);
                let sig = self.radius[i] + self.radius[j];
                if r < sig {
                    let kr = p.stiffness * (self.radius[i] * self.radius[j] / sig).sqrt();
                    potential += hertz::elastic_energy(kr, sig - r);
                }
                if WET && self.list.flags[q] & BOND != 0 {
                    potential += p.bridge_force * (r - sig);
                }
            }
        }
        let t = self.time();
        let zw = p.drive.map_or(0.0, |(a, w)| a * (w * t).sin());
        for k in 0..D {
            if p.periodic[k] {
                continue;
            }
            let shift = if k == D - 1 { zw } else { 0.0 };
            for i in 0..n {
                let xk = x[k * n + i];
                let ri = self.radius[i];
                for ov in [ri - (xk - shift), xk + ri - (p.size[k] + shift)] {
                    if ov > 0.0 {
                        potential += hertz::elastic_energy(self.wall_kr[i], ov);
                    }
                }
            }
        }
        EnergyLedger {
            kinetic,
            potential,
            dissipated_restitution: self.dissipated_damping,
            dissipated_ruptures: self.dissipated_bridges,
            added_by_collapse_remedies: 0.0,
            added_by_wall_placement: 0.0,
            work_by_drive: self.work_by_drive,
        }
    }

    /// Centre distance of `i` and `j` (nearest image).
    fn distance(&self, i: usize, j: usize) -> f64 {
        let n = self.n;
        let mut r2 = 0.0;
        for k in 0..D {
            let mut d = self.now_at(k * n + i).0 - self.now_at(k * n + j).0;
            if self.p.periodic[k] {
                let l = self.p.size[k];
                d -= l * (d / l).round();
            }
            r2 += d * d;
        }
        r2.sqrt()
    }

    /// Total momentum.
    pub fn momentum(&self) -> [f64; D] {
        let vs = self.velocity_scale();
        let v = self.v_now();
        std::array::from_fn(|k| {
            v[k * self.n..(k + 1) * self.n].iter().sum::<f64>() * vs * self.p.mass
        })
    }

    /// Granular temperature `T_g = m (<v^2> - <v>^2) / f_d` (Eq. 3.2, `f_d = D`).
    pub fn granular_temperature(&self) -> f64 {
        let n = self.n as f64;
        let vs = self.velocity_scale();
        let mut mean_sq = 0.0;
        let mut mean2 = 0.0;
        let v = self.v_now();
        for k in 0..D {
            let col = &v[k * self.n..(k + 1) * self.n];
            let m = col.iter().sum::<f64>() * vs / n;
            mean_sq += col.iter().map(|v| v * v).sum::<f64>() * vs * vs / n;
            mean2 += m * m;
        }
        self.p.mass * (mean_sq - mean2) / D as f64
    }

    /// Positions flat with stride `D`, scene order.
    pub fn positions_flat(&self) -> Vec<f64> {
        (0..self.n).flat_map(|i| self.position(i)).collect()
    }

    /// Velocities flat with stride `D`, scene order.
    pub fn velocities_flat(&self) -> Vec<f64> {
        (0..self.n).flat_map(|i| self.velocity(i)).collect()
    }

    /// Test aid, `O(N^2)`: the first pair that overlaps (or is within `s_crit` of contact in a
    /// wet scene) but is missing from the Verlet list, which would make its force vanish.
    pub fn pair_missing_from_list(&self) -> Option<(usize, usize)> {
        let reach = if WET { self.p.s_crit } else { 0.0 };
        for i in 0..self.n {
            let row =
                &self.list.partner[self.list.start[i] as usize..self.list.start[i + 1] as usize];
            for j in i + 1..self.n {
                let r = self.distance(i, j);
                if r < self.radius[i] + self.radius[j] + reach
                    && row.binary_search(&(j as u32)).is_err()
                {
                    return Some((i, j));
                }
            }
        }
        None
    }

    /// Checks the invariants: finite numbers; every centre inside the box (between the walls at
    /// their current position); no pair or wall overlap beyond [`SANITY_OVERLAP`] `d`; no
    /// bridge stretched beyond `s_crit` by more than the same amount; no pair in contact or
    /// bonded lost from the neighbour list. Returns the first violation.
    pub fn sanity_check(&self) -> Result<(), String> {
        let n = self.n;
        let t = self.time();
        let tol = SANITY_OVERLAP * self.p.diameter;
        let zw = self.p.drive.map_or(0.0, |(a, w)| a * (w * t).sin());
        if let Some((i, j)) = self.list.lost_pair {
            return Err(format!(
                "flagged pair {i}-{j} (in contact or bonded) left the neighbour list: it moved \
                 apart by more than the skin between two list builds, a blown-up run (engine.dt \
                 too large for the speeds reached); at t = {t}"
            ));
        }
        for i in 0..n {
            let x = self.position(i);
            let v = self.velocity(i);
            if !x.iter().chain(v.iter()).all(|a| a.is_finite()) {
                return Err(format!("particle {i} has a non-finite state at t = {t}"));
            }
            for k in 0..D {
                let (lo, hi) = if self.p.periodic[k] {
                    (0.0, self.p.size[k])
                } else {
                    let s = if k == D - 1 { zw } else { 0.0 };
                    (
                        s + self.radius[i] - tol,
                        self.p.size[k] + s - self.radius[i] + tol,
                    )
                };
                if x[k] < lo || x[k] > hi {
                    return Err(format!(
                        "particle {i} is outside the box along axis {k}: x = {} not in [{lo}, {hi}] at t = {t}",
                        x[k]
                    ));
                }
            }
        }
        for i in 0..n {
            for q in self.list.start[i] as usize..self.list.start[i + 1] as usize {
                let j = self.list.partner[q] as usize;
                let r = self.distance(i, j);
                let sig = self.radius[i] + self.radius[j];
                if sig - r > tol {
                    return Err(format!(
                        "particles {i} and {j} overlap by {} at t = {t}",
                        sig - r
                    ));
                }
                if WET && self.list.flags[q] & BOND != 0 && r - sig > self.p.s_crit + tol {
                    return Err(format!(
                        "bonded pair {i}-{j} stretched beyond s_crit by {} at t = {t}",
                        r - sig - self.p.s_crit
                    ));
                }
            }
        }
        Ok(())
    }
}

/// The walls of every axis at time `t` (used on the non-periodic ones): Hertz with
/// `R_eff = R_i`; the last axis's walls move with the drive, `z_w(t) = A sin(omega t)`
/// (MODEL.md 4.1). `vs` turns the velocity array into velocities, `dt` weights the books.
fn wall_axes<const D: usize>(p: &Params<D>, t: f64, vs: f64, dt: f64) -> [WallAxis; D] {
    let (zw, vw) = match p.drive {
        Some((a, w)) => (a * (w * t).sin(), a * w * (w * t).cos()),
        None => (0.0, 0.0),
    };
    std::array::from_fn(|k| {
        let (shift, velocity) = if k == D - 1 { (zw, vw) } else { (0.0, 0.0) };
        WallAxis::new(
            shift,
            p.size[k] + shift,
            velocity,
            vs,
            p.wall_damping,
            dt,
            p.max_radius,
        )
    })
}

/// What the per-particle phase does after the forces ([`TimeEngine::forces_then`]).
#[derive(Debug, Clone, Copy, PartialEq)]
enum Then {
    /// Nothing (the initial forces, a re-evaluation after `set_state`).
    Nothing,
    /// Gear's corrector of this step fused with the predictor of the next.
    Gear,
    /// Velocity Verlet's second half, `v += a dt / 2`.
    VerletKick,
}

/// What one chunk of the per-particle phase books.
#[derive(Debug, Clone, Copy)]
struct ChunkBooks<const D: usize> {
    walls: WallBooks,
    /// Largest move of a predicted position per axis (Gear).
    moved: [f64; D],
}

/// What the per-particle phase reads (shared by every chunk).
struct ChunkContext<'a, const D: usize> {
    n: usize,
    /// Pair forces per list entry, `D` values each ([`pair_chunk`]).
    pf: &'a [f64],
    start: &'a [u32],
    row_of: &'a [u32],
    partner: &'a [u32],
    in_start: &'a [u32],
    in_entry: &'a [u32],
    radius: &'a [f64],
    wall_kr: &'a [f64],
    /// Body force per particle, particle-major (empty without one).
    body_f: &'a [f64],
    /// The force every coordinate starts from (the weight on the last axis).
    init: [f64; D],
    periodic: [bool; D],
    size: [f64; D],
    /// Per axis: the walls (used on the non-periodic axes).
    walls: [WallAxis; D],
    inv_mass: Option<f64>,
    dt: f64,
    then: Then,
    gear: [f64; 6],
    half_dt2: f64,
    /// Whether this step flushes the Gear derivatives ([`GEAR_FLUSH_EVERY`]).
    flush: bool,
}

/// Splits the flat coordinates `e0..e0 + len` (axis-major, `n` per axis) at the axis
/// boundaries and calls `f(k, offset, m)` for each piece: axis `k`, offset in the chunk, length.
#[inline(always)]
fn for_each_axis_segment(n: usize, e0: usize, len: usize, mut f: impl FnMut(usize, usize, usize)) {
    let mut o = 0;
    while o < len {
        let e = e0 + o;
        let m = (len - o).min(n - e % n);
        f(e / n, o, m);
        o += m;
    }
}

/// `b` if it is larger, else `a` (a NaN `b` is ignored): the running maximum of the integrator
/// loops (`integrator::lane_max`), exact and so independent of the order of the chunks.
#[inline(always)]
fn max_ignoring_nan(a: f64, b: f64) -> f64 {
    if b > a { b } else { a }
}

/// `x < 0: x + L; x >= L: x - L` on every element.
fn wrap_slice(xs: &mut [f64], l: f64) {
    for x in xs {
        if *x < 0.0 {
            *x += l;
        } else if *x >= l {
            *x -= l;
        }
    }
}

/// The per-particle phase on the flat coordinates `e0..e0 + acc.len()` (one chunk, see
/// [`TimeEngine::forces_then`]): `acc` is computed (start value, pair forces gathered in the
/// half list's order, walls, body force, `1/m`), then `cx.then` updates `r`.
fn particle_chunk<const D: usize>(
    cx: &ChunkContext<D>,
    e0: usize,
    acc: &mut [f64],
    r: [&mut [f64]; 6],
    touch: &mut [u8],
) -> ChunkBooks<D> {
    let mut walls = WallBooks::default();
    let mut moved = [0.0; D];
    let n = cx.n;
    let [r0, r1, r2, r3, r4, r5] = r;
    for_each_axis_segment(n, e0, acc.len(), |k, o, m| {
        let i0 = (e0 + o) % n;
        let acc = &mut acc[o..o + m];
        acc.fill(cx.init[k]);
        // The partners' rows, ascending: `f_j -= f_ij`.
        for &q in &cx.in_entry[cx.in_start[i0] as usize..cx.in_start[i0 + m] as usize] {
            let q = q as usize;
            acc[cx.partner[q] as usize - i0] -= cx.pf[q * D + k];
        }
        // The particle's own row, summed first: `f_i += sum_j f_ij`.
        let (mut q, end) = (cx.start[i0] as usize, cx.start[i0 + m] as usize);
        while q < end {
            let i = cx.row_of[q] as usize;
            let row_end = cx.start[i + 1] as usize;
            let mut own = 0.0;
            while q < row_end {
                own += cx.pf[q * D + k];
                q += 1;
            }
            acc[i - i0] += own;
        }
        if !cx.periodic[k] {
            let radius = &cx.radius[i0..i0 + m];
            let wall_kr = &cx.wall_kr[i0..i0 + m];
            let (x, v, touching) = (&r0[o..o + m], &r1[o..o + m], &mut touch[o..o + m]);
            wall_forces(
                &cx.walls[k],
                x,
                v,
                radius,
                wall_kr,
                touching,
                acc,
                &mut walls,
            );
        }
        if !cx.body_f.is_empty() {
            for i in 0..m {
                acc[i] += cx.body_f[(i0 + i) * D + k];
            }
        }
        // a = F / m.
        if let Some(inv_m) = cx.inv_mass {
            for a in acc.iter_mut() {
                *a *= inv_m;
            }
        }
        match cx.then {
            Then::Nothing => {}
            Then::Gear => {
                let s = o..o + m;
                let step_move = gear_correct_predict_axis(
                    [
                        &mut r0[s.clone()],
                        &mut r1[s.clone()],
                        &mut r2[s.clone()],
                        &mut r3[s.clone()],
                        &mut r4[s.clone()],
                        &mut r5[s],
                    ],
                    acc,
                    cx.init[k],
                    cx.half_dt2,
                    &cx.gear,
                    cx.periodic[k].then_some(cx.size[k]),
                    cx.flush,
                );
                moved[k] = max_ignoring_nan(moved[k], step_move);
            }
            Then::VerletKick => verlet_kick(&mut r1[o..o + m], acc, cx.dt),
        }
    });
    ChunkBooks { walls, moved }
}

#[cfg(test)]
mod domain_tests {
    //! The spatial domains (`domains.rs`) against the serial step and against themselves.
    use super::*;

    /// A shaken wet bed of 360 disks in a 120 x 9 box (bridges form and rupture, across the
    /// cut too).
    fn wet_bed() -> Scene {
        let text = "dimension = 2\ngravity = 1.0\n[box]\nsize = [120.0, 9.0]\n\
            boundary = [\"periodic\", \"wall\"]\n[particles]\ncount = 360\npolydispersity = 0.06\n\
            [contact]\ndamping = 1.5e-4\n[capillary]\nmodel = \"thin_thread\"\ns_crit = 0.0711\n\
            e_cb = 0.2844\n[drive]\nkind = \"sine\"\ngamma = 5.0\ne_star = 10.0\n\
            [initial]\ntemperature_over_ecb = 20.0\nseed = 3\n[run]\nduration = 1.0\n\
            [engine]\nkind = \"time\"\n";
        Scene::from_toml_str(text, "domain test").expect("valid scene")
    }

    type Wet = TimeEngine<2, true, true>;

    fn engine(mode: DomainMode) -> Wet {
        let mut e = Wet::new(&wet_bed());
        e.set_domain_mode(mode);
        e.team_door = std::time::Duration::from_secs(60);
        e
    }

    /// Every bit of the state and of the books.
    fn bits(e: &Wet) -> Vec<u64> {
        let mut v: Vec<u64> = e.positions_flat().iter().map(|x| x.to_bits()).collect();
        v.extend(e.velocities_flat().iter().map(|x| x.to_bits()));
        let c = e.counts();
        v.extend([
            c.pair_collisions,
            c.wall_collisions,
            c.bridge_formations,
            c.bridge_ruptures,
            e.steps(),
            e.list_builds(),
        ]);
        v.extend(e.bridges().iter().flat_map(|&(i, j)| [i as u64, j as u64]));
        // The list checks' state: where the next exact displacement test falls.
        if let Some(dec) = e.domains.0.as_ref() {
            for dm in &dec.domains {
                let dm = super::super::domains::lock(dm);
                v.extend([dm.bound.to_bits(), u64::from(dm.since_check)]);
            }
        }
        let l = e.energy();
        v.extend(
            [
                l.kinetic,
                l.potential,
                l.dissipated_restitution,
                l.dissipated_ruptures,
                l.work_by_drive,
                e.max_overlap(),
            ]
            .map(f64::to_bits),
        );
        v
    }

    fn pool(threads: usize) -> rayon::ThreadPool {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("a pool")
    }

    /// The cross pairs bonded in domain 0's copy.
    fn cross_bonds(e: &Wet) -> usize {
        let dec = e.domains.0.as_ref().expect("a decomposition");
        let d0 = super::super::domains::lock(&dec.domains[0]);
        d0.cross_flags.iter().filter(|&&f| f & BOND != 0).count()
    }

    #[test]
    fn one_two_and_three_threads_give_the_same_bits() {
        let run = |threads: usize| {
            pool(threads).install(|| {
                let mut e = engine(DomainMode::Always);
                e.run_until(1.0);
                assert!(e.counts().bridge_ruptures > 0, "bridges rupture");
                (bits(&e), e.team_steps(), e.steps())
            })
        };
        let (one, team1, _) = run(1);
        let (two, team2, steps) = run(2);
        let (three, team3, _) = run(3);
        assert_eq!(team1, 0, "one thread runs no team");
        // The long door admits both members: nearly every step ran on two threads (the first,
        // predicting, step runs alone).
        assert!(
            team2 + 1 >= steps && team3 + 1 >= steps,
            "{team2} {team3} of {steps}"
        );
        assert!(one == two, "one and two threads differ");
        assert!(one == three, "one and three threads differ");
    }

    /// The bits after one `run_until(1.0)` of the bed on a pool of `threads`.
    fn bits_of_one_run(threads: usize) -> Vec<u64> {
        pool(threads).install(|| {
            let mut e = engine(DomainMode::Always);
            e.run_until(1.0);
            bits(&e)
        })
    }

    /// Runs `e` to 1 time unit in `run_until` pieces of `piece` time units.
    fn run_in_pieces(e: &mut Wet, piece: f64) {
        let mut t = 0.0f64;
        while t < 1.0 {
            t = (t + piece).min(1.0);
            e.run_until(t);
        }
    }

    /// Regions with a door of 20 us, so that the pool's second thread joins some regions and
    /// not others, as on a busy machine, give the bits of one thread. (On the development VM
    /// about a quarter of the steps ran on two members; the mix depends on the machine and is
    /// printed, not asserted.)
    #[test]
    fn a_team_of_changing_size_changes_no_number() {
        let one = bits_of_one_run(1);
        let varying = pool(2).install(|| {
            let mut e = engine(DomainMode::Always);
            e.team_door = std::time::Duration::from_micros(20);
            run_in_pieces(&mut e, 0.01);
            println!("{} of {} steps on a team of two", e.team_steps(), e.steps());
            bits(&e)
        });
        assert!(one == varying, "a team of changing size changes numbers");
    }

    /// A region goes on through the list builds (the team builds the list itself): one run
    /// takes far fewer regions than builds, and the same bits come out as when every build
    /// ends the region (a region per step, which builds between regions).
    #[test]
    fn the_team_builds_the_list_without_leaving_its_region() {
        let (whole, regions, builds, partitions) = pool(2).install(|| {
            let mut e = engine(DomainMode::Always);
            e.run_until(1.0);
            (bits(&e), e.regions, e.list_builds(), e.partitions)
        });
        assert!(builds > 20, "{builds} builds");
        assert!(
            regions <= partitions + 1,
            "{regions} regions for {builds} builds and {partitions} partitions"
        );
        let stepwise = pool(2).install(|| {
            let mut e = engine(DomainMode::Always);
            while e.time() < 1.0 - 0.5 * e.p.dt {
                e.step();
            }
            bits(&e)
        });
        assert!(whole == stepwise, "builds inside the team change numbers");
    }

    #[test]
    fn where_regions_end_changes_no_number() {
        let whole = bits_of_one_run(2);
        let pieces = pool(2).install(|| {
            let mut e = engine(DomainMode::Always);
            run_in_pieces(&mut e, 0.0173);
            bits(&e)
        });
        assert!(
            whole == pieces,
            "a run in pieces differs from one in one go"
        );
    }

    /// On one thread (the domains in turn), so that a domain reading a halo of the wrong step
    /// parity sees the other's newer state and fails here (on two threads the halo locks
    /// would then deadlock instead).
    #[test]
    fn both_copies_of_a_cross_pair_take_the_same_decisions() {
        pool(1).install(|| {
            let mut e = engine(DomainMode::Always);
            let mut bonded = 0;
            for k in 1..=20 {
                e.run_until(0.05 * k as f64);
                let dec = e.domains.0.as_mut().expect("a decomposition");
                assert!(
                    dec.cross_flags_agree(),
                    "cross flags differ at t = {}",
                    e.time()
                );
                bonded = bonded.max(cross_bonds(&e));
            }
            assert!(bonded > 0, "some cross pair is bonded");
        });
    }

    /// 3D (the same code): 400 wet spheres, cut across the longest (periodic) axis; one and
    /// two threads give the same bits, and the serial path agrees to round-off.
    #[test]
    fn spheres_on_domains_agree_with_the_serial_step() {
        let text = "dimension = 3\ngravity = 1.0\n[box]\nsize = [16.0, 8.0, 8.0]\n\
            boundary = [\"periodic\", \"periodic\", \"wall\"]\n[particles]\ncount = 400\n\
            polydispersity = 0.06\n[contact]\ndamping = 1.5e-4\n[capillary]\n\
            model = \"thin_thread\"\ns_crit = 0.0711\ne_cb = 0.2844\n[drive]\nkind = \"sine\"\n\
            gamma = 5.0\ne_star = 10.0\n[initial]\ntemperature_over_ecb = 20.0\nseed = 5\n\
            [run]\nduration = 1.0\n[engine]\nkind = \"time\"\n";
        let scene = Scene::from_toml_str(text, "domain test 3D").expect("valid scene");
        let run = |mode: DomainMode, threads: usize| {
            pool(threads).install(|| {
                let mut e = TimeEngine::<3, true, true>::new(&scene);
                e.set_domain_mode(mode);
                e.team_door = std::time::Duration::from_secs(60);
                e.run_until(0.4);
                e
            })
        };
        let one = run(DomainMode::Always, 1);
        let two = run(DomainMode::Always, 2);
        let serial = run(DomainMode::Never, 1);
        assert!(
            two.team_steps() + 1 >= two.steps(),
            "two members ran the steps"
        );
        assert!(one.counts().bridge_formations > 0, "bridges form");
        let bits = |e: &TimeEngine<3, true, true>| -> Vec<u64> {
            let mut v: Vec<u64> = e.positions_flat().iter().map(|x| x.to_bits()).collect();
            v.extend(e.velocities_flat().iter().map(|x| x.to_bits()));
            let l = e.energy();
            v.extend(
                [
                    l.dissipated_restitution,
                    l.dissipated_ruptures,
                    l.work_by_drive,
                ]
                .map(f64::to_bits),
            );
            v.extend([
                e.counts().pair_collisions,
                e.counts().bridge_ruptures,
                e.list_builds(),
            ]);
            v
        };
        assert!(bits(&one) == bits(&two), "one and two threads differ");
        assert_eq!(serial.list_builds(), one.list_builds());
        assert_eq!(
            serial.counts().pair_collisions,
            one.counts().pair_collisions
        );
        assert_eq!(
            serial.counts().bridge_formations,
            one.counts().bridge_formations
        );
        assert_eq!(
            serial.counts().bridge_ruptures,
            one.counts().bridge_ruptures
        );
        assert_eq!(serial.bridges(), one.bridges());
        let dx = serial
            .positions_flat()
            .iter()
            .zip(&one.positions_flat())
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(dx < 1e-9, "positions differ by {dx}");
    }

    /// The point of the domains: in the bench system (1200 disks, 400 x 9, cut across x)
    /// the threads exchange only a small halo per step. Prints the figures quoted in
    /// docs/performance.md ("Sixth round").
    #[test]
    fn the_halo_is_a_small_part_of_the_bench_system() {
        let s = crate::scene::reference::dry_shaken_time_driven("gear5");
        let mut e = TimeEngine::<2, true, false>::new(&s);
        assert!(e.uses_domains(), "N = 1200 runs on the domains by default");
        e.run_until(0.5);
        let dec = e.domains.0.as_ref().expect("a decomposition");
        for (d, dm) in dec.domains.iter().enumerate() {
            let dm = super::super::domains::lock(dm);
            let m = dm.ids.len();
            println!(
                "domain {d}: {m} particles, {} inner entries, {} cross entries, {} ghosts, {} published",
                dm.partner.len(),
                dm.cross_own.len(),
                dm.ghosts,
                dm.halo_out.len()
            );
            assert_eq!(m, 600);
            assert!(dm.ghosts > 0 && dm.ghosts * 10 < m, "{} ghosts", dm.ghosts);
        }
        println!(
            "{} partitions over {} list builds",
            e.partitions,
            e.list_builds()
        );
    }

    /// The domains change the serial trajectory by round-off only: the same list builds,
    /// counts and (to round-off) positions and books, over a run long enough for several
    /// partitions. The books would differ by the cross pairs' share if both domains booked
    /// them.
    #[test]
    fn domains_change_the_serial_trajectory_by_round_off() {
        let mut serial = engine(DomainMode::Never);
        let mut split = engine(DomainMode::Always);
        let t = 1.2;
        serial.run_until(t);
        split.run_until(t);
        assert!(split.partitions > 1, "{} partitions", split.partitions);
        assert_eq!(serial.list_builds(), split.list_builds());
        let (cs, cd) = (serial.counts(), split.counts());
        assert_eq!(cs.pair_collisions, cd.pair_collisions);
        assert_eq!(cs.wall_collisions, cd.wall_collisions);
        assert_eq!(cs.bridge_formations, cd.bridge_formations);
        assert_eq!(cs.bridge_ruptures, cd.bridge_ruptures);
        assert_eq!(serial.bridges(), split.bridges());
        let (xs, xd) = (serial.positions_flat(), split.positions_flat());
        let dx = xs
            .iter()
            .zip(&xd)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(dx < 1e-9, "positions differ by {dx}");
        assert!(dx > 0.0, "the summation order differs, so some bit should");
        let (ls, ld) = (serial.energy(), split.energy());
        for (a, b, what) in [
            (
                ls.dissipated_restitution,
                ld.dissipated_restitution,
                "damping",
            ),
            (ls.dissipated_ruptures, ld.dissipated_ruptures, "ruptures"),
            (ls.work_by_drive, ld.work_by_drive, "drive work"),
            (ls.kinetic, ld.kinetic, "kinetic"),
        ] {
            assert!(
                (a - b).abs() <= 1e-9 * a.abs().max(1.0),
                "{what}: {a} vs {b}"
            );
        }
    }
}
