//! The thesis's tabulated wall-collision times (docs/model.md 6, Appendix B.4-B.5): a table per
//! wall motion `(A, omega, g)`, filled once before the run and shared by every particle and every
//! job with that drive (the bounded cache `sim::event_driven::table_cache` keeps them).
//!
//! In the wall's axis (origin at the wall's mean position, particle on the `+` side) a flight
//! from a base point `(h0, v0)` at wall phase `phi0` has the gap
//!
//! ```text
//! s(tau) = h0 + v0 tau - g tau^2 / 2 - A sin(phi0 + omega tau)                  (Eq. B.7)
//! ```
//!
//! The band `-A <= z <= A` is the wall's reach. A flight is identified by where it enters the
//! reach within one period, the *edge* (B.4):
//! - edge I, `z = +A` from above: `(phase, v < 0)`;
//! - edge II, `z = -A` from below (a flight behind the wall, e.g. a virtual continuation):
//!   `(phase, v > 0)`;
//! - edge III, the start of the period: `(h, v)` with `-A <= h <= A`;
//! - the wall itself after a wall hit (B.5.2): `(collision phase, outgoing velocity relative
//!   to the wall)`.
//!
//! Velocities are unbounded, so the second coordinate is the mapped velocity
//! `u = ln(1 + |v| / v_min)` (signed for edge III): linear below `v_min`, logarithmic above;
//! beyond the upper cut-off `v_max` the table does not answer and the caller uses the exact
//! solver. The root times are discontinuous in the parameters, so a cell never interpolates
//! between nodes: it stores, at its reference point (the midpoint), every root in one period
//! (up to four; odd-numbered ones enter the wall, even-numbered ones leave it), the partial
//! derivatives `d tau / dP = -(ds/dP) / (ds/d tau)` (Eq. B.17), the approach speed at each
//! entering root `v_rel = -ds/d tau` and its derivatives (Eqs. B.20-B.21); a lookup extrapolates
//! linearly from the reference point.
//!
//! Safeguards at build time: every corner of every cell must extrapolate to `tau >= 0` and
//! `v_rel > 0`, else the offending derivatives are shrunk (to zero at worst, B.5.4); a cell whose
//! midpoint escapes (no entering root in the period) but a corner of which hits is re-referenced
//! to that corner, so that no flight in it tunnels through the wall (B.5.5). Nothing is tabulated
//! beyond one period: a flight without a hit is queried again one period later.

mod build;
mod flight;
#[cfg(test)]
pub(crate) mod tests;

use super::shaken_wall::WallMotion;
use build::build_edge;
use rayon::prelude::*;
use std::f64::consts::TAU;
use std::time::Instant;

/// Most roots of the gap in one period: `s''` changes sign at most twice per period, so `s` has
/// at most four zeros there.
pub(crate) const MAX_ROOTS: usize = 4;

/// Resolution and velocity map of a table.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TableSpec {
    /// Cells along the first parameter (phase, or height for edge III).
    pub phase_cells: usize,
    /// Cells along the mapped velocity.
    pub velocity_cells: usize,
    /// Where the velocity map turns from linear to logarithmic (absolute units).
    pub v_min: f64,
    /// Upper cut-off of the speed (absolute units); faster flights are not tabulated.
    pub v_max: f64,
    /// Corner check of each cell's linear model, in units of the period: a cell whose
    /// extrapolated roots miss the true roots at one of its corners by more than this (or whose
    /// corners have another number of roots) is answered by the exact solver. `None`: no check,
    /// the thesis's table as printed.
    pub corner_tolerance: Option<f64>,
}

/// Where a flight enters the wall's reach (see the module header).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Edge {
    /// Edge I: `z = +A`, moving down.
    Top = 0,
    /// Edge II: `z = -A`, moving up.
    Bottom = 1,
    /// Edge III: the start of the period.
    Start = 2,
    /// The wall trajectory, just after a wall hit.
    Wall = 3,
}

const EDGES: [Edge; 4] = [Edge::Top, Edge::Bottom, Edge::Start, Edge::Wall];

/// One root of the gap stored in a cell, at the cell's reference point.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct Root {
    tau: f64,
    dtau: [f64; 2],
    /// Approach speed at an entering root (0 for a leaving one).
    vrel: f64,
    dvrel: [f64; 2],
}

/// One cell: its reference point and the roots there.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct Cell {
    reference: [f64; 2],
    /// Whether the flight starts behind the wall (at the base point).
    starts_inside: bool,
    /// The linear model failed the corner check: the exact solver answers for this cell.
    exact_only: bool,
    count: u8,
    roots: [Root; MAX_ROOTS],
}

