//! Verlet neighbour list with skin, built from cells (a counting sort by cell), for the
//! time-driven engine: a half list in compressed-row form, row `i` holding the partners `j > i`
//! whose centres were closer than `R_i + R_j + s_crit + skin` at the build, sorted by `j`, each
//! entry with flags (in contact at the last force evaluation; bridged). The list is rebuilt when
//! some particle has moved more than `skin / 2` since the last build ([`needs_rebuild`]; then no
//! pair can have come into interaction from outside the range), the old flags carried into the
//! new rows by merging the sorted rows. Buffers are reused: a rebuild allocates only while the
//! list grows beyond its largest size so far.

/// Entry flag: the pair overlapped at the last force evaluation.
pub(crate) const CONTACT: u8 = 1;
/// Entry flag: the pair holds a capillary bridge (docs/model.md 3.1).
pub(crate) const BOND: u8 = 2;

/// The exact displacement test of the list runs at least every this many steps (it bounds the
/// round-off accumulated in the engine's displacement bound, `State::update_list`).
pub(crate) const EXACT_CHECK_EVERY: u32 = 1024;

/// Linked cells and the Verlet list.
#[derive(Debug, Clone)]
pub(crate) struct NeighbourList<const D: usize> {
    /// Row starts, `n + 1` entries.
    pub start: Vec<u32>,
    pub partner: Vec<u32>,
    /// Flags of each entry ([`CONTACT`], [`BOND`]).
    pub flags: Vec<u8>,
    /// The rows that hold at least one partner, ascending: the pair loop visits only these (in
    /// a dilute system most rows are empty, and testing each costs a mispredicted branch).
    pub rows: Vec<u32>,
    old_start: Vec<u32>,
    old_partner: Vec<u32>,
    old_flags: Vec<u8>,
    /// Positions (axis-major, as the engine's) at the last build.
    built_at: Vec<f64>,
    /// Cells per axis, cell width per axis, lower edge per axis.
    cells: [usize; D],
    width: [f64; D],
    lower: [f64; D],
    periodic: [bool; D],
    size: [f64; D],
    /// The particles binned by cell (counting sort): cell `c` holds
    /// `order[cell_start[c]..cell_start[c + 1]]`, ascending; `sorted_x` (axis-major) and
    /// `sorted_r` are their positions and radii in that order, so that the scan reads the
    /// candidates of a row of neighbour cells as one contiguous run.
    cell_start: Vec<u32>,
    order: Vec<u32>,
    sorted_x: Vec<f64>,
    sorted_r: Vec<f64>,
    /// Per particle: its cell at the last build; after a build, the fill cursor of the
    /// transposed list.
    scratch: Vec<u32>,
    /// Cell coordinates of each particle at the last build, `D` per particle.
    cell_at: Vec<u32>,
    /// Per axis `k` and cell coordinate `c`: the coordinates of the cells at offsets -1, 0, +1
    /// (`3 c + o + 1`), periodic images wrapped (a periodic axis has at least 3 cells, so no
    /// cell is named twice), [`NONE`] beyond a wall; the build walks the `3^D` neighbour cells
    /// from these tables, without a division.
    axis_next: [Vec<u32>; D],
    /// Stride of each axis in the cell index.
    stride: [usize; D],
    /// Reused buffers of the row scan (two halves).
    scan: [RowScan; 2],
    /// Interaction range beyond contact (`s_crit` or 0) plus the skin.
    extra: f64,
    skin: f64,
    pub builds: u64,
    /// The first flagged pair `(i, j)` missing from a rebuilt list (its flags dropped): it moved
    /// apart by more than the skin within one list's life, which only a blown-up run does. The
    /// engine's `sanity_check` reports it; the list goes on.
    pub(crate) lost_pair: Option<(usize, usize)>,
}

const NONE: u32 = u32::MAX;

/// From this many particles on, a build on a pool of several threads scans the two halves of the
/// rows at once (about 1000 instructions per particle pay back a hand-over of a few microseconds
/// from about a thousand particles on).
pub(crate) const PARALLEL_BUILD_MIN: usize = 1024;

