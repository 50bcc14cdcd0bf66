//! Bonded clusters: which grains belong to a dense, bound structure at a sample, and how such a
//! structure moves as a rigid body (docs/model.md 7, docs/model-choices.md "Regions made of
//! bonded clusters").
//!
//! **Bonds.** In a wet scene a bond is a capillary bridge; in a dry scene a pair whose surfaces
//! are closer than [`DRY_BOND_GAP`] `d`. Bridges form at every contact, so a gas grain that
//! bounces off a drop holds one for the duration of the bounce. A grain is *settled* once it has
//! held a bond (any bond) at every sample for at least `bond_time` time units
//! (`observe.bond_time`), and at two samples at least: with samples further apart than
//! `bond_time`, a grain bonded at two consecutive samples is settled. The persistence is the
//! grain's, not the bond's: in a strongly shaken liquid drop (Gamma = 30) single bridges break
//! and re-form within a few hundredths of a time unit, but a grain of the drop is bonded to some
//! neighbour almost all the time, where a vapour grain is bonded only while it bounces.
//!
//! **Members.** The bonds between settled grains make a graph; a grain is a *member* at a sample
//! when its connected component holds at least `min_size` grains (`observe.cluster_min_size`).
//! Region observables of a coexistence's dense part use members only (`observe::lateral`).
//!
//! **Rigid motion.** [`rigid_residuals`] removes from each member's displacement over a lag the
//! translation of its cluster and, for a cluster smaller than half the box along every periodic
//! axis, the best-fit rotation (2D: the angle that maximises the overlap, closed form; 3D: the
//! Kabsch rotation from the SVD of the covariance). A drop that drifts and turns as a whole then
//! shows only its grains' motion relative to each other.

use crate::sim::Frame;
use nalgebra::{Matrix3, Vector3};

/// Dry scenes: largest surface gap, in units of `d`, of a pair that counts as a bond.
pub(crate) const DRY_BOND_GAP: f64 = 0.1;
/// Component id of a grain that is not a member of any cluster.
pub(crate) const NOT_MEMBER: u32 = u32::MAX;

/// Tracks how long each grain has been bonded and labels the members of large bonded clusters.
#[derive(Debug, Clone)]
pub(crate) struct BondedClusters {
    wet: bool,
    bond_time: f64,
    min_size: usize,
    /// Per grain: the first time of the current unbroken run of samples at which it held a bond
    /// (`None`: it held none at the last sample).
    bonded_since: Vec<Option<f64>>,
}

/// The clusters of one sample.
#[derive(Debug, Clone, PartialEq)]
pub struct Membership {
    /// Per grain: its cluster's id (`0..clusters`), or [`NOT_MEMBER`].
    pub cluster: Vec<u32>,
    /// Number of clusters of at least the minimum size.
    pub clusters: usize,
    /// The lasting bonds between members (both grains members of the same cluster): each
    /// member's bonded neighbours, its cage (`observe::lateral`).
    pub bonds: Vec<(u32, u32)>,
}

impl Membership {
    /// Whether grain `i` is a member of a large bonded cluster.
    pub(crate) fn is_member(&self, i: usize) -> bool {
        self.cluster[i] != NOT_MEMBER
    }
}

impl BondedClusters {
    /// `bond_time`: how long a grain must have held a bond, time units; `min_size`: the smallest
    /// cluster whose grains are members.
    pub(crate) fn new(wet: bool, bond_time: f64, min_size: usize) -> Self {
        Self {
            wet,
            bond_time,
            min_size: min_size.max(1),
            bonded_since: Vec::new(),
        }
    }

