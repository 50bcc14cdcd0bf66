//! Line analyses over a set of results: the fluid-gas boundary along a line of constant Gamma
//! (docs/model.md 7) and the relabelling of the line's points by it ([`classify_line`]). For
//! elastic grains the boundary is the jump of `T_g / E_cb(E*)` ([`fluid_gas_jump`]); for
//! inelastic ones the inflection point ([`fluid_gas_inflection`]). Either is reported only where
//! it stands out of the line's scatter; otherwise the line says "no transition" and its points
//! keep their per-point labels.
//!
//! **The curve.** `T_g / E_cb` spans decades and grows roughly like a power of `E*`, so the
//! curve is read on log-log axes, `x = ln E*`, `y = ln(T_g / E_cb)` ([`Curve`]). Only the
//! line's *homogeneous mobile* points enter it: a solid point (rule 1 of `classify`) is not on
//! the fluid-gas curve, and the whole-system temperature of a coexistence mixes a condensed
//! and a dilute region. Replicas of one `E*` are averaged in `y`.
//!
//! **Errors.** Each point carries the standard error of `y`: the relative block error of the
//! temperature where the run stored one (`Observables::trend`, the block test of
//! `temperature_reduced`: `standard_error / mean`), for replicas `sqrt(sum s_i^2) / n` or
//! their spread `sd / sqrt(n)`, whichever is larger. Where no error is stored (results from
//! before the run-length policy) the scatter is estimated from the line itself: the median
//! absolute residual of each interior point from the straight line through its two
//! neighbours, normalised to a standard deviation ([`scatter_estimate`]); a single jump
//! spoils two residuals, which the median ignores when the line has enough points. Every
//! error has a floor of [`MIN_REL_ERROR`].
//!
//! **Jump (elastic).** At each gap between neighbours with at least two points on either side
//! (one point beyond a step cannot be told from an outlier), a power law `y = a + b x` is
//! fitted to each side and both are extended to the middle of the gap; the step between them
//! there, in units of its standard error, is the test statistic (a bend without a
//! discontinuity gives none). The errors are widened by `s^2 = max(1, chi^2 / (n - 4))` of the
//! two fits, where the sides scatter more than the errors say (errors underestimated, or an
//! elastic gas that keeps heating). The gap with the largest statistic is a jump when its
//! one-sided p-value times the number of gaps tried (Bonferroni) is below [`JUMP_LEVEL`] and
//! the raw ratio `T_{k+1} / T_k` reaches `line_jump_ratio`. The boundary is the geometric mean
//! of the two `E*` that bracket it.
//!
//! **Inflection (inelastic).** The inflection is where the log-log slope `dy/dx` is largest
//! (the second derivative changes sign there). It is reported when a power law for the whole
//! line is rejected by its chi-square at [`INFLECTION_LEVEL`], the steepest slope between
//! neighbours is interior, and it is steeper than the flattest slope on each side by more than
//! their errors allow (one-sided, family-wise [`SLOPE_LEVEL`] with a Bonferroni correction over
//! the slopes; neighbouring slopes share a point, and their covariance counts). It is located
//! by the vertex of the parabola through the largest midpoint slope and its two neighbours.
//!
//! **Gas branch.** With a transition, a homogeneous point is gas when it lies above the
//! boundary *and* its `T_g` is on the gas branch: for a jump, at or above the midpoint (in `y`)
//! between the two fitted branches at its own `E*`, or at least as hot as the point just above
//! the jump (the branches, extended far, may cross); for an inflection, at or above the
//! temperature interpolated at the inflection. A point above the boundary but below the gas
//! branch stays fluid, and its `decided_on.reason` says so.
//!
//! **No transition.** Where the curve shows none, but the line has fluid-gas coexistences, the
//! coexistences mark the transition (method `"coexistence"`): a homogeneous point below the
//! lowest coexistence `E*` and colder than every coexistence is fluid, one above the highest
//! and hotter than every coexistence is gas; any other point keeps the per-point fallback.
//! Otherwise every point keeps its per-point label, with
//! [`FluidGasFrom::LineWithoutTransition`] saying why.

