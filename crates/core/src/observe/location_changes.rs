//! Frequency of location changes `f_lc` (docs/model.md 7): how often a grain moves into a
//! neighbour's place.
//!
//! **2D (Delaunay).** At every sample the particle centres are triangulated (spade's robust
//! Delaunay triangulation; on a periodic axis ghost images within `4 lc_max_edge` of each side
//! are added, and an edge to a ghost counts as an edge to its original). The triangulation
//! stays Delaunay as long as no centre has entered a neighbour's circumcircle; every in-circle
//! violation is repaired by one edge flip, which removes one edge and creates one new edge.
//! The number of location changes between two samples is therefore the number of Delaunay
//! edges present now that were absent at the previous sample (the flips needed to turn the old
//! triangulation into the new one when every edge flips at most once). Only new edges of length
//! at most `lc_max_edge` count: longer ones span the empty space above a bed or in a gas and
//! change whenever a surface grain rattles, without any neighbour exchange. A flip counts only
//! once it is decisive (hysteresis `lc_flip_margin`, see [`compare`]): four nearly co-circular
//! grains would otherwise count every rattle.
//!
//! **Rebuilt at every sample.** Each sample is triangulated from scratch ([`delaunay_edges`]),
//! its edges listed and compared with the pairs tracked from the previous sample
//! ([`compare`]). Where the same pair is an edge through two periodic images, the shortest copy
//! is kept ([`finish_edges`]), whatever order the triangulation lists its edges in. The observer
//! is off unless asked for (`observe.location_changes`, or `classify.mobility =
//! "location_changes"`, which reads `f_lc`; docs/observables.md).
//!
//! **3D (neighbour shells).** Grains `i, j` become neighbours when their centres come closer
//! than `lc_enter_factor (r_i + r_j)` and stay neighbours until they separate beyond
//! `lc_leave_factor (r_i + r_j)` (the hysteresis keeps a rattling pair at the shell's edge from
//! counting again and again). A location change is a pair that has become neighbours since the
//! previous sample.
//!
//! **Normalisation.** `f_lc` = location changes per particle per period (driving period, or
//! time unit without a drive): `count / (N * window / period)`. Per lateral bin, changes are
//! counted at the new edge's midpoint and divided by the bin's mean particle number.
//!
//! **Sampling.** Changes that happen and are undone between two samples (a pair that swaps and
//! swaps back) are not seen, so a coarse sampling undercounts; the count converges from below
//! as the sampling interval shrinks below the time a grain needs to cross a fraction of its
//! diameter (crates/core/tests/observe_location_changes.rs shows it on a slow system).

use super::bins::LateralBins;
use crate::sim::Frame;
use spade::{DelaunayTriangulation, HasPosition, Point2, Triangulation};
use std::collections::HashMap;

/// One neighbour relation of the current sample: scene indices `i < j`, the current length of
/// the edge (nearest image) and the lateral coordinate of its midpoint.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Edge {
    pub i: u32,
    pub j: u32,
    pub length: f64,
    pub(crate) mid_x: f64,
    /// Midpoint `y` (3D; 0 in 2D).
    pub(crate) mid_y: f64,
    /// 2D: the vertices `c < d` opposite the edge in its two triangles and the sum of the angles
    /// at `c` and `d`; `None` on the hull (and always for neighbour shells). The edge is Delaunay
    /// while the sum is at most `pi`; `pi - sum` is by how much.
    pub(crate) opposite: Option<(u32, u32, f64)>,
}

#[derive(Debug, Clone, Copy)]
struct Site {
    p: Point2<f64>,
    id: u32,
    ghost: bool,
}

impl HasPosition for Site {
    type Scalar = f64;
    fn position(&self) -> Point2<f64> {
        self.p
    }
}

/// Pushes the sites of particle `i`: the wrapped position, plus the images shifted by one box
/// length along a periodic axis that lie within `ghost_width` (at most the box length) of the
/// box.
fn push_images(frame: &Frame, i: usize, ghost_width: f64, sites: &mut Vec<Site>) {
    let size = [frame.box_size[0], frame.box_size[1]];
    let x = [frame.wrap(0, frame.x(i)[0]), frame.wrap(1, frame.x(i)[1])];
    for sx in -1i32..=1 {
        for sz in -1i32..=1 {
            let shift = [sx, sz];
            let mut p = x;
            let mut inside = true;
            for k in 0..2 {
                if shift[k] != 0 {
                    if !frame.periodic[k] {
                        inside = false;
                        break;
                    }
                    p[k] += shift[k] as f64 * size[k];
                    let g = ghost_width.min(size[k]);
                    if p[k] < -g || p[k] >= size[k] + g {
                        inside = false;
                    }
                }
            }
            if inside {
                sites.push(Site {
                    p: Point2::new(p[0], p[1]),
                    id: i as u32,
                    ghost: shift != [0, 0],
                });
            }
        }
    }
}