/// The list check of a step (the engine's `State::update_list`, and each spatial domain's):
/// whether some particle at `x` has moved more than `half_skin` since the build at `built_at`.
/// The exact test runs only when `bound`, an upper bound on every displacement (the sum over
/// steps of the per-step moves' [`norm`]), reaches `half_skin` (less a relative margin of
/// `1e-6` for its round-off), or after [`EXACT_CHECK_EVERY`] steps (`since` counts them);
/// otherwise no particle can have moved that far, so the decision is the exact test's. After
/// an exact test that finds no rebuild, the bound restarts from the exact largest displacement.
pub(crate) fn needs_rebuild<const D: usize>(
    bound: &mut f64,
    since: &mut u32,
    half_skin: f64,
    x: &[f64],
    built_at: &[f64],
) -> bool {
    *since += 1;
    if *bound < half_skin * (1.0 - 1e-6) && *since < EXACT_CHECK_EVERY {
        return false;
    }
    *since = 0;
    let worst = max_displacement_sq::<D>(x, built_at);
    if worst > half_skin * half_skin {
        return true;
    }
    *bound = worst.sqrt();
    false
}

/// `sqrt(sum_k m_k^2)` of the largest moves `m_k` per axis of a step, summed in axis order.
pub(crate) fn norm<const D: usize>(moved: [f64; D]) -> f64 {
    let mut moved2 = 0.0;
    for m in moved {
        moved2 += m * m;
    }
    moved2.sqrt()
}

/// The largest squared displacement between positions `x` and `built_at` (axis-major, the
/// same length), without the periodic image: a particle that crossed a periodic face counts as
/// having moved by about `L` and triggers a (harmless, rare) rebuild; in exchange the loop,
/// in blocks of 64 particles, vectorises.
fn max_displacement_sq<const D: usize>(x: &[f64], built_at: &[f64]) -> f64 {
    let n = x.len() / D;
    let mut worst = 0.0f64;
    let mut acc = [0.0f64; 64];
    let mut i0 = 0;
    while i0 < n {
        let m = (n - i0).min(64);
        acc[..m].fill(0.0);
        for k in 0..D {
            let xs = &x[k * n + i0..k * n + i0 + m];
            let bs = &built_at[k * n + i0..k * n + i0 + m];
            for ((a, &xv), &bv) in acc[..m].iter_mut().zip(xs).zip(bs) {
                let d = xv - bv;
                *a += d * d;
            }
        }
        for &a in &acc[..m] {
            worst = if a > worst { a } else { worst };
        }
        i0 += m;
    }
    worst
}

/// The rows of part of a build: partners, flags, row lengths, the first lost flagged pair.
#[derive(Debug, Clone, Default)]
pub(crate) struct RowScan {
    partner: Vec<u32>,
    flags: Vec<u8>,
    len: Vec<u32>,
    lost: Option<(usize, usize)>,
}

impl RowScan {
    fn clear(&mut self) {
        self.partner.clear();
        self.flags.clear();
        self.len.clear();
        self.lost = None;
    }
}

impl<const D: usize> NeighbourList<D> {
    /// A list for `n` particles in a box of edges `size`; `lower`/`upper` bound the wall axes
    /// (the shaken floor and lid move), `range` is the largest `d_max + s_crit + skin`.
    pub(crate) fn new(
        n: usize,
        size: [f64; D],
        periodic: [bool; D],
        lower: [f64; D],
        upper: [f64; D],
        extra: f64,
        skin: f64,
        range: f64,
    ) -> Self {
        let mut cells = [1usize; D];
        let mut width = [0.0; D];
        for k in 0..D {
            let span = upper[k] - lower[k];
            cells[k] = ((span / range).floor() as usize).max(1);
            if periodic[k] {
                assert!(cells[k] >= 3, "periodic axis {k} needs >= 3 cells");
            }
            width[k] = span / cells[k] as f64;
        }
        let total: usize = cells.iter().product();
        Self {
            start: vec![0; n + 1],
            partner: Vec::with_capacity(8 * n),
            flags: Vec::with_capacity(8 * n),
            rows: Vec::with_capacity(n),
            old_start: vec![0; n + 1],
            old_partner: Vec::with_capacity(8 * n),
            old_flags: Vec::with_capacity(8 * n),
            built_at: vec![0.0; D * n],
            cells,
            width,
            lower,
            periodic,
            size,
            cell_start: vec![0; total + 1],
            order: vec![0; n],
            sorted_x: vec![0.0; D * n],
            sorted_r: vec![0.0; n],
            scratch: vec![0; n],
            cell_at: vec![0; D * n],
            axis_next: std::array::from_fn(|k| {
                let m = cells[k] as i64;
                (0..3 * m)
                    .map(|co| {
                        let v = co / 3 + co % 3 - 1;
                        if periodic[k] {
                            v.rem_euclid(m) as u32
                        } else if (0..m).contains(&v) {
                            v as u32
                        } else {
                            NONE
                        }
                    })
                    .collect()
            }),
            stride: std::array::from_fn(|k| cells[..k].iter().product()),
            scan: Default::default(),
            extra,
            skin,
            builds: 0,
            lost_pair: None,
        }
    }