use super::Observables;
use super::classify::{Classification, FluidGasFrom, Phase, Thresholds, classify, classify_with};
use super::criterion::sig;
use super::noise::{erfc, normal_cdf};
use serde::{Deserialize, Serialize};

/// Family-wise level of the jump test (after the Bonferroni correction over positions).
pub(crate) const JUMP_LEVEL: f64 = 0.01;
/// Level at which the inflection test rejects a power law for the whole line.
pub(crate) const INFLECTION_LEVEL: f64 = 0.01;
/// Family-wise level (Bonferroni over the slopes) at which the steepest slope must be steeper
/// than the flattest on each side.
pub(crate) const SLOPE_LEVEL: f64 = 0.05;
/// Floor on the relative error of a point's `T_g / E_cb` (a block error of zero would make any
/// wiggle significant).
pub const MIN_REL_ERROR: f64 = 1e-3;
/// Fewest points of a curve for either test.
pub(crate) const MIN_CURVE_POINTS: usize = 4;
/// Fewest interior residuals for the scatter estimate where no errors are stored.
pub(crate) const MIN_SCATTER_RESIDUALS: usize = 3;

/// One point of a line: `E*`, `T_g / E_cb` and the relative standard error of `T_g / E_cb`
/// (`None` where the run stored none).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinePoint {
    pub e_star: f64,
    pub t: f64,
    pub rel_error: Option<f64>,
}

impl LinePoint {
    /// A point without a stored error.
    pub fn new(e_star: f64, t: f64) -> Self {
        Self {
            e_star,
            t,
            rel_error: None,
        }
    }
}

/// The curve of a line in log-log: distinct `E*` in increasing order, replicas merged.
#[derive(Debug, Clone, PartialEq)]
pub struct Curve {
    /// `ln E*`.
    pub x: Vec<f64>,
    /// `ln(T_g / E_cb)`, the mean over replicas.
    pub y: Vec<f64>,
    /// Standard error of each `y`.
    pub sigma: Vec<f64>,
    /// Where the errors came from, in words.
    pub errors: String,
}

/// The relative standard error of a result's `T_g / E_cb`: the block test of the temperature in
/// its trend (`None` for observables without one).
pub fn temperature_rel_error(obs: &Observables) -> Option<f64> {
    let t = obs
        .trend
        .as_ref()?
        .tests
        .iter()
        .find(|t| t.quantity == super::trend::TEMPERATURE)?;
    let r = t.standard_error / t.mean.abs();
    (r.is_finite() && r >= 0.0).then_some(r)
}

/// Robust standard deviation of the scatter of `y` about a smooth curve: for each interior
/// point the residual from the straight line through its two neighbours, divided by its
/// standard deviation in units of the points' (`sqrt(1 + w^2 + (1 - w)^2)`, `w` the
/// interpolation weight), then `1.4826` times the median absolute value. `None` with fewer than
/// [`MIN_SCATTER_RESIDUALS`] residuals.
pub(crate) fn scatter_estimate(x: &[f64], y: &[f64]) -> Option<f64> {
    let mut r: Vec<f64> = (1..x.len().saturating_sub(1))
        .map(|i| {
            let w = (x[i] - x[i - 1]) / (x[i + 1] - x[i - 1]);
            let line = y[i - 1] + w * (y[i + 1] - y[i - 1]);
            ((y[i] - line) / (1.0 + w * w + (1.0 - w) * (1.0 - w)).sqrt()).abs()
        })
        .collect();
    if r.len() < MIN_SCATTER_RESIDUALS {
        return None;
    }
    r.sort_by(f64::total_cmp);
    let m = r.len();
    let median = if m % 2 == 1 {
        r[m / 2]
    } else {
        0.5 * (r[m / 2 - 1] + r[m / 2])
    };
    Some(1.4826 * median)
}

