//! Collision times of a particle flying on a parabola with a sinusoidally moving flat wall
//! (docs/model.md 6, Appendix B of the thesis).
//!
//! In the wall's axis, origin at the wall's mean position, particle on the `+` side, the gap is
//!
//! ```text
//! s_rel(dt) = (-g/2 dt^2 + v dt + s - R) - A sin(omega (t0 + dt))            (Eq. B.7)
//! ```
//!
//! (the lid is the same problem mirrored: `g -> -g`, coordinates measured downwards). The
//! collision is the smallest `dt > 0` with `s_rel(dt) = 0` reached from above.
//!
//! [`exact_root`] is conservative advancement: with `|s_rel''| <= K = |g| + A omega^2`, the gap
//! after a step `h` is at least `s + s' h - K h^2 / 2`, so stepping by the first zero of that
//! bound can never jump over a root. It stops within a requested gap tolerance of the earliest
//! root, from the safe side. [`reference_root`] brackets the same root with a fine fixed step and
//! bisection to round-off; it is the slow independent method the tests compare against.

use std::f64::consts::PI;

/// A sinusoidal wall motion `z_w(t) = A sin(omega t)` and the particle's acceleration towards
/// the wall's `-` side (`g > 0` pulls the particle towards the wall, as gravity does for the
/// floor; use `-g` for the lid).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WallMotion {
    pub amplitude: f64,
    pub omega: f64,
    pub g: f64,
}

impl WallMotion {
    /// Wall position at time `t`.
    #[inline]
    pub fn position(&self, t: f64) -> f64 {
        self.amplitude * (self.omega * t).sin()
    }

    /// Wall velocity at time `t`.
    #[inline]
    pub fn velocity(&self, t: f64) -> f64 {
        self.amplitude * self.omega * (self.omega * t).cos()
    }

    /// Bound on the second derivative of the gap: `|g| + A omega^2`.
    #[inline]
    pub(crate) fn curvature_bound(&self) -> f64 {
        self.g.abs() + self.amplitude * self.omega * self.omega
    }

    /// Driving period `2 pi / omega`.
    pub fn period(&self) -> f64 {
        2.0 * PI / self.omega
    }

    /// Gap `s_rel` and its rate at `t0 + dt` for a particle whose contact coordinate (centre
    /// height minus radius) is `h` with velocity `v` at `t0` (Eq. B.7).
    #[inline]
    pub fn gap(&self, h: f64, v: f64, t0: f64, dt: f64) -> (f64, f64) {
        let t = t0 + dt;
        let s = h + v * dt - 0.5 * self.g * dt * dt - self.position(t);
        let ds = v - self.g * dt - self.velocity(t);
        (s, ds)
    }
}

/// Outcome of a wall-root search.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum WallRoot {
    /// The particle reaches the wall after `dt` (from `t0`).
    Hit(f64),
    /// No contact within the searched horizon (the particle flies away from the wall).
    None,
}

/// Earliest time the gap closes, by conservative advancement, to gap tolerance `tol`:
/// the returned `dt` satisfies `0 <= s_rel(dt) <= tol` and no root lies in `[0, dt)`.
/// A particle that already overlaps the wall and approaches it hits now (docs/model.md 6, B.5.6).
/// The search gives up after `horizon` (returns [`WallRoot::None`]); with `g > 0` every flight
/// comes back, so callers pass a horizon beyond which they re-query.
pub fn exact_root(w: &WallMotion, h: f64, v: f64, t0: f64, tol: f64, horizon: f64) -> WallRoot {
    match exact_root_until(w, h, v, t0, tol, horizon, f64::INFINITY, None) {
        Search::Done(root) => root,
        Search::Later(_) => unreachable!("a search without a bound runs to its end"),
    }
}

/// Where an [`exact_root_until`] search stands.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Search {
    /// The answer of [`exact_root`].
    Done(WallRoot),
    /// [`exact_root`]'s answer lies beyond the bound `until`: the search goes on from this
    /// step (`None`: from its start), with the same steps as one search without a bound.
    Later(Option<f64>),
}

