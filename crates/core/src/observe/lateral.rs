//! Per-bin observables over the stationary window, accumulated in time blocks: particle
//! number, packing, bridge count, granular temperature of all grains and of the *members* of
//! bonded clusters, and the lateral mobility (mean-square displacement over two lags in time).
//!
//! **Region membership.** A coexistence is classified from the grains that belong to each
//! region at each sample, not from everything that crosses a bin (a gas grain that bounces off a
//! drop would heat it). A grain is a *member* at a sample when it belongs to a large bonded
//! cluster (`observe::clusters`: bonds that have lasted `observe.bond_time`, components of at
//! least `observe.cluster_min_size` grains). The dense region of a coexistence is described by
//! its members, the dilute region by all of its grains (`observe::classify`). The per-bin
//! `field::CLUSTERED` counts members.
//!
//! **Temperature.** `T_b = m sum |v - <v>|^2 / (D (n - 1))` over the `n >= 2` grains of a group
//! in a bin at a sample: the unbiased estimate, since the group's own mean velocity is
//! subtracted (with `n` instead of `n - 1` a bin of three grains would read a third cold).
//!
//! **Mobility.** Lateral displacements are unwrapped sample by sample (nearest image) and
//! compared over a lag of `k = max(1, round(lag / dt))` samples, `tau = k dt` close to
//! `observe.mobility_lag` whatever the sampling interval `dt`, and over a short lag of a quarter
//! of it; origins are taken every `max(1, k / 4)` samples of each lag. `D_lat = <|Delta
//! r_lat|^2> / (2 n_lat tau)` (`n_lat` = 1 in 2D, 2 in 3D) per unit time. How `D_lat` changes
//! between the two lags tells caged motion (the mean-square displacement saturates: `D_lat`
//! falls like `1 / tau`) from diffusion (`D_lat` stays); `observe::classify` applies it. The
//! displacement of a member is taken relative to its own cluster's rigid motion (translation and
//! rotation, `clusters::rigid_residuals`) so that a drifting, turning solid drop is solid, or,
//! for a cluster that spans half the box (a bed, `clusters::spans_box`), relative to the mean
//! displacement of its members that started in the same bin; that of any other grain relative to
//! the mean displacement of the non-members that started in the same bin, so that a bed or gas
//! layer swaying as a whole does not count as mobile. A
//! displacement is booked to the bin the grain was in at the lag's origin, and to the member
//! accumulators when it was a member there.
//!
//! **Blocks.** Sums are kept per block of `block_time` (initially one observation period);
//! when more than [`MAX_BLOCKS`] exist, neighbours are merged and the block time doubles. The
//! block means give the statistical error of every bin's time average (`noise`).

use super::bins::LateralBins;
use super::clusters::{BondedClusters, Membership, NOT_MEMBER, rigid_residuals, spans_box};
use super::profiles::particle_volume;
use crate::sim::Frame;
use std::collections::VecDeque;

/// Most blocks kept before neighbouring blocks are merged.
pub(crate) const MAX_BLOCKS: usize = 256;
/// The short mobility lag is the long one divided by this.
pub(crate) const SHORT_LAG_DIVISOR: f64 = 4.0;