    /// Positions (axis-major) at the last build.
    pub(crate) fn built_at(&self) -> &[f64] {
        &self.built_at
    }

    /// The skin (the list holds pairs up to `skin` beyond their interaction range).
    pub(crate) fn skin(&self) -> f64 {
        self.skin
    }

    fn cell_index(&self, c: &[usize; D]) -> usize {
        let mut idx = 0;
        for k in (0..D).rev() {
            idx = idx * self.cells[k] + c[k];
        }
        idx
    }

    /// Rebuilds the list from positions `x` (axis-major) and radii, keeping the flags of pairs
    /// that stay listed (a flagged pair always does: it is within `s_crit` of contact). The
    /// phases ([`Self::begin_build`], [`Self::scan_part`] per part, [`Self::finish_build`])
    /// are also run by the domains' team (`domains.rs`), with the same list.
    pub(crate) fn build(&mut self, x: &[f64], radius: &[f64]) {
        self.begin_build(x, radius);
        let [mut lo, mut hi] = self.take_scans();
        if radius.len() >= PARALLEL_BUILD_MIN && rayon::current_num_threads() > 1 {
            let this = &*self;
            rayon::join(
                || this.scan_part(radius, 0, &mut lo),
                || this.scan_part(radius, 1, &mut hi),
            );
        } else {
            self.scan_part(radius, 0, &mut lo);
            self.scan_part(radius, 1, &mut hi);
        }
        self.finish_build([lo, hi]);
    }

    /// First phase of a build: the old rows kept for the flags, the positions of the build
    /// (`x`, axis-major) and the particles binned into the cells (a counting sort by cell,
    /// ascending index within a cell), with their positions and radii in that order.
    pub(crate) fn begin_build(&mut self, x: &[f64], radius: &[f64]) {
        let n = self.scratch.len();
        self.builds += 1;
        std::mem::swap(&mut self.start, &mut self.old_start);
        std::mem::swap(&mut self.partner, &mut self.old_partner);
        std::mem::swap(&mut self.flags, &mut self.old_flags);
        self.partner.clear();
        self.flags.clear();
        self.rows.clear();
        self.built_at.copy_from_slice(x);
        self.cell_start.fill(0);
        for i in 0..n {
            let mut c = [0usize; D];
            for k in 0..D {
                let f = ((x[k * n + i] - self.lower[k]) / self.width[k]).floor();
                c[k] = if self.periodic[k] {
                    (f as i64).rem_euclid(self.cells[k] as i64) as usize
                } else {
                    f.clamp(0.0, (self.cells[k] - 1) as f64) as usize
                };
            }
            let idx = self.cell_index(&c);
            for k in 0..D {
                self.cell_at[D * i + k] = c[k] as u32;
            }
            self.scratch[i] = idx as u32;
            self.cell_start[idx + 1] += 1;
        }
        let total = self.cell_start.len() - 1;
        for c in 0..total {
            self.cell_start[c + 1] += self.cell_start[c];
        }
        // Fill: `cell_start[c]` runs to the end of cell `c` (the start of `c + 1`), then the
        // starts are shifted back by one cell.
        for i in 0..n {
            let c = self.scratch[i] as usize;
            let p = self.cell_start[c] as usize;
            self.cell_start[c] += 1;
            self.order[p] = i as u32;
            for k in 0..D {
                self.sorted_x[k * n + p] = x[k * n + i];
            }
            self.sorted_r[p] = radius[i];
        }
        for c in (1..=total).rev() {
            self.cell_start[c] = self.cell_start[c - 1];
        }
        self.cell_start[0] = 0;
    }

    /// The reused buffers of the two parts of the row scan (give them back through
    /// [`Self::finish_build`]).
    pub(crate) fn take_scans(&mut self) -> [RowScan; 2] {
        std::mem::take(&mut self.scan)
    }

    /// Second phase of a build: the rows of part `part` (0: the first `n / 2` particles, 1:
    /// the rest) into `out`. The parts are independent: two threads may scan them at once.
    pub(crate) fn scan_part(&self, radius: &[f64], part: usize, out: &mut RowScan) {
        let n = radius.len();
        let h = n / 2;
        let range = if part == 0 { 0..h } else { h..n };
        self.scan_rows(radius, range, out);
    }