/// The curve of a line from its points in any order (positive finite values only). `Err` says
/// why there is none (too few points, or no errors and too few points to estimate them).
pub fn curve(points: &[LinePoint]) -> Result<Curve, String> {
    let mut p: Vec<LinePoint> = points
        .iter()
        .copied()
        .filter(|p| p.e_star > 0.0 && p.t > 0.0 && p.e_star.is_finite() && p.t.is_finite())
        .collect();
    p.sort_by(|a, b| a.e_star.total_cmp(&b.e_star));
    // Per distinct E*: x, mean y, the block error of the mean (if every replica has one), the
    // replicas' spread error (if several), the number of replicas.
    type Group = (f64, f64, Option<f64>, Option<f64>, usize);
    let mut groups: Vec<Group> = Vec::new();
    for g in p.chunk_by(|a, b| a.e_star == b.e_star) {
        let n = g.len() as f64;
        let ys: Vec<f64> = g.iter().map(|q| q.t.ln()).collect();
        let mean = ys.iter().sum::<f64>() / n;
        let block = g
            .iter()
            .map(|q| q.rel_error.map(|e| e * e))
            .sum::<Option<f64>>()
            .map(|s| s.sqrt() / n);
        let spread = (g.len() > 1).then(|| {
            let var = ys.iter().map(|y| (y - mean) * (y - mean)).sum::<f64>() / (n - 1.0);
            (var / n).sqrt()
        });
        groups.push((g[0].e_star.ln(), mean, block, spread, g.len()));
    }
    if groups.len() < MIN_CURVE_POINTS {
        return Err(format!(
            "{} homogeneous mobile point(s) on the line, fewer than {MIN_CURVE_POINTS}",
            groups.len()
        ));
    }
    let x: Vec<f64> = groups.iter().map(|g| g.0).collect();
    let y: Vec<f64> = groups.iter().map(|g| g.1).collect();
    let missing = groups.iter().filter(|g| g.2.is_none()).count();
    let scatter = if missing > 0 {
        Some(scatter_estimate(&x, &y).ok_or_else(|| {
            format!(
                "no errors stored for {missing} point(s) and too few points ({}) to estimate \
                 the line's scatter",
                x.len()
            )
        })?)
    } else {
        None
    };
    let sigma: Vec<f64> = groups
        .iter()
        .map(|&(_, _, block, spread, n)| {
            let stored = block.or_else(|| scatter.map(|s| s / (n as f64).sqrt()));
            stored
                .into_iter()
                .chain(spread)
                .fold(MIN_REL_ERROR, f64::max)
        })
        .collect();
    let errors = match (missing, scatter) {
        (0, _) => "errors: each run's block error, or the spread of its replicas".to_string(),
        (m, Some(s)) => format!(
            "no block errors stored for {m} of {} point(s): their error {s:.3} in ln(T_g/E_cb) \
             estimated from the line's scatter",
            x.len()
        ),
        (_, None) => unreachable!("missing errors have an estimate"),
    };
    Ok(Curve {
        x,
        y,
        sigma,
        errors,
    })
}

/// Weighted least squares of `y` on the columns `cols` (weights `1 / sigma^2`): the
/// coefficients, their covariance matrix and the chi-square. `None` if the columns are
/// degenerate.
fn wls(cols: &[Vec<f64>], y: &[f64], sigma: &[f64]) -> Option<(Vec<f64>, Vec<Vec<f64>>, f64)> {
    let p = cols.len();
    // [normal matrix | identity | right-hand side], reduced by Gauss-Jordan.
    let mut a = vec![vec![0.0; 2 * p + 1]; p];
    for i in 0..y.len() {
        let w = 1.0 / (sigma[i] * sigma[i]);
        for r in 0..p {
            for c in 0..p {
                a[r][c] += w * cols[r][i] * cols[c][i];
            }
            a[r][2 * p] += w * cols[r][i] * y[i];
        }
    }
    let scale: f64 = (0..p).map(|r| a[r][r]).fold(0.0, f64::max);
    for (r, row) in a.iter_mut().enumerate() {
        row[p + r] = 1.0;
    }
    for c in 0..p {
        let piv = (c..p).max_by(|&i, &j| a[i][c].abs().total_cmp(&a[j][c].abs()))?;
        if a[piv][c].abs() <= 1e-12 * scale {
            return None;
        }
        a.swap(c, piv);
        let d = a[c][c];
        a[c].iter_mut().for_each(|v| *v /= d);
        for r in 0..p {
            if r != c {
                let f = a[r][c];
                let pivot_row = a[c].clone();
                a[r].iter_mut()
                    .zip(&pivot_row)
                    .for_each(|(v, pv)| *v -= f * pv);
            }
        }
    }
    let beta: Vec<f64> = (0..p).map(|r| a[r][2 * p]).collect();
    let cov: Vec<Vec<f64>> = (0..p).map(|r| a[r][p..2 * p].to_vec()).collect();
    let chi2 = (0..y.len())
        .map(|i| {
            let f: f64 = (0..p).map(|r| beta[r] * cols[r][i]).sum();
            ((y[i] - f) / sigma[i]).powi(2)
        })
        .sum();
    Some((beta, cov, chi2))
}