/// [`exact_root`] stopped once its answer is known to lie beyond `until` (a time after `t0`,
/// as `horizon`), and resumed from where it stopped (`from`, a [`Search::Later`]'s step):
/// searches resumed until [`Search::Done`] give exactly [`exact_root`]'s answer, bit for bit,
/// whatever the bounds. A search starts with a bound that needs no sine: when the particle's
/// flight stays above the wall's crest (`A`) by more than `tol` up to `until` and the steps
/// cannot fall below the clock's resolution there, no answer lies before `until` and nothing
/// is computed (`Later(None)`). Otherwise the search steps on and stops at its first step
/// beyond `until`.
pub fn exact_root_until(
    w: &WallMotion,
    h: f64,
    v: f64,
    t0: f64,
    tol: f64,
    horizon: f64,
    until: f64,
    from: Option<f64>,
) -> Search {
    let k = w.curvature_bound();
    if let Some(tau) = from {
        let (s, ds) = w.gap(h, v, t0, tau);
        if s <= tol {
            return Search::Done(WallRoot::Hit(tau));
        }
        return advance(w, h, v, t0, tol, horizon, until, (tau, s, ds));
    }
    if until < horizon && clear_of_the_wall(w, h, v, tol, until) {
        return Search::Later(None);
    }
    let (mut s, mut ds) = w.gap(h, v, t0, 0.0);
    // On or behind the wall: hit now if approaching; if separating, first march until the gap
    // has opened (bound-based steps need s > 0).
    if s <= tol && ds < 0.0 {
        return Search::Done(WallRoot::Hit(0.0));
    }
    let mut tau = 0.0;
    let mut guard = 0u32;
    while s <= tol {
        // s' >= 0 here; the gap keeps opening for at least ds / k.
        let step = (ds / k).max(1e-12 * w.period());
        tau += step;
        (s, ds) = w.gap(h, v, t0, tau);
        if s <= tol && ds < 0.0 {
            return Search::Done(WallRoot::Hit(tau));
        }
        guard += 1;
        if guard > 1_000_000 || tau > horizon {
            return Search::Done(WallRoot::None);
        }
    }
    advance(w, h, v, t0, tol, horizon, until, (tau, s, ds))
}

/// The conservative advancement of [`exact_root_until`] from `(tau, s, ds)` (`s > tol`),
/// stopped at its first step beyond `until`.
fn advance(
    w: &WallMotion,
    h: f64,
    v: f64,
    t0: f64,
    tol: f64,
    horizon: f64,
    until: f64,
    (mut tau, mut s, mut ds): (f64, f64, f64),
) -> Search {
    let k = w.curvature_bound();
    loop {
        // First zero of the lower bound s + ds h - k h^2 / 2 (cancellation-free form).
        let step = 2.0 * s / ((ds * ds + 2.0 * k * s).sqrt() - ds);
        if tau + step <= tau {
            // The step fell below the resolution of the clock: the root is here to machine
            // precision (a tolerance below round-off of the gap lands in this case).
            return Search::Done(WallRoot::Hit(tau));
        }
        tau += step;
        if tau > horizon {
            return Search::Done(WallRoot::None);
        }
        if tau > until {
            return Search::Later(Some(tau));
        }
        (s, ds) = w.gap(h, v, t0, tau);
        if s <= tol {
            return Search::Done(WallRoot::Hit(tau));
        }
    }
}

/// Whether [`exact_root`] from `(h, v)` surely ends after `until`, from bounds without a
/// sine: on `[0, until]` the gap is at least `m = h - A - max(0, -v) until - max(0, g) until^2
/// / 2` and its rate at most `|v| + |g| until + A omega` in size, so with `m` above `tol` (by a
/// margin for the gap's round-off) no step stops on a contact, and with the smallest step
/// `2 m / (sqrt(rate^2 + 2 K m) + rate)` (the step grows with the gap) above four times the
/// clock's resolution at `until` none stops on the resolution either.
fn clear_of_the_wall(w: &WallMotion, h: f64, v: f64, tol: f64, until: f64) -> bool {
    let a = w.amplitude.abs();
    let m = h - a - (-v).max(0.0) * until - 0.5 * w.g.max(0.0) * until * until;
    let margin = 1e-9 * (1.0 + h.abs() + a);
    // A NaN bound proves nothing.
    if m.is_nan() || m <= tol + margin {
        return false;
    }
    let rate = v.abs() + w.g.abs() * until + a * w.omega.abs();
    let k = w.curvature_bound();
    let step = 2.0 * m / ((rate * rate + 2.0 * k * m).sqrt() + rate);
    step > 4.0 * f64::EPSILON * until
}

