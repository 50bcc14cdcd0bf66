//! Earliest root of a polynomial of degree at most 4 on an interval: the pair-event solver of
//! the shear drive (docs/model.md 4.2).
//!
//! Two particles in slabs of different force have a constant relative acceleration `a`, so their
//! squared distance minus the contact distance squared,
//!
//! ```text
//! p(t) = |r + v t + a t^2 / 2|^2 - sigma^2
//!      = |a|^2/4 t^4 + (a.v) t^3 + (|v|^2 + a.r) t^2 + 2 (r.v) t + (|r|^2 - sigma^2),
//! ```
//!
//! is a quartic in the time `t` (the thesis used the Herbison-Evans quartic solver). The bonded
//! pair's well edge at `s = s_crit` is the same quartic with `sigma + s_crit` and the sign
//! reversed.
//!
//! Method (no closed-form quartic formula, whose cancellation can lose or invent roots):
//! *isolation by derivatives*. The real roots of `p'` split `[0, T]` into pieces on which `p` is
//! monotone; `p'` is a cubic whose roots come the same way from its quadratic derivative, and
//! so on down to a linear polynomial. On a monotone piece `p` has a root exactly when its end
//! values differ in sign, and that root is found by Newton steps safeguarded by bisection (a
//! Newton step leaving the bracket is replaced by bisection; the bracket always shrinks). A root
//! of `p` can therefore only be missed where `p` does not change sign: a double root (tangential
//! contact) at a critical point. Critical points where `|p|` is within the evaluation error bound
//! `16 eps sum |c_k| t^k` of zero are treated as contacts, so a grazing contact is never lost to
//! round-off either.
//!
//! [`earliest_entry`] returns the first time at which `p` is `<= 0` *and* not increasing: a
//! contact while approaching (or, negated, a bonded pair reaching the well edge while separating).

/// At most 6 sorted points (ends plus up to 4 critical points), on the stack: the solver runs
/// in the engine's hot path and allocates nothing.
#[derive(Debug, Clone, Copy, Default)]
pub struct Points {
    x: [f64; 6],
    len: usize,
}

impl Points {
    fn push(&mut self, v: f64) {
        if self.len < self.x.len() {
            self.x[self.len] = v;
            self.len += 1;
        }
    }

    /// The points, sorted.
    pub fn as_slice(&self) -> &[f64] {
        &self.x[..self.len]
    }

    fn last(&self) -> Option<f64> {
        self.as_slice().last().copied()
    }
}

/// A polynomial `c[0] + c[1] t + ... + c[n] t^n`, `n <= 4`, stored with its degree.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Poly {
    c: [f64; 5],
    n: usize,
}

impl Poly {
    /// `scale * prod_k (t - r_k)` for at most four roots (test cases with known roots).
    pub fn from_roots(roots: &[f64], scale: f64) -> Poly {
        assert!(roots.len() <= 4, "a quartic has at most four roots");
        let mut c = [0.0; 5];
        c[0] = scale;
        for (m, &r) in roots.iter().enumerate() {
            // Multiply the degree-m polynomial by (t - r), highest coefficient first.
            for k in (0..=m + 1).rev() {
                let lower = if k > 0 { c[k - 1] } else { 0.0 };
                c[k] = lower - r * c[k];
            }
        }
        Poly::new(c)
    }

    /// The polynomial with coefficients `c` (lowest order first); trailing zeros lower the
    /// degree.
    pub fn new(c: [f64; 5]) -> Self {
        let mut n = 4;
        while n > 0 && c[n] == 0.0 {
            n -= 1;
        }
        Poly { c, n }
    }

    /// Coefficients, lowest order first.
    pub fn coefficients(&self) -> [f64; 5] {
        self.c
    }

    /// `p(t)` by Horner's rule.
    #[inline]
    pub(crate) fn eval(&self, t: f64) -> f64 {
        let mut s = self.c[self.n];
        for k in (0..self.n).rev() {
            s = s * t + self.c[k];
        }
        s
    }

    /// `p(t)` and `p'(t)` together.
    #[inline]
    fn eval_d(&self, t: f64) -> (f64, f64) {
        let mut s = self.c[self.n];
        let mut d = 0.0;
        for k in (0..self.n).rev() {
            d = d * t + s;
            s = s * t + self.c[k];
        }
        (s, d)
    }

