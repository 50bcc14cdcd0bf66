//! A 2D Delaunay triangulation of the particle centres (and their periodic ghost images) kept
//! from one observer sample to the next and repaired by edge flips: the incremental method of
//! the location-change observer ([`super::location_changes`], MODEL.md 7: "move the points,
//! restore the Delaunay property by flipping the edges whose in-circle test fails").
//!
//! **Sites.** The same sites as the rebuilt triangulation ([`super::location_changes::images`]):
//! every particle at its wrapped position, plus its images shifted by one box length along each
//! periodic axis that fall within the ghost band `[-g, L + g)`. A site is one image of one
//! particle; when a particle crosses a periodic face its images are renamed (the shift relative
//! to the wrapped position changes by one) so that every site moves continuously.
//!
//! **Structure.** Triangles with their three neighbours, closed into a sphere by one vertex at
//! infinity ([`INF`]): each hull edge `a -> b` (interior on its left) carries the infinite
//! triangle `(b, a, INF)`. The predicates are exact (`robust`: Shewchuk's adaptive
//! `orient2d`, `incircle`), so the triangulation is the unique Delaunay triangulation whenever no
//! four sites are co-circular, the same one the rebuild (spade, also exact) finds.
//!
//! **Conflict** (the in-circle test, extended to the infinite triangles): a site `d` conflicts
//! with a finite triangle when it lies strictly inside its circumcircle (`incircle > 0`), and with
//! an infinite triangle `(x, y, INF)` when it lies strictly beyond its hull edge
//! (`orient2d(x, y, d) > 0`). An edge is flipped when the vertex across it conflicts with the
//! triangle on this side (Lawson's algorithm); across an edge `(c, INF)` this removes a reflex
//! hull vertex `c`.
//!
//! **One update** ([`KineticDelaunay::update`]):
//! 1. every kept site moves to its new position; if a finite triangle is not strictly positive
//!    (it inverted or went flat) the move is split into halves, recursively up to
//!    [`MAX_BISECTIONS`] levels, flipping to Delaunay after each part (the final triangulation
//!    does not depend on the path);
//! 2. Lawson flips from every edge until no edge conflicts;
//! 3. sites that left the ghost band are deleted (each is then the outermost site on its side,
//!    hence a hull vertex: it is merged into `INF` and the hull made convex again by flips);
//! 4. sites that entered the band are inserted (split the containing triangle, or the infinite
//!    triangle whose hull edge they lie beyond, then flips);
//! 5. a final check: every finite triangle positive and the hull a convex polygon that turns
//!    once (total turning `2 pi`); with both, the triangles tile the hull exactly once.
//!
//! **Fallback**: a rebuild from scratch (spade's bulk load, converted into this structure) at the
//! first sample, when the number of particles or the box changes, and whenever a step fails
//! (a move that still inverts a triangle after [`MAX_BISECTIONS`] halvings, a site exactly on an
//! edge, a leaving site not on the hull, too many flips, a failed final check). Every fallback is
//! counted by reason in [`KineticStats`]. Where spade cannot triangulate (fewer than three
//! sites, all collinear, two sites at the same position) the structure stays empty and each
//! sample is triangulated from scratch.

use super::location_changes::{Edge, SiteRef, edge_between, finish_edges, images};
use crate::sim::Frame;
use robust::{Coord, incircle, orient2d};
use spade::{DelaunayTriangulation, HasPosition, Point2, Triangulation};

/// The vertex at infinity.
pub const INF: u32 = u32::MAX;
/// Marks a deleted triangle (first vertex) or a deleted site (particle).
const DEAD: u32 = u32::MAX - 1;
/// Halvings of a move whose full step inverts a triangle, before a rebuild.
pub const MAX_BISECTIONS: u32 = 20;
/// Most sites held back in one sample, as a fraction of all sites, before a rebuild is cheaper.
pub const MAX_HELD_FRACTION: f64 = 0.15;
/// Most halvings of held sites' moves in one sample before a rebuild.
pub const MAX_HALVINGS: u32 = 256;
/// Longest back-off after failed repairs: `2^4 - 1 = 15` samples rebuilt without trying.
pub const MAX_BACKOFF_LOG2: u32 = 4;
/// Most images of one particle (shifts -1, 0, 1 on two axes).
const MAX_IMAGES: usize = 9;

