//! Event source of particle pairs: hard-core collisions and, with bridges (`WET`), the
//! thin-thread bridges and their well events (docs/model.md 2.1, 3.2). [`PairSource`] owns each
//! particle's earliest pair event and the bond lists.
//!
//! Prediction: all particles feel the same gravity, so the relative motion of two particles in
//! the same slab is a straight line and the contact time the root of a quadratic (Eq. B.3); two
//! particles in slabs of different force (shear drive) need the quartics of
//! [`super::shear::pair_times`]. A particle's pair event is the earliest over the partners in
//! its neighbourhood of cells; it remembers the partner's velocity-change count at prediction
//! time, and the scheduler drops it (and re-predicts) if the count moved on (lazy invalidation).
//!
//! Safeguards (each tested in `crates/core/tests/engine_safeguards.rs`): an overlapping pair
//! that approaches collides now, one that separates is left alone (B.5.6); a pair half a
//! periodic box apart (four cells) is predicted through both images; collapse: the TC model and
//! the rebound floor of `physics::contact::rebound_speed`; a pair grazing the concave well wall
//! leaves it at least at the rebound floor.

use super::bodies::{Bodies, Vector, permute_in_place, vec_bytes};
use super::cell_source::{CellSource, Neighbourhood};
use super::cells::{BATCH, CellGrid};
use super::event::{Event, EventSource, NONE, PairEvent, PairKind};
use super::shear::pair_times;
use super::slabs::SlabSource;
use crate::physics::capillary::{WellOutcome, well_outcome};
use crate::physics::contact::rebound_speed;
use crate::scene::{RuptureRule, Scene};
use crate::sim::books::{EnergyLedger, EventCounts};

/// Fraction of a periodic box edge beyond which a pair is also predicted through its other
/// image (see `PairSource::predict_pair_from`): above the `0.4 L` that partners in adjacent
/// cells reach with five cells, below the `0.5 L` tie of four.
const FAR_IMAGE: f64 = 0.45;
/// Most bridges one particle may hold (a guard: more means the packing is unphysical).
pub const MAX_BONDS: usize = 16;

/// Contact and bridge parameters of the pair source.
#[derive(Debug, Clone, Copy)]
pub struct PairParams {
    pub eps: f64,
    pub tc: f64,
    pub min_rebound: f64,
    pub s_crit: f64,
    pub e_cb: f64,
    pub rule: RuptureRule,
}

/// Each particle's earliest pair event, and the bonds (empty unless `WET`).
#[derive(Debug, Clone)]
pub struct PairSource<const D: usize, const WET: bool> {
    pub p: PairParams,
    pub ev: Vec<PairEvent>,
    /// Bond partners of particle `i` in `bonds[i * MAX_BONDS..][..bond_len[i]]`.
    pub bonds: Vec<u32>,
    pub bond_len: Vec<u8>,
}

impl<const D: usize, const WET: bool> PairSource<D, WET> {
    /// The source of a validated scene for `n` particles.
    pub fn new(scene: &Scene, n: usize) -> Self {
        Self {
            p: PairParams {
                eps: scene.contact.restitution,
                tc: scene.engine.tc,
                min_rebound: scene.engine.min_rebound_speed,
                s_crit: scene.s_crit(),
                e_cb: scene.e_cb(),
                rule: scene.rupture_rule(),
            },
            ev: vec![PairEvent::NEVER; n],
            bonds: vec![NONE; if WET { n * MAX_BONDS } else { 0 }],
            bond_len: vec![0; if WET { n } else { 0 }],
        }
    }

    /// Heap bytes of each per-particle array (`wetgran-bench memory`).
    pub fn memory(&self) -> Vec<(&'static str, usize)> {
        vec![
            ("pairs.ev", vec_bytes(&self.ev)),
            ("pairs.bonds", vec_bytes(&self.bonds)),
            ("pairs.bond_len", vec_bytes(&self.bond_len)),
        ]
    }

