//! The neighbour grid: the box divided into cells no smaller than the interaction range
//! (largest diameter plus `s_crit`), with doubly linked per-cell particle lists so that a
//! particle changes cell in `O(1)` without allocation.
//!
//! The lists end in a sentinel index one past the last particle, linked to itself, so that a
//! neighbour scan may take the first steps of a list walk without asking whether the list has
//! ended ([`CellGrid::gather`]): a cell's occupancy is then no branch to mispredict.

/// List steps [`CellGrid::gather`] takes per cell without a branch: at the reference densities
/// (0.5 particles per cell in 3D) only 1.4 % of the cells hold more, and fall back to the loop.
const GATHER_STEPS: usize = 2;
/// Particle indices [`CellGrid::gather`] gathers before it hands them on (a power of two).
pub const BATCH: usize = 64;

/// Where [`CellGrid::gather`] stopped: the rest of a list (`j`, the sentinel if none) and
/// its cell's tag.
#[derive(Debug, Clone, Copy)]
pub struct Gather {
    j: u32,
    tag: u8,
}

/// A regular grid of `n[0] x ... x n[D-1]` cells.
#[derive(Debug, Clone)]
pub struct CellGrid<const D: usize> {
    pub n: [i32; D],
    pub width: [f64; D],
    pub periodic: [bool; D],
    /// Whether every periodic axis has at least five cells: then two particles in the
    /// neighbourhood of an interior cell are less than half the box apart, so their separation
    /// needs no minimum image.
    pub interior_needs_no_image: bool,
    /// The list sentinel: the particle count (`next[end] == end`).
    end: u32,
    head: Vec<u32>,
    next: Vec<u32>,
    prev: Vec<u32>,
}

impl<const D: usize> CellGrid<D> {
    /// A grid over a box of edges `size` with cells no smaller than `min_edge`.
    pub fn new(size: [f64; D], periodic: [bool; D], min_edge: f64, particles: usize) -> Self {
        let n: [i32; D] = std::array::from_fn(|k| ((size[k] / min_edge).floor() as i32).max(1));
        let width: [f64; D] = std::array::from_fn(|k| size[k] / n[k] as f64);
        let total: usize = n.iter().map(|&x| x as usize).product();
        Self {
            n,
            width,
            periodic,
            interior_needs_no_image: (0..D).all(|k| !periodic[k] || n[k] >= 5),
            end: particles as u32,
            head: vec![particles as u32; total],
            next: vec![particles as u32; particles + 1],
            prev: vec![particles as u32; particles],
        }
    }

    /// Heap bytes of the cell heads and the per-particle links (`wetgran-bench memory`).
    pub fn memory(&self) -> Vec<(&'static str, usize)> {
        use super::bodies::vec_bytes;
        vec![
            ("cells.grid.head (per cell)", vec_bytes(&self.head)),
            ("cells.grid.next", vec_bytes(&self.next)),
            ("cells.grid.prev", vec_bytes(&self.prev)),
        ]
    }

    /// The cell containing coordinate `x` (clamped into the grid).
    pub fn locate(&self, x: &[f64; D]) -> [i32; D] {
        std::array::from_fn(|k| ((x[k] / self.width[k]).floor() as i32).clamp(0, self.n[k] - 1))
    }

    #[inline]
    pub fn linear(&self, c: &[i32; D]) -> usize {
        let mut idx = 0usize;
        for k in (0..D).rev() {
            idx = idx * self.n[k] as usize + c[k] as usize;
        }
        idx
    }

    /// The cell `c + offset`, wrapped on periodic axes; `None` past a wall.
    #[inline]
    pub fn shifted(&self, c: &[i32; D], offset: &[i32; D]) -> Option<usize> {
        let mut s = [0i32; D];
        for k in 0..D {
            let mut v = c[k] + offset[k];
            if v < 0 || v >= self.n[k] {
                if !self.periodic[k] {
                    return None;
                }
                v = v.rem_euclid(self.n[k]);
            }
            s[k] = v;
        }
        Some(self.linear(&s))
    }