/// How often each path was taken.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct KineticStats {
    /// Samples repaired by flips (no rebuild).
    pub incremental: u64,
    /// Rebuilds: the first sample, or the particle number or box changed.
    pub rebuild_start: u64,
    /// Rebuilds because a move still inverted a triangle after every halving.
    pub rebuild_inverted: u64,
    /// Rebuilds because an inserted or deleted ghost image was degenerate (on an edge, not on
    /// the hull, collinear with a hull edge).
    pub rebuild_images: u64,
    /// Rebuilds because the flip count ran over its cap or the final check failed.
    pub rebuild_check: u64,
    /// Rebuilds without a repair attempt: after `f` consecutive failed repairs the next
    /// `2^f - 1` samples (at most `2^MAX_BACKOFF_LOG2 - 1`) are rebuilt at once.
    pub rebuild_backoff: u64,
    /// Samples triangulated from scratch because the sites are degenerate for spade.
    pub degenerate: u64,
    /// Edges flipped because a site crossed them (into the next triangle or out of the hull).
    pub unfolds: u64,
    /// Sites held back and moved alone (their move inverted a triangle no flip undoes).
    pub held: u64,
    /// Moves of held sites split into halves (each halving counted).
    pub bisections: u64,
    /// Edge flips.
    pub flips: u64,
    /// Ghost images inserted and deleted incrementally.
    pub inserted: u64,
    pub deleted: u64,
}

impl KineticStats {
    /// All rebuilds, the first sample included.
    pub fn rebuilds(&self) -> u64 {
        self.rebuild_start
            + self.rebuild_inverted
            + self.rebuild_images
            + self.rebuild_check
            + self.rebuild_backoff
    }
}

/// Why an incremental step gave up.
#[derive(Debug, Clone, Copy)]
enum Failure {
    Inverted,
    Images,
    Check,
}

/// The kept triangulation. See the module header.
#[derive(Debug, Clone, Default)]
pub struct KineticDelaunay {
    ghost_width: f64,
    box_size: [f64; 2],
    periodic: [bool; 2],
    /// Site positions.
    pos: Vec<[f64; 2]>,
    /// Particle of each site (`DEAD` for a free slot).
    particle: Vec<u32>,
    /// Image shift of each site relative to its particle's wrapped position.
    shift: Vec<[i32; 2]>,
    /// One triangle containing each site.
    vtri: Vec<u32>,
    free_sites: Vec<u32>,
    /// Wrapped position of each particle at the last update.
    wrapped: Vec<[f64; 2]>,
    /// Sites of each particle (`INF`-padded).
    sites_of: Vec<[u32; MAX_IMAGES]>,
    /// Triangle vertices, counter-clockwise; `tv[t][0] == DEAD` for a free slot.
    tv: Vec<[u32; 3]>,
    /// `tn[t][k]`: the triangle across the edge opposite `tv[t][k]`.
    tn: Vec<[u32; 3]>,
    free_tris: Vec<u32>,
    /// False while there is no triangulation (degenerate sites): every sample is rebuilt.
    valid: bool,
    stack: Vec<(u32, u8)>,
    /// Consecutive failed repairs, and samples still to rebuild without trying (`2^f - 1`).
    failures: u32,
    skip: u32,
    pub stats: KineticStats,
}

/// Spade's vertex: a site position and its index.
#[derive(Debug, Clone, Copy)]
struct SpadeSite {
    p: Point2<f64>,
    site: u32,
}

impl HasPosition for SpadeSite {
    type Scalar = f64;
    fn position(&self) -> Point2<f64> {
        self.p
    }
}

#[inline]
fn c(p: [f64; 2]) -> Coord<f64> {
    Coord { x: p[0], y: p[1] }
}

impl KineticDelaunay {
    /// An empty triangulation for ghost bands of width `ghost_width`; the first
    /// [`update`](Self::update) builds it.
    pub fn new(ghost_width: f64) -> Self {
        Self {
            ghost_width,
            ..Self::default()
        }
    }

    /// The Delaunay edges of `frame` (as [`super::location_changes::delaunay_edges`] returns
    /// them), repairing the triangulation of the previous call.
    pub fn update(&mut self, frame: &Frame) -> Vec<Edge> {
        self.update_for_counter(frame, &[])
    }

    /// [`update`](Self::update) for the counter: the pairs in `known` (sorted) get no opposite
    /// vertices (the comparison with the previous sample does not use them), which saves their
    /// angles.
    pub fn update_for_counter(&mut self, frame: &Frame, known: &[(u32, u32)]) -> Vec<Edge> {
        assert_eq!(frame.dimension, 2, "Delaunay location changes are 2D");
        let same_system = self.valid
            && self.wrapped.len() == frame.len()
            && self.box_size == [frame.box_size[0], frame.box_size[1]]
            && self.periodic == [frame.periodic[0], frame.periodic[1]];
        if !same_system {
            self.stats.rebuild_start += 1;
            self.rebuild(frame);
        } else if self.skip > 0 {
            // Back off after failed repairs: rebuilding at once is cheaper than failing again.
            self.skip -= 1;
            self.stats.rebuild_backoff += 1;
            self.rebuild(frame);
        } else {
            match self.repair(frame) {
                Ok(()) => {
                    self.stats.incremental += 1;
                    self.failures = 0;
                }
                Err(f) => {
                    self.failures = (self.failures + 1).min(MAX_BACKOFF_LOG2);
                    self.skip = (1u32 << self.failures) - 1;
                    match f {
                        Failure::Inverted => self.stats.rebuild_inverted += 1,
                        Failure::Images => self.stats.rebuild_images += 1,
                        Failure::Check => self.stats.rebuild_check += 1,
                    }
                    self.rebuild(frame);
                }
            }
        }
        if !self.valid {
            self.stats.degenerate += 1;
            return super::location_changes::delaunay_edges(frame, self.ghost_width);
        }
        self.edges(known)
    }

