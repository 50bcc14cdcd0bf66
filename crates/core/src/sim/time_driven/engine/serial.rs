//! The serial strategy: a step on the calling thread, as one loop per kind of force. The pair
//! loop scatters each pair force to both partners (`pair_forces_serial`, rows ascending, so
//! every particle receives its partners' forces in the order the rayon strategy's gather adds
//! them), then walls, body force, `1/m` and the integrator pass per axis. The booked sums are
//! taken per chunk as in the rayon strategy, so both give the same bits
//! (`crates/core/tests/time_driven_pins.rs` runs each pin on one thread, this strategy, and on
//! two, the rayon one); this one does less work (no per-entry force buffer, no gather).

use super::stepping::{Then, for_each_axis_segment, wall_axes};
use super::*;
use crate::sim::time_driven::integrator::{
    GEAR_FLUSH_EVERY, gear_correct_predict_axes, verlet_kick,
};
use crate::sim::time_driven::pair_kernel::pair_forces_serial;
use crate::sim::time_driven::walls::{WallBooks, wall_forces};

/// The serial strategy (no state of its own).
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Serial;

impl<const D: usize, const GRAV: bool, const WET: bool, B: BodyForce<D>> Strategy<D, GRAV, WET, B>
    for Serial
{
    fn advance(&mut self, s: &mut State<D, GRAV, WET, B>, _target: u64) {
        s.step_with(false, |s, t, vs, dt, then| {
            s.forces_then_serial(t, vs, dt, then)
        });
    }
}

impl<const D: usize, const GRAV: bool, const WET: bool, B: BodyForce<D>> State<D, GRAV, WET, B> {
    /// [`TimeEngine::forces_then`] on the calling thread (see the module doc).
    pub(super) fn forces_then_serial(&mut self, t: f64, vs: f64, dt: f64, then: Then) -> [f64; D] {
        let n = self.n;
        let init = self.force_start();
        if !self.acc_is_start {
            for k in 0..D {
                self.acc[k * n..(k + 1) * n].fill(init[k]);
            }
        }
        // The integrator pass below leaves the start values for the next evaluation.
        self.acc_is_start = then == Then::Gear;
        let pc = self.p.pair_constants(vs, dt);
        let list = &mut self.list;
        let pb = pair_forces_serial::<D, WET>(
            &pc,
            &self.r[0],
            &self.r[1],
            &mut self.acc,
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
        self.max_overlap = self.max_overlap.max(pb.max_overlap);
        let (diss, mut work) = self.walls_serial(t, vs, dt, pb.dissipated);
        if B::ACTIVE {
            work = self.body_force_serial(t, vs, dt, work);
        }
        let p = &self.p;
        // a = F / m.
        if p.mass != 1.0 {
            let inv_m = 1.0 / p.mass;
            for e in &mut self.acc {
                *e *= inv_m;
            }
        }
        self.dissipated_damping += diss;
        self.work_by_drive += work;
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

    /// The walls' forces added to `acc`, per chunk of coordinates (the chunks of the rayon
    /// strategy), each chunk's dissipation and work summed on its own and added in order (a
    /// chunk that booked nothing adds +0 and changes nothing) to `diss` and to a work sum from
    /// 0; books the onsets and the largest overlap, returns the dissipation and the work.
    fn walls_serial(&mut self, t: f64, vs: f64, dt: f64, mut diss: f64) -> (f64, f64) {
        let (n, p) = (self.n, &self.p);
        let mut work = 0.0;
        if p.periodic.iter().all(|&periodic| periodic) {
            return (diss, work);
        }
        let walls = wall_axes(p, t, vs, dt);
        let (x, v, f) = (&self.r[0], &self.r[1], &mut self.acc);
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
            self.max_overlap = self.max_overlap.max(part.max_overlap);
            self.counts.wall_collisions += part.onsets;
        }
        (diss, work)
    }

    /// The body force added to `acc`; returns `work` plus its work, summed per
    /// [`PARTICLE_CHUNK`] particles and the sums added in order.
    fn body_force_serial(&mut self, t: f64, vs: f64, dt: f64, mut work: f64) -> f64 {
        let n = self.n;
        let (x, v, f) = (&self.r[0], &self.r[1], &mut self.acc);
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
        work + part
    }
}
