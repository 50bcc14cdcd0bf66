//! The time-driven engine: soft disks (`D = 2`) and spheres (`D = 3`) with damped Hertz contacts
//! (docs/model.md 2.2, Eq. 2.7), the minimal capillary model (docs/model.md 3.1), gravity, periodic
//! lateral axes, static or sinusoidally shaken Hertz floor and lid (docs/model.md 4.1) and an
//! optional body force per particle ([`BodyForce`]). Effects are compile-time parameters: `GRAV`,
//! `WET` (bridges and their bookkeeping) and the body force type `B` ([`NoBodyForce`] compiles to
//! nothing).
//!
//! State: structure of arrays, axis-major (`x[k * n + i]`). With Gear `r[k]` holds the scaled
//! `k`-th derivative (`integrator.rs`), with velocity Verlet `r[0]` is the position and `r[1]` the
//! velocity. Between Gear steps `r` holds the prediction for the next step; the current position
//! and velocity are recovered on demand by inverting the predictor. Forces come from the Verlet
//! list (`neighbours.rs`, rebuilt as `neighbours::needs_rebuild` decides), each pair once,
//! through the one kernel of `pair_kernel.rs`. Nothing is allocated inside a step once the list
//! has reached its working size. The execution strategies (`stepping.rs`) and the other files
//! of this folder are described in ARCHITECTURE.md, "Time engine".
//!
//! Energy bookkeeping ([`EnergyLedger`], same fields as the event engine):
//! - `potential`: gravity `m g z`, Hertz elastic energy of pairs and walls (`(2/5) k sqrt(R_eff)
//!   xi^(5/2)`), and the bridge energy `F_B s` of every bonded pair (docs/model.md 3.1: zero at
//!   contact, `E_cb` at rupture);
//! - `dissipated_restitution`: work of the damping part of Eq. 2.7, `sum F_damp xi_dot dt`;
//! - `dissipated_ruptures`: the bridge energy `F_B s` removed at each rupture (about `E_cb`),
//!   minus the (small, negative) `F_B s` a bridge starts with when it forms at overlap `-s`;
//! - `work_by_drive`: work of the moving walls, `sum F_wall v_wall dt`, and of the body force,
//!   `sum F . v dt`.
//!
//! The sums over `dt` are rectangle rules at the force evaluations, so the ledger closes to the
//! integrator's accuracy (exactly in the limit `dt -> 0`), not to round-off as in the event engine.

use super::domains::DOMAIN_MIN_PARTICLES;
use super::integrator::gear_unpredict;
use super::neighbours::{BOND, NeighbourList};
use super::pair_kernel::{Books, PairConstants};
use crate::physics::hertz;
use crate::scene::IntegratorKind;
use crate::sim::books::{EnergyLedger, EventCounts};
use std::borrow::Cow;

mod build;
mod domain_step;
#[cfg(test)]
mod domain_tests;
mod measures;
mod particle_phase;
mod serial;
mod stepping;

use domain_step::Domains;
use serial::Serial;
use stepping::Strategy;

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

/// Coordinates per chunk of the per-particle phase (and of Verlet's drift): the unit of the
/// booked sums, added in chunk order.
pub(crate) const PARTICLE_CHUNK: usize = 128;

/// Largest overlap, in units of the mean diameter, that [`TimeEngine::sanity_check`] tolerates
/// (five times the 1 % the default stiffness is chosen for).
pub(crate) const SANITY_OVERLAP: f64 = 0.05;

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

/// What every strategy steps: the parameters, the particles' arrays, the neighbour list and
/// the books. The strategies' own buffers and caches are kept apart ([`TimeEngine`]).
#[derive(Debug)]
struct State<const D: usize, const GRAV: bool, const WET: bool, B> {
    p: Params<D>,
    n: usize,
    steps: u64,
    /// Scaled derivatives (Gear) or position, velocity (Verlet); axis-major.
    r: [Vec<f64>; 6],
    /// Gear: whether `r` holds the prediction for the next step (the current state is then
    /// recovered by [`gear_unpredict`]).
    predicted: bool,
    /// Acceleration of the last force evaluation, axis-major; or, when `acc_is_start`, the
    /// value every coordinate's force starts from ([`State::force_start`]).
    acc: Vec<f64>,
    /// Whether `acc` holds the force start values, written by the last integrator pass as it
    /// read the accelerations (the next force evaluation then needs no pass to initialise it).
    acc_is_start: bool,
    radius: Vec<f64>,
    /// `k sqrt(R_i)`: the wall prefactor of each particle (`R_eff = R_i`).
    wall_kr: Vec<f64>,
    /// Per coordinate (axis-major): bit 0 touching the lower wall, bit 1 the upper wall of
    /// that axis.
    wall_contact: Vec<u8>,
    list: NeighbourList<D>,
    /// Upper bound on every particle's displacement since the last list build or exact check
    /// (`neighbours::needs_rebuild`).
    moved_bound: f64,
    /// Steps since the last exact displacement check.
    since_check: u32,
    counts: EventCounts,
    dissipated_damping: f64,
    dissipated_bridges: f64,
    work_by_drive: f64,
    max_overlap: f64,
    body: B,
}