    /// The current edges in the observer's format.
    fn edges(&self, known: &[(u32, u32)]) -> Vec<Edge> {
        let mut out = Vec::with_capacity(3 * self.wrapped.len());
        let site = |s: u32| SiteRef {
            p: self.pos[s as usize],
            id: self.particle[s as usize],
            ghost: self.shift[s as usize] != [0, 0],
        };
        for (t, v) in self.tv.iter().enumerate() {
            if v[0] == DEAD {
                continue;
            }
            for k in 0..3 {
                let u = self.tn[t][k];
                let (a, b) = (v[(k + 1) % 3], v[(k + 2) % 3]);
                if (t as u32) > u || a == INF || b == INF {
                    continue;
                }
                let w = self.tv[u as usize];
                let opposite = (!v.contains(&INF) && !w.contains(&INF))
                    .then(|| (site(v[k]), site(w[self.back_index(u as usize, t as u32)])));
                if let Some(e) = edge_between(site(a), site(b), opposite, known) {
                    out.push(e);
                }
            }
        }
        finish_edges(&mut out);
        out
    }

    // ---------------------------------------------------------------------------------------
    // Rebuild

    /// Rebuilds from scratch: the sites of `frame`, spade's Delaunay triangulation, converted.
    fn rebuild(&mut self, frame: &Frame) {
        let n = frame.len();
        self.box_size = [frame.box_size[0], frame.box_size[1]];
        self.periodic = [frame.periodic[0], frame.periodic[1]];
        self.pos.clear();
        self.particle.clear();
        self.shift.clear();
        self.free_sites.clear();
        self.wrapped.clear();
        self.sites_of.clear();
        self.sites_of.resize(n, [INF; MAX_IMAGES]);
        for i in 0..n {
            let img = images(frame, i, self.ghost_width);
            let (w, imgs) = (img.wrapped, img.as_slice());
            self.wrapped.push(w);
            for (k, (s, p)) in imgs.iter().enumerate() {
                self.sites_of[i][k] = self.pos.len() as u32;
                self.pos.push(*p);
                self.particle.push(i as u32);
                self.shift.push(*s);
            }
        }
        self.vtri.clear();
        self.vtri.resize(self.pos.len(), INF);
        self.tv.clear();
        self.tn.clear();
        self.free_tris.clear();
        self.valid = false;
        let sites: Vec<SpadeSite> = self
            .pos
            .iter()
            .enumerate()
            .map(|(k, p)| SpadeSite {
                p: Point2::new(p[0], p[1]),
                site: k as u32,
            })
            .collect();
        let Ok(tri) = DelaunayTriangulation::<SpadeSite>::bulk_load_stable(sites) else {
            return;
        };
        if tri.num_vertices() != self.pos.len() || tri.num_inner_faces() == 0 {
            return;
        }
        // Finite triangles: spade's inner faces (indices 1.., the outer face is 0), in order.
        // Face edges e0 = v0 -> v1, e1 = v1 -> v2, e2 = v2 -> v0: the edge opposite v_k is
        // e_{k+1}. Across a hull edge a -> b lies the infinite triangle (b, a, INF).
        let mut hull_from = vec![INF; self.pos.len()];
        let mut hull_to = vec![INF; self.pos.len()];
        for f in tri.inner_faces() {
            let t = self.tv.len();
            debug_assert_eq!(f.fix().index(), t + 1);
            let v = f.vertices().map(|h| h.data().site);
            let e = f.adjacent_edges();
            let mut n = [INF; 3];
            for k in 0..3 {
                n[k] = match e[(k + 1) % 3].rev().face().as_inner() {
                    Some(g) => (g.fix().index() - 1) as u32,
                    None => INF - 2, // a hull edge, linked below
                };
            }
            self.tv.push(v);
            self.tn.push(n);
        }
        let finite = self.tv.len();
        for t in 0..finite {
            for k in 0..3 {
                if self.tn[t][k] != INF - 2 {
                    continue;
                }
                let v = self.tv[t];
                let (a, b) = (v[(k + 1) % 3], v[(k + 2) % 3]);
                let x = self.tv.len() as u32;
                self.tv.push([b, a, INF]);
                self.tn.push([INF, INF, t as u32]);
                self.tn[t][k] = x;
                hull_from[a as usize] = x;
                hull_to[b as usize] = x;
            }
        }
        // (b, a, INF): opposite b the edge (a, INF), shared with the triangle of the hull edge
        // ending at a; opposite a the edge (INF, b), shared with that of the edge starting at b.
        for x in finite..self.tv.len() {
            let [b, a, _] = self.tv[x];
            let (p, q) = (hull_to[a as usize], hull_from[b as usize]);
            if p == INF || q == INF {
                return; // not a closed hull: leave invalid
            }
            self.tn[x][0] = p;
            self.tn[x][1] = q;
        }
        for t in 0..self.tv.len() {
            for &v in &self.tv[t] {
                if v != INF {
                    self.vtri[v as usize] = t as u32;
                }
            }
        }
        self.valid = self.vtri.iter().all(|&t| t != INF);
    }

