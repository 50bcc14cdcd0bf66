//! The event-driven engine for hard disks (`D = 2`) and spheres (`D = 3`): a small scheduler
//! over event sources (ARCHITECTURE.md, "Event engine": the sources, one step, renumbering).
//!
//! The engine owns the clock, the particles ([`Bodies`]), the queue (`Q`, any [`EventQueue`]),
//! the books ([`EnergyLedger`], [`EventCounts`]) and the sources ([`PairSource`], [`CellSource`],
//! [`WallSource`], [`SlabSource`]), each of which predicts, fires and renumbers its own events
//! ([`EventSource`]). Effects are compile-time parameters (`GRAV`, `WET`, `SHEAR` and the queue
//! `Q`): a dry, gravity-free or unsheared scene runs code in which the other branches do not
//! exist. Numerical safeguards live with the source they protect (see each module's header)
//! and are each tested in `crates/core/tests/engine_safeguards.rs`.

pub use super::bodies::Vector;
use super::bodies::{Bodies, Body};
use super::cell_source::CellSource;
use super::cells::CellGrid;
use super::event::{Event, EventKind, EventSource, NONE};
use super::pairs::PairSource;
use super::queue::{CalendarQueue, EventQueue};
use super::shear::{FORCE_AXIS, ShearField};
use super::slabs::SlabSource;
use super::table_cache::{DEFAULT_TABLE_CACHE_MIB, TableCache};
use super::walls::WallSource;
use crate::scene::{Boundary, Scene};
use crate::sim::books::{EnergyLedger, EventCounts};
use crate::sim::initial::{FlatInitialState, initial_state_flat};

mod checks;

/// Events between two renumberings of the particles in cell order (see `reorder_by_cell`).
fn reorder_interval(n: usize) -> u64 {
    (20 * n as u64).max(100_000)
}

/// The event-driven simulation state.
#[derive(Debug, Clone)]
pub struct Engine<
    const D: usize,
    const GRAV: bool,
    const WET: bool,
    const SHEAR: bool = false,
    Q: EventQueue = CalendarQueue,
> {
    /// Current simulation time (time of the last processed event).
    time: f64,
    bodies: Bodies<D, GRAV, SHEAR>,
    queue: Q,
    pairs: PairSource<D, WET>,
    cells: CellSource<D>,
    walls: WallSource,
    slabs: SlabSource,
    counts: EventCounts,
    /// The energy exchanged at events (kinetic and potential are filled in by `energy`; the
    /// shear field's work on flights is kept by `Bodies`, which does the flights).
    ledger: EnergyLedger,
    /// Largest overlap the invariant check tolerates.
    overlap_tolerance: f64,
    /// Events whose time lay before the current time by more than round-off (must stay 0).
    time_reversals: u64,
    /// Event count at which particles are next renumbered in cell order, and the interval.
    next_reorder: u64,
    reorder_every: u64,
}

