//! The quartic pair solver of the shear drive (`physics::quartic`) against an independent
//! high-precision reference: double-double (about 32 significant digits) evaluation of the same
//! polynomial, a fine scan for the first entry into `p <= 0` and bisection. Random contact
//! quartics and nearly degenerate ones (double roots, close root pairs, tangential contacts
//! under a relative acceleration): the solver's earliest root is never later than the
//! reference's.

use rand::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus as ChaCha8Rng;
use wetgran_core::physics::quartic::{Poly, contact_quartic, earliest_entry};

/// `a + b` exactly as `(sum, error)`.
fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let bb = s - a;
    (s, (a - (s - bb)) + (b - bb))
}

/// `p(t)` in double-double arithmetic (the coefficients taken as exact).
fn eval_dd(p: &Poly, t: f64) -> f64 {
    let c = p.coefficients();
    let (mut hi, mut lo) = (c[4], 0.0);
    for k in (0..4).rev() {
        // (hi + lo) * t exactly up to lo * t's rounding, then + c[k].
        let ph = hi * t;
        let pl = hi.mul_add(t, -ph) + lo * t;
        let (s, e) = two_sum(ph, c[k]);
        let (h2, l2) = two_sum(s, e + pl);
        hi = h2;
        lo = l2;
    }
    hi + lo
}