/// The time-driven simulation state.
#[derive(Debug)]
pub struct TimeEngine<const D: usize, const GRAV: bool, const WET: bool, B = NoBodyForce> {
    s: State<D, GRAV, WET, B>,
    /// Gear steps of a scene without a body force run on the spatial domains from this many
    /// particles on ([`DOMAIN_MIN_PARTICLES`]; the domain tests move it). The domains sum the
    /// forces on a particle in another order than the serial step (round-off, `domains.rs`),
    /// so it is part of a run's definition.
    domains_from: usize,
    /// The serial strategy's reused buffers.
    serial: Serial<D>,
    /// The domain strategy's decomposition and counters.
    domains: Domains<D>,
}

impl<const D: usize, const GRAV: bool, const WET: bool, B: BodyForce<D>>
    TimeEngine<D, GRAV, WET, B>
{
    /// Position and scaled velocity (`r_0`, `r_1`) of the current step at flat index `e` (for
    /// a predicted Gear state by [`gear_unpredict`], wrapped into the box on periodic axes).
    fn now_at(&self, e: usize) -> (f64, f64) {
        let s = &self.s;
        if !s.predicted {
            return (s.r[0][e], s.r[1][e]);
        }
        let a = gear_unpredict(std::array::from_fn(|k| s.r[k][e]));
        let k = e / s.n;
        if s.p.periodic[k] {
            (stepping::wrap_into(a[0], s.p.size[k]), a[1])
        } else {
            (a[0], a[1])
        }
    }

    /// Positions (`q = 0`) or velocities times [`State::velocity_scale`] (`q = 1`) of the
    /// current step, axis-major.
    fn now(&self, q: usize) -> Cow<'_, [f64]> {
        if self.s.predicted {
            let pick = |(x, v)| if q == 0 { x } else { v };
            Cow::Owned((0..D * self.s.n).map(|e| pick(self.now_at(e))).collect())
        } else {
            Cow::Borrowed(&self.s.r[q])
        }
    }

    pub fn len(&self) -> usize {
        self.s.n
    }

    pub fn is_empty(&self) -> bool {
        self.s.n == 0
    }

    /// Current time, `steps * dt`.
    pub fn time(&self) -> f64 {
        self.s.time()
    }

    pub fn steps(&self) -> u64 {
        self.s.steps
    }

    pub fn dt(&self) -> f64 {
        self.s.p.dt
    }

    pub fn list_builds(&self) -> u64 {
        self.s.list.builds
    }

    pub fn list_entries(&self) -> usize {
        self.s.list.partner.len()
    }

    /// Contact onsets (pair, wall), bridge formations and ruptures so far.
    pub fn counts(&self) -> &EventCounts {
        &self.s.counts
    }

    /// Largest pair or wall overlap seen at any force evaluation, in units of `d`.
    pub fn max_overlap(&self) -> f64 {
        self.s.max_overlap / self.s.p.diameter
    }

    /// Position of particle `i` (scene order).
    pub fn position(&self, i: usize) -> [f64; D] {
        std::array::from_fn(|k| self.now_at(k * self.s.n + i).0)
    }

    pub fn velocity(&self, i: usize) -> [f64; D] {
        let vs = self.s.velocity_scale();
        std::array::from_fn(|k| self.now_at(k * self.s.n + i).1 * vs)
    }

    pub fn radii(&self) -> &[f64] {
        &self.s.radius
    }

    /// Capillary bridges as pairs `(i, j)`, `i < j`, sorted.
    pub fn bridges(&self) -> Vec<(usize, usize)> {
        if WET {
            self.s.list.flagged(BOND)
        } else {
            Vec::new()
        }
    }

    pub fn bridge_count(&self) -> usize {
        if WET { self.s.list.count(BOND) } else { 0 }
    }
}

impl<const D: usize, const GRAV: bool, const WET: bool, B> State<D, GRAV, WET, B> {
    fn time(&self) -> f64 {
        self.steps as f64 * self.p.dt
    }

    /// Factor turning `r[1]` into a velocity.
    fn velocity_scale(&self) -> f64 {
        match self.p.integrator {
            IntegratorKind::Gear5 => 1.0 / self.p.dt,
            IntegratorKind::Verlet => 1.0,
        }
    }

    /// Adds the counts and the largest overlap of `b`.
    fn add_counts(&mut self, b: &Books) {
        self.max_overlap = self.max_overlap.max(b.max_overlap);
        self.counts.pair_collisions += b.pair_onsets;
        self.counts.wall_collisions += b.wall_onsets;
        self.counts.bridge_formations += b.formations;
        self.counts.bridge_ruptures += b.ruptures;
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
}

impl<const D: usize> Params<D> {
    /// The pair kernel's constants for a force evaluation (`vs` turns the velocity array into
    /// velocities, `dt` weights the books).
    fn pair_constants(&self, vs: f64, dt: f64) -> PairConstants<D> {
        PairConstants {
            periodic: self.periodic,
            size: self.size,
            half: std::array::from_fn(|k| 0.5 * self.size[k]),
            stiffness: self.stiffness,
            damping: self.damping,
            bridge_force: self.bridge_force,
            s_crit: self.s_crit,
            vs,
            dt,
        }
    }
}