impl<const D: usize, const GRAV: bool, const WET: bool, const SHEAR: bool, Q: EventQueue>
    Engine<D, GRAV, WET, SHEAR, Q>
{
    /// Builds the engine for a validated scene: initial state, cells, first predictions; a
    /// `table` wall solver builds its tables into a cache of its own.
    pub fn new(scene: &Scene) -> Self {
        Self::from_state(
            scene,
            None,
            &TableCache::with_cap_mib(DEFAULT_TABLE_CACHE_MIB),
        )
    }

    /// Takes the bridges, event counts and energy books of a saved state (resumed at `t0`).
    fn restore(&mut self, st: &crate::sim::EngineState, t0: f64) {
        if WET {
            for &(i, j) in &st.bridges {
                let (id_i, id_j) = (self.bodies.id[i], self.bodies.id[j]);
                self.pairs.add_bond_half(i, j, id_i, t0);
                self.pairs.add_bond_half(j, i, id_j, t0);
            }
        }
        self.counts = st.counts.clone();
        self.ledger = st.ledger.clone();
        if SHEAR {
            // The shear field's work is summed where the flights are done.
            self.bodies.field_work = st.ledger.work_by_drive;
        }
        self.next_reorder = self.counts.total().saturating_add(self.reorder_every);
    }

    /// The engine of [`Self::new`] or, with `Some(state)`, rebuilt from a saved state
    /// (`sim::state`): particles at the state's time, bridges, event counts and energy ledger
    /// continued, cells and predictions derived afresh, the TC remedy's last-collision times
    /// unset. It follows the uninterrupted run to round-off (`observe_runs.rs`,
    /// `checkpoint_continues_the_event_trajectory`). A `table` wall solver takes its tables
    /// from `tables`.
    pub(crate) fn from_state(
        scene: &Scene,
        start: Option<&crate::sim::EngineState>,
        tables: &TableCache,
    ) -> Self {
        let init = start.map_or_else(|| initial_state_flat(scene), FlatInitialState::of_state);
        let t0 = start.map_or(0.0, |s| s.time);
        let shear = scene.shear_slabs().is_some();
        assert_eq!(
            (scene.dimension, scene.gravity > 0.0, scene.is_wet(), shear),
            (D, GRAV, WET, SHEAR),
            "the scene's dimension, gravity, capillary and shear flags do not match the engine"
        );
        assert!(!SHEAR || D > FORCE_AXIS, "shear needs a y axis");
        let n = init.radius.len();
        // Pair events pack the partner's index into 31 bits (`event::PairEvent`).
        assert!(
            n < (1 << 31) - 1,
            "too many particles for the event engine: {n}"
        );
        let size: [f64; D] = std::array::from_fn(|k| scene.container.size[k]);
        let boundaries = scene.boundaries();
        let periodic: [bool; D] = std::array::from_fn(|k| boundaries[k] == Boundary::Periodic);
        let (_, d_max) = scene.diameter_range();
        let range = (d_max + scene.s_crit()).max(scene.engine.cell_size);
        let grid = CellGrid::new(size, periodic, range, n);
        assert!(
            grid.neighbourhood_is_distinct(),
            "box too small for the cell grid (validation should have caught this)"
        );
        let field = scene
            .shear_slabs()
            .map(|s| ShearField::new(&s, scene.particles.mass, scene.container.size[0]));
        let slabs = SlabSource::new(field, init.position.chunks(D).map(|x| x[0]));
        let body: Vec<Body<D>> = (0..n)
            .map(|i| Body {
                x: Vector::<D>::from_column_slice(&init.position[i * D..(i + 1) * D]),
                t: t0,
                v: Vector::<D>::from_column_slice(&init.velocity[i * D..(i + 1) * D]),
                r: init.radius[i],
            })
            .collect();
        drop(init); // before the other arrays are built (peak memory)
        // Times of the last collisions feed only the TC model (`tc > 0`, docs/model.md 2.1).
        let tc_model = scene.engine.tc > 0.0;
        let bodies = Bodies {
            body,
            count: vec![0; n],
            last_collision: vec![f64::NEG_INFINITY; if tc_model { n } else { 0 }],
            accel: slabs.accelerations(),
            id: (0..n as u32).collect(),
            slot_of: (0..n as u32).collect(),
            size,
            periodic,
            gravity: scene.gravity,
            mass: scene.particles.mass,
            field_work: 0.0,
        };
        let cells = CellSource::new(grid, bodies.body.iter().map(|b| b.x));
        let pairs = PairSource::new(scene, n);
        let walls = WallSource::new(scene, n, !periodic.iter().all(|&p| p), tables);
        let mut engine = Self {
            time: t0,
            bodies,
            queue: Q::new(n),
            pairs,
            cells,
            walls,
            slabs,
            counts: EventCounts::default(),
            ledger: EnergyLedger::default(),
            overlap_tolerance: scene.engine.overlap_tolerance,
            time_reversals: 0,
            next_reorder: reorder_interval(n),
            reorder_every: reorder_interval(n),
        };
        if let Some(st) = start {
            engine.restore(st, t0);
        }
        for i in 0..n {
            engine.predict_all(i);
        }
        engine
    }

    pub fn len(&self) -> usize {
        self.bodies.len()
    }

    pub fn is_empty(&self) -> bool {
        self.bodies.is_empty()
    }

    pub fn time(&self) -> f64 {
        self.time
    }

    pub fn counts(&self) -> &EventCounts {
        &self.counts
    }

    pub fn bridge_count(&self) -> usize {
        self.pairs.bridge_count()
    }

    /// The capillary bridges as pairs of scene indices `(i, j)`, `i < j`, sorted (empty for dry
    /// scenes). Read-only view for the observers.
    pub fn bridges(&self) -> Vec<(usize, usize)> {
        let mut out = Vec::with_capacity(self.bridge_count());
        for k in 0..self.len() {
            for &b in self.pairs.bonds_of(k) {
                let (i, j) = (
                    self.bodies.id[k] as usize,
                    self.bodies.id[b as usize] as usize,
                );
                if i < j {
                    out.push((i, j));
                }
            }
        }
        out.sort_unstable();
        out
    }

    /// The earliest candidate event of `i` over the sources (pair, slab, wall, cell; ties go to
    /// the earlier-named source).
    #[inline]
    fn next_event(&self, i: usize) -> Event {
        let mut e = self.pairs.candidate(i);
        if SHEAR {
            e = e.earlier(self.slabs.candidate(i));
        }
        e.earlier(self.walls.candidate(i))
            .earlier(self.cells.candidate(i))
    }

    /// Queue key of `i`: the time of its earliest candidate.
    #[inline]
    fn queue_key(&self, i: usize) -> f64 {
        let key = self.pairs.ev[i]
            .time
            .min(self.cells.ev[i].time)
            .min(self.walls.time(i));
        if SHEAR {
            key.min(self.slabs.ev[i].time)
        } else {
            key
        }
    }

    /// The time of the earliest event of `i` other than its wall event.
    #[inline]
    fn earliest_but_walls(&self, i: usize) -> f64 {
        let t = self.pairs.ev[i].time.min(self.cells.ev[i].time);
        if SHEAR {
            t.min(self.slabs.ev[i].time)
        } else {
            t
        }
    }

    /// Full re-prediction of every event of `i` (brought to the current time first).
    fn predict_all(&mut self, i: usize) {
        let t = self.time;
        self.bodies.advance(i, t);
        if SHEAR {
            // Before the pair scan: sheared pair predictions stop at the first slab exit.
            self.slabs.predict(i, &self.bodies, t);
        }
        self.pairs.ev[i] = super::event::PairEvent::NEVER;
        self.pairs.scan(
            i,
            &self.cells.all,
            &self.bodies,
            &self.cells,
            &self.slabs,
            t,
        );
        self.cells.predict(i, &self.bodies, t);
        let other = self.earliest_but_walls(i);
        self.walls.predict(i, &self.bodies, t, other);
        self.queue.update(i, self.queue_key(i));
    }

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

    /// Processes the earliest event, which belongs to particle `i` at time `t`: validate, then
    /// dispatch to its source.
    fn step(&mut self, i: usize, t: f64) {
        if t < self.time {
            // Predictions are clamped at "now", so this only reflects round-off in the clock.
            if t < self.time - 1e-12 * self.time.abs().max(1.0) {
                self.time_reversals += 1;
            }
        } else {
            self.time = t;
        }
        let now = self.time;
        match self.next_event(i).kind {
            EventKind::Collide {
                partner,
                partner_count,
            }
            | EventKind::Well {
                partner,
                partner_count,
            } if self.bodies.count[partner as usize] != partner_count => {
                self.counts.invalidated += 1;
                self.predict_all(i);
            }
            kind @ (EventKind::Collide { partner, .. } | EventKind::Well { partner, .. }) => {
                let j = partner as usize;
                let (b, l, c) = (&mut self.bodies, &mut self.ledger, &mut self.counts);
                if matches!(kind, EventKind::Collide { .. }) {
                    self.pairs.collide(i, j, now, b, l, c);
                } else {
                    self.pairs.well_edge(i, j, now, b, l, c);
                }
                self.predict_all(i);
                self.predict_all(j);
            }
            EventKind::Slab { up } => {
                self.bodies.advance(i, now);
                self.counts.slab_crossings += 1;
                self.slabs.fire(i, up, &mut self.bodies);
                // The force changed: a course change.
                self.bodies.bump(i);
                self.predict_all(i);
            }
            EventKind::Wall { axis, up } => {
                self.walls.fire(
                    i,
                    axis as usize,
                    up,
                    now,
                    &mut self.bodies,
                    &mut self.cells,
                    &mut self.ledger,
                    &mut self.counts,
                );
                self.predict_all(i);
            }
            EventKind::Cell { axis, up } => {
                self.bodies.advance(i, now);
                self.counts.cell_crossings += 1;
                let axis = axis as usize;
                self.cells.fire(i, axis, up, &mut self.bodies);
                // Only the newly adjacent cells can hold an earlier partner.
                self.pairs.scan(
                    i,
                    self.cells.far_slab(axis, up),
                    &self.bodies,
                    &self.cells,
                    &self.slabs,
                    now,
                );
                self.cells.predict(i, &self.bodies, now);
                // The flight is unchanged: a stopped wall search goes on only if the new key
                // reaches its bound.
                let other = self.earliest_but_walls(i);
                self.walls.resume::<D>(i, other);
                self.queue.update(i, self.queue_key(i));
            }
            EventKind::Never => unreachable!("a particle with a finite key has an event"),
        }
    }

    /// Sets how many events pass between two renumberings in cell order (`u64::MAX`: never).
    pub fn set_reorder_interval(&mut self, events: u64) {
        self.reorder_every = events;
        self.next_reorder = self.counts.total().saturating_add(events);
    }

    /// Renumbers the particles in cell order so that neighbours sit close together in memory.
    /// A pure relabelling (no state, prediction or event time changes; the public API keeps
    /// speaking in scene order): each source permutes its own per-particle state.
    fn reorder_by_cell(&mut self) {
        let n = self.len();
        self.next_reorder = self.counts.total().saturating_add(self.reorder_every);
        let order = self.cells.cell_order();
        let mut new_of_old = vec![0u32; n];
        for (new, &old) in order.iter().enumerate() {
            new_of_old[old as usize] = new as u32;
        }
        self.bodies.permute(&order);
        self.pairs.permute(&order, &new_of_old);
        self.cells.permute(&order, &new_of_old);
        self.walls.permute(&order, &new_of_old);
        self.slabs.permute(&order, &new_of_old);
        // The old queue goes before the new one is built (peak memory).
        self.queue = Q::new(0);
        self.queue = Q::new(n);
        for k in 0..n {
            self.queue.update(k, self.queue_key(k));
        }
    }

    /// Position and velocity of every particle at the current time, in internal order, leaving
    /// the delayed states alone (observing never changes the round-off of a trajectory), and
    /// without allocating: computed as they are read.
    fn current_states(&self) -> impl Iterator<Item = (Vector<D>, Vector<D>)> + '_ {
        (0..self.len()).map(|i| self.bodies.state_at(i, self.time))
    }

    pub fn energy(&self) -> EnergyLedger {
        let m = self.bodies.mass;
        let kinetic = self
            .current_states()
            .map(|(_, v)| 0.5 * m * v.norm_squared())
            .sum();
        let potential = if GRAV {
            self.current_states()
                .map(|(x, _)| m * self.bodies.gravity * x[D - 1])
                .sum()
        } else {
            0.0
        };
        let mut out = EnergyLedger {
            kinetic,
            potential,
            ..self.ledger.clone()
        };
        if SHEAR {
            // The shear field's work, including the flights not yet brought to the current
            // time (the ledger's is the shaken walls'; the two drives exclude each other).
            let pending: f64 = self
                .current_states()
                .enumerate()
                .map(|(i, (x, _))| self.bodies.field_work(i, &x))
                .sum();
            out.work_by_drive = self.bodies.field_work + pending;
        }
        out
    }

    /// The kinetic and potential energies of [`Self::energy`] and the granular temperature of
    /// [`Self::granular_temperature`] in one pass over the particles (a report sample), each
    /// summed in the same order, so with the same bits.
    pub fn sample_energies(&self) -> (f64, f64, f64) {
        let (m, g, n) = (self.bodies.mass, self.bodies.gravity, self.len() as f64);
        // `-0.0` is the neutral element of a float sum, as in `Iterator::sum`.
        let (mut kinetic, mut potential, mut v_sq) = (-0.0f64, -0.0f64, -0.0f64);
        let mut v_sum = Vector::<D>::zeros();
        for (x, v) in self.current_states() {
            let v2 = v.norm_squared();
            kinetic += 0.5 * m * v2;
            if GRAV {
                potential += m * g * x[D - 1];
            }
            v_sum += v;
            v_sq += v2;
        }
        let mean = v_sum / n;
        let t_g = m * (v_sq / n - mean.norm_squared()) / D as f64;
        (kinetic, if GRAV { potential } else { 0.0 }, t_g)
    }

    pub fn momentum(&self) -> Vector<D> {
        self.current_states()
            .fold(Vector::<D>::zeros(), |a, (_, v)| a + v)
            * self.bodies.mass
    }

    /// Granular temperature `T_g = m (<v^2> - <v>^2) / f_d` (Eq. 3.2, `k_B = 1`, `f_d = D`).
    pub fn granular_temperature(&self) -> f64 {
        let n = self.len() as f64;
        let mean = self
            .current_states()
            .fold(Vector::<D>::zeros(), |a, (_, v)| a + v)
            / n;
        let mean_sq = self
            .current_states()
            .map(|(_, v)| v.norm_squared())
            .sum::<f64>()
            / n;
        self.bodies.mass * (mean_sq - mean.norm_squared()) / D as f64
    }

    /// `f` of each particle's internal index, in scene order.
    fn in_scene_order<T>(&self, f: impl Fn(usize) -> T) -> Vec<T> {
        self.bodies.slot_of.iter().map(|&k| f(k as usize)).collect()
    }

    /// Positions at the current time, in scene order.
    pub fn positions(&self) -> Vec<Vector<D>> {
        self.in_scene_order(|k| self.bodies.state_at(k, self.time).0)
    }

    /// Velocities at the current time, in scene order.
    pub fn velocities(&self) -> Vec<Vector<D>> {
        self.in_scene_order(|k| self.bodies.state_at(k, self.time).1)
    }

    /// Particle radii, in scene order.
    pub fn radii(&self) -> Vec<f64> {
        self.in_scene_order(|k| self.bodies.body[k].r)
    }

    /// Overwrites the velocity of particle `i` at the current time (tests and set-ups) and
    /// re-predicts its events.
    pub fn set_velocity(&mut self, i: usize, v: Vector<D>) {
        let i = self.bodies.slot_of[i] as usize;
        self.bodies.advance(i, self.time);
        self.bodies.body[i].v = v;
        self.bodies.bump(i);
        self.predict_all(i);
    }

    /// Overwrites the position of particle `i` at the current time (tests and set-ups), moves
    /// it to its new cell (and slab) and re-predicts its events.
    pub fn set_position(&mut self, i: usize, x: Vector<D>) {
        let i = self.bodies.slot_of[i] as usize;
        self.bodies.advance(i, self.time);
        self.bodies.body[i].x = x;
        self.cells.relocate(i, &x);
        self.slabs.relocate(i, x[0], &mut self.bodies);
        self.bodies.bump(i);
        self.predict_all(i);
    }

    /// Recomputes every still-valid pair event from the current states and reports the first
    /// one that disagrees with the stored prediction (debugging aid for lazy invalidation).
    pub fn check_predictions(&self) -> Result<(), String> {
        let t = self.time;
        for i in 0..self.len() {
            let pe = self.pairs.ev[i];
            if pe.partner() == NONE || self.bodies.count[pe.partner() as usize] != pe.partner_count
            {
                continue;
            }
            let j = pe.partner() as usize;
            let (xi, vi) = self.bodies.state_at(i, t);
            let now =
                self.pairs
                    .predict_pair_from(&self.bodies, &self.slabs, &xi, &vi, i, j, t, true);
            match now {
                Some((tn, kind))
                    if (tn - pe.time).abs() <= 1e-6 * (tn - t).abs().max(1e-3)
                        && kind == pe.kind() => {}
                other => {
                    return Err(format!(
                        "particle {i}: stored {:?} with {j} at {:.17}, recomputed {other:?} at t={t}",
                        pe.kind(),
                        pe.time
                    ));
                }
            }
        }
        Ok(())
    }

    /// Heap bytes of every per-particle (and per-cell) array of the engine, by structure, each
    /// from its capacity and element size (`wetgran-bench memory`). The wall tables of the
    /// `table` solver are shared through the table cache and not counted.
    pub fn memory(&self) -> Vec<(&'static str, usize)> {
        let mut out = self.bodies.memory();
        out.extend(self.pairs.memory());
        out.extend(self.cells.memory());
        out.extend(self.walls.memory());
        out.extend(self.slabs.memory());
        out.extend(self.queue.memory());
        out
    }
}