    /// Whether every neighbour of cell `c` lies inside the grid without wrapping, so that
    /// [`Self::interior_delta`] finds it (the fast path of neighbour scans).
    #[inline]
    pub fn is_interior(&self, c: &[i32; D]) -> bool {
        (0..D).all(|k| c[k] >= 1 && c[k] <= self.n[k] - 2)
    }

    /// Number of wall classes ([`Self::wall_class`]): two bits per axis.
    pub const WALL_CLASSES: usize = 1 << (2 * D);

    /// The wall class of cell `c` (`None` on the edge of a periodic axis): per wall axis, bit
    /// `2k` set at its low face (`c_k = 0`), bit `2k + 1` at its high face (both for a single
    /// layer). With the class, the neighbours of `c` are the interior index changes of the
    /// offsets that stay inside the walls ([`Self::inside_walls`]).
    #[inline]
    pub fn wall_class(&self, c: &[i32; D]) -> Option<usize> {
        let mut class = 0usize;
        for k in 0..D {
            let (low, high) = (c[k] == 0, c[k] == self.n[k] - 1);
            if self.periodic[k] {
                if low || high {
                    return None;
                }
            } else {
                class |= (usize::from(low) | (usize::from(high) << 1)) << (2 * k);
            }
        }
        Some(class)
    }

    /// Whether a cell of wall class `class` has a neighbour at `offset` (it does not step
    /// through the face of a wall it lies on).
    pub fn inside_walls(class: usize, offset: &[i32; D]) -> bool {
        (0..D).all(|k| {
            let (low, high) = ((class >> (2 * k)) & 1 == 1, (class >> (2 * k + 1)) & 1 == 1);
            !((low && offset[k] < 0) || (high && offset[k] > 0))
        })
    }

    /// The change of the linear index from an interior cell to its neighbour at `offset` (the
    /// same for every interior cell: precomputed per offset for the neighbour scans).
    pub fn interior_delta(&self, offset: &[i32; D]) -> isize {
        let mut delta = 0isize;
        let mut stride = 1isize;
        for k in 0..D {
            delta += offset[k] as isize * stride;
            stride *= self.n[k] as isize;
        }
        delta
    }

    /// Per axis `k` and step `s` in `-1, 0, 1`: the part `stride_k * wrap(c_k + s)` of the linear
    /// index of a neighbour of cell `c`, or `usize::MAX` past a wall; the linear index of `c + o`
    /// is the sum of the parts `o_k` picks ([`Self::shifted`] without its per-offset division).
    #[inline]
    pub fn axis_parts(&self, c: &[i32; D]) -> [[usize; 3]; D] {
        let mut parts = [[usize::MAX; 3]; D];
        let mut stride = 1usize;
        for k in 0..D {
            for s in 0..3 {
                let mut v = c[k] + s as i32 - 1;
                if v < 0 || v >= self.n[k] {
                    if !self.periodic[k] {
                        continue;
                    }
                    v = v.rem_euclid(self.n[k]);
                }
                parts[k][s] = v as usize * stride;
            }
            stride *= self.n[k] as usize;
        }
        parts
    }

    /// [`Self::axis_parts`], and per axis `k` and step `s` the image shift of the partners in
    /// that slab of cells: `-size[k]` where `c_k + s` wraps past the upper face of a periodic
    /// axis, `+size[k]` past the lower face, `0` otherwise. With five cells or more on every
    /// periodic axis this is the minimum image of every pair in neighbouring cells (those
    /// `n_k - 1` cells apart are more than `0.6 L` apart, the others less than `0.4 L`).
    #[inline]
    pub fn axis_parts_and_shifts(
        &self,
        c: &[i32; D],
        size: &[f64; D],
    ) -> ([[usize; 3]; D], [[f64; 3]; D]) {
        let parts = self.axis_parts(c);
        let mut shifts = [[0.0; 3]; D];
        for k in 0..D {
            if self.periodic[k] {
                if c[k] == 0 {
                    shifts[k][0] = size[k];
                }
                if c[k] == self.n[k] - 1 {
                    shifts[k][2] = -size[k];
                }
            }
        }
        (parts, shifts)
    }

