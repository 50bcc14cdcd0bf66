//! Slack of the kept triangulation's tests ([`super::kinetic_delaunay`]): how far each site of
//! one test may move from where it is now (each by at most its own returned distance, all at
//! once) before the test's outcome can change. A site that stays within the smallest slack of every test it takes
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

/// Slack of each vertex for "the triangle `(a, b, c)` is strictly counter-clockwise".
///
/// `det = (b - a) x (c - a) > 0`. Moving the vertices by `alpha, beta, gamma` changes it by the
/// linear terms `alpha x (b - c) + beta x (c - a) + gamma x (a - b)`, at most
/// `sum_v delta_v |side opposite v|`, and the quadratic `(beta - alpha) x (gamma - alpha)`, at
/// most `(2 max delta)^2`. With `delta_v <= h_v / 4` (`h_v = det / |side opposite v|`, the
/// altitude from `v`) the linear terms take at most `3/4 det`, and with every
/// `delta_v < sqrt(det) / 4` the quadratic one less than `det / 4`: the sign holds.
pub fn orientation_slack(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> [f64; 3] {
    let (u, w) = (sub(b, a), sub(c, a));
    let det = u[0] * w[1] - u[1] * w[0];
    let opposite = [norm(sub(c, b)), norm(w), norm(u)];
    let longest = opposite[0].max(opposite[1]).max(opposite[2]);
    let err = rounding_allowance(magnitude(&[a, b, c])) * (1.0 + longest * longest);
    let det = det - err;
    if det.is_nan() || det <= 0.0 {
        return [0.0; 3];
    }
    let cap = 0.25 * det.sqrt();
    opposite.map(|side| ((0.25 * det / side).min(cap) * (1.0 - 1e-9) - err).max(0.0))
}

/// Slack of each of `a, b, c, d` for "the edge `ab` is locally Delaunay": `d` (across `ab` from `c`, with `(a, b, c)`
/// counter-clockwise) is not inside the circle through `a, b, c`.
///
/// Certificate: a circle that holds `a` and `b` strictly inside and `c` and `d` strictly
/// outside. Lifted onto the paraboloid `z = |p|^2` the circle is a plane with `a, b` below and
/// `c, d` above; where the diagonals `ab` and `cd` cross, the lifted `ab` then lies below the
/// lifted `cd`, which is the in-circle condition (where the quadrilateral is not convex the edge
/// is locally Delaunay anyway). A point that moves by less than its distance to the circle stays
/// on its side: that distance is its slack.
///
/// The certificate assumes both triangles `abc` and `bad` stay positive (their own tests).
///
/// The circle: among those through `a` and `b` (centres `m + lambda n` on the bisector, `n`
/// towards `c`), `c` is outside for `lambda < lambda_c` (the circumcentre of `abc`) and `d` for
/// `lambda > lambda_d`; the middle `lambda` of that interval, its radius then grown by half the
/// smaller of the distances of `c` and `d` to it.
pub fn edge_slack(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> [f64; 4] {
    let m = [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])];
    let e = sub(b, a);
    let len = norm(e);
    if len.is_nan() || len <= 0.0 {
        return [0.0; 4];
    }
    let n = [-e[1] / len, e[0] / len];
    let (cm, dm) = (sub(c, m), sub(d, m));
    let (hc, hd) = (n[0] * cm[0] + n[1] * cm[1], n[0] * dm[0] + n[1] * dm[1]);
    let half2 = 0.25 * len * len;
    let lambda_c = (cm[0] * cm[0] + cm[1] * cm[1] - half2) / (2.0 * hc);
    let lambda_d = (dm[0] * dm[0] + dm[1] * dm[1] - half2) / (2.0 * hd);
    // c strictly on n's side, d strictly on the other, a non-empty interval of centres.
    if !(hc > 0.0
        && hd < 0.0
        && lambda_d < lambda_c
        && lambda_c.is_finite()
        && lambda_d.is_finite())
    {
        return [0.0; 4];
    }
    let lambda = 0.5 * (lambda_c + lambda_d);
    let o = [m[0] + lambda * n[0], m[1] + lambda * n[1]];
    let rho = (half2 + lambda * lambda).sqrt();
    let (out_c, out_d) = (norm(sub(c, o)) - rho, norm(sub(d, o)) - rho);
    let err = rounding_allowance(magnitude(&[a, b, c, d]) + rho + lambda.abs());
    // Radius rho + t, t half the smaller distance outside: a and b inside by t, c and d outside
    // by their distance less t.
    let t = 0.5 * out_c.min(out_d);
    [t, t, out_c - t, out_d - t].map(|s| (s * (1.0 - 1e-9) - err).max(0.0))
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

    /// Moves each point by its `delta` in a direction from the generator (on the circle of
    /// radius `delta`, the worst case of the bound).
    fn moved(p: &[[f64; 2]], delta: &[f64], state: &mut u64) -> Vec<[f64; 2]> {
        p.iter()
            .zip(delta)
            .map(|(q, d)| {
                let t = std::f64::consts::TAU * next(state);
                [q[0] + d * t.cos(), q[1] + d * t.sin()]
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
            assert!(s.iter().all(|&x| x >= 0.0));
            for _ in 0..20 {
                let m = moved(&[a, b, q], &s, &mut state);
                assert!(
                    orient2d(c(m[0]), c(m[1]), c(m[2])) > 0.0,
                    "{a:?} {b:?} {q:?} {s:?}"
                );
            }
            // The bound is not hopelessly loose: five times the slack can invert it.
            let m = moved(&[a, b, q], &s.map(|x| 5.0 * x + 1e-9), &mut state);
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
                assert_eq!(s, [0.0; 4], "a conflicting edge has no slack");
                continue;
            }
            if s.iter().all(|&x| x > 0.0) {
                certified += 1;
            }
            for _ in 0..20 {
                let m = moved(&[a, b, q, d], &s, &mut state);
                // Both triangles still positive (certified apart, `orientation_slack`).
                if orient2d(c(m[0]), c(m[1]), c(m[2])) > 0.0
                    && orient2d(c(m[1]), c(m[0]), c(m[3])) > 0.0
                {
                    assert!(incircle(c(m[0]), c(m[1]), c(m[2]), c(m[3])) <= 0.0);
                }
            }
        }
        assert!(certified > 100);
    }
}
