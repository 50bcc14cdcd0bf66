//! The block test behind the run policy (scene section `[convergence]`, docs/observables.md
//! "Run to a settled label"): block statistics of a sampled history, whether its blocks agree
//! and whether it drifts (`observe::trend` applies it to each monitored quantity).
//!
//! - **Standard error of a correlated series**: Flyvbjerg-Petersen blocking (J. Chem. Phys. 91,
//!   461 (1989)). At level `l` the series of `n_l` values is replaced by the means of
//!   neighbouring pairs; at every level `SE_l = sqrt(c0_l / (n_l - 1))`, `c0_l` the (biased)
//!   variance of the level's values, with its own error `SE_l / sqrt(2 (n_l - 1))`. `SE_l`
//!   grows with `l` until the blocks are longer than the correlation time and then stays put
//!   (the plateau); the estimate is the first level whose successor no longer rises by more
//!   than its error bar. Levels with fewer than [`MIN_BLOCKS`] values are not used.
//! - **Agreement**: the window is cut into `blocks` parts of equal sample count, each with its
//!   mean `m_i`. Under the hypothesis being tested (a stationary series) all blocks share one
//!   error `SE = sqrt(var_res tau / n_b)`: `var_res` the variance of the samples about their
//!   block's mean, `tau` the integrated autocorrelation time of those residuals
//!   ([`integrated_time`]), `n_b` samples per block. Residuals about the block means keep a step
//!   or a drift between blocks out of the error; blocking within a single block would need
//!   blocks hundreds of correlation times long to reach its plateau, and underestimates the
//!   error (by 10-15 % at 50 correlation times per block). Every pair of block means must
//!   agree, `|m_i - m_j| <= k sqrt(2) SE + tol`.
//! - **Trend**: the least-squares slope `b` of the block means against the block index,
//!   `b = sum w_i m_i`, `w_i = (i - i_bar) / sum (i - i_bar)^2`, has the error
//!   `SE_b = SE sqrt(sum w_i^2)`; the drift over the window `b (blocks - 1)` must satisfy
//!   `|b| <= k SE_b + tol / (blocks - 1)`. A slow monotone drift that hides inside every
//!   pairwise error bar still fails here, because the slope uses all blocks at once.
//! - `tol = rel_tolerance * max(|window mean|, floor)`: differences smaller than a fixed
//!   fraction of the value (or of the quantity's floor where it is nearly zero) are accepted as
//!   stationary in practice, so that a solid with an almost frozen bridge count is not extended
//!   forever over a drift of a thousandth.

use serde::{Deserialize, Serialize};

/// Fewest values at a blocking level for its standard error to be used.
pub(crate) const MIN_BLOCKS: usize = 16;

/// Floor of `Delta n_cb` (units `d^-(D-1)`) for the tolerance of the test.
pub(crate) const FLOOR_DELTA_N_CB: f64 = 0.05;

/// The standard error of the mean of `x` by blocking (see the module doc), and whether it
/// reached a plateau: if not, it is the last usable level's value (a lower bound: the series is
/// short compared with its correlation time). Series shorter than [`MIN_BLOCKS`] fall back to
/// the uncorrelated estimate `sqrt(c0 / (n - 1))` (no plateau).
pub(crate) fn blocking_error(x: &[f64]) -> (f64, bool) {
    let se_of = |v: &[f64]| -> f64 {
        let n = v.len();
        if n < 2 {
            return f64::INFINITY;
        }
        let mean = v.iter().sum::<f64>() / n as f64;
        let c0 = v.iter().map(|a| (a - mean) * (a - mean)).sum::<f64>() / n as f64;
        (c0 / (n - 1) as f64).sqrt()
    };
    let mut levels: Vec<(f64, f64)> = Vec::new(); // (SE_l, error of SE_l)
    let mut v = x.to_vec();
    while v.len() >= MIN_BLOCKS {
        let se = se_of(&v);
        levels.push((se, se / (2.0 * (v.len() - 1) as f64).sqrt()));
        v = v.chunks_exact(2).map(|p| 0.5 * (p[0] + p[1])).collect();
    }
    for pair in levels.windows(2) {
        let (se, err) = pair[0];
        if pair[1].0 <= se + err {
            return (se, true);
        }
    }
    (levels.last().map_or_else(|| se_of(x), |l| l.0), false)
}