    /// The image shift of the cell at `offset` from [`Self::axis_parts_and_shifts`].
    #[inline]
    pub fn shift_of(shifts: &[[f64; 3]; D], offset: &[i32; D]) -> [f64; D] {
        std::array::from_fn(|k| shifts[k][(offset[k] + 1) as usize])
    }

    /// Linear index of `c + offset` from [`Self::axis_parts`] of `c`; `None` past a wall.
    #[inline]
    pub fn from_parts(parts: &[[usize; 3]; D], offset: &[i32; D]) -> Option<usize> {
        let mut idx = 0usize;
        for k in 0..D {
            let p = parts[k][(offset[k] + 1) as usize];
            if p == usize::MAX {
                return None;
            }
            idx += p;
        }
        Some(idx)
    }

    /// Empties every cell list (before re-inserting all particles under new indices).
    pub fn clear(&mut self) {
        self.head.fill(self.end);
    }

    /// Inserts particle `i` into cell `cell`.
    #[inline]
    pub fn insert(&mut self, i: usize, cell: usize) {
        let h = self.head[cell];
        self.next[i] = h;
        self.prev[i] = self.end;
        if h != self.end {
            self.prev[h as usize] = i as u32;
        }
        self.head[cell] = i as u32;
    }

    /// Removes particle `i` from cell `cell`.
    #[inline]
    pub fn remove(&mut self, i: usize, cell: usize) {
        let (p, nx) = (self.prev[i], self.next[i]);
        if p != self.end {
            self.next[p as usize] = nx;
        } else {
            self.head[cell] = nx;
        }
        if nx != self.end {
            self.prev[nx as usize] = p;
        }
    }

    /// Calls `f(j)` for every particle in cell `cell`.
    #[inline]
    pub fn for_each_in(&self, cell: usize, mut f: impl FnMut(usize)) {
        let mut j = self.head[cell];
        while j != self.end {
            f(j as usize);
            j = self.next[j as usize];
        }
    }

    /// The state of [`Self::gather`] before its first call.
    pub fn gather_start(&self) -> Gather {
        Gather {
            j: self.end,
            tag: 0,
        }
    }

    /// Gathers into `buf` the particles of the cells `cells` yields, in the order
    /// [`Self::for_each_in`] visits them, each with its cell's tag in `tags` (if `tagged`): the
    /// first [`GATHER_STEPS`] steps of each list store the index and count it only if it is not
    /// the sentinel (no branch on the occupancy). Returns how many it gathered and whether to
    /// call again (the buffer was full; `state` remembers where it stopped).
    pub fn gather(
        &self,
        cells: &mut impl Iterator<Item = (usize, u8)>,
        state: &mut Gather,
        buf: &mut [u32; BATCH],
        tags: &mut [u8; BATCH],
        tagged: bool,
    ) -> (usize, bool) {
        let end = self.end;
        let mut len = 0usize;
        // The rest of a list cut short by a full buffer.
        let (j, tag) = (state.j, state.tag);
        state.j = end;
        if self.walk(j, tag, state, buf, tags, &mut len) || len > BATCH - GATHER_STEPS {
            return (len, true);
        }
        for (cell, tag) in cells.by_ref() {
            let mut j = self.head[cell];
            for _ in 0..GATHER_STEPS {
                // `len <= BATCH - GATHER_STEPS` here; the mask only spares the bounds test.
                buf[len % BATCH] = j;
                if tagged {
                    tags[len % BATCH] = tag;
                }
                len += usize::from(j != end);
                j = self.next[j as usize];
            }
            if self.walk(j, tag, state, buf, tags, &mut len) || len > BATCH - GATHER_STEPS {
                return (len, true);
            }
        }
        (len, false)
    }

