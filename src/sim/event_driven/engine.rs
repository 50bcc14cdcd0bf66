//! The event-driven engine for hard disks (`D = 2`) and spheres (`D = 3`).
//!
//! Effects are chosen once, at scene start, as compile-time parameters: `GRAV` (parabolic
//! flights and the vertical-root formulas), `WET` (thin-thread bridges and their
//! bookkeeping) and `SHEAR` (the slab forces of the shear drive, MODEL.md 4.2: slab-crossing
//! events, parabolic flights along `y`, quartic pair predictions in [`super::shear`]). A dry,
//! gravity-free or unsheared scene therefore runs code in which the other branches do not exist.
//!
//! Structure (after DynamO's split of event sources, written anew):
//! - delayed states: particle `i` stores its position and velocity at its own time `t_loc[i]`;
//!   it is brought to the current time only when an event involves it;
//! - per particle three candidate events: the earliest pair event (collision, or the bonded-pair
//!   event at `s = s_crit`), the next cell crossing, and the next wall collision; the queue
//!   ([`EventQueue`]) holds the earliest of the three;
//! - lazy invalidation: each particle counts its velocity changes; a pair event remembers the
//!   partner's count at prediction time and is re-predicted when popped if the count moved on;
//! - cell crossings keep the pair event and only scan the newly adjacent slab of cells.
//!
//! Numerical safeguards (each tested in `tests/engine_safeguards.rs`):
//! - overlap: an overlapping pair (or particle beyond a wall) that approaches collides now; one
//!   that separates is left alone (MODEL.md 6, B.5.6);
//! - collapse: the TC model and the rebound floor of `physics::contact::rebound_speed`;
//! - round-off at cell faces: crossing times are clamped at zero and cells are tracked by index,
//!   never recomputed from positions.

use super::cells::CellGrid;
use super::queue::{EventQueue, HeapQueue};
use super::shear::{FORCE_AXIS, ShearField, pair_times};
use super::table_cache::TableCache;
use crate::physics::capillary::{WellOutcome, well_outcome};
use crate::physics::contact::rebound_speed;
use crate::physics::flight::{
    accelerated_time_to_plane, linear_time_to_plane, parabola_time_down, parabola_time_up,
};
use crate::physics::shaken_wall::{WallMotion, WallRoot, bracket_root, exact_root};
use crate::physics::wall_table::{TableHit, WallTable};
use crate::scene::{Boundary, DEFAULT_ROOT_TOLERANCE, RuptureRule, Scene, WallSolverKind};
use crate::sim::initial::initial_state;
use nalgebra::SVector;
use serde::{Deserialize, Serialize};
use std::sync::Arc;

/// A point or velocity in `D` dimensions.
pub type Vector<const D: usize> = SVector<f64, D>;

const NONE: u32 = u32::MAX;
/// Events between two renumberings of the particles in cell order (see `reorder_by_cell`).
fn reorder_interval(n: usize) -> u64 {
    (20 * n as u64).max(100_000)
}

/// Most bridges one particle may hold (a guard: more means the packing is unphysical).
pub const MAX_BONDS: usize = 16;

/// Kind of a pair event.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum PairKind {
    Collide,
    Well,
}

#[derive(Debug, Clone, Copy)]
struct PairEvent {
    time: f64,
    partner: u32,
    partner_count: u32,
    kind: PairKind,
}

impl PairEvent {
    const NEVER: PairEvent = PairEvent {
        time: f64::INFINITY,
        partner: NONE,
        partner_count: 0,
        kind: PairKind::Collide,
    };
}

/// A cell crossing or wall event: when, along which axis, in which direction.
#[derive(Debug, Clone, Copy)]
struct PlaneEvent {
    time: f64,
    axis: u8,
    up: bool,
}

impl PlaneEvent {
    const NEVER: PlaneEvent = PlaneEvent {
        time: f64::INFINITY,
        axis: 0,
        up: false,
    };

    /// Replaces this event by `(time, axis, up)` if that is earlier.
    #[inline]
    fn keep_earlier(&mut self, time: f64, axis: usize, up: bool) {
        if time < self.time {
            *self = PlaneEvent {
                time,
                axis: axis as u8,
                up,
            };
        }
    }
}

/// Events processed, by kind.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct EventCounts {
    pub pair_collisions: u64,
    pub wall_collisions: u64,
    pub cell_crossings: u64,
    pub bridge_formations: u64,
    pub bridge_ruptures: u64,
    pub well_bounces: u64,
    /// Shaken walls: scheduled re-checks of a particle that did not reach a wall within the
    /// solver's horizon (no velocity change).
    pub wall_rechecks: u64,
    /// Pair events found stale when popped (partner changed course) and re-predicted.
    pub invalidated: u64,
    /// Shear drive: crossings of a slab face (the force on the particle changes).
    pub slab_crossings: u64,
}

impl EventCounts {
    /// All processed events, stale ones included.
    pub fn total(&self) -> u64 {
        self.pair_collisions
            + self.wall_collisions
            + self.cell_crossings
            + self.well_bounces
            + self.bridge_ruptures
            + self.invalidated
            + self.wall_rechecks
            + self.slab_crossings
    }
}

/// Energy bookkeeping in units of `m g d` (or the scene's energy unit).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct EnergyLedger {
    pub kinetic: f64,
    pub potential: f64,
    /// Net energy removed by particle-particle and particle-wall restitution.
    pub dissipated_restitution: f64,
    /// Energy removed by bridge ruptures (`E_cb` each with the reduced-mass rule).
    pub dissipated_ruptures: f64,
    /// Energy added by the rebound floor (collapse remedy); zero in elastic systems.
    pub added_by_collapse_remedies: f64,
    /// Potential energy added by placing particles exactly on the wall at tabulated hits
    /// (`table` solver, B.5.1); zero for the other solvers.
    pub added_by_wall_placement: f64,
    /// Work done on the particles by the drive: the shaken walls, or the shear field
    /// (`sum m a_k dy` over every flight in slab `k`, MODEL.md 4.2).
    pub work_by_drive: f64,
}

impl EnergyLedger {
    /// `kinetic + potential + dissipated - injected`: constant in exact arithmetic.
    pub fn total_accounted(&self) -> f64 {
        self.kinetic + self.potential + self.dissipated_restitution + self.dissipated_ruptures
            - self.added_by_collapse_remedies
            - self.added_by_wall_placement
            - self.work_by_drive
    }
}

/// The delayed state of one particle: position and velocity at its own time `t`, and its
/// radius. Kept together (64 bytes for spheres) because a pair prediction reads all of it.
#[derive(Debug, Clone, Copy)]
#[repr(C, align(64))]
struct Body<const D: usize> {
    x: Vector<D>,
    t: f64,
    v: Vector<D>,
    r: f64,
}

/// Runtime parameters of the engine, derived once from the scene.
#[derive(Debug, Clone)]
struct Params<const D: usize> {
    size: [f64; D],
    periodic: [bool; D],
    gravity: f64,
    mass: f64,
    eps: f64,
    e_wall: f64,
    tc: f64,
    min_rebound: f64,
    s_crit: f64,
    e_cb: f64,
    rule: RuptureRule,
    overlap_tolerance: f64,
    /// Floor and lid motion (MODEL.md 4.1), `None` for static walls.
    drive: Option<WallMotion>,
    /// Gap tolerance of the wall-root solver.
    root_tolerance: f64,
    /// Which wall-root solver, and the `bracket` solver's step.
    wall_solver: WallSolverKind,
    t_min: f64,
    /// `table` solver: the shared tables of the floor and of the lid (gravity pointing away).
    tables: Option<[Arc<WallTable>; 2]>,
    /// Shear drive: the slabs and their accelerations (`None` unless `SHEAR`).
    shear: Option<ShearField>,
}