/// Integrated autocorrelation time `tau = 1 + 2 sum_(t=1..M) rho(t)` (in samples) of the
/// residuals `x - m_b` about the block means, with lags taken inside blocks only (a step or a
/// drift between blocks does not inflate it) and Sokal's window: the smallest `M >= 5 tau(M)`,
/// at most half a block.
pub(crate) fn integrated_time(x: &[f64], block_means: &[f64], per: usize) -> f64 {
    let r: Vec<f64> = x
        .iter()
        .enumerate()
        .map(|(i, v)| v - block_means[i / per])
        .collect();
    let c = |lag: usize| -> f64 {
        let (mut sum, mut count) = (0.0, 0usize);
        for b in r.chunks_exact(per) {
            for i in 0..per - lag {
                sum += b[i] * b[i + lag];
            }
            count += per - lag;
        }
        sum / count.max(1) as f64
    };
    let c0 = c(0);
    if c0 <= 0.0 {
        return 1.0;
    }
    let mut tau = 1.0;
    for m in 1..per / 2 {
        tau += 2.0 * c(m) / c0;
        if m as f64 >= 5.0 * tau {
            break;
        }
    }
    tau.max(1.0)
}

/// The block statistics and the verdict of one monitored quantity. A quantity with too few
/// values to test has NaN statistics, which JSON stores as `null`: they read back as NaN.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BlockTest {
    pub quantity: String,
    /// Mean over the window.
    #[serde(deserialize_with = "nan_if_null")]
    pub mean: f64,
    /// Standard error of the window mean (blocking).
    #[serde(deserialize_with = "nan_if_null")]
    pub standard_error: f64,
    pub block_means: Vec<f64>,
    /// Standard error of each block mean, pooled over the blocks:
    /// `sqrt(var_res tau / samples per block)`, `var_res` the variance about the block means,
    /// `tau` from [`integrated_time`] (the same for every block).
    pub block_errors: Vec<f64>,
    /// Largest `|m_i - m_j| / (sqrt(2) SE)` over the pairs of blocks (`SE` pooled).
    #[serde(deserialize_with = "nan_if_null")]
    pub max_pair_sigmas: f64,
    /// Least-squares change of the block means from the first to the last block.
    #[serde(deserialize_with = "nan_if_null")]
    pub drift: f64,
    /// Standard error of `drift`.
    #[serde(deserialize_with = "nan_if_null")]
    pub drift_error: f64,
    /// The allowance `rel_tolerance * max(|mean|, floor)`.
    #[serde(deserialize_with = "nan_if_null")]
    pub tolerance: f64,
    /// Every pair of blocks agrees.
    pub agree: bool,
    /// No trend beyond the errors.
    pub no_trend: bool,
}

/// A stored number, or NaN where JSON stored `null` (serde_json writes NaN as `null`).
fn nan_if_null<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
}

impl BlockTest {
    /// Both tests passed.
    pub fn ok(&self) -> bool {
        self.agree && self.no_trend
    }
}