    // ---------------------------------------------------------------------------------------
    // Incremental repair

    /// Moves, deletes and inserts sites to match `frame`; Delaunay again on success.
    fn repair(&mut self, frame: &Frame) -> Result<(), Failure> {
        let n = frame.len();
        // Plan: new position of every kept site; sites leaving; images entering.
        let mut from: Vec<(u32, [f64; 2])> = Vec::with_capacity(self.pos.len());
        let mut to: Vec<[f64; 2]> = Vec::with_capacity(self.pos.len());
        let mut leaving: Vec<u32> = Vec::new();
        let mut entering: Vec<(u32, [i32; 2], [f64; 2])> = Vec::new();
        for i in 0..n {
            let img = images(frame, i, self.ghost_width);
            let (w, imgs) = (img.wrapped, img.as_slice());
            let mut delta = [0i32; 2];
            for k in 0..2 {
                if self.periodic[k] {
                    delta[k] = ((w[k] - self.wrapped[i][k]) / self.box_size[k]).round() as i32;
                }
            }
            self.wrapped[i] = w;
            let mut kept = [false; MAX_IMAGES];
            let old = self.sites_of[i];
            let mut new_sites = [INF; MAX_IMAGES];
            let mut m = 0;
            for &s in old.iter().take_while(|&&s| s != INF) {
                let sh = self.shift[s as usize];
                let sh = [sh[0] - delta[0], sh[1] - delta[1]];
                self.shift[s as usize] = sh;
                match imgs.iter().position(|(s2, _)| *s2 == sh) {
                    Some(k) => {
                        kept[k] = true;
                        from.push((s, self.pos[s as usize]));
                        to.push(imgs[k].1);
                        new_sites[m] = s;
                        m += 1;
                    }
                    None => {
                        // Continue the site's motion to just outside the band.
                        let p = [
                            w[0] + sh[0] as f64 * self.box_size[0],
                            w[1] + sh[1] as f64 * self.box_size[1],
                        ];
                        from.push((s, self.pos[s as usize]));
                        to.push(p);
                        leaving.push(s);
                    }
                }
            }
            for (k, (sh, p)) in imgs.iter().enumerate() {
                if !kept[k] {
                    entering.push((i as u32, *sh, *p));
                }
            }
            self.sites_of[i] = new_sites;
        }
        // 1-2: move and flip.
        let start: Vec<[f64; 2]> = from.iter().map(|f| f.1).collect();
        let sites: Vec<u32> = from.iter().map(|f| f.0).collect();
        self.advance(&sites, &start, &to)?;
        // 3: deletions, outermost first (each is a hull vertex when deleted).
        let mut left = leaving;
        while !left.is_empty() {
            let Some(k) = left.iter().position(|&s| self.on_hull(s)) else {
                return Err(Failure::Images);
            };
            let s = left.swap_remove(k);
            self.delete(s)?;
        }
        // 4: insertions.
        for (i, sh, p) in entering {
            let s = self.insert(p)?;
            self.particle[s as usize] = i;
            self.shift[s as usize] = sh;
            let slot = self.sites_of[i as usize]
                .iter()
                .position(|&x| x == INF)
                .expect("at most nine images");
            self.sites_of[i as usize][slot] = s;
        }
        // 5: final check.
        if self.hull_is_convex_once() {
            Ok(())
        } else {
            Err(Failure::Check)
        }
    }

    /// Moves `sites` from `from` to `to` and flips to Delaunay. Sites of triangles that invert
    /// in a way no single flip undoes are held back; the others move at once (repaired by
    /// unfolding flips and Lawson's algorithm over every edge); then the held sites move alone,
    /// their move halved where it still inverts a triangle ([`Self::advance_local`]).
    fn advance(
        &mut self,
        sites: &[u32],
        from: &[[f64; 2]],
        to: &[[f64; 2]],
    ) -> Result<(), Failure> {
        for (k, &s) in sites.iter().enumerate() {
            self.pos[s as usize] = to[k];
        }
        let mut slot = vec![u32::MAX; self.pos.len()];
        for (k, &s) in sites.iter().enumerate() {
            slot[s as usize] = k as u32;
        }
        let mut held: Vec<usize> = Vec::new();
        let mut is_held = vec![false; sites.len()];
        let all: Vec<usize> = (0..self.tv.len()).collect();
        loop {
            let blocked: Vec<usize> = self
                .inverted_in(&all)
                .into_iter()
                .filter(|&(_, crossed)| crossed.is_none())
                .map(|(t, _)| t)
                .collect();
            if blocked.is_empty() {
                break;
            }
            let before = held.len();
            for t in blocked {
                for v in self.tv[t] {
                    let k = slot[v as usize];
                    if k != u32::MAX && !is_held[k as usize] {
                        is_held[k as usize] = true;
                        held.push(k as usize);
                        self.pos[v as usize] = from[k as usize];
                    }
                }
            }
            if held.len() == before || held.len() as f64 > MAX_HELD_FRACTION * sites.len() as f64 {
                return Err(Failure::Inverted);
            }
        }
        self.stack.clear();
        self.unfold(&all)?;
        self.stack.clear();
        for t in 0..self.tv.len() {
            if self.tv[t][0] == DEAD {
                continue;
            }
            for k in 0..3 {
                if (t as u32) < self.tn[t][k] {
                    self.stack.push((t as u32, k as u8));
                }
            }
        }
        self.lawson()?;
        if held.is_empty() {
            return Ok(());
        }
        // One held site at a time, with a budget of halvings for the whole sample.
        self.stats.held += held.len() as u64;
        let mut budget = MAX_HALVINGS;
        for k in held {
            self.advance_local(&[sites[k]], &[from[k]], &[to[k]], 0, &mut budget)?;
        }
        Ok(())
    }