/// Per-bin fields of a block (sums over the block's samples).
pub(crate) mod field {
    /// Particles in the bin (summed over samples).
    pub(crate) const PARTICLES: usize = 0;
    /// Summed particle volume (area in 2D).
    pub(crate) const VOLUME: usize = 1;
    /// Bridges whose midpoint lies in the bin.
    pub(crate) const BRIDGES: usize = 2;
    /// `sum n_b T_b` over samples with at least two grains, all grains.
    pub(crate) const T_ALL: usize = 3;
    /// `sum n_b` over those samples.
    pub(crate) const T_ALL_W: usize = 4;
    /// The same for the cluster members of the bin.
    pub(crate) const T_CL: usize = 5;
    pub(crate) const T_CL_W: usize = 6;
    /// Cluster members in the bin (summed over samples).
    pub(crate) const CLUSTERED: usize = 7;
    /// Summed `|Delta r_lat|^2` over the long lag, all grains with origin in the bin, and their
    /// count.
    pub(crate) const MSD_ALL: usize = 8;
    pub(crate) const MSD_ALL_N: usize = 9;
    /// The same for grains that were members at the origin.
    pub(crate) const MSD_CL: usize = 10;
    pub(crate) const MSD_CL_N: usize = 11;
    /// The four sums above over the short lag.
    pub(crate) const MSD_SHORT_ALL: usize = 12;
    pub(crate) const MSD_SHORT_ALL_N: usize = 13;
    pub(crate) const MSD_SHORT_CL: usize = 14;
    pub(crate) const MSD_SHORT_CL_N: usize = 15;
    /// Long-lag displacements of members (at both ends) that held a lasting bond at the origin:
    /// the grains whose cage-relative displacement is measured.
    pub(crate) const CAGE_N: usize = 16;
    /// Of those, the number whose cage-relative mobility is at most `CAGE_EDGES[k]`, at
    /// `CAGE_WITHIN + k`.
    pub(crate) const CAGE_WITHIN: usize = 17;
    /// `sum n_b T_b` and `sum n_b` of the grains of the bin that are not members
    /// (`observe::settling` follows the dilute region by them).
    pub(crate) const T_UB: usize = 22;
    pub(crate) const T_UB_W: usize = 23;
    /// Number of fields.
    pub(crate) const COUNT: usize = T_UB_W + 1;
    const _: () = assert!(CAGE_WITHIN + super::CAGE_EDGES.len() == T_UB);
}

/// Mobilities `d^2 / (2 n_lat tau)` (`d^2` per time unit) at which the cage-relative
/// displacements of the members are counted: the fraction of members that stay within a
/// threshold between two edges is interpolated in `ln D` (`observe::classify`).
pub(crate) const CAGE_EDGES: [f64; 5] = [1e-4, 3e-4, 1e-3, 3e-3, 1e-2];

/// One block of samples.
#[derive(Debug, Clone)]
pub(crate) struct Block {
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
    pub(crate) fn get(&self, b: usize, f: usize) -> f64 {
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

/// A lag origin: sample index, positions (lateral axes unwrapped), bins and cluster ids.
#[derive(Debug, Clone)]
struct Origin {
    index: u64,
    positions: Vec<f64>,
    bin: Vec<u32>,
    cluster: Vec<u32>,
    /// The members' lasting bonds (long lag only; empty for the short one).
    bonds: Vec<(u32, u32)>,
}

/// The origins of one lag and where its sums go.
#[derive(Debug, Clone)]
struct LagTrack {
    samples: u64,
    stride: u64,
    origins: VecDeque<Origin>,
    /// `field::MSD_ALL` or `field::MSD_SHORT_ALL`: the first of the lag's four fields.
    first_field: usize,
}

impl LagTrack {
    fn new(samples: u64, first_field: usize) -> Self {
        Self {
            samples,
            stride: (samples / 4).max(1),
            origins: VecDeque::new(),
            first_field,
        }
    }
}

/// `T_g` (Eq. 3.2) from the sums `sum v` (per axis), `sum |v|^2` and the count of a group,
/// unbiased (`n - 1`, the group's mean velocity being subtracted); `None` for fewer than two
/// grains.
fn temperature_of(sum_v: &[f64], sum_sq: f64, n: usize, mass: f64) -> Option<f64> {
    if n < 2 {
        return None;
    }
    let nf = n as f64;
    let mean_sq: f64 = sum_v.iter().map(|s| (s / nf) * (s / nf)).sum();
    Some(mass * (sum_sq - nf * mean_sq) / ((nf - 1.0) * sum_v.len() as f64))
}

/// The per-bin block accumulator of the window (see the module doc).
#[derive(Debug, Clone)]
pub(crate) struct LateralObserver {
    bins: LateralBins,
    /// Energy unit of the reduced temperatures.
    unit: f64,
    sample_interval: f64,
    clusters: BondedClusters,
    long: LagTrack,
    short: LagTrack,
    pub(crate) block_time: f64,
    pub blocks: Vec<Block>,
    /// Window samples seen.
    samples: u64,
    /// Positions with the periodic axes unwrapped, and the last sample's raw positions.
    unwrapped: Vec<f64>,
    previous: Vec<f64>,
}

/// How a [`LateralObserver`] finds bonded clusters and measures mobility.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct LateralSettings {
    /// Capillary bridges are the bonds (else close pairs).
    pub wet: bool,
    /// Energy unit of the reduced temperatures.
    pub unit: f64,
    pub sample_interval: f64,
    /// Initial block length (one observation period).
    pub(crate) block_time: f64,
    /// The long mobility lag, time units.
    pub lag: f64,
    /// Age a bond needs to count, time units.
    pub bond_time: f64,
    /// Smallest cluster whose grains are members.
    pub cluster_min_size: usize,
}

impl LateralObserver {
    pub(crate) fn new(bins: LateralBins, s: LateralSettings) -> Self {
        let long = ((s.lag / s.sample_interval).round() as u64).max(1);
        let short = ((s.lag / SHORT_LAG_DIVISOR / s.sample_interval).round() as u64).max(1);
        Self {
            bins,
            unit: s.unit,
            sample_interval: s.sample_interval,
            clusters: BondedClusters::new(s.wet, s.bond_time, s.cluster_min_size),
            long: LagTrack::new(long, field::MSD_ALL),
            short: LagTrack::new(short, field::MSD_SHORT_ALL),
            block_time: s.block_time,
            blocks: Vec::new(),
            samples: 0,
            unwrapped: Vec::new(),
            previous: Vec::new(),
        }
    }

