//! Stepping the time-driven engine: the [`Strategy`] trait of the two execution strategies,
//! the choice of strategy per step, and what they share: one step of Gear or velocity Verlet
//! around a force evaluation ([`State::step_with`]), the list update and the walls of a step.

use super::*;
use crate::sim::time_driven::domains::DOMAINS;
use crate::sim::time_driven::integrator::{
    GEAR_FLUSH_EVERY, gear_correct_predict_axes, gear_predict, verlet_drift, verlet_kick,
};
use crate::sim::time_driven::neighbours::{needs_rebuild, norm};
use crate::sim::time_driven::walls::WallAxis;

/// An execution strategy: [`Serial`] or [`Domains`] (ARCHITECTURE.md, "Time engine"). Each
/// gives the same bits on any number of threads.
pub(super) trait Strategy<const D: usize, const GRAV: bool, const WET: bool, B: BodyForce<D>> {
    /// Advances `s` by at least one step and at most to step `target`.
    fn advance(&mut self, s: &mut State<D, GRAV, WET, B>, target: u64);
}

impl<const D: usize, const GRAV: bool, const WET: bool, B: BodyForce<D>>
    TimeEngine<D, GRAV, WET, B>
{
    /// One time step of the scene's integrator.
    pub fn step(&mut self) {
        let target = self.s.steps + 1;
        self.advance(target);
    }

    /// Runs until the time is the multiple of `dt` nearest to `t_end`. Always returns true (the
    /// time engine has no event cap). Runs on the caller's rayon pool (`sim::threads::Threads`).
    pub fn run_until(&mut self, t_end: f64) -> bool {
        let target = (t_end / self.s.p.dt).round().max(0.0) as u64;
        while self.s.steps < target {
            self.advance(target);
        }
        true
    }

    /// Advances by at least one step towards `target`: on the domains for a predicted Gear step
    /// where [`Self::uses_domains`], else serially.
    fn advance(&mut self, target: u64) {
        if self.s.predicted && self.uses_domains() {
            self.domains.advance(&mut self.s, target);
        } else {
            self.serial.advance(&mut self.s, target);
        }
    }

    /// Whether the Gear steps run on the domains: no body force and at least
    /// `domains_from` (and [`DOMAINS`]) particles, whatever the threads.
    pub(super) fn uses_domains(&self) -> bool {
        self.s.p.integrator == IntegratorKind::Gear5
            && !B::ACTIVE
            && self.s.n >= DOMAINS
            && self.s.n >= self.domains_from
    }

    /// Accelerations at positions `r[0]` and velocities `r[1] * vs` at time `t`, then `then`
    /// (the Gear corrector-predictor or Verlet's second half); books dissipation, drive work,
    /// contact onsets and bridge events with weight `dt` (0: a re-evaluation that is not a
    /// step). Returns the largest move per axis of the Gear update (zeros otherwise). Serial:
    /// the initial forces and a re-evaluation after `set_state`.
    pub(super) fn forces_then(&mut self, t: f64, vs: f64, dt: f64, then: Then) -> [f64; D] {
        self.serial.forces_then(&mut self.s, t, vs, dt, then)
    }
}

impl<const D: usize, const GRAV: bool, const WET: bool, B: BodyForce<D>> State<D, GRAV, WET, B> {
    /// Wraps periodic coordinates of `r[0]` into `[0, L)` (Verlet, and the first Gear
    /// prediction; afterwards the Gear loop wraps its own output).
    fn wrap(&mut self) {
        let n = self.n;
        for k in 0..D {
            if self.p.periodic[k] {
                wrap_slice(&mut self.r[0][k * n..(k + 1) * n], self.p.size[k]);
            }
        }
    }

    /// Keeps the Verlet list valid: rebuilds it when some particle has moved more than
    /// `skin / 2` since the last build (tested exactly only where `moved_bound` says it might
    /// be, [`needs_rebuild`]).
    pub(super) fn update_list(&mut self) {
        let (half_skin, x) = (0.5 * self.list.skin(), &self.r[0]);
        let (bound, since) = (&mut self.moved_bound, &mut self.since_check);
        if needs_rebuild::<D>(bound, since, half_skin, x, self.list.built_at()) {
            self.list.build(&self.r[0], &self.radius);
            self.moved_bound = 0.0;
        }
    }