/// Runs the agreement and trend tests on `x` (one window, equally spaced samples) cut into
/// `blocks` blocks of equal sample count (the remainder, fewer than `blocks` samples, is dropped
/// from the start). `sigmas` is `k`. Fewer than two samples per block fails both tests.
pub(crate) fn block_test(
    quantity: &str,
    x: &[f64],
    blocks: usize,
    sigmas: f64,
    rel_tolerance: f64,
    floor: f64,
) -> BlockTest {
    assert!(blocks >= 2, "at least two blocks");
    let per = x.len() / blocks;
    let x = &x[x.len() - per * blocks..];
    let mean = if x.is_empty() {
        f64::NAN
    } else {
        x.iter().sum::<f64>() / x.len() as f64
    };
    let tolerance = rel_tolerance * mean.abs().max(floor);
    let mut out = BlockTest {
        quantity: quantity.to_string(),
        mean,
        standard_error: blocking_error(x).0,
        block_means: Vec::new(),
        block_errors: Vec::new(),
        max_pair_sigmas: f64::INFINITY,
        drift: f64::NAN,
        drift_error: f64::NAN,
        tolerance,
        agree: false,
        no_trend: false,
    };
    if per < 2 {
        return out;
    }
    for b in x.chunks_exact(per) {
        out.block_means.push(b.iter().sum::<f64>() / per as f64);
    }
    let tau = integrated_time(x, &out.block_means, per);
    let residual_var = x
        .chunks_exact(per)
        .zip(&out.block_means)
        .flat_map(|(b, m)| b.iter().map(move |v| (v - m) * (v - m)))
        .sum::<f64>()
        / (x.len() - blocks) as f64;
    // One error for every block (the hypothesis: a stationary series).
    let pooled = (residual_var * tau / per as f64).sqrt();
    out.block_errors = vec![pooled; blocks];
    let m = &out.block_means;
    let mut agree = true;
    let mut max_sig: f64 = 0.0;
    for i in 0..blocks {
        for j in i + 1..blocks {
            let diff = (m[i] - m[j]).abs();
            let err = std::f64::consts::SQRT_2 * pooled;
            agree &= diff <= sigmas * err + tolerance;
            let sig = if err > 0.0 {
                diff / err
            } else if diff > 0.0 {
                f64::INFINITY
            } else {
                0.0
            };
            max_sig = max_sig.max(sig);
        }
    }
    // Least-squares slope over the block index: b = sum w_i m_i.
    let i_bar = (blocks - 1) as f64 / 2.0;
    let sxx: f64 = (0..blocks).map(|i| (i as f64 - i_bar).powi(2)).sum();
    let w: Vec<f64> = (0..blocks).map(|i| (i as f64 - i_bar) / sxx).collect();
    let slope: f64 = w.iter().zip(m).map(|(w, m)| w * m).sum();
    let slope_err = pooled * w.iter().map(|w| w * w).sum::<f64>().sqrt();
    let span = (blocks - 1) as f64;
    out.drift = slope * span;
    out.drift_error = slope_err * span;
    out.no_trend = out.drift.abs() <= sigmas * out.drift_error + tolerance;
    out.agree = agree;
    out.max_pair_sigmas = max_sig;
    out
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, StandardNormal};
    use rand_xoshiro::Xoshiro256PlusPlus;

    /// `x_t = phi x_(t-1) + e_t`, `e_t` standard normal, started in the stationary law.
    pub(crate) fn ar1(phi: f64, n: usize, seed: u64) -> Vec<f64> {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
        let mut e = || -> f64 { StandardNormal.sample(&mut rng) };
        let mut x = e() / (1.0 - phi * phi).sqrt();
        (0..n)
            .map(|_| {
                x = phi * x + e();
                x
            })
            .collect()
    }

    /// Known standard error of the mean of `n` AR(1) values for large `n`:
    /// `sqrt(var / n * (1 + phi) / (1 - phi))`, `var = 1 / (1 - phi^2)`.
    fn ar1_error(phi: f64, n: usize) -> f64 {
        (1.0 / (1.0 - phi * phi) / n as f64 * (1.0 + phi) / (1.0 - phi)).sqrt()
    }

    #[test]
    fn blocking_matches_the_ar1_standard_error() {
        for (phi, seed) in [(0.0, 1), (0.5, 2), (0.9, 3), (0.95, 4)] {
            let n = 1 << 16;
            let mut ratios = Vec::new();
            for r in 0..4 {
                let x = ar1(phi, n, seed * 10 + r);
                let (se, plateau) = blocking_error(&x);
                assert!(plateau, "phi {phi}: {se}");
                ratios.push(se / ar1_error(phi, n));
            }
            let mean = ratios.iter().sum::<f64>() / ratios.len() as f64;
            assert!((mean - 1.0).abs() < 0.15, "phi {phi}: ratios {ratios:?}");
        }
    }

    #[test]
    fn blocking_of_white_noise_stays_at_level_zero_value() {
        let x = ar1(0.0, 4096, 7);
        let (se, _) = blocking_error(&x);
        let naive = {
            let m = x.iter().sum::<f64>() / x.len() as f64;
            (x.iter().map(|a| (a - m).powi(2)).sum::<f64>() / x.len() as f64 / 4095.0).sqrt()
        };
        assert!((se / naive - 1.0).abs() < 0.1, "{se} vs {naive}");
    }

    #[test]
    fn a_stationary_ar1_series_passes() {
        let mut passed = 0;
        for seed in 0..40 {
            let x: Vec<f64> = ar1(0.9, 4000, 100 + seed).iter().map(|v| 5.0 + v).collect();
            let t = block_test("x", &x, 4, 3.0, 0.0, 0.0);
            passed += t.ok() as usize;
        }
        // 4000 samples of correlation time 19 (the size of a real window: 150 periods of 20
        // samples with a correlation time of one period). With k = 3, six pairs and a slope,
        // and an error estimated from the window itself (about 15 % uncertain at this length),
        // a false alarm costs one more window in about one window of ten.
        assert!(passed >= 34, "{passed} of 40 stationary series passed");
    }

    #[test]
    fn a_linear_drift_fails() {
        // A drift of 1.5 noise standard deviations over the window: inside each pair's error
        // bar only for neighbouring blocks, caught by the trend test.
        for seed in 0..10 {
            let x = ar1(0.9, 4000, 200 + seed);
            let sd = (1.0f64 / (1.0 - 0.81)).sqrt();
            let y: Vec<f64> = x
                .iter()
                .enumerate()
                .map(|(i, v)| 5.0 + v + 1.5 * sd * i as f64 / 4000.0)
                .collect();
            let t = block_test("x", &y, 4, 3.0, 0.0, 0.0);
            assert!(!t.no_trend, "seed {seed}: {t:?}");
            assert!(!t.ok());
            assert!(t.drift > 0.0);
        }
    }

    #[test]
    fn a_step_change_fails() {
        for seed in 0..10 {
            let x = ar1(0.9, 4000, 300 + seed);
            let y: Vec<f64> = x
                .iter()
                .enumerate()
                .map(|(i, v)| if i < 3000 { 5.0 + v } else { 7.0 + v })
                .collect();
            let t = block_test("x", &y, 4, 3.0, 0.0, 0.0);
            assert!(!t.agree, "seed {seed}: {t:?}");
        }
    }

    #[test]
    fn the_tolerance_accepts_a_tiny_drift_of_a_frozen_quantity() {
        // Bridges per particle of a solid: no noise, a drift of 0.1 % over the window.
        let y: Vec<f64> = (0..400)
            .map(|i| 1.5 * (1.0 + 1e-3 * i as f64 / 400.0))
            .collect();
        assert!(!block_test("b", &y, 4, 3.0, 0.0, 0.1).ok());
        assert!(block_test("b", &y, 4, 3.0, 0.02, 0.1).ok());
        // A constant passes without any tolerance.
        assert!(block_test("b", &[0.0; 40], 4, 3.0, 0.0, 0.0).ok());
    }

    #[test]
    fn too_few_samples_fail() {
        let t = block_test("x", &[1.0, 1.0, 1.0], 4, 3.0, 0.1, 1.0);
        assert!(!t.ok());
    }
}