    /// The long lag actually used, `k dt`.
    pub(crate) fn lag(&self) -> f64 {
        self.long.samples as f64 * self.sample_interval
    }

    /// The short lag actually used.
    pub(crate) fn short_lag(&self) -> f64 {
        self.short.samples as f64 * self.sample_interval
    }

    pub(crate) fn bins(&self) -> &LateralBins {
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
    pub(crate) fn observe(&mut self, frame: &Frame) {
        let bk = self.block_for(frame.time);
        let bin: Vec<u32> = (0..frame.len())
            .map(|i| self.bins.of_particle(frame, i) as u32)
            .collect();
        let members = self.clusters.observe(frame);
        self.book_sample(frame, bk, &bin, &members);
        self.unwrap(frame);
        for which in [false, true] {
            self.close_lags(frame, bk, which, &members);
            let track = if which {
                &mut self.short
            } else {
                &mut self.long
            };
            if self.samples.is_multiple_of(track.stride) {
                track.origins.push_back(Origin {
                    index: self.samples,
                    positions: self.unwrapped.clone(),
                    bin: bin.clone(),
                    cluster: members.cluster.clone(),
                    bonds: if which {
                        Vec::new()
                    } else {
                        members.bonds.clone()
                    },
                });
            }
        }
        self.samples += 1;
    }

    /// Counts, volumes, bridges and temperatures of one sample into block `bk`.
    fn book_sample(&mut self, frame: &Frame, bk: usize, bin: &[u32], members: &Membership) {
        let dim = frame.dimension;
        let nb = self.bins.n;
        // Per-bin velocity sums, `|v|^2` sums and counts: all grains, members, the others.
        let mut sv = [
            vec![0.0; nb * dim],
            vec![0.0; nb * dim],
            vec![0.0; nb * dim],
        ];
        let mut sq = [vec![0.0; nb], vec![0.0; nb], vec![0.0; nb]];
        let mut n = [vec![0usize; nb], vec![0usize; nb], vec![0usize; nb]];
        let block = &mut self.blocks[bk];
        block.samples += 1;
        block.t1 = frame.time;
        for i in 0..frame.len() {
            let b = bin[i] as usize;
            let v = frame.v(i);
            let s2: f64 = v.iter().map(|x| x * x).sum();
            let member = members.is_member(i);
            for g in [0, if member { 1 } else { 2 }] {
                n[g][b] += 1;
                sq[g][b] += s2;
                for k in 0..dim {
                    sv[g][b * dim + k] += v[k];
                }
            }
            let s = &mut block.sums[b * field::COUNT..(b + 1) * field::COUNT];
            s[field::PARTICLES] += 1.0;
            s[field::VOLUME] += particle_volume(dim, frame.radii[i]);
            if member {
                s[field::CLUSTERED] += 1.0;
            }
        }
        for &(i, j) in &frame.bridges {
            let b = self.bins.of_pair(frame, i, j);
            block.sums[b * field::COUNT + field::BRIDGES] += 1.0;
        }
        for b in 0..nb {
            let s = &mut block.sums[b * field::COUNT..(b + 1) * field::COUNT];
            for (g, f) in [field::T_ALL, field::T_CL, field::T_UB]
                .into_iter()
                .enumerate()
            {
                let sums = &sv[g][b * dim..(b + 1) * dim];
                if let Some(t) = temperature_of(sums, sq[g][b], n[g][b], frame.mass) {
                    s[f] += n[g][b] as f64 * t / self.unit;
                    s[f + 1] += n[g][b] as f64;
                }
            }
        }
    }

    /// Advances the unwrapped positions to `frame` (lateral axes by nearest image).
    fn unwrap(&mut self, frame: &Frame) {
        let dim = frame.dimension;
        if self.unwrapped.is_empty() {
            self.unwrapped = frame.positions.clone();
            self.previous = frame.positions.clone();
            return;
        }
        for i in 0..frame.len() {
            for k in 0..dim {
                let x = frame.x(i)[k];
                let p = &mut self.previous[i * dim + k];
                self.unwrapped[i * dim + k] += frame.min_image(k, x - *p);
                *p = x;
            }
        }
    }

    /// Closes the lags (long, or short with `short`) that end at this sample: each grain's
    /// lateral displacement, relative to its cluster's rigid motion (members) or to the mean of
    /// the non-members that started in its bin (others), into block `bk`. The member sums take
    /// the grains that are members at both ends of the lag: a grain that evaporated from a drop
    /// during the lag moved as vapour, not as part of the drop.
    fn close_lags(&mut self, frame: &Frame, bk: usize, short: bool, now_members: &Membership) {
        let dim = frame.dimension;
        let n_lat = dim - 1;
        let nb = self.bins.n;
        let now = self.samples;
        // Cage-relative displacement within `CAGE_EDGES[k]`: `d^2 <= 2 n_lat tau CAGE_EDGES[k]`.
        let within: Vec<f64> = CAGE_EDGES
            .iter()
            .map(|e| 2.0 * n_lat as f64 * self.lag() * e)
            .collect();
        let track = if short {
            &mut self.short
        } else {
            &mut self.long
        };
        let (lag, first) = (track.samples, track.first_field);
        while let Some(o) = track.origins.front() {
            if now - o.index < lag {
                break;
            }
            let o = track.origins.pop_front().expect("front exists");
            let r2 = lag_displacements(&o, &self.unwrapped, frame, nb, n_lat, now_members);
            let cage = (!short).then(|| cage_relative(&o, &self.unwrapped, dim, n_lat));
            let block = &mut self.blocks[bk];
            for (i, d2) in r2.into_iter().enumerate() {
                let s = &mut block.sums[o.bin[i] as usize * field::COUNT..];
                s[first] += d2;
                s[first + 1] += 1.0;
                if o.cluster[i] != NOT_MEMBER && now_members.is_member(i) {
                    s[first + 2] += d2;
                    s[first + 3] += 1.0;
                    if let Some(c2) = cage.as_ref().and_then(|c| c[i]) {
                        s[field::CAGE_N] += 1.0;
                        for (k, &w) in within.iter().enumerate() {
                            if c2 <= w {
                                s[field::CAGE_WITHIN + k] += 1.0;
                            }
                        }
                    }
                }
            }
        }
    }

    /// Blocks whose start lies at or after `t` (all blocks for `t` at or before the first).
    pub(crate) fn blocks_from(&self, t: f64) -> &[Block] {
        let eps = 1e-9 * t.abs().max(1.0);
        let k = self
            .blocks
            .iter()
            .position(|b| b.t0 >= t - eps)
            .unwrap_or(self.blocks.len());
        &self.blocks[k..]
    }
}

/// Squared lateral displacement of every grain since origin `o` (see the module doc for the
/// reference each is taken against). A cluster's rigid motion is fitted to its grains that are
/// still members (`now_members`); those that left it are measured against that motion too.
fn lag_displacements(
    o: &Origin,
    now: &[f64],
    frame: &Frame,
    bins: usize,
    n_lat: usize,
    now_members: &Membership,
) -> Vec<f64> {
    let dim = frame.dimension;
    let n = frame.len();
    let mut r2 = vec![0.0; n];
    // Non-members: relative to the mean lateral displacement of the non-members of their bin.
    let others: Vec<usize> = (0..n).filter(|&i| o.cluster[i] == NOT_MEMBER).collect();
    bin_relative(&others, o, now, dim, n_lat, bins, &mut r2);
    // Members: relative to their own cluster's rigid motion.
    let clusters = o
        .cluster
        .iter()
        .filter(|&&c| c != NOT_MEMBER)
        .map(|&c| c as usize + 1)
        .max()
        .unwrap_or(0);
    let mut grains: Vec<Vec<usize>> = vec![Vec::new(); clusters];
    for i in 0..n {
        if o.cluster[i] != NOT_MEMBER {
            grains[o.cluster[i] as usize].push(i);
        }
    }
    for members in &grains {
        let (stayed, left): (Vec<usize>, Vec<usize>) =
            members.iter().partition(|&&i| now_members.is_member(i));
        let fit = if stayed.is_empty() { &left } else { &stayed };
        if spans_box(fit, &o.positions, dim, &frame.periodic, &frame.box_size) {
            // A cluster that wraps around the box (a bed) does not move rigidly: its long
            // sways and breathing are removed bin by bin, as for the non-members.
            bin_relative(fit, o, now, dim, n_lat, bins, &mut r2);
        } else {
            let res = rigid_residuals(
                fit,
                &o.positions,
                now,
                dim,
                &frame.periodic,
                &frame.box_size,
            );
            for (&i, d) in fit.iter().zip(&res) {
                r2[i] = d[..n_lat].iter().map(|x| x * x).sum();
            }
        }
        if !stayed.is_empty() {
            // Grains that left: displacement less the cluster's mean translation.
            let shift: Vec<f64> = (0..n_lat)
                .map(|k| {
                    stayed
                        .iter()
                        .map(|&i| now[i * dim + k] - o.positions[i * dim + k])
                        .sum::<f64>()
                        / stayed.len() as f64
                })
                .collect();
            for &i in &left {
                r2[i] = (0..n_lat)
                    .map(|k| (now[i * dim + k] - o.positions[i * dim + k] - shift[k]).powi(2))
                    .sum();
            }
        }
    }
    r2
}

/// Per grain, the squared lateral displacement since origin `o` relative to the mean
/// displacement of the grains it was bonded to at the origin (its cage; `None` for a grain
/// without a lasting bond there). Against its own neighbours a grain of a solid piece rattles in
/// place however the piece drifts, turns or bends, and a grain that left its neighbours (a
/// liquid's, or a solid's mobile surface grain) shows it.
fn cage_relative(o: &Origin, now: &[f64], dim: usize, n_lat: usize) -> Vec<Option<f64>> {
    let n = o.cluster.len();
    let mut sum = vec![0.0; n * n_lat];
    let mut count = vec![0usize; n];
    let disp = |i: usize, k: usize| now[i * dim + k] - o.positions[i * dim + k];
    for &(i, j) in &o.bonds {
        let (i, j) = (i as usize, j as usize);
        for k in 0..n_lat {
            sum[i * n_lat + k] += disp(j, k);
            sum[j * n_lat + k] += disp(i, k);
        }
        count[i] += 1;
        count[j] += 1;
    }
    (0..n)
        .map(|i| {
            (count[i] > 0).then(|| {
                (0..n_lat)
                    .map(|k| (disp(i, k) - sum[i * n_lat + k] / count[i] as f64).powi(2))
                    .sum()
            })
        })
        .collect()
}

/// For the grains `group`, the squared lateral displacement since origin `o` relative to the mean
/// displacement of the grains of `group` that started in the same bin, into `r2`.
fn bin_relative(
    group: &[usize],
    o: &Origin,
    now: &[f64],
    dim: usize,
    n_lat: usize,
    bins: usize,
    r2: &mut [f64],
) {
    let mut mean = vec![0.0; bins * n_lat];
    let mut count = vec![0.0f64; bins];
    for &i in group {
        let b = o.bin[i] as usize;
        count[b] += 1.0;
        for k in 0..n_lat {
            mean[b * n_lat + k] += now[i * dim + k] - o.positions[i * dim + k];
        }
    }
    for &i in group {
        let b = o.bin[i] as usize;
        r2[i] = (0..n_lat)
            .map(|k| {
                let d = now[i * dim + k] - o.positions[i * dim + k];
                (d - mean[b * n_lat + k] / count[b]).powi(2)
            })
            .sum();
    }
}

/// Sums of one field per bin over blocks.
pub(crate) fn field_sums(blocks: &[Block], bins: usize, f: usize) -> Vec<f64> {
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

    /// Settings with a bond age of `bond_time` and clusters of at least two grains.
    fn settings(dt: f64, block: f64, lag: f64, bond_time: f64) -> LateralSettings {
        LateralSettings {
            wet: true,
            unit: 1.0,
            sample_interval: dt,
            block_time: block,
            lag,
            bond_time,
            cluster_min_size: 2,
        }
    }

    #[test]
    fn mobility_lag_is_set_in_time_and_displacements_unwrap() {
        // Two grains in one bin moving apart at unit speed each along x across the periodic
        // edge; dt = 0.5, lag 2: each moves 2 against their mean (0) per lag, whatever the
        // wraps.
        let mut o = LateralObserver::new(LateralBins::new(1, 20.0), settings(0.5, 1.0, 2.0, 1.0));
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
        let mut o = LateralObserver::new(LateralBins::new(1, 20.0), settings(0.5, 1.0, 2.0, 1.0));
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
    fn member_temperature_ignores_passing_grains() {
        // Bin 0 holds a bonded, still pair and a fast unbonded grain: the bin's temperature
        // of all grains is high, of the members zero. The pair becomes a cluster once its
        // bridge is one time unit old (the third sample).
        let x = [(1.0, 1.0), (2.0, 1.0), (3.0, 5.0)];
        let v = [(0.0, 0.0), (0.0, 0.0), (10.0, 0.0)];
        let mut o = LateralObserver::new(LateralBins::new(4, 20.0), settings(0.5, 10.0, 2.0, 1.0));
        for k in 0..3 {
            o.observe(&frame_2d(&x, &v, vec![(0, 1)], 0.5 * k as f64));
        }
        let b = &o.blocks[0];
        assert!(b.get(0, field::T_ALL) / b.get(0, field::T_ALL_W) > 5.0);
        assert_eq!(b.get(0, field::T_CL), 0.0);
        assert_eq!(b.get(0, field::T_CL_W), 2.0);
        assert_eq!(b.get(0, field::CLUSTERED), 2.0);
        assert_eq!(b.get(0, field::BRIDGES), 3.0);
    }

    #[test]
    fn bin_temperature_is_unbiased() {
        // Two grains at velocities (1, 0) and (-1, 0), m = 1, 2D: about their mean (0) the
        // unbiased estimate is sum |v - <v>|^2 / (D (n - 1)) = 2 / 2 = 1; the biased one (n)
        // would give 1/2.
        let x = [(1.0, 1.0), (2.0, 1.0)];
        let v = [(1.0, 0.0), (-1.0, 0.0)];
        let mut o = LateralObserver::new(LateralBins::new(1, 20.0), settings(0.5, 10.0, 2.0, 1.0));
        o.observe(&frame_2d(&x, &v, vec![], 0.0));
        let b = &o.blocks[0];
        let t = b.get(0, field::T_ALL) / b.get(0, field::T_ALL_W);
        assert!((t - 1.0).abs() < 1e-12, "{t}");
    }

    #[test]
    fn a_turning_drop_is_still_and_its_rattle_is_caged() {
        // Safeguard for the rigid-motion reference: a drop of four bonded grains turning at
        // 0.2 rad per time unit about its centre (radius ~1) has no displacement relative to
        // itself; measured against the bin mean instead, its grains would move ~0.4 per lag.
        let mut o = LateralObserver::new(LateralBins::new(1, 20.0), settings(0.25, 10.0, 4.0, 0.5));
        let bonds = vec![(0, 1), (1, 2), (2, 3), (3, 0)];
        for k in 0..200 {
            let t = 0.25 * k as f64;
            let th = 0.2 * t;
            let pts: Vec<(f64, f64)> = (0..4)
                .map(|q| {
                    let a = th + q as f64 * std::f64::consts::FRAC_PI_2;
                    (10.0 + 0.3 * t + a.cos(), 5.0 + a.sin())
                })
                .collect();
            o.observe(&frame_2d(&pts, &[(0.0, 0.0); 4], bonds.clone(), t));
        }
        let cl = field_sums(&o.blocks, 1, field::MSD_CL);
        let n = field_sums(&o.blocks, 1, field::MSD_CL_N);
        assert!(n[0] > 100.0, "{n:?}");
        assert!(cl[0] / n[0] < 1e-20, "{}", cl[0] / n[0]);
    }

    #[test]
    fn a_bed_wrapping_the_box_sways_bin_by_bin() {
        // Safeguard for clusters that wrap around the box: a bonded row of 20 grains around the
        // 20-wide box whose lateral positions sway by 0.5 sin(2 pi x / L) sin(t): against the
        // bin means (10 bins of 2) the residual is the sway's variation within a bin, against the
        // cluster's mean translation it would be the whole sway (mean square ~0.12 per lag).
        let mut o =
            LateralObserver::new(LateralBins::new(10, 20.0), settings(0.25, 10.0, 4.0, 0.5));
        let bonds: Vec<(usize, usize)> = (0..20).map(|i| (i, (i + 1) % 20)).collect();
        for k in 0..200 {
            let t = 0.25 * k as f64;
            let pts: Vec<(f64, f64)> = (0..20)
                .map(|i| {
                    let x0 = 0.5 + i as f64;
                    let u = 0.5 * (std::f64::consts::TAU * x0 / 20.0).sin() * t.sin();
                    ((x0 + u).rem_euclid(20.0), 1.0)
                })
                .collect();
            o.observe(&frame_2d(&pts, &[(0.0, 0.0); 20], bonds.clone(), t));
        }
        let cl: f64 = field_sums(&o.blocks, 10, field::MSD_CL).iter().sum();
        let n: f64 = field_sums(&o.blocks, 10, field::MSD_CL_N).iter().sum();
        assert!(n > 100.0, "{n}");
        assert!(cl / n < 0.02, "{}", cl / n);
    }

    /// Of the member displacements measured against their cage, the fraction within each
    /// edge, after 200 samples of `pts(t)` (bonds `bonds`, one bin).
    fn cage_fractions(pts: &dyn Fn(f64) -> Vec<(f64, f64)>, bonds: &[(usize, usize)]) -> Vec<f64> {
        let mut o = LateralObserver::new(LateralBins::new(1, 20.0), settings(0.25, 10.0, 4.0, 0.5));
        for k in 0..200 {
            let t = 0.25 * k as f64;
            let p = pts(t);
            o.observe(&frame_2d(&p, &vec![(0.0, 0.0); p.len()], bonds.to_vec(), t));
        }
        let n = field_sums(&o.blocks, 1, field::CAGE_N)[0];
        assert!(n > 100.0, "{n}");
        (0..CAGE_EDGES.len())
            .map(|k| field_sums(&o.blocks, 1, field::CAGE_WITHIN + k)[0] / n)
            .collect()
    }

    #[test]
    fn grains_that_keep_their_neighbours_stay_in_their_cage() {
        // Two rows of three bonded grains sliding apart at 0.1 per time unit each, held in one
        // cluster by the bond 2-3: against the cluster's rigid motion every grain moves 0.4 per
        // lag of 4, against its bonded neighbours only the two grains of the link bond do.
        let bonds = [(0, 1), (1, 2), (2, 3), (3, 4), (4, 5)];
        let slide = |t: f64| -> Vec<(f64, f64)> {
            (0..6)
                .map(|i| {
                    let v = if i < 3 { -0.1 } else { 0.1 };
                    ((8.0 + i as f64 + v * t).rem_euclid(20.0), 1.0)
                })
                .collect()
        };
        let f = cage_fractions(&slide, &bonds);
        assert!(f.iter().all(|&x| (x - 4.0 / 6.0).abs() < 1e-12), "{f:?}");
        // Grains that wander about by 0.5 independently of their bonded neighbours leave
        // their cage: a liquid's grains.
        let wander = |t: f64| -> Vec<(f64, f64)> {
            (0..6)
                .map(|i| (8.0 + i as f64 + 0.5 * (0.3 * t + 1.7 * i as f64).sin(), 1.0))
                .collect()
        };
        let f = cage_fractions(&wander, &bonds);
        assert!(f[2] < 0.2, "{f:?}");
    }

    #[test]
    fn blocks_merge_and_keep_every_sample() {
        let mut o = LateralObserver::new(LateralBins::new(1, 20.0), settings(0.1, 0.1, 1.0, 1.0));
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
