//! The particles' delayed states and everything about their free flight: [`Bodies`].
//!
//! Particle `i` stores its position and velocity at its own time `t` (one 64-byte [`Body`] per
//! sphere); it is brought to the current time only when an event involves it. Between events
//! every particle flies on a parabola under gravity (`GRAV`) and, under the shear drive
//! (`SHEAR`), under its slab's constant acceleration along `y`. `Bodies` also keeps the
//! per-particle counters every source reads: the velocity-change count of lazy invalidation and
//! the time of the last collision (TC model), and the numbering (internal index <-> scene index)
//! that `Engine::reorder_by_cell` permutes.

use super::shear::FORCE_AXIS;
use crate::physics::flight::{
    accelerated_time_to_plane, linear_time_to_plane, parabola_time_down, parabola_time_up,
};
use nalgebra::SVector;

/// A point or velocity in `D` dimensions.
pub type Vector<const D: usize> = SVector<f64, D>;

/// The delayed state of one particle: position and velocity at its own time `t`, and its
/// radius. Kept together (64 bytes for spheres) because a pair prediction reads all of it.
#[derive(Debug, Clone, Copy)]
#[repr(C, align(64))]
pub struct Body<const D: usize> {
    pub x: Vector<D>,
    pub t: f64,
    pub v: Vector<D>,
    pub r: f64,
}

/// The particles: states, counters, numbering, and the box geometry their flights need.
#[derive(Debug, Clone)]
pub struct Bodies<const D: usize, const GRAV: bool, const SHEAR: bool> {
    pub body: Vec<Body<D>>,
    /// Velocity changes of each particle (lazy invalidation of pair events).
    pub count: Vec<u32>,
    /// Time of each particle's last collision (TC model; empty when `tc = 0`).
    pub(crate) last_collision: Vec<f64>,
    /// Shear drive: acceleration along `y` in the particle's slab (empty otherwise).
    pub(crate) accel: Vec<f64>,
    /// Original index (scene order) of the particle stored at each internal index.
    pub id: Vec<u32>,
    /// Internal index of each original particle.
    pub(crate) slot_of: Vec<u32>,
    pub size: [f64; D],
    pub periodic: [bool; D],
    pub gravity: f64,
    pub mass: f64,
    /// Work of the shear field on the flights already brought up to date
    /// (`sum m a_k dy`, docs/model.md 4.2); 0 without shear.
    pub(crate) field_work: f64,
}

/// Bytes a vector holds on the heap (its capacity, not its length).
pub(crate) fn vec_bytes<T>(v: &Vec<T>) -> usize {
    v.capacity() * std::mem::size_of::<T>()
}

/// Reorders `v` in place so that entry `k` becomes the old `v[order[k]]`, cycle by cycle (one
/// byte of marks per entry instead of a second copy of `v`: no peak memory). An empty `v` stays
/// empty.
pub(crate) fn permute_in_place<T: Copy>(v: &mut [T], order: &[u32]) {
    if v.is_empty() {
        return;
    }
    assert_eq!(v.len(), order.len(), "permutation of another length");
    let mut done = vec![false; v.len()];
    for start in 0..v.len() {
        if done[start] {
            continue;
        }
        let first = v[start];
        let mut k = start;
        loop {
            done[k] = true;
            let src = order[k] as usize;
            if src == start {
                v[k] = first;
                break;
            }
            v[k] = v[src];
            k = src;
        }
    }
}

impl<const D: usize, const GRAV: bool, const SHEAR: bool> Bodies<D, GRAV, SHEAR> {
    #[inline]
    pub fn len(&self) -> usize {
        self.body.len()
    }

    pub fn is_empty(&self) -> bool {
        self.body.is_empty()
    }

    /// Time since the later of the last collisions of `i` and `j` at time `t` (TC model; pass
    /// `j = i` for one particle); `+inf` when the engine keeps no collision times (`tc = 0`, where
    /// `rebound_speed` never looks at it: `since < 0` cannot hold).
    #[inline]
    pub(crate) fn since_last_collision(&self, i: usize, j: usize, t: f64) -> f64 {
        if self.last_collision.is_empty() {
            f64::INFINITY
        } else {
            t - self.last_collision[i].max(self.last_collision[j])
        }
    }

    /// Records a collision of `i` at time `t` (TC model; nothing without it).
    #[inline]
    pub(crate) fn record_collision(&mut self, i: usize, t: f64) {
        if let Some(last) = self.last_collision.get_mut(i) {
            *last = t;
        }
    }