/// Angle at `c` of the triangle `(a, b, c)` (symmetric in `a` and `b` to the last bit).
fn angle(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    let (u, v) = ((a[0] - c[0], a[1] - c[1]), (b[0] - c[0], b[1] - c[1]));
    (u.0 * v.1 - u.1 * v.0).abs().atan2(u.0 * v.0 + u.1 * v.1)
}

/// The observer's record of the Delaunay edge `ab` (`opposite`: the vertices across it when both
/// its triangles are finite), or `None` for an edge between two ghosts or between two images of
/// one particle. Symmetric in `a` and `b`, and in the two opposite vertices, to the last bit.
fn edge_between(a: Site, b: Site, opposite: Option<(Site, Site)>) -> Option<Edge> {
    if (a.ghost && b.ghost) || a.id == b.id {
        return None;
    }
    let xy = |s: &Site| [s.p.x, s.p.y];
    let (pa, pb) = (xy(&a), xy(&b));
    let opposite = opposite.map(|(c, d)| {
        let sum = angle(pa, pb, xy(&c)) + angle(pa, pb, xy(&d));
        (c.id.min(d.id), c.id.max(d.id), sum)
    });
    let (dx, dz) = (pb[0] - pa[0], pb[1] - pa[1]);
    Some(Edge {
        i: a.id.min(b.id),
        j: a.id.max(b.id),
        length: (dx * dx + dz * dz).sqrt(),
        mid_x: 0.5 * (pa[0] + pb[0]),
        mid_y: 0.0,
        opposite,
    })
}

/// Whether the copy `p` of a pair's edge is kept before the copy `q` ([`finish_edges`]):
/// shorter, then the smaller midpoint, then the smaller opposite vertices and angle sum. A
/// total order on copies: two copies equal under it are equal in every field.
fn better_copy(p: &Edge, q: &Edge) -> bool {
    let key = |e: &Edge| e.opposite.map(|(c, d, s)| (c, d, s.to_bits()));
    p.length
        .total_cmp(&q.length)
        .then(p.mid_x.total_cmp(&q.mid_x))
        .then_with(|| key(p).cmp(&key(q)))
        .is_lt()
}

/// Sorts the edges by pair and keeps one per pair: of the copies of a pair seen through
/// different periodic images, the shortest (then the smallest midpoint, then the opposite
/// vertices), a choice that does not depend on the order the triangulation lists its edges in.
fn finish_edges(edges: &mut Vec<Edge>) {
    edges.sort_unstable_by_key(|e| ((e.i as u64) << 32) | e.j as u64);
    // Runs of one pair (copies through periodic images): keep the first by the full key.
    let mut w = 0;
    for r in 0..edges.len() {
        if w > 0 && (edges[w - 1].i, edges[w - 1].j) == (edges[r].i, edges[r].j) {
            if better_copy(&edges[r], &edges[w - 1]) {
                edges[w - 1] = edges[r];
            }
        } else {
            edges[w] = edges[r];
            w += 1;
        }
    }
    edges.truncate(w);
}

/// How the neighbour relations are found, with their parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Method {
    /// 2D: Delaunay edges; new edges longer than `max_edge` do not count, and a flip counts
    /// only once the old edge violates the in-circle condition by more than `margin` (radians).
    Delaunay { max_edge: f64, margin: f64 },
    /// 3D (or on request): neighbour shells with hysteresis.
    NeighbourShell { enter: f64, leave: f64 },
}

impl Method {
    /// Name used in results.
    pub fn name(&self) -> &'static str {
        match self {
            Method::Delaunay { .. } => "delaunay",
            Method::NeighbourShell { .. } => "neighbour_shell",
        }
    }
}

/// The Delaunay edges of a 2D frame (sorted by `(i, j)`, each pair once), triangulated from
/// scratch by spade.
pub fn delaunay_edges(frame: &Frame, ghost_width: f64) -> Vec<Edge> {
    assert_eq!(frame.dimension, 2, "Delaunay location changes are 2D");
    let mut sites = Vec::with_capacity(frame.len() * 11 / 10 + 8);
    for i in 0..frame.len() {
        push_images(frame, i, ghost_width, &mut sites);
    }
    let tri: DelaunayTriangulation<Site> =
        DelaunayTriangulation::bulk_load_stable(sites).expect("finite particle positions");
    let mut edges: Vec<Edge> = Vec::with_capacity(3 * frame.len());
    for e in tri.undirected_edges() {
        let [a, b] = e.vertices();
        let directed = e.as_directed();
        let opposite = match (directed.opposite_vertex(), directed.rev().opposite_vertex()) {
            (Some(c), Some(d)) => Some((*c.data(), *d.data())),
            _ => None,
        };
        if let Some(edge) = edge_between(*a.data(), *b.data(), opposite) {
            edges.push(edge);
        }
    }
    finish_edges(&mut edges);
    edges
}