/// The thesis's reference algorithm (B.3): march in steps of `t_min` until the gap changes
/// sign, then refine with Newton-Raphson safeguarded by bisection to gap tolerance `tol`.
/// Termination rules: a particle above the wall's reach (`h > A`) cannot hit before its parabola
/// falls to `h = A`, so the march starts there (computed exactly); a particle that leaves the
/// reach upwards is followed to its re-entry the same way; the search stops at `horizon`.
/// Roots narrower than `t_min` (grazing shots) can be missed: `t_min` is the accuracy knob.
pub fn bracket_root(
    w: &WallMotion,
    h: f64,
    v: f64,
    t0: f64,
    t_min: f64,
    tol: f64,
    horizon: f64,
) -> WallRoot {
    let (s0, ds0) = w.gap(h, v, t0, 0.0);
    if s0 <= tol && ds0 < 0.0 {
        return WallRoot::Hit(0.0);
    }
    let reach = w.amplitude;
    // Height of the particle (without the wall) relative to the wall's mean position.
    let height = |dt: f64| h + v * dt - 0.5 * w.g * dt * dt;
    let rate = |dt: f64| v - w.g * dt;
    let mut tau = 0.0;
    loop {
        if tau > horizon {
            return WallRoot::None;
        }
        if height(tau) > reach {
            // Above the reach: jump to the time the parabola falls back to h = A.
            match time_to_fall_to(height(tau), rate(tau), w.g, reach) {
                Some(dt) => tau += dt,
                None => return WallRoot::None,
            }
        }
        // Inside the reach: march.
        let (mut s_a, _) = w.gap(h, v, t0, tau);
        loop {
            let b = tau + t_min;
            let (s_b, _) = w.gap(h, v, t0, b);
            if s_a > 0.0 && s_b <= 0.0 {
                return WallRoot::Hit(refine(w, h, v, t0, tau, b, tol));
            }
            tau = b;
            s_a = s_b;
            if tau > horizon {
                return WallRoot::None;
            }
            if height(tau) > reach && rate(tau) > 0.0 {
                break; // left the reach upwards: find the re-entry
            }
        }
    }
}

/// Time until a parabola at height `z` with rate `v` and acceleration `-g` first reaches
/// `plane < z` from above; `None` if it never does.
fn time_to_fall_to(z: f64, v: f64, g: f64, plane: f64) -> Option<f64> {
    let dz = z - plane; // > 0
    if g > 0.0 {
        Some(crate::physics::flight::parabola_time_down(z, v, g, plane))
    } else if g < 0.0 {
        // Accelerating away from the wall (the lid problem): reaches the plane only if moving
        // towards it fast enough: dz + v t + |g| t^2 / 2 = 0 with v < 0.
        let a = -g;
        let disc = v * v - 2.0 * a * dz;
        if v >= 0.0 || disc < 0.0 {
            None
        } else {
            Some(2.0 * dz / (-v + disc.sqrt()))
        }
    } else if v < 0.0 {
        Some(dz / -v)
    } else {
        None
    }
}

/// Newton-Raphson on the gap, safeguarded by bisection on the bracket `[a, b]`
/// (`s(a) > 0 >= s(b)`), until the gap is within `[0, tol]` or the bracket is exhausted; returns
/// the time on the particle's side of the wall.
fn refine(w: &WallMotion, h: f64, v: f64, t0: f64, mut a: f64, mut b: f64, tol: f64) -> f64 {
    let mut x = 0.5 * (a + b);
    for _ in 0..200 {
        let (s, ds) = w.gap(h, v, t0, x);
        if (0.0..=tol).contains(&s) {
            return x;
        }
        if s > 0.0 {
            a = x;
        } else {
            b = x;
        }
        let newton = if ds != 0.0 { x - s / ds } else { f64::NAN };
        x = if newton > a && newton < b {
            newton
        } else {
            0.5 * (a + b)
        };
        if b - a <= f64::EPSILON * b.abs().max(1.0) {
            break;
        }
    }
    a
}

