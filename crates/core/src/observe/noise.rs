//! Noise baselines for the coexistence test (docs/model.md 7, Eq. 3.3).
//!
//! `Delta n = max_b n_b - min_b n_b` over `B` lateral bins is never zero in a finite run: each
//! bin's time average `n_b` carries a statistical error `se_b`. In a homogeneous state the `n_b`
//! scatter around one common mean, and `Delta n` is the *range* of `B` such values. For `B`
//! independent normal values of standard deviation `s`, the range `R` has the distribution
//!
//! ```text
//! P(R <= r) = B * integral phi(x) [Phi(x + r/s) - Phi(x)]^(B-1) dx
//! ```
//!
//! (`phi`, `Phi`: the standard normal density and distribution). [`range_quantile`] inverts it;
//! a `Delta n` above the `q` quantile of the range for `s = rms(se_b)` is significant at level
//! `1 - q`. The per-bin errors `se_b` come from block means ([`block_standard_error`]): the
//! window is cut into blocks long against the correlation time, so that block means are nearly
//! independent.

use std::f64::consts::{FRAC_1_SQRT_2, PI};

/// `erfc(x)`, relative error below `1.2e-7` everywhere (the Chebyshev-fitted exponential of
/// Press et al., Numerical Recipes, Sec. 6.2, written out here).
pub fn erfc(x: f64) -> f64 {
    let z = x.abs();
    let t = 1.0 / (1.0 + 0.5 * z);
    let poly = -z * z - 1.265_512_23
        + t * (1.000_023_68
            + t * (0.374_091_96
                + t * (0.096_784_18
                    + t * (-0.186_288_06
                        + t * (0.278_868_07
                            + t * (-1.135_203_98
                                + t * (1.488_515_87 + t * (-0.822_152_23 + t * 0.170_872_77))))))));
    let r = t * poly.exp();
    if x >= 0.0 { r } else { 2.0 - r }
}

/// Standard normal distribution function `Phi(x)`.
pub fn normal_cdf(x: f64) -> f64 {
    0.5 * erfc(-x * FRAC_1_SQRT_2)
}

/// Standard normal density `phi(x)`.
pub fn normal_pdf(x: f64) -> f64 {
    (-0.5 * x * x).exp() / (2.0 * PI).sqrt()
}

/// Trapezoid rule over `[-9, 9]` (3600 steps): the integrands here are smooth and negligible
/// outside.
fn integrate(f: impl Fn(f64) -> f64) -> f64 {
    let (lo, hi, n) = (-9.0, 9.0, 3600);
    let h = (hi - lo) / n as f64;
    let mut s = 0.0;
    for k in 0..=n {
        let w = if k == 0 || k == n { 0.5 } else { 1.0 };
        s += w * f(lo + k as f64 * h);
    }
    s * h
}

/// `P(R <= r)` for the range `R` of `b` independent standard normal values.
pub fn range_cdf(b: usize, r: f64) -> f64 {
    if b < 2 {
        return 1.0;
    }
    if r <= 0.0 {
        return 0.0;
    }
    let s = integrate(|x| {
        let inner = (normal_cdf(x + r) - normal_cdf(x)).max(0.0);
        normal_pdf(x) * inner.powi(b as i32 - 1)
    });
    (b as f64 * s).clamp(0.0, 1.0)
}