    /// Last phase of a build: the parts' rows joined into the list, and the transposed list.
    pub(crate) fn finish_build(&mut self, parts: [RowScan; 2]) {
        let n = self.scratch.len();
        let mut i = 0;
        for part in &parts {
            let base = self.partner.len();
            self.partner.extend_from_slice(&part.partner);
            self.flags.extend_from_slice(&part.flags);
            let mut q = base;
            for &len in &part.len {
                self.start[i] = q as u32;
                if len > 0 {
                    self.rows.push(i as u32);
                }
                q += len as usize;
                i += 1;
            }
            if self.lost_pair.is_none() {
                self.lost_pair = part.lost;
            }
        }
        self.scan = parts;
        self.start[n] = self.partner.len() as u32;
    }

    /// The rows `range` of a build (after the binning) into `out` (cleared first): each row's
    /// partners, sorted, with the flags carried from the old list. The neighbour cells along
    /// axis 0 are adjacent in the cell order, so each row of up to three cells is read as one
    /// or two contiguous runs of the sorted arrays (two where a periodic axis wraps); `j > i`
    /// is combined with the distance test, so the loop has no data-dependent branch but the
    /// rare push.
    fn scan_rows(&self, radius: &[f64], range: std::ops::Range<usize>, out: &mut RowScan) {
        out.clear();
        let n = radius.len();
        let x = &self.built_at;
        let rest = 3usize.pow(D as u32 - 1);
        for i in range {
            let row_start = out.partner.len();
            let c: [usize; D] = std::array::from_fn(|k| self.cell_at[D * i + k] as usize);
            let xi: [f64; D] = std::array::from_fn(|k| x[k * n + i]);
            let ri = radius[i];
            // Runs of consecutive cells along axis 0: (first, last) coordinates.
            let mut runs = [(0u32, 0u32); 3];
            let mut nruns = 0;
            for &v in &self.axis_next[0][3 * c[0]..3 * c[0] + 3] {
                if v == NONE {
                    continue;
                }
                if nruns > 0 && runs[nruns - 1].1 + 1 == v {
                    runs[nruns - 1].1 = v;
                } else {
                    runs[nruns] = (v, v);
                    nruns += 1;
                }
            }
            'rows: for s in 0..rest {
                // Offset digits of `s` (base 3) on axes 1.., from the per-axis tables.
                let mut code = s;
                let mut base = 0;
                for k in 1..D {
                    let o = code % 3;
                    code /= 3;
                    let v = self.axis_next[k][3 * c[k] + o];
                    if v == NONE {
                        continue 'rows;
                    }
                    base += v as usize * self.stride[k];
                }
                for &(first, last) in &runs[..nruns] {
                    let p0 = self.cell_start[base + first as usize] as usize;
                    let p1 = self.cell_start[base + last as usize + 1] as usize;
                    let order = &self.order[p0..p1];
                    let rs = &self.sorted_r[p0..p1];
                    let xs: [&[f64]; D] =
                        std::array::from_fn(|k| &self.sorted_x[k * n + p0..k * n + p1]);
                    for (p, (&j, &rj)) in order.iter().zip(rs).enumerate() {
                        let mut r2 = 0.0;
                        for k in 0..D {
                            let mut d = xi[k] - xs[k][p];
                            if self.periodic[k] {
                                let l = self.size[k];
                                if d > 0.5 * l {
                                    d -= l;
                                } else if d < -0.5 * l {
                                    d += l;
                                }
                            }
                            r2 += d * d;
                        }
                        let cut = ri + rj + self.extra;
                        if (j as usize > i) & (r2 < cut * cut) {
                            out.partner.push(j);
                        }
                    }
                }
            }
            let row = row_start..out.partner.len();
            out.partner[row.clone()].sort_unstable();
            out.flags.resize(out.partner.len(), 0);
            out.len.push(row.len() as u32);
            // Carry the flags of the old row (both rows sorted).
            let (o0, o1) = (self.old_start[i] as usize, self.old_start[i + 1] as usize);
            if self.builds > 1 {
                let mut p = row.start;
                for q in o0..o1 {
                    let fl = self.old_flags[q];
                    if fl == 0 {
                        continue;
                    }
                    let pj = self.old_partner[q];
                    while p < row.end && out.partner[p] < pj {
                        p += 1;
                    }
                    if p < row.end && out.partner[p] == pj {
                        out.flags[p] = fl;
                    } else if out.lost.is_none() {
                        // Safeguard: a blown-up run must not panic the worker; the broken
                        // invariant is reported by the next sanity check.
                        out.lost = Some((i, pj as usize));
                    }
                }
            }
        }
    }

    /// Sets `flag` on the entry of the pair `(i, j)`, `i < j`; false if the pair is not in the
    /// list (restoring saved bridges, `TimeEngine::from_state`).
    pub(crate) fn set_flag(&mut self, i: usize, j: usize, flag: u8) -> bool {
        let row = self.start[i] as usize..self.start[i + 1] as usize;
        match self.partner[row.clone()].binary_search(&(j as u32)) {
            Ok(k) => {
                self.flags[row.start + k] |= flag;
                true
            }
            Err(_) => false,
        }
    }

    /// Pairs with `flag` set, as `(i, j)` with `i < j`, sorted.
    pub(crate) fn flagged(&self, flag: u8) -> Vec<(usize, usize)> {
        let n = self.start.len() - 1;
        let mut out = Vec::new();
        for i in 0..n {
            for p in self.start[i] as usize..self.start[i + 1] as usize {
                if self.flags[p] & flag != 0 {
                    out.push((i, self.partner[p] as usize));
                }
            }
        }
        out
    }

    /// Number of entries with `flag` set.
    pub(crate) fn count(&self, flag: u8) -> usize {
        self.flags.iter().filter(|&&f| f & flag != 0).count()
    }
}

