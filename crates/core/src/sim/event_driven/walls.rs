//! Event source of the walls: static flat walls on every non-periodic axis and the shaken floor
//! and lid (docs/model.md 4.1, 6) under one of three solvers, chosen once at scene start as a
//! [`WallSolver`] that owns its state (the `table` solver's two tables and its one-particle
//! memories). [`WallSource`] keeps each particle's next wall event.
//!
//! Safeguards (tested in `crates/core/tests/engine_safeguards.rs` and `shaken_container.rs`):
//! a particle found behind a wall and approaching collides now, one separating is left alone
//! (B.5.6); a wall event that finds the particle away from the wall is a re-check that changes
//! nothing; a tabulated hit places the particle on the wall only within
//! [`TABLE_PLACEMENT_TOLERANCE`] (B.5.1) or when late (placed whatever the depth), else the
//! exact solver answers that particle's next prediction (a table error cannot repeat itself
//! forever), and only as far as its neighbours leave room (`placement_room`); no grain leaves
//! the floor slower than the rebound floor.
//!
//! Searches stopped at the particle's next event (`exact` solver): a particle in a dense bed
//! meets many partners before it reaches a wall, and each of its events used to search the
//! floor's and the lid's roots to the end (a sine and a cosine per step). The search of each
//! shaken wall now stops once its answer is known to lie beyond the particle's next other
//! event (`shaken_wall::exact_root_until`: before any sine when the flight stays above the
//! wall's crest until then); every event that changes the flight predicts afresh, and a cell
//! crossing, which does not, resumes a stopped search whose bound it has reached
//! ([`WallSource::resume`]). The resumed pieces give the search's answer bit for bit and a
//! stopped wall is always later than the particle's key, so the engine's events are the same.

use super::bodies::{Bodies, permute_in_place, vec_bytes};
use super::cell_source::CellSource;
use super::event::{Event, EventKind, EventSource, PlaneEvent};
use super::table_cache::TableCache;
use crate::physics::contact::rebound_speed;
use crate::physics::shaken_wall::{
    Search, WallMotion, WallRoot, bracket_root, exact_root, exact_root_until,
};
use crate::physics::wall_table::{TableHit, WallTable};
use crate::scene::{DEFAULT_ROOT_TOLERANCE, Scene, WallSolverKind};
use crate::sim::books::{EnergyLedger, EventCounts};
use std::sync::Arc;

/// Largest gap (in units of `d`) at which a tabulated wall hit is accepted and the particle
/// placed on the wall (B.5.1); a larger gap makes the event a re-check. Bounds the
/// displacement a table error can cause.
pub(crate) const TABLE_PLACEMENT_TOLERANCE: f64 = 1e-2;

/// State of the `table` solver (B.4-B.5).
#[derive(Debug, Clone)]
pub(crate) struct TableState {
    pub motion: WallMotion,
    /// Gap tolerance of the exact solver it falls back on.
    pub tol: f64,
    /// The tables of the floor and of the lid (gravity pointing away), from the engine's
    /// [`TableCache`].
    pub tables: [Arc<WallTable>; 2],
    /// The particle that has just left the floor (`false`) or lid (`true`); its next wall
    /// prediction uses the wall-edge table (B.5.2).
    pub(crate) launched: Option<(usize, bool)>,
    /// The particle whose tabulated hit found it away from the wall; its next wall prediction
    /// comes from the exact solver.
    pub(crate) distrusted: Option<usize>,
}

/// How wall collision times are found: static walls, or the shaken floor and lid with one of
/// the solvers of `physics::shaken_wall` / `physics::wall_table`.
#[derive(Debug, Clone)]
pub(crate) enum WallSolver {
    /// Static flat walls: straight or parabolic flights to the planes.
    Static,
    /// Conservative advancement with the curvature bound `g + A omega^2` (cannot skip a root).
    Exact { motion: WallMotion, tol: f64 },
    /// The thesis's reference algorithm (B.3): march by `t_min`, refine by safeguarded Newton.
    Bracket {
        motion: WallMotion,
        tol: f64,
        t_min: f64,
    },
    /// The thesis's tabulated method (B.4-B.5), with the exact solver where the table does not
    /// answer.
    Table(Box<TableState>),
}

