//! Free flight between events: straight lines without gravity, parabolas with it, and the
//! robust root formulas for when a flight reaches a plane (cell faces, floor, lid).

/// Time until a straight flight `x(t) = x0 + v t` reaches the plane `x = plane`, if it moves
/// towards it (`+inf` otherwise). Never negative: a particle slightly past the plane (round-off)
/// reaches it "now".
#[inline]
pub(crate) fn linear_time_to_plane(x0: f64, v: f64, plane: f64, upward: bool) -> f64 {
    if upward {
        if v > 0.0 {
            ((plane - x0) / v).max(0.0)
        } else {
            f64::INFINITY
        }
    } else if v < 0.0 {
        ((plane - x0) / v).max(0.0)
    } else {
        f64::INFINITY
    }
}

/// The earlier of the two straight-flight times to the faces of a cell `[lo, lo + w]` and
/// whether it is the upper face: the same number as the smaller of the two
/// [`linear_time_to_plane`] calls (`+inf` for `v = 0` or NaN), a face marked `closed` (the
/// outer face of an edge cell of a wall axis) counting as a plane at infinity. Written without
/// a branch on the sign of `v`, a coin toss for cell faces (docs/performance.md, "Ideas kept
/// and rejected"): the face is `lo + w * [v > 0]` (`lo + 0.0` is `lo` for `lo >= 0`), and
/// `+inf` is added when the face is never reached (else `0.0`, which at most turns `-0.0` into
/// `+0.0`).
#[inline(always)]
pub(crate) fn linear_time_to_faces(
    x0: f64,
    v: f64,
    lo: f64,
    w: f64,
    lo_closed: bool,
    hi_closed: bool,
) -> (f64, bool) {
    let up = v > 0.0;
    let down = v < 0.0;
    let plane = lo + w * f64::from(i32::from(up));
    let never_reached = !(up | down) | (up & hi_closed) | (down & lo_closed);
    let mask = 0u64.wrapping_sub(u64::from(never_reached));
    let never = f64::from_bits(f64::INFINITY.to_bits() & mask);
    (((plane - x0) / v).max(0.0) + never, up)
}

/// Time until the parabola `z(t) = z0 + v t - g t^2 / 2` (`g > 0`) reaches `plane` from below
/// while rising (the first root), `+inf` if it turns before. Cancellation-free form
/// `t = 2 dz / (v + sqrt(v^2 - 2 g dz))`, `dz = plane - z0`.
#[inline]
pub(crate) fn parabola_time_up(z0: f64, v: f64, g: f64, plane: f64) -> f64 {
    if v <= 0.0 {
        return f64::INFINITY;
    }
    let dz = plane - z0;
    if dz <= 0.0 {
        return 0.0;
    }
    let disc = v * v - 2.0 * g * dz;
    if disc < 0.0 {
        return f64::INFINITY;
    }
    2.0 * dz / (v + disc.sqrt())
}

/// Time until the parabola reaches `plane` from above while falling (the later root,
/// `t = (v + sqrt(v^2 + 2 g dz)) / g`, `dz = z0 - plane >= 0`). Always finite for `g > 0`.
/// If round-off put the particle slightly below the plane, the discriminant is clamped at zero,
/// and a particle already below it and falling reaches it "now".
#[inline]
pub(crate) fn parabola_time_down(z0: f64, v: f64, g: f64, plane: f64) -> f64 {
    let dz = z0 - plane;
    if dz <= 0.0 && v <= 0.0 {
        return 0.0;
    }
    let disc = (v * v + 2.0 * g * dz).max(0.0);
    if v <= 0.0 {
        // Falling already: the root is 2 dz / (-v + sqrt(disc)) without cancellation.
        let den = -v + disc.sqrt();
        if den > 0.0 { 2.0 * dz / den } else { 0.0 }
    } else {
        (v + disc.sqrt()) / g
    }
}

