//! Integrators of the time-driven engine, as loops over flat coordinate arrays (every particle
//! and axis in one array, so the loops vectorise).
//!
//! **Gear predictor-corrector, 5th order** (six values per coordinate; Gear 1971, coefficients as
//! tabulated by Allen & Tildesley, *Computer Simulation of Liquids*, 1987, Table E.1, and used by
//! Pöschel & Schwager, *Computational Granular Dynamics*, 2005, Sec. 2.3). The state holds the
//! scaled derivatives `r_k = dt^k / k! d^k x / dt^k`, `k = 0..5`:
//!
//! 1. predict with the Pascal triangle (Taylor series to 5th order): `r_k += sum_{l > k} C(l, k) r_l`;
//! 2. evaluate the acceleration `a` at the predicted positions and velocities;
//! 3. correct with `Delta = a dt^2 / 2 - r_2`: `r_k += c_k Delta`,
//!    `c = (3/16, 251/360, 1, 11/18, 1/6, 1/60)`.
//!
//! For velocity-dependent forces (damped contacts) Gear's `c_0 = 3/20` replaces `3/16` (Allen &
//! Tildesley Table E.1, footnote); the engine picks it when any damping is set.
//!
//! **Velocity Verlet** (Swope et al. 1982): `v += a dt/2; x += v dt; a = a(x, v); v += a dt/2`.
//! The damping force is evaluated with the half-step velocity, which keeps one force evaluation
//! per step and makes the method first-order in the damping term.

/// Gear corrector coefficients for second-order equations, six values, velocity-independent
/// forces (Allen & Tildesley Table E.1).
pub(crate) const GEAR5: [f64; 6] = [
    3.0 / 16.0,
    251.0 / 360.0,
    1.0,
    11.0 / 18.0,
    1.0 / 6.0,
    1.0 / 60.0,
];

/// `c_0` of Gear's 5th-order corrector when the force depends on the velocity.
pub(crate) const GEAR5_C0_VELOCITY_DEPENDENT: f64 = 3.0 / 20.0;

/// Predictor: Taylor step of the scaled derivatives `r[0..6]`, element-wise.
pub(crate) fn gear_predict(r: &mut [Vec<f64>; 6]) {
    let [r0, r1, r2, r3, r4, r5] = r;
    for e in 0..r0.len() {
        let (a1, a2, a3, a4, a5) = (r1[e], r2[e], r3[e], r4[e], r5[e]);
        r0[e] += a1 + a2 + a3 + a4 + a5;
        r1[e] = a1 + 2.0 * a2 + 3.0 * a3 + 4.0 * a4 + 5.0 * a5;
        r2[e] = a2 + 3.0 * a3 + 6.0 * a4 + 10.0 * a5;
        r3[e] = a3 + 4.0 * a4 + 10.0 * a5;
        r4[e] = a4 + 5.0 * a5;
    }
}

/// Safeguard: below this magnitude the corrector sets the scaled derivatives `r_2 .. r_5` to
/// zero. In free flight the higher derivatives left by a contact decay geometrically and would
/// become subnormal numbers after some thousand steps, which makes every operation on them about
/// a hundred times slower; this is far below any physical scale.
pub(crate) const GEAR_FLUSH: f64 = 1e-200;

/// Corrector: `Delta = a dt^2/2 - r_2`, `r_k += c_k Delta`, flushing at [`GEAR_FLUSH`] (the
/// reference the fused loop is tested against).
#[cfg(test)]
pub(crate) fn gear_correct(r: &mut [Vec<f64>; 6], acc: &[f64], half_dt2: f64, c: &[f64; 6]) {
    let [r0, r1, r2, r3, r4, r5] = r;
    let flush = |x: f64| if x.abs() < GEAR_FLUSH { 0.0 } else { x };
    for e in 0..r0.len() {
        let delta = acc[e] * half_dt2 - r2[e];
        r0[e] += c[0] * delta;
        r1[e] += c[1] * delta;
        r2[e] = flush(r2[e] + c[2] * delta);
        r3[e] = flush(r3[e] + c[3] * delta);
        r4[e] = flush(r4[e] + c[4] * delta);
        r5[e] = flush(r5[e] + c[5] * delta);
    }
}