impl WallSolver {
    /// The solver the scene asks for (a `table` solver's tables from `tables`).
    pub(crate) fn from_scene(scene: &Scene, tables: &TableCache) -> Self {
        let Some((amplitude, omega)) = scene.drive_motion() else {
            return WallSolver::Static;
        };
        let motion = WallMotion {
            amplitude,
            omega,
            g: scene.gravity,
        };
        let tol = scene.drive.root_tolerance.unwrap_or(DEFAULT_ROOT_TOLERANCE);
        match scene.drive.wall_solver {
            WallSolverKind::Bracket => WallSolver::Bracket {
                motion,
                tol,
                t_min: scene.bracket_step(omega),
            },
            WallSolverKind::Table if amplitude > 0.0 => {
                let spec = scene.wall_table_spec(amplitude, omega);
                let lid = WallMotion {
                    g: -scene.gravity,
                    ..motion
                };
                WallSolver::Table(Box::new(TableState {
                    motion,
                    tol,
                    tables: [tables.get(motion, spec), tables.get(lid, spec)],
                    launched: None,
                    distrusted: None,
                }))
            }
            _ => WallSolver::Exact { motion, tol },
        }
    }

    /// The floor's motion, `None` for static walls.
    pub(crate) fn motion(&self) -> Option<WallMotion> {
        match self {
            WallSolver::Static => None,
            WallSolver::Exact { motion, .. } | WallSolver::Bracket { motion, .. } => Some(*motion),
            WallSolver::Table(s) => Some(s.motion),
        }
    }

    /// Time until a flight from gap `h` with velocity `v` at `t0` meets `w` (shaken wall frame),
    /// with the exact or bracket solver, and the tabulated approach speed (NaN: not tabulated);
    /// `miss` if none within `horizon`.
    fn exact(
        &self,
        w: &WallMotion,
        h: f64,
        v: f64,
        t0: f64,
        miss: f64,
        horizon: f64,
    ) -> (f64, f64) {
        let root = match self {
            WallSolver::Bracket { tol, t_min, .. } => {
                bracket_root(w, h, v, t0, *t_min, *tol, horizon)
            }
            WallSolver::Exact { tol, .. } => exact_root(w, h, v, t0, *tol, horizon),
            WallSolver::Table(s) => exact_root(w, h, v, t0, s.tol, horizon),
            WallSolver::Static => unreachable!("static walls have no shaken-wall roots"),
        };
        match root {
            WallRoot::Hit(dt) => (dt, f64::NAN),
            WallRoot::None => (miss, f64::NAN),
        }
    }

    fn tol(&self) -> f64 {
        match self {
            WallSolver::Static => DEFAULT_ROOT_TOLERANCE,
            WallSolver::Exact { tol, .. } | WallSolver::Bracket { tol, .. } => *tol,
            WallSolver::Table(s) => s.tol,
        }
    }
}

/// One shaken wall's root search for one particle (`exact` solver), in the wall's frame.
#[derive(Debug, Clone, Copy)]
pub(crate) struct WallSearch {
    /// Contact coordinate and velocity at the prediction (the `h`, `v` of `exact_root`).
    h: f64,
    v: f64,
    /// `Some(from)`: stopped, to go on from step `from` (`None`: from its start); `None`: done.
    stopped: Option<Option<f64>>,
    /// Done: the event's time after the prediction. Stopped: the earliest absolute time the
    /// event can have.
    time: f64,
}