    /// The live triangles around `sites`.
    fn stars_of(&self, sites: &[u32]) -> Vec<usize> {
        let mut tris: Vec<usize> = sites
            .iter()
            .flat_map(|&s| self.star(s).into_iter().map(|(t, _)| t))
            .collect();
        tris.sort_unstable();
        tris.dedup();
        tris
    }

    /// Flips the edges that sites crossed (see [`Self::inverted_in`]) among `tris` and the
    /// triangles the flips make, one at a time; fails where an inverted triangle has no such
    /// edge.
    fn unfold(&mut self, tris: &[usize]) -> Result<bool, Failure> {
        let mut tris = tris.to_vec();
        let mut unfolded = 0;
        loop {
            let inverted = self.inverted_in(&tris);
            let Some(&(t, crossed)) = inverted.first() else {
                return Ok(true);
            };
            if inverted.iter().any(|&(_, h)| h.is_none()) {
                return if unfolded > 0 {
                    Err(Failure::Check)
                } else {
                    Ok(false)
                };
            }
            let k = crossed.expect("unfoldable");
            let u = self.tn[t][k] as usize;
            let j = self.back_index(u, t as u32);
            self.flip(t, k, u, j);
            tris.push(u);
            self.stats.unfolds += 1;
            unfolded += 1;
            if unfolded > self.tv.len() {
                return Err(Failure::Check);
            }
        }
    }

    /// Moves a few `sites` alone from `from` to `to`: unfolding flips and Lawson's algorithm
    /// around them only; the move is halved (up to [`MAX_BISECTIONS`] levels) where it inverts
    /// a triangle that no flip undoes.
    fn advance_local(
        &mut self,
        sites: &[u32],
        from: &[[f64; 2]],
        to: &[[f64; 2]],
        depth: u32,
        budget: &mut u32,
    ) -> Result<(), Failure> {
        for (k, &s) in sites.iter().enumerate() {
            self.pos[s as usize] = to[k];
        }
        self.stack.clear();
        let star = self.stars_of(sites);
        if self.unfold(&star)? {
            for t in self.stars_of(sites) {
                for k in 0..3 {
                    self.stack.push((t as u32, k as u8));
                }
            }
            return self.lawson();
        }
        for (k, &s) in sites.iter().enumerate() {
            self.pos[s as usize] = from[k];
        }
        if depth >= MAX_BISECTIONS || *budget == 0 {
            return Err(Failure::Inverted);
        }
        *budget -= 1;
        self.stats.bisections += 1;
        let mid: Vec<[f64; 2]> = from
            .iter()
            .zip(to)
            .map(|(a, b)| [a[0] + 0.5 * (b[0] - a[0]), a[1] + 0.5 * (b[1] - a[1])])
            .collect();
        self.advance_local(sites, from, &mid, depth + 1, budget)?;
        self.advance_local(sites, &mid, to, depth + 1, budget)
    }

    /// The finite triangles that are not strictly counter-clockwise; with each, the index `k`
    /// of a vertex that crossed its opposite edge into the neighbouring triangle: it lies
    /// strictly inside that neighbour, or, where the neighbour is the triangle's only infinite
    /// one, strictly beyond the hull edge. Flipping that edge undoes the crossing (the two
    /// positive triangles it makes cover what the inverted one and its neighbour covered,
    /// counted with sign).
    fn inverted_in(&self, tris: &[usize]) -> Vec<(usize, Option<usize>)> {
        let mut out = Vec::new();
        for &t in tris {
            let v = self.tv[t];
            if v[0] == DEAD || v.contains(&INF) {
                continue;
            }
            let p = v.map(|x| c(self.pos[x as usize]));
            if orient2d(p[0], p[1], p[2]) > 0.0 {
                continue;
            }
            let infinite = (0..3)
                .filter(|&k| self.tv[self.tn[t][k] as usize].contains(&INF))
                .count();
            let crossed = (0..3).find(|&k| {
                let u = self.tn[t][k] as usize;
                let w = self.tv[u];
                if w.contains(&INF) {
                    return infinite == 1;
                }
                let q = w.map(|x| c(self.pos[x as usize]));
                orient2d(q[0], q[1], p[k]) > 0.0
                    && orient2d(q[1], q[2], p[k]) > 0.0
                    && orient2d(q[2], q[0], p[k]) > 0.0
            });
            out.push((t, crossed));
        }
        out
    }