/// Runs `$body!([arrays], e)` for `e = 0..$n` in order and evaluates to the largest value it
/// returned (0 when none). The loop runs over blocks of [`BLOCK`] elements, each array
/// re-sliced to the block (no bounds checks inside), and keeps one running maximum per block
/// position (a compare-and-select that compiles to packed `maxpd`); the positions are reduced
/// once at the end. So the body vectorises: a single floating-point running maximum is a
/// loop-carried dependence the compiler does not vectorise without fast-math. NaN values are
/// ignored (caught by the engine's sanity check).
macro_rules! lane_max {
    ($n:expr, $body:ident, mut [$($m:ident),*], [$($c:ident),*]) => {{
        let n: usize = $n;
        let mut lane = [0.0f64; BLOCK];
        let mut b = 0;
        while b < n {
            let m = (n - b).min(BLOCK);
            $(let $m = &mut $m[b..b + m];)*
            $(let $c = &$c[b..b + m];)*
            let lane = &mut lane[..m];
            for j in 0..m {
                let s = $body!([$($m,)* $($c),*], j);
                lane[j] = if s > lane[j] { s } else { lane[j] };
            }
            b += m;
        }
        let mut moved = 0.0f64;
        for m in lane {
            moved = if m > moved { m } else { moved };
        }
        moved
    }};
}

/// Block length of [`lane_max`].
const BLOCK: usize = 64;

/// Inverse of the predictor (the inverse Pascal triangle): the corrected scaled derivatives of
/// step `n` from the prediction `p` for step `n + 1`. Exact up to round-off (the position to
/// about one ulp of `|x|`); the engine uses it to read the current state instead of storing it
/// every step.
pub(crate) fn gear_unpredict(p: [f64; 6]) -> [f64; 6] {
    let a5 = p[5];
    let a4 = p[4] - 5.0 * a5;
    let a3 = p[3] - 4.0 * a4 - 10.0 * a5;
    let a2 = p[2] - 3.0 * a3 - 6.0 * a4 - 10.0 * a5;
    let a1 = p[1] - 2.0 * a2 - 3.0 * a3 - 4.0 * a4 - 5.0 * a5;
    let a0 = p[0] - (a1 + a2 + a3 + a4 + a5);
    [a0, a1, a2, a3, a4, a5]
}

/// Corrector of one step fused with the predictor of the next on one slice of coordinates (one
/// axis of the engine's axis-major arrays): `r` goes from predicted (step `n`) to predicted
/// (step `n + 1`) in one pass, the arithmetic of [`gear_correct`] then [`gear_predict`]. The
/// corrected state is not stored (the engine recovers it on demand with [`gear_unpredict`]),
/// and two more jobs are done in the same pass:
///
/// - with `period = Some(L)`, the new predicted position `r[0]` is wrapped into `[0, L)` (the
///   operation of a separate wrap pass, so the numbers are identical);
/// - returns the largest move of a predicted position in this step, before the wrap (the true
///   displacement), for the list's displacement bound (`neighbours::needs_rebuild`); NaN
///   moves are ignored (`lane_max`: the engine's sanity check catches them).
///
/// With `flush = false` the [`GEAR_FLUSH`] safeguard is left out of this step (see
/// [`GEAR_FLUSH_EVERY`]). Each `acc[e]` is set to `force_start` once read: the next force
/// evaluation starts from it without a pass of its own.
pub(crate) fn gear_correct_predict_axis(
    r: [&mut [f64]; 6],
    acc: &mut [f64],
    force_start: f64,
    half_dt2: f64,
    c: &[f64; 6],
    period: Option<f64>,
    flush: bool,
) -> f64 {
    let h = (half_dt2, force_start);
    match (period, flush) {
        (Some(l), true) => fused_axis::<true, true>(r, acc, h, c, l),
        (None, true) => fused_axis::<false, true>(r, acc, h, c, 0.0),
        (Some(l), false) => fused_axis::<true, false>(r, acc, h, c, l),
        (None, false) => fused_axis::<false, false>(r, acc, h, c, 0.0),
    }
}