/// Largest gap (in units of `d`) at which a tabulated wall hit is accepted and the particle
/// placed on the wall (B.5.1); a larger gap makes the event a re-check. Bounds the
/// displacement a table error can cause.
const TABLE_PLACEMENT_TOLERANCE: f64 = 1e-2;

/// The event-driven simulation state.
#[derive(Debug, Clone)]
pub struct Engine<
    const D: usize,
    const GRAV: bool,
    const WET: bool,
    const SHEAR: bool = false,
    Q: EventQueue = HeapQueue,
> {
    p: Params<D>,
    /// Current simulation time (time of the last processed event).
    time: f64,
    /// Per-particle state, one cache line per sphere (see [`Body`]).
    body: Vec<Body<D>>,
    count: Vec<u32>,
    last_collision: Vec<f64>,
    cell: Vec<[i32; D]>,
    grid: CellGrid<D>,
    offsets: Vec<[i32; D]>,
    bonds: Vec<u32>,
    bond_len: Vec<u8>,
    pair_ev: Vec<PairEvent>,
    cross_ev: Vec<PlaneEvent>,
    wall_ev: Vec<PlaneEvent>,
    queue: Q,
    counts: EventCounts,
    dissipated_restitution: f64,
    dissipated_ruptures: f64,
    /// Energy the collapse remedies kept or added compared with plain restitution.
    added: f64,
    work_by_drive: f64,
    /// Potential energy added by wall placement (`table` solver).
    placement: f64,
    /// `table` solver: tabulated approach speed of each particle's predicted wall hit (NaN when
    /// the hit was not tabulated).
    wall_vrel: Vec<f64>,
    /// `table` solver: the particle that has just left the floor (`false`) or lid (`true`);
    /// its next wall prediction uses the wall-edge table (B.5.2).
    launched: Option<(usize, bool)>,
    /// `table` solver: the particle whose tabulated hit found it away from the wall; its next
    /// wall prediction comes from the exact solver, so a table error cannot repeat itself at
    /// the same time forever.
    distrusted: Option<usize>,
    /// Events whose time lay before the current time by more than round-off (must stay 0).
    time_reversals: u64,
    /// Original index (scene order) of the particle stored at each internal index.
    id: Vec<u32>,
    /// Internal index of each original particle.
    slot_of: Vec<u32>,
    /// Event count at which particles are next renumbered in cell order, and the interval.
    next_reorder: u64,
    reorder_every: u64,
    /// Shear drive (empty otherwise): slab index, acceleration along `y`, and the next slab
    /// crossing of each particle.
    slab: Vec<u32>,
    accel: Vec<f64>,
    slab_ev: Vec<PlaneEvent>,
}