    /// Bound on the round-off of [`Poly::eval`] at `t`: `16 eps sum |c_k| |t|^k`.
    pub fn error_bound(&self, t: f64) -> f64 {
        let at = t.abs();
        let mut s = self.c[self.n].abs();
        for k in (0..self.n).rev() {
            s = s * at + self.c[k].abs();
        }
        16.0 * f64::EPSILON * s
    }

    pub fn derivative(&self) -> Poly {
        let mut c = [0.0; 5];
        for k in 1..=self.n {
            c[k - 1] = k as f64 * self.c[k];
        }
        Poly::new(c)
    }

    pub fn negated(&self) -> Poly {
        Poly::new(self.c.map(|x| -x))
    }

    /// Cauchy's bound: every real root has `|t| <= 1 + max_k |c_k / c_n|` (infinite for a
    /// constant).
    pub(crate) fn root_bound(&self) -> f64 {
        if self.n == 0 {
            return f64::INFINITY;
        }
        let lead = self.c[self.n].abs();
        1.0 + self.c[..self.n]
            .iter()
            .map(|x| x.abs() / lead)
            .fold(0.0, f64::max)
    }

    /// Sorted real roots in `[a, b]` where the sign changes (simple and odd-order roots), found
    /// by isolation through the derivative's roots. Even-order roots (no sign change) are not
    /// listed; [`earliest_entry`] handles them at the critical points.
    pub(crate) fn sign_changes_in(&self, a: f64, b: f64) -> Points {
        let mut out = Points::default();
        if a.partial_cmp(&b)
            .is_none_or(|o| o == std::cmp::Ordering::Greater)
        {
            return out;
        }
        let pieces = self.monotone_pieces(a, b);
        for (x0, x1) in pieces.as_slice().windows(2).map(|w| (w[0], w[1])) {
            let (p0, p1) = (self.eval(x0), self.eval(x1));
            if p1 == 0.0 {
                if out.last() != Some(x1) {
                    out.push(x1);
                }
            } else if p0 != 0.0 && (p0 < 0.0) != (p1 < 0.0) {
                out.push(self.refine(x0, x1));
            }
        }
        out
    }

    /// `[a, c_1, ..., c_k, b]`: the ends and the critical points (roots of `p'`) between them;
    /// `p` is monotone between consecutive entries.
    fn monotone_pieces(&self, a: f64, b: f64) -> Points {
        let mut pts = Points::default();
        pts.push(a);
        if self.n >= 2 {
            for &c in self.derivative().sign_changes_in(a, b).as_slice() {
                if c > a && c < b {
                    pts.push(c);
                }
            }
        }
        pts.push(b);
        pts
    }

    /// The root in `[lo, hi]` of a polynomial monotone there with `p(lo)` and `p(hi)` of
    /// opposite signs: Newton steps safeguarded by bisection. Returns the bracket end on the side
    /// of `p(lo)`'s sign (for a pair: the last time they do not yet touch), so a root is never
    /// overshot.
    fn refine(&self, mut lo: f64, mut hi: f64) -> f64 {
        let lo_negative = self.eval(lo) < 0.0;
        let mut x = 0.5 * (lo + hi);
        for _ in 0..200 {
            let (p, d) = self.eval_d(x);
            if p == 0.0 {
                return x;
            }
            if (p < 0.0) == lo_negative {
                lo = x;
            } else {
                hi = x;
            }
            if hi - lo <= 4.0 * f64::EPSILON * lo.abs().max(hi.abs())
                || hi - lo <= f64::MIN_POSITIVE
            {
                break;
            }
            // Newton from x; bisection where the step leaves the bracket or stalls.
            let newton = x - p / d;
            x = if d != 0.0 && newton > lo && newton < hi {
                newton
            } else {
                0.5 * (lo + hi)
            };
            if x <= lo || x >= hi {
                x = 0.5 * (lo + hi);
                if x <= lo || x >= hi {
                    break;
                }
            }
        }
        lo
    }
}