/// Independent reference: steps of `step` (much finer than a period) until the gap changes
/// sign, then bisects to round-off. Tangential roots narrower than `step` can be missed, so this
/// is a test oracle, not an engine solver.
pub fn reference_root(
    w: &WallMotion,
    h: f64,
    v: f64,
    t0: f64,
    step: f64,
    horizon: f64,
) -> WallRoot {
    let (s0, ds0) = w.gap(h, v, t0, 0.0);
    if s0 <= 0.0 && ds0 < 0.0 {
        return WallRoot::Hit(0.0);
    }
    let mut a = 0.0;
    let mut sa = s0;
    while a < horizon {
        let b = a + step;
        let (sb, _) = w.gap(h, v, t0, b);
        if sa > 0.0 && sb <= 0.0 {
            return WallRoot::Hit(bisect(a, b, |t| w.gap(h, v, t0, t).0 > 0.0));
        }
        a = b;
        sa = sb;
    }
    WallRoot::None
}

/// Bisects `[lo, hi]` (`positive(lo)`, not `positive(hi)`) to round-off and returns the end
/// where `positive` is false.
pub(crate) fn bisect(mut lo: f64, mut hi: f64, positive: impl Fn(f64) -> bool) -> f64 {
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if positive(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    hi
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    fn motion(amplitude: f64, omega: f64, g: f64) -> WallMotion {
        WallMotion {
            amplitude,
            omega,
            g,
        }
    }

    #[test]
    fn static_wall_matches_the_parabola() {
        // A = 0: the root is the falling root of h + v t - g t^2 / 2 = 0.
        let w = motion(0.0, 1.0, 1.0);
        let (h, v) = (2.0f64, 0.5f64);
        let exact = (v + (v * v + 2.0 * h).sqrt()) / 1.0;
        match exact_root(&w, h, v, 0.3, 1e-12, 100.0) {
            WallRoot::Hit(t) => assert!((t - exact).abs() < 1e-9, "{t} vs {exact}"),
            r => panic!("{r:?}"),
        }
    }

    /// A floor motion with Gamma in [0.3, 20) and omega in [0.5, 10), g = 1.
    fn random_motion(rng: &mut impl Rng) -> WallMotion {
        let gamma: f64 = rng.gen_range(0.3..20.0);
        let omega: f64 = rng.gen_range(0.5..10.0);
        motion(gamma / (omega * omega), omega, 1.0)
    }

    #[test]
    fn exact_root_never_misses_the_earliest_root_on_random_shots() {
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(17);
        let mut worst_gap_time = 0.0f64;
        for _ in 0..3000 {
            let w = random_motion(&mut rng);
            let h = rng.gen_range(w.amplitude..(w.amplitude + 3.0));
            let v = rng.gen_range(-3.0..3.0);
            let t0 = rng.gen_range(0.0..w.period());
            let horizon = 20.0;
            let reference = reference_root(&w, h, v, t0, 1e-4 * w.period().min(1.0), horizon);
            let ours = exact_root(&w, h, v, t0, 1e-12, horizon);
            match (reference, ours) {
                (WallRoot::Hit(r), WallRoot::Hit(o)) => {
                    // Ours may only be earlier than the reference by the tolerance's worth, and
                    // never later (that would mean a skipped root).
                    assert!(
                        o <= r + 1e-9,
                        "skipped: ours {o}, reference {r}, {w:?} h={h} v={v}"
                    );
                    let (gap, _) = w.gap(h, v, t0, o);
                    assert!((-1e-9..=1e-12).contains(&gap), "gap at our root {gap}");
                    worst_gap_time = worst_gap_time.max(r - o);
                }
                (WallRoot::None, WallRoot::None) => {}
                // The stepping reference may miss a grazing root narrower than its step; ours
                // must then still have found a genuine contact.
                (WallRoot::None, WallRoot::Hit(o)) => {
                    assert!(w.gap(h, v, t0, o).0 <= 1e-12);
                }
                (r, o) => panic!("reference {r:?}, ours {o:?}, {w:?} h={h} v={v} t0={t0}"),
            }
        }
        assert!(worst_gap_time < 1e-6, "worst time error {worst_gap_time}");
    }

    /// Runs `exact_root_until` from the start through the bounds `untils` (then without a
    /// bound) and checks every `Later` against `answer` (in time units after `t0`).
    fn resumed(w: &WallMotion, h: f64, v: f64, t0: f64, untils: &[f64]) -> (WallRoot, usize) {
        let (tol, horizon) = (1e-10, 2.0 * w.period());
        let answer = exact_root(w, h, v, t0, tol, horizon);
        let mut from = None;
        let mut skipped = 0;
        for &until in untils.iter().chain(std::iter::once(&f64::INFINITY)) {
            match exact_root_until(w, h, v, t0, tol, horizon, until, from) {
                Search::Done(r) => return (r, skipped),
                Search::Later(f) => {
                    // The answer lies beyond the bound: a hit after it, or a miss (the caller's
                    // re-check at the horizon, which lies beyond it too).
                    if let WallRoot::Hit(t) = answer {
                        assert!(t > until, "answer {t} not beyond the bound {until}");
                    }
                    assert!(until < horizon);
                    skipped += usize::from(f.is_none());
                    from = f;
                }
            }
        }
        unreachable!("the last search has no bound")
    }

    #[test]
    fn a_search_resumed_through_bounds_gives_the_same_bits_as_one_search() {
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(29);
        let (mut paused, mut skipped) = (0, 0);
        for _ in 0..4000 {
            let w = random_motion(&mut rng);
            let lid = rng.gen_bool(0.3);
            let w = if lid { WallMotion { g: -w.g, ..w } } else { w };
            let h = rng.gen_range(-0.5 * w.amplitude..(w.amplitude + 4.0));
            let v = rng.gen_range(-3.0..3.0);
            let t0 = rng.gen_range(0.0..50.0);
            let mut untils: Vec<f64> = (0..rng.gen_range(0..5))
                .map(|_| rng.gen_range(0.0..2.0 * w.period()))
                .collect();
            untils.sort_by(f64::total_cmp);
            let one = exact_root(&w, h, v, t0, 1e-10, 2.0 * w.period());
            let (pieces, s) = resumed(&w, h, v, t0, &untils);
            let bits = |r: WallRoot| match r {
                WallRoot::Hit(t) => Some(t.to_bits()),
                WallRoot::None => None,
            };
            assert_eq!(
                bits(one),
                bits(pieces),
                "{w:?} h={h} v={v} t0={t0} {untils:?}"
            );
            paused += usize::from(!untils.is_empty());
            skipped += s;
        }
        assert!(
            paused > 2000 && skipped > 200,
            "{paused} paused, {skipped} without a sine"
        );
    }

    #[test]
    fn the_bound_without_a_sine_says_no_near_the_crest() {
        // Within reach of the crest, or a flight that falls to it before the bound, or a gap
        // too small for the clock at the bound: the search must compute.
        let w = motion(0.1, 4.0, 1.0);
        assert!(clear_of_the_wall(&w, 2.0, 0.0, 1e-10, 0.5));
        assert!(!clear_of_the_wall(&w, 0.1, 0.0, 1e-10, 0.5), "at the crest");
        assert!(!clear_of_the_wall(&w, 2.0, -4.0, 1e-10, 0.5), "falls to it");
        assert!(
            !clear_of_the_wall(&w, 2.0, 0.0, 1e-10, 2.0),
            "falls to it by gravity"
        );
        assert!(
            !clear_of_the_wall(&w, 0.1 + 1e-9, 0.0, 1e-10, 1e-6),
            "inside the round-off margin"
        );
    }

    #[test]
    fn bracket_root_agrees_with_exact_root_when_t_min_is_fine() {
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(23);
        let mut misses = 0;
        for _ in 0..2000 {
            let w = random_motion(&mut rng);
            let h = rng
                .gen_range(0.0..(w.amplitude + 3.0))
                .max(w.position(0.3) + 1e-9);
            let v = rng.gen_range(-3.0..3.0);
            let t0 = 0.3;
            let exact = exact_root(&w, h, v, t0, 1e-13, 20.0);
            let bracket = bracket_root(&w, h, v, t0, 1e-3 * w.period(), 1e-13, 20.0);
            match (exact, bracket) {
                (WallRoot::Hit(e), WallRoot::Hit(b)) => {
                    if (e - b).abs() > 1e-8 {
                        // Only a grazing root narrower than t_min may be missed, and then the
                        // bracket root is later.
                        assert!(b > e, "bracket earlier than the earliest root: {b} < {e}");
                        misses += 1;
                    }
                }
                (WallRoot::None, WallRoot::None) => {}
                (e, b) => panic!("exact {e:?}, bracket {b:?}, {w:?} h={h} v={v}"),
            }
        }
        assert!(misses < 20, "{misses} grazing misses out of 2000");
    }

    #[test]
    fn lid_problem_with_gravity_pointing_away() {
        // g < 0: the particle accelerates away from the (mirrored) lid; thrown towards it fast
        // enough it hits, otherwise never.
        let w = motion(0.05, 4.0, -1.0);
        for (h, v, hits) in [(1.0, -3.0, true), (1.0, -0.5, false), (1.0, 1.0, false)] {
            let e = exact_root(&w, h, v, 0.0, 1e-12, 10.0);
            let b = bracket_root(&w, h, v, 0.0, 1e-4, 1e-12, 10.0);
            assert_eq!(
                matches!(e, WallRoot::Hit(_)),
                hits,
                "exact h={h} v={v}: {e:?}"
            );
            assert_eq!(
                matches!(b, WallRoot::Hit(_)),
                hits,
                "bracket h={h} v={v}: {b:?}"
            );
            if let (WallRoot::Hit(x), WallRoot::Hit(y)) = (e, b) {
                assert!((x - y).abs() < 1e-9);
            }
        }
    }

    #[test]
    fn tolerance_below_round_off_terminates() {
        // A gap tolerance below the round-off of the gap must not make the step underflow the
        // clock's resolution, which would keep the loop from ending.
        let w = motion(0.3, 2.0, 1.0);
        for &(h, v, t0) in &[(3.0, -1.0, 1234.5), (0.5, 0.3, 0.7), (2.0, 2.0, 1e6)] {
            assert!(matches!(
                exact_root(&w, h, v, t0, 0.0, 50.0),
                WallRoot::Hit(_)
            ));
        }
    }

    #[test]
    fn bracket_root_ends_on_the_particle_side_for_any_tolerance_and_clock() {
        // Fuzz of the thesis's solver at the edges of its inputs: gap tolerances at and below
        // the gap's round-off (0, 1e-300), clocks far from the origin (t0 up to 1e7), coarse
        // and fine marching steps. Every search must end, and a hit must never put the particle
        // inside the wall (`refine` returns the bracket's particle side when the tolerance
        // cannot be met; returning `b` fails here), nor come before the earliest root.
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(41);
        let mut hits = 0;
        for i in 0..3000 {
            let w = random_motion(&mut rng);
            let t0 = match i % 3 {
                0 => rng.gen_range(0.0..w.period()),
                1 => rng.gen_range(1e3..1e5),
                _ => rng.gen_range(1e6..1e7),
            };
            let h = rng
                .gen_range(0.0..(w.amplitude + 3.0))
                .max(w.position(t0) + 1e-9);
            let v = rng.gen_range(-3.0..3.0);
            let tol = [0.0, 1e-300, 1e-13, 1e-6][i % 4];
            let t_min = w.period() * [1e-4, 1e-2, 0.2][i % 3];
            match bracket_root(&w, h, v, t0, t_min, tol, 20.0) {
                WallRoot::Hit(t) => {
                    hits += 1;
                    assert!(t >= 0.0 && t.is_finite(), "{t}");
                    let (gap, _) = w.gap(h, v, t0, t);
                    assert!(
                        gap >= 0.0,
                        "inside the wall: gap {gap} at {t}, {w:?} h={h} v={v} t0={t0} tol={tol}"
                    );
                    if let WallRoot::Hit(e) = exact_root(&w, h, v, t0, 1e-9, 20.0) {
                        assert!(t >= e - 1e-6, "bracket {t} before the earliest root {e}");
                    }
                }
                WallRoot::None => {}
            }
        }
        assert!(
            hits > 1500,
            "{hits} hits: the shots should mostly reach the wall"
        );
    }

    #[test]
    fn grazing_shot_is_caught() {
        // A trajectory whose apex touches the wall's crest: h(t) = A + small at the crest time.
        let w = motion(0.1, 2.0, 1.0);
        let t_crest = PI / 2.0 / w.omega;
        // Apex exactly at the crest height: h + v t - t^2/2 reaches A at t = v with zero slope.
        let v = 0.5;
        let h = w.amplitude - 0.5 * v * v + 1e-10; // 1e-10 above the crest at the apex
        let t0 = t_crest - v;
        // The wall's crest is curved (A omega^2 = 0.4 < g = 1), so the particle, falling faster
        // than the crest descends, hits just after the apex.
        match exact_root(&w, h, v, t0, 1e-13, 50.0) {
            WallRoot::Hit(t) => {
                assert!(w.gap(h, v, t0, t).0 <= 1e-13);
                assert!(t > v - 0.1 && t < v + 1.0, "{t}");
            }
            r => panic!("{r:?}"),
        }
    }
}
