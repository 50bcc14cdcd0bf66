//! Filling the edge tables: each cell's roots at its midpoint, with the safeguards of B.5.4
//! (derivatives shrunk until every corner extrapolates to `tau >= 0`, `v_rel > 0`) and B.5.5
//! (an escaping cell re-referenced to a corner that hits) and the corner check of the linear
//! model; cells are filled in parallel and counted in [`BuildStats`].

use super::flight::{all_roots, base_point, gap3, partials};
use super::{BuildStats, Cell, Edge, EdgeTable, MAX_ROOTS, Root, TableSpec, extrapolate};
use crate::physics::shaken_wall::WallMotion;
use rayon::prelude::*;
use std::f64::consts::TAU;

/// Cells per unit of parallel work in [`build_edge`] (a cell costs five root searches).
const CELLS_PER_TASK: usize = 64;

/// The table of one edge, its cells filled in parallel (see [`WallTable::build`]).
pub(super) fn build_edge(w: &WallMotion, spec: &TableSpec, edge: Edge) -> (EdgeTable, BuildStats) {
    let a = w.amplitude;
    let u_max = (spec.v_max / spec.v_min).ln_1p();
    let (lo, hi) = match edge {
        Edge::Start => ([-a, -u_max], [a, u_max]),
        _ => ([0.0, 0.0], [TAU, u_max]),
    };
    let n = [spec.phase_cells, spec.velocity_cells];
    let width = [(hi[0] - lo[0]) / n[0] as f64, (hi[1] - lo[1]) / n[1] as f64];
    let period = w.period();
    let built: Vec<(Cell, BuildStats)> = (0..n[0] * n[1])
        .into_par_iter()
        .with_min_len(CELLS_PER_TASK)
        .map(|c| build_cell(w, spec, edge, (lo, width), [c / n[1], c % n[1]], period))
        .collect();
    let mut stats = BuildStats::default();
    let mut cells = Vec::with_capacity(built.len());
    for (cell, s) in built {
        stats.add(&s);
        cells.push(cell);
    }
    (
        EdgeTable {
            lo,
            width,
            n,
            cells,
        },
        stats,
    )
}

/// Cell `[i0, i1]` of an edge table with lower corner `lo` and cell widths `width`: the roots
/// at its midpoint, with the safeguards of B.5.4 and B.5.5 and the corner check; the counters
/// say which safeguards acted.
fn build_cell(
    w: &WallMotion,
    spec: &TableSpec,
    edge: Edge,
    (lo, width): ([f64; 2], [f64; 2]),
    [i0, i1]: [usize; 2],
    period: f64,
) -> (Cell, BuildStats) {
    let mut stats = BuildStats::default();
    let corner = |c0: f64, c1: f64| {
        [
            lo[0] + (i0 as f64 + c0) * width[0],
            lo[1] + (i1 as f64 + c1) * width[1],
        ]
    };
    let mid = corner(0.5, 0.5);
    let mut cell = tabulate(w, spec, edge, mid, period);
    let corners = [
        corner(0.0, 0.0),
        corner(1.0, 0.0),
        corner(0.0, 1.0),
        corner(1.0, 1.0),
    ];
    let at_corners = corners.map(|c| tabulate(w, spec, edge, c, period));
    // B.5.5: a cell that escapes at its midpoint but hits at a corner is re-referenced
    // to the corner that hits earliest.
    if entering_count(&cell) == 0 {
        let best = at_corners
            .iter()
            .filter(|c| entering_count(c) > 0)
            .min_by(|x, y| first_entering(x).total_cmp(&first_entering(y)));
        if let Some(c) = best {
            cell = *c;
            stats.rereferenced_cells += 1;
        }
    }
    // B.5.4: every corner extrapolates to tau >= 0 and v_rel > 0.
    for k in 0..cell.count as usize {
        let entering = (k % 2 == 0) != cell.starts_inside;
        let r = &mut cell.roots[k];
        let mut shrunk = false;
        for attempt in 0..12 {
            let ok = corners.iter().all(|c| {
                let d = [c[0] - cell.reference[0], c[1] - cell.reference[1]];
                extrapolate(r.tau, r.dtau, d) >= 0.0
                    && (!entering || extrapolate(r.vrel, r.dvrel, d) > 0.0)
            });
            if ok {
                break;
            }
            shrunk = true;
            if attempt == 11 {
                r.dtau = [0.0; 2];
                r.dvrel = [0.0; 2];
            } else {
                for j in 0..2 {
                    r.dtau[j] *= 0.5;
                    r.dvrel[j] *= 0.5;
                }
            }
        }
        if shrunk {
            stats.shrunk_derivatives += 1;
        }
    }
    if let Some(tol) = spec.corner_tolerance
        && !model_matches(&cell, &at_corners, tol * period)
    {
        cell.exact_only = true;
        stats.exact_only_cells += 1;
    }
    stats.cells += 1;
    (cell, stats)
}

