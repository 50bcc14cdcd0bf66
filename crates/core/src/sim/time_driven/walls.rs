//! The Hertz walls of the time-driven engine (docs/model.md 4.1; Eq. 2.7 with `R_eff = R_i`): the
//! force of the lower and upper wall of one non-periodic axis on a run of particles, with the
//! contact onsets, the damping's dissipation and the drive's work, for every execution strategy.
//!
//! Most particles touch no wall at a given step, so the pass first screens blocks of
//! [`SCREEN_BLOCK`] particles with branch-free (packed) compares of the centres against a band
//! from which no particle can reach a wall, and runs the per-particle code only on a block with
//! a centre outside the band (or NaN) or a contact bit to clear. The screen is conservative, so
//! the forces and books are the bits of a per-particle pass.

use super::pair_kernel::Books;
use crate::physics::hertz;

/// Bits of the per-coordinate wall-contact byte: touching the lower, the upper wall of the
/// coordinate's axis.
pub(super) const WALL_LO: u8 = 1;
pub(super) const WALL_HI: u8 = 2;

/// Particles per block of the screening pass.
pub(super) const SCREEN_BLOCK: usize = 8;

/// One axis's pair of walls at the time of a force evaluation.
#[derive(Debug, Clone, Copy)]
pub(super) struct WallAxis {
    /// Position of the lower wall (its drive displacement on the driven axis, else 0).
    pub lo: f64,
    /// Position of the upper wall (the box size plus the same displacement).
    pub hi: f64,
    /// Velocity of both walls.
    pub velocity: f64,
    /// Factor turning the velocity array into velocities.
    pub vs: f64,
    /// The walls' damping `A_d` of Eq. 2.7.
    pub damping: f64,
    /// Weight of the bookkeeping (the step, or 0 for a re-evaluation).
    pub dt: f64,
    /// A centre strictly between `quiet_lo` and `quiet_hi` touches neither wall, whatever its
    /// radius (see [`WallAxis::new`]).
    quiet_lo: f64,
    quiet_hi: f64,
}

impl WallAxis {
    /// The walls at `lo` and `hi` for particles of radius at most `max_radius`. The screening
    /// band is `(lo + max_radius + margin, hi - max_radius - margin)` with a margin of
    /// `1e-9 (|lo| + |hi| + max_radius)`, far more than the round-off of computing the band:
    /// a centre `x` inside it has `x - lo > R_i` and `x + R_i < hi` exactly, so the rounded
    /// overlaps `R_i - (x - lo)` and `x + R_i - hi` of the per-particle test are `<= 0`
    /// (rounding is monotone and `R_i`, `hi` are floating-point numbers).
    pub(super) fn new(
        lo: f64,
        hi: f64,
        velocity: f64,
        vs: f64,
        damping: f64,
        dt: f64,
        max_radius: f64,
    ) -> Self {
        let margin = 1e-9 * (lo.abs() + hi.abs() + max_radius);
        Self {
            lo,
            hi,
            velocity,
            vs,
            damping,
            dt,
            quiet_lo: lo + max_radius + margin,
            quiet_hi: hi - max_radius - margin,
        }
    }
}

/// Adds the wall forces on particles with positions `x` (one axis), velocities `v * w.vs`, radii
/// `radius` and wall prefactors `wall_kr` (`k sqrt(R_i)`) to `f`, updates their contact bits
/// `touching` and books into `b`. All slices have the length of `x`.
pub(super) fn wall_forces(
    w: &WallAxis,
    x: &[f64],
    v: &[f64],
    radius: &[f64],
    wall_kr: &[f64],
    touching: &mut [u8],
    f: &mut [f64],
    b: &mut Books,
) {
    let m = x.len();
    let (v, radius, wall_kr) = (&v[..m], &radius[..m], &wall_kr[..m]);
    let (touching, f) = (&mut touching[..m], &mut f[..m]);
    let mut s = 0;
    while s < m {
        let e = (s + SCREEN_BLOCK).min(m);
        if e - s == SCREEN_BLOCK && block_is_quiet(w, &x[s..e], &touching[s..e]) {
            s = e;
            continue;
        }
        for i in s..e {
            let ri = radius[i];
            let ov_lo = ri - (x[i] - w.lo);
            let ov_hi = x[i] + ri - w.hi;
            if ov_lo <= 0.0 && ov_hi <= 0.0 {
                if touching[i] != 0 {
                    touching[i] = 0;
                }
                continue;
            }
            let (ov, sign, bit) = if ov_lo > 0.0 {
                (ov_lo, 1.0, WALL_LO)
            } else {
                (ov_hi, -1.0, WALL_HI)
            };
            if touching[i] & bit == 0 {
                touching[i] |= bit;
                b.wall_onsets += 1;
            }
            b.max_overlap = b.max_overlap.max(ov);
            // Overlap rate: lower wall -(v - v_w), upper wall +(v - v_w).
            let xi_dot = -sign * (v[i] * w.vs - w.velocity);
            let kr = wall_kr[i];
            // Eq. 2.7 with R_eff = R_i, never a pull.
            let total = hertz::force(kr, ov, xi_dot, w.damping);
            if w.damping > 0.0 {
                b.dissipated += (total - kr * ov * ov.sqrt()) * xi_dot * w.dt;
            }
            let fw = sign * total;
            f[i] += fw;
            b.work += fw * w.velocity * w.dt;
        }
        s = e;
    }
}