/// The first time in `[0, horizon]` at which `p` (positive at 0) reaches zero, by a scan of
/// `steps` samples and bisection, all in double-double; `None` if it stays positive at every
/// sample.
fn reference_entry(p: &Poly, horizon: f64, steps: usize) -> Option<f64> {
    assert!(eval_dd(p, 0.0) > 0.0);
    let mut prev = 0.0;
    for k in 1..=steps {
        let t = horizon * k as f64 / steps as f64;
        if eval_dd(p, t) <= 0.0 {
            let (mut lo, mut hi) = (prev, t);
            for _ in 0..200 {
                let mid = 0.5 * (lo + hi);
                if mid <= lo || mid >= hi {
                    break;
                }
                if eval_dd(p, mid) > 0.0 {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            return Some(hi);
        }
        prev = t;
    }
    None
}

/// Checks the solver against the reference on one polynomial with `p(0) > 0`.
fn check(p: &Poly, horizon: f64, label: &str) {
    let got = earliest_entry(p, horizon);
    let want = reference_entry(p, horizon, 20_000);
    match (got, want) {
        (None, Some(w)) => panic!("{label}: solver missed the root at {w}: {p:?}"),
        (Some(g), Some(w)) => {
            let tol = 1e-9 * w.max(1.0);
            if g > w + tol {
                panic!("{label}: solver root {g} later than reference {w}: {p:?}");
            }
            if g < w - tol {
                // Earlier than the scan's first sign change: only a real touch in between
                // (two roots closer than a scan step) may explain it.
                let at = eval_dd(p, g);
                assert!(
                    at <= p.error_bound(g) * 4.0 || reference_entry_near(p, g),
                    "{label}: solver root {g} before reference {w} with p = {at}: {p:?}"
                );
            }
        }
        (Some(g), None) => {
            // The scan saw no sign change: the solver may only report a (near-)touch.
            let at = eval_dd(p, g);
            assert!(
                at <= p.error_bound(g) * 4.0 || reference_entry_near(p, g),
                "{label}: solver invents a root at {g} with p = {at}: {p:?}"
            );
        }
        (None, None) => {}
    }
}

/// Whether `p` dips to `<= 0` in a tiny neighbourhood of `t` (roots closer than a scan step).
fn reference_entry_near(p: &Poly, t: f64) -> bool {
    let h = 1e-6 * t.abs().max(1e-3);
    (0..=2000).any(|k| eval_dd(p, t - h + 2.0 * h * k as f64 / 2000.0) <= 0.0)
}

/// Seeds of the random samples (named, so a failing case reproduces with the same numbers).
const RANDOM_CONTACTS_SEED: u64 = 7;
const DOUBLE_ROOTS_SEED: u64 = 11;
const TANGENTIAL_SEED: u64 = 3;

#[test]
fn random_contact_quartics_match_the_reference() {
    let mut rng = ChaCha8Rng::seed_from_u64(RANDOM_CONTACTS_SEED);
    let mut found = 0;
    for case in 0..3000 {
        let sigma = rng.gen_range(0.8..1.2);
        // Outside contact, within a couple of diameters, random velocities and a relative
        // acceleration along y of either sign.
        let r = loop {
            let r = [
                rng.gen_range(-1.8..1.8),
                rng.gen_range(-1.8..1.8),
                rng.gen_range(-1.8..1.8),
            ];
            let rr: f64 = r.iter().map(|x| x * x).sum();
            if rr > sigma * sigma * 1.0001 {
                break r;
            }
        };
        let v = [
            rng.gen_range(-2.0..2.0),
            rng.gen_range(-2.0..2.0),
            rng.gen_range(-2.0..2.0),
        ];
        let a = [0.0, rng.gen_range(-2.0..2.0), 0.0];
        let p = contact_quartic(&r, &v, &a, sigma);
        let horizon = rng.gen_range(0.5..6.0);
        check(&p, horizon, &format!("contact case {case}"));
        // The well edge of a bonded pair: the negated quartic at sigma + s_crit, from inside.
        let lambda = (r.iter().map(|x| x * x).sum::<f64>()).sqrt() * rng.gen_range(1.0001..1.2);
        let q = contact_quartic(&r, &v, &a, lambda).negated();
        check(&q, horizon, &format!("well case {case}"));
        found += usize::from(earliest_entry(&p, horizon).is_some());
    }
    // The sample holds many hits, not only misses.
    assert!(found > 200, "only {found} contacts in the sample");
}

#[test]
fn double_roots_and_close_pairs_are_never_missed() {
    let mut rng = ChaCha8Rng::seed_from_u64(DOUBLE_ROOTS_SEED);
    for case in 0..500 {
        let r0 = rng.gen_range(0.05..3.0);
        let far = r0 + rng.gen_range(0.5..2.0);
        let farther = far + rng.gen_range(0.1..2.0);
        let scale = rng.gen_range(0.01..10.0);
        // A double root (tangential contact): touching without a sign change.
        let p = Poly::from_roots(&[r0, r0, far, farther], scale);
        let t = earliest_entry(&p, 10.0)
            .unwrap_or_else(|| panic!("case {case}: double root at {r0} missed: {p:?}"));
        assert!(
            (t - r0).abs() <= 1e-6 * r0.max(1.0),
            "case {case}: double root {r0} reported at {t}"
        );
        // Two roots closer than any fixed step: the entry is the first.
        let delta = 10f64.powf(rng.gen_range(-10.0..-4.0));
        let q = Poly::from_roots(&[r0, r0 + delta, far, farther], scale);
        let t = earliest_entry(&q, 10.0)
            .unwrap_or_else(|| panic!("case {case}: close pair at {r0} (+{delta}) missed"));
        // Against the nominal roots only to the conditioning of a near-double root: rounding
        // the coefficients to f64 moves it by about sqrt(eps) (the exact check is `check`).
        assert!(
            (t - r0).abs() <= 1e-6 * r0.max(1.0),
            "case {case}: close pair at {r0} reported at {t}"
        );
        check(&q, 10.0, &format!("close pair {case}"));
    }
}

#[test]
fn tangential_contacts_under_relative_acceleration() {
    // r = (b, -1, 0), v = (0, u, 0), a = (0, a_y, 0): |r(t)|^2 - sigma^2 = b^2 - sigma^2 +
    // y(t)^2 with y(t) = -1 + u t + a_y t^2 / 2. With b = sigma the pair grazes (double root)
    // when y(t) = 0.
    let mut rng = ChaCha8Rng::seed_from_u64(TANGENTIAL_SEED);
    for case in 0..500 {
        let sigma = rng.gen_range(0.8..1.2);
        let u: f64 = rng.gen_range(0.2..2.0);
        let a_y: f64 = rng.gen_range(-0.05..2.0);
        // Root of -1 + u t + a t^2 / 2, cancellation-free: t = 2 / (u + sqrt(u^2 + 2 a)).
        let t_star = 2.0 / (u + (u * u + 2.0 * a_y).sqrt());
        let v = [0.0, u, 0.0];
        let a = [0.0, a_y, 0.0];
        // Exactly tangential, just crossing, and just missing.
        let graze = contact_quartic(&[sigma, -1.0, 0.0], &v, &a, sigma);
        let t = earliest_entry(&graze, 10.0)
            .unwrap_or_else(|| panic!("case {case}: tangential contact at {t_star} missed"));
        assert!((t - t_star).abs() <= 1e-6, "case {case}: {t} vs {t_star}");
        let cross = contact_quartic(&[sigma * (1.0 - 1e-9), -1.0, 0.0], &v, &a, sigma);
        let t = earliest_entry(&cross, 10.0)
            .unwrap_or_else(|| panic!("case {case}: shallow crossing at {t_star} missed"));
        assert!(t <= t_star + 1e-9 && t >= t_star - 1e-3, "case {case}: {t}");
        check(&cross, 10.0, &format!("shallow crossing {case}"));
        let miss = contact_quartic(&[sigma * (1.0 + 1e-3), -1.0, 0.0], &v, &a, sigma);
        assert_eq!(
            earliest_entry(&miss, 10.0),
            None,
            "case {case}: a clear miss hits"
        );
    }
}

#[test]
fn touching_now_and_separating_is_no_event_but_coming_back_is() {
    // At contact, separating along x, pulled back along y by nothing: no event.
    let p = contact_quartic(&[1.0, 0.0, 0.0], &[0.5, 0.0, 0.0], &[0.0, 1.0, 0.0], 1.0);
    assert_eq!(earliest_entry(&p, 100.0), None);
    // At contact and separating along y while the relative acceleration pulls the pair back:
    // the next contact is when y returns to 0, at t = 2 u / |a| (r_x = sigma exactly).
    let p = contact_quartic(&[1.0, 0.0, 0.0], &[0.0, 0.5, 0.0], &[0.0, -1.0, 0.0], 1.0);
    let t = earliest_entry(&p, 100.0).expect("the pair comes back");
    assert!((t - 1.0).abs() < 1e-6, "{t}");
}