/// `P(chi^2_nu > c)`, exact for integer `nu >= 1` (the regularised upper incomplete gamma
/// function at half-integer order, by its finite series).
pub(crate) fn chi2_sf(c: f64, nu: usize) -> f64 {
    let h = 0.5 * c.max(0.0);
    if nu.is_multiple_of(2) {
        let (mut term, mut sum) = (1.0, 1.0);
        for k in 1..nu / 2 {
            term *= h / k as f64;
            sum += term;
        }
        (-h).exp() * sum
    } else {
        let mut sum = erfc(h.sqrt());
        // h^(k + 1/2) / Gamma(k + 3/2), from k = 0: Gamma(3/2) = sqrt(pi) / 2.
        let mut term = h.sqrt() / (0.5 * std::f64::consts::PI.sqrt());
        for k in 0..(nu - 1) / 2 {
            sum += (-h).exp() * term;
            term *= h / (k as f64 + 1.5);
        }
        sum.min(1.0)
    }
}

/// The fluid-gas jump of an elastic line ([`fluid_gas_jump`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Jump {
    /// The boundary: the geometric mean of the bracketing `E*`.
    pub e_star: f64,
    /// `T_g / E_cb` ratio across the jump (raw, between the bracketing points).
    pub ratio: f64,
    pub bracket: (f64, f64),
    /// The step between the two fitted branches at the middle of the gap, in
    /// `ln(T_g / E_cb)`.
    pub step: f64,
    /// The step in units of its standard error.
    pub z: f64,
    /// Its p-value, Bonferroni-corrected for the positions tried.
    pub p_value: f64,
    /// Where the errors came from ([`Curve::errors`]).
    pub errors: String,
    /// Midway between the two fitted branches: `ln(T_g / E_cb) = level.0 + level.1 ln E*`.
    pub level: (f64, f64),
    /// `T_g / E_cb` of the point just above the jump.
    pub(crate) upper_t: f64,
}

impl Jump {
    /// `T_g / E_cb` at which a point at `e_star` is on the gas branch: closer to the upper
    /// branch than to the lower one, or at least as hot as the point just above the jump
    /// (where the two fitted branches, extended far, would cross).
    pub fn gas_temperature(&self, e_star: f64) -> f64 {
        (self.level.0 + self.level.1 * e_star.ln())
            .exp()
            .min(self.upper_t)
    }
}