    #[inline]
    pub fn bonded(&self, i: usize, j: usize) -> bool {
        self.bonds_of(i).iter().any(|&b| b as usize == j)
    }

    /// Adds `j` to `i`'s bonds (`who` and `time` name the particle in the guard's message).
    pub fn add_bond_half(&mut self, i: usize, j: usize, who: u32, time: f64) {
        let len = self.bond_len[i] as usize;
        assert!(
            len < MAX_BONDS,
            "particle {who} (scene index) would hold more than {MAX_BONDS} bridges at t = {time}: \
             packing is unphysical",
        );
        self.bonds[i * MAX_BONDS + len] = j as u32;
        self.bond_len[i] += 1;
    }

    pub fn remove_bond_half(&mut self, i: usize, j: usize) {
        if let Some(k) = self.bonds_of(i).iter().position(|&b| b as usize == j) {
            let (base, last) = (i * MAX_BONDS, self.bond_len[i] as usize - 1);
            self.bonds[base + k] = self.bonds[base + last];
            self.bonds[base + last] = NONE;
            self.bond_len[i] -= 1;
        }
    }

    #[inline]
    pub fn bonds_of(&self, i: usize) -> &[u32] {
        if !WET {
            return &[];
        }
        let base = i * MAX_BONDS;
        &self.bonds[base..base + self.bond_len[i] as usize]
    }

    pub fn bridge_count(&self) -> usize {
        self.bond_len.iter().map(|&l| l as usize).sum::<usize>() / 2
    }

    /// Earliest pair event of `i`, with state `(xi, vi)` at time `t`, with `j`. `wrap`: take
    /// the minimum image of the separation (`false` only where it cannot change it, see
    /// [`CellGrid::interior_needs_no_image`]).
    #[inline]
    pub fn predict_pair_from<const G: bool, const S: bool>(
        &self,
        bodies: &Bodies<D, G, S>,
        slabs: &SlabSource,
        xi: &Vector<D>,
        vi: &Vector<D>,
        i: usize,
        j: usize,
        t: f64,
        wrap: bool,
    ) -> Option<(f64, PairKind)> {
        let (xj, vj) = bodies.state_at(j, t);
        let r = if wrap {
            bodies.min_image(xi - xj)
        } else {
            xi - xj
        };
        let v = vi - vj;
        let mut best = self.predict_image(bodies, slabs, &r, &v, i, j, t);
        // Safeguard: with four cells on a periodic axis two partners may sit half a box apart,
        // where the minimum image is a tie and the collision may come through the other image
        // (no later cell crossing re-predicts them). So a pair beyond `FAR_IMAGE` of the box is
        // also predicted through its other image(s). With five cells or more (always without
        // `wrap`) partners are at most `0.4 L` apart and this never runs.
        let far = |k: usize| bodies.periodic[k] && r[k].abs() >= FAR_IMAGE * bodies.size[k];
        if wrap && (0..D).any(far) {
            for mask in 1..1usize << D {
                if (0..D).any(|k| mask >> k & 1 == 1 && !far(k)) {
                    continue;
                }
                let mut other = r;
                for k in (0..D).filter(|k| mask >> k & 1 == 1) {
                    other[k] -= bodies.size[k].copysign(r[k]);
                }
                if let Some((t2, PairKind::Collide)) =
                    self.predict_image(bodies, slabs, &other, &v, i, j, t)
                    && best.is_none_or(|(tb, _)| t2 < tb)
                {
                    best = Some((t2, PairKind::Collide));
                }
            }
        }
        best
    }