    /// Whether site `d` conflicts with triangle `t` (module header).
    fn conflicts(&self, t: usize, d: u32) -> bool {
        if d == INF {
            return false;
        }
        let v = self.tv[t];
        let pd = c(self.pos[d as usize]);
        match v.iter().position(|&x| x == INF) {
            None => {
                incircle(
                    c(self.pos[v[0] as usize]),
                    c(self.pos[v[1] as usize]),
                    c(self.pos[v[2] as usize]),
                    pd,
                ) > 0.0
            }
            Some(k) => {
                let (x, y) = (v[(k + 1) % 3], v[(k + 2) % 3]);
                orient2d(c(self.pos[x as usize]), c(self.pos[y as usize]), pd) > 0.0
            }
        }
    }

    /// Lawson's algorithm from the edges on the stack.
    fn lawson(&mut self) -> Result<(), Failure> {
        let cap = 64 * self.tv.len() as u64 + 1024;
        let mut flips = 0u64;
        while let Some((t, k)) = self.stack.pop() {
            let (t, k) = (t as usize, k as usize);
            if self.tv[t][0] == DEAD {
                continue;
            }
            let u = self.tn[t][k] as usize;
            let j = self.back_index(u, t as u32);
            let d = self.tv[u][j];
            if !self.conflicts(t, d) {
                continue;
            }
            flips += 1;
            if flips > cap {
                return Err(Failure::Check);
            }
            self.flip(t, k, u, j);
        }
        self.stats.flips += flips;
        Ok(())
    }

    /// The index in `u` of the edge shared with `t`.
    #[inline]
    fn back_index(&self, u: usize, t: u32) -> usize {
        let n = self.tn[u];
        if n[0] == t {
            0
        } else if n[1] == t {
            1
        } else {
            debug_assert_eq!(n[2], t);
            2
        }
    }

    /// Flips the edge opposite `tv[t][k]` (shared with `u`, where it is opposite `tv[u][j]`),
    /// and pushes the four outer edges of the quadrilateral.
    fn flip(&mut self, t: usize, k: usize, u: usize, j: usize) {
        // t = (a, b, cc), u = (d, cc, b); new t = (a, b, d), new u = (a, d, cc).
        let a = self.tv[t][k];
        let b = self.tv[t][(k + 1) % 3];
        let cc = self.tv[t][(k + 2) % 3];
        let d = self.tv[u][j];
        let n_ca = self.tn[t][(k + 1) % 3];
        let n_ab = self.tn[t][(k + 2) % 3];
        let n_bd = self.tn[u][(j + 1) % 3];
        let n_dc = self.tn[u][(j + 2) % 3];
        self.tv[t] = [a, b, d];
        self.tn[t] = [n_bd, u as u32, n_ab];
        self.tv[u] = [a, d, cc];
        self.tn[u] = [n_dc, n_ca, t as u32];
        self.relink(n_bd, u as u32, t as u32);
        self.relink(n_ca, t as u32, u as u32);
        for (v, tri) in [(a, t), (b, t), (d, t), (cc, u)] {
            if v != INF {
                self.vtri[v as usize] = tri as u32;
            }
        }
        self.stack.push((t as u32, 0)); // b-d
        self.stack.push((t as u32, 2)); // a-b
        self.stack.push((u as u32, 0)); // d-cc
        self.stack.push((u as u32, 1)); // cc-a
    }

    /// In triangle `x`, the neighbour `old` becomes `new`.
    #[inline]
    fn relink(&mut self, x: u32, old: u32, new: u32) {
        let n = &mut self.tn[x as usize];
        for e in n.iter_mut() {
            if *e == old {
                *e = new;
                return;
            }
        }
        unreachable!("triangle {x} is not a neighbour of {old}");
    }

    /// The triangles around site `v`, counter-clockwise, each with `v`'s index in it.
    fn star(&self, v: u32) -> Vec<(usize, usize)> {
        let start = self.vtri[v as usize] as usize;
        let mut out = Vec::with_capacity(8);
        let mut t = start;
        loop {
            let k = self.tv[t]
                .iter()
                .position(|&x| x == v)
                .expect("v in its star");
            out.push((t, k));
            t = self.tn[t][(k + 1) % 3] as usize;
            if t == start || out.len() > self.tv.len() {
                return out;
            }
        }
    }

    /// Whether site `v` is a hull vertex (a neighbour of `INF`).
    fn on_hull(&self, v: u32) -> bool {
        self.star(v).iter().any(|&(t, _)| self.tv[t].contains(&INF))
    }