/// The fluid-gas jump along a line (elastic grains), from its points in any order; `Err` says
/// why the line shows none. See the module doc for the test.
pub fn fluid_gas_jump(points: &[LinePoint], min_ratio: f64) -> Result<Jump, String> {
    let c = curve(points)?;
    let n = c.x.len();
    let positions = n - 3;
    // (k, z, step, level) of the position with the largest z.
    let mut best: Option<(usize, f64, f64, (f64, f64))> = None;
    for k in 1..=positions {
        let Some(b) = branches(&c, k) else { continue };
        if best.as_ref().is_none_or(|x| b.0 > x.1) {
            best = Some((k, b.0, b.1, b.2));
        }
    }
    let (k, z, step, level) = best.ok_or("degenerate line (no power law fits a side)")?;
    let p_value = (positions as f64 * (1.0 - normal_cdf(z))).min(1.0);
    let (lo, hi) = (c.x[k].exp(), c.x[k + 1].exp());
    let ratio = (c.y[k + 1] - c.y[k]).exp();
    let errors = &c.errors;
    if p_value >= JUMP_LEVEL {
        return Err(format!(
            "no step stands out of the scatter: the best, between E* = {lo:.3} and {hi:.3}, is \
             {step:.3} in ln(T_g/E_cb) at {z:.2} standard errors, p = {p_value:.3} (Bonferroni \
             over {positions} position(s)) >= {JUMP_LEVEL}; {errors}"
        ));
    }
    if ratio < min_ratio {
        return Err(format!(
            "the significant step between E* = {lo:.3} and {hi:.3} has a ratio {ratio:.2} < \
             line_jump_ratio = {min_ratio}; {errors}"
        ));
    }
    Ok(Jump {
        e_star: (lo * hi).sqrt(),
        ratio,
        bracket: (lo, hi),
        step,
        z,
        p_value,
        level,
        upper_t: c.y[k + 1].exp(),
        errors: c.errors.clone(),
    })
}

/// The two branches of a line cut between points `k` and `k + 1`: a power law fitted to each
/// side, both extended to the middle of the gap. Returns the step there in units of its
/// standard error (errors widened by `s^2 = max(1, chi^2 / (n - 4))` of the two fits), the
/// step, and the gas-branch level (the mean of the two branches, `(a, b)` of `a + b ln E*`).
fn branches(c: &Curve, k: usize) -> Option<(f64, f64, (f64, f64))> {
    let n = c.x.len();
    let xm = 0.5 * (c.x[k] + c.x[k + 1]);
    let fit = |r: std::ops::Range<usize>| {
        let ones = vec![1.0; r.len()];
        let x: Vec<f64> = c.x[r.clone()].iter().map(|x| x - xm).collect();
        wls(&[ones, x], &c.y[r.clone()], &c.sigma[r])
    };
    let (lo, cov_lo, chi_lo) = fit(0..k + 1)?;
    let (hi, cov_hi, chi_hi) = fit(k + 1..n)?;
    let s2 = if n > 4 {
        ((chi_lo + chi_hi) / (n - 4) as f64).max(1.0)
    } else {
        1.0
    };
    // At the gap's middle (x - xm = 0) each branch is its intercept.
    let step = hi[0] - lo[0];
    let se = ((cov_lo[0][0] + cov_hi[0][0]) * s2).sqrt();
    let level = (
        0.5 * (lo[0] + hi[0]) - 0.5 * (lo[1] + hi[1]) * xm,
        0.5 * (lo[1] + hi[1]),
    );
    Some((step / se, step, level))
}

/// The result of [`fluid_gas_inflection`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Inflection {
    /// `E*` of the inflection point.
    pub e_star: f64,
    /// The largest log-log slope `d ln(T_g/E_cb) / d ln E*` found.
    pub max_slope: f64,
    /// `E*` of the two sampled points that bracket it.
    pub bracket: (f64, f64),
    /// `T_g / E_cb` interpolated (log-log) at the inflection: the gas branch begins there.
    pub t_star: f64,
    /// p-value of the power law's chi-square.
    pub(crate) p_line: f64,
    /// p-value of the steepest slope against the flattest on its less steep side
    /// (Bonferroni-corrected over the slopes).
    pub p_value: f64,
    /// Where the errors came from ([`Curve::errors`]).
    pub errors: String,
}