    /// One step of the scene's integrator around the force evaluation `forces` (a strategy's
    /// `forces_then`).
    pub(super) fn step_with(
        &mut self,
        forces: impl FnOnce(&mut Self, f64, f64, f64, Then) -> [f64; D],
    ) {
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
                let moved = forces(self, t1, 1.0 / dt, dt, Then::Gear);
                self.moved_bound += norm(moved);
                self.predicted = true;
            }
            IntegratorKind::Verlet => {
                let moved = self.verlet_drift_wrap(dt);
                self.moved_bound += norm(moved);
                self.update_list();
                forces(self, t1, 1.0, dt, Then::VerletKick);
            }
        }
        self.steps += 1;
    }

    /// `then` on whole axes (after the forces, `ParticlePhase::run` on the calling thread):
    /// returns the largest move per axis of the Gear pass.
    pub(super) fn integrate_axes(&mut self, then: Then, dt: f64) -> [f64; D] {
        let (p, init) = (&self.p, self.force_start());
        match then {
            Then::Nothing => [0.0; D],
            Then::Gear => gear_correct_predict_axes(
                &mut self.r,
                &mut self.acc,
                init,
                0.5 * p.dt * p.dt,
                &p.gear,
                std::array::from_fn(|k| p.periodic[k].then_some(p.size[k])),
                self.steps.is_multiple_of(GEAR_FLUSH_EVERY),
            ),
            Then::VerletKick => {
                verlet_kick(&mut self.r[1], &self.acc, dt);
                [0.0; D]
            }
        }
    }

    /// Velocity Verlet's first half on every coordinate (`verlet_drift`), chunk by chunk, with
    /// the wrap of the periodic axes; returns the largest move per axis.
    fn verlet_drift_wrap(&mut self, dt: f64) -> [f64; D] {
        let n = self.n;
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
        x.chunks_mut(PARTICLE_CHUNK)
            .zip(v.chunks_mut(PARTICLE_CHUNK))
            .zip(self.acc.chunks_mut(PARTICLE_CHUNK))
            .enumerate()
            .map(|(c, ((x, v), acc))| drift(c * PARTICLE_CHUNK, x, v, acc))
            .fold([0.0; D], |a, b| {
                std::array::from_fn(|k| max_ignoring_nan(a[k], b[k]))
            })
    }
}

/// The walls of every axis at time `t` (used on the non-periodic ones): Hertz with
/// `R_eff = R_i`; the last axis's walls move with the drive, `z_w(t) = A sin(omega t)`
/// (docs/model.md 4.1). `vs` turns the velocity array into velocities, `dt` weights the books.
pub(super) fn wall_axes<const D: usize>(p: &Params<D>, t: f64, vs: f64, dt: f64) -> [WallAxis; D] {
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

/// What the per-particle phase does after the forces.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Then {
    /// Nothing (the initial forces, a re-evaluation after `set_state`).
    Nothing,
    /// Gear's corrector of this step fused with the predictor of the next.
    Gear,
    /// Velocity Verlet's second half, `v += a dt / 2`.
    VerletKick,
}

/// Splits the flat coordinates `e0..e0 + len` (axis-major, `n` per axis) at the axis
/// boundaries and calls `f(k, offset, m)` for each piece: axis `k`, offset in the chunk, length.
pub(super) fn for_each_axis_segment(
    n: usize,
    e0: usize,
    len: usize,
    mut f: impl FnMut(usize, usize, usize),
) {
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
pub(super) fn max_ignoring_nan(a: f64, b: f64) -> f64 {
    if b > a { b } else { a }
}

/// [`wrap_into`] on every element, writing only the wrapped ones (few are: no store per
/// element).
fn wrap_slice(xs: &mut [f64], l: f64) {
    for x in xs.iter_mut().filter(|x| **x < 0.0 || **x >= l) {
        *x = wrap_into(*x, l);
    }
}

/// `x` back into `[0, L)` after a move of less than `L`: `x < 0: x + L; x >= L: x - L`.
#[inline(always)]
pub(super) fn wrap_into(x: f64, l: f64) -> f64 {
    if x < 0.0 {
        x + l
    } else if x >= l {
        x - l
    } else {
        x
    }
}