#[cfg(test)]
mod tests {
    //! The list against a brute-force pass over all pairs (the independent method).
    use super::*;
    use rand::{Rng, SeedableRng};

    /// Every pair `i < j` with `|x_i - x_j| < R_i + R_j + extra` (nearest image on the
    /// periodic axes, the list's arithmetic), as sorted rows.
    fn brute<const D: usize>(
        x: &[f64],
        radius: &[f64],
        periodic: [bool; D],
        size: [f64; D],
        extra: f64,
    ) -> Vec<Vec<u32>> {
        let n = radius.len();
        (0..n)
            .map(|i| {
                (i + 1..n)
                    .filter(|&j| {
                        let mut r2 = 0.0;
                        for k in 0..D {
                            let mut d = x[k * n + i] - x[k * n + j];
                            if periodic[k] {
                                let l = size[k];
                                if d > 0.5 * l {
                                    d -= l;
                                } else if d < -0.5 * l {
                                    d += l;
                                }
                            }
                            r2 += d * d;
                        }
                        let cut = radius[i] + radius[j] + extra;
                        r2 < cut * cut
                    })
                    .map(|j| j as u32)
                    .collect()
            })
            .collect()
    }

    /// Builds lists of random particles three times (the rows carry flags over) and compares
    /// each with [`brute`]; some particles lie beyond the wall bounds (clamped into the edge
    /// cells).
    fn check<const D: usize>(n: usize, size: [f64; D], periodic: [bool; D], seed: u64) {
        let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
        let (extra, skin, rmax) = (0.07, 0.3, 0.53);
        let lower = [0.0; D];
        let range = 2.0 * rmax + extra + skin;
        let mut list =
            NeighbourList::<D>::new(n, size, periodic, lower, size, extra + skin, skin, range);
        let radius: Vec<f64> = (0..n).map(|_| rng.gen_range(0.47..rmax)).collect();
        for round in 0..3 {
            let mut x = vec![0.0; D * n];
            for k in 0..D {
                for i in 0..n {
                    let margin = if periodic[k] { 0.0 } else { 0.4 };
                    x[k * n + i] = rng.gen_range(-margin..size[k] + margin);
                }
            }
            list.build(&x, &radius);
            let want = brute(&x, &radius, periodic, size, extra + skin);
            let mut entries = 0;
            for (i, row) in want.iter().enumerate() {
                let got = &list.partner[list.start[i] as usize..list.start[i + 1] as usize];
                assert_eq!(got, &row[..], "row {i}, round {round}");
                entries += row.len();
            }
            assert!(entries > n / 4, "a dense enough test: {entries} entries");
            assert_eq!(list.lost_pair, None);
        }
    }

    #[test]
    fn the_list_holds_exactly_the_pairs_in_range() {
        // 2D: a periodic axis of 3 cells (the runs of neighbour cells wrap at both ends), and a
        // wide one; walls on the other axis.
        check::<2>(60, [4.5, 6.0], [true, false], 1);
        check::<2>(400, [60.0, 9.0], [true, false], 2);
        check::<2>(300, [20.0, 20.0], [false, false], 3);
        // 3D: two periodic axes, walls on the third.
        check::<3>(500, [8.0, 6.0, 7.0], [true, true, false], 4);
        check::<3>(200, [4.5, 4.5, 4.5], [true, true, true], 5);
    }
}