/// The inflection point of `T_g / E_cb` against `E*` along one line of constant Gamma (inelastic
/// grains), from its points in any order; `Err` says why the line shows none. See the module
/// doc for the test.
pub fn fluid_gas_inflection(points: &[LinePoint]) -> Result<Inflection, String> {
    let c = curve(points)?;
    let n = c.x.len();
    let errors = &c.errors;
    let ones = vec![1.0; n];
    let (_, _, chi) = wls(&[ones, c.x.clone()], &c.y, &c.sigma)
        .ok_or("degenerate line (a power law cannot be fitted)")?;
    let p_line = chi2_sf(chi, n - 2);
    if p_line >= INFLECTION_LEVEL {
        return Err(format!(
            "a power law fits the line (chi^2 = {chi:.1} on {} degrees of freedom, p = \
             {p_line:.3} >= {INFLECTION_LEVEL}); {errors}",
            n - 2
        ));
    }
    let (k, z_left, z_right) = slope_contrast(&c).ok_or_else(|| {
        format!("the steepest sampled slope lies at an end of the line; {errors}")
    })?;
    let m = (n - 1) as f64;
    let p_value = (m * (1.0 - normal_cdf(z_left.min(z_right)))).min(1.0);
    if p_value >= SLOPE_LEVEL {
        return Err(format!(
            "the steepest slope (between E* = {:.3} and {:.3}) is not significantly steeper than \
             the flattest on both sides ({z_left:.2} and {z_right:.2} standard errors, p = \
             {p_value:.3} >= {SLOPE_LEVEL}, Bonferroni over {m} slopes); {errors}",
            c.x[k].exp(),
            c.x[k + 1].exp()
        ));
    }
    let (e_star, max_slope, kb) = steepest(&c.x, &c.y, k);
    let xi = e_star.ln();
    let w = ((xi - c.x[kb]) / (c.x[kb + 1] - c.x[kb])).clamp(0.0, 1.0);
    let t_star = (c.y[kb] + w * (c.y[kb + 1] - c.y[kb])).exp();
    Ok(Inflection {
        e_star,
        max_slope,
        bracket: (c.x[kb].exp(), c.x[kb + 1].exp()),
        t_star,
        p_line,
        p_value,
        errors: c.errors.clone(),
    })
}

/// The slopes of consecutive points of the curve: the index `k` of the steepest (between points
/// `k` and `k + 1`), and by how many standard errors it is steeper than the flattest slope on
/// its left and on its right (neighbouring slopes share a point: their covariance counts).
/// `None` when the steepest slope is at an end.
fn slope_contrast(c: &Curve) -> Option<(usize, f64, f64)> {
    let m = c.x.len() - 1;
    let dx: Vec<f64> = (0..m).map(|j| c.x[j + 1] - c.x[j]).collect();
    let s: Vec<f64> = (0..m).map(|j| (c.y[j + 1] - c.y[j]) / dx[j]).collect();
    let var = |j: usize| (c.sigma[j].powi(2) + c.sigma[j + 1].powi(2)) / (dx[j] * dx[j]);
    let cov = |i: usize, j: usize| {
        let (a, b) = (i.min(j), i.max(j));
        if b == a + 1 {
            -c.sigma[b].powi(2) / (dx[a] * dx[b])
        } else {
            0.0
        }
    };
    let k = (0..m).max_by(|&a, &b| s[a].total_cmp(&s[b]))?;
    if k == 0 || k == m - 1 {
        return None;
    }
    let flattest = |r: std::ops::Range<usize>| r.min_by(|&a, &b| s[a].total_cmp(&s[b]));
    let z = |j: usize| (s[k] - s[j]) / (var(k) + var(j) - 2.0 * cov(k, j)).sqrt();
    Some((k, z(flattest(0..k)?), z(flattest(k + 1..m)?)))
}

