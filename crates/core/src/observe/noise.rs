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
//!
//! That model treats the bins as independent, which neighbouring bins of a profile are not (a
//! grain near a bin edge, a density wave, a bed swaying as a whole). [`NullRanges`] does without
//! it: a *maximum-statistic bootstrap over the profile*. The window's block means form a matrix
//! (blocks x bins); whole rows are resampled, so every correlation between bins is kept, and
//! each resample gives the range over the bins of its mean's deviation from the window mean.
//! Those ranges are the spread a homogeneous state with the same noise shows; their quantiles
//! are stored with the result and the classifier compares `Delta` with the one at its level.
//! Blocks are merged until neighbouring block means are uncorrelated
//! ([`decorrelated_blocks`]), so resampling rows as independent draws is justified.

use serde::{Deserialize, Serialize};
use std::collections::HashMap;
use std::f64::consts::{FRAC_1_SQRT_2, PI};
use std::sync::{LazyLock, Mutex};

/// `erfc(x)`, relative error below `1.2e-7` everywhere (the Chebyshev-fitted exponential of
/// Press et al., Numerical Recipes, Sec. 6.2, written out here).
pub(crate) fn erfc(x: f64) -> f64 {
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
pub(crate) fn normal_cdf(x: f64) -> f64 {
    0.5 * erfc(-x * FRAC_1_SQRT_2)
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
pub(crate) fn range_cdf(b: usize, r: f64) -> f64 {
    if b < 2 {
        return 1.0;
    }
    if r <= 0.0 {
        return 0.0;
    }
    let s = integrate(|x| {
        let inner = (normal_cdf(x + r) - normal_cdf(x)).max(0.0);
        // The standard normal density phi(x) times the rest of the integrand.
        (-0.5 * x * x).exp() / (2.0 * PI).sqrt() * inner.powi(b as i32 - 1)
    });
    (b as f64 * s).clamp(0.0, 1.0)
}

/// Values of [`range_quantile`] (`q` as its bits) and [`range_mean`] (`q = None`) computed in
/// this process, by number of bins. Each is a pure function of its arguments that costs 60 or
/// one numerical integrals of 3 600 steps, and a sweep's results share a handful of `(b, q)`:
/// relabelling 10^4 results without a stored bootstrap null asked for the same few values
/// 10^4 times.
static RANGE_CACHE: LazyLock<Mutex<HashMap<RangeKey, f64>>> = LazyLock::new(Default::default);

/// `(bins, quantile bits)`, `None` for the mean.
type RangeKey = (usize, Option<u64>);

/// `f()`, computed once per process for `key` (a poisoned lock only costs the cache).
fn cached(key: RangeKey, f: impl FnOnce() -> f64) -> f64 {
    if let Some(v) = RANGE_CACHE.lock().ok().and_then(|c| c.get(&key).copied()) {
        return v;
    }
    let v = f();
    if let Ok(mut c) = RANGE_CACHE.lock() {
        c.insert(key, v);
    }
    v
}

/// The `q` quantile of the range of `b` independent standard normal values (0 for `b < 2`).
pub fn range_quantile(b: usize, q: f64) -> f64 {
    if b < 2 {
        return 0.0;
    }
    cached((b, Some(q.to_bits())), || range_quantile_uncached(b, q))
}

fn range_quantile_uncached(b: usize, q: f64) -> f64 {
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
pub(crate) fn range_mean(b: usize) -> f64 {
    if b < 2 {
        return 0.0;
    }
    cached((b, None), || range_mean_uncached(b))
}

fn range_mean_uncached(b: usize) -> f64 {
    integrate(|x| {
        let p = normal_cdf(x);
        1.0 - p.powi(b as i32) - (1.0 - p).powi(b as i32)
    })
}

/// Standard error of the mean of a series from its block means: `sd(block means) /
/// sqrt(blocks)`, the blocks being consecutive groups of the given means merged until at most
/// `max_blocks` remain (so each is long against the correlation time). `None` with fewer than
/// two blocks.
pub(crate) fn block_standard_error(
    means: &[f64],
    weights: &[f64],
    max_blocks: usize,
) -> Option<f64> {
    let (mut m, mut w): (Vec<f64>, Vec<f64>) = (means.to_vec(), weights.to_vec());
    while m.len() > max_blocks.max(2) {
        // Neighbours merged by weight; a last odd block kept as it is.
        (m, w) = m
            .chunks(2)
            .zip(w.chunks(2))
            .map(|pair| match pair {
                (&[a, b], &[wa, wb]) => {
                    let wt = wa + wb;
                    let mean = if wt > 0.0 {
                        (a * wa + b * wb) / wt
                    } else {
                        0.5 * (a + b)
                    };
                    (mean, wt)
                }
                (a, wa) => (a[0], wa[0]),
            })
            .unzip();
    }
    let n = m.len();
    if n < 2 {
        return None;
    }
    let mean = m.iter().sum::<f64>() / n as f64;
    let var = m.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (n - 1) as f64;
    Some((var / n as f64).sqrt())
}

/// Resamples drawn by [`null_ranges`].
pub(crate) const BOOTSTRAP_RESAMPLES: usize = 4000;
/// The quantile levels stored in [`NullRanges`]: a classifier level between two of them is read
/// by interpolation in `ln(1 - q)`.
pub(crate) const NULL_LEVELS: [f64; 8] = [0.5, 0.8, 0.9, 0.95, 0.98, 0.99, 0.995, 0.999];
/// Fewest blocks the bootstrap keeps when it merges correlated blocks.
pub(crate) const MIN_BOOTSTRAP_BLOCKS: usize = 8;

/// The null distribution of a profile's spread `Delta` (see the module doc).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct NullRanges {
    /// Blocks resampled (after merging correlated ones).
    pub blocks: usize,
    /// Lag-one autocorrelation of the block means' deviations, pooled over bins, of those blocks.
    pub lag1_correlation: f64,
    /// `(q, range)`: the `q` quantile of the bootstrap ranges, for every `q` of [`NULL_LEVELS`].
    pub(crate) quantiles: Vec<(f64, f64)>,
}

impl NullRanges {
    /// The `q` quantile of the null range: interpolated in `ln(1 - q)` between stored levels,
    /// clamped to the extreme ones.
    pub fn quantile(&self, q: f64) -> f64 {
        let qs = &self.quantiles;
        let Some(first) = qs.first() else {
            return f64::NAN;
        };
        if q <= first.0 {
            return first.1;
        }
        for w in qs.windows(2) {
            let ((q0, r0), (q1, r1)) = (w[0], w[1]);
            if q <= q1 {
                let (x0, x1, x) = ((1.0 - q0).ln(), (1.0 - q1).ln(), (1.0 - q).ln());
                return r0 + (r1 - r0) * (x - x0) / (x1 - x0);
            }
        }
        qs[qs.len() - 1].1
    }
}

/// Block means and weights merged pairwise (weighted) until at most `max_blocks` remain.
pub(crate) fn merge_to(
    mut means: Vec<Vec<f64>>,
    mut weights: Vec<f64>,
    max_blocks: usize,
) -> (Vec<Vec<f64>>, Vec<f64>) {
    while means.len() > max_blocks.max(1) {
        (means, weights) = merge_pairs(&means, &weights);
    }
    (means, weights)
}

/// One halving: blocks `2i` and `2i + 1` merged by weight (a last odd block kept).
fn merge_pairs(means: &[Vec<f64>], weights: &[f64]) -> (Vec<Vec<f64>>, Vec<f64>) {
    let k = means.len();
    let (mut m, mut w) = (Vec::with_capacity(k / 2 + 1), Vec::with_capacity(k / 2 + 1));
    for pair in (0..k).collect::<Vec<_>>().chunks(2) {
        let wt: f64 = pair.iter().map(|&i| weights[i]).sum();
        let row = (0..means[pair[0]].len())
            .map(|b| {
                if wt > 0.0 {
                    pair.iter().map(|&i| means[i][b] * weights[i]).sum::<f64>() / wt
                } else {
                    pair.iter().map(|&i| means[i][b]).sum::<f64>() / pair.len() as f64
                }
            })
            .collect();
        m.push(row);
        w.push(wt);
    }
    (m, w)
}

/// Block means (`means[k][b]`: block `k`, bin `b`) and block weights merged pairwise while the
/// lag-one autocorrelation of the deviations from the weighted mean, pooled over bins, exceeds
/// `max(0.1, 2 / sqrt(K))` and more than [`MIN_BOOTSTRAP_BLOCKS`] remain; returns the blocks and
/// the final correlation.
pub(crate) fn decorrelated_blocks(
    mut means: Vec<Vec<f64>>,
    mut weights: Vec<f64>,
) -> (Vec<Vec<f64>>, Vec<f64>, f64) {
    loop {
        let r = lag1_correlation(&means, &weights);
        let k = means.len();
        if k < 2 * MIN_BOOTSTRAP_BLOCKS || r <= (2.0 / (k as f64).sqrt()).max(0.1) {
            return (means, weights, r);
        }
        (means, weights) = merge_pairs(&means, &weights);
    }
}

/// Weighted mean over blocks, per bin.
fn column_means(means: &[Vec<f64>], weights: &[f64]) -> Vec<f64> {
    let bins = means.first().map_or(0, Vec::len);
    let wt: f64 = weights.iter().sum();
    (0..bins)
        .map(|b| {
            means
                .iter()
                .zip(weights)
                .map(|(row, w)| row[b] * w)
                .sum::<f64>()
                / wt.max(f64::MIN_POSITIVE)
        })
        .collect()
}

/// Lag-one autocorrelation of the rows' deviations from the column means, pooled over bins.
fn lag1_correlation(means: &[Vec<f64>], weights: &[f64]) -> f64 {
    if means.len() < 3 {
        return 0.0;
    }
    let mu = column_means(means, weights);
    let dev: Vec<Vec<f64>> = means
        .iter()
        .map(|row| row.iter().zip(&mu).map(|(x, m)| x - m).collect())
        .collect();
    let (mut num, mut den) = (0.0, 0.0);
    for k in 0..dev.len() {
        for b in 0..dev[k].len() {
            den += dev[k][b] * dev[k][b];
            if k + 1 < dev.len() {
                num += dev[k][b] * dev[k + 1][b];
            }
        }
    }
    if den > 0.0 { num / den } else { 0.0 }
}

/// The bootstrap null distribution of the profile's range (module doc) from block means
/// `means[k][b]` with weights (samples per block); `None` with fewer than
/// [`MIN_BOOTSTRAP_BLOCKS`] blocks. Deterministic: the generator is seeded by a constant.
pub(crate) fn null_ranges(means: Vec<Vec<f64>>, weights: Vec<f64>) -> Option<NullRanges> {
    use rand::{Rng, SeedableRng};
    let (means, weights, r1) = decorrelated_blocks(means, weights);
    let k = means.len();
    if k < MIN_BOOTSTRAP_BLOCKS {
        return None;
    }
    let bins = means[0].len();
    let mu = column_means(&means, &weights);
    let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(0x005e_ed0f_b007);
    // sqrt(K / (K - 1)): the bootstrap of a mean from K draws underestimates its variance.
    let inflate = (k as f64 / (k - 1) as f64).sqrt();
    let mut ranges = Vec::with_capacity(BOOTSTRAP_RESAMPLES);
    let mut sum = vec![0.0; bins];
    for _ in 0..BOOTSTRAP_RESAMPLES {
        sum.iter_mut().for_each(|x| *x = 0.0);
        let mut wt = 0.0;
        for _ in 0..k {
            let i = rng.gen_range(0..k);
            wt += weights[i];
            for (s, x) in sum.iter_mut().zip(&means[i]) {
                *s += x * weights[i];
            }
        }
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for (s, m) in sum.iter().zip(&mu) {
            let d = s / wt.max(f64::MIN_POSITIVE) - m;
            lo = lo.min(d);
            hi = hi.max(d);
        }
        ranges.push(inflate * (hi - lo));
    }
    ranges.sort_by(f64::total_cmp);
    let quantiles = NULL_LEVELS
        .iter()
        .map(|&q| {
            let i = ((q * ranges.len() as f64).ceil() as usize).clamp(1, ranges.len()) - 1;
            (q, ranges[i])
        })
        .collect();
    Some(NullRanges {
        blocks: k,
        lag1_correlation: r1,
        quantiles,
    })
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
    fn cached_range_values_equal_the_computed_ones() {
        for b in [3, 7, 16] {
            for q in [0.95, 0.99] {
                // The first call fills the cache (if no other test did), the second reads it.
                range_quantile(b, q);
                assert_eq!(
                    range_quantile(b, q).to_bits(),
                    range_quantile_uncached(b, q).to_bits()
                );
            }
            range_mean(b);
            assert_eq!(range_mean(b).to_bits(), range_mean_uncached(b).to_bits());
        }
        // Another level is another entry.
        assert!(range_quantile(7, 0.99) > range_quantile(7, 0.95));
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

    /// Block means of a homogeneous profile: `bins` values per block, independent normal noise
    /// of standard deviation `sd` shared by groups of `corr` neighbouring bins (a density wave
    /// that moves every block), plus `profile(b)`.
    fn blocks(
        rng: &mut impl rand::Rng,
        k: usize,
        bins: usize,
        sd: f64,
        corr: usize,
        profile: &dyn Fn(usize) -> f64,
    ) -> Vec<Vec<f64>> {
        use rand_distr::StandardNormal;
        (0..k)
            .map(|_| {
                let shared: Vec<f64> = (0..bins.div_ceil(corr))
                    .map(|_| rng.sample::<f64, _>(StandardNormal))
                    .collect();
                (0..bins)
                    .map(|b| profile(b) + sd * shared[b / corr])
                    .collect()
            })
            .collect()
    }

    #[test]
    fn bootstrap_level_holds_with_correlated_bins() {
        // Homogeneous profiles whose noise is shared by groups of 10 bins (100 bins): the range
        // test that treats the bins as independent has the wrong level; the bootstrap's 0.95
        // quantile is exceeded in about 5 % of windows.
        use rand::SeedableRng;
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(11);
        let (windows, k, bins, sd) = (400, 32, 100, 1.0);
        let (mut boot, mut independent) = (0usize, 0usize);
        for _ in 0..windows {
            let m = blocks(&mut rng, k, bins, sd, 10, &|_| 5.0);
            let mu = column_means(&m, &vec![1.0; k]);
            let delta = mu.iter().copied().fold(f64::MIN, f64::max)
                - mu.iter().copied().fold(f64::MAX, f64::min);
            let null = null_ranges(m, vec![1.0; k]).unwrap();
            boot += usize::from(delta > null.quantile(0.95));
            let se = sd / (k as f64).sqrt();
            independent += usize::from(delta > se * range_quantile(bins, 0.95));
        }
        let (b, i) = (
            boot as f64 / windows as f64,
            independent as f64 / windows as f64,
        );
        println!("false positives at level 0.05: bootstrap {b:.3}, independent bins {i:.3}");
        assert!((0.02..=0.09).contains(&b), "bootstrap {b}");
        // The independent-bin model is miscalibrated here (too few distinct values: its range
        // quantile is too wide, so it rarely fires; on other structures it fires too often).
        assert!((i - 0.05).abs() > 0.03, "independent {i}");
    }

    #[test]
    fn bootstrap_detects_a_step_profile() {
        // A dense half and a dilute half 6 block-standard-errors apart: detected every time.
        use rand::SeedableRng;
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(12);
        let (k, bins, sd) = (32, 100, 1.0);
        let step = 6.0 * sd / (k as f64).sqrt();
        for _ in 0..50 {
            let m = blocks(&mut rng, k, bins, sd, 1, &|b| {
                if b < 50 { step } else { 0.0 }
            });
            let mu = column_means(&m, &vec![1.0; k]);
            let delta = mu.iter().copied().fold(f64::MIN, f64::max)
                - mu.iter().copied().fold(f64::MAX, f64::min);
            let null = null_ranges(m, vec![1.0; k]).unwrap();
            assert!(
                delta > null.quantile(0.99),
                "{delta} vs {:?}",
                null.quantiles
            );
        }
    }

    #[test]
    fn correlated_blocks_are_merged() {
        // Safeguard: blocks of an AR(1) series with phi = 0.8 per block are merged until the
        // lag-one correlation is small; without merging the bootstrap would see 32 "independent"
        // blocks and a range too narrow by about sqrt((1 + phi) / (1 - phi)) = 3.
        use rand::{Rng, SeedableRng};
        use rand_distr::StandardNormal;
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(13);
        let mut x = vec![0.0f64; 20];
        let m: Vec<Vec<f64>> = (0..64)
            .map(|_| {
                for v in x.iter_mut() {
                    *v = 0.8 * *v + 0.6 * rng.sample::<f64, _>(StandardNormal);
                }
                x.clone()
            })
            .collect();
        let (merged, _, r) = decorrelated_blocks(m, vec![1.0; 64]);
        assert!(
            merged.len() < 64 && merged.len() >= MIN_BOOTSTRAP_BLOCKS,
            "{}",
            merged.len()
        );
        assert!(r < 0.8, "{r}");
    }

    #[test]
    fn null_quantile_interpolates_between_levels() {
        let n = NullRanges {
            blocks: 32,
            lag1_correlation: 0.0,
            quantiles: vec![(0.9, 1.0), (0.99, 2.0)],
        };
        assert_eq!(n.quantile(0.5), 1.0);
        assert!((n.quantile(0.9683772) - 1.5).abs() < 1e-6);
        assert_eq!(n.quantile(0.999), 2.0);
    }
}
