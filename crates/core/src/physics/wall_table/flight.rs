//! The gap along one flight from a base point (Eq. B.7) and everything the table is built from:
//! the base point of a table parameter `(p1, u)` on each edge, the gap's partial derivatives in
//! the parameters, and every zero of the gap in a window, found by conservative advancement.

use super::{Edge, MAX_ROOTS};
use crate::physics::shaken_wall::{WallMotion, bisect};

/// Inverse of [`map_velocity`] and `dv/du`, with the sign each edge's flights have.
fn unmap_velocity(edge: Edge, u: f64, v_min: f64) -> (f64, f64) {
    let m = u.abs().exp_m1() * v_min;
    let dm = u.abs().exp() * v_min;
    match edge {
        Edge::Top => (-m, -dm),
        Edge::Bottom | Edge::Wall => (m, dm),
        Edge::Start => (u.signum() * m, dm),
    }
}

/// Base point `(h0, v0, phi0)` of the flight with parameters `(p1, u)` on `edge`.
pub(super) fn base_point(
    w: &WallMotion,
    edge: Edge,
    p1: f64,
    u: f64,
    v_min: f64,
) -> (f64, f64, f64) {
    let (v, _) = unmap_velocity(edge, u, v_min);
    let a = w.amplitude;
    match edge {
        Edge::Top => (a, v, p1),
        Edge::Bottom => (-a, v, p1),
        Edge::Start => (p1, v, 0.0),
        Edge::Wall => (a * p1.sin(), a * w.omega * p1.cos() + v, p1),
    }
}

/// `(ds/dP1, ds/du)` and `(d s_tau/dP1, d s_tau/du)` at `tau` for the flight `(p1, u)` on `edge`.
pub(super) fn partials(
    w: &WallMotion,
    edge: Edge,
    p1: f64,
    u: f64,
    v_min: f64,
    tau: f64,
) -> [[f64; 2]; 2] {
    let (_, dv) = unmap_velocity(edge, u, v_min);
    let (a, om) = (w.amplitude, w.omega);
    let phi0 = if edge == Edge::Start { 0.0 } else { p1 };
    let arg = phi0 + om * tau;
    let (s_p1, st_p1) = match edge {
        Edge::Top | Edge::Bottom => (-a * arg.cos(), a * om * arg.sin()),
        Edge::Start => (1.0, 0.0),
        Edge::Wall => (
            a * p1.cos() - a * om * p1.sin() * tau - a * arg.cos(),
            -a * om * p1.sin() + a * om * arg.sin(),
        ),
    };
    [[s_p1, tau * dv], [st_p1, dv]]
}

/// Gap and its first two derivatives along a flight from a base point.
#[inline]
pub(super) fn gap3(w: &WallMotion, (h0, v0, phi0): (f64, f64, f64), tau: f64) -> (f64, f64, f64) {
    let arg = phi0 + w.omega * tau;
    let (sn, cs) = arg.sin_cos();
    let a = w.amplitude;
    let s = h0 + v0 * tau - 0.5 * w.g * tau * tau - a * sn;
    let ds = v0 - w.g * tau - a * w.omega * cs;
    let dds = -w.g + a * w.omega * w.omega * sn;
    (s, ds, dds)
}

/// Every zero of the gap in `[0, window]` in order, with whether the flight starts behind the
/// wall. Conservative advancement on `sigma = side * s` (`|s''| <= g + A omega^2`) cannot skip
/// a zero; a touch without crossing is not a root.
pub(super) fn all_roots(
    w: &WallMotion,
    base: (f64, f64, f64),
    window: f64,
    skip_start: bool,
) -> (bool, Vec<f64>) {
    let k = w.curvature_bound().max(1e-300);
    let scale = w.amplitude.max(base.0.abs()).max(1e-12);
    let tol = 1e-14 * scale;
    let (s0, ds0, _) = gap3(w, base, 0.0);
    let mut roots = Vec::new();
    // Side at the start: a zero gap counts by its rate (leaving the wall: outside).
    let starts_inside = if skip_start || s0.abs() <= tol {
        ds0 < 0.0 && !skip_start
    } else {
        s0 < 0.0
    };
    let mut side = if starts_inside { -1.0 } else { 1.0 };
    let mut tau = 0.0;
    if s0.abs() <= tol {
        // Start on the wall: move off it along the rate.
        tau = (2.0 * tol / ds0.abs().max(1e-300)).min(1e-9 * window);
    }
    let min_step = 1e-15 * window.max(1.0);
    let mut guard = 0;
    while tau <= window && guard < 100_000 {
        guard += 1;
        let (s, ds, _) = gap3(w, base, tau);
        let (sg, dsg) = (side * s, side * ds);
        if sg > tol {
            let step = 2.0 * sg / ((dsg * dsg + 2.0 * k * sg).sqrt() - dsg);
            tau += step.max(min_step);
            continue;
        }
        // Within tol of a zero (or past it by round-off). Look for a sign change ahead.
        if dsg >= 0.0 && sg > -tol {
            // Touching, not crossing: move on.
            tau += (2.0 * tol / k).sqrt().max(min_step);
            continue;
        }
        let a = tau;
        let mut b = tau + (2.0 * sg.abs().max(tol) / dsg.abs().max(1e-300)).max(min_step);
        let mut crossed = false;
        for _ in 0..60 {
            if side * gap3(w, base, b).0 < 0.0 {
                crossed = true;
                break;
            }
            b = a + 2.0 * (b - a);
            if b - a > (8.0 * tol / k).sqrt() + 1e-6 * window {
                break;
            }
        }
        if !crossed {
            tau = b;
            continue;
        }
        // Bisect [a, b] to round-off: sigma(a) >= -tol... sigma(b) < 0.
        let hi = bisect(a, b, |t| side * gap3(w, base, t).0 > 0.0);
        if hi <= window && roots.len() < MAX_ROOTS {
            roots.push(hi);
        }
        side = -side;
        tau = hi + min_step;
    }
    (starts_inside, roots)
}
