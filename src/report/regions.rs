//! The regions of a phase map: the Voronoi tessellation of the sampled points inside the plot's
//! rectangle, computed in the picture's own coordinates (pixels, so in the axes' own scales: a
//! log axis is tessellated in decades), and the interface between two neighbouring cells.
//!
//! Each cell is the plot rectangle clipped by the perpendicular bisector between its point and
//! each of its Delaunay neighbours (`boundary::delaunay_pairs`, spade): a Voronoi cell is bounded
//! by those bisectors alone. The interface of two cells of different phase is a stretch of a
//! phase boundary; it passes through the boundary point halfway between the two samples where
//! their Delaunay edge crosses it.

/// A polygon, its vertices in order.
pub(crate) type Polygon = Vec<(f64, f64)>;

/// A segment between two points.
pub(crate) type Segment = ((f64, f64), (f64, f64));

/// `poly` clipped to the half-plane of points at least as close to `p` as to `q`.
fn clip_to_nearer(poly: &Polygon, p: (f64, f64), q: (f64, f64)) -> Polygon {
    let (nx, ny) = (q.0 - p.0, q.1 - p.1);
    let (mx, my) = ((p.0 + q.0) / 2.0, (p.1 + q.1) / 2.0);
    // Positive on q's side of the bisector.
    let side = |v: (f64, f64)| (v.0 - mx) * nx + (v.1 - my) * ny;
    let mut out = Vec::with_capacity(poly.len() + 1);
    for k in 0..poly.len() {
        let (a, b) = (poly[k], poly[(k + 1) % poly.len()]);
        let (sa, sb) = (side(a), side(b));
        if sa <= 0.0 {
            out.push(a);
        }
        if (sa < 0.0 && sb > 0.0) || (sa > 0.0 && sb < 0.0) {
            let t = sa / (sa - sb);
            out.push((a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1)));
        }
    }
    out
}

/// The Voronoi cell of every point inside the rectangle `(x0, y0, x1, y1)`, in the points'
/// order (empty for a point that shares its position with an earlier one, or when the points
/// cannot be triangulated).
pub(crate) fn voronoi_cells(points: &[(f64, f64)], rect: (f64, f64, f64, f64)) -> Vec<Polygon> {
    let (x0, y0, x1, y1) = rect;
    let frame: Polygon = vec![(x0, y0), (x1, y0), (x1, y1), (x0, y1)];
    // The distinct positions (a repeated one keeps its first index) and their neighbours.
    let distinct: Vec<usize> = (0..points.len())
        .filter(|&i| !points[..i].contains(&points[i]))
        .collect();
    let pos: Vec<(f64, f64)> = distinct.iter().map(|&i| points[i]).collect();
    let mut neighbours: Vec<Vec<usize>> = vec![Vec::new(); points.len()];
    // Fewer than three points, or all on a line: every other point is a neighbour.
    let pairs = if pos.len() < 3 {
        Err(0)
    } else {
        crate::boundary::delaunay_pairs(&pos)
    };
    match pairs {
        Ok(pairs) if !pairs.is_empty() => {
            for (i, j) in pairs {
                neighbours[distinct[i]].push(distinct[j]);
                neighbours[distinct[j]].push(distinct[i]);
            }
        }
        _ => {
            for &i in &distinct {
                neighbours[i].extend(distinct.iter().copied().filter(|&j| j != i));
            }
        }
    }
    (0..points.len())
        .map(|i| {
            // A duplicate position (spade keeps the first) has no cell of its own.
            if points[..i].contains(&points[i]) {
                return Vec::new();
            }
            let mut cell = frame.clone();
            for &j in &neighbours[i] {
                if points[j] != points[i] {
                    cell = clip_to_nearer(&cell, points[i], points[j]);
                }
            }
            cell
        })
        .collect()
}

/// The interface of the cell `cell` of `p` with the cell of its neighbour `q`: the stretch of
/// the cell's outline on their bisector (`None` where the cells do not touch).
pub(crate) fn interface(cell: &Polygon, p: (f64, f64), q: (f64, f64)) -> Option<Segment> {
    let (nx, ny) = (q.0 - p.0, q.1 - p.1);
    let len = nx.hypot(ny);
    if len == 0.0 {
        return None;
    }
    let (mx, my) = ((p.0 + q.0) / 2.0, (p.1 + q.1) / 2.0);
    let on = |v: (f64, f64)| ((v.0 - mx) * nx + (v.1 - my) * ny).abs() / len < 1e-6 * (1.0 + len);
    // The cell is convex: its vertices on the bisector span the interface (clipping may leave
    // near-duplicates of a vertex, so take the two farthest apart).
    let on_line: Vec<(f64, f64)> = cell.iter().copied().filter(|&v| on(v)).collect();
    let mut best: Option<(Segment, f64)> = None;
    for (k, &a) in on_line.iter().enumerate() {
        for &b in &on_line[k + 1..] {
            let d = (a.0 - b.0).hypot(a.1 - b.1);
            if best.is_none_or(|(_, e)| d > e) {
                best = Some(((a, b), d));
            }
        }
    }
    best.filter(|b| b.1 > 1e-9 * (1.0 + len)).map(|(s, _)| s)
}

/// The area of a polygon (shoelace formula, positive).
#[cfg(test)]
fn area(poly: &Polygon) -> f64 {
    let n = poly.len();
    (0..n)
        .map(|k| {
            let (a, b) = (poly[k], poly[(k + 1) % n]);
            a.0 * b.1 - b.0 * a.1
        })
        .sum::<f64>()
        .abs()
        / 2.0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_cells_tile_the_rectangle_and_each_holds_its_point() {
        // A jittered 4 x 3 grid and a point in a corner.
        let mut pts: Vec<(f64, f64)> = (0..12)
            .map(|k| {
                let (i, j) = ((k % 4) as f64, (k / 4) as f64);
                (10.0 + 25.0 * i + (k as f64 * 1.7) % 3.0, 8.0 + 30.0 * j)
            })
            .collect();
        pts.push((1.0, 99.0));
        let cells = voronoi_cells(&pts, (0.0, 0.0, 100.0, 100.0));
        let total: f64 = cells.iter().map(area).sum();
        assert!((total - 1e4).abs() < 1e-6, "{total}");
        for (cell, &p) in cells.iter().zip(&pts) {
            // Every vertex of the cell is at least as close to its point as to any other.
            for &v in cell {
                let d = |q: (f64, f64)| (v.0 - q.0).hypot(v.1 - q.1);
                assert!(pts.iter().all(|&q| d(p) <= d(q) + 1e-9));
            }
        }
        // Two grid neighbours share an interface on their bisector; far points do not.
        let (a, b) = interface(&cells[0], pts[0], pts[1]).unwrap();
        let mid_x = (pts[0].0 + pts[1].0) / 2.0;
        assert!((a.0 - mid_x).abs() < 3.0 && (b.0 - mid_x).abs() < 3.0);
        assert!(interface(&cells[0], pts[0], pts[11]).is_none());
    }

    #[test]
    fn two_points_split_the_rectangle_and_a_duplicate_has_no_cell() {
        let cells = voronoi_cells(
            &[(25.0, 50.0), (75.0, 50.0), (25.0, 50.0)],
            (0.0, 0.0, 100.0, 100.0),
        );
        assert!((area(&cells[0]) - 5000.0).abs() < 1e-9);
        assert!((area(&cells[1]) - 5000.0).abs() < 1e-9);
        assert!(cells[2].is_empty());
    }
}