/// The table of one edge.
#[derive(Debug, Clone)]
struct EdgeTable {
    lo: [f64; 2],
    width: [f64; 2],
    n: [usize; 2],
    cells: Vec<Cell>,
}

/// What a table lookup says about the next wall hit, relative to the query time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TableHit {
    /// The flight reaches the wall after `dt` with approach speed `v_rel > 0`.
    Hit { dt: f64, v_rel: f64 },
    /// The flight is behind the wall and approaching it: collide now (B.5.5/B.5.6).
    Now,
    /// No hit before the horizon.
    None,
    /// The state lies outside the table (speed beyond `v_max`, or below the wall's reach):
    /// ask the exact solver.
    OutOfRange,
}

/// Counters of the build-time safeguards (read by the tests that check each safeguard acts).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(crate) struct BuildStats {
    pub(crate) cells: usize,
    /// Roots whose derivatives were shrunk because a corner extrapolated to `tau < 0` or
    /// `v_rel <= 0` (B.5.4).
    pub(crate) shrunk_derivatives: usize,
    /// Escaping cells re-referenced to a corner that hits (B.5.5).
    pub(crate) rereferenced_cells: usize,
    /// Cells answered by the exact solver because their linear model failed the corner check.
    pub(crate) exact_only_cells: usize,
}

impl BuildStats {
    fn add(&mut self, other: &BuildStats) {
        self.cells += other.cells;
        self.shrunk_derivatives += other.shrunk_derivatives;
        self.rereferenced_cells += other.rereferenced_cells;
        self.exact_only_cells += other.exact_only_cells;
    }
}

/// Tabulated collision times for one wall motion.
#[derive(Debug, Clone)]
pub struct WallTable {
    motion: WallMotion,
    spec: TableSpec,
    edges: Vec<EdgeTable>,
    pub build_seconds: f64,
    #[cfg(test)]
    stats: BuildStats,
}

impl WallTable {
    /// Fills the four edge tables for `motion`, in parallel on the caller's rayon pool (the
    /// table cache installs the one `sim::threads` chooses); each cell is a function of its
    /// indices alone, so the table is the same bits on any number of threads.
    pub fn build(motion: WallMotion, spec: TableSpec) -> WallTable {
        let start = Instant::now();
        let built: Vec<(EdgeTable, BuildStats)> = EDGES
            .par_iter()
            .map(|&e| build_edge(&motion, &spec, e))
            .collect();
        #[cfg(test)]
        let stats = built.iter().fold(BuildStats::default(), |mut sum, (_, s)| {
            sum.add(s);
            sum
        });
        let edges = built.into_iter().map(|(e, _)| e).collect();
        WallTable {
            motion,
            spec,
            edges,
            build_seconds: start.elapsed().as_secs_f64(),
            #[cfg(test)]
            stats,
        }
    }

    /// Memory held by the cells, in bytes.
    pub fn bytes(&self) -> usize {
        self.edges
            .iter()
            .map(|e| e.cells.len() * std::mem::size_of::<Cell>())
            .sum()
    }

    pub fn motion(&self) -> &WallMotion {
        &self.motion
    }

    /// Next entering root for a flight with contact coordinate `h` and velocity `v` at time
    /// `t0`, searched up to `t0 + horizon`.
    pub fn next_hit(&self, h: f64, v: f64, t0: f64, horizon: f64) -> TableHit {
        let w = &self.motion;
        let reach = w.amplitude;
        let period = w.period();
        let (mut t, mut z, mut vz) = (t0, h, v);
        // After a period without a hit the base point is the next period's start (edge III).
        let mut period_start = false;
        // Each pass covers at least one period from its base point.
        for _ in 0..(horizon / period) as usize + 3 {
            if t - t0 > horizon {
                return TableHit::None;
            }
            if vz.abs() > self.spec.v_max {
                return TableHit::OutOfRange;
            }
            let (base_time, edge, p1, v_base) = if z > reach {
                // Above the reach: the flight enters through edge I (or never comes back).
                let Some(dt) = time_to_fall_to(z, vz, w.g, reach) else {
                    return TableHit::None;
                };
                let te = t + dt;
                (te, Edge::Top, phase_of(w, te), vz - w.g * dt)
            } else if z < -reach {
                return TableHit::OutOfRange;
            } else if period_start {
                (t, Edge::Start, z, vz)
            } else {
                self.base_in_reach(t, z, vz)
            };
            if v_base.abs() > self.spec.v_max {
                return TableHit::OutOfRange;
            }
            let Some((cell, delta)) = self.lookup(edge, p1, v_base) else {
                return TableHit::OutOfRange;
            };
            // The query time from the base point (negative when the base lies ahead, edge I).
            let now = t - base_time;
            match answer_from_cell(cell, delta, now, w.velocity(t) - vz) {
                Some(TableHit::Hit { dt, v_rel }) => {
                    let dt = dt + (t - t0);
                    return if dt <= horizon {
                        TableHit::Hit { dt, v_rel }
                    } else {
                        TableHit::None
                    };
                }
                // Behind the wall at a later period's start (round-off or table error): exact.
                Some(TableHit::Now) if t > t0 => return TableHit::OutOfRange,
                Some(answer) => return answer,
                None => {}
            }
            // No hit in this period: query again from the start of the next one.
            let next = match edge {
                Edge::Start => base_time + period,
                _ => {
                    let k = (base_time / period).floor() + 1.0;
                    let next = k * period;
                    if next <= t { next + period } else { next }
                }
            };
            let dt = next - t;
            z += vz * dt - 0.5 * w.g * dt * dt;
            vz -= w.g * dt;
            t = next;
            period_start = true;
        }
        TableHit::None
    }