/// The steepest slope of the log-log points `(x, y)` (sorted, distinct x): `(E*, slope, kb)` of
/// the vertex of the parabola through the largest midpoint slope (between points `k` and
/// `k + 1`, not at an end: [`slope_contrast`]) and its two neighbours, bracketed by the points
/// `kb` and `kb + 1`.
fn steepest(x: &[f64], y: &[f64], k: usize) -> (f64, f64, usize) {
    let mid = |i: usize| {
        (
            0.5 * (x[i] + x[i + 1]),
            (y[i + 1] - y[i]) / (x[i + 1] - x[i]),
        )
    };
    let (x0, y0) = mid(k - 1);
    let (x1, y1) = mid(k);
    let (x2, y2) = mid(k + 1);
    // Vertex of the parabola through three points (divided differences).
    let d01 = (y1 - y0) / (x1 - x0);
    let d12 = (y2 - y1) / (x2 - x1);
    let a = (d12 - d01) / (x2 - x0);
    let v = if a < 0.0 {
        (0.5 * (x0 + x1) - d01 / (2.0 * a)).clamp(x0, x2)
    } else {
        x1
    };
    // The bracket of the vertex among the sampled points.
    let kb = (k.saturating_sub(1)..=k + 1)
        .find(|&i| x[i] <= v && v <= x[i + 1])
        .unwrap_or(k);
    (v.exp(), y1, kb)
}

/// How a line decides fluid versus gas for its homogeneous points.
enum Decision {
    Jump(Jump),
    Inflection(Inflection),
    /// No transition on the curve; the coexistences `(E* range, T range)` mark it.
    Coexistence {
        e: (f64, f64),
        t: (f64, f64),
        boundary: f64,
        why: String,
    },
    None(String),
}

/// Classifies the points `(E*, observables)` of one line of constant `gamma`: each point by
/// [`classify`], then fluid versus gas of every homogeneous point by the line (module doc).
/// Solid points and coexistences keep their per-point labels (the regions of a coexistence are
/// told apart by their own temperatures, `classify` rule 3).
pub fn classify_line(
    gamma: f64,
    points: &[(f64, &Observables)],
    th: &Thresholds,
    elastic: bool,
) -> Vec<Classification> {
    let first: Vec<Classification> = points.iter().map(|(_, o)| classify(o, th)).collect();
    let on_curve = |c: &Classification| !c.decided_on.split && c.decided_on.whole.phase != Phase::S;
    let curve_points: Vec<LinePoint> = points
        .iter()
        .zip(&first)
        .filter(|(_, c)| on_curve(c))
        .map(|((e, o), _)| LinePoint {
            e_star: *e,
            t: o.granular_temperature_reduced,
            rel_error: temperature_rel_error(o),
        })
        .collect();
    let method = if elastic { "jump" } else { "inflection" };
    let found = if elastic {
        fluid_gas_jump(&curve_points, th.line_jump_ratio).map(Decision::Jump)
    } else {
        fluid_gas_inflection(&curve_points).map(Decision::Inflection)
    };
    let decision = found.unwrap_or_else(|why| by_coexistences(points, &first, &curve_points, why));
    points
        .iter()
        .zip(&first)
        .map(|(&(e, o), c0)| {
            let t = o.granular_temperature_reduced;
            let (gas, from, note) = decide(&decision, gamma, method, e, t, th);
            let mut c = classify_with(o, th, &|_| gas, from);
            let note = if on_curve(c0) {
                note
            } else if c0.decided_on.split {
                "a coexistence: kept out of the line's curve, its regions decided by their own \
                 temperatures (rule 3)"
                    .to_string()
            } else {
                "solid: kept out of the line's curve".to_string()
            };
            c.decided_on.reason = format!(
                "{}; line at Gamma = {}: {note}",
                c.decided_on.reason,
                sig(gamma)
            );
            c
        })
        .collect()
}

/// Where the curve shows no transition: the line's fluid-gas coexistences mark it, if it has
/// any (module doc); else [`Decision::None`].
fn by_coexistences(
    points: &[(f64, &Observables)],
    first: &[Classification],
    curve: &[LinePoint],
    why: String,
) -> Decision {
    let fgc: Vec<(f64, f64)> = points
        .iter()
        .zip(first)
        .filter(|(_, c)| c.phase == Phase::Fgc)
        .map(|((e, o), _)| (*e, o.granular_temperature_reduced))
        .collect();
    if fgc.is_empty() {
        return Decision::None(why);
    }
    let e = fgc.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |a, p| {
        (a.0.min(p.0), a.1.max(p.0))
    });
    let t = fgc.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |a, p| {
        (a.0.min(p.1), a.1.max(p.1))
    });
    let below = curve
        .iter()
        .map(|p| p.e_star)
        .filter(|&x| x < e.0)
        .fold(f64::NAN, f64::max);
    let boundary = if below.is_nan() {
        e.0
    } else {
        (below * e.0).sqrt()
    };
    Decision::Coexistence {
        e,
        t,
        boundary,
        why,
    }
}

