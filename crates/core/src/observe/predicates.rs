//! The exact geometric predicates of the kept triangulation ([`super::kinetic_delaunay`]):
//! `orient2d` and `incircle` with the same signs as `robust`'s (Shewchuk's adaptive
//! predicates), with the first, floating-point stage of Shewchuk's method inlined in front: the
//! determinant in doubles and its error bound (a multiple of the permanent); only where the
//! determinant is within that bound of zero does `robust` take over and decide exactly. Most
//! tests end in the first stage, without the call.

use robust::Coord;

/// Half an ulp of 1: Shewchuk's `epsilon`.
const EPSILON: f64 = f64::EPSILON * 0.5;
/// Shewchuk's `ccwerrboundA`.
const CCW_ERR_BOUND: f64 = (3.0 + 16.0 * EPSILON) * EPSILON;
/// Shewchuk's `iccerrboundA`.
const ICC_ERR_BOUND: f64 = (10.0 + 96.0 * EPSILON) * EPSILON;

/// Positive when `a, b, c` turn counter-clockwise, negative when clockwise, zero when collinear
/// (the sign is exact).
#[inline]
pub fn orient2d(a: Coord<f64>, b: Coord<f64>, c: Coord<f64>) -> f64 {
    let left = (a.x - c.x) * (b.y - c.y);
    let right = (a.y - c.y) * (b.x - c.x);
    let det = left - right;
    let sum = if left > 0.0 {
        if right <= 0.0 {
            return det;
        }
        left + right
    } else if left < 0.0 {
        if right >= 0.0 {
            return det;
        }
        -left - right
    } else {
        return det;
    };
    if det.abs() >= CCW_ERR_BOUND * sum {
        return det;
    }
    robust::orient2d(a, b, c)
}

/// Positive when `d` lies inside the circle through `a, b, c` (counter-clockwise), negative
/// outside, zero on it (the sign is exact).
#[inline]
pub fn incircle(a: Coord<f64>, b: Coord<f64>, c: Coord<f64>, d: Coord<f64>) -> f64 {
    let (adx, ady) = (a.x - d.x, a.y - d.y);
    let (bdx, bdy) = (b.x - d.x, b.y - d.y);
    let (cdx, cdy) = (c.x - d.x, c.y - d.y);
    let (bdxcdy, cdxbdy) = (bdx * cdy, cdx * bdy);
    let (cdxady, adxcdy) = (cdx * ady, adx * cdy);
    let (adxbdy, bdxady) = (adx * bdy, bdx * ady);
    let alift = adx * adx + ady * ady;
    let blift = bdx * bdx + bdy * bdy;
    let clift = cdx * cdx + cdy * cdy;
    let det = alift * (bdxcdy - cdxbdy) + blift * (cdxady - adxcdy) + clift * (adxbdy - bdxady);
    let permanent = (bdxcdy.abs() + cdxbdy.abs()) * alift
        + (cdxady.abs() + adxcdy.abs()) * blift
        + (adxbdy.abs() + bdxady.abs()) * clift;
    if det.abs() > ICC_ERR_BOUND * permanent {
        return det;
    }
    robust::incircle(a, b, c, d)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn c(x: f64, y: f64) -> Coord<f64> {
        Coord { x, y }
    }

    #[test]
    fn signs_agree_with_robust_also_near_degenerate() {
        let mut s = 0x1234_5678_9ABC_DEF1u64;
        let mut next = || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut near = 0;
        for k in 0..20000 {
            // Every other case on a circle or a line, perturbed in the last bits.
            let p: Vec<Coord<f64>> = if k % 2 == 0 {
                (0..4)
                    .map(|_| c(300.0 + 3.0 * next(), 3.0 * next()))
                    .collect()
            } else {
                let t: Vec<f64> = (0..4).map(|_| std::f64::consts::TAU * next()).collect();
                t.iter()
                    .map(|a| c(200.0 + 0.7 * a.cos(), 5.0 + 0.7 * a.sin()))
                    .collect()
            };
            let (i_fast, i_exact) = (
                incircle(p[0], p[1], p[2], p[3]),
                robust::incircle(p[0], p[1], p[2], p[3]),
            );
            assert_eq!(i_fast.partial_cmp(&0.0), i_exact.partial_cmp(&0.0), "{p:?}");
            let line = c(
                p[0].x + 2.0 * (p[1].x - p[0].x),
                p[0].y + 2.0 * (p[1].y - p[0].y),
            );
            for q in [p[2], line] {
                let (o_fast, o_exact) = (orient2d(p[0], p[1], q), robust::orient2d(p[0], p[1], q));
                assert_eq!(o_fast.partial_cmp(&0.0), o_exact.partial_cmp(&0.0), "{p:?}");
            }
            near += (k % 2 == 1) as usize;
        }
        assert!(near > 0);
    }
}