    /// Earliest pair event of `i` and `j` at time `t` with separation `r` (one periodic image)
    /// and relative velocity `v`.
    #[inline]
    fn predict_image<const G: bool, const S: bool>(
        &self,
        bodies: &Bodies<D, G, S>,
        slabs: &SlabSource,
        r: &Vector<D>,
        v: &Vector<D>,
        i: usize,
        j: usize,
        t: f64,
    ) -> Option<(f64, PairKind)> {
        let (r, v) = (*r, *v);
        // Same force on both: relative motion is a straight line (Eq. B.3).
        if S && bodies.accel[i] != bodies.accel[j] {
            return self.predict_sheared_pair(bodies, slabs, &r, &v, i, j, t);
        }
        let b = r.dot(&v);
        if !WET && b >= 0.0 {
            return None;
        }
        let rr = r.norm_squared();
        let sigma = bodies.body[i].r + bodies.body[j].r;
        let vv = v.norm_squared();
        let mut best: Option<(f64, PairKind)> = None;
        if b < 0.0 {
            let c = rr - sigma * sigma;
            if c <= 0.0 {
                // Overlap safeguard: approaching while overlapping collides now.
                return Some((t, PairKind::Collide));
            }
            let disc = b * b - vv * c;
            if disc > 0.0 {
                // Smaller root of |r + v dt| = sigma, cancellation-free.
                best = Some((t + c / (-b + disc.sqrt()), PairKind::Collide));
            }
        }
        if WET
            && self.bonded(i, j)
            && let Some(tw) = Self::well_time(b, rr, vv, sigma + self.p.s_crit, t)
            && best.is_none_or(|(tb, _)| tw < tb)
        {
            best = Some((tw, PairKind::Well));
        }
        best
    }

    /// Pair events of `i` and `j` in slabs of different force (shear drive): the quartics of
    /// [`super::shear::pair_times`], solved up to the first slab exit of either particle.
    fn predict_sheared_pair<const G: bool, const S: bool>(
        &self,
        bodies: &Bodies<D, G, S>,
        slabs: &SlabSource,
        r: &Vector<D>,
        v: &Vector<D>,
        i: usize,
        j: usize,
        t: f64,
    ) -> Option<(f64, PairKind)> {
        let horizon = (slabs.ev[i].time.min(slabs.ev[j].time) - t).max(0.0);
        let sigma = bodies.body[i].r + bodies.body[j].r;
        let lambda = (WET && self.bonded(i, j)).then_some(sigma + self.p.s_crit);
        let (contact, well) = pair_times::<D>(
            &(*r).into(),
            &(*v).into(),
            bodies.accel[i] - bodies.accel[j],
            sigma,
            lambda,
            horizon,
        );
        match (contact, well) {
            (Some(c), Some(w)) if w < c => Some((t + w, PairKind::Well)),
            (Some(c), _) => Some((t + c, PairKind::Collide)),
            (None, Some(w)) => Some((t + w, PairKind::Well)),
            (None, None) => None,
        }
    }