    /// Appends the list from `j` on (its cell's tag `tag`) to `buf[..len]`; `true` if the
    /// buffer filled first (`state` then says where to go on).
    #[inline(always)]
    fn walk(
        &self,
        mut j: u32,
        tag: u8,
        state: &mut Gather,
        buf: &mut [u32; BATCH],
        tags: &mut [u8; BATCH],
        len: &mut usize,
    ) -> bool {
        while j != self.end {
            if *len == BATCH {
                *state = Gather { j, tag };
                return true;
            }
            buf[*len] = j;
            tags[*len] = tag;
            *len += 1;
            j = self.next[j as usize];
        }
        false
    }

    /// Calls `f` with the batches of [`Self::gather`] (particles and tags) until all the cells
    /// `cells` yields are done.
    pub fn for_each_batch(
        &self,
        mut cells: impl Iterator<Item = (usize, u8)>,
        tagged: bool,
        mut f: impl FnMut(&[u32], &[u8]),
    ) {
        let mut state = self.gather_start();
        let mut buf = [0u32; BATCH];
        let mut tags = [0u8; BATCH];
        loop {
            let (len, more) = self.gather(&mut cells, &mut state, &mut buf, &mut tags, tagged);
            f(&buf[..len], &tags[..len]);
            if !more {
                return;
            }
        }
    }

    /// All `3^D` neighbour offsets (including the cell itself).
    pub fn neighbour_offsets() -> Vec<[i32; D]> {
        (0..3usize.pow(D as u32))
            .map(|m| std::array::from_fn(|k| (m / 3usize.pow(k as u32) % 3) as i32 - 1))
            .collect()
    }