/// The `exact` solver's searches of one particle: what its wall event is made of.
#[derive(Debug, Clone, Copy)]
pub(crate) struct WallSearches {
    /// Time of the prediction.
    now: f64,
    /// Earliest event of the static walls (the axes before the shaken one), after `now`.
    fixed: PlaneEvent,
    /// The lid and the floor, in the order their events are offered.
    wall: [WallSearch; 2],
}

/// Each particle's next wall event and the solver.
#[derive(Debug, Clone)]
pub(crate) struct WallSource {
    pub solver: WallSolver,
    /// Wall restitution and the collapse remedies.
    pub(crate) e_wall: f64,
    pub tc: f64,
    pub min_rebound: f64,
    /// Next wall event of each particle (empty when no axis has walls: every candidate is then
    /// never).
    pub ev: Vec<PlaneEvent>,
    /// `table` solver: tabulated approach speed of each particle's predicted wall hit (NaN when
    /// the hit was not tabulated; empty, i.e. NaN throughout, under the other solvers).
    pub(crate) vrel: Vec<f64>,
    /// `exact` solver on a shaken container: each particle's searches (empty otherwise).
    searches: Vec<WallSearches>,
}

impl WallSource {
    /// The source of a validated scene for `n` particles; `walls`: whether any axis has walls;
    /// a `table` solver's tables from `tables`.
    pub(crate) fn new(scene: &Scene, n: usize, walls: bool, tables: &TableCache) -> Self {
        let solver = WallSolver::from_scene(scene, tables);
        let tabulated = matches!(solver, WallSolver::Table(_));
        let vertical_walls = scene.boundaries().last() == Some(&crate::scene::Boundary::Wall);
        let stopped = vertical_walls && matches!(solver, WallSolver::Exact { .. });
        let none = WallSearch {
            h: 0.0,
            v: 0.0,
            stopped: None,
            time: f64::INFINITY,
        };
        let searches = WallSearches {
            now: 0.0,
            fixed: PlaneEvent::NEVER,
            wall: [none; 2],
        };
        Self {
            solver,
            e_wall: scene.contact.wall_restitution,
            tc: scene.engine.tc,
            min_rebound: scene.engine.min_rebound_speed,
            ev: vec![PlaneEvent::NEVER; if walls { n } else { 0 }],
            vrel: vec![f64::NAN; if tabulated { n } else { 0 }],
            searches: vec![searches; if stopped { n } else { 0 }],
        }
    }

    /// Time of the next wall event of `i` (`+inf` without walls).
    pub(crate) fn time(&self, i: usize) -> f64 {
        self.ev.get(i).map_or(f64::INFINITY, |e| e.time)
    }

    /// Heap bytes of the per-particle arrays (`wetgran-bench memory`; shared tables excluded).
    pub(crate) fn memory(&self) -> Vec<(&'static str, usize)> {
        vec![
            ("walls.ev", vec_bytes(&self.ev)),
            ("walls.vrel", vec_bytes(&self.vrel)),
            ("walls.searches", vec_bytes(&self.searches)),
        ]
    }

    /// Predicts the next wall collision of `i` (at time `now`; `up`: the lid or upper wall) and
    /// the tabulated approach speed of a shaken-wall hit; `other`: the particle's earliest
    /// other event (the `exact` solver's searches stop beyond it). Ends the `table` solver's
    /// memories of `i` (edge table after a launch, exact solver after a table error): they
    /// serve one prediction.
    pub(crate) fn predict<const D: usize, const G: bool, const S: bool>(
        &mut self,
        i: usize,
        bodies: &Bodies<D, G, S>,
        now: f64,
        other: f64,
    ) {
        if self.ev.is_empty() {
            return;
        }
        if !self.searches.is_empty() {
            self.predict_stopped(i, bodies, now, other);
            return;
        }
        let mut best = PlaneEvent::NEVER;
        let mut vrel = f64::NAN;
        let r = bodies.body[i].r;
        let drive = self.solver.motion();
        for k in 0..D {
            if bodies.periodic[k] {
                continue;
            }
            let ((t_lid, v_lid), (t_floor, v_floor)) = match drive {
                Some(w) if k == D - 1 => self.shaken_wall_times(i, &w, bodies, now),
                _ => {
                    let (lid, floor) = bodies.times_to_planes(i, k, r, bodies.size[k] - r);
                    ((lid, f64::NAN), (floor, f64::NAN))
                }
            };
            for (t, v, up) in [(t_lid, v_lid, true), (t_floor, v_floor, false)] {
                if t < best.time {
                    vrel = v;
                }
                best.keep_earlier(t, k, up);
            }
        }
        best.time += now;
        self.ev[i] = best;
        if let Some(v) = self.vrel.get_mut(i) {
            *v = vrel;
        }
        if let WallSolver::Table(s) = &mut self.solver {
            if s.launched.is_some_and(|(j, _)| j == i) {
                s.launched = None;
            }
            if s.distrusted == Some(i) {
                s.distrusted = None;
            }
        }
    }