    /// Books one sample and returns its membership. Samples must come in time order.
    pub(crate) fn observe(&mut self, frame: &Frame) -> Membership {
        let now = frame.time;
        let n = frame.len();
        let pairs = if self.wet {
            frame.bridges.clone()
        } else {
            // The gap in units of the frame's mean diameter.
            let d = 2.0 * frame.radii.iter().sum::<f64>() / n.max(1) as f64;
            close_pairs(frame, DRY_BOND_GAP * d)
        };
        let first = self.bonded_since.len() != n;
        let mut bonded = vec![false; n];
        for &(i, j) in &pairs {
            bonded[i] = true;
            bonded[j] = true;
        }
        let since: Vec<Option<f64>> = (0..n)
            .map(|i| {
                bonded[i].then(|| {
                    if first {
                        now
                    } else {
                        self.bonded_since[i].unwrap_or(now)
                    }
                })
            })
            .collect();
        // Settled: bonded at every sample for at least `bond_time` and at two samples or more
        // (the tolerance keeps an exact `bond_time` apart from round-off).
        let settled: Vec<bool> = (0..n)
            .map(|i| {
                !first
                    && self.bonded_since[i].is_some()
                    && since[i].is_some_and(|t0| now - t0 >= self.bond_time * (1.0 - 1e-9))
            })
            .collect();
        self.bonded_since = since;
        let lasting: Vec<(u32, u32)> = pairs
            .into_iter()
            .filter(|&(i, j)| settled[i] && settled[j])
            .map(|(i, j)| (i as u32, j as u32))
            .collect();
        components(n, &lasting, self.min_size)
    }
}

/// The connected components of the graph `bonds` over `n` grains (union-find with path halving);
/// components of at least `min_size` grains get ids `0..` in the order of their smallest grain.
pub fn components(n: usize, bonds: &[(u32, u32)], min_size: usize) -> Membership {
    let mut parent: Vec<u32> = (0..n as u32).collect();
    fn root(parent: &mut [u32], mut i: u32) -> u32 {
        while parent[i as usize] != i {
            parent[i as usize] = parent[parent[i as usize] as usize];
            i = parent[i as usize];
        }
        i
    }
    for &(i, j) in bonds {
        let (a, b) = (root(&mut parent, i), root(&mut parent, j));
        if a != b {
            let (lo, hi) = (a.min(b), a.max(b));
            parent[hi as usize] = lo;
        }
    }
    let roots: Vec<u32> = (0..n as u32).map(|i| root(&mut parent, i)).collect();
    let mut size = vec![0usize; n];
    for &r in &roots {
        size[r as usize] += 1;
    }
    let mut id = vec![NOT_MEMBER; n];
    let mut clusters = 0usize;
    let cluster: Vec<u32> = roots
        .iter()
        .map(|&r| {
            if size[r as usize] < min_size {
                return NOT_MEMBER;
            }
            if id[r as usize] == NOT_MEMBER {
                id[r as usize] = clusters as u32;
                clusters += 1;
            }
            id[r as usize]
        })
        .collect();
    let bonds = bonds
        .iter()
        .copied()
        .filter(|&(i, _)| cluster[i as usize] != NOT_MEMBER)
        .collect();
    Membership {
        cluster,
        clusters,
        bonds,
    }
}

/// Pairs `(i, j)`, `i < j`, whose surfaces lie within `gap` (units of length): a cell list of
/// cell size at least `2 r_max + gap`, periodic where the box is.
pub fn close_pairs(frame: &Frame, gap: f64) -> Vec<(usize, usize)> {
    let n = frame.len();
    let dim = frame.dimension;
    let r_max = frame.radii.iter().copied().fold(0.0, f64::max);
    let reach = 2.0 * r_max + gap;
    let mut cells = [1usize; 3];
    let mut size = [1.0f64; 3];
    for k in 0..dim {
        cells[k] = ((frame.box_size[k] / reach).floor() as usize).max(1);
        size[k] = frame.box_size[k] / cells[k] as f64;
    }
    let cell_of = |i: usize| -> [usize; 3] {
        let x = frame.x(i);
        let mut c = [0usize; 3];
        for k in 0..dim {
            let v = if k == dim - 1 {
                x[k] - frame.wall_offset
            } else {
                x[k]
            };
            let w = if frame.periodic[k] {
                v.rem_euclid(frame.box_size[k])
            } else {
                v
            };
            c[k] = ((w / size[k]).floor().max(0.0) as usize).min(cells[k] - 1);
        }
        c
    };
    let index = |c: [usize; 3]| c[0] + cells[0] * (c[1] + cells[1] * c[2]);
    let mut members: Vec<Vec<usize>> = vec![Vec::new(); cells[0] * cells[1] * cells[2]];
    let own: Vec<[usize; 3]> = (0..n).map(cell_of).collect();
    for (i, c) in own.iter().enumerate() {
        members[index(*c)].push(i);
    }
    // The distinct neighbour cells along one axis (fewer than three on a short axis).
    let span = |c: usize, k: usize| -> Vec<usize> {
        if k >= dim {
            return vec![0];
        }
        let m = cells[k] as i64;
        let mut v: Vec<usize> = Vec::with_capacity(3);
        for d in -1i64..=1 {
            let x = c as i64 + d;
            let x = if frame.periodic[k] {
                x.rem_euclid(m)
            } else if x < 0 || x >= m {
                continue;
            } else {
                x
            };
            if !v.contains(&(x as usize)) {
                v.push(x as usize);
            }
        }
        v
    };
    let mut out = Vec::new();
    for i in 0..n {
        let c = own[i];
        for &a in &span(c[0], 0) {
            for &b in &span(c[1], 1) {
                for &z in &span(c[2], 2) {
                    for &j in &members[index([a, b, z])] {
                        if j <= i {
                            continue;
                        }
                        let (xi, xj) = (frame.x(i), frame.x(j));
                        let r2: f64 = (0..dim)
                            .map(|k| frame.min_image(k, xj[k] - xi[k]).powi(2))
                            .sum();
                        let contact = frame.radii[i] + frame.radii[j] + gap;
                        if r2 < contact * contact {
                            out.push((i, j));
                        }
                    }
                }
            }
        }
    }
    out
}

