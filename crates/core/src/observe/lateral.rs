//! Per-bin observables over the stationary window, accumulated in time blocks: particle
//! number, packing, bridge count, granular temperature of all grains and of the *clustered*
//! grains, and the lateral mobility (mean-square displacement over a fixed lag in time).
//!
//! **Region membership.** A coexistence is classified from the grains that belong to each
//! region at each sample, not from everything that crosses a bin (a gas grain flying through a
//! bonded cluster would heat it). A grain is *clustered* at a sample when it is bound into a
//! dense structure: in a wet scene it holds at least one capillary bridge; in a dry scene it has
//! at least [`DRY_CLUSTER_NEIGHBOURS`] neighbours whose surfaces are closer than
//! [`DRY_CLUSTER_GAP`] `d`. The dense region of a coexistence is described by its clustered
//! grains, the dilute region by all of its grains (`observe::classify`).
//!
//! **Mobility.** Lateral displacements are unwrapped sample by sample (nearest image) and
//! compared over a lag of `k = max(1, round(lag / dt))` samples, `tau = k dt` close to
//! `observe.mobility_lag` whatever the sampling interval `dt`; origins are taken every
//! `max(1, k / 4)` samples. `D_lat = <|Delta r_lat|^2> / (2 n_lat tau)` (`n_lat` = 1 in 2D, 2 in
//! 3D) per unit time: it does not depend on the sampling rate (positions at two times do not
//! depend on how often one looked in between) nor on the driving period. Displacements are
//! taken relative to the mean displacement of the grains that started in the same bin, so that
//! a bed or cluster drifting or swaying as a whole (its grains keeping their neighbours) does
//! not count as mobile: a resting bed at Gamma = 0.6 gave `D_lat` = 6e-3 without this, from a
//! collective sway, and 1e-5 with it (docs/observables.md). A displacement is booked to the bin
//! the grain was in at the lag's origin, and to the clustered accumulators when it was
//! clustered there.
//!
//! **Blocks.** Sums are kept per block of `block_time` (initially one observation period);
//! when more than [`MAX_BLOCKS`] exist, neighbours are merged and the block time doubles. The
//! block means give the statistical error of every bin's time average (`noise`).

use super::bins::LateralBins;
use super::profiles::particle_volume;
use crate::sim::Frame;
use std::collections::VecDeque;

/// Dry scenes: largest surface gap, in units of `d`, of a neighbour that counts towards being
/// clustered.
pub const DRY_CLUSTER_GAP: f64 = 0.1;
/// Dry scenes: neighbours within [`DRY_CLUSTER_GAP`] that make a grain clustered.
pub const DRY_CLUSTER_NEIGHBOURS: usize = 2;
/// Most blocks kept before neighbouring blocks are merged.
pub const MAX_BLOCKS: usize = 256;

/// Per-bin fields of a block (sums over the block's samples).
pub mod field {
    /// Particles in the bin (summed over samples).
    pub const PARTICLES: usize = 0;
    /// Summed particle volume (area in 2D).
    pub const VOLUME: usize = 1;
    /// Bridges whose midpoint lies in the bin.
    pub const BRIDGES: usize = 2;
    /// `sum n_b T_b` over samples with at least two grains, all grains.
    pub const T_ALL: usize = 3;
    /// `sum n_b` over those samples.
    pub const T_ALL_W: usize = 4;
    /// The same for the clustered grains of the bin.
    pub const T_CL: usize = 5;
    pub const T_CL_W: usize = 6;
    /// Clustered grains in the bin (summed over samples).
    pub const CLUSTERED: usize = 7;
    /// Summed `|Delta r_lat|^2` over the lag, all grains with origin in the bin, and their count.
    pub const MSD_ALL: usize = 8;
    pub const MSD_ALL_N: usize = 9;
    /// The same for grains clustered at the origin.
    pub const MSD_CL: usize = 10;
    pub const MSD_CL_N: usize = 11;
    /// Number of fields.
    pub const COUNT: usize = 12;
}

/// One block of samples.
#[derive(Debug, Clone)]
pub struct Block {
    pub t0: f64,
    pub t1: f64,
    pub samples: u64,
    /// `field::COUNT` numbers per bin, bin-major.
    pub sums: Vec<f64>,
}

impl Block {
    fn new(t0: f64, bins: usize) -> Self {
        Self {
            t0,
            t1: t0,
            samples: 0,
            sums: vec![0.0; bins * field::COUNT],
        }
    }