/// Neighbour pairs of a frame with hysteresis: pairs closer than `enter (r_i + r_j)`, plus the
/// pairs of `previous` still closer than `leave (r_i + r_j)` (sorted, each pair once).
pub fn neighbour_shell_edges(
    frame: &Frame,
    previous: &[(u32, u32)],
    enter: f64,
    leave: f64,
) -> Vec<Edge> {
    let d = frame.dimension;
    let r_max = frame.radii.iter().copied().fold(0.0, f64::max);
    let cell = (2.0 * r_max * leave).max(1e-9);
    let ncell: Vec<i64> = (0..d)
        .map(|k| ((frame.box_size[k] / cell).floor() as i64).max(1))
        .collect();
    let cell_of = |i: usize| -> Vec<i64> {
        (0..d)
            .map(|k| {
                let x = frame.wrap(k, frame.x(i)[k]);
                ((x / frame.box_size[k] * ncell[k] as f64).floor() as i64).clamp(0, ncell[k] - 1)
            })
            .collect()
    };
    let mut grid: HashMap<Vec<i64>, Vec<usize>> = HashMap::new();
    for i in 0..frame.len() {
        grid.entry(cell_of(i)).or_default().push(i);
    }
    let mut out = Vec::new();
    let offsets: Vec<Vec<i64>> = (0..3i64.pow(d as u32))
        .map(|m| (0..d).map(|k| (m / 3i64.pow(k as u32)) % 3 - 1).collect())
        .collect();
    for i in 0..frame.len() {
        let c = cell_of(i);
        let mut seen: Vec<usize> = Vec::new();
        for off in &offsets {
            let mut nb = c.clone();
            let mut valid = true;
            for k in 0..d {
                nb[k] += off[k];
                if frame.periodic[k] {
                    nb[k] = nb[k].rem_euclid(ncell[k]);
                } else if nb[k] < 0 || nb[k] >= ncell[k] {
                    valid = false;
                }
            }
            if !valid {
                continue;
            }
            if let Some(list) = grid.get(&nb) {
                seen.extend(list.iter().copied().filter(|&j| j > i));
            }
        }
        seen.sort_unstable();
        seen.dedup();
        for j in seen {
            let mut dx = [0.0; 3];
            for k in 0..d {
                dx[k] = frame.min_image(k, frame.x(j)[k] - frame.x(i)[k]);
            }
            let contact = frame.radii[i] + frame.radii[j];
            let r = dx.iter().map(|x| x * x).sum::<f64>().sqrt();
            let key = (i as u32, j as u32);
            if r < enter * contact || (r < leave * contact && previous.binary_search(&key).is_ok())
            {
                out.push(Edge {
                    i: key.0,
                    j: key.1,
                    length: r,
                    mid_x: frame.x(i)[0] + 0.5 * dx[0],
                    mid_y: frame.x(i)[1] + 0.5 * dx[1],
                    opposite: None,
                });
            }
        }
    }
    out.sort_by_key(|p| (p.i, p.j));
    out
}

/// The current neighbour relations of a frame by `method` (`previous`: those of the last
/// sample, used by the hysteresis of the neighbour shells).
pub fn edges(frame: &Frame, method: Method, previous: &[(u32, u32)]) -> Vec<Edge> {
    match method {
        Method::Delaunay { max_edge, .. } => delaunay_edges(frame, 4.0 * max_edge),
        Method::NeighbourShell { enter, leave } => {
            neighbour_shell_edges(frame, previous, enter, leave)
        }
    }
}