/// [`gear_correct_predict_axis`] on every axis of axis-major arrays of `m` particles per axis
/// (`force_start[k]` and `period[k]` per axis); returns the largest move per axis.
pub(crate) fn gear_correct_predict_axes<const D: usize>(
    r: &mut [Vec<f64>; 6],
    acc: &mut [f64],
    force_start: [f64; D],
    half_dt2: f64,
    c: &[f64; 6],
    period: [Option<f64>; D],
    flush: bool,
) -> [f64; D] {
    let m = acc.len() / D;
    std::array::from_fn(|k| {
        let a = k * m..(k + 1) * m;
        gear_correct_predict_axis(
            r.each_mut().map(|r| &mut r[a.clone()]),
            &mut acc[a],
            force_start[k],
            half_dt2,
            c,
            period[k],
            flush,
        )
    })
}

/// The engine applies the subnormal flush of the Gear derivatives ([`GEAR_FLUSH`]) in every
/// `GEAR_FLUSH_EVERY`-th step only, which takes four compare-and-mask operations per value out
/// of the other steps. Safe: after a flush every derivative is 0 or at least `1e-200` in
/// magnitude; one step forms each value from sums of products of such values with
/// coefficients of at least `1/60`, so a non-zero result is at least `2^-52 / 60` (about
/// `3.7e-18`) of the smallest non-zero input; in 4 steps a value can shrink to no less than
/// `1e-200 * (3.7e-18)^4`, about `2e-271`, far above the subnormal range (`< 2.2e-308`; 6 steps
/// would still be safe). Values between `1e-271` and `1e-200` change the position and the
/// velocity by nothing (they are below one ulp of either).
pub(crate) const GEAR_FLUSH_EVERY: u64 = 4;

fn fused_axis<const WRAP: bool, const FLUSH: bool>(
    r: [&mut [f64]; 6],
    acc: &mut [f64],
    (half_dt2, force_start): (f64, f64),
    c: &[f64; 6],
    l: f64,
) -> f64 {
    let [r0, r1, r2, r3, r4, r5] = r;
    let n = r0.len();
    // Equal lengths up front, so the loop below carries no bounds checks and vectorises.
    let (r1, r2, r3, r4, r5) = (
        &mut r1[..n],
        &mut r2[..n],
        &mut r3[..n],
        &mut r4[..n],
        &mut r5[..n],
    );
    let acc = &mut acc[..n];
    let flush = |x: f64| {
        if FLUSH && x.abs() < GEAR_FLUSH {
            0.0
        } else {
            x
        }
    };
    // `x < 0: x + L; x >= L: x - L`, written as the addition of selected constants (adding or
    // subtracting 0 leaves `x` unchanged) so that it compiles to packed compares and masks,
    // not branches.
    let wrap = |x: f64| {
        if WRAP {
            let up = if x < 0.0 { l } else { 0.0 };
            let down = if x >= l { l } else { 0.0 };
            x + up - down
        } else {
            x
        }
    };
    // One element `e` of the arrays `r0 .. r5, acc` (slices, or blocks of them): the fused update; evaluates to the move `|r0_new - r0_old|` before the
    // wrap.
    macro_rules! update {
        ([$r0:ident, $r1:ident, $r2:ident, $r3:ident, $r4:ident, $r5:ident, $acc:ident $(,)?], $e:expr) => {{
            let e = $e;
            let old = $r0[e];
            let delta = $acc[e] * half_dt2 - $r2[e];
            $acc[e] = force_start;
            let a0 = old + c[0] * delta;
            let a1 = $r1[e] + c[1] * delta;
            let a2 = flush($r2[e] + c[2] * delta);
            let a3 = flush($r3[e] + c[3] * delta);
            let a4 = flush($r4[e] + c[4] * delta);
            let a5 = flush($r5[e] + c[5] * delta);
            let p0 = a0 + (a1 + a2 + a3 + a4 + a5);
            $r0[e] = wrap(p0);
            $r1[e] = a1 + 2.0 * a2 + 3.0 * a3 + 4.0 * a4 + 5.0 * a5;
            $r2[e] = a2 + 3.0 * a3 + 6.0 * a4 + 10.0 * a5;
            $r3[e] = a3 + 4.0 * a4 + 10.0 * a5;
            $r4[e] = a4 + 5.0 * a5;
            $r5[e] = a5;
            (p0 - old).abs()
        }};
    }
    lane_max!(n, update, mut [r0, r1, r2, r3, r4, r5, acc], [])
}