    /// [`Self::predict`] under the `exact` solver on a shaken container: the static walls as
    /// there, the lid and the floor by searches stopped beyond `other`.
    fn predict_stopped<const D: usize, const G: bool, const S: bool>(
        &mut self,
        i: usize,
        bodies: &Bodies<D, G, S>,
        now: f64,
        other: f64,
    ) {
        let r = bodies.body[i].r;
        let mut fixed = PlaneEvent::NEVER;
        for k in 0..D - 1 {
            if !bodies.periodic[k] {
                let (lid, floor) = bodies.times_to_planes(i, k, r, bodies.size[k] - r);
                fixed.keep_earlier(lid, k, true);
                fixed.keep_earlier(floor, k, false);
            }
        }
        let b = &bodies.body[i];
        let (z, vz) = (b.x[D - 1], b.v[D - 1]);
        let search = |h: f64, v: f64| WallSearch {
            h,
            v,
            stopped: Some(None),
            time: now,
        };
        let mut s = WallSearches {
            now,
            fixed,
            wall: [search(bodies.size[D - 1] - z - r, -vz), search(z - r, vz)],
        };
        for wall in 0..2 {
            self.search(&mut s, wall, other);
        }
        self.ev[i] = combined::<D>(&s);
        self.searches[i] = s;
    }

    /// Goes on with the stopped searches of `i` whose bound the particle's key has reached
    /// (`other`: its earliest event besides the walls), after an event that left its flight
    /// unchanged (a cell crossing).
    pub(crate) fn resume<const D: usize>(&mut self, i: usize, other: f64) {
        let Some(mut s) = self.searches.get(i).copied() else {
            return;
        };
        for wall in 0..2 {
            let key = other.min(self.ev[i].time);
            if s.wall[wall].stopped.is_some() && s.wall[wall].time <= key {
                self.search(&mut s, wall, key);
                self.ev[i] = combined::<D>(&s);
            }
        }
        self.searches[i] = s;
    }

    /// Runs the search of `wall` (0: the lid, 1: the floor) of `s` until its answer is known or
    /// known to lie after the absolute time `until`.
    fn search(&self, s: &mut WallSearches, wall: usize, until: f64) {
        let WallSolver::Exact { motion, tol } = self.solver else {
            unreachable!("stopped searches belong to the exact solver")
        };
        let horizon = 2.0 * motion.period();
        // The lid is the floor problem mirrored: gravity pointing away, phase shifted by pi.
        let (w, t0, miss) = if wall == 0 {
            let lid = WallMotion {
                g: -motion.g,
                ..motion
            };
            (lid, s.now + 0.5 * motion.period(), f64::INFINITY)
        } else {
            (motion, s.now, horizon)
        };
        let x = &mut s.wall[wall];
        let from = x.stopped.expect("only a stopped search goes on");
        // In time after the prediction, with a margin for the round-off of the difference.
        let bound = if until.is_finite() {
            (until - s.now) + 8.0 * f64::EPSILON * (until.abs() + s.now.abs())
        } else {
            f64::INFINITY
        };
        let mut outcome = exact_root_until(&w, x.h, x.v, t0, tol, horizon, bound, from);
        if let Search::Later(next) = outcome {
            let earliest = next.unwrap_or(bound) + s.now;
            if earliest > until {
                *x = WallSearch {
                    stopped: Some(next),
                    time: earliest,
                    ..*x
                };
                return;
            }
            // The margin did not clear the bound after round-off: search to the end.
            outcome = exact_root_until(&w, x.h, x.v, t0, tol, horizon, f64::INFINITY, next);
        }
        let dt = match outcome {
            Search::Done(WallRoot::Hit(dt)) => dt,
            Search::Done(WallRoot::None) => miss,
            Search::Later(_) => unreachable!("a search without a bound runs to its end"),
        };
        *x = WallSearch {
            stopped: None,
            time: dt,
            ..*x
        };
    }