    /// Next hit of a flight that has just left the wall at `t0` with speed `v_rel > 0` relative
    /// to it, placed exactly on the wall (B.5.1-B.5.2).
    pub(crate) fn next_hit_after_wall(&self, v_rel: f64, t0: f64, horizon: f64) -> TableHit {
        let w = &self.motion;
        let phi = phase_of(w, t0);
        let v_abs = w.velocity(t0) + v_rel;
        if v_rel > self.spec.v_max || v_abs.abs() > self.spec.v_max {
            return TableHit::OutOfRange;
        }
        let Some((cell, delta)) = self.lookup(Edge::Wall, phi, v_rel) else {
            return TableHit::OutOfRange;
        };
        for k in 0..cell.count as usize {
            let r = &cell.roots[k];
            // Odd-numbered roots (index 1, 3: the flight starts outside) enter the wall.
            if k % 2 == 1 {
                let tau = extrapolate(r.tau, r.dtau, delta);
                if tau > 0.0 {
                    if tau > horizon {
                        return TableHit::None;
                    }
                    let vrel = extrapolate(r.vrel, r.dvrel, delta);
                    return TableHit::Hit {
                        dt: tau,
                        v_rel: vrel,
                    };
                }
            }
        }
        // Escapes within the period: query again from one period later.
        let period = w.period();
        let z = w.position(t0) + v_abs * period - 0.5 * w.g * period * period;
        let v = v_abs - w.g * period;
        match self.next_hit(z, v, t0 + period, horizon - period) {
            TableHit::Hit { dt, v_rel } => TableHit::Hit {
                dt: dt + period,
                v_rel,
            },
            other => other,
        }
    }

    /// Base point of a flight inside the reach at `t`: the last time within the current period
    /// it entered the reach (edge I or II), else the start of the period (edge III).
    fn base_in_reach(&self, t: f64, z: f64, v: f64) -> (f64, Edge, f64, f64) {
        let w = &self.motion;
        let a = w.amplitude;
        let period = w.period();
        let t_start = (t / period).floor() * period;
        let back = t_start - t; // <= 0
        let mut best: Option<(f64, Edge)> = None;
        for (plane, edge) in [(a, Edge::Top), (-a, Edge::Bottom)] {
            for dt in crossings(z, v, w.g, plane) {
                if dt >= back && dt <= 0.0 {
                    let rate = v - w.g * dt;
                    let enters = match edge {
                        Edge::Top => rate < 0.0,
                        _ => rate > 0.0,
                    };
                    if enters && best.is_none_or(|(b, _)| dt > b) {
                        best = Some((dt, edge));
                    }
                }
            }
        }
        match best {
            Some((dt, edge)) => {
                let te = t + dt;
                (te, edge, phase_of(w, te), v - w.g * dt)
            }
            None => {
                let dt = back;
                let h = (z + v * dt - 0.5 * w.g * dt * dt).clamp(-a, a);
                (t_start, Edge::Start, h, v - w.g * dt)
            }
        }
    }