/// Whether the grains `members` (positions `start`, `dim` per grain) spread over half the box or
/// more along a periodic axis, measured from the first member by nearest image: a cluster that
/// wraps around the box (a bed, a percolating network) and cannot turn as a whole.
pub(crate) fn spans_box(
    members: &[usize],
    start: &[f64],
    dim: usize,
    periodic: &[bool],
    box_size: &[f64],
) -> bool {
    let Some(&reference) = members.first() else {
        return false;
    };
    (0..dim).filter(|&k| periodic[k]).any(|k| {
        let (mut lo, mut hi) = (0.0f64, 0.0f64);
        for &i in members {
            let mut d = start[i * dim + k] - start[reference * dim + k];
            d -= box_size[k] * (d / box_size[k]).round();
            lo = lo.min(d);
            hi = hi.max(d);
        }
        hi - lo >= 0.5 * box_size[k]
    })
}

/// For the grains `members` of one cluster, their displacements over a lag with the cluster's
/// rigid motion removed: `start[i]` and `end[i]` are grain `i`'s positions at the lag's ends
/// (`dim` numbers each, periodic axes unwrapped continuously so that `end - start` is the true
/// displacement); `periodic`, `box_size`: the box. Returns one residual vector per member, in
/// the order of `members`. The translation is the mean displacement; the rotation is fitted
/// about the centroid, so the cluster must not wrap around the box ([`spans_box`]: such a
/// cluster cannot turn, and `observe::lateral` measures it bin by bin instead).
pub(crate) fn rigid_residuals(
    members: &[usize],
    start: &[f64],
    end: &[f64],
    dim: usize,
    periodic: &[bool],
    box_size: &[f64],
) -> Vec<Vec<f64>> {
    let m = members.len();
    if m == 0 {
        return Vec::new();
    }
    let reference = members[0];
    // Positions at the start relative to the first member (nearest image), and displacements.
    let mut rel = vec![0.0; m * dim];
    let mut disp = vec![0.0; m * dim];
    for k in 0..dim {
        for (a, &i) in members.iter().enumerate() {
            let mut d = start[i * dim + k] - start[reference * dim + k];
            if periodic[k] {
                d -= box_size[k] * (d / box_size[k]).round();
            }
            rel[a * dim + k] = d;
            disp[a * dim + k] = end[i * dim + k] - start[i * dim + k];
        }
    }
    let mean = |v: &[f64], k: usize| (0..m).map(|a| v[a * dim + k]).sum::<f64>() / m as f64;
    let c0: Vec<f64> = (0..dim).map(|k| mean(&rel, k)).collect();
    let shift: Vec<f64> = (0..dim).map(|k| mean(&disp, k)).collect();
    // a: positions about the centroid at the start; b: the same at the end.
    let a: Vec<f64> = (0..m * dim).map(|x| rel[x] - c0[x % dim]).collect();
    let b: Vec<f64> = (0..m * dim)
        .map(|x| a[x] + disp[x] - shift[x % dim])
        .collect();
    let rotation = if m >= 2 {
        best_rotation(&a, &b, dim)
    } else {
        identity(dim)
    };
    (0..m)
        .map(|p| {
            (0..dim)
                .map(|k| {
                    let turned: f64 = (0..dim)
                        .map(|l| rotation[k * dim + l] * a[p * dim + l])
                        .sum();
                    b[p * dim + k] - turned
                })
                .collect()
        })
        .collect()
}