    /// Scans the cells of `hood` around particle `i` (at time `t`) and lowers its pair event
    /// if a partner there gives an earlier one. Cells are visited in the order of `hood`, so
    /// that among equal times the same partner wins on every path.
    pub fn scan<const G: bool, const S: bool>(
        &mut self,
        i: usize,
        hood: &Neighbourhood<D>,
        bodies: &Bodies<D, G, S>,
        cells: &CellSource<D>,
        slabs: &SlabSource,
        t: f64,
    ) {
        let grid = &cells.grid;
        let c = cells.cell[i];
        let no_shift = [0.0; D];
        if grid.is_interior(&c) {
            let base = grid.linear(&c) as isize;
            let around = hood.deltas.iter().map(|&d| ((base + d) as usize, no_shift));
            if !S && grid.interior_needs_no_image {
                let zero = [[0.0; D]; 27];
                let around = around.map(|(cell, _)| (cell, 0));
                self.scan_dry(i, around, bodies, grid, &zero, t, false);
            } else {
                let wrap = !grid.interior_needs_no_image;
                self.scan_cells(i, around, bodies, grid, slabs, t, wrap, false);
            }
        } else if !S
            && grid.interior_needs_no_image
            && let Some(class) = grid.wall_class(&c)
        {
            // Next to a wall, inside along every periodic axis: the interior index changes that
            // stay inside the walls, in the order of `hood`, all with image shift 0.
            let base = grid.linear(&c) as isize;
            let around = hood.deltas_by_wall_class[class]
                .iter()
                .map(|&d| ((base + d) as usize, 0));
            let zero = [[0.0; D]; 27];
            self.scan_dry(i, around, bodies, grid, &zero, t, false);
        } else if grid.interior_needs_no_image {
            // Boundary cell, every periodic axis of five cells or more: a partner across a
            // periodic face is exactly one box edge away (`CellGrid::axis_parts_and_shifts`),
            // so the known shift gives the minimum image and no pair is far.
            let (parts, shifts) = grid.axis_parts_and_shifts(&c, &bodies.size);
            if !S {
                // One force for all: each cell's offset is its partners' tag into the shifts.
                let mut table = [[0.0; D]; 27];
                for (m, o) in hood.offsets.iter().enumerate() {
                    table[m] = CellGrid::<D>::shift_of(&shifts, o);
                }
                let around = hood.offsets.iter().enumerate().filter_map(|(m, o)| {
                    CellGrid::<D>::from_parts(&parts, o).map(|cell| (cell, m as u8))
                });
                self.scan_dry(i, around, bodies, grid, &table, t, true);
                return;
            }
            let around = hood.offsets.iter().filter_map(|o| {
                CellGrid::<D>::from_parts(&parts, o)
                    .map(|cell| (cell, CellGrid::<D>::shift_of(&shifts, o)))
            });
            self.scan_cells(i, around, bodies, grid, slabs, t, false, true);
        } else {
            let parts = grid.axis_parts(&c);
            let around = hood
                .offsets
                .iter()
                .filter_map(|o| CellGrid::<D>::from_parts(&parts, o).map(|cell| (cell, no_shift)));
            self.scan_cells(i, around, bodies, grid, slabs, t, true, false);
        }
    }

    /// The pair predictions of `i` with every particle of the cells `around`, in order. Each
    /// cell comes with the image shift of its partners (`shifted`: added to the separation on
    /// the axes where it is not zero; the minimum image then needs no `wrap`).
    fn scan_cells<const G: bool, const S: bool>(
        &mut self,
        i: usize,
        around: impl Iterator<Item = (usize, [f64; D])>,
        bodies: &Bodies<D, G, S>,
        grid: &CellGrid<D>,
        slabs: &SlabSource,
        t: f64,
        wrap: bool,
        shifted: bool,
    ) {
        let this = &*self;
        let mut best = this.ev[i];
        let (xi, vi) = (bodies.body[i].x, bodies.body[i].v);
        if shifted {
            for (cell, shift) in around {
                grid.for_each_in(cell, |j| {
                    this.consider(
                        bodies, slabs, &xi, &vi, i, j, t, &shift, &mut best, wrap, shifted,
                    );
                });
            }
        } else {
            // Batched, so that the cells' occupancies cost no mispredicted branches.
            let no_shift = [0.0; D];
            grid.for_each_batch(around.map(|(cell, _)| (cell, 0)), false, |batch, _| {
                for &j in batch {
                    this.consider(
                        bodies, slabs, &xi, &vi, i, j as usize, t, &no_shift, &mut best, wrap,
                        shifted,
                    );
                }
            });
        }
        self.ev[i] = best;
    }