    /// Whether every periodic axis has at least four cells: then the `3^D` neighbourhood holds no
    /// cell twice, and two particles in neighbouring cells are always less than half a box apart,
    /// so the minimum image cannot switch without a cell crossing.
    pub fn neighbourhood_is_distinct(&self) -> bool {
        (0..D).all(|k| !self.periodic[k] || self.n[k] >= crate::scene::MIN_PERIODIC_CELLS)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gathering_visits_the_lists_in_order_across_full_buffers() {
        // Cells with 0, 1, 2, 3, 70 and 127 particles (more than a buffer: the walk resumes in the
        // middle of a list and after it), in a deliberately mixed insertion order.
        let sizes = [0usize, 1, 2, 3, 127, 0, 2, 70, 1];
        let n: usize = sizes.iter().sum();
        let mut g = CellGrid::<2>::new([9.0, 1.0], [true, false], 1.0, n);
        assert_eq!(g.n, [9, 1]);
        let mut k = 0;
        for (cell, &m) in sizes.iter().enumerate() {
            for _ in 0..m {
                g.insert(k, cell);
                k += 1;
            }
        }
        // Particles 6..133 are in cell 4: one of them moved to the head of its list.
        g.remove(10, 4);
        g.insert(10, 4);
        assert_eq!(
            (0..g.head.len())
                .map(|c| {
                    let mut m = 0;
                    g.for_each_in(c, |_| m += 1);
                    m
                })
                .sum::<usize>(),
            n
        );
        let order = [4usize, 2, 0, 7, 3, 4, 8, 1, 6, 5];
        let mut want = vec![];
        for &c in &order {
            g.for_each_in(c, |j| want.push((j as u32, c as u8)));
        }
        let mut got = vec![];
        let mut cells = order.iter().map(|&c| (c, c as u8));
        let mut state = g.gather_start();
        let (mut buf, mut tags) = ([0u32; BATCH], [0u8; BATCH]);
        loop {
            let (len, more) = g.gather(&mut cells, &mut state, &mut buf, &mut tags, true);
            assert!(len <= BATCH);
            got.extend(buf[..len].iter().copied().zip(tags[..len].iter().copied()));
            if !more {
                break;
            }
        }
        assert_eq!(got, want);
        let mut batched = vec![];
        let cells = order.iter().map(|&c| (c, c as u8));
        g.for_each_batch(cells, true, |b, t| {
            batched.extend(b.iter().copied().zip(t.iter().copied()))
        });
        assert_eq!(batched, want);
    }

    #[test]
    fn lists_follow_insert_and_remove() {
        let mut g = CellGrid::<2>::new([10.0, 5.0], [true, false], 1.1, 5);
        assert_eq!(g.n, [9, 4]);
        for i in 0..5 {
            g.insert(i, 3);
        }
        g.remove(2, 3);
        g.remove(4, 3);
        g.insert(4, 7);
        let mut seen = vec![];
        g.for_each_in(3, |j| seen.push(j));
        seen.sort();
        assert_eq!(seen, vec![0, 1, 3]);
        let mut seen7 = vec![];
        g.for_each_in(7, |j| seen7.push(j));
        assert_eq!(seen7, vec![4]);
        // Periodic wrap in x, wall in z.
        assert_eq!(g.shifted(&[0, 0], &[-1, 0]), Some(g.linear(&[8, 0])));
        assert_eq!(g.shifted(&[0, 0], &[0, -1]), None);
        assert_eq!(CellGrid::<3>::neighbour_offsets().len(), 27);
        // The interior fast path agrees with the general wrap-aware lookup.
        let g3 = CellGrid::<3>::new([10.0, 10.0, 10.0], [true, true, false], 1.0, 1);
        let c = [4, 1, 8];
        assert!(g3.is_interior(&c) && !g3.is_interior(&[0, 1, 8]) && !g3.is_interior(&[4, 1, 9]));
        for o in CellGrid::<3>::neighbour_offsets() {
            assert_eq!(
                Some((g3.linear(&c) as isize + g3.interior_delta(&o)) as usize),
                g3.shifted(&c, &o)
            );
        }
        // The image shifts are the minimum image of points in neighbouring cells (five cells
        // or more on each periodic axis), at the cells' corners and centres.
        let g5 = CellGrid::<3>::new([10.0, 7.5, 6.0], [true, true, false], 1.2, 1);
        assert!(g5.interior_needs_no_image);
        let size = [10.0, 7.5, 6.0];
        let w = g5.width;
        for c in [[0, 0, 0], [7, 5, 4], [0, 5, 2], [7, 0, 4], [3, 3, 0]] {
            assert!((0..3).all(|k| c[k] < g5.n[k]));
            let (parts, shifts) = g5.axis_parts_and_shifts(&c, &size);
            for o in CellGrid::<3>::neighbour_offsets() {
                let Some(cell) = CellGrid::<3>::from_parts(&parts, &o) else {
                    continue;
                };
                assert_eq!(Some(cell), g5.shifted(&c, &o));
                let s = CellGrid::<3>::shift_of(&shifts, &o);
                for (fi, fj) in [(0.0, 0.999), (0.999, 0.0), (0.5, 0.5)] {
                    for k in 0..3 {
                        let ck = c[k] + o[k];
                        let cj = if g5.periodic[k] {
                            ck.rem_euclid(g5.n[k])
                        } else {
                            ck
                        };
                        let xi = (c[k] as f64 + fi) * w[k];
                        let xj = (cj as f64 + fj) * w[k];
                        let mut r = xi - xj;
                        if g5.periodic[k] && r > 0.5 * size[k] {
                            r -= size[k];
                        } else if g5.periodic[k] && r < -0.5 * size[k] {
                            r += size[k];
                        }
                        assert_eq!(r, xi - xj + s[k], "cell {c:?} offset {o:?} axis {k}");
                    }
                }
            }
        }
        // The per-axis parts give the wrap-aware lookup at every cell, edges included.
        for c in [[0, 0, 0], [9, 9, 9], [0, 5, 9], [4, 1, 8], [9, 0, 0]] {
            let parts = g3.axis_parts(&c);
            for o in CellGrid::<3>::neighbour_offsets() {
                assert_eq!(CellGrid::<3>::from_parts(&parts, &o), g3.shifted(&c, &o));
            }
        }
    }
}
