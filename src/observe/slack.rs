//! Slack of the kept triangulation's tests ([`super::kinetic_delaunay`]): how far the sites of
//! one test may move, each by at most the returned distance from where they are now, before the
//! test's outcome can change. A site that stays within the smallest slack of every test it takes
//! part in needs none of those tests again; only the tests around sites that moved farther are
//! repeated at the next sample.
//!
//! Both bounds hold for exact arithmetic on the moved positions (the tests themselves are exact,
//! `robust`), and are shrunk by an absolute allowance for the rounding of the floating-point
//! arithmetic that computes them ([`rounding_allowance`]). A test that cannot be certified
//! (degenerate, or its outcome the wrong way) gets slack 0: its sites are checked at every
//! sample until a later certificate succeeds.

/// Allowance for the rounding of the slack arithmetic on coordinates up to `scale` in size:
/// `1e-12 (1 + scale)`, four orders of magnitude above the few `1e-16`-relative roundings of a
/// dozen operations.
#[inline]
fn rounding_allowance(scale: f64) -> f64 {
    1e-12 * (1.0 + scale)
}

#[inline]
fn sub(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    [a[0] - b[0], a[1] - b[1]]
}

#[inline]
fn norm(a: [f64; 2]) -> f64 {
    a[0].hypot(a[1])
}

#[inline]
fn magnitude(points: &[[f64; 2]]) -> f64 {
    points
        .iter()
        .fold(0.0f64, |m, p| m.max(p[0].abs()).max(p[1].abs()))
}

/// Slack of "the triangle `(a, b, c)` is strictly counter-clockwise".
///
/// With `u = b - a`, `w = c - a` and `det = u x w > 0`, moving every vertex by at most `delta`
/// changes `u` and `w` by at most `2 delta` each, so the determinant stays above
/// `det - 2 delta (|u| + |w|) - 4 delta^2`; it stays positive for
/// `delta < det / (S + sqrt(S^2 + 4 det))` with `S = |u| + |w|`. Taking `a` opposite the longest
/// side gives the smallest `S`: the perimeter minus the longest side.
pub fn orientation_slack(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    let (u, w) = (sub(b, a), sub(c, a));
    let det = u[0] * w[1] - u[1] * w[0];
    let sides = [norm(u), norm(w), norm(sub(c, b))];
    let s = sides[0] + sides[1] + sides[2] - sides[0].max(sides[1]).max(sides[2]);
    let err = rounding_allowance(magnitude(&[a, b, c])) * (1.0 + s * s);
    let det = det - err;
    if !(det > 0.0) {
        return 0.0;
    }
    let delta = det / (s + (s * s + 4.0 * det).sqrt());
    (delta * (1.0 - 1e-9) - err).max(0.0)
}

