//! Event source of the neighbour cells: which cell each particle is in, and its next crossing
//! of a cell face ([`CellSource`], over the grid of [`super::cells`]).
//!
//! Round-off at cell faces: crossing times are clamped at zero and a particle's cell is tracked
//! by index, never recomputed from its position; crossing a periodic face wraps the position.
//! After a crossing only the newly adjacent slab of cells needs a pair scan.

use super::bodies::{Bodies, Vector, permute_in_place, vec_bytes};
use super::cells::CellGrid;
use super::event::{Event, EventKind, EventSource, PlaneEvent};
use super::shear::FORCE_AXIS;
use crate::physics::flight::linear_time_to_faces;

/// A set of neighbour offsets and, for interior cells, the linear-index change of each.
#[derive(Debug, Clone)]
pub struct Neighbourhood<const D: usize> {
    pub offsets: Vec<[i32; D]>,
    pub(crate) deltas: Vec<isize>,
    /// For a cell next to walls but inside along every periodic axis, indexed by its
    /// [`CellGrid::wall_class`]: the index changes of the offsets that stay inside the walls,
    /// in the order of `offsets`.
    pub(crate) deltas_by_wall_class: Vec<Vec<isize>>,
}

impl<const D: usize> Neighbourhood<D> {
    fn new(grid: &CellGrid<D>, offsets: Vec<[i32; D]>) -> Self {
        let deltas = offsets.iter().map(|o| grid.interior_delta(o)).collect();
        let deltas_by_wall_class = (0..CellGrid::<D>::WALL_CLASSES)
            .map(|class| {
                offsets
                    .iter()
                    .filter(|o| CellGrid::<D>::inside_walls(class, o))
                    .map(|o| grid.interior_delta(o))
                    .collect()
            })
            .collect();
        Self {
            offsets,
            deltas,
            deltas_by_wall_class,
        }
    }
}

/// The grid, each particle's cell and its next crossing.
#[derive(Debug, Clone)]
pub struct CellSource<const D: usize> {
    pub grid: CellGrid<D>,
    /// Cell of each particle (per-axis indices).
    pub cell: Vec<[i32; D]>,
    /// The `3^D` neighbour offsets.
    pub all: Neighbourhood<D>,
    /// The far slab of the neighbourhood after a crossing along `axis` (index `2 axis + up`):
    /// the offsets with `+-1` along `axis`, in the order of `all`.
    far: Vec<Neighbourhood<D>>,
    /// Next crossing of a face of the particle's cell.
    pub ev: Vec<PlaneEvent>,
}

impl<const D: usize> CellSource<D> {
    /// Puts particles at `positions` into `grid`.
    pub fn new(grid: CellGrid<D>, positions: impl ExactSizeIterator<Item = Vector<D>>) -> Self {
        let offsets = CellGrid::<D>::neighbour_offsets();
        let far = (0..2 * D)
            .map(|m| {
                let (axis, step) = (m / 2, if m % 2 == 1 { 1 } else { -1 });
                let slab = offsets
                    .iter()
                    .filter(|o| o[axis] == step)
                    .copied()
                    .collect();
                Neighbourhood::new(&grid, slab)
            })
            .collect();
        let all = Neighbourhood::new(&grid, offsets);
        let mut s = Self {
            grid,
            cell: Vec::with_capacity(positions.len()),
            all,
            far,
            ev: Vec::new(),
        };
        for (i, x) in positions.enumerate() {
            let c = s.grid.locate(&x.into());
            s.cell.push(c);
            let lin = s.grid.linear(&c);
            s.grid.insert(i, lin);
        }
        s.ev = vec![PlaneEvent::NEVER; s.cell.len()];
        s
    }

    /// Heap bytes of the grid and the per-particle arrays (`wetgran-bench memory`).
    pub fn memory(&self) -> Vec<(&'static str, usize)> {
        let mut out = self.grid.memory();
        out.push(("cells.cell", vec_bytes(&self.cell)));
        out.push(("cells.ev", vec_bytes(&self.ev)));
        out
    }