/// Whether the cell's linear model reproduces the true roots at every corner within `tol`.
fn model_matches(cell: &Cell, corners: &[Cell; 4], tol: f64) -> bool {
    corners.iter().all(|c| {
        let d = [
            c.reference[0] - cell.reference[0],
            c.reference[1] - cell.reference[1],
        ];
        c.count == cell.count
            && c.starts_inside == cell.starts_inside
            && (0..c.count as usize).all(|k| {
                let r = &cell.roots[k];
                (extrapolate(r.tau, r.dtau, d) - c.roots[k].tau).abs() <= tol
            })
    })
}

pub(super) fn entering_count(c: &Cell) -> usize {
    (0..c.count as usize)
        .filter(|k| (k % 2 == 0) != c.starts_inside)
        .count()
}

fn first_entering(c: &Cell) -> f64 {
    (0..c.count as usize)
        .find(|k| (k % 2 == 0) != c.starts_inside)
        .map_or(f64::INFINITY, |k| c.roots[k].tau)
}

/// Roots, derivatives and approach speeds of the flight at parameter point `p`.
pub(super) fn tabulate(
    w: &WallMotion,
    spec: &TableSpec,
    edge: Edge,
    p: [f64; 2],
    period: f64,
) -> Cell {
    let base = base_point(w, edge, p[0], p[1], spec.v_min);
    let (starts_inside, taus) = all_roots(w, base, period, edge == Edge::Wall);
    // The flight from the wall edge continues one that was behind the wall and leaves it at
    // tau = 0: its stored roots start with that leaving root, so that odd indices mean
    // "entering" as for a flight that starts behind the wall.
    let mut cell = Cell {
        reference: p,
        exact_only: false,
        starts_inside: starts_inside || edge == Edge::Wall,
        count: 0,
        roots: [Root::default(); MAX_ROOTS],
    };
    let mut list: Vec<f64> = Vec::with_capacity(MAX_ROOTS);
    if edge == Edge::Wall {
        list.push(0.0);
    }
    list.extend(taus);
    list.truncate(MAX_ROOTS);
    for (k, &tau) in list.iter().enumerate() {
        let (_, st, stt) = gap3(w, base, tau);
        let entering = (k % 2 == 0) != cell.starts_inside;
        let mut root = Root {
            tau,
            ..Root::default()
        };
        if !(edge == Edge::Wall && k == 0) && st != 0.0 {
            let [s_p, st_p] = partials(w, edge, p[0], p[1], spec.v_min, tau);
            for j in 0..2 {
                // Eq. B.17.
                root.dtau[j] = -s_p[j] / st;
                if entering {
                    // Eqs. B.20-B.21: v_rel = -s_tau at the root.
                    root.dvrel[j] = -(st_p[j] + stt * root.dtau[j]);
                }
            }
        }
        if entering {
            root.vrel = -st;
        }
        cell.roots[k] = root;
    }
    cell.count = list.len() as u8;
    cell
}