/// Velocity Verlet, first half: `v += a dt/2; x += v dt`. Returns `max_e |v dt|`, the largest
/// move of this step (see [`gear_correct_predict_axis`]; the engine calls this per axis). Each
/// `acc[e]` is set to `force_start` once read (as in [`gear_correct_predict_axis`]).
pub(crate) fn verlet_drift(
    x: &mut [f64],
    v: &mut [f64],
    acc: &mut [f64],
    force_start: f64,
    dt: f64,
) -> f64 {
    let n = x.len();
    let (v, acc) = (&mut v[..n], &mut acc[..n]);
    macro_rules! drift {
        ([$x:ident, $v:ident, $acc:ident $(,)?], $e:expr) => {{
            let e = $e;
            $v[e] += 0.5 * dt * $acc[e];
            $acc[e] = force_start;
            let step = dt * $v[e];
            $x[e] += step;
            step.abs()
        }};
    }
    lane_max!(n, drift, mut [x, v, acc], [])
}

/// Velocity Verlet, second half: `v += a dt/2` with the new acceleration.
pub(crate) fn verlet_kick(v: &mut [f64], acc: &[f64], dt: f64) {
    for e in 0..v.len() {
        v[e] += 0.5 * dt * acc[e];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The engine's safeguard: the per-axis loop flushing every [`GEAR_FLUSH_EVERY`] steps
    /// keeps every derivative of a free flight away from subnormal numbers and drives them to
    /// exact zeros; without any flush they become subnormal (the test would fail without the
    /// safeguard).
    #[test]
    fn flush_every_few_steps_leaves_no_subnormal_derivatives() {
        let dt = 1e-4;
        let run = |every: Option<u64>| {
            let mut r: [Vec<f64>; 6] = [
                vec![0.0, 5.0],
                vec![dt, 0.0],
                vec![0.0, 0.0],
                vec![1e-12, -2e-12],
                vec![-3e-13, 1e-13],
                vec![1e-14, 3e-15],
            ];
            let (mut subnormal, mut zero) = (false, false);
            for step in 0..200_000u64 {
                let [a, b, c, d, e, f] = &mut r;
                let flush = every.is_some_and(|k| step.is_multiple_of(k));
                gear_correct_predict_axis(
                    [a, b, c, d, e, f],
                    &mut [0.0, 0.0],
                    0.0,
                    0.5 * dt * dt,
                    &GEAR5,
                    Some(10.0),
                    flush,
                );
                subnormal |= r[2..].iter().flatten().any(|x| x.is_subnormal());
                zero |= r[5].iter().all(|&x| x == 0.0);
            }
            (subnormal, zero)
        };
        assert_eq!(run(Some(GEAR_FLUSH_EVERY)), (false, true));
        assert!(
            run(None).0,
            "without the flush the derivatives go subnormal"
        );
    }

    /// The engine's per-axis loop is `gear_correct` then `gear_predict` bit for bit (the
    /// predicted state, with the wrap on a periodic axis), returns the largest move of the
    /// predicted position, and `gear_unpredict` recovers the corrected position and velocity,
    /// to round-off.
    #[test]
    fn axis_loop_matches_the_reference_and_unpredict_recovers_the_corrected_state() {
        let m = 131; // not a multiple of the block length: exercises the tail
        let l = 10.0;
        let init: [Vec<f64>; 6] = std::array::from_fn(|k| {
            (0..m)
                .map(|e| {
                    let t = e as f64;
                    match k {
                        0 => (t * 0.37).rem_euclid(l),
                        1 => 1e-4 * (t * 1.3).sin() * (1.0 + (e % 7) as f64),
                        _ => 1e-9 * (t * (k as f64)).cos() / (k * k) as f64,
                    }
                })
                .collect()
        });
        // Particles at the faces, moving out: the wrap is exercised both ways.
        let mut init = init;
        init[0][3] = 1e-6;
        init[1][3] = -1e-3;
        init[0][4] = l - 1e-6;
        init[1][4] = 1e-3;
        let acc: Vec<f64> = (0..m).map(|e| (e as f64 * 0.11).cos() - 1.0).collect();
        let h = 5e-9;
        let mut want = init.clone();
        gear_correct(&mut want, &acc, h, &GEAR5_DAMPED_TEST);
        let now = [want[0].clone(), want[1].clone()];
        gear_predict(&mut want);
        let mut got = init.clone();
        let [g0, g1, g2, g3, g4, g5] = &mut got;
        let mut acc_left = acc.clone();
        let moved = gear_correct_predict_axis(
            [g0, g1, g2, g3, g4, g5],
            &mut acc_left,
            -0.25,
            h,
            &GEAR5_DAMPED_TEST,
            Some(l),
            true,
        );
        let mut wrapped = 0;
        let mut most = 0.0f64;
        for e in 0..m {
            most = most.max((want[0][e] - init[0][e]).abs());
            let w = want[0][e];
            let w = if w < 0.0 {
                w + l
            } else if w >= l {
                w - l
            } else {
                w
            };
            wrapped += usize::from(w != want[0][e]);
            assert_eq!(got[0][e], w, "position {e}");
            for k in 1..6 {
                assert_eq!(got[k][e], want[k][e], "r_{k} at {e}");
            }
            let a = gear_unpredict(std::array::from_fn(|k| want[k][e]));
            assert!(
                (a[0] - now[0][e]).abs() <= 4.0 * f64::EPSILON * l,
                "x at {e}"
            );
            assert!(
                (a[1] - now[1][e]).abs() <= 1e-12 * now[1][e].abs().max(1e-12),
                "v at {e}: {} vs {}",
                a[1],
                now[1][e]
            );
        }
        assert!(wrapped >= 2, "the face particles wrap");
        assert!(
            acc_left.iter().all(|&a| a == -0.25),
            "acc is left at the force start"
        );
        assert_eq!(moved, most);
    }

    const GEAR5_DAMPED_TEST: [f64; 6] = {
        let mut c = GEAR5;
        c[0] = GEAR5_C0_VELOCITY_DEPENDENT;
        c
    };

    /// Both integrators on the harmonic oscillator `x'' = -x`: the error after one period
    /// falls with the step at the integrator's order (Verlet 2; the 6-value Gear method, whose
    /// local error is `O(dt^6)`, at least 4 here).
    #[test]
    fn orders_on_the_harmonic_oscillator() {
        let err = |gear: bool, steps: usize| {
            let dt = 2.0 * std::f64::consts::PI / steps as f64;
            let (mut x, mut v, mut a) = (vec![1.0], vec![0.0], vec![-1.0]);
            let mut r: [Vec<f64>; 6] = [
                vec![1.0],
                vec![0.0],
                vec![-0.5 * dt * dt],
                vec![0.0],
                vec![dt.powi(4) / 24.0],
                vec![0.0],
            ];
            for _ in 0..steps {
                if gear {
                    gear_predict(&mut r);
                    let acc = [-r[0][0]];
                    gear_correct(&mut r, &acc, 0.5 * dt * dt, &GEAR5);
                } else {
                    verlet_drift(&mut x, &mut v, &mut a, 0.0, dt);
                    a[0] = -x[0];
                    verlet_kick(&mut v, &a, dt);
                }
            }
            if gear {
                (r[0][0] - 1.0).abs() + (r[1][0] / dt).abs()
            } else {
                (x[0] - 1.0).abs() + v[0].abs()
            }
        };
        for gear in [false, true] {
            let (e1, e2) = (err(gear, 200), err(gear, 400));
            let order = (e1 / e2).log2();
            let want = if gear { 3.8 } else { 1.9 };
            assert!(
                order > want,
                "gear {gear}: errors {e1:e} {e2:e}, order {order}"
            );
        }
    }
}