    /// Times until particle `i` meets the shaken lid and floor (docs/model.md 6), with the scene's
    /// solver. The search looks two periods ahead; a particle that meets neither gets a
    /// re-check at the horizon (a wall event that finds no contact and only re-predicts). The
    /// lid is the floor problem mirrored: depth below the lid's mean position, velocity
    /// reversed, gravity pointing away, wall phase shifted by pi.
    fn shaken_wall_times<const D: usize, const G: bool, const S: bool>(
        &self,
        i: usize,
        w: &WallMotion,
        bodies: &Bodies<D, G, S>,
        t: f64,
    ) -> ((f64, f64), (f64, f64)) {
        let b = &bodies.body[i];
        let (z, vz, r) = (b.x[D - 1], b.v[D - 1], b.r);
        let horizon = 2.0 * w.period();
        let half_period = 0.5 * w.period();
        let lid_motion = WallMotion { g: -w.g, ..*w };
        let h_lid = bodies.size[D - 1] - z - r;
        let solver = &self.solver;
        let table = match solver {
            WallSolver::Table(s) if s.distrusted != Some(i) => Some(s),
            _ => None,
        };
        let Some(state) = table else {
            return (
                solver.exact(
                    &lid_motion,
                    h_lid,
                    -vz,
                    t + half_period,
                    f64::INFINITY,
                    horizon,
                ),
                solver.exact(w, z - r, vz, t, horizon, horizon),
            );
        };
        // The `table` solver (B.4-B.5), with the exact solver where the table does not answer.
        let tol = state.tol;
        let tabulated = |k: usize, h: f64, v: f64, t0: f64, miss: f64| {
            let table = &state.tables[k];
            let answer = match state.launched {
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
                TableHit::None => (miss, f64::NAN),
                TableHit::Now | TableHit::OutOfRange => {
                    solver.exact(table.motion(), h, v, t0, miss, horizon)
                }
            }
        };
        (
            tabulated(1, h_lid, -vz, t + half_period, f64::INFINITY),
            tabulated(0, z - r, vz, t, horizon),
        )
    }

    /// Carries out the wall event of `i` at time `t` along `axis` (`lid`: the upper wall); the
    /// caller re-predicts every event of `i` afterwards.
    pub(crate) fn fire<const D: usize, const G: bool, const S: bool>(
        &mut self,
        i: usize,
        axis: usize,
        lid: bool,
        t: f64,
        bodies: &mut Bodies<D, G, S>,
        cells: &mut CellSource<D>,
        ledger: &mut EnergyLedger,
        counts: &mut EventCounts,
    ) {
        if let Some(w) = self.solver.motion()
            && axis == D - 1
        {
            self.shaken_collision(i, &w, lid, t, bodies, cells, ledger, counts);
            return;
        }
        bodies.advance(i, t);
        let v = bodies.body[i].v[axis];
        // A grain exactly at rest on a floor under gravity is pressed into it: approaching.
        let floor_under_gravity = G && axis == D - 1 && !lid;
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
        let u_out = self.rebound(i, t, v.abs(), floor_under_gravity, bodies, ledger, counts);
        bodies.body[i].v[axis] = if lid { -u_out } else { u_out };
    }