/// Slack of "the edge `ab` is locally Delaunay": `d` (across `ab` from `c`, with `(a, b, c)`
/// counter-clockwise) is not inside the circle through `a, b, c`.
///
/// Certificate: a circle that holds `a` and `b` strictly inside and `c` and `d` strictly
/// outside. Lifted onto the paraboloid `z = |p|^2` the circle is a plane with `a, b` below and
/// `c, d` above; where the diagonals `ab` and `cd` cross, the lifted `ab` then lies below the
/// lifted `cd`, which is the in-circle condition. A point that moves by less than its distance
/// to the circle stays on its side, so the slack is the smallest of the four distances.
///
/// The circle: among those through `a` and `b` (centres `m + lambda n` on the bisector, `n`
/// towards `c`), `c` is outside for `lambda < lambda_c` (the circumcentre of `abc`) and `d` for
/// `lambda > lambda_d`; the middle `lambda` of that interval, its radius then grown by half the
/// smaller of the distances of `c` and `d` to it.
pub fn edge_slack(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> f64 {
    let m = [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])];
    let e = sub(b, a);
    let len = norm(e);
    if !(len > 0.0) {
        return 0.0;
    }
    let n = [-e[1] / len, e[0] / len];
    let (cm, dm) = (sub(c, m), sub(d, m));
    let (hc, hd) = (n[0] * cm[0] + n[1] * cm[1], n[0] * dm[0] + n[1] * dm[1]);
    let half2 = 0.25 * len * len;
    let lambda_c = (cm[0] * cm[0] + cm[1] * cm[1] - half2) / (2.0 * hc);
    let lambda_d = (dm[0] * dm[0] + dm[1] * dm[1] - half2) / (2.0 * hd);
    // c strictly on n's side, d strictly on the other, a non-empty interval of centres.
    if !(hc > 0.0 && hd < 0.0 && lambda_d < lambda_c && lambda_c.is_finite() && lambda_d.is_finite())
    {
        return 0.0;
    }
    let lambda = 0.5 * (lambda_c + lambda_d);
    let o = [m[0] + lambda * n[0], m[1] + lambda * n[1]];
    let rho = (half2 + lambda * lambda).sqrt();
    let outside = (norm(sub(c, o)) - rho).min(norm(sub(d, o)) - rho);
    let err = rounding_allowance(magnitude(&[a, b, c, d]) + rho + lambda.abs());
    // Radius rho + outside / 2: a and b inside by outside / 2, c and d outside by as much.
    (0.5 * outside * (1.0 - 1e-9) - err).max(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use robust::{Coord, incircle, orient2d};

    fn c(p: [f64; 2]) -> Coord<f64> {
        Coord { x: p[0], y: p[1] }
    }

    /// A small deterministic generator (xorshift) for the random moves.
    fn next(state: &mut u64) -> f64 {
        *state ^= *state << 13;
        *state ^= *state >> 7;
        *state ^= *state << 17;
        (*state >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Moves each point by `delta` in a direction from the generator (on the circle of radius
    /// `delta`, the worst case of the bound).
    fn moved(p: &[[f64; 2]], delta: f64, state: &mut u64) -> Vec<[f64; 2]> {
        p.iter()
            .map(|q| {
                let t = std::f64::consts::TAU * next(state);
                [q[0] + delta * t.cos(), q[1] + delta * t.sin()]
            })
            .collect()
    }

    #[test]
    fn orientation_holds_within_its_slack_and_fails_somewhere_beyond() {
        let mut state = 0x9E37_79B9_7F4A_7C15u64;
        let mut beyond_failed = 0;
        for _ in 0..2000 {
            let p: Vec<[f64; 2]> = (0..3)
                .map(|_| [100.0 + 2.0 * next(&mut state), 2.0 * next(&mut state)])
                .collect();
            let (a, b, q) = if orient2d(c(p[0]), c(p[1]), c(p[2])) > 0.0 {
                (p[0], p[1], p[2])
            } else {
                (p[1], p[0], p[2])
            };
            let s = orientation_slack(a, b, q);
            assert!(s >= 0.0);
            for _ in 0..20 {
                let m = moved(&[a, b, q], s, &mut state);
                assert!(orient2d(c(m[0]), c(m[1]), c(m[2])) > 0.0, "{a:?} {b:?} {q:?} {s}");
            }
            // The bound is not hopelessly loose: four times the slack can invert it.
            let m = moved(&[a, b, q], 4.0 * s + 1e-9, &mut state);
            beyond_failed += (orient2d(c(m[0]), c(m[1]), c(m[2])) <= 0.0) as usize;
        }
        assert!(beyond_failed > 0);
    }

    #[test]
    fn edge_stays_delaunay_within_its_slack() {
        let mut state = 0x2545_F491_4F6C_DD1Du64;
        let mut certified = 0;
        for _ in 0..4000 {
            let p: Vec<[f64; 2]> = (0..4)
                .map(|_| [2.0 * next(&mut state), 2.0 * next(&mut state)])
                .collect();
            let (a, b, q, d) = (p[0], p[1], p[2], p[3]);
            // (a, b, q) counter-clockwise, d on the other side of ab.
            if orient2d(c(a), c(b), c(q)) <= 0.0 || orient2d(c(b), c(a), c(d)) <= 0.0 {
                continue;
            }
            let s = edge_slack(a, b, q, d);
            let delaunay = incircle(c(a), c(b), c(q), c(d)) < 0.0;
            if !delaunay {
                assert_eq!(s, 0.0, "a conflicting edge has no slack");
                continue;
            }
            if s > 0.0 {
                certified += 1;
            }
            for _ in 0..20 {
                let m = moved(&[a, b, q, d], s, &mut state);
                if orient2d(c(m[0]), c(m[1]), c(m[2])) > 0.0 {
                    assert!(incircle(c(m[0]), c(m[1]), c(m[2]), c(m[3])) <= 0.0);
                }
            }
        }
        assert!(certified > 100);
    }
}