    /// The scan under one force for all and without minimum image (see [`Self::scan`]):
    /// `around` gives each neighbour cell with the index of its partners' image shift in
    /// `table` (used if `shifted`). The partners are gathered first ([`CellGrid::gather`]: the
    /// cells' occupancies cost no mispredicted branches), then predicted in one loop that
    /// chooses each contact time after the whole arithmetic ([`Self::dry_time`]); wet, a
    /// bonded partner's well event follows ([`Self::well_time`]). Among equal times the first
    /// in the cells' order wins, as in [`Self::scan_cells`]: the same events, bit for bit.
    fn scan_dry<const G: bool, const S: bool>(
        &mut self,
        i: usize,
        mut around: impl Iterator<Item = (usize, u8)>,
        bodies: &Bodies<D, G, S>,
        grid: &CellGrid<D>,
        table: &[[f64; D]; 27],
        t: f64,
        shifted: bool,
    ) {
        let (xi, vi, ri) = (bodies.body[i].x, bodies.body[i].v, bodies.body[i].r);
        let (mut best_t, mut best_j, mut best_well) = (self.ev[i].time, NONE, false);
        // Wet: the bonds of `i`, searched whole for each partner (no early exit to mispredict).
        let bonds = self.bonds_of(i);
        let s_crit = self.p.s_crit;
        let mut gather = grid.gather_start();
        let mut buf = [0u32; BATCH];
        let mut tags = [0u8; BATCH];
        loop {
            let (len, more) = grid.gather(&mut around, &mut gather, &mut buf, &mut tags, shifted);
            for m in 0..len.min(BATCH) {
                let j = buf[m];
                let shift = &table[if shifted { tags[m] as usize } else { 0 }];
                let (mut tj, b, rr, vv, sigma) =
                    Self::dry_time(bodies, &xi, &vi, ri, i, j, t, shift, shifted);
                let mut well = false;
                if WET && bonds.iter().fold(false, |a, &k| a | (k == j)) {
                    // As in `predict_image`: the well wins only if strictly earlier (an
                    // overlapping pair's contact at `t` wins, as the early return there).
                    if let Some(tw) = Self::well_time(b, rr, vv, sigma + s_crit, t)
                        && tw < tj
                    {
                        tj = tw;
                        well = true;
                    }
                }
                let better = tj < best_t;
                best_t = if better { tj } else { best_t };
                best_j = if better { j } else { best_j };
                best_well = if better { well } else { best_well };
            }
            if !more {
                break;
            }
        }
        if best_j != NONE {
            let j = best_j as usize;
            let kind = if best_well {
                PairKind::Well
            } else {
                PairKind::Collide
            };
            self.ev[i] = PairEvent::new(best_t, best_j, bodies.count[j], kind);
        }
    }

    /// Time of the well event of a bonded pair (`lambda = sigma + s_crit`) from `b`, `r^2`,
    /// `v^2` at `t` (both scans: [`Self::predict_image`] and [`Self::scan_dry`]).
    fn well_time(b: f64, rr: f64, vv: f64, lambda: f64, t: f64) -> Option<f64> {
        let c = rr - lambda * lambda;
        let dt = if b > 0.0 && c >= 0.0 {
            // At or beyond the well edge (round-off) and separating: the event is now.
            Some(0.0)
        } else if vv > 0.0 {
            // Larger root of |r + v dt| = lambda. Right after a bounce off the well wall the
            // pair sits on the edge (c may be +round-off): the root is then the next exit, not
            // "none" (else a bond could stretch past s_crit).
            let disc = (b * b - vv * c).max(0.0);
            Some(if b > 0.0 {
                -c / (b + disc.sqrt())
            } else {
                (-b + disc.sqrt()) / vv
            })
        } else {
            None
        };
        dt.map(|dt| t + dt)
    }