    /// Predicts the next crossing of a face of `i`'s cell (particle at time `now`).
    pub fn predict<const G: bool, const S: bool>(
        &mut self,
        i: usize,
        bodies: &Bodies<D, G, S>,
        now: f64,
    ) {
        let c = self.cell[i];
        let mut best = PlaneEvent::NEVER;
        for k in 0..D {
            let w = self.grid.width[k];
            let lo = c[k] as f64 * w;
            let periodic = bodies.periodic[k];
            // The outer faces of the edge cells of a wall axis are never crossed.
            let lo = if periodic || c[k] > 0 {
                lo
            } else {
                f64::NEG_INFINITY
            };
            let hi = if periodic || c[k] < self.grid.n[k] - 1 {
                c[k] as f64 * w + w
            } else {
                f64::INFINITY
            };
            if (S && k == FORCE_AXIS) || (G && k == D - 1) {
                let (t_up, t_down) = bodies.times_to_planes(i, k, lo, hi);
                best.keep_earlier(t_up, k, true);
                best.keep_earlier(t_down, k, false);
            } else {
                // Straight flight: the face ahead chosen without a branch; the same time and
                // winner as the two calls above.
                let (x, v) = (bodies.body[i].x[k], bodies.body[i].v[k]);
                let lo_closed = !periodic & (c[k] == 0);
                let hi_closed = !periodic & (c[k] == self.grid.n[k] - 1);
                let (t, up) = linear_time_to_faces(x, v, c[k] as f64 * w, w, lo_closed, hi_closed);
                best.keep_earlier(t, k, up);
            }
        }
        best.time += now;
        self.ev[i] = best;
    }

    /// Moves `i` (already at the current time) into the neighbouring cell along `axis`,
    /// wrapping its position across a periodic face. The newly adjacent cells are then
    /// [`Self::far_slab`]`(axis, up)`.
    #[inline]
    pub(crate) fn fire<const G: bool, const S: bool>(
        &mut self,
        i: usize,
        axis: usize,
        up: bool,
        bodies: &mut Bodies<D, G, S>,
    ) {
        let n = self.grid.n[axis];
        let mut c = self.cell[i];
        if up {
            c[axis] += 1;
            if c[axis] == n {
                c[axis] = 0;
                bodies.body[i].x[axis] -= bodies.size[axis];
            }
        } else {
            c[axis] -= 1;
            if c[axis] < 0 {
                c[axis] = n - 1;
                bodies.body[i].x[axis] += bodies.size[axis];
            }
        }
        self.move_to(i, c);
    }

    /// Moves `i` out of its cell's list into that of cell `c`.
    fn move_to(&mut self, i: usize, c: [i32; D]) {
        let old = self.grid.linear(&self.cell[i]);
        self.grid.remove(i, old);
        self.cell[i] = c;
        let new = self.grid.linear(&c);
        self.grid.insert(i, new);
    }

    /// Offsets of the far slab of the neighbourhood after a crossing along `axis` (`up`:
    /// towards larger coordinates): `+-1` along `axis`, anything across.
    #[inline]
    pub(crate) fn far_slab(&self, axis: usize, up: bool) -> &Neighbourhood<D> {
        &self.far[2 * axis + usize::from(up)]
    }

    /// Calls `f(j)` for every particle `j` in the `3^D` cells around the cell of `i` (`i`
    /// included): the plain walk for the rare callers (placements, invariant checks).
    pub(crate) fn for_each_near(&self, i: usize, mut f: impl FnMut(usize)) {
        for o in &self.all.offsets {
            if let Some(cell) = self.grid.shifted(&self.cell[i], o) {
                self.grid.for_each_in(cell, &mut f);
            }
        }
    }

    /// Moves `i` to the cell of position `x` (a placement or a set-up): out of its list and
    /// into the new one.
    pub(crate) fn relocate(&mut self, i: usize, x: &Vector<D>) {
        self.move_to(i, self.grid.locate(&(*x).into()));
    }

    /// Like [`Self::relocate`], but leaves the lists alone when the cell does not change.
    pub(crate) fn relocate_if_moved(&mut self, i: usize, x: &Vector<D>) {
        let c = self.grid.locate(&(*x).into());
        if c != self.cell[i] {
            self.move_to(i, c);
        }
    }

