//! The event engine's invariant checks, without allocation: the per-particle check
//! ([`Engine::quick_check`], `O(N)`: what a blown-up or broken run shows first) and the full
//! check ([`Engine::sanity_check`]), which adds each particle's cell and slab and the pairs
//! (`O(N x neighbours)`). How often the sampling loop runs each: `sim::checks`.

use super::super::queue::EventQueue;
use super::super::walls::{TABLE_PLACEMENT_TOLERANCE, WallSolver};
use super::Engine;

/// What the quick check found wrong with one particle.
enum Fault {
    NonFinite,
    /// Outside the box along the axis, which spans `[lo, hi]` for this particle.
    Outside {
        axis: usize,
        lo: f64,
        hi: f64,
    },
    EventInThePast,
}

impl<const D: usize, const GRAV: bool, const WET: bool, const SHEAR: bool, Q: EventQueue>
    Engine<D, GRAV, WET, SHEAR, Q>
{
    /// Checks every invariant ([`Self::quick_check`], then every particle in its cell and slab,
    /// no pair overlap, no over-stretched or one-sided bond) and returns the first violation.
    pub fn sanity_check(&self) -> Result<(), String> {
        self.quick_check()?;
        self.neighbour_check()
    }

    /// The invariants of each particle on its own: no time reversal, finite numbers, every
    /// particle inside the box (with the `table` solver up to `TABLE_PLACEMENT_TOLERANCE`
    /// behind a shaken wall, by design), no event in the past. Returns the first violation.
    pub fn quick_check(&self) -> Result<(), String> {
        if self.time_reversals > 0 {
            return Err(format!(
                "{} events processed out of time order",
                self.time_reversals
            ));
        }
        let t = self.time;
        // The shaken floor and lid move by z_w(t).
        let shift = self.walls.solver.motion().map_or(0.0, |w| w.position(t));
        let tabulated = matches!(self.walls.solver, WallSolver::Table(_));
        let past = t - 1e-9 * t.abs().max(1.0);
        let fault = |i: usize| -> Option<Fault> {
            let b = &self.bodies;
            let (x, v) = b.state_at(i, t);
            if !x.iter().chain(v.iter()).all(|a| a.is_finite()) {
                return Some(Fault::NonFinite);
            }
            let r = b.body[i].r;
            for k in 0..D {
                let (lo, hi) = if b.periodic[k] {
                    (0.0, b.size[k])
                } else {
                    let s = if k == D - 1 { shift } else { 0.0 };
                    (r + s, b.size[k] - r + s)
                };
                // The `table` solver places a particle on the shaken wall only as far as its
                // neighbours leave room (`walls::placement_room`): the rest, at most its
                // placement tolerance, may stay behind the wall until the particle leaves it.
                let behind = (lo - x[k]).max(x[k] - hi);
                let residual = tabulated && k == D - 1 && behind <= TABLE_PLACEMENT_TOLERANCE;
                if behind > self.overlap_tolerance && !residual {
                    return Some(Fault::Outside { axis: k, lo, hi });
                }
            }
            (self.queue.key(i) < past).then_some(Fault::EventInThePast)
        };
        // A screen without branches first (every sample runs it): it flags at least every
        // particle `fault` would; `fault` then names the first one, if any.
        let b = &self.bodies;
        let mut flagged = false;
        for i in 0..self.len() {
            let (x, v) = b.state_at(i, t);
            let r = b.body[i].r;
            let mut bad = !(x.sum() + v.sum()).is_finite();
            for k in 0..D {
                if !b.periodic[k] {
                    let s = if k == D - 1 { shift } else { 0.0 };
                    let behind = (r + s - x[k]).max(x[k] - (b.size[k] - r + s));
                    bad |= behind > self.overlap_tolerance;
                } else {
                    bad |= (-x[k]).max(x[k] - b.size[k]) > self.overlap_tolerance;
                }
            }
            flagged |= bad | (self.queue.key(i) < past);
        }
        if !flagged {
            return Ok(());
        }
        let Some((i, f)) = (0..self.len()).find_map(|i| fault(i).map(|f| (i, f))) else {
            return Ok(());
        };
        // Messages name particles by their scene index.
        let si = self.bodies.id[i];
        Err(match f {
            Fault::NonFinite => format!("particle {si} has a non-finite state at t = {t}"),
            Fault::Outside { axis, lo, hi } => format!(
                "particle {si} is outside the box along axis {axis}: x = {} not in [{lo}, {hi}] \
                 at t = {t}",
                self.bodies.state_at(i, t).0[axis]
            ),
            Fault::EventInThePast => format!(
                "particle {si} has an event in the past: {} < {t}",
                self.queue.key(i)
            ),
        })
    }

    /// The invariants of each particle's neighbourhood: in its cell (and slab), no pair
    /// overlap and no bonded pair beyond `s_crit` by more than the tolerance, no one-sided
    /// bond. Returns the first violation.
    fn neighbour_check(&self) -> Result<(), String> {
        let tol = self.overlap_tolerance;
        let t = self.time;
        let b = &self.bodies;
        for i in 0..self.len() {
            let si = b.id[i];
            let xi = b.state_at(i, t).0;
            if let Some(e) = self.cells.check(i, &xi, &b.periodic, tol) {
                return Err(format!("particle {si} {e} at t = {t}"));
            }
            if SHEAR && let Err(e) = self.slabs.check(i, xi[0], tol) {
                return Err(format!("particle {si} {e} at t = {t}"));
            }
            let mut err = None;
            self.cells.for_each_near(i, |j| {
                if j <= i || err.is_some() {
                    return;
                }
                let r = b.min_image(xi - b.state_at(j, t).0).norm();
                let sigma = b.body[i].r + b.body[j].r;
                if r < sigma - tol {
                    err = Some(format!(
                        "particles {si} and {} overlap by {} at t = {t}",
                        b.id[j],
                        sigma - r
                    ));
                }
            });
            if let Some(e) = err {
                return Err(e);
            }
            if WET {
                for &j in self.pairs.bonds_of(i) {
                    let j = j as usize;
                    let sj = b.id[j];
                    let r = b.min_image(xi - b.state_at(j, t).0).norm();
                    let lambda = b.body[i].r + b.body[j].r + self.pairs.p.s_crit;
                    if r > lambda + tol {
                        return Err(format!(
                            "bonded pair {si}-{sj} stretched beyond s_crit by {} at t = {t}",
                            r - lambda
                        ));
                    }
                    if !self.pairs.bonded(j, i) {
                        return Err(format!("bond {si}-{sj} is one-sided"));
                    }
                }
            }
        }
        Ok(())
    }
}