    /// The time of the contact of `i` (radius `ri`) with `j` (`+inf` if none, or if
    /// `j == i`), and the `b`, `r^2`, `v^2`, `sigma` it used, for a pair under one force for
    /// all and without minimum image (`shift`: the partner's image shift, if `shifted`). Every
    /// partner pays the whole arithmetic and the result is chosen without a branch (whether a
    /// pair meets is a coin toss a processor mispredicts: docs/performance.md, "Ideas kept and
    /// rejected"); the same operations as [`Self::predict_image`] (Eq. B.3, overlap: `t`
    /// itself), so the same bits.
    fn dry_time<const G: bool, const S: bool>(
        bodies: &Bodies<D, G, S>,
        xi: &Vector<D>,
        vi: &Vector<D>,
        ri: f64,
        i: usize,
        j: u32,
        t: f64,
        shift: &[f64; D],
        shifted: bool,
    ) -> (f64, f64, f64, f64, f64) {
        let (xj, vj) = bodies.state_at(j as usize, t);
        let mut r = xi - xj;
        if shifted {
            // A zero shift can only turn `-0.0` into `+0.0`, which nothing below tells apart.
            for k in 0..D {
                r[k] += shift[k];
            }
        }
        let v = vi - vj;
        let b = r.dot(&v);
        let rr = r.norm_squared();
        let sigma = ri + bodies.body[j as usize].r;
        let vv = v.norm_squared();
        let c = rr - sigma * sigma;
        let disc = b * b - vv * c;
        // The smaller root, cancellation-free; overlapping and approaching (`c <= 0`): now.
        let dt = (c / (-b + disc.max(0.0).sqrt())).max(0.0);
        // Negated tests, as in `predict_image`: not approaching or not meeting is a miss.
        #[allow(clippy::neg_cmp_op_on_partial_ord)]
        let miss = !(b < 0.0) | ((c > 0.0) & !(disc > 0.0)) | (j as usize == i);
        let never = if miss { f64::INFINITY } else { 0.0 };
        (t + dt + never, b, rr, vv, sigma)
    }

    /// Lowers `best` (the pair event of `i`, state `(xi, vi)` at `t`) if partner `j` gives an
    /// earlier one (`j == i` is skipped). `shift`: see [`Self::scan_cells`].
    fn consider<const G: bool, const S: bool>(
        &self,
        bodies: &Bodies<D, G, S>,
        slabs: &SlabSource,
        xi: &Vector<D>,
        vi: &Vector<D>,
        i: usize,
        j: usize,
        t: f64,
        shift: &[f64; D],
        best: &mut PairEvent,
        wrap: bool,
        shifted: bool,
    ) {
        if j == i {
            return;
        }
        let predicted = if shifted {
            // Bit for bit the minimum image where that shifts by exactly `shift`
            // (`Bodies::min_image` adds or subtracts the box edge, the same operation), and
            // such a pair is never far.
            let (xj, vj) = bodies.state_at(j, t);
            let mut r = xi - xj;
            for k in (0..D).filter(|&k| shift[k] != 0.0) {
                r[k] += shift[k];
            }
            self.predict_image(bodies, slabs, &r, &(vi - vj), i, j, t)
        } else {
            self.predict_pair_from(bodies, slabs, xi, vi, i, j, t, wrap)
        };
        if let Some((tj, kind)) = predicted
            && tj < best.time
        {
            *best = PairEvent::new(tj, j as u32, bodies.count[j], kind);
        }
    }

    /// Unit normal from `j` to `i` and the normal relative velocity, both brought to `t`; both
    /// particles change course.
    fn normal<const G: bool, const S: bool>(
        bodies: &mut Bodies<D, G, S>,
        i: usize,
        j: usize,
        t: f64,
    ) -> (Vector<D>, f64) {
        bodies.advance(i, t);
        bodies.advance(j, t);
        let r = bodies.min_image(bodies.body[i].x - bodies.body[j].x);
        let n = r / r.norm();
        bodies.bump(i);
        bodies.bump(j);
        (n, (bodies.body[i].v - bodies.body[j].v).dot(&n))
    }