/// Fluid versus gas of a homogeneous point at `(E*, T)` by the line's decision: whether it is
/// gas, the record of how, and the words.
fn decide(
    d: &Decision,
    gamma: f64,
    method: &str,
    e: f64,
    t: f64,
    th: &Thresholds,
) -> (bool, FluidGasFrom, String) {
    let line = |m: &str, b: f64| FluidGasFrom::Line {
        gamma,
        method: m.to_string(),
        e_star_boundary: b,
    };
    let fallback = t > th.gas_temperature;
    let per_point = format!(
        "per-point fallback: T_g/E_cb = {} {} gas_temperature = {}",
        sig(t),
        super::classify::above(t, th.gas_temperature),
        sig(th.gas_temperature)
    );
    let branch = |b: f64, level: f64, what: &str| -> (bool, String) {
        let (es, bs, ts, ls) = (sig(e), sig(b), sig(t), sig(level));
        if e <= b {
            (
                false,
                format!("E* = {es} below the {what} boundary E* = {bs}: fluid side"),
            )
        } else if t >= level {
            (
                true,
                format!(
                    "E* = {es} above the {what} boundary E* = {bs} and T_g/E_cb = {ts} on the \
                     gas branch (>= {ls})"
                ),
            )
        } else {
            (
                false,
                format!(
                    "E* = {es} above the {what} boundary E* = {bs}, but T_g/E_cb = {ts} below \
                     the gas branch ({ls}): stays fluid"
                ),
            )
        }
    };
    match d {
        Decision::Jump(j) => {
            let (gas, note) = branch(j.e_star, j.gas_temperature(e), "jump");
            let note = format!(
                "{note}; the jump: ratio {:.2} between E* = {} and {}, p = {:.2e}; {}",
                j.ratio,
                sig(j.bracket.0),
                sig(j.bracket.1),
                j.p_value,
                j.errors
            );
            (gas, line("jump", j.e_star), note)
        }
        Decision::Inflection(i) => {
            let (gas, note) = branch(i.e_star, i.t_star, "inflection");
            let note = format!(
                "{note}; the inflection: between E* = {} and {}, power law p = {:.2e}, slopes p = \
                 {:.2e}; {}",
                sig(i.bracket.0),
                sig(i.bracket.1),
                i.p_line,
                i.p_value,
                i.errors
            );
            (gas, line("inflection", i.e_star), note)
        }
        Decision::Coexistence {
            e: (lo, hi),
            t: (tlo, thi),
            boundary,
            why,
        } => {
            let (gas, note) = if e < *lo && t <= *tlo {
                (
                    false,
                    format!(
                        "below the line's fluid-gas coexistences (E* >= {}) and colder than \
                         all of them (T_g/E_cb >= {}): fluid",
                        sig(*lo),
                        sig(*tlo)
                    ),
                )
            } else if e > *hi && t >= *thi {
                (
                    true,
                    format!(
                        "above the line's fluid-gas coexistences (E* <= {}) and hotter than \
                         all of them (T_g/E_cb <= {}): gas",
                        sig(*hi),
                        sig(*thi)
                    ),
                )
            } else {
                (
                    fallback,
                    format!(
                        "not outside the line's fluid-gas coexistences in both E* and T_g: \
                         {per_point}"
                    ),
                )
            };
            let note = format!("no transition on the curve ({why}); {note}");
            (gas, line("coexistence", *boundary), note)
        }
        Decision::None(why) => (
            fallback,
            FluidGasFrom::LineWithoutTransition {
                gamma,
                method: method.to_string(),
                reason: why.clone(),
            },
            format!("no transition ({why}); {per_point}"),
        ),
    }
}