fn identity(dim: usize) -> Vec<f64> {
    (0..dim * dim)
        .map(|x| if x / dim == x % dim { 1.0 } else { 0.0 })
        .collect()
}

/// The proper rotation `R` (row-major, `dim x dim`) minimising `sum |b_p - R a_p|^2`.
fn best_rotation(a: &[f64], b: &[f64], dim: usize) -> Vec<f64> {
    let m = a.len() / dim;
    if dim == 2 {
        // theta = atan2(sum a x b, sum a . b).
        let (mut cross, mut dot) = (0.0, 0.0);
        for p in 0..m {
            let (ax, ay, bx, by) = (a[2 * p], a[2 * p + 1], b[2 * p], b[2 * p + 1]);
            cross += ax * by - ay * bx;
            dot += ax * bx + ay * by;
        }
        let th = cross.atan2(dot);
        let (s, c) = th.sin_cos();
        return vec![c, -s, s, c];
    }
    // Kabsch: H = sum a b^T = U S V^T, R = V diag(1, 1, det(V U^T)) U^T.
    let mut h = Matrix3::<f64>::zeros();
    for p in 0..m {
        let ap = Vector3::new(a[3 * p], a[3 * p + 1], a[3 * p + 2]);
        let bp = Vector3::new(b[3 * p], b[3 * p + 1], b[3 * p + 2]);
        h += ap * bp.transpose();
    }
    let svd = h.svd(true, true);
    let (Some(u), Some(vt)) = (svd.u, svd.v_t) else {
        return identity(3);
    };
    let v = vt.transpose();
    let d = (v * u.transpose()).determinant().signum();
    let r = v * Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, d)) * u.transpose();
    (0..9).map(|x| r[(x / 3, x % 3)]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(t: f64, x: &[(f64, f64)], bridges: Vec<(usize, usize)>) -> Frame {
        let mut f = Frame::from_parts(
            2,
            vec![40.0, 10.0],
            vec![true, false],
            x.iter().flat_map(|p| [p.0, p.1]).collect(),
            vec![0.0; 2 * x.len()],
            vec![0.5; x.len()],
            bridges,
        );
        f.time = t;
        f
    }

    #[test]
    fn components_keep_only_large_ones() {
        // 0-1-2 a chain of three, 3-4 a pair, 5 alone.
        let m = components(6, &[(0, 1), (2, 1), (3, 4)], 3);
        assert_eq!(m.clusters, 1);
        assert_eq!(m.cluster[..3], [0, 0, 0]);
        assert!(m.cluster[3..].iter().all(|&c| c == NOT_MEMBER));
        // Only bonds between members are kept: each member's cage.
        assert_eq!(m.bonds, vec![(0, 1), (2, 1)]);
        let all = components(6, &[(0, 1), (2, 1), (3, 4)], 1);
        assert_eq!(all.clusters, 3);
    }

    #[test]
    fn a_bounce_is_not_a_bond() {
        // Safeguard: a grain bonded at one sample only (bouncing off) never counts; grains
        // bonded at every sample from 0.0 count from the sample at which they have been bonded
        // for one time unit.
        let x = [(1.0, 1.0), (2.0, 1.0), (3.0, 1.0)];
        let mut c = BondedClusters::new(true, 1.0, 2);
        let m = c.observe(&frame(0.0, &x, vec![(0, 1), (1, 2)]));
        assert_eq!(m.clusters, 0);
        // The bounce 1-2 is gone at the next sample; 0-1 persists.
        for k in 1..=3 {
            let t = 0.5 * k as f64;
            let m = c.observe(&frame(t, &x, vec![(0, 1)]));
            assert_eq!(m.is_member(0), t >= 1.0, "t = {t}");
            assert!(!m.is_member(2));
        }
        // A bond that breaks starts its age again.
        c.observe(&frame(2.0, &x, vec![]));
        assert_eq!(c.observe(&frame(2.5, &x, vec![(0, 1)])).clusters, 0);
    }

    #[test]
    fn dry_bonds_are_close_pairs() {
        let x = [
            (1.0, 1.0),
            (2.05, 1.0),
            (3.1, 1.0),
            (10.0, 5.0),
            (39.6, 5.0),
        ];
        let f = frame(0.0, &x, vec![]);
        let mut p = close_pairs(&f, 0.1);
        p.sort_unstable();
        assert_eq!(p, vec![(0, 1), (1, 2)]);
        // Across the periodic edge: 39.6 and 0.5 are 0.9 apart.
        let y = [(0.5, 5.0), (39.6, 5.0)];
        assert_eq!(close_pairs(&frame(0.0, &y, vec![]), 0.1), vec![(0, 1)]);
    }

    #[test]
    fn a_rigid_turn_and_drift_leave_no_residual() {
        // A 2D cluster of five grains straddling the periodic edge, turned by 0.3 rad about its
        // centroid and moved by (7, 0.5).
        let pts = [
            (39.0, 2.0),
            (0.2, 2.5),
            (39.5, 3.4),
            (1.0, 3.0),
            (38.8, 4.0),
        ];
        let (l, th) = (40.0f64, 0.3f64);
        let start: Vec<f64> = pts.iter().flat_map(|p| [p.0, p.1]).collect();
        // Unwrapped positions about the centroid.
        let un: Vec<(f64, f64)> = pts
            .iter()
            .map(|p| (if p.0 > 20.0 { p.0 - l } else { p.0 }, p.1))
            .collect();
        let c = (
            un.iter().map(|p| p.0).sum::<f64>() / 5.0,
            un.iter().map(|p| p.1).sum::<f64>() / 5.0,
        );
        let end: Vec<f64> = un
            .iter()
            .zip(&pts)
            .flat_map(|(u, p)| {
                let (dx, dy) = (u.0 - c.0, u.1 - c.1);
                let (s, co) = th.sin_cos();
                let nx = c.0 + co * dx - s * dy + 7.0;
                let ny = c.1 + s * dx + co * dy + 0.5;
                // Continuous unwrapping: end - start is the true displacement.
                [p.0 + (nx - u.0), ny]
            })
            .collect();
        let r = rigid_residuals(
            &[0, 1, 2, 3, 4],
            &start,
            &end,
            2,
            &[true, false],
            &[l, 10.0],
        );
        for v in &r {
            assert!(v.iter().all(|x| x.abs() < 1e-12), "{v:?}");
        }
        // Each grain moving on its own keeps its motion relative to the others.
        let mut moved = end.clone();
        moved[0] += 0.4;
        let r = rigid_residuals(
            &[0, 1, 2, 3, 4],
            &start,
            &moved,
            2,
            &[true, false],
            &[l, 10.0],
        );
        assert!(r[0][0].abs() > 0.2, "{:?}", r[0]);
    }

    #[test]
    fn kabsch_recovers_a_3d_rotation() {
        let a = [
            (1.0, 0.0, 0.0),
            (0.0, 2.0, 0.0),
            (0.0, 0.0, 1.5),
            (1.0, 1.0, 1.0),
            (-1.0, 0.5, -0.3),
        ];
        let (s, c) = 0.4f64.sin_cos();
        // Rotation about z by 0.4 then translation by (1, 2, 3).
        let start: Vec<f64> = a.iter().flat_map(|p| [p.0, p.1, p.2]).collect();
        let end: Vec<f64> = a
            .iter()
            .flat_map(|p| [c * p.0 - s * p.1 + 1.0, s * p.0 + c * p.1 + 2.0, p.2 + 3.0])
            .collect();
        let r = rigid_residuals(
            &[0, 1, 2, 3, 4],
            &start,
            &end,
            3,
            &[true, true, false],
            &[50.0, 50.0, 10.0],
        );
        for v in &r {
            assert!(v.iter().all(|x| x.abs() < 1e-9), "{v:?}");
        }
    }
}
