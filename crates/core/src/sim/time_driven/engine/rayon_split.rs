//! The rayon strategy: each phase of a step split over the threads of the current pool, in
//! fixed chunks whose results are combined in chunk order, so the numbers do not depend on the
//! number of threads:
//!
//! 1. the pair forces of every Verlet-list entry (each pair once), into a buffer, with the
//!    contact and bridge flags (`pair_chunk`, chunks of [`ENTRY_CHUNK`] entries);
//! 2. the body force per particle, into a buffer, with its work;
//! 3. per chunk of [`PARTICLE_CHUNK`] coordinates: the weight, the pair forces gathered in the
//!    order the half list's rows visit them (the partners' rows, ascending, then the
//!    particle's own row), the walls, the body force, `1/m`, then the integrator pass
//!    ([`particle_chunk`]).
//!
//! Phases 2 and 3 ([`ParticlePhase`]) are the serial strategy's too, run on the calling thread
//! after its pair loop (the integrator pass then on whole axes); its accelerations are the same
//! bits as the gather's.

use super::stepping::{Then, for_each_axis_segment, max_ignoring_nan, wall_axes};
use super::*;
use crate::sim::time_driven::integrator::{
    GEAR_FLUSH_EVERY, gear_correct_predict_axis, verlet_kick,
};
use crate::sim::time_driven::pair_kernel::{Books, ENTRY_CHUNK, pair_chunk};
use crate::sim::time_driven::walls::{WallAxis, wall_forces};
use rayon::prelude::*;

/// The rayon strategy's buffers, reused from step to step (per list entry or per chunk).
#[derive(Debug, Clone, Default)]
pub(super) struct RayonSplit<const D: usize> {
    /// Pair force of each Verlet-list entry on its row's particle, `D` values per entry.
    pair_f: Vec<f64>,
    pair_books: Vec<Books>,
    phase: ParticlePhase<D>,
}

/// The buffers of phases 2 and 3, which the serial strategy runs too (on the calling thread).
#[derive(Debug, Clone, Default)]
pub(super) struct ParticlePhase<const D: usize> {
    /// Body force per particle, particle-major (empty without one).
    body_f: Vec<f64>,
    body_work: Vec<f64>,
    chunk_books: Vec<ChunkBooks<D>>,
}

impl<const D: usize, const GRAV: bool, const WET: bool, B: BodyForce<D>> Strategy<D, GRAV, WET, B>
    for RayonSplit<D>
{
    fn advance(&mut self, s: &mut State<D, GRAV, WET, B>, _target: u64) {
        s.step_with(true, |s, t, vs, dt, then| {
            self.forces_then(s, t, vs, dt, then)
        });
    }
}

impl<const D: usize> RayonSplit<D> {
    /// [`TimeEngine::forces_then`] split over the pool's threads (see the module doc).
    pub(super) fn forces_then<const GRAV: bool, const WET: bool, B: BodyForce<D>>(
        &mut self,
        s: &mut State<D, GRAV, WET, B>,
        t: f64,
        vs: f64,
        dt: f64,
        then: Then,
    ) -> [f64; D] {
        s.list.ensure_transposed();
        let pc = s.p.pair_constants(vs, dt);
        self.pair_f.resize(D * s.list.partner.len(), 0.0);
        let (x, v, radius) = (&s.r[0], &s.r[1], &s.radius);
        let (row_of, partner) = (&s.list.row_of, &s.list.partner);
        s.list
            .flags
            .par_chunks_mut(ENTRY_CHUNK)
            .zip(self.pair_f.par_chunks_mut(ENTRY_CHUNK * D))
            .enumerate()
            .with_min_len(1)
            .map(|(c, (flags, pf))| {
                let q0 = c * ENTRY_CHUNK;
                pair_chunk::<D, WET>(&pc, x, v, radius, &row_of[q0..], &partner[q0..], flags, pf)
            })
            .collect_into_vec(&mut self.pair_books);
        let pair_f = Some(&self.pair_f[..]);
        self.phase.run(s, pair_f, &self.pair_books, t, vs, dt, then)
    }
}