    /// Field `f` of bin `b`.
    pub fn get(&self, b: usize, f: usize) -> f64 {
        self.sums[b * field::COUNT + f]
    }

    fn merge(&mut self, other: &Block) {
        self.t1 = other.t1;
        self.samples += other.samples;
        for (a, b) in self.sums.iter_mut().zip(&other.sums) {
            *a += b;
        }
    }
}

/// A lag origin: sample index, unwrapped lateral positions, bins and clustered flags.
#[derive(Debug, Clone)]
struct Origin {
    index: u64,
    lateral: Vec<f64>,
    bin: Vec<u32>,
    clustered: Vec<bool>,
}

/// Whether each grain of a frame is clustered (see the module doc).
pub fn clustered(frame: &Frame, wet: bool) -> Vec<bool> {
    let n = frame.len();
    if wet {
        let mut c = vec![false; n];
        for &(i, j) in &frame.bridges {
            c[i] = true;
            c[j] = true;
        }
        return c;
    }
    close_neighbour_counts(frame, DRY_CLUSTER_GAP)
        .into_iter()
        .map(|k| k >= DRY_CLUSTER_NEIGHBOURS)
        .collect()
}

/// For every grain, the number of others whose surface lies within `gap` (units of length) of
/// its own: a cell list of cell size at least `2 r_max + gap`, periodic where the box is.
pub fn close_neighbour_counts(frame: &Frame, gap: f64) -> Vec<usize> {
    let n = frame.len();
    let dim = frame.dimension;
    let r_max = frame.radii.iter().copied().fold(0.0, f64::max);
    let reach = 2.0 * r_max + gap;
    let mut cells = [1usize; 3];
    let mut size = [1.0f64; 3];
    for k in 0..dim {
        let l = frame.box_size[k];
        cells[k] = ((l / reach).floor() as usize).max(1);
        size[k] = l / cells[k] as f64;
    }
    let offset = frame.wall_offset;
    let cell_of = |i: usize| -> [usize; 3] {
        let x = frame.x(i);
        let mut c = [0usize; 3];
        for k in 0..dim {
            let v = if k == dim - 1 { x[k] - offset } else { x[k] };
            let w = if frame.periodic[k] {
                v.rem_euclid(frame.box_size[k])
            } else {
                v
            };
            c[k] = ((w / size[k]).floor().max(0.0) as usize).min(cells[k] - 1);
        }
        c
    };
    let total = cells[0] * cells[1] * cells[2];
    let mut heads: Vec<Vec<usize>> = vec![Vec::new(); total];
    let index = |c: [usize; 3]| c[0] + cells[0] * (c[1] + cells[1] * c[2]);
    let own: Vec<[usize; 3]> = (0..n).map(cell_of).collect();
    for (i, c) in own.iter().enumerate() {
        heads[index(*c)].push(i);
    }
    let mut count = vec![0usize; n];
    for i in 0..n {
        let c = own[i];
        let mut seen: Vec<usize> = Vec::with_capacity(27);
        let span = |k: usize| -> Vec<usize> {
            if k >= dim {
                return vec![0];
            }
            let m = cells[k] as i64;
            let mut v = Vec::new();
            for d in -1i64..=1 {
                let x = c[k] as i64 + d;
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
        for &a in &span(0) {
            for &b in &span(1) {
                for &z in &span(2) {
                    let cell = index([a, b, z]);
                    if seen.contains(&cell) {
                        continue;
                    }
                    seen.push(cell);
                    for &j in &heads[cell] {
                        if j == i {
                            continue;
                        }
                        let (xi, xj) = (frame.x(i), frame.x(j));
                        let mut r2 = 0.0;
                        for k in 0..dim {
                            let dx = frame.min_image(k, xj[k] - xi[k]);
                            r2 += dx * dx;
                        }
                        let contact = frame.radii[i] + frame.radii[j] + gap;
                        if r2 < contact * contact {
                            count[i] += 1;
                        }
                    }
                }
            }
        }
    }
    count
}

/// `T_g` (Eq. 3.2) from the sums `sum v` (per axis), `sum |v|^2` and the count of a group;
/// `None` for fewer than two grains.
fn temperature_of(sum_v: &[f64], sum_sq: f64, n: usize, mass: f64) -> Option<f64> {
    if n < 2 {
        return None;
    }
    let nf = n as f64;
    let mean_sq: f64 = sum_v.iter().map(|s| (s / nf) * (s / nf)).sum();
    Some(mass * (sum_sq / nf - mean_sq) / sum_v.len() as f64)
}

/// The per-bin block accumulator of the window (see the module doc).
#[derive(Debug, Clone)]
pub struct LateralObserver {
    bins: LateralBins,
    wet: bool,
    /// Energy unit of the reduced temperatures.
    unit: f64,
    sample_interval: f64,
    lag_samples: u64,
    origin_stride: u64,
    pub block_time: f64,
    pub blocks: Vec<Block>,
    /// Window samples seen.
    samples: u64,
    unwrapped: Vec<f64>,
    previous: Vec<f64>,
    origins: VecDeque<Origin>,
}

impl LateralObserver {
    /// `block_time`: initial block length (one observation period); `lag`: the mobility lag in
    /// time units.
    pub fn new(
        bins: LateralBins,
        wet: bool,
        unit: f64,
        sample_interval: f64,
        block_time: f64,
        lag: f64,
    ) -> Self {
        let lag_samples = ((lag / sample_interval).round() as u64).max(1);
        Self {
            bins,
            wet,
            unit,
            sample_interval,
            lag_samples,
            origin_stride: (lag_samples / 4).max(1),
            block_time,
            blocks: Vec::new(),
            samples: 0,
            unwrapped: Vec::new(),
            previous: Vec::new(),
            origins: VecDeque::new(),
        }
    }

    /// The lag actually used, `k dt`.
    pub fn lag(&self) -> f64 {
        self.lag_samples as f64 * self.sample_interval
    }

    pub fn bins(&self) -> &LateralBins {
        &self.bins
    }

    /// The block a sample at `t` goes to (opening a new one, merging when there are too many).
    fn block_for(&mut self, t: f64) -> usize {
        let nb = self.bins.n;
        let start_new = match self.blocks.last() {
            None => true,
            Some(b) => t >= b.t0 + self.block_time * (1.0 - 1e-9),
        };
        if start_new {
            // Blocks tile time from the first sample on, whatever the sampling.
            let t0 = match self.blocks.last() {
                None => t,
                Some(b) => {
                    let k = ((t - b.t0) / self.block_time * (1.0 + 1e-12))
                        .floor()
                        .max(1.0);
                    b.t0 + k * self.block_time
                }
            };
            self.blocks.push(Block::new(t0, nb));
            if self.blocks.len() > MAX_BLOCKS {
                let old = std::mem::take(&mut self.blocks);
                let mut it = old.into_iter();
                while let Some(mut a) = it.next() {
                    if let Some(b) = it.next() {
                        a.merge(&b);
                    }
                    self.blocks.push(a);
                }
                self.block_time *= 2.0;
            }
        }
        self.blocks.len() - 1
    }

    /// Books one window sample.
    pub fn observe(&mut self, frame: &Frame) {
        let n = frame.len();
        let dim = frame.dimension;
        let n_lat = dim - 1;
        let bk = self.block_for(frame.time);
        let nb = self.bins.n;
        let bin: Vec<u32> = (0..n)
            .map(|i| self.bins.of_particle(frame, i) as u32)
            .collect();
        let cl = clustered(frame, self.wet);
        // Per-bin velocity sums for all and clustered grains.
        let mut sv_all = vec![0.0; nb * dim];
        let mut sq_all = vec![0.0; nb];
        let mut n_all = vec![0usize; nb];
        let mut sv_cl = vec![0.0; nb * dim];
        let mut sq_cl = vec![0.0; nb];
        let mut n_cl = vec![0usize; nb];
        let block = &mut self.blocks[bk];
        block.samples += 1;
        block.t1 = frame.time;
        for i in 0..n {
            let b = bin[i] as usize;
            let v = frame.v(i);
            let s2: f64 = v.iter().map(|x| x * x).sum();
            n_all[b] += 1;
            sq_all[b] += s2;
            for k in 0..dim {
                sv_all[b * dim + k] += v[k];
            }
            if cl[i] {
                n_cl[b] += 1;
                sq_cl[b] += s2;
                for k in 0..dim {
                    sv_cl[b * dim + k] += v[k];
                }
            }
            let s = &mut block.sums[b * field::COUNT..(b + 1) * field::COUNT];
            s[field::PARTICLES] += 1.0;
            s[field::VOLUME] += particle_volume(dim, frame.radii[i]);
            if cl[i] {
                s[field::CLUSTERED] += 1.0;
            }
        }
        for &(i, j) in &frame.bridges {
            let b = self.bins.of_pair(frame, i, j);
            block.sums[b * field::COUNT + field::BRIDGES] += 1.0;
        }
        for b in 0..nb {
            let s = &mut block.sums[b * field::COUNT..(b + 1) * field::COUNT];
            if let Some(t) = temperature_of(
                &sv_all[b * dim..(b + 1) * dim],
                sq_all[b],
                n_all[b],
                frame.mass,
            ) {
                s[field::T_ALL] += n_all[b] as f64 * t / self.unit;
                s[field::T_ALL_W] += n_all[b] as f64;
            }
            if let Some(t) = temperature_of(
                &sv_cl[b * dim..(b + 1) * dim],
                sq_cl[b],
                n_cl[b],
                frame.mass,
            ) {
                s[field::T_CL] += n_cl[b] as f64 * t / self.unit;
                s[field::T_CL_W] += n_cl[b] as f64;
            }
        }

        // Mobility: unwrap, close lags that end now, open an origin when due.
        if self.unwrapped.is_empty() {
            self.unwrapped = (0..n).flat_map(|i| frame.x(i)[..n_lat].to_vec()).collect();
            self.previous = self.unwrapped.clone();
        } else {
            for i in 0..n {
                for k in 0..n_lat {
                    let x = frame.x(i)[k];
                    let p = &mut self.previous[i * n_lat + k];
                    self.unwrapped[i * n_lat + k] += frame.min_image(k, x - *p);
                    *p = x;
                }
            }
        }
        let now = self.samples;
        while let Some(o) = self.origins.front() {
            if now - o.index < self.lag_samples {
                break;
            }
            let o = self.origins.pop_front().expect("front exists");
            // Mean displacement of the grains that started in each bin: a bed or cluster
            // drifting or swaying as a whole is not mobile (its grains keep their neighbours).
            let mut mean = vec![0.0; nb * n_lat];
            let mut count = vec![0.0f64; nb];
            for i in 0..n {
                let b = o.bin[i] as usize;
                count[b] += 1.0;
                for k in 0..n_lat {
                    mean[b * n_lat + k] += self.unwrapped[i * n_lat + k] - o.lateral[i * n_lat + k];
                }
            }
            for b in 0..nb {
                for k in 0..n_lat {
                    mean[b * n_lat + k] /= count[b].max(1.0);
                }
            }
            for i in 0..n {
                let b = o.bin[i] as usize;
                let mut r2 = 0.0;
                for k in 0..n_lat {
                    let d = self.unwrapped[i * n_lat + k]
                        - o.lateral[i * n_lat + k]
                        - mean[b * n_lat + k];
                    r2 += d * d;
                }
                let s = &mut block.sums[o.bin[i] as usize * field::COUNT..];
                s[field::MSD_ALL] += r2;
                s[field::MSD_ALL_N] += 1.0;
                if o.clustered[i] {
                    s[field::MSD_CL] += r2;
                    s[field::MSD_CL_N] += 1.0;
                }
            }
        }
        if now.is_multiple_of(self.origin_stride) {
            self.origins.push_back(Origin {
                index: now,
                lateral: self.unwrapped.clone(),
                bin,
                clustered: cl,
            });
        }
        self.samples += 1;
    }

    /// Blocks whose start lies at or after `t` (all blocks for `t` at or before the first).
    pub fn blocks_from(&self, t: f64) -> &[Block] {
        let eps = 1e-9 * t.abs().max(1.0);
        let k = self
            .blocks
            .iter()
            .position(|b| b.t0 >= t - eps)
            .unwrap_or(self.blocks.len());
        &self.blocks[k..]
    }
}

/// Sums of one field per bin over blocks.
pub fn field_sums(blocks: &[Block], bins: usize, f: usize) -> Vec<f64> {
    (0..bins)
        .map(|b| blocks.iter().map(|k| k.get(b, f)).sum())
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame_2d(x: &[(f64, f64)], v: &[(f64, f64)], bridges: Vec<(usize, usize)>, t: f64) -> Frame {
        let mut f = Frame::from_parts(
            2,
            vec![20.0, 10.0],
            vec![true, false],
            x.iter().flat_map(|p| [p.0, p.1]).collect(),
            v.iter().flat_map(|p| [p.0, p.1]).collect(),
            vec![0.5; x.len()],
            bridges,
        );
        f.time = t;
        f
    }

    #[test]
    fn dry_clusters_need_two_close_neighbours() {
        // A row of three touching grains and one lone grain; the ends of the row have one
        // neighbour, the middle two.
        let x = [(1.0, 1.0), (2.05, 1.0), (3.1, 1.0), (10.0, 5.0)];
        let f = frame_2d(&x, &[(0.0, 0.0); 4], vec![], 0.0);
        assert_eq!(close_neighbour_counts(&f, 0.1), vec![1, 2, 1, 0]);
        assert_eq!(clustered(&f, false), vec![false, true, false, false]);
        // Across the periodic edge.
        let y = [(0.2, 1.0), (19.3, 1.0), (18.25, 1.0)];
        let g = frame_2d(&y, &[(0.0, 0.0); 3], vec![], 0.0);
        assert_eq!(close_neighbour_counts(&g, 0.1), vec![1, 2, 1]);
    }

    #[test]
    fn mobility_lag_is_set_in_time_and_displacements_unwrap() {
        // Two grains in one bin moving apart at unit speed each along x across the periodic
        // edge; dt = 0.5, lag 2: each moves 2 against their mean (0) per lag, whatever the
        // wraps.
        let mut o = LateralObserver::new(LateralBins::new(1, 20.0), true, 1.0, 0.5, 1.0, 2.0);
        assert_eq!(o.lag(), 2.0);
        for k in 0..40 {
            let t = 0.5 * k as f64;
            let x = (15.0 + t).rem_euclid(20.0);
            let y = (5.0 - t).rem_euclid(20.0);
            o.observe(&frame_2d(
                &[(x, 1.0), (y, 1.0)],
                &[(1.0, 0.0), (-1.0, 0.0)],
                vec![],
                t,
            ));
        }
        let all = field_sums(&o.blocks, 1, field::MSD_ALL);
        let n = field_sums(&o.blocks, 1, field::MSD_ALL_N);
        let (s, c): (f64, f64) = (all.iter().sum(), n.iter().sum());
        assert!(c > 0.0);
        assert!((s / c - 4.0).abs() < 1e-9, "{}", s / c);
    }

    #[test]
    fn a_block_moving_as_a_whole_is_not_mobile() {
        // Safeguard: three bonded grains in one bin translating together at unit speed have
        // zero displacement relative to their bin's mean (without the subtraction: 4 per lag).
        let mut o = LateralObserver::new(LateralBins::new(1, 20.0), true, 1.0, 0.5, 1.0, 2.0);
        for k in 0..40 {
            let t = 0.5 * k as f64;
            let x = (5.0 + t).rem_euclid(20.0);
            o.observe(&frame_2d(
                &[(x, 1.0), (x + 1.0, 1.0), (x + 2.0, 1.0)],
                &[(1.0, 0.0); 3],
                vec![(0, 1), (1, 2)],
                t,
            ));
        }
        let all = field_sums(&o.blocks, 1, field::MSD_ALL);
        let n = field_sums(&o.blocks, 1, field::MSD_ALL_N);
        assert!(n[0] > 0.0);
        assert!(all[0] / n[0] < 1e-18, "{}", all[0] / n[0]);
    }

    #[test]
    fn clustered_temperature_ignores_passing_grains() {
        // Bin 0 holds a bonded, still pair and a fast unbonded grain: the bin's temperature
        // of all grains is high, of the clustered ones zero.
        let x = [(1.0, 1.0), (2.0, 1.0), (3.0, 5.0)];
        let v = [(0.0, 0.0), (0.0, 0.0), (10.0, 0.0)];
        let mut o = LateralObserver::new(LateralBins::new(4, 20.0), true, 1.0, 0.5, 1.0, 2.0);
        o.observe(&frame_2d(&x, &v, vec![(0, 1)], 0.0));
        let b = &o.blocks[0];
        assert!(b.get(0, field::T_ALL) / b.get(0, field::T_ALL_W) > 5.0);
        assert_eq!(b.get(0, field::T_CL), 0.0);
        assert_eq!(b.get(0, field::T_CL_W), 2.0);
        assert_eq!(b.get(0, field::CLUSTERED), 2.0);
        assert_eq!(b.get(0, field::BRIDGES), 1.0);
    }

    #[test]
    fn blocks_merge_and_keep_every_sample() {
        let mut o = LateralObserver::new(LateralBins::new(1, 20.0), true, 1.0, 0.1, 0.1, 1.0);
        for k in 0..(3 * MAX_BLOCKS) {
            o.observe(&frame_2d(
                &[(1.0, 1.0)],
                &[(0.0, 0.0)],
                vec![],
                0.1 * k as f64,
            ));
        }
        assert!(o.blocks.len() <= MAX_BLOCKS);
        let total: u64 = o.blocks.iter().map(|b| b.samples).sum();
        assert_eq!(total, 3 * MAX_BLOCKS as u64);
        assert!(o.block_time > 0.1 * 2.0 - 1e-12);
    }
}
