//! The per-particle phase of a step, after the pair loop (`serial.rs`) has left the pair forces
//! in `acc` over the force start values: the body force per particle, then per chunk of
//! [`PARTICLE_CHUNK`] coordinates the walls, the body force and `1/m` ([`particle_chunk`]),
//! the books summed per chunk and the chunks added in order; then the integrator pass on whole
//! axes.

use super::stepping::{Then, for_each_axis_segment, wall_axes};
use super::*;
use crate::sim::time_driven::pair_kernel::Books;
use crate::sim::time_driven::walls::{WallAxis, wall_forces};

/// The per-particle phase's buffers, reused from step to step.
#[derive(Debug, Clone, Default)]
pub(super) struct ParticlePhase<const D: usize> {
    /// Body force per particle, particle-major (empty without one).
    body_f: Vec<f64>,
    body_work: Vec<f64>,
    chunk_books: Vec<Books>,
}

impl<const D: usize> ParticlePhase<D> {
    /// The phase after the pair loop (the pair forces in `acc`, over the force start values):
    /// books the pair loop's `pair_books` (in chunk order), then the walls and the body force;
    /// returns the largest move per axis of the Gear pass.
    pub(super) fn run<const GRAV: bool, const WET: bool, B: BodyForce<D>>(
        &mut self,
        s: &mut State<D, GRAV, WET, B>,
        pair_books: &[Books],
        t: f64,
        vs: f64,
        dt: f64,
        then: Then,
    ) -> [f64; D] {
        let mut total = Books::default();
        for b in pair_books {
            total.add(b);
        }
        self.body_forces(s, t, vs, dt);
        // The Gear pass leaves the start values for the next evaluation.
        s.acc_is_start = then == Then::Gear;
        let walls = wall_axes(&s.p, t, vs, dt);
        self.particles(s, walls);
        // The integrator pass on whole axes (a call per chunk costs the step about a tenth at
        // N = 1200).
        let moved = s.integrate_axes(then, dt);
        for b in &self.chunk_books {
            total.add(b);
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
    ) {
        self.body_work.clear();
        if !B::ACTIVE {
            return;
        }
        let n = s.n;
        self.body_f.resize(D * n, 0.0);
        let (x, v, body) = (&s.r[0], &s.r[1], &s.body);
        let works = self
            .body_f
            .chunks_mut(PARTICLE_CHUNK * D)
            .enumerate()
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
            });
        self.body_work.extend(works);
    }

    /// [`particle_chunk`] on every chunk of coordinates, the books into `chunk_books`.
    fn particles<const GRAV: bool, const WET: bool, B: BodyForce<D>>(
        &mut self,
        s: &mut State<D, GRAV, WET, B>,
        walls: [WallAxis; D],
    ) {
        let cx = ChunkContext::<D> {
            n: s.n,
            radius: &s.radius,
            wall_kr: &s.wall_kr,
            body_f: if B::ACTIVE { &self.body_f } else { &[] },
            p: &s.p,
            walls,
        };
        let (x, v) = (&s.r[0], &s.r[1]);
        self.chunk_books.clear();
        let chunks = s
            .acc
            .chunks_mut(PARTICLE_CHUNK)
            .zip(s.wall_contact.chunks_mut(PARTICLE_CHUNK))
            .enumerate()
            .map(|(c, (acc, touch))| {
                let e0 = c * PARTICLE_CHUNK;
                let (x, v) = (&x[e0..e0 + acc.len()], &v[e0..e0 + acc.len()]);
                particle_chunk(&cx, e0, acc, x, v, touch)
            });
        self.chunk_books.extend(chunks);
    }
}

/// What the per-particle phase reads (shared by every chunk).
struct ChunkContext<'a, const D: usize> {
    n: usize,
    radius: &'a [f64],
    wall_kr: &'a [f64],
    /// Body force per particle, particle-major (empty without one).
    body_f: &'a [f64],
    p: &'a Params<D>,
    /// Per axis: the walls (used on the non-periodic axes).
    walls: [WallAxis; D],
}

/// The per-particle phase on the flat coordinates `e0..e0 + acc.len()` (one chunk; `x`, `v`
/// and `touch` the chunk's positions, velocities and wall contacts): adds the walls and the
/// body force to `acc`, then divides by `m`.
fn particle_chunk<const D: usize>(
    cx: &ChunkContext<D>,
    e0: usize,
    acc: &mut [f64],
    x: &[f64],
    v: &[f64],
    touch: &mut [u8],
) -> Books {
    let mut walls = Books::default();
    let (n, p) = (cx.n, cx.p);
    for_each_axis_segment(n, e0, acc.len(), |k, o, m| {
        let i0 = (e0 + o) % n;
        let acc = &mut acc[o..o + m];
        if !p.periodic[k] {
            let radius = &cx.radius[i0..i0 + m];
            let wall_kr = &cx.wall_kr[i0..i0 + m];
            let (x, v, touching) = (&x[o..o + m], &v[o..o + m], &mut touch[o..o + m]);
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
    });
    walls
}