impl<const D: usize> ParticlePhase<D> {
    /// Phases 2 and 3 after the pair phase, on the pool's threads where `pair_f` (phase 1's
    /// forces, gathered per particle) is given, else on the calling thread (the serial
    /// strategy: the pair forces are in `acc`, over the force start values). Books the pair
    /// loop's `pair_books` (in chunk order), then the walls and the body force; returns the
    /// largest move per axis of the Gear pass.
    pub(super) fn run<const GRAV: bool, const WET: bool, B: BodyForce<D>>(
        &mut self,
        s: &mut State<D, GRAV, WET, B>,
        pair_f: Option<&[f64]>,
        pair_books: &[Books],
        t: f64,
        vs: f64,
        dt: f64,
        then: Then,
    ) -> [f64; D] {
        let min_len = if pair_f.is_some() { 1 } else { usize::MAX };
        let mut total = Books::default();
        for b in pair_books {
            total.add(b);
        }
        self.body_forces(s, t, vs, dt, min_len);
        // The Gear pass leaves the start values for the next evaluation.
        s.acc_is_start = then == Then::Gear;
        let walls = wall_axes(&s.p, t, vs, dt);
        // On the calling thread the integrator pass runs on whole axes afterwards (the same
        // bits; a call per chunk costs the serial step about a tenth at N = 1200).
        let chunk_then = if pair_f.is_some() {
            then
        } else {
            Then::Nothing
        };
        self.particles(s, pair_f, walls, dt, chunk_then, min_len);
        let mut moved = if pair_f.is_some() {
            [0.0; D]
        } else {
            s.integrate_axes(then, dt)
        };
        for b in &self.chunk_books {
            total.add(&b.walls);
            for k in 0..D {
                moved[k] = max_ignoring_nan(moved[k], b.moved[k]);
            }
        }
        for w in &self.body_work {
            total.work += w;
        }
        s.dissipated_damping += total.dissipated;
        s.dissipated_bridges += total.bridge_ledger;
        s.work_by_drive += total.work;
        s.add_counts(&total);
        moved
    }

    /// Phase 2: the body force per particle (all axes at once, particle-major) into `body_f`,
    /// its work per chunk into `body_work` (nothing without a body force).
    fn body_forces<const GRAV: bool, const WET: bool, B: BodyForce<D>>(
        &mut self,
        s: &State<D, GRAV, WET, B>,
        t: f64,
        vs: f64,
        dt: f64,
        min_len: usize,
    ) {
        self.body_work.clear();
        if !B::ACTIVE {
            return;
        }
        let n = s.n;
        self.body_f.resize(D * n, 0.0);
        let (x, v, body) = (&s.r[0], &s.r[1], &s.body);
        self.body_f
            .par_chunks_mut(PARTICLE_CHUNK * D)
            .enumerate()
            .with_min_len(min_len)
            .map(|(c, bf)| {
                let i0 = c * PARTICLE_CHUNK;
                let mut work = 0.0;
                for (m, out) in bf.chunks_mut(D).enumerate() {
                    let i = i0 + m;
                    let xi: [f64; D] = std::array::from_fn(|k| x[k * n + i]);
                    let fb = body.force(&xi, t);
                    for k in 0..D {
                        out[k] = fb[k];
                        work += fb[k] * v[k * n + i] * vs * dt;
                    }
                }
                work
            })
            .collect_into_vec(&mut self.body_work);
    }

    /// Phase 3: [`particle_chunk`] on every chunk of coordinates, the books into
    /// `chunk_books`.
    fn particles<const GRAV: bool, const WET: bool, B: BodyForce<D>>(
        &mut self,
        s: &mut State<D, GRAV, WET, B>,
        pair_f: Option<&[f64]>,
        walls: [WallAxis; D],
        dt: f64,
        then: Then,
        min_len: usize,
    ) {
        let cx = ChunkContext::<D> {
            n: s.n,
            pf: pair_f,
            list: &s.list,
            radius: &s.radius,
            wall_kr: &s.wall_kr,
            body_f: if B::ACTIVE { &self.body_f } else { &[] },
            init: s.force_start(),
            p: &s.p,
            walls,
            dt,
            then,
            flush: s.steps.is_multiple_of(GEAR_FLUSH_EVERY),
        };
        let [r0, r1, r2, r3, r4, r5] = &mut s.r;
        (
            s.acc.par_chunks_mut(PARTICLE_CHUNK),
            r0.par_chunks_mut(PARTICLE_CHUNK),
            r1.par_chunks_mut(PARTICLE_CHUNK),
            r2.par_chunks_mut(PARTICLE_CHUNK),
            r3.par_chunks_mut(PARTICLE_CHUNK),
            r4.par_chunks_mut(PARTICLE_CHUNK),
            r5.par_chunks_mut(PARTICLE_CHUNK),
            s.wall_contact.par_chunks_mut(PARTICLE_CHUNK),
        )
            .into_par_iter()
            .enumerate()
            .with_min_len(min_len)
            .map(|(c, (acc, r0, r1, r2, r3, r4, r5, touch))| {
                particle_chunk(
                    &cx,
                    c * PARTICLE_CHUNK,
                    acc,
                    [r0, r1, r2, r3, r4, r5],
                    touch,
                )
            })
            .collect_into_vec(&mut self.chunk_books);
    }
}