/// Whether every centre of a full block is inside the screening band of [`WallAxis::new`]
/// (false for a NaN) and no particle of it has a contact bit set: then the block adds no force,
/// books nothing and changes no bit. Branch-free over a fixed-size block, so it compiles to
/// packed compares.
fn block_is_quiet(w: &WallAxis, x: &[f64], touching: &[u8]) -> bool {
    let x: &[f64; SCREEN_BLOCK] = x.try_into().expect("a full block");
    let touching: &[u8; SCREEN_BLOCK] = touching.try_into().expect("a full block");
    let mut inside = true;
    for &xi in x {
        inside &= (xi > w.quiet_lo) & (xi < w.quiet_hi);
    }
    inside && u64::from_le_bytes(*touching) == 0
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The screened pass gives the same bits as the per-particle pass (screening switched off by
    /// taking every block as loud) on particles near, in and beyond both walls, with contact
    /// bits set and cleared; a block with a NaN position is never screened out.
    #[test]
    fn screening_changes_no_bit() {
        let m = 203; // not a multiple of the block: exercises the tail
        let radius: Vec<f64> = (0..m)
            .map(|i| 0.5 + 0.03 * ((i % 5) as f64 - 2.0))
            .collect();
        let w = WallAxis::new(0.013, 9.013, 0.7, 1e4, 1.5e-4, 1e-4, 0.56);
        let x: Vec<f64> = (0..m)
            .map(|i| match i % 37 {
                0 => w.lo + radius[i] - 0.004,
                1 => w.hi - radius[i] + 0.003,
                2 => w.lo + radius[i] + 0.001,
                _ => 0.6 + 8.0 * ((i * 7919) % 1000) as f64 / 1000.0,
            })
            .collect();
        let v: Vec<f64> = (0..m).map(|i| 1e-4 * ((i as f64) * 0.3).sin()).collect();
        let wall_kr: Vec<f64> = radius.iter().map(|r| 1e7 * r.sqrt()).collect();
        let mut touching0 = vec![0u8; m];
        for i in (0..m).step_by(41) {
            touching0[i] = WALL_LO;
        }
        touching0[37] = WALL_LO | WALL_HI;
        let reference = |x: &[f64]| {
            let (mut t, mut f, mut b) = (touching0.clone(), vec![-1.0; m], Books::default());
            for i in 0..m {
                // One particle at a time: a block of one is never screened.
                let s = i..i + 1;
                wall_forces(
                    &w,
                    &x[s.clone()],
                    &v[s.clone()],
                    &radius[s.clone()],
                    &wall_kr[s.clone()],
                    &mut t[s.clone()],
                    &mut f[s],
                    &mut b,
                );
            }
            (t, f, b)
        };
        let (t_ref, f_ref, b_ref) = reference(&x);
        let (mut t, mut f, mut b) = (touching0.clone(), vec![-1.0; m], Books::default());
        wall_forces(&w, &x, &v, &radius, &wall_kr, &mut t, &mut f, &mut b);
        assert_eq!(t, t_ref);
        let bits = |f: &[f64]| f.iter().map(|a| a.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&f), bits(&f_ref));
        assert_eq!(b.dissipated.to_bits(), b_ref.dissipated.to_bits());
        assert_eq!(b.work.to_bits(), b_ref.work.to_bits());
        assert_eq!(b.wall_onsets, b_ref.wall_onsets);
        assert_eq!(b.max_overlap.to_bits(), b_ref.max_overlap.to_bits());
        // The case mix is exercised: onsets at both walls, cleared bits, quiet blocks.
        assert!(b.wall_onsets >= 10 && b.dissipated != 0.0 && b.work != 0.0);
        assert!(t.iter().zip(&touching0).any(|(a, b)| *a == 0 && *b != 0));
        assert!(
            (0..m / SCREEN_BLOCK).any(|c| {
                let s = c * SCREEN_BLOCK..(c + 1) * SCREEN_BLOCK;
                block_is_quiet(&w, &x[s.clone()], &touching0[s])
            }),
            "no block is screened out: the test does not exercise the screening"
        );
        let far = [4.5; SCREEN_BLOCK];
        let mut nan = far;
        nan[5] = f64::NAN;
        assert!(block_is_quiet(&w, &far, &[0; SCREEN_BLOCK]));
        assert!(!block_is_quiet(&w, &nan, &[0; SCREEN_BLOCK]));
        let mut bit = [0; SCREEN_BLOCK];
        bit[7] = WALL_HI;
        assert!(!block_is_quiet(&w, &far, &bit));
    }

    /// The screen is conservative: a centre it passes is apart from both walls by the
    /// per-particle test, for the largest radius, centres on a fine grid around both edges of
    /// the band, and walls far from the origin (large round-off).
    #[test]
    fn the_screening_band_is_conservative() {
        for (lo, hi, r) in [
            (0.0, 9.0, 0.53),
            (-0.05, 8.95, 0.5),
            (1e6 + 0.3, 1e6 + 7.1, 0.031),
        ] {
            let w = WallAxis::new(lo, hi, 0.0, 1.0, 0.0, 1e-4, r);
            let mut passed = 0;
            for edge in [w.quiet_lo, w.quiet_hi] {
                let mut x = edge;
                for _ in 0..2000 {
                    x = x.next_down();
                }
                for _ in 0..4000 {
                    x = x.next_up();
                    if block_is_quiet(&w, &[x; SCREEN_BLOCK], &[0; SCREEN_BLOCK]) {
                        passed += 1;
                        assert!(r - (x - lo) <= 0.0 && x + r - hi <= 0.0, "x = {x}");
                    }
                }
            }
            assert!(
                passed > 3000,
                "the band's edges are exercised from both sides"
            );
        }
    }
}