/// Compares the neighbour relations of the current sample with the tracked ones of the previous
/// sample. Returns the location changes (new edges that count) and the relations to track from
/// now on (sorted pairs).
///
/// 2D hysteresis: a new Delaunay edge `ab` that replaced a tracked edge `cd` in one flip (`c, d`
/// opposite `ab`) counts only when the flip is decisive, `pi - (angle_c + angle_d) > margin`:
/// the old edge's in-circle violation, measured by the angles of its quadrilateral, exceeds
/// `margin`. Until then `cd` stays tracked in place of `ab`, so a near-square quadrilateral
/// (four almost co-circular grains, common in a lattice-like solid) whose diagonal flips back and
/// forth with every rattle counts nothing. Any other new edge counts at once.
pub fn compare(
    previous: &[(u32, u32)],
    current: &[Edge],
    method: Method,
) -> (Vec<Edge>, Vec<(u32, u32)>) {
    let known = |p: (u32, u32)| previous.binary_search(&p).is_ok();
    let mut fresh = Vec::new();
    let mut tracked = Vec::with_capacity(current.len());
    for e in current {
        let pair = (e.i, e.j);
        if known(pair) {
            tracked.push(pair);
            continue;
        }
        match method {
            Method::Delaunay { max_edge, margin } => {
                if let Some((c, d, sum)) = e.opposite {
                    let old = (c.min(d), c.max(d));
                    if known(old) && std::f64::consts::PI - sum <= margin {
                        tracked.push(old);
                        continue;
                    }
                }
                tracked.push(pair);
                if e.length <= max_edge {
                    fresh.push(*e);
                }
            }
            Method::NeighbourShell { .. } => {
                tracked.push(pair);
                fresh.push(*e);
            }
        }
    }
    tracked.sort_unstable();
    tracked.dedup();
    (fresh, tracked)
}

/// Counts location changes sample by sample.
#[derive(Debug, Clone)]
pub struct LocationChangeCounter {
    method: Method,
    bins: LateralBins,
    period: f64,
    /// The previous sample: its time and whether it lay in the window.
    previous: Option<(f64, bool)>,
    /// The relations tracked since the previous sample (sorted).
    tracked: Vec<(u32, u32)>,
    /// `(t, location changes per particle per period)` over each sample interval ending at `t`.
    pub series: Vec<(f64, f64)>,
    /// Changes counted in intervals inside the window.
    pub window_count: u64,
    /// Summed length of those intervals.
    pub(crate) window_time: f64,
    /// Changes per bin inside the window.
    pub(crate) bin_count: Vec<u64>,
    particles: usize,
}

impl LocationChangeCounter {
    /// The counter; it triangulates (2D) or searches the neighbour shells (3D) at every sample.
    pub fn new(method: Method, bins: LateralBins, period: f64) -> Self {
        let n = bins.n;
        Self {
            method,
            bins,
            period,
            previous: None,
            tracked: Vec::new(),
            series: Vec::new(),
            window_count: 0,
            window_time: 0.0,
            bin_count: vec![0; n],
            particles: 0,
        }
    }

    /// The method in use.
    pub fn method(&self) -> Method {
        self.method
    }

    /// `f_lc` over the window: changes per particle per period.
    pub fn per_particle_per_period(&self) -> f64 {
        self.window_count as f64 / (self.particles as f64 * self.window_time / self.period)
    }

    /// `f_lc` over the window per unit time: changes per particle per time unit.
    pub fn per_particle_per_time(&self) -> f64 {
        self.window_count as f64 / (self.particles as f64 * self.window_time)
    }

    /// `f_lc` per bin per unit time, given the mean particle number of every bin (`0` for
    /// empty bins).
    pub(crate) fn per_bin(&self, particles: &[f64]) -> Vec<f64> {
        self.bin_count
            .iter()
            .zip(particles)
            .map(|(&c, &n)| {
                if n > 0.0 {
                    c as f64 / (n * self.window_time)
                } else {
                    0.0
                }
            })
            .collect()
    }

    /// Books one sample; `in_window`: whether its time lies in the stationary window.
    pub fn observe(&mut self, frame: &Frame, in_window: bool) {
        self.particles = frame.len();
        let first = self.previous.is_none();
        let current = edges(frame, self.method, &self.tracked);
        let fresh = if first {
            self.tracked = current.iter().map(|e| (e.i, e.j)).collect();
            Vec::new()
        } else {
            let (fresh, keep) = compare(&self.tracked, &current, self.method);
            self.tracked = keep;
            fresh
        };
        if let Some((t0, was_in_window)) = self.previous {
            let dt = frame.time - t0;
            if dt > 0.0 {
                self.series.push((
                    frame.time,
                    fresh.len() as f64 / (frame.len() as f64 * dt / self.period),
                ));
            }
            if in_window && was_in_window {
                self.window_count += fresh.len() as u64;
                self.window_time += dt;
                for e in &fresh {
                    self.bin_count[self.bins.of_xy(e.mid_x, e.mid_y)] += 1;
                }
            }
        }
        self.previous = Some((frame.time, in_window));
    }
}