    /// The cell holding `(p1, v)` on `edge` and the offset from its reference point.
    fn lookup(&self, edge: Edge, p1: f64, v: f64) -> Option<(&Cell, [f64; 2])> {
        let table = &self.edges[edge as usize];
        let u = map_velocity(edge, v, self.spec.v_min);
        let p = [p1, u];
        let mut idx = [0usize; 2];
        for k in 0..2 {
            let x = (p[k] - table.lo[k]) / table.width[k];
            if !x.is_finite() {
                return None;
            }
            let i = x.floor();
            if i < 0.0 || i >= table.n[k] as f64 {
                // Phases wrap; a height or speed just outside the grid belongs to the edge cell.
                if k == 0 && edge != Edge::Start {
                    idx[k] = (i.rem_euclid(table.n[k] as f64)) as usize;
                    continue;
                }
                if x < -1e-9 || x > table.n[k] as f64 + 1e-9 {
                    return None;
                }
                idx[k] = (i.max(0.0) as usize).min(table.n[k] - 1);
                continue;
            }
            idx[k] = i as usize;
        }
        let cell = &table.cells[idx[0] * table.n[1] + idx[1]];
        if cell.exact_only {
            return None;
        }
        let delta = [p[0] - cell.reference[0], p[1] - cell.reference[1]];
        Some((cell, delta))
    }
}

/// Decides from one cell's roots, with `now` the query time measured from the base point.
/// Returns the hit relative to the base point's `now`, or `None` when the flight has no entering
/// root in the tabulated period after `now`. `approach` is the flight's approach speed to the
/// wall at `now` (`v_wall - v`), used when the roots say the flight is behind the wall.
fn answer_from_cell(cell: &Cell, delta: [f64; 2], now: f64, approach: f64) -> Option<TableHit> {
    let count = cell.count as usize;
    let tau = |k: usize| extrapolate(cell.roots[k].tau, cell.roots[k].dtau, delta);
    // Roots alternate between entering and leaving: toggle the start side per root before now.
    let mut inside = cell.starts_inside;
    let mut k = 0;
    while k < count && tau(k) <= now {
        inside = !inside;
        k += 1;
    }
    if inside {
        // Behind the wall: collide now if approaching (B.5.6), else hit at the next entering root.
        if approach > 0.0 {
            return Some(TableHit::Now);
        }
        k += 1;
    }
    (k < count).then(|| {
        let r = &cell.roots[k];
        TableHit::Hit {
            dt: tau(k) - now,
            v_rel: extrapolate(r.vrel, r.dvrel, delta),
        }
    })
}

#[inline]
fn extrapolate(value: f64, d: [f64; 2], delta: [f64; 2]) -> f64 {
    value + d[0] * delta[0] + d[1] * delta[1]
}

/// Wall phase `omega t` reduced to `[0, 2 pi)`.
fn phase_of(w: &WallMotion, t: f64) -> f64 {
    (w.omega * t).rem_euclid(TAU)
}

/// Mapped velocity (see the module header): `u = ln(1 + |v| / v_min)`, signed on edge III.
fn map_velocity(edge: Edge, v: f64, v_min: f64) -> f64 {
    let u = (v.abs() / v_min).ln_1p();
    if edge == Edge::Start && v < 0.0 {
        -u
    } else {
        u
    }
}

/// Times (relative, either sign) at which the parabola `z + v t - g t^2 / 2` passes `plane`;
/// NaN marks a crossing that does not exist (no allocation: this runs on every query).
fn crossings(z: f64, v: f64, g: f64, plane: f64) -> [f64; 2] {
    let c = z - plane;
    if g == 0.0 {
        return [if v != 0.0 { -c / v } else { f64::NAN }, f64::NAN];
    }
    // -g/2 t^2 + v t + c = 0
    let disc = v * v + 2.0 * g * c;
    if disc < 0.0 {
        return [f64::NAN; 2];
    }
    let sq = disc.sqrt();
    [(v - sq) / g, (v + sq) / g]
}

/// First time `>= 0` at which the parabola reaches `plane` moving down.
fn time_to_fall_to(z: f64, v: f64, g: f64, plane: f64) -> Option<f64> {
    crossings(z, v, g, plane)
        .into_iter()
        .filter(|&t| t >= 0.0 && v - g * t < 0.0)
        .min_by(f64::total_cmp)
}

/// Default phase (or height) cells of a table.
pub(crate) const DEFAULT_PHASE_CELLS: usize = 128;
/// Default velocity cells of a table.
pub(crate) const DEFAULT_VELOCITY_CELLS: usize = 128;
/// Default `v_min` in units of the wall's peak speed `A omega`.
pub const DEFAULT_V_MIN_OVER_WALL_SPEED: f64 = 0.05;
/// Default `v_max` in units of the wall's peak speed `A omega`.
pub const DEFAULT_V_MAX_OVER_WALL_SPEED: f64 = 50.0;
/// Default corner-check tolerance on root times, in units of the period.
pub const DEFAULT_CORNER_TOLERANCE: f64 = 1e-3;