    /// Pair collision at `t` with restitution (Eqs. 2.3-2.4) and, if wet, bridge formation.
    pub fn collide<const G: bool, const S: bool>(
        &mut self,
        i: usize,
        j: usize,
        t: f64,
        bodies: &mut Bodies<D, G, S>,
        ledger: &mut EnergyLedger,
        counts: &mut EventCounts,
    ) {
        let (n, u) = Self::normal(bodies, i, j, t);
        if u < 0.0 {
            let since = bodies.since_last_collision(i, j, t);
            let u_out = rebound_speed(-u, self.p.eps, since, self.p.tc, self.p.min_rebound);
            Self::kick(bodies, i, j, &n, u_out - u);
            ledger.book_restitution(0.5 * bodies.mass, -u, self.p.eps, u_out);
            bodies.record_collision(i, t);
            bodies.record_collision(j, t);
        }
        counts.pair_collisions += 1;
        if WET && !self.bonded(i, j) {
            self.add_bond_half(i, j, bodies.id[i], t);
            self.add_bond_half(j, i, bodies.id[j], t);
            counts.bridge_formations += 1;
        }
    }

    /// Bonded pair at `s = s_crit` at time `t`: bounce or rupture (docs/model.md 3.2).
    pub fn well_edge<const G: bool, const S: bool>(
        &mut self,
        i: usize,
        j: usize,
        t: f64,
        bodies: &mut Bodies<D, G, S>,
        ledger: &mut EnergyLedger,
        counts: &mut EventCounts,
    ) {
        let (n, u) = Self::normal(bodies, i, j, t);
        // Moving tangentially on the edge (u <= 0 by round-off): zero normal speed.
        let u_in = u.max(0.0);
        let u_out = match well_outcome(bodies.mass, u_in, self.p.e_cb, self.p.rule) {
            WellOutcome::Bounce(reflected) => {
                counts.well_bounces += 1;
                // A pair grazing the concave well wall would bounce ever more often: it leaves
                // at least at the rebound floor, the energy added booked with the remedies.
                let u_out = reflected.min(-self.p.min_rebound);
                ledger.added_by_collapse_remedies += 0.25 * bodies.mass * (u_out * u_out - u * u);
                u_out
            }
            WellOutcome::Rupture {
                new_normal_speed,
                energy,
            } => {
                self.remove_bond_half(i, j);
                self.remove_bond_half(j, i);
                ledger.dissipated_ruptures += energy;
                counts.bridge_ruptures += 1;
                new_normal_speed
            }
        };
        Self::kick(bodies, i, j, &n, u_out - u);
    }

    /// Changes the normal relative velocity by `du`, shared equally (equal masses).
    fn kick<const G: bool, const S: bool>(
        bodies: &mut Bodies<D, G, S>,
        i: usize,
        j: usize,
        n: &Vector<D>,
        du: f64,
    ) {
        bodies.body[i].v += n * (0.5 * du);
        bodies.body[j].v -= n * (0.5 * du);
    }
}

impl<const D: usize, const WET: bool> EventSource for PairSource<D, WET> {
    #[inline]
    fn candidate(&self, i: usize) -> Event {
        self.ev[i].event()
    }

    /// Renumbers the particles: new index `k` holds old particle `order[k]`; `new_of_old` maps
    /// back (partner indices in events and bonds are renamed).
    fn permute(&mut self, order: &[u32], new_of_old: &[u32]) {
        let n = order.len();
        permute_in_place(&mut self.ev, order);
        for e in &mut self.ev {
            e.rename_partner(new_of_old);
        }
        if WET {
            let mut bonds = vec![NONE; n * MAX_BONDS];
            let mut bond_len = vec![0u8; n];
            for (new, &old) in order.iter().enumerate() {
                let old = old as usize;
                let len = self.bond_len[old] as usize;
                for m in 0..len {
                    bonds[new * MAX_BONDS + m] =
                        new_of_old[self.bonds[old * MAX_BONDS + m] as usize];
                }
                bond_len[new] = len as u8;
            }
            self.bonds = bonds;
            self.bond_len = bond_len;
        }
    }
}
