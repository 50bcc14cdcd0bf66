//! The serial strategy: a step on the calling thread. The pair loop scatters each pair force to
//! both partners (`pair_forces_serial`, rows ascending), then the per-particle phase runs
//! (`ParticlePhase`: walls, body force and `1/m` per chunk, books summed per chunk; the
//! integrator pass on whole axes).

use super::particle_phase::ParticlePhase;
use super::stepping::Then;
use super::*;
use crate::sim::time_driven::pair_kernel::pair_forces_serial;

/// The serial strategy: the per-particle phase's buffers.
#[derive(Debug, Clone, Default)]
pub(super) struct Serial<const D: usize>(ParticlePhase<D>);

impl<const D: usize, const GRAV: bool, const WET: bool, B: BodyForce<D>> Strategy<D, GRAV, WET, B>
    for Serial<D>
{
    fn advance(&mut self, s: &mut State<D, GRAV, WET, B>, _target: u64) {
        s.step_with(|s, t, vs, dt, then| self.forces_then(s, t, vs, dt, then));
    }
}

impl<const D: usize> Serial<D> {
    /// [`TimeEngine::forces_then`] on the calling thread (see the module doc).
    pub(super) fn forces_then<const GRAV: bool, const WET: bool, B: BodyForce<D>>(
        &mut self,
        s: &mut State<D, GRAV, WET, B>,
        t: f64,
        vs: f64,
        dt: f64,
        then: Then,
    ) -> [f64; D] {
        let n = s.n;
        if !s.acc_is_start {
            let init = s.force_start();
            for k in 0..D {
                s.acc[k * n..(k + 1) * n].fill(init[k]);
            }
        }
        let pc = s.p.pair_constants(vs, dt);
        let list = &mut s.list;
        let pb = pair_forces_serial::<D, WET>(
            &pc,
            &s.r[0],
            &s.r[1],
            &mut s.acc,
            &s.radius,
            &list.start,
            &list.rows,
            &list.partner,
            &mut list.flags,
        );
        self.0.run(s, &[pb], t, vs, dt, then)
    }
}