    /// Books the wall collision of `i` at `t` at approach speed `u_in` (relative to the wall)
    /// and returns the outgoing speed. Rest on a floor is the one state an event-driven engine
    /// cannot represent (zero-time bounces): no grain leaves a `floor` slower than the rebound
    /// floor.
    fn rebound<const D: usize, const G: bool, const S: bool>(
        &self,
        i: usize,
        t: f64,
        u_in: f64,
        floor: bool,
        bodies: &mut Bodies<D, G, S>,
        ledger: &mut EnergyLedger,
        counts: &mut EventCounts,
    ) -> f64 {
        bodies.bump(i);
        counts.wall_collisions += 1;
        let since = bodies.since_last_collision(i, i, t);
        let mut u_out = rebound_speed(u_in, self.e_wall, since, self.tc, self.min_rebound);
        if floor {
            u_out = u_out.max(self.min_rebound);
        }
        ledger.book_restitution(bodies.mass, u_in, self.e_wall, u_out);
        bodies.record_collision(i, t);
        u_out
    }

    /// Collision with the shaken floor or lid, `v' = v_w + e_w (v_w - v)` along the normal
    /// (docs/model.md 4.1), with the collapse remedies applied to the speed relative to the wall. An
    /// event that finds the particle away from the wall is a re-check and changes nothing.
    fn shaken_collision<const D: usize, const G: bool, const S: bool>(
        &mut self,
        i: usize,
        w: &WallMotion,
        lid: bool,
        t: f64,
        bodies: &mut Bodies<D, G, S>,
        cells: &mut CellSource<D>,
        ledger: &mut EnergyLedger,
        counts: &mut EventCounts,
    ) {
        bodies.advance(i, t);
        let b = bodies.body[i];
        let (z, vz) = (b.x[D - 1], b.v[D - 1]);
        let (z_w, v_w) = (w.position(t), w.velocity(t));
        let h = bodies.size[D - 1];
        // Gap and approach speed in the wall's frame, both positive when the particle is on the
        // right side and approaching.
        let (gap, mut u_in) = if lid {
            (h + z_w - z - b.r, vz - v_w)
        } else {
            (z - b.r - z_w, v_w - vz)
        };
        let tabulated = self.vrel.get(i).copied().unwrap_or(f64::NAN);
        let (contact, approaching) = if tabulated.is_finite() {
            // A tabulated hit (B.5.1): approach speed positive by construction (B.5.4), the
            // time error absorbed by placing the particle on the wall. Early by more than the
            // tolerance: a re-check. Late (behind the wall, approaching): placed whatever the
            // depth, since no later prediction can undo it.
            let late = gap < 0.0 && u_in > 0.0;
            (gap.abs() <= TABLE_PLACEMENT_TOLERANCE || late, true)
        } else {
            (
                gap <= 1e3 * self.solver.tol() + 1e-12,
                if lid { u_in > 0.0 } else { u_in >= 0.0 },
            )
        };
        if !(contact && approaching) {
            // The caller re-predicts (with the exact solver after a table error).
            counts.wall_rechecks += 1;
            if tabulated.is_finite()
                && let WallSolver::Table(s) = &mut self.solver
            {
                s.distrusted = Some(i);
            }
            return;
        }
        if tabulated.is_finite() {
            u_in = tabulated;
            let z_wall = if lid { h + z_w - b.r } else { z_w + b.r };
            // Placed on the wall as far as the neighbours leave room: a full shift could push
            // the particle into a grain resting a hair above it. The rest of the gap stays.
            let z_new = z + placement_room(i, z_wall - z, t, bodies, cells);
            if G {
                ledger.added_by_wall_placement += bodies.mass * bodies.gravity * (z_new - z);
            }
            bodies.body[i].x[D - 1] = z_new;
            // The shift may cross a cell face (the caller rescans the neighbourhood).
            let x = bodies.body[i].x;
            cells.relocate_if_moved(i, &x);
            if let WallSolver::Table(s) = &mut self.solver {
                s.launched = Some((i, lid));
            }
        }
        let u_out = self.rebound(i, t, u_in, !lid, bodies, ledger, counts);
        let v_new = if lid { v_w - u_out } else { v_w + u_out };
        let m = bodies.mass;
        // Loss in the wall's frame; the rest of the kinetic energy change is the wall's work.
        let de = 0.5 * m * (u_in * u_in - u_out * u_out);
        ledger.work_by_drive += 0.5 * m * (v_new * v_new - vz * vz) + de;
        bodies.body[i].v[D - 1] = v_new;
    }
}