/// The `q` quantile of the range of `b` independent standard normal values (0 for `b < 2`).
pub fn range_quantile(b: usize, q: f64) -> f64 {
    if b < 2 {
        return 0.0;
    }
    let (mut lo, mut hi) = (0.0, 20.0);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if range_cdf(b, mid) < q {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// Mean of the range of `b` independent standard normal values,
/// `E[R] = integral (1 - Phi^b - (1 - Phi)^b) dx`.
pub fn range_mean(b: usize) -> f64 {
    if b < 2 {
        return 0.0;
    }
    integrate(|x| {
        let p = normal_cdf(x);
        1.0 - p.powi(b as i32) - (1.0 - p).powi(b as i32)
    })
}

/// Standard error of the mean of a series from its block means: `sd(block means) /
/// sqrt(blocks)`, the blocks being consecutive groups of the given means merged until at most
/// `max_blocks` remain (so each is long against the correlation time). `None` with fewer than
/// two blocks.
pub fn block_standard_error(means: &[f64], weights: &[f64], max_blocks: usize) -> Option<f64> {
    let (mut m, mut w): (Vec<f64>, Vec<f64>) = (means.to_vec(), weights.to_vec());
    while m.len() > max_blocks.max(2) {
        let mut mm = Vec::with_capacity(m.len() / 2 + 1);
        let mut ww = Vec::with_capacity(m.len() / 2 + 1);
        for k in (0..m.len()).step_by(2) {
            if k + 1 < m.len() {
                let wt = w[k] + w[k + 1];
                mm.push(if wt > 0.0 {
                    (m[k] * w[k] + m[k + 1] * w[k + 1]) / wt
                } else {
                    0.5 * (m[k] + m[k + 1])
                });
                ww.push(wt);
            } else {
                mm.push(m[k]);
                ww.push(w[k]);
            }
        }
        m = mm;
        w = ww;
    }
    let n = m.len();
    if n < 2 {
        return None;
    }
    let mean = m.iter().sum::<f64>() / n as f64;
    let var = m.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (n - 1) as f64;
    Some((var / n as f64).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn erfc_matches_known_values() {
        // Abramowitz & Stegun Table 7.1.
        assert!((erfc(0.0) - 1.0).abs() < 1e-7);
        assert!((erfc(0.5) - 0.479_500_122).abs() < 1e-7);
        assert!((erfc(1.0) - 0.157_299_207).abs() < 1e-7);
        assert!((erfc(2.0) - 0.004_677_735).abs() < 1e-8);
        assert!((erfc(-1.0) - 1.842_700_793).abs() < 1e-7);
    }

    #[test]
    fn range_of_two_normals_is_half_normal_with_sd_sqrt2() {
        // R = |X1 - X2| ~ |N(0, 2)|: E[R] = 2 / sqrt(pi), P(R <= r) = 2 Phi(r / sqrt 2) - 1.
        assert!((range_mean(2) - 2.0 / PI.sqrt()).abs() < 1e-6);
        for r in [0.5, 1.0, 2.5] {
            let exact = 2.0 * normal_cdf(r / 2f64.sqrt()) - 1.0;
            assert!((range_cdf(2, r) - exact).abs() < 1e-6, "r = {r}");
        }
    }

    #[test]
    fn range_mean_matches_tables() {
        // Expected range of n normals (the d2 constants of quality control tables).
        for (b, d2) in [(5, 2.326), (10, 3.078), (25, 3.931), (100, 5.015)] {
            assert!(
                (range_mean(b) - d2).abs() < 2e-3,
                "b = {b}: {}",
                range_mean(b)
            );
        }
    }

    #[test]
    fn range_quantile_inverts_the_cdf_and_matches_monte_carlo() {
        use rand::{Rng, SeedableRng};
        use rand_distr::StandardNormal;
        let q = range_quantile(100, 0.99);
        assert!((range_cdf(100, q) - 0.99).abs() < 1e-9);
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(7);
        let trials = 20_000;
        let mut above = 0;
        for _ in 0..trials {
            let v: Vec<f64> = (0..100).map(|_| rng.sample(StandardNormal)).collect();
            let r = v.iter().copied().fold(f64::MIN, f64::max)
                - v.iter().copied().fold(f64::MAX, f64::min);
            above += usize::from(r > q);
        }
        let frac = above as f64 / trials as f64;
        assert!((frac - 0.01).abs() < 0.003, "{frac}");
    }

    #[test]
    fn block_error_of_independent_values_is_sigma_over_sqrt_n() {
        use rand::{Rng, SeedableRng};
        use rand_distr::StandardNormal;
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(3);
        let mut ratios = Vec::new();
        for _ in 0..200 {
            let x: Vec<f64> = (0..1024).map(|_| rng.sample(StandardNormal)).collect();
            let se = block_standard_error(&x, &vec![1.0; x.len()], 32).unwrap();
            ratios.push(se / (1.0 / 32.0));
        }
        let mean = ratios.iter().sum::<f64>() / ratios.len() as f64;
        assert!((mean - 1.0).abs() < 0.05, "{mean}");
    }

    #[test]
    fn block_error_sees_correlation() {
        // AR(1) with phi = 0.9: the standard error of the mean is sqrt((1+phi)/(1-phi)) = 4.36
        // times the naive one.
        use rand::{Rng, SeedableRng};
        use rand_distr::StandardNormal;
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(5);
        let phi: f64 = 0.9;
        let n = 1 << 16;
        let mut ses = Vec::new();
        for _ in 0..40 {
            let mut x = 0.0;
            let s: Vec<f64> = (0..n)
                .map(|_| {
                    let e: f64 = rng.sample(StandardNormal);
                    x = phi * x + e * (1.0 - phi * phi).sqrt();
                    x
                })
                .collect();
            ses.push(block_standard_error(&s, &vec![1.0; n], 32).unwrap());
        }
        let mean = ses.iter().sum::<f64>() / ses.len() as f64;
        let expect = ((1.0 + phi) / (1.0 - phi)).sqrt() / (n as f64).sqrt();
        assert!((mean / expect - 1.0).abs() < 0.1, "{mean} vs {expect}");
    }
}
