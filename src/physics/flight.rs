//! Free flight between events: straight lines without gravity, parabolas with it, and the
//! robust root formulas for when a flight reaches a plane (cell faces, floor, lid).

/// Time until a straight flight `x(t) = x0 + v t` reaches the plane `x = plane`, if it moves
/// towards it (`+inf` otherwise). Never negative: a particle slightly past the plane (round-off)
/// reaches it "now".
#[inline]
pub fn linear_time_to_plane(x0: f64, v: f64, plane: f64, upward: bool) -> f64 {
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

/// Time until the parabola `z(t) = z0 + v t - g t^2 / 2` (`g > 0`) reaches `plane` from below
/// while rising (the first root), `+inf` if it turns before. Cancellation-free form
/// `t = 2 dz / (v + sqrt(v^2 - 2 g dz))`, `dz = plane - z0`.
#[inline]
pub fn parabola_time_up(z0: f64, v: f64, g: f64, plane: f64) -> f64 {
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
pub fn parabola_time_down(z0: f64, v: f64, g: f64, plane: f64) -> f64 {
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
pub fn accelerated_time_to_plane(x0: f64, v: f64, a: f64, plane: f64, upward: bool) -> f64 {
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
    fn linear_never_negative() {
        assert_eq!(linear_time_to_plane(1.0 + 1e-15, 1.0, 1.0, true), 0.0);
        assert_eq!(linear_time_to_plane(0.5, -1.0, 1.0, true), f64::INFINITY);
        assert!((linear_time_to_plane(0.5, -2.0, 0.0, false) - 0.25).abs() < 1e-15);
    }
}