impl<const D: usize, const GRAV: bool, const WET: bool, const SHEAR: bool, Q: EventQueue>
    Engine<D, GRAV, WET, SHEAR, Q>
{
    /// Builds the engine for a validated scene: initial state, cells, first predictions.
    pub fn new(scene: &Scene) -> Self {
        Self::assemble(scene, initial_state(scene), None)
    }

    /// Rebuilds the engine from a saved state (`sim::state`): every particle at the state's
    /// time, the bridges bonded, the event counts and the energy ledger continued, cells and
    /// predictions derived afresh. The TC remedy's last-collision times start unset. A run
    /// continued from a state follows the uninterrupted run to round-off: predictions are
    /// recomputed from positions advanced to the common time, which rounds differently
    /// (`tests/observe_runs.rs`, `checkpoint_continues_the_event_trajectory`).
    pub fn from_state(scene: &Scene, state: &crate::sim::EngineState) -> Self {
        let d = scene.dimension;
        let init = crate::sim::initial::InitialState {
            radius: state.radii.clone(),
            position: state.positions.chunks(d).map(<[f64]>::to_vec).collect(),
            velocity: state.velocities.chunks(d).map(<[f64]>::to_vec).collect(),
        };
        Self::assemble(scene, init, Some(state))
    }

    fn assemble(
        scene: &Scene,
        init: crate::sim::initial::InitialState,
        start: Option<&crate::sim::EngineState>,
    ) -> Self {
        let t0 = start.map_or(0.0, |s| s.time);
        assert_eq!(
            scene.dimension, D,
            "scene dimension does not match the engine"
        );
        assert_eq!(
            GRAV,
            scene.gravity > 0.0,
            "gravity flag does not match the scene"
        );
        assert_eq!(
            WET,
            scene.is_wet(),
            "capillary flag does not match the scene"
        );
        assert_eq!(
            SHEAR,
            scene.shear_slabs().is_some(),
            "shear flag does not match the scene"
        );
        assert!(!SHEAR || D > FORCE_AXIS, "shear needs a y axis");
        let n = init.radius.len();
        let mut size = [0.0; D];
        let mut periodic = [false; D];
        let boundaries = scene.boundaries();
        for k in 0..D {
            size[k] = scene.container.size[k];
            periodic[k] = boundaries[k] == Boundary::Periodic;
        }
        let (_, d_max) = scene.diameter_range();
        let range = (d_max + scene.s_crit()).max(scene.engine.cell_size);
        let grid = CellGrid::new(size, periodic, range, n);
        assert!(
            grid.neighbourhood_is_distinct(),
            "box too small for the cell grid (validation should have caught this)"
        );
        let p = Params {
            size,
            periodic,
            gravity: scene.gravity,
            mass: scene.particles.mass,
            eps: scene.contact.restitution,
            e_wall: scene.contact.wall_restitution,
            tc: scene.engine.tc,
            min_rebound: scene.engine.min_rebound_speed,
            s_crit: scene.s_crit(),
            e_cb: scene.e_cb(),
            rule: scene.rupture_rule(),
            overlap_tolerance: scene.engine.overlap_tolerance,
            drive: scene.drive_motion().map(|(amplitude, omega)| WallMotion {
                amplitude,
                omega,
                g: scene.gravity,
            }),
            root_tolerance: scene.drive.root_tolerance.unwrap_or(DEFAULT_ROOT_TOLERANCE),
            wall_solver: scene.drive.wall_solver,
            t_min: scene.drive.t_min.unwrap_or_else(|| {
                scene.drive_motion().map_or(0.0, |(_, omega)| {
                    2.0 * std::f64::consts::PI / omega / 1000.0
                })
            }),
            tables: match (scene.drive.wall_solver, scene.drive_motion()) {
                (WallSolverKind::Table, Some((amplitude, omega))) if amplitude > 0.0 => {
                    let spec = scene.wall_table_spec(amplitude, omega);
                    let floor = WallMotion {
                        amplitude,
                        omega,
                        g: scene.gravity,
                    };
                    let lid = WallMotion {
                        g: -scene.gravity,
                        ..floor
                    };
                    let cache = TableCache::current();
                    Some([cache.get(floor, spec), cache.get(lid, spec)])
                }
                _ => None,
            },
            shear: scene
                .shear_slabs()
                .map(|s| ShearField::new(&s, scene.particles.mass, scene.container.size[0])),
        };
        let slab: Vec<u32> = match &p.shear {
            Some(f) => init
                .position
                .iter()
                .map(|x| f.slab_of(x[0]) as u32)
                .collect(),
            None => Vec::new(),
        };
        let accel: Vec<f64> = match &p.shear {
            Some(f) => slab.iter().map(|&k| f.accel(k as usize)).collect(),
            None => Vec::new(),
        };
        let to_vec = |v: &Vec<f64>| Vector::<D>::from_iterator(v.iter().copied());
        let mut engine = Self {
            p,
            time: t0,
            body: (0..n)
                .map(|i| Body {
                    x: to_vec(&init.position[i]),
                    t: t0,
                    v: to_vec(&init.velocity[i]),
                    r: init.radius[i],
                })
                .collect(),
            count: vec![0; n],
            last_collision: vec![f64::NEG_INFINITY; n],
            cell: vec![[0; D]; n],
            grid,
            offsets: CellGrid::<D>::neighbour_offsets(),
            bonds: if WET {
                vec![NONE; n * MAX_BONDS]
            } else {
                Vec::new()
            },
            bond_len: if WET { vec![0; n] } else { Vec::new() },
            pair_ev: vec![PairEvent::NEVER; n],
            cross_ev: vec![PlaneEvent::NEVER; n],
            wall_ev: vec![PlaneEvent::NEVER; n],
            queue: Q::new(n),
            counts: EventCounts::default(),
            dissipated_restitution: 0.0,
            dissipated_ruptures: 0.0,
            added: 0.0,
            work_by_drive: 0.0,
            placement: 0.0,
            wall_vrel: vec![f64::NAN; n],
            launched: None,
            distrusted: None,
            time_reversals: 0,
            id: (0..n as u32).collect(),
            slot_of: (0..n as u32).collect(),
            next_reorder: reorder_interval(n),
            reorder_every: reorder_interval(n),
            slab,
            accel,
            slab_ev: if SHEAR {
                vec![PlaneEvent::NEVER; n]
            } else {
                Vec::new()
            },
        };
        for i in 0..n {
            let x: [f64; D] = engine.body[i].x.into();
            let c = engine.grid.locate(&x);
            engine.cell[i] = c;
            let lin = engine.grid.linear(&c);
            engine.grid.insert(i, lin);
        }
        if let Some(st) = start {
            if WET {
                for &(i, j) in &st.bridges {
                    engine.add_bond_half(i, j);
                    engine.add_bond_half(j, i);
                }
            }
            engine.counts = st.counts.clone();
            let l = &st.ledger;
            engine.dissipated_restitution = l.dissipated_restitution;
            engine.dissipated_ruptures = l.dissipated_ruptures;
            engine.added = l.added_by_collapse_remedies;
            engine.placement = l.added_by_wall_placement;
            engine.work_by_drive = l.work_by_drive;
            engine.next_reorder = engine.counts.total().saturating_add(engine.reorder_every);
        }
        for i in 0..n {
            engine.predict_all(i);
        }
        engine
    }

    /// Number of particles.
    pub fn len(&self) -> usize {
        self.body.len()
    }

    /// Whether the system holds no particle.
    pub fn is_empty(&self) -> bool {
        self.body.is_empty()
    }

    /// Current simulation time.
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Events processed so far.
    pub fn counts(&self) -> &EventCounts {
        &self.counts
    }

    // ----- free flight -------------------------------------------------------------------

    /// Position and velocity of particle `i` at time `t` (without storing them).
    #[inline]
    fn state_at(&self, i: usize, t: f64) -> (Vector<D>, Vector<D>) {
        let dt = t - self.body[i].t;
        let mut x = self.body[i].x + self.body[i].v * dt;
        let mut v = self.body[i].v;
        if GRAV {
            x[D - 1] -= 0.5 * self.p.gravity * dt * dt;
            v[D - 1] -= self.p.gravity * dt;
        }
        if SHEAR {
            let a = self.accel[i];
            x[FORCE_AXIS] += 0.5 * a * dt * dt;
            v[FORCE_AXIS] += a * dt;
        }
        (x, v)
    }

    /// Work of the shear field on particle `i` from its own time to `t` at state `x`:
    /// `m a (y(t) - y(t_i))` (constant force over the flight).
    #[inline]
    fn field_work(&self, i: usize, x: &Vector<D>) -> f64 {
        self.p.mass * self.accel[i] * (x[FORCE_AXIS] - self.body[i].x[FORCE_AXIS])
    }

    /// Brings particle `i` to time `t`.
    #[inline]
    fn advance(&mut self, i: usize, t: f64) {
        if self.body[i].t != t {
            let (x, v) = self.state_at(i, t);
            if SHEAR {
                self.work_by_drive += self.field_work(i, &x);
            }
            self.body[i].x = x;
            self.body[i].v = v;
            self.body[i].t = t;
        }
    }

    /// Minimum-image separation vector `a - b`.
    /// Positions on periodic axes stay within a cell of `[0, L)` (crossings wrap them), so
    /// separations lie in `(-1.5 L, 1.5 L)` and one conditional shift suffices.
    #[inline]
    fn min_image(&self, mut r: Vector<D>) -> Vector<D> {
        for k in 0..D {
            if self.p.periodic[k] {
                let (l, half) = (self.p.size[k], 0.5 * self.p.size[k]);
                if r[k] > half {
                    r[k] -= l;
                } else if r[k] < -half {
                    r[k] += l;
                }
            }
        }
        r
    }

    // ----- bonds -------------------------------------------------------------------------

    #[inline]
    fn bonded(&self, i: usize, j: usize) -> bool {
        if !WET {
            return false;
        }
        let base = i * MAX_BONDS;
        self.bonds[base..base + self.bond_len[i] as usize]
            .iter()
            .any(|&b| b as usize == j)
    }

    fn add_bond_half(&mut self, i: usize, j: usize) {
        let len = self.bond_len[i] as usize;
        assert!(
            len < MAX_BONDS,
            "particle {} (scene index) would hold more than {MAX_BONDS} bridges at t = {}: packing \
             is unphysical",
            self.id[i],
            self.time
        );
        self.bonds[i * MAX_BONDS + len] = j as u32;
        self.bond_len[i] += 1;
    }

    fn remove_bond_half(&mut self, i: usize, j: usize) {
        let base = i * MAX_BONDS;
        let len = self.bond_len[i] as usize;
        if let Some(k) = self.bonds[base..base + len]
            .iter()
            .position(|&b| b as usize == j)
        {
            self.bonds[base + k] = self.bonds[base + len - 1];
            self.bonds[base + len - 1] = NONE;
            self.bond_len[i] -= 1;
        }
    }

    /// Number of capillary bridges.
    pub fn bridge_count(&self) -> usize {
        if !WET {
            return 0;
        }
        self.bond_len.iter().map(|&l| l as usize).sum::<usize>() / 2
    }

    /// The capillary bridges as pairs of scene indices `(i, j)`, `i < j`, sorted (empty for dry
    /// scenes). Read-only view for the observers.
    pub fn bridges(&self) -> Vec<(usize, usize)> {
        if !WET {
            return Vec::new();
        }
        let mut out = Vec::with_capacity(self.bridge_count());
        for k in 0..self.len() {
            let base = k * MAX_BONDS;
            for &b in &self.bonds[base..base + self.bond_len[k] as usize] {
                let (i, j) = (self.id[k] as usize, self.id[b as usize] as usize);
                if i < j {
                    out.push((i, j));
                }
            }
        }
        out.sort_unstable();
        out
    }

    // ----- prediction --------------------------------------------------------------------

    /// Earliest pair event of `i` (already at time `t`) with `j`, as an absolute time.
    #[inline]
    fn predict_pair(&self, i: usize, j: usize, t: f64) -> Option<(f64, PairKind)> {
        self.predict_pair_from(&self.body[i].x, &self.body[i].v, i, j, t)
    }

    /// Earliest pair event of `i`, with state `(xi, vi)` at time `t`, with `j`.
    #[inline]
    fn predict_pair_from(
        &self,
        xi: &Vector<D>,
        vi: &Vector<D>,
        i: usize,
        j: usize,
        t: f64,
    ) -> Option<(f64, PairKind)> {
        let (xj, vj) = self.state_at(j, t);
        let r = self.min_image(xi - xj);
        // All particles feel the same gravity, so relative motion is a straight line (Eq. B.3).
        let v = vi - vj;
        if SHEAR && self.accel[i] != self.accel[j] {
            return self.predict_sheared_pair(&r, &v, i, j, t);
        }
        let b = r.dot(&v);
        let rr = r.norm_squared();
        let sigma = self.body[i].r + self.body[j].r;
        let vv = v.norm_squared();
        let mut best: Option<(f64, PairKind)> = None;
        if b < 0.0 {
            let c = rr - sigma * sigma;
            if c <= 0.0 {
                // Overlap safeguard: approaching while overlapping collides now.
                return Some((t, PairKind::Collide));
            }
            let disc = b * b - vv * c;
            if disc > 0.0 {
                // Smaller root of |r + v dt| = sigma, cancellation-free.
                best = Some((t + c / (-b + disc.sqrt()), PairKind::Collide));
            }
        }
        if WET && self.bonded(i, j) {
            let lambda = sigma + self.p.s_crit;
            let c = rr - lambda * lambda;
            let dt = if b > 0.0 && c >= 0.0 {
                // At or beyond the well edge (round-off) and separating: the event is now.
                Some(0.0)
            } else if vv > 0.0 {
                // Larger root of |r + v dt| = sigma + s_crit. Right after a bounce off the well
                // wall the pair sits on the edge (c may be +round-off) and approaches: the root
                // is then the next exit, not "none" (regression: bonds stretched past s_crit).
                let disc = (b * b - vv * c).max(0.0);
                Some(if b > 0.0 {
                    -c / (b + disc.sqrt())
                } else {
                    (-b + disc.sqrt()) / vv
                })
            } else {
                None
            };
            if let Some(dt) = dt {
                let tw = t + dt;
                if best.is_none_or(|(tb, _)| tw < tb) {
                    best = Some((tw, PairKind::Well));
                }
            }
        }
        best
    }

    /// Pair events of `i` and `j` in slabs of different force (shear drive): the quartics of
    /// [`super::shear::pair_times`], solved up to the first slab exit of either particle.
    #[cold]
    fn predict_sheared_pair(
        &self,
        r: &Vector<D>,
        v: &Vector<D>,
        i: usize,
        j: usize,
        t: f64,
    ) -> Option<(f64, PairKind)> {
        let horizon = (self.slab_ev[i].time.min(self.slab_ev[j].time) - t).max(0.0);
        let sigma = self.body[i].r + self.body[j].r;
        let lambda = (WET && self.bonded(i, j)).then_some(sigma + self.p.s_crit);
        let (contact, well) = pair_times::<D>(
            &(*r).into(),
            &(*v).into(),
            self.accel[i] - self.accel[j],
            sigma,
            lambda,
            horizon,
        );
        match (contact, well) {
            (Some(c), Some(w)) if w < c => Some((t + w, PairKind::Well)),
            (Some(c), _) => Some((t + c, PairKind::Collide)),
            (None, Some(w)) => Some((t + w, PairKind::Well)),
            (None, None) => None,
        }
    }

    /// Scans the cells at `offsets` around particle `i` and lowers its pair event if a partner
    /// there gives an earlier one.
    fn scan_cells(&mut self, i: usize, offsets: &[[i32; D]]) {
        let t = self.time;
        let c = self.cell[i];
        let mut best = self.pair_ev[i];
        let interior = self.grid.is_interior(&c);
        let base = self.grid.linear(&c);
        for o in offsets {
            let cell = if interior {
                self.grid.interior_neighbour(base, o)
            } else {
                match self.grid.shifted(&c, o) {
                    Some(cell) => cell,
                    None => continue,
                }
            };
            self.grid.for_each_in(cell, |j| {
                if j == i {
                    return;
                }
                if let Some((tj, kind)) = self.predict_pair(i, j, t)
                    && tj < best.time
                {
                    best = PairEvent {
                        time: tj,
                        partner: j as u32,
                        partner_count: self.count[j],
                        kind,
                    };
                }
            });
        }
        self.pair_ev[i] = best;
    }

    /// Times until particle `i` (at the current time) reaches the plane `hi` moving up and the
    /// plane `lo` moving down along axis `k` (`+inf` for a plane at infinity or never reached):
    /// parabolas on the vertical axis under gravity, straight lines otherwise.
    #[inline]
    fn times_to_planes(&self, i: usize, k: usize, lo: f64, hi: f64) -> (f64, f64) {
        let (x, v) = (self.body[i].x[k], self.body[i].v[k]);
        let never = f64::INFINITY;
        if SHEAR && k == FORCE_AXIS {
            let a = self.accel[i];
            return (
                if hi.is_finite() {
                    accelerated_time_to_plane(x, v, a, hi, true)
                } else {
                    never
                },
                if lo.is_finite() {
                    accelerated_time_to_plane(x, v, a, lo, false)
                } else {
                    never
                },
            );
        }
        if GRAV && k == D - 1 {
            let g = self.p.gravity;
            (
                if hi.is_finite() {
                    parabola_time_up(x, v, g, hi)
                } else {
                    never
                },
                if lo.is_finite() {
                    parabola_time_down(x, v, g, lo)
                } else {
                    never
                },
            )
        } else {
            (
                if hi.is_finite() {
                    linear_time_to_plane(x, v, hi, true)
                } else {
                    never
                },
                if lo.is_finite() {
                    linear_time_to_plane(x, v, lo, false)
                } else {
                    never
                },
            )
        }
    }

    /// Next crossing of a face of `i`'s cell (particle at the current time).
    fn predict_crossing(&self, i: usize) -> PlaneEvent {
        let c = self.cell[i];
        let mut best = PlaneEvent::NEVER;
        for k in 0..D {
            let w = self.grid.width[k];
            let lo = c[k] as f64 * w;
            let periodic = self.p.periodic[k];
            // The outer faces of the edge cells of a wall axis are never crossed.
            let lo = if periodic || c[k] > 0 {
                lo
            } else {
                f64::NEG_INFINITY
            };
            let hi = if periodic || c[k] < self.grid.n[k] - 1 {
                c[k] as f64 * w + w
            } else {
                f64::INFINITY
            };
            let (t_up, t_down) = self.times_to_planes(i, k, lo, hi);
            best.keep_earlier(t_up, k, true);
            best.keep_earlier(t_down, k, false);
        }
        best.time += self.time;
        best
    }

    /// Next crossing of a slab face by `i` (shear drive; particle at the current time): the
    /// `x` motion is force-free, so the time is linear.
    fn predict_slab(&self, i: usize) -> PlaneEvent {
        let Some(f) = &self.p.shear else {
            return PlaneEvent::NEVER;
        };
        let mut best = PlaneEvent::NEVER;
        if f.count() > 1 {
            let (x, v) = (self.body[i].x[0], self.body[i].v[0]);
            let (lo, hi) = f.faces(self.slab[i] as usize, x);
            best.keep_earlier(linear_time_to_plane(x, v, hi, true), 0, true);
            best.keep_earlier(linear_time_to_plane(x, v, lo, false), 0, false);
        }
        best.time += self.time;
        best
    }

    /// Moves `i` into the neighbouring slab (shear drive): its force changes, so it counts as
    /// a course change and every event of `i` is re-predicted.
    fn cross_slab(&mut self, i: usize, up: bool) {
        self.advance(i, self.time);
        self.counts.slab_crossings += 1;
        let f = self.p.shear.as_ref().expect("shear engine has slabs");
        let k = f.next(self.slab[i] as usize, up);
        self.slab[i] = k as u32;
        self.accel[i] = f.accel(k);
        self.count[i] = self.count[i].wrapping_add(1);
        self.predict_all(i);
    }

    /// Next collision of `i` with a wall (`up`: the lid or upper wall), and the tabulated
    /// approach speed of a shaken-wall hit (NaN unless the `table` solver provided one).
    fn predict_wall(&self, i: usize) -> (PlaneEvent, f64) {
        let mut best = PlaneEvent::NEVER;
        let mut vrel = f64::NAN;
        let r = self.body[i].r;
        for k in 0..D {
            if self.p.periodic[k] {
                continue;
            }
            let ((t_lid, v_lid), (t_floor, v_floor)) = match self.p.drive {
                Some(w) if k == D - 1 => self.shaken_wall_times(i, &w),
                _ => {
                    let (lid, floor) = self.times_to_planes(i, k, r, self.p.size[k] - r);
                    ((lid, f64::NAN), (floor, f64::NAN))
                }
            };
            if t_lid < best.time {
                vrel = v_lid;
            }
            best.keep_earlier(t_lid, k, true);
            if t_floor < best.time {
                vrel = v_floor;
            }
            best.keep_earlier(t_floor, k, false);
        }
        best.time += self.time;
        (best, vrel)
    }

    /// Times until particle `i` meets the shaken lid and floor (MODEL.md 6), with the scene's
    /// solver (`physics::shaken_wall`). The search looks two periods ahead; a
    /// particle that meets neither gets a re-check at the horizon (a wall event that finds no
    /// contact and only re-predicts). The lid is the floor problem mirrored: depth below the
    /// lid's mean position, velocity reversed, gravity pointing away, wall phase shifted by pi.
    fn shaken_wall_times(&self, i: usize, w: &WallMotion) -> ((f64, f64), (f64, f64)) {
        let b = &self.body[i];
        let (z, vz, r) = (b.x[D - 1], b.v[D - 1], b.r);
        let t = self.time;
        let horizon = 2.0 * w.period();
        let tol = self.p.root_tolerance;
        let half_period = 0.5 * w.period();
        let lid_motion = WallMotion { g: -w.g, ..*w };
        let h_lid = self.p.size[D - 1] - z - r;
        // (time, tabulated approach speed); a miss is a re-check at the horizon for the floor
        // (gravity brings every flight back) and never for the lid.
        let exact = |w: &WallMotion, h: f64, v: f64, t0: f64, miss: f64| {
            let root = match self.p.wall_solver {
                WallSolverKind::Bracket => bracket_root(w, h, v, t0, self.p.t_min, tol, horizon),
                _ => exact_root(w, h, v, t0, tol, horizon),
            };
            match root {
                WallRoot::Hit(dt) => (dt, f64::NAN),
                WallRoot::None => (miss, f64::NAN),
            }
        };
        let tables = match &self.p.tables {
            Some(t) if self.distrusted != Some(i) => Some(t),
            _ => None,
        };
        let Some(tables) = tables else {
            return (
                exact(&lid_motion, h_lid, -vz, t + half_period, f64::INFINITY),
                exact(w, z - r, vz, t, horizon),
            );
        };
        // The `table` solver (B.4-B.5), with the exact solver where the table does not answer.
        let tabulated = |k: usize, h: f64, v: f64, t0: f64, miss: f64| {
            let table = &tables[k];
            let answer = match self.launched {
                Some((j, lid)) if j == i && lid == (k == 1) => {
                    // Just left this wall, placed on it: the wall-edge table (B.5.2).
                    let v_rel = v - table.motion().velocity(t0);
                    table.next_hit_after_wall(v_rel, t0, horizon)
                }
                _ => table.next_hit(h, v, t0, horizon),
            };
            match answer {
                TableHit::Hit { dt, v_rel } => (dt, v_rel),
                // Behind the wall by the table's roots: collide now if the gap agrees (B.5.6),
                // else the table erred near a root and the exact solver decides.
                TableHit::Now if h - table.motion().position(t0) <= 1e3 * tol + 1e-12 => {
                    (0.0, f64::NAN)
                }
                TableHit::Now => exact(table.motion(), h, v, t0, miss),
                TableHit::None => (miss, f64::NAN),
                TableHit::OutOfRange => exact(table.motion(), h, v, t0, miss),
            }
        };
        (
            tabulated(1, h_lid, -vz, t + half_period, f64::INFINITY),
            tabulated(0, z - r, vz, t, horizon),
        )
    }

    #[inline]
    fn queue_key(&self, i: usize) -> f64 {
        let key = self.pair_ev[i]
            .time
            .min(self.cross_ev[i].time)
            .min(self.wall_ev[i].time);
        if SHEAR {
            key.min(self.slab_ev[i].time)
        } else {
            key
        }
    }

    /// Full re-prediction of every event of `i` (which must be at the current time).
    fn predict_all(&mut self, i: usize) {
        self.advance(i, self.time);
        if SHEAR {
            // Before the pair scan: sheared pair predictions stop at the first slab exit.
            self.slab_ev[i] = self.predict_slab(i);
        }
        self.pair_ev[i] = PairEvent::NEVER;
        let offsets = std::mem::take(&mut self.offsets);
        self.scan_cells(i, &offsets);
        self.offsets = offsets;
        self.cross_ev[i] = self.predict_crossing(i);
        (self.wall_ev[i], self.wall_vrel[i]) = self.predict_wall(i);
        if self.launched.is_some_and(|(j, _)| j == i) {
            self.launched = None;
        }
        if self.distrusted == Some(i) {
            self.distrusted = None;
        }
        self.queue.update(i, self.queue_key(i));
    }

    // ----- event processing --------------------------------------------------------------

    /// Processes every event up to time `t_end` (exclusive of later ones) or until `max_events`
    /// events have been processed in total; leaves the clock at `t_end` if it got there.
    /// Returns `false` if it stopped on the event cap.
    pub fn run_until(&mut self, t_end: f64, max_events: Option<u64>) -> bool {
        loop {
            if let Some(cap) = max_events
                && self.counts.total() >= cap
            {
                return false;
            }
            let Some((i, t)) = self.queue.min() else {
                break;
            };
            if t > t_end || t == f64::INFINITY {
                break;
            }
            self.step(i, t);
            if self.counts.total() >= self.next_reorder {
                self.reorder_by_cell();
            }
        }
        if t_end.is_finite() {
            self.time = self.time.max(t_end);
        }
        true
    }

    /// Sets how many events pass between two renumberings in cell order (`u64::MAX`: never).
    /// The default grows with the particle count; tests use this to prove the renumbering is a
    /// pure relabelling.
    pub fn set_reorder_interval(&mut self, events: u64) {
        self.reorder_every = events;
        self.next_reorder = self.counts.total().saturating_add(events);
    }

    /// Renumbers the particles in cell order so that neighbours sit close together in memory
    /// (a pair scan then mostly hits cache lines already loaded). A pure relabelling: no state,
    /// prediction or event time changes; the public API keeps speaking in scene order.
    fn reorder_by_cell(&mut self) {
        let n = self.len();
        self.next_reorder = self.counts.total().saturating_add(self.reorder_every);
        let mut order: Vec<u32> = (0..n as u32).collect();
        order.sort_by_key(|&k| (self.grid.linear(&self.cell[k as usize]), k));
        // new index of every old index
        let mut new_of_old = vec![0u32; n];
        for (new, &old) in order.iter().enumerate() {
            new_of_old[old as usize] = new as u32;
        }
        let pick = |k: u32| k as usize;
        self.body = order.iter().map(|&k| self.body[pick(k)]).collect();
        self.count = order.iter().map(|&k| self.count[pick(k)]).collect();
        self.last_collision = order
            .iter()
            .map(|&k| self.last_collision[pick(k)])
            .collect();
        self.cell = order.iter().map(|&k| self.cell[pick(k)]).collect();
        self.cross_ev = order.iter().map(|&k| self.cross_ev[pick(k)]).collect();
        self.wall_ev = order.iter().map(|&k| self.wall_ev[pick(k)]).collect();
        self.wall_vrel = order.iter().map(|&k| self.wall_vrel[pick(k)]).collect();
        if SHEAR {
            self.slab = order.iter().map(|&k| self.slab[pick(k)]).collect();
            self.accel = order.iter().map(|&k| self.accel[pick(k)]).collect();
            self.slab_ev = order.iter().map(|&k| self.slab_ev[pick(k)]).collect();
        }
        self.pair_ev = order
            .iter()
            .map(|&k| {
                let mut e = self.pair_ev[pick(k)];
                if e.partner != NONE {
                    e.partner = new_of_old[e.partner as usize];
                }
                e
            })
            .collect();
        if WET {
            let mut bonds = vec![NONE; n * MAX_BONDS];
            let mut bond_len = vec![0u8; n];
            for (new, &old) in order.iter().enumerate() {
                let old = old as usize;
                let len = self.bond_len[old] as usize;
                for m in 0..len {
                    bonds[new * MAX_BONDS + m] =
                        new_of_old[self.bonds[old * MAX_BONDS + m] as usize];
                }
                bond_len[new] = len as u8;
            }
            self.bonds = bonds;
            self.bond_len = bond_len;
        }
        self.id = order.iter().map(|&k| self.id[pick(k)]).collect();
        for (new, &orig) in self.id.iter().enumerate() {
            self.slot_of[orig as usize] = new as u32;
        }
        self.grid.clear();
        for k in 0..n {
            let c = self.grid.linear(&self.cell[k]);
            self.grid.insert(k, c);
        }
        self.queue = Q::new(n);
        for k in 0..n {
            self.queue.update(k, self.queue_key(k));
        }
    }

    /// Processes the earliest event, which belongs to particle `i` at time `t`.
    fn step(&mut self, i: usize, t: f64) {
        if t < self.time {
            // Predictions are clamped at "now", so this only reflects round-off in the clock.
            if t < self.time - 1e-12 * self.time.abs().max(1.0) {
                self.time_reversals += 1;
            }
        } else {
            self.time = t;
        }
        let pair = self.pair_ev[i];
        let cross = self.cross_ev[i];
        let wall = self.wall_ev[i];
        let slab = if SHEAR {
            self.slab_ev[i]
        } else {
            PlaneEvent::NEVER
        };
        if pair.time <= cross.time && pair.time <= wall.time && pair.time <= slab.time {
            let j = pair.partner as usize;
            if self.count[j] != pair.partner_count {
                self.counts.invalidated += 1;
                self.predict_all(i);
                return;
            }
            match pair.kind {
                PairKind::Collide => self.collide(i, j),
                PairKind::Well => self.well_edge(i, j),
            }
            self.predict_all(i);
            self.predict_all(j);
        } else if SHEAR && slab.time <= cross.time && slab.time <= wall.time {
            self.cross_slab(i, slab.up);
        } else if wall.time <= cross.time {
            self.wall_collision(i, wall.axis as usize, wall.up);
            self.predict_all(i);
        } else {
            self.cross_cell(i, cross.axis as usize, cross.up);
        }
    }

    /// Books a collision of normal speed `u_in` (in the frame of the partner or wall) with
    /// coefficient `e` that left at `u_out`: plain restitution dissipates
    /// `inertia/2 (u_in^2 - e^2 u_in^2)`; what the collapse remedies kept or added on top,
    /// `inertia/2 (u_out^2 - e^2 u_in^2) >= 0`, is booked apart (`inertia` = `m/2` for pairs,
    /// `m` for walls).
    #[inline]
    fn book_restitution(&mut self, inertia: f64, u_in: f64, e: f64, u_out: f64) {
        let plain = e * u_in;
        self.dissipated_restitution += 0.5 * inertia * (u_in * u_in - plain * plain);
        self.added += 0.5 * inertia * (u_out * u_out - plain * plain);
    }

    /// Unit normal from `j` to `i` and the normal relative velocity, both particles at `time`.
    fn normal(&mut self, i: usize, j: usize) -> (Vector<D>, f64) {
        let t = self.time;
        self.advance(i, t);
        self.advance(j, t);
        let r = self.min_image(self.body[i].x - self.body[j].x);
        let n = r / r.norm();
        let u = (self.body[i].v - self.body[j].v).dot(&n);
        (n, u)
    }

    /// Pair collision with restitution (Eqs. 2.3-2.4) and, if wet, bridge formation.
    fn collide(&mut self, i: usize, j: usize) {
        let (n, u) = self.normal(i, j);
        self.count[i] = self.count[i].wrapping_add(1);
        self.count[j] = self.count[j].wrapping_add(1);
        if u < 0.0 {
            let since = self.time - self.last_collision[i].max(self.last_collision[j]);
            let u_out = rebound_speed(-u, self.p.eps, since, self.p.tc, self.p.min_rebound);
            // Change of the normal relative velocity, shared equally (equal masses).
            let du = u_out - u;
            self.body[i].v += n * (0.5 * du);
            self.body[j].v -= n * (0.5 * du);
            self.book_restitution(0.5 * self.p.mass, -u, self.p.eps, u_out);
            self.last_collision[i] = self.time;
            self.last_collision[j] = self.time;
        }
        self.counts.pair_collisions += 1;
        if WET && !self.bonded(i, j) {
            self.add_bond_half(i, j);
            self.add_bond_half(j, i);
            self.counts.bridge_formations += 1;
        }
    }

    /// Bonded pair at `s = s_crit`: bounce or rupture (MODEL.md 3.2).
    fn well_edge(&mut self, i: usize, j: usize) {
        let (n, u) = self.normal(i, j);
        self.count[i] = self.count[i].wrapping_add(1);
        self.count[j] = self.count[j].wrapping_add(1);
        // A pair on the edge moving tangentially (u <= 0 by round-off) is treated as touching the
        // wall with zero normal speed.
        let u_in = u.max(0.0);
        let u_out = match well_outcome(self.p.mass, u_in, self.p.e_cb, self.p.rule) {
            WellOutcome::Bounce(reflected) => {
                self.counts.well_bounces += 1;
                // A pair grazing the concave well wall would bounce ever more often (about
                // pi / angle bounces to slide round): it leaves the wall inwards at least at the
                // rebound floor, and the energy that adds is booked with the collapse remedies.
                let u_out = reflected.min(-self.p.min_rebound);
                self.added += 0.25 * self.p.mass * (u_out * u_out - u * u);
                u_out
            }
            WellOutcome::Rupture {
                new_normal_speed,
                energy,
            } => {
                self.remove_bond_half(i, j);
                self.remove_bond_half(j, i);
                self.dissipated_ruptures += energy;
                self.counts.bridge_ruptures += 1;
                new_normal_speed
            }
        };
        let du = u_out - u;
        self.body[i].v += n * (0.5 * du);
        self.body[j].v -= n * (0.5 * du);
    }

    /// Collision with a flat static wall: `v_n' = e_w v_n` reversed.
    fn wall_collision(&mut self, i: usize, axis: usize, lid: bool) {
        if let Some(w) = self.p.drive
            && axis == D - 1
        {
            self.shaken_wall_collision(i, &w, lid);
            return;
        }
        self.advance(i, self.time);
        let v = self.body[i].v[axis];
        // A grain exactly at rest on a floor under gravity is pressed into it: approaching.
        let floor_under_gravity = GRAV && axis == D - 1 && !lid;
        let approaching = if lid {
            v > 0.0
        } else if floor_under_gravity {
            v <= 0.0
        } else {
            v < 0.0
        };
        if !approaching {
            // Round-off put the event a hair late: nothing to do (the caller re-predicts).
            return;
        }
        self.count[i] = self.count[i].wrapping_add(1);
        self.counts.wall_collisions += 1;
        let since = self.time - self.last_collision[i];
        let mut u_out = rebound_speed(v.abs(), self.p.e_wall, since, self.p.tc, self.p.min_rebound);
        if floor_under_gravity {
            // Rest on a static floor is the one state an event-driven engine cannot represent
            // (zero-time bounces): no grain leaves the floor slower than the rebound floor.
            u_out = u_out.max(self.p.min_rebound);
        }
        self.book_restitution(self.p.mass, v.abs(), self.p.e_wall, u_out);
        self.body[i].v[axis] = if lid { -u_out } else { u_out };
        self.last_collision[i] = self.time;
    }

    /// Collision with the shaken floor or lid, `v' = v_w + e_w (v_w - v)` along the normal
    /// (MODEL.md 4.1), with the collapse remedies applied to the speed relative to the wall. An
    /// event that finds the particle away from the wall is a re-check and changes nothing.
    fn shaken_wall_collision(&mut self, i: usize, w: &WallMotion, lid: bool) {
        let t = self.time;
        self.advance(i, t);
        let b = self.body[i];
        let (z, vz) = (b.x[D - 1], b.v[D - 1]);
        let (z_w, v_w) = (w.position(t), w.velocity(t));
        // Gap and approach speed in the wall's frame, both positive when the particle is on the
        // right side and approaching.
        let (gap, mut u_in) = if lid {
            (self.p.size[D - 1] + z_w - z - b.r, vz - v_w)
        } else {
            (z - b.r - z_w, v_w - vz)
        };
        let tabulated = self.wall_vrel[i];
        let (contact, approaching) = if tabulated.is_finite() {
            // A tabulated hit (B.5.1): its approach speed is positive by construction (B.5.4);
            // the table's time error is absorbed by placing the particle on the wall.
            (gap.abs() <= TABLE_PLACEMENT_TOLERANCE, true)
        } else {
            (
                gap <= 1e3 * self.p.root_tolerance + 1e-12,
                if lid { u_in > 0.0 } else { u_in >= 0.0 },
            )
        };
        if !(contact && approaching) {
            // The caller re-predicts (with the exact solver after a table error).
            self.counts.wall_rechecks += 1;
            if tabulated.is_finite() {
                self.distrusted = Some(i);
            }
            return;
        }
        if tabulated.is_finite() {
            u_in = tabulated;
            let z_new = if lid {
                self.p.size[D - 1] + z_w - b.r
            } else {
                z_w + b.r
            };
            if GRAV {
                self.placement += self.p.mass * self.p.gravity * (z_new - z);
            }
            self.body[i].x[D - 1] = z_new;
            // The shift may cross a cell face: keep the cell lists right (the caller rescans
            // the neighbourhood).
            let x: [f64; D] = self.body[i].x.into();
            let c = self.grid.locate(&x);
            if c != self.cell[i] {
                let old = self.grid.linear(&self.cell[i]);
                self.grid.remove(i, old);
                self.cell[i] = c;
                let new = self.grid.linear(&c);
                self.grid.insert(i, new);
            }
            self.launched = Some((i, lid));
        }
        self.count[i] = self.count[i].wrapping_add(1);
        self.counts.wall_collisions += 1;
        let since = t - self.last_collision[i];
        let mut u_out = rebound_speed(u_in, self.p.e_wall, since, self.p.tc, self.p.min_rebound);
        if !lid {
            // As on the static floor: no grain leaves the floor slower than the rebound floor.
            u_out = u_out.max(self.p.min_rebound);
        }
        let v_new = if lid { v_w - u_out } else { v_w + u_out };
        let m = self.p.mass;
        // Loss in the wall's frame; the rest of the kinetic energy change is the wall's work.
        self.book_restitution(m, u_in, self.p.e_wall, u_out);
        let de = 0.5 * m * (u_in * u_in - u_out * u_out);
        self.work_by_drive += 0.5 * m * (v_new * v_new - vz * vz) + de;
        self.body[i].v[D - 1] = v_new;
        self.last_collision[i] = t;
    }

    /// Moves `i` into the neighbouring cell and scans only the newly adjacent slab.
    fn cross_cell(&mut self, i: usize, axis: usize, up: bool) {
        self.advance(i, self.time);
        self.counts.cell_crossings += 1;
        let old = self.grid.linear(&self.cell[i]);
        self.grid.remove(i, old);
        let n = self.grid.n[axis];
        let c = &mut self.cell[i][axis];
        if up {
            *c += 1;
            if *c == n {
                *c = 0;
                self.body[i].x[axis] -= self.p.size[axis];
            }
        } else {
            *c -= 1;
            if *c < 0 {
                *c = n - 1;
                self.body[i].x[axis] += self.p.size[axis];
            }
        }
        let new = self.grid.linear(&self.cell[i]);
        self.grid.insert(i, new);
        // The far slab of the new neighbourhood: offset +-1 along `axis`, anything across.
        let step = if up { 1 } else { -1 };
        let mut slab = [[0i32; D]; 9];
        let mut m = 0;
        for o in &self.offsets {
            if o[axis] == step {
                slab[m] = *o;
                m += 1;
            }
        }
        self.scan_cells(i, &slab[..m]);
        self.cross_ev[i] = self.predict_crossing(i);
        self.queue.update(i, self.queue_key(i));
    }

    // ----- observables -------------------------------------------------------------------

    /// Position and velocity of every particle at the current time, in internal order. The
    /// stored delayed states are left as they are: observing never changes the round-off of a
    /// trajectory, so the sampling interval cannot change the physics.
    fn current_states(&self) -> Vec<(Vector<D>, Vector<D>)> {
        (0..self.len())
            .map(|i| self.state_at(i, self.time))
            .collect()
    }

    /// Energy bookkeeping at the current time.
    pub fn energy(&self) -> EnergyLedger {
        let m = self.p.mass;
        let states = self.current_states();
        let kinetic = states.iter().map(|(_, v)| 0.5 * m * v.norm_squared()).sum();
        let potential = if GRAV {
            states
                .iter()
                .map(|(x, _)| m * self.p.gravity * x[D - 1])
                .sum()
        } else {
            0.0
        };
        // The field's work on the flights not yet brought to the current time.
        let pending: f64 = if SHEAR {
            states
                .iter()
                .enumerate()
                .map(|(i, (x, _))| self.field_work(i, x))
                .sum()
        } else {
            0.0
        };
        EnergyLedger {
            kinetic,
            potential,
            dissipated_restitution: self.dissipated_restitution,
            dissipated_ruptures: self.dissipated_ruptures,
            added_by_collapse_remedies: self.added,
            added_by_wall_placement: self.placement,
            work_by_drive: self.work_by_drive + pending,
        }
    }

    /// Total momentum.
    pub fn momentum(&self) -> Vector<D> {
        let states = self.current_states();
        states.iter().fold(Vector::<D>::zeros(), |a, (_, v)| a + v) * self.p.mass
    }

    /// Granular temperature `T_g = m (<v^2> - <v>^2) / f_d` (Eq. 3.2, `k_B = 1`, `f_d = D`).
    pub fn granular_temperature(&self) -> f64 {
        let states = self.current_states();
        let n = self.len() as f64;
        let mean = states.iter().fold(Vector::<D>::zeros(), |a, (_, v)| a + v) / n;
        let mean_sq = states.iter().map(|(_, v)| v.norm_squared()).sum::<f64>() / n;
        self.p.mass * (mean_sq - mean.norm_squared()) / D as f64
    }

    /// Positions at the current time, in scene order.
    pub fn positions(&self) -> Vec<Vector<D>> {
        let states = self.current_states();
        self.slot_of.iter().map(|&k| states[k as usize].0).collect()
    }

    /// Velocities at the current time, in scene order.
    pub fn velocities(&self) -> Vec<Vector<D>> {
        let states = self.current_states();
        self.slot_of.iter().map(|&k| states[k as usize].1).collect()
    }

    /// A per-particle constant listed in scene order (the order of the initial state).
    fn in_scene_order<T: Clone>(&self, f: impl Fn(&Body<D>) -> T) -> Vec<T> {
        self.slot_of
            .iter()
            .map(|&k| f(&self.body[k as usize]))
            .collect()
    }

    /// Particle radii.
    pub fn radii(&self) -> Vec<f64> {
        self.in_scene_order(|b| b.r)
    }

    /// Number of events processed out of time order beyond round-off (must be 0).
    pub fn time_reversals(&self) -> u64 {
        self.time_reversals
    }

    /// Overwrites the velocity of particle `i` at the current time (tests and set-ups) and
    /// re-predicts its events.
    pub fn set_velocity(&mut self, i: usize, v: Vector<D>) {
        let i = self.slot_of[i] as usize;
        self.advance(i, self.time);
        self.body[i].v = v;
        self.count[i] = self.count[i].wrapping_add(1);
        self.predict_all(i);
    }

    /// Overwrites the position of particle `i` at the current time (tests and set-ups), moves
    /// it to its new cell and re-predicts its events.
    pub fn set_position(&mut self, i: usize, x: Vector<D>) {
        let i = self.slot_of[i] as usize;
        self.advance(i, self.time);
        let old = self.grid.linear(&self.cell[i]);
        self.grid.remove(i, old);
        self.body[i].x = x;
        let arr: [f64; D] = x.into();
        self.cell[i] = self.grid.locate(&arr);
        if let Some(f) = &self.p.shear {
            let k = f.slab_of(x[0]);
            self.slab[i] = k as u32;
            self.accel[i] = f.accel(k);
        }
        let new = self.grid.linear(&self.cell[i]);
        self.grid.insert(i, new);
        self.count[i] = self.count[i].wrapping_add(1);
        self.predict_all(i);
    }

    /// Recomputes every still-valid pair event from the current states and reports the first
    /// one that disagrees with the stored prediction (debugging aid for lazy invalidation).
    pub fn check_predictions(&self) -> Result<(), String> {
        let t = self.time;
        for i in 0..self.len() {
            let pe = self.pair_ev[i];
            if pe.partner == NONE || self.count[pe.partner as usize] != pe.partner_count {
                continue;
            }
            let j = pe.partner as usize;
            let (xi, vi) = self.state_at(i, t);
            let now = self.predict_pair_from(&xi, &vi, i, j, t);
            match now {
                Some((tn, kind))
                    if (tn - pe.time).abs() <= 1e-6 * (tn - t).abs().max(1e-3)
                        && kind == pe.kind => {}
                other => {
                    return Err(format!(
                        "particle {i}: stored {:?} with {j} at {:.17}, recomputed {other:?} at t={t}",
                        pe.kind, pe.time
                    ));
                }
            }
        }
        Ok(())
    }

    // ----- invariants --------------------------------------------------------------------

    /// Checks the invariants: finite numbers, every particle inside the box, no pair overlap
    /// and no bonded pair beyond `s_crit` by more than the tolerance, every particle in the
    /// cell its position says, no event scheduled in the past, no time reversal. Returns a
    /// description of the first violation.
    pub fn sanity_check(&self) -> Result<(), String> {
        let states = self.current_states();
        let tol = self.p.overlap_tolerance;
        let t = self.time;
        if self.time_reversals > 0 {
            return Err(format!(
                "{} events processed out of time order",
                self.time_reversals
            ));
        }
        for i in 0..self.len() {
            // Messages name particles by their scene index.
            let si = self.id[i];
            let (x, v) = states[i];
            if !x.iter().chain(v.iter()).all(|a| a.is_finite()) {
                return Err(format!("particle {si} has a non-finite state at t = {t}"));
            }
            for k in 0..D {
                // The shaken floor and lid move by z_w(t).
                let shift = match self.p.drive {
                    Some(w) if k == D - 1 => w.position(t),
                    _ => 0.0,
                };
                let r = self.body[i].r;
                let (lo, hi) = if self.p.periodic[k] {
                    (0.0, self.p.size[k])
                } else {
                    (r + shift, self.p.size[k] - r + shift)
                };
                if x[k] < lo - tol || x[k] > hi + tol {
                    return Err(format!(
                        "particle {si} is outside the box along axis {k}: x = {} not in [{lo}, {hi}] at t = {t}",
                        x[k]
                    ));
                }
                // Edge cells of a wall axis extend outwards (the shaken floor leaves the grid).
                let w = self.grid.width[k];
                let c = self.cell[i][k];
                let open_lo = !self.p.periodic[k] && c == 0;
                let open_hi = !self.p.periodic[k] && c == self.grid.n[k] - 1;
                let (c_lo, c_hi) = (c as f64 * w, (c as f64 + 1.0) * w);
                if (!open_lo && x[k] < c_lo - tol) || (!open_hi && x[k] > c_hi + tol) {
                    return Err(format!(
                        "particle {si} at {} is not in its cell {c} along axis {k} at t = {t}",
                        x[k]
                    ));
                }
            }
            if SHEAR && let Some(f) = &self.p.shear {
                let (lo, hi) = f.faces(self.slab[i] as usize, x[0]);
                if x[0] < lo - tol || x[0] > hi + tol {
                    return Err(format!(
                        "particle {si} at x = {} is not in its slab {} [{lo}, {hi}] at t = {t}",
                        x[0], self.slab[i]
                    ));
                }
            }
            if self.queue.key(i) < t - 1e-9 * t.abs().max(1.0) {
                return Err(format!(
                    "particle {si} has an event in the past: {} < {t}",
                    self.queue.key(i)
                ));
            }
        }
        for i in 0..self.len() {
            let si = self.id[i];
            for o in &self.offsets {
                let Some(cell) = self.grid.shifted(&self.cell[i], o) else {
                    continue;
                };
                let mut err = None;
                self.grid.for_each_in(cell, |j| {
                    if j <= i || err.is_some() {
                        return;
                    }
                    let sj = self.id[j];
                    let r = self.min_image(states[i].0 - states[j].0).norm();
                    let sigma = self.body[i].r + self.body[j].r;
                    if r < sigma - tol {
                        err = Some(format!(
                            "particles {si} and {sj} overlap by {} at t = {t}",
                            sigma - r
                        ));
                    }
                });
                if let Some(e) = err {
                    return Err(e);
                }
            }
            if WET {
                let base = i * MAX_BONDS;
                for &j in &self.bonds[base..base + self.bond_len[i] as usize] {
                    let j = j as usize;
                    let sj = self.id[j];
                    let r = self.min_image(states[i].0 - states[j].0).norm();
                    let lambda = self.body[i].r + self.body[j].r + self.p.s_crit;
                    if r > lambda + tol {
                        return Err(format!(
                            "bonded pair {si}-{sj} stretched beyond s_crit by {} at t = {t}",
                            r - lambda
                        ));
                    }
                    if !self.bonded(j, i) {
                        return Err(format!("bond {si}-{sj} is one-sided"));
                    }
                }
            }
        }
        Ok(())
    }
}