/// Earliest `t` in `[0, horizon]` at which `p(t) <= 0` while `p` is not increasing, or `None`.
///
/// - `p(0) <= 0` and `p` decreasing at 0: returns 0 (overlap safeguard: approaching while
///   overlapping acts now, docs/model.md 6 B.5.6).
/// - Pieces where `p` increases are skipped (touching but separating: no event).
/// - On a decreasing piece `[x0, x1]`: `p(x0) <= 0` gives `x0` (a local maximum still at or
///   below zero: contact held, now approaching); a sign change gives the refined root (the last
///   time before it); `0 < p(x1) <= error bound` at a critical point `x1` gives `x1` (a
///   tangential contact, double root, that round-off may lift above zero).
///
/// An infinite `horizon` is replaced by Cauchy's root bound.
pub fn earliest_entry(p: &Poly, horizon: f64) -> Option<f64> {
    let end = horizon.min(p.root_bound());
    if p.n == 0 {
        return None;
    }
    if end.is_nan() || end < 0.0 {
        return None;
    }
    let pts = p.monotone_pieces(0.0, end);
    let dp = p.derivative();
    let pts = pts.as_slice();
    let last = pts.len() - 1;
    for (k, w) in pts.windows(2).enumerate() {
        let (x0, x1) = (w[0], w[1]);
        let (p0, p1) = (p.eval(x0), p.eval(x1));
        // Direction of the piece: from its end values, or the derivative inside when they tie.
        let decreasing = if p1 != p0 {
            p1 < p0
        } else {
            dp.eval(0.5 * (x0 + x1)) < 0.0
        };
        if !decreasing {
            continue;
        }
        if p0 <= 0.0 {
            return Some(x0);
        }
        if p1 <= 0.0 {
            return Some(p.refine(x0, x1));
        }
        // x1 is a critical point (not the horizon) where p touches zero within round-off.
        if k + 1 < last && p1 <= p.error_bound(x1) {
            return Some(x1);
        }
    }
    None
}

/// The contact quartic of two bodies with relative position `r`, velocity `v` and constant
/// acceleration `a` (all `i` minus `j`) and contact distance `sigma`:
/// `p(t) = |r + v t + a t^2/2|^2 - sigma^2` (module doc).
pub fn contact_quartic<const D: usize>(
    r: &[f64; D],
    v: &[f64; D],
    a: &[f64; D],
    sigma: f64,
) -> Poly {
    let dot = |x: &[f64; D], y: &[f64; D]| x.iter().zip(y).map(|(p, q)| p * q).sum::<f64>();
    Poly::new([
        dot(r, r) - sigma * sigma,
        2.0 * dot(r, v),
        dot(v, v) + dot(a, r),
        dot(a, v),
        0.25 * dot(a, a),
    ])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn simple_roots_are_found_in_order() {
        let p = Poly::from_roots(&[0.5, 1.5, 2.0, 3.25], 1.0);
        let r = p.sign_changes_in(0.0, 10.0);
        let r = r.as_slice();
        assert_eq!(r.len(), 4);
        for (got, want) in r.iter().zip([0.5, 1.5, 2.0, 3.25]) {
            assert!((got - want).abs() < 1e-12, "{got} vs {want}");
        }
        // p > 0 before 0.5 and decreasing into it: the first entry.
        let t = earliest_entry(&p, f64::INFINITY).unwrap();
        assert!((t - 0.5).abs() < 1e-12 && t <= 0.5);
    }

    #[test]
    fn increasing_start_is_skipped() {
        // p = (t + 1)(t - 2)(t - 3)(t - 4): p(0) = -24 < 0 but p'(0) = 2 > 0 (overlapping and
        // separating: no event); p rises through 2, turns in (2, 3) and enters p <= 0 at 3.
        let p = Poly::from_roots(&[-1.0, 2.0, 3.0, 4.0], 1.0);
        let t = earliest_entry(&p, 10.0).unwrap();
        assert!((t - 3.0).abs() < 1e-12, "{t}");
        // Negated: -p(0) = 24 > 0 and falling: the entry is the first root, 2.
        let t = earliest_entry(&p.negated(), 10.0).unwrap();
        assert!((t - 2.0).abs() < 1e-12, "{t}");
        // Overlapping (p(0) < 0) and approaching (p'(0) < 0): now.
        let q = Poly::from_roots(&[-0.5, 2.0, 3.0, 4.0], 1.0);
        assert!(q.eval(0.0) < 0.0);
        assert_eq!(earliest_entry(&q, 10.0), Some(0.0));
    }
}
