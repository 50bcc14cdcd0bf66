//! A lower bound on the per-sample cost of any repair that re-tests every edge of the kept
//! triangulation (docs/performance.md, "Round 5"): the leanest verification pass, as a
//! measurement. The topology of a [`super::kinetic_delaunay::KineticDelaunay`] is copied into
//! flat lists (every finite triangle; every edge between two finite triangles as the four
//! corner sites of its quadrilateral; every hull test), and [`FlatCheck::verify`] moves the
//! sites to a frame's positions (wrapped position plus the site's fixed image offset) and runs
//! the filtered predicates ([`super::predicates`]: Shewchuk's floating-point stage, the exact
//! one only where it is inconclusive) over the lists, with no bookkeeping: it counts the
//! triangles that are not strictly positive and the edges in conflict (MODEL.md 7: an edge is
//! flipped when the vertex across lies strictly inside the circumcircle).
//!
//! The lists would be patched only where flips happen; what patching costs is not part of the
//! bound.

use super::kinetic_delaunay::{c, wrap_fast};
use super::predicates::{incircle, orient2d};
use crate::sim::Frame;

/// The flat lists (see the module header).
#[derive(Debug, Clone, Default)]
pub struct FlatCheck {
    /// Particle of each site (`u32::MAX`: a free slot, not moved).
    pub(crate) particle: Vec<u32>,
    /// Image offset of each site: its shift times the box length.
    pub(crate) offset: Vec<[f64; 2]>,
    /// Finite triangles, counter-clockwise.
    pub(crate) tri: Vec<[u32; 3]>,
    /// Edges between two finite triangles: `(a, b, c)` counter-clockwise, `d` across.
    pub(crate) quad: Vec<[u32; 4]>,
    /// Hull tests `(x, y, d)`: in conflict when `orient2d(x, y, d) > 0`.
    pub(crate) hull: Vec<[u32; 3]>,
    /// Site positions at the last [`Self::verify`].
    pub pos: Vec<[f64; 2]>,
}

impl FlatCheck {
    /// How many triangles, quadrilaterals (edges with both opposite sites) and hull edges are
    /// tested per frame.
    pub fn sizes(&self) -> [usize; 3] {
        [self.tri.len(), self.quad.len(), self.hull.len()]
    }

    /// Moves the sites to `frame` and tests every triangle and edge: `(triangles not strictly
    /// positive, edges and hull tests in conflict)`.
    #[inline(never)]
    pub fn verify(&mut self, frame: &Frame) -> (usize, usize) {
        self.pos.resize(self.particle.len(), [0.0; 2]);
        for ((p, &i), o) in self.pos.iter_mut().zip(&self.particle).zip(&self.offset) {
            if i == u32::MAX {
                continue;
            }
            let x = frame.x(i as usize);
            let (w0, w1) = (wrap_fast(frame, 0, x[0]), wrap_fast(frame, 1, x[1]));
            *p = [w0 + o[0], w1 + o[1]];
        }
        let pos = &self.pos;
        let inverted = self
            .tri
            .iter()
            .filter(|v| {
                orient2d(
                    c(pos[v[0] as usize]),
                    c(pos[v[1] as usize]),
                    c(pos[v[2] as usize]),
                ) <= 0.0
            })
            .count();
        let mut conflicts = self
            .quad
            .iter()
            .filter(|v| {
                incircle(
                    c(pos[v[0] as usize]),
                    c(pos[v[1] as usize]),
                    c(pos[v[2] as usize]),
                    c(pos[v[3] as usize]),
                ) > 0.0
            })
            .count();
        conflicts += self
            .hull
            .iter()
            .filter(|v| {
                orient2d(
                    c(pos[v[0] as usize]),
                    c(pos[v[1] as usize]),
                    c(pos[v[2] as usize]),
                ) > 0.0
            })
            .count();
        (inverted, conflicts)
    }
}