/// The wall event of a particle's searches: the earliest of the static walls, the lid and the
/// floor (in that order among equal times, as the solver's loop over the axes offers them) of
/// those whose search is done, at its absolute time.
fn combined<const D: usize>(s: &WallSearches) -> PlaneEvent {
    let mut best = s.fixed;
    for (x, up) in s.wall.iter().zip([true, false]) {
        if x.stopped.is_none() {
            best.keep_earlier(x.time, D - 1, up);
        }
    }
    best.time += s.now;
    best
}

/// The shift `s` along the vertical axis, of the sign of `want` and at most `|want|`, that
/// particle `i` can make at time `t` without coming closer than contact to any neighbour (of
/// the `3^D` cells around it) it does not already overlap: the smallest positive root of
/// `|d - s e_z|^2 = sigma^2` (`d` the separation, `sigma` the contact distance). A grain two
/// cells away is reachable only if the cell edge is within [`TABLE_PLACEMENT_TOLERANCE`] of
/// the largest diameter (not excluded).
fn placement_room<const D: usize, const G: bool, const S: bool>(
    i: usize,
    want: f64,
    t: f64,
    bodies: &Bodies<D, G, S>,
    cells: &CellSource<D>,
) -> f64 {
    let up = want >= 0.0;
    let mut room = want.abs();
    let (xi, _) = bodies.state_at(i, t);
    let ri = bodies.body[i].r;
    cells.for_each_near(i, |j| {
        if j == i {
            return;
        }
        let (xj, _) = bodies.state_at(j, t);
        let d = bodies.min_image(xj - xi);
        let sigma = ri + bodies.body[j].r;
        let c = d.norm_squared() - sigma * sigma;
        // Along the shift: `dz > 0` means the neighbour lies ahead.
        let dz = if up { d[D - 1] } else { -d[D - 1] };
        let disc = dz * dz - c;
        if c < 0.0 || dz <= 0.0 || disc < 0.0 {
            // Already overlapping (left to the pair events), behind, or missed by the shift.
            return;
        }
        room = room.min(dz - disc.sqrt());
    });
    let room = room.max(0.0);
    if up { room } else { -room }
}

impl EventSource for WallSource {
    #[inline]
    fn candidate(&self, i: usize) -> Event {
        let e = self.ev.get(i).copied().unwrap_or(PlaneEvent::NEVER);
        e.event(|axis, up| EventKind::Wall { axis, up })
    }

    /// Renumbers the particles (see [`Bodies::permute`]). The `table` solver's one-particle
    /// memories last one prediction and are always spent between events; they are renamed all
    /// the same.
    fn permute(&mut self, order: &[u32], new_of_old: &[u32]) {
        permute_in_place(&mut self.ev, order);
        permute_in_place(&mut self.vrel, order);
        permute_in_place(&mut self.searches, order);
        if let WallSolver::Table(s) = &mut self.solver {
            s.launched = s.launched.map(|(j, lid)| (new_of_old[j] as usize, lid));
            s.distrusted = s.distrusted.map(|j| new_of_old[j] as usize);
        }
    }
}