    /// The order that sorts the particles by cell (ties by index): the renumbering that puts
    /// neighbours close together in memory.
    pub(crate) fn cell_order(&self) -> Vec<u32> {
        let mut order: Vec<u32> = (0..self.cell.len() as u32).collect();
        // Keys are distinct, so the unstable sort (no buffer) gives the stable order.
        order.sort_unstable_by_key(|&k| (self.grid.linear(&self.cell[k as usize]), k));
        order
    }

    /// Invariant: particle `i` at `x` lies in its cell (edge cells of a wall axis extend
    /// outwards: the shaken floor leaves the grid). Returns the violation, if any.
    pub fn check(&self, i: usize, x: &Vector<D>, periodic: &[bool; D], tol: f64) -> Option<String> {
        for k in 0..D {
            let w = self.grid.width[k];
            let c = self.cell[i][k];
            let open_lo = !periodic[k] && c == 0;
            let open_hi = !periodic[k] && c == self.grid.n[k] - 1;
            let (c_lo, c_hi) = (c as f64 * w, (c as f64 + 1.0) * w);
            if (!open_lo && x[k] < c_lo - tol) || (!open_hi && x[k] > c_hi + tol) {
                return Some(format!("at {} is not in its cell {c} along axis {k}", x[k]));
            }
        }
        None
    }
}

impl<const D: usize> EventSource for CellSource<D> {
    #[inline]
    fn candidate(&self, i: usize) -> Event {
        self.ev[i].event(|axis, up| EventKind::Cell { axis, up })
    }

    /// Renumbers the particles (see [`Bodies::permute`]) and rebuilds the cell lists.
    fn permute(&mut self, order: &[u32], _new_of_old: &[u32]) {
        permute_in_place(&mut self.cell, order);
        permute_in_place(&mut self.ev, order);
        self.grid.clear();
        for k in 0..self.cell.len() {
            let c = self.grid.linear(&self.cell[k]);
            self.grid.insert(k, c);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every cell with a wall class (inside along the periodic axes, anywhere along the wall
    /// axes, including single layers) finds by its class's index changes exactly the
    /// neighbours, in the same order, that the general path ([`CellGrid::shifted`]) finds: for
    /// the whole neighbourhood and for each far slab of a crossing.
    fn wall_classes_find_the_neighbours_of<const D: usize>(n: [usize; D], periodic: [bool; D]) {
        let size = n.map(|k| k as f64);
        let grid = CellGrid::<D>::new(size, periodic, 1.0, 1);
        let source = CellSource::new(grid, std::iter::once(Vector::<D>::zeros()));
        let grid = &source.grid;
        let total: usize = n.iter().product();
        let mut classed = 0;
        for linear in 0..total {
            let c: [i32; D] =
                std::array::from_fn(|k| (linear / n[..k].iter().product::<usize>() % n[k]) as i32);
            let Some(class) = grid.wall_class(&c) else {
                assert!((0..D).any(|k| periodic[k] && (c[k] == 0 || c[k] == n[k] as i32 - 1)));
                continue;
            };
            classed += 1;
            let base = grid.linear(&c) as isize;
            for hood in std::iter::once(&source.all).chain(source.far.iter()) {
                let fast: Vec<usize> = hood.deltas_by_wall_class[class]
                    .iter()
                    .map(|&d| (base + d) as usize)
                    .collect();
                let general: Vec<usize> = hood
                    .offsets
                    .iter()
                    .filter_map(|o| grid.shifted(&c, o))
                    .collect();
                assert_eq!(fast, general, "cell {c:?}");
            }
        }
        assert!(classed > 0);
    }

    #[test]
    fn wall_classes_find_the_same_neighbours_as_the_general_path() {
        // The standard 2D box's layout: periodic along x, walls along y; and 3D with a floor
        // and lid, walls on two axes, and a single layer of cells between walls.
        wall_classes_find_the_neighbours_of::<2>([7, 4], [true, false]);
        wall_classes_find_the_neighbours_of::<2>([6, 1], [true, false]);
        wall_classes_find_the_neighbours_of::<3>([5, 6, 4], [true, true, false]);
        wall_classes_find_the_neighbours_of::<3>([5, 3, 2], [true, false, false]);
        wall_classes_find_the_neighbours_of::<3>([3, 4, 1], [false, false, false]);
    }
}