    /// Records a velocity change of `i` (invalidates pair events predicted with its old course).
    #[inline]
    pub fn bump(&mut self, i: usize) {
        self.count[i] = self.count[i].wrapping_add(1);
    }

    /// Position and velocity of particle `i` at time `t` (without storing them).
    #[inline]
    pub(crate) fn state_at(&self, i: usize, t: f64) -> (Vector<D>, Vector<D>) {
        let dt = t - self.body[i].t;
        let mut x = self.body[i].x + self.body[i].v * dt;
        let mut v = self.body[i].v;
        if GRAV {
            x[D - 1] -= 0.5 * self.gravity * dt * dt;
            v[D - 1] -= self.gravity * dt;
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
    pub(crate) fn field_work(&self, i: usize, x: &Vector<D>) -> f64 {
        self.mass * self.accel[i] * (x[FORCE_AXIS] - self.body[i].x[FORCE_AXIS])
    }

    /// Brings particle `i` to time `t`.
    #[inline]
    pub fn advance(&mut self, i: usize, t: f64) {
        if self.body[i].t != t {
            let (x, v) = self.state_at(i, t);
            if SHEAR {
                self.field_work += self.field_work(i, &x);
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
    pub fn min_image(&self, mut r: Vector<D>) -> Vector<D> {
        for k in 0..D {
            if self.periodic[k] {
                let (l, half) = (self.size[k], 0.5 * self.size[k]);
                if r[k] > half {
                    r[k] -= l;
                } else if r[k] < -half {
                    r[k] += l;
                }
            }
        }
        r
    }

    /// Times until particle `i` (at the current time) reaches the plane `hi` moving up and the
    /// plane `lo` moving down along axis `k` (`+inf` for a plane at infinity or never reached):
    /// parabolas on the vertical axis under gravity, straight lines otherwise.
    pub(crate) fn times_to_planes(&self, i: usize, k: usize, lo: f64, hi: f64) -> (f64, f64) {
        let (x, v) = (self.body[i].x[k], self.body[i].v[k]);
        let time = |plane: f64, up: bool| {
            if !plane.is_finite() {
                f64::INFINITY
            } else if SHEAR && k == FORCE_AXIS {
                accelerated_time_to_plane(x, v, self.accel[i], plane, up)
            } else if GRAV && k == D - 1 && up {
                parabola_time_up(x, v, self.gravity, plane)
            } else if GRAV && k == D - 1 {
                parabola_time_down(x, v, self.gravity, plane)
            } else {
                linear_time_to_plane(x, v, plane, up)
            }
        };
        (time(hi, true), time(lo, false))
    }

    /// Heap bytes of each per-particle array (`wetgran-bench memory`).
    pub fn memory(&self) -> Vec<(&'static str, usize)> {
        vec![
            ("bodies.body (x, t, v, r)", vec_bytes(&self.body)),
            ("bodies.count", vec_bytes(&self.count)),
            ("bodies.last_collision", vec_bytes(&self.last_collision)),
            ("bodies.accel", vec_bytes(&self.accel)),
            ("bodies.id", vec_bytes(&self.id)),
            ("bodies.slot_of", vec_bytes(&self.slot_of)),
        ]
    }

    /// Renumbers the particles: new index `k` holds old particle `order[k]`.
    pub(crate) fn permute(&mut self, order: &[u32]) {
        permute_in_place(&mut self.body, order);
        permute_in_place(&mut self.count, order);
        permute_in_place(&mut self.last_collision, order);
        permute_in_place(&mut self.accel, order);
        permute_in_place(&mut self.id, order);
        for (new, &orig) in self.id.iter().enumerate() {
            self.slot_of[orig as usize] = new as u32;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::permute_in_place;

    #[test]
    fn permuting_in_place_matches_a_copy() {
        // A permutation with a fixed point, a 2-cycle and a 4-cycle.
        let order = [3u32, 0, 2, 5, 6, 1, 4];
        let old: Vec<u64> = (0..7).map(|k| 100 + k).collect();
        let copy: Vec<u64> = order.iter().map(|&k| old[k as usize]).collect();
        let mut v = old.clone();
        permute_in_place(&mut v, &order);
        assert_eq!(v, copy);
        let mut empty: Vec<u64> = Vec::new();
        permute_in_place(&mut empty, &order);
        assert!(empty.is_empty());
    }
}