/// Time until `x(t) = x0 + v t + a t^2 / 2` (any sign of `a`) reaches `plane` moving up
/// (`upward`, `dx/dt >= 0` there) or down, `+inf` if never. Reduced to the gravity formulas
/// above: `a < 0` is a parabola under `g = -a`; `a > 0` is the mirror image `z = -x` under
/// `g = a`, where reaching a plane upwards is falling onto its mirror. `a = 0` is the straight
/// line. Never negative.
#[inline]
pub(crate) fn accelerated_time_to_plane(x0: f64, v: f64, a: f64, plane: f64, upward: bool) -> f64 {
    if a < 0.0 {
        if upward {
            parabola_time_up(x0, v, -a, plane)
        } else {
            parabola_time_down(x0, v, -a, plane)
        }
    } else if a > 0.0 {
        if upward {
            parabola_time_down(-x0, -v, a, -plane)
        } else {
            parabola_time_up(-x0, -v, a, -plane)
        }
    } else {
        linear_time_to_plane(x0, v, plane, upward)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn accelerated_roots_satisfy_the_trajectory() {
        for &(x0, v, a) in &[
            (0.5, -1.0, 2.0),
            (0.5, 1.0, 2.0),
            (0.5, 1.0, -2.0),
            (0.5, -1.0, -2.0),
            (0.5, 0.0, 0.3),
            (0.5, 0.0, -0.3),
        ] {
            let x = |t: f64| x0 + v * t + 0.5 * a * t * t;
            for (plane, up) in [(1.0, true), (0.0, false)] {
                let t = accelerated_time_to_plane(x0, v, a, plane, up);
                if t.is_finite() {
                    assert!(
                        (x(t) - plane).abs() < 1e-12,
                        "x0={x0} v={v} a={a} plane={plane}"
                    );
                    let vt = v + a * t;
                    assert!(if up { vt >= -1e-12 } else { vt <= 1e-12 });
                    // No earlier crossing: sample the flight before t.
                    for k in 1..100 {
                        let s = t * k as f64 / 100.0;
                        assert!(if up {
                            x(s) < plane + 1e-12
                        } else {
                            x(s) > plane - 1e-12
                        });
                    }
                } else {
                    // Never reached: e.g. decelerating before the plane.
                    for k in 0..1000 {
                        let s = k as f64 * 0.01;
                        assert!(if up { x(s) < plane } else { x(s) > plane });
                    }
                }
            }
        }
    }

    #[test]
    fn parabola_roots_satisfy_the_trajectory() {
        let g = 1.0;
        for &(z0, v, plane) in &[
            (0.5, 2.0, 1.5),
            (0.5, 0.1, 0.4),
            (3.0, -1.0, 0.5),
            (1.0, 3.0, 1.0),
        ] {
            let z = |t: f64| z0 + v * t - 0.5 * g * t * t;
            let tu = parabola_time_up(z0, v, g, plane);
            if tu.is_finite() && plane >= z0 {
                assert!((z(tu) - plane).abs() < 1e-12 && v - g * tu >= 0.0);
            }
            let td = parabola_time_down(z0, v, g, plane);
            assert!((z(td) - plane).abs() < 1e-12, "z0={z0} v={v}");
            assert!(v - g * td <= 1e-12);
        }
        // A particle sitting on the plane and rising does not "hit" it again now.
        let td = parabola_time_down(1.0, 0.5, g, 1.0);
        assert!((td - 1.0).abs() < 1e-14);
        assert_eq!(parabola_time_up(0.0, 1.0, g, 1.0), f64::INFINITY);
    }

    #[test]
    fn faces_match_the_two_plane_times() {
        // Finite speeds and NaN (an infinite speed towards a closed face gives `inf / inf`,
        // so 0, in the two-plane form and `+inf` here; no flight has one).
        let speeds = [
            -2.5,
            -1.0,
            -1e-300,
            -0.0,
            0.0,
            1e-300,
            0.3,
            1.0,
            2.5,
            f64::NAN,
        ];
        let (lo, w) = (1.0, 0.75);
        for &x0 in &[1.5, 1.0, 1.75, 1.75 + 1e-15, 1.0 - 1e-15, 1.25] {
            for &v in &speeds {
                for (lo_closed, hi_closed) in
                    [(false, false), (true, false), (false, true), (true, true)]
                {
                    let hi = if hi_closed { f64::INFINITY } else { lo + w };
                    let lo_plane = if lo_closed { f64::NEG_INFINITY } else { lo };
                    let up = linear_time_to_plane(x0, v, hi, true);
                    let down = linear_time_to_plane(x0, v, lo_plane, false);
                    let (t, is_up) = linear_time_to_faces(x0, v, lo, w, lo_closed, hi_closed);
                    let want = if down < up { down } else { up };
                    // Equal as numbers (a zero's sign is invisible to every later compare and
                    // to `now + t`).
                    assert!(
                        t == want,
                        "x0={x0} v={v} closed={lo_closed},{hi_closed}: {t} against {want}"
                    );
                    if want.is_finite() {
                        assert_eq!(is_up, up.is_finite(), "x0={x0} v={v}");
                    }
                }
            }
        }
        // The lower face of the first cell: `0 + 0.0` is `+0.0`.
        assert_eq!(
            linear_time_to_faces(0.5, -1.0, 0.0, 1.0, false, false),
            (0.5, false)
        );
    }

    #[test]
    fn linear_never_negative() {
        assert_eq!(linear_time_to_plane(1.0 + 1e-15, 1.0, 1.0, true), 0.0);
        assert_eq!(linear_time_to_plane(0.5, -1.0, 1.0, true), f64::INFINITY);
        assert!((linear_time_to_plane(0.5, -2.0, 0.0, false) - 0.25).abs() < 1e-15);
    }
}