    fn alloc_tri(&mut self, v: [u32; 3], n: [u32; 3]) -> usize {
        match self.free_tris.pop() {
            Some(t) => {
                self.tv[t as usize] = v;
                self.tn[t as usize] = n;
                t as usize
            }
            None => {
                self.tv.push(v);
                self.tn.push(n);
                self.tv.len() - 1
            }
        }
    }

    fn free_tri(&mut self, t: usize) {
        self.tv[t] = [DEAD; 3];
        self.tn[t] = [INF; 3];
        self.free_tris.push(t as u32);
    }

    /// Deletes the hull vertex `v`: merges it into `INF` (its finite triangles become infinite,
    /// its two infinite triangles disappear), then flips until the hull is convex and every edge
    /// Delaunay again.
    fn delete(&mut self, v: u32) -> Result<(), Failure> {
        let star = self.star(v);
        let m = star.len();
        if m < 3 {
            return Err(Failure::Images);
        }
        // Rotate so that star[0] = (v, INF, L1) and star[m-1] = (v, L_{m-1}, INF).
        let Some(r) = star
            .iter()
            .position(|&(t, k)| self.tv[t][(k + 1) % 3] == INF)
        else {
            return Err(Failure::Images);
        };
        let star: Vec<(usize, usize)> = (0..m).map(|q| star[(r + q) % m]).collect();
        // A vertex on the hull twice (a pinched hull) cannot be merged into INF.
        if star[1..m - 1]
            .iter()
            .any(|&(t, _)| self.tv[t].contains(&INF))
        {
            return Err(Failure::Images);
        }
        let (t0, k0) = star[0];
        let (tl, kl) = star[m - 1];
        if self.tv[tl][(kl + 2) % 3] != INF {
            return Err(Failure::Images);
        }
        let x0 = self.tn[t0][k0];
        let xl = self.tn[tl][kl];
        let l1 = self.tv[t0][(k0 + 2) % 3];
        let llast = self.tv[tl][(kl + 1) % 3];
        // A hull neighbour whose only finite triangle is v's would be left without one (its
        // other hull neighbour is the next vertex of v's link): not merged, rebuilt.
        let l2 = self.tv[star[1].0][(star[1].1 + 2) % 3];
        let lm2 = self.tv[star[m - 2].0][(star[m - 2].1 + 1) % 3];
        let other = |x: u32, l: u32| {
            self.tv[x as usize]
                .into_iter()
                .find(|&y| y != INF && y != l)
        };
        if other(x0, l1) == Some(l2) || other(xl, llast) == Some(lm2) {
            return Err(Failure::Images);
        }
        for &(t, k) in &star[1..m - 1] {
            self.tv[t][k] = INF;
        }
        // star[1] = (INF, L1, L2): its edge (INF, L1) is opposite L2.
        let (t1, k1) = star[1];
        self.tn[t1][(k1 + 2) % 3] = x0;
        self.relink(x0, t0 as u32, t1 as u32);
        // star[m-2] = (INF, L_{m-2}, L_{m-1}): its edge (L_{m-1}, INF) is opposite L_{m-2}.
        let (tp, kp) = star[m - 2];
        self.tn[tp][(kp + 1) % 3] = xl;
        self.relink(xl, tl as u32, tp as u32);
        self.free_tri(t0);
        self.free_tri(tl);
        self.vtri[l1 as usize] = t1 as u32;
        self.vtri[llast as usize] = tp as u32;
        self.particle[v as usize] = DEAD;
        self.vtri[v as usize] = INF;
        self.free_sites.push(v);
        self.stack.clear();
        for &(t, _) in &star[1..m - 1] {
            for k in 0..3 {
                self.stack.push((t as u32, k as u8));
            }
        }
        self.stats.deleted += 1;
        self.lawson()
    }