/// What one chunk of the per-particle phase books.
#[derive(Debug, Clone, Copy)]
struct ChunkBooks<const D: usize> {
    walls: Books,
    /// Largest move of a predicted position per axis (Gear).
    moved: [f64; D],
}

/// What the per-particle phase reads (shared by every chunk).
struct ChunkContext<'a, const D: usize> {
    n: usize,
    /// Pair forces per list entry, `D` values each (`pair_chunk`); `None`: already in `acc`.
    pf: Option<&'a [f64]>,
    list: &'a NeighbourList<D>,
    radius: &'a [f64],
    wall_kr: &'a [f64],
    /// Body force per particle, particle-major (empty without one).
    body_f: &'a [f64],
    /// The force every coordinate starts from (the weight on the last axis).
    init: [f64; D],
    p: &'a Params<D>,
    /// Per axis: the walls (used on the non-periodic axes).
    walls: [WallAxis; D],
    dt: f64,
    then: Then,
    /// Whether this step flushes the Gear derivatives ([`GEAR_FLUSH_EVERY`]).
    flush: bool,
}

/// The per-particle phase on the flat coordinates `e0..e0 + acc.len()` (one chunk, see
/// [`RayonSplit::forces_then`]): `acc` is computed (start value, pair forces gathered in the
/// half list's order, walls, body force, `1/m`), then `cx.then` updates `r`.
fn particle_chunk<const D: usize>(
    cx: &ChunkContext<D>,
    e0: usize,
    acc: &mut [f64],
    mut r: [&mut [f64]; 6],
    touch: &mut [u8],
) -> ChunkBooks<D> {
    let mut walls = Books::default();
    let mut moved = [0.0; D];
    let (n, p, l) = (cx.n, cx.p, cx.list);
    for_each_axis_segment(n, e0, acc.len(), |k, o, m| {
        let i0 = (e0 + o) % n;
        let acc = &mut acc[o..o + m];
        if let Some(pf) = cx.pf {
            acc.fill(cx.init[k]);
            // The partners' rows, ascending: `f_j -= f_ij`.
            for &q in &l.in_entry[l.in_start[i0] as usize..l.in_start[i0 + m] as usize] {
                let q = q as usize;
                acc[l.partner[q] as usize - i0] -= pf[q * D + k];
            }
            // The particle's own row, summed first: `f_i += sum_j f_ij`.
            let (mut q, end) = (l.start[i0] as usize, l.start[i0 + m] as usize);
            while q < end {
                let i = l.row_of[q] as usize;
                let row_end = l.start[i + 1] as usize;
                let mut own = 0.0;
                while q < row_end {
                    own += pf[q * D + k];
                    q += 1;
                }
                acc[i - i0] += own;
            }
        }
        if !p.periodic[k] {
            let radius = &cx.radius[i0..i0 + m];
            let wall_kr = &cx.wall_kr[i0..i0 + m];
            let (x, v, touching) = (&r[0][o..o + m], &r[1][o..o + m], &mut touch[o..o + m]);
            wall_forces(
                &cx.walls[k],
                x,
                v,
                radius,
                wall_kr,
                touching,
                acc,
                &mut walls,
            );
        }
        if !cx.body_f.is_empty() {
            for i in 0..m {
                acc[i] += cx.body_f[(i0 + i) * D + k];
            }
        }
        // a = F / m.
        if p.mass != 1.0 {
            let inv_m = 1.0 / p.mass;
            for a in acc.iter_mut() {
                *a *= inv_m;
            }
        }
        match cx.then {
            Then::Nothing => {}
            Then::Gear => {
                let step_move = gear_correct_predict_axis(
                    r.each_mut().map(|r| &mut r[o..o + m]),
                    acc,
                    cx.init[k],
                    0.5 * p.dt * p.dt,
                    &p.gear,
                    p.periodic[k].then_some(p.size[k]),
                    cx.flush,
                );
                moved[k] = max_ignoring_nan(moved[k], step_move);
            }
            Then::VerletKick => verlet_kick(&mut r[1][o..o + m], acc, cx.dt),
        }
    });
    ChunkBooks { walls, moved }
}