    /// Inserts a site at `p` (its particle and shift are set by the caller); returns its index.
    fn insert(&mut self, p: [f64; 2]) -> Result<u32, Failure> {
        let s = match self.free_sites.pop() {
            Some(s) => {
                self.pos[s as usize] = p;
                s
            }
            None => {
                self.pos.push(p);
                self.particle.push(DEAD);
                self.shift.push([0, 0]);
                self.vtri.push(INF);
                (self.pos.len() - 1) as u32
            }
        };
        let pc = c(p);
        // Locate: a finite triangle containing p strictly, else an infinite one that p lies
        // strictly beyond.
        let mut found = None;
        for t in 0..self.tv.len() {
            let v = self.tv[t];
            if v[0] == DEAD || v.contains(&INF) {
                continue;
            }
            let o = [
                orient2d(c(self.pos[v[1] as usize]), c(self.pos[v[2] as usize]), pc),
                orient2d(c(self.pos[v[2] as usize]), c(self.pos[v[0] as usize]), pc),
                orient2d(c(self.pos[v[0] as usize]), c(self.pos[v[1] as usize]), pc),
            ];
            if o.iter().all(|&x| x > 0.0) {
                found = Some((t, 0));
                break;
            }
            if o.iter().all(|&x| x >= 0.0) {
                return Err(Failure::Images); // on an edge or a vertex
            }
        }
        if found.is_none() {
            for t in 0..self.tv.len() {
                let v = self.tv[t];
                if v[0] == DEAD {
                    continue;
                }
                if let Some(k) = v.iter().position(|&x| x == INF) {
                    let (x, y) = (v[(k + 1) % 3], v[(k + 2) % 3]);
                    let o = orient2d(c(self.pos[x as usize]), c(self.pos[y as usize]), pc);
                    if o > 0.0 {
                        found = Some((t, (k + 1) % 3));
                        break;
                    }
                }
            }
        }
        let Some((t, k)) = found else {
            return Err(Failure::Images);
        };
        // t = (a, b, cc) rotated so that a = tv[t][k]; split into (a,b,p), (b,cc,p), (cc,a,p).
        let a = self.tv[t][k];
        let b = self.tv[t][(k + 1) % 3];
        let cc = self.tv[t][(k + 2) % 3];
        let n_a = self.tn[t][k];
        let n_b = self.tn[t][(k + 1) % 3];
        let n_c = self.tn[t][(k + 2) % 3];
        let t1 = self.alloc_tri([b, cc, s], [INF, t as u32, n_a]);
        let t2 = self.alloc_tri([cc, a, s], [t as u32, t1 as u32, n_b]);
        self.tn[t1][0] = t2 as u32;
        self.tv[t] = [a, b, s];
        self.tn[t] = [t1 as u32, t2 as u32, n_c];
        self.relink(n_a, t as u32, t1 as u32);
        self.relink(n_b, t as u32, t2 as u32);
        self.vtri[s as usize] = t as u32;
        if cc != INF {
            self.vtri[cc as usize] = t1 as u32;
        }
        for v in [a, b] {
            if v != INF {
                self.vtri[v as usize] = t as u32;
            }
        }
        self.stack.clear();
        self.stack.push((t as u32, 2));
        self.stack.push((t1 as u32, 2));
        self.stack.push((t2 as u32, 2));
        self.stats.inserted += 1;
        self.lawson()?;
        Ok(s)
    }

    /// The final check: the hull, walked around `INF`, has no reflex vertex and turns once.
    fn hull_is_convex_once(&self) -> bool {
        let Some(t0) = self
            .tv
            .iter()
            .position(|v| v[0] != DEAD && v.contains(&INF))
        else {
            return false;
        };
        // Around INF: triangles (INF, x_j, x_{j+1}); the hull sequence x_j.
        let mut hull = Vec::new();
        let mut t = t0;
        loop {
            let k = self.tv[t].iter().position(|&x| x == INF).expect("infinite");
            hull.push(self.tv[t][(k + 1) % 3]);
            t = self.tn[t][(k + 1) % 3] as usize;
            if t == t0 || hull.len() > self.pos.len() {
                break;
            }
        }
        let h = hull.len();
        if h < 3 {
            return false;
        }
        let mut turning = 0.0;
        for q in 0..h {
            let (p0, p1, p2) = (
                self.pos[hull[q] as usize],
                self.pos[hull[(q + 1) % h] as usize],
                self.pos[hull[(q + 2) % h] as usize],
            );
            // The walk around INF runs clockwise along the hull: no left turn allowed.
            if orient2d(c(p0), c(p1), c(p2)) > 0.0 {
                return false;
            }
            let (u, w) = (
                [p1[0] - p0[0], p1[1] - p0[1]],
                [p2[0] - p1[0], p2[1] - p1[1]],
            );
            turning += (u[0] * w[1] - u[1] * w[0]).atan2(u[0] * w[0] + u[1] * w[1]);
        }
        (turning + std::f64::consts::TAU).abs() < 1e-6
    }

    /// Whether the neighbour links are consistent: every neighbour links back across the same
    /// two vertices.
    pub fn links_consistent(&self) -> Result<(), String> {
        for (t, v) in self.tv.iter().enumerate() {
            if v[0] == DEAD {
                continue;
            }
            for k in 0..3 {
                let u = self.tn[t][k] as usize;
                if u >= self.tv.len() || self.tv[u][0] == DEAD {
                    return Err(format!("triangle {t} {v:?}: neighbour {k} dead"));
                }
                let j = self.tn[u].iter().position(|&x| x as usize == t);
                let Some(j) = j else {
                    return Err(format!(
                        "triangle {t} {v:?}: {u} {:?} does not link back",
                        self.tv[u]
                    ));
                };
                let (a, b) = (v[(k + 1) % 3], v[(k + 2) % 3]);
                let w = self.tv[u];
                if (w[(j + 1) % 3], w[(j + 2) % 3]) != (b, a) {
                    return Err(format!("triangle {t} {v:?} and {u} {w:?} share no edge"));
                }
            }
        }
        Ok(())
    }

    /// Number of live triangles (finite and infinite), for tests.
    pub fn triangle_count(&self) -> usize {
        self.tv.iter().filter(|v| v[0] != DEAD).count()
    }
}
