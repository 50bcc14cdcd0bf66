//! What a run's monitored series did (docs/observables.md "Run to stationarity"): where the start
//! had relaxed, whether what followed is stationary, and if not, which way it went.
//!
//! The input is the whole sampled history of the monitored quantities (`T_g / E_cb`, bridges per
//! grain, `Delta n_cb`, Eq. 3.2-3.3), not one window, so that a drift too slow to show inside any
//! single window still shows over the run.
//!
//! - **Relaxation** (the end of the transient): the Marginal Standard Error Rule (MSER, White,
//!   Simulation 69, 323 (1997)) on batch means `y_i` of each quantity picks the truncation
//!   `d* = argmin_d sum_(i >= d) (y_i - ybar_d)^2 / (n - d)^2`, the start that minimises the
//!   squared standard error of the mean of what is kept. A start still relaxing (or a series
//!   that never stops drifting) puts `d*` in the second half of the history: the history is then
//!   "not relaxed". The relaxation time is the latest `d*` over the quantities.
//! - **Tests**: the history from the relaxation time on (or from the reported window's start,
//!   where that is earlier: a transient tail inside the window must then pass the tests too) is
//!   cut into blocks and tested with
//!   [`block_test`] (every pair of block means agrees, and the least-squares drift over the
//!   history lies within its error plus the tolerance). The tolerance is relative to the history,
//!   not to one window: a drift of 2 % per window over five windows is a 10 % drift here.
//! - **State**: `stationary` when the history relaxed and every test passed; otherwise `coarsening` when `Delta n_cb` rises beyond its errors (drops grow),
//!   else `heating` / `cooling` when `T_g` rises / falls beyond its errors, else `undecided`
//!   (no monotone trend, yet not stationary: steps, or a history too short to tell).
//!
//! The state describes the whole system. Whether a label is settled is decided region by region
//! from the same tests and the regions' own quantities ([`assess_regions`],
//! `observe::settling`).

use super::convergence::{BlockTest, block_test};
use serde::{Deserialize, Serialize};
use std::fmt;

/// Batch means the MSER search works on (at most): long series are averaged into this many
/// batches first, which keeps the search linear and smooths sample-to-sample noise.
pub(crate) const MSER_BATCHES: usize = 200;

/// What the monitored series did over the run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum TrendState {
    /// Relaxed before the window and no drift or step beyond the errors since.
    Stationary,
    /// `T_g` keeps rising.
    Heating,
    /// `T_g` keeps falling.
    Cooling,
    /// `Delta n_cb` keeps rising: the dense drops grow.
    Coarsening,
    /// Not stationary, with no monotone trend to name (steps, or too short a history).
    Undecided,
}

impl TrendState {
    /// Every state, in storage order.
    pub const ALL: [TrendState; 5] = [
        TrendState::Stationary,
        TrendState::Heating,
        TrendState::Cooling,
        TrendState::Coarsening,
        TrendState::Undecided,
    ];

    /// The stored name.
    pub fn name(self) -> &'static str {
        match self {
            TrendState::Stationary => "stationary",
            TrendState::Heating => "heating",
            TrendState::Cooling => "cooling",
            TrendState::Coarsening => "coarsening",
            TrendState::Undecided => "undecided",
        }
    }

    /// Parses a stored name.
    pub fn parse(s: &str) -> Option<TrendState> {
        Self::ALL.into_iter().find(|t| t.name() == s)
    }
}

impl fmt::Display for TrendState {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// The trend of a run, stored with its result: what its history did and, for a run under a
/// `[convergence]` policy, how the policy ended it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Trend {
    pub state: TrendState,
    /// The end of the transient found by MSER (the latest over the sampled quantities).
    pub relaxed_at: f64,
    /// Whether the sampled history had relaxed (every quantity's truncation in the first half).
    pub relaxed: bool,
    /// The history the tests of the sampled quantities cover, `[from, to]`.
    pub from: f64,
    pub to: f64,
    /// The tests over that history, one per sampled quantity (drift = change from the first
    /// to the last block, with its error).
    pub tests: Vec<BlockTest>,
    /// The tests of the regions' quantities (`observe::settling`), each over its own history
    /// of per-period blocks (empty in results stored before they existed).
    #[serde(default)]
    pub region_tests: Vec<BlockTest>,
    /// The quantities, sampled or per block, whose history had not relaxed.
    #[serde(default)]
    pub unrelaxed: Vec<String>,
    /// How the run policy ended the run (`None`: a fixed-length run, or a result stored before
    /// it was recorded).
    #[serde(default)]
    pub policy: Option<PolicyEnd>,
}

impl Trend {
    /// Every test, the sampled quantities' first.
    pub fn all_tests(&self) -> impl Iterator<Item = &BlockTest> {
        self.tests.iter().chain(&self.region_tests)
    }
}

/// Why and when a run under a `[convergence]` policy ended.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PolicyEnd {
    pub ending: Ending,
    /// Checks made (1 = no extension).
    pub checks: usize,
    /// Time of the first check (the minimum run).
    pub first_check: f64,
    /// Longest run the policy allowed.
    pub cap: f64,
}

/// Why a run with a `[convergence]` policy ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Ending {
    /// Its label's verdict was stationary (`observe::settling::Verdict`).
    Stationary,
    /// Its label was kept (every region settled, some quantity still moving in a direction
    /// that cannot change it) at two checks in a row with the same label.
    Settled,
    /// The next window would have passed the cap before the label settled.
    Cap,
}

/// The parameters of the tests (the scene's `[convergence]` section, or its defaults).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct TrendTest {
    pub blocks: usize,
    pub sigmas: f64,
    pub rel_tolerance: f64,
}

/// One monitored quantity's history: its name, its floor for the tolerance, its values.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Monitored<'a> {
    pub name: &'a str,
    pub floor: f64,
    pub values: &'a [f64],
}

/// The MSER truncation of `x`: the index of the first kept sample and whether the series
/// relaxed. The search runs over the first half of the batches only (near the end a few batch
/// means can agree by chance and give a spuriously small statistic); a minimum in the last fifth
/// of that range (after 40 % of the series) means the statistic was still falling near mid-run:
/// the series has not relaxed. (Right at mid-run the statistic of a steady rise is flat to within
/// its noise, so the minimum wanders a few batches below the end of the range.)
/// Series too short to batch give `(0, false)`.
pub(crate) fn mser_truncation(x: &[f64]) -> (usize, bool) {
    let n = x.len();
    if n < 8 {
        return (0, false);
    }
    let per = n.div_ceil(MSER_BATCHES);
    let y: Vec<f64> = x
        .chunks(per)
        .map(|c| c.iter().sum::<f64>() / c.len() as f64)
        .collect();
    let nb = y.len();
    let half = nb / 2;
    // Suffix sums of y and y^2 give each d's statistic in O(1).
    let (mut s1, mut s2) = (0.0, 0.0);
    let mut best = (f64::INFINITY, 0usize);
    for d in (0..nb).rev() {
        s1 += y[d];
        s2 += y[d] * y[d];
        if d > half {
            continue;
        }
        let k = (nb - d) as f64;
        let ss = (s2 - s1 * s1 / k).max(0.0);
        let stat = ss / (k * k);
        // `<=` keeps the earliest start among equal values (a constant series keeps everything).
        if stat <= best.0 {
            best = (stat, d);
        }
    }
    let d = best.1;
    ((d * per).min(n), 5 * d < 4 * half)
}

/// Assesses a run's history: `time` the sample times, `quantities` the monitored series on
/// those times, `window_start` the start of the reported window (the tests cover it whole). Samples before `t_floor` (the shortest transient the
/// scene allows) are not looked at.
pub(crate) fn assess(
    time: &[f64],
    quantities: &[Monitored<'_>],
    t_floor: f64,
    window_start: f64,
    test: TrendTest,
) -> Trend {
    let eps = 1e-9 * time.last().map_or(1.0, |t| t.abs().max(1.0));
    let first = time.partition_point(|&t| t < t_floor - eps);
    let n = time.len() - first;
    // The truncation over all quantities, and whether every one relaxed. A quantity whose two
    // halves agree within the tolerance counts as relaxed from the start whatever MSER says:
    // MSER has no scale, and a solid's T_g creeping from 0.0019 to 0.0012 E_cb is a trend to
    // it, but not one that changes anything.
    let (mut cut, mut relaxed) = (0usize, true);
    let mut unrelaxed = Vec::new();
    for q in quantities {
        let x = &q.values[first..];
        let (d, ok) = mser_truncation(x);
        if !ok && halves_agree_within_tolerance(x, test.rel_tolerance, q.floor) {
            continue;
        }
        cut = cut.max(d);
        relaxed &= ok;
        if !ok {
            unrelaxed.push(q.name.to_string());
        }
    }
    // A relaxed history is tested from its relaxation on, or from the window's start where
    // that is earlier: a transient tail inside the window then fails the tests if it matters,
    // and passes if MSER's cut was noise. An unrelaxed history is tested over its second half:
    // the state names what the run is doing now, not what the start did.
    let in_window = time.partition_point(|&t| t < window_start - eps);
    let start = if relaxed {
        (first + cut).min(in_window.max(first))
    } else {
        first + cut.max(n / 2)
    };
    let tests: Vec<BlockTest> = quantities
        .iter()
        .map(|q| {
            block_test(
                q.name,
                &q.values[start..],
                test.blocks,
                test.sigmas,
                test.rel_tolerance,
                q.floor,
            )
        })
        .collect();
    let rising = |name: &str| {
        tests
            .iter()
            .find(|t| t.quantity == name)
            .filter(|t| !t.no_trend && t.block_means.len() >= 2)
            .map(|t| t.drift > 0.0)
    };
    let all_ok = !tests.is_empty() && tests.iter().all(BlockTest::ok);
    // A history MSER cannot cut in its first 40 % may still have relaxed by mid-run: where the
    // tested second half holds the whole window and passes every test, the transient ended
    // there.
    let late_relaxation = !relaxed && all_ok && in_window >= start;
    let relaxed = relaxed || late_relaxation;
    if late_relaxation {
        unrelaxed.clear();
    }
    let relaxed_at = time
        .get(if late_relaxation { start } else { first + cut })
        .copied()
        .unwrap_or(f64::NAN);
    // Where MSER puts the end of the transient inside the window, the window's part before it
    // must agree with what follows, or the window's averages still carry the start.
    let tail_ok = !relaxed || first + cut <= start || {
        let split = first + cut;
        quantities.iter().all(|q| {
            let (a, b) = (&q.values[start..split], &q.values[split..]);
            transient_tail_agrees(a, b, test, q.floor)
        })
    };
    let state = if relaxed && tail_ok && all_ok {
        TrendState::Stationary
    } else if rising(DELTA_N_CB) == Some(true) {
        TrendState::Coarsening
    } else {
        match rising(TEMPERATURE) {
            Some(true) => TrendState::Heating,
            Some(false) => TrendState::Cooling,
            None => TrendState::Undecided,
        }
    };
    Trend {
        state,
        relaxed_at,
        relaxed,
        from: time.get(start).copied().unwrap_or(f64::NAN),
        to: time.last().copied().unwrap_or(f64::NAN),
        tests,
        region_tests: Vec::new(),
        unrelaxed,
        policy: None,
    }
}

/// One region quantity over the blocks of the history: its name, its tolerance floor, the
/// blocks' mid times and values (blocks where it is undefined left out).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct BlockSeries {
    pub name: &'static str,
    pub floor: f64,
    pub time: Vec<f64>,
    pub values: Vec<f64>,
}

/// The tests of the regions' per-block quantities (`observe::settling::region_series`), each
/// assessed on its own history like the sampled ones ([`assess`]): its MSER cut, then the block
/// test from there (or from the window's start, where earlier). Returns the tests and the names
/// of the quantities whose history had not relaxed.
pub(crate) fn assess_regions(
    series: &[BlockSeries],
    t_floor: f64,
    window_start: f64,
    test: TrendTest,
) -> (Vec<BlockTest>, Vec<String>) {
    let mut tests = Vec::new();
    let mut unrelaxed = Vec::new();
    // A quantity with no value at all was not measured in this run (no grain in a cluster, or
    // a run shorter than the mobility lag): it is left out, not tested. One with a few values
    // is tested, and reads unknown where they cannot fill the blocks.
    for s in series.iter().filter(|s| !s.values.is_empty()) {
        let one = assess(
            &s.time,
            &[Monitored {
                name: s.name,
                floor: s.floor,
                values: &s.values,
            }],
            t_floor,
            window_start,
            test,
        );
        unrelaxed.extend(one.unrelaxed);
        tests.extend(one.tests);
    }
    (tests, unrelaxed)
}

/// Whether the means of the two halves of `x` differ by at most `rel_tolerance * max(|mean|,
/// floor)`.
fn halves_agree_within_tolerance(x: &[f64], rel_tolerance: f64, floor: f64) -> bool {
    if x.len() < 2 {
        return false;
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let (a, b) = x.split_at(x.len() / 2);
    (mean(a) - mean(b)).abs() <= rel_tolerance * mean(x).abs().max(floor)
}

/// Whether the samples `a` before MSER's cut agree with the samples `b` after it: `|mean a -
/// mean b| <= k sqrt(SE_a^2 + SE_b^2) + tol`, both errors from `b`'s blocking error (the
/// relaxed part's correlations) scaled by the sample counts.
fn transient_tail_agrees(a: &[f64], b: &[f64], test: TrendTest, floor: f64) -> bool {
    if a.is_empty() || b.len() < 2 {
        return true;
    }
    let mean = |x: &[f64]| x.iter().sum::<f64>() / x.len() as f64;
    let (ma, mb) = (mean(a), mean(b));
    let se_b = super::convergence::blocking_error(b).0;
    let se_a = se_b * (b.len() as f64 / a.len() as f64).sqrt();
    let tol = test.rel_tolerance * mb.abs().max(floor);
    (ma - mb).abs() <= test.sigmas * se_a.hypot(se_b) + tol
}

/// The name of the granular temperature among the monitored quantities.
pub const TEMPERATURE: &str = "temperature_reduced";
/// The name of the bridges per grain among the monitored quantities.
pub const BRIDGES: &str = "bridges_per_particle";
/// The name of the bridge-density contrast among the monitored quantities.
pub const DELTA_N_CB: &str = "delta_n_cb";
/// The name of a sheared scene's `E_par` among the monitored quantities.
pub const E_PAR: &str = "e_par";

#[cfg(test)]
mod tests {
    use super::*;
    use crate::observe::convergence::tests::ar1 as noise;

    const TEST: TrendTest = TrendTest {
        blocks: 4,
        sigmas: 3.0,
        rel_tolerance: 0.02,
    };

    /// Assesses a temperature series `t(i)` and a contrast series `d(i)` sampled at unit
    /// spacing, with the window starting at `window_start`.
    fn state_of(t: &[f64], d: &[f64], window_start: f64) -> Trend {
        let time: Vec<f64> = (0..t.len()).map(|i| i as f64).collect();
        let flat = vec![1.0; t.len()];
        assess(
            &time,
            &[
                Monitored {
                    name: TEMPERATURE,
                    floor: 0.01,
                    values: t,
                },
                Monitored {
                    name: BRIDGES,
                    floor: 0.01,
                    values: &flat,
                },
                Monitored {
                    name: DELTA_N_CB,
                    floor: 0.05,
                    values: d,
                },
            ],
            0.0,
            window_start,
            TEST,
        )
    }

    /// A series with mean `level`, noise of standard deviation `sd` (correlation time about 10
    /// samples).
    fn around(level: f64, sd: f64, n: usize, seed: u64) -> Vec<f64> {
        let phi: f64 = 0.9;
        let scale = sd * (1.0 - phi * phi).sqrt();
        noise(phi, n, seed)
            .into_iter()
            .map(|v| level + scale * v)
            .collect()
    }

    /// A hot start relaxing as `1 + 4 exp(-t / 300)` with 5 % noise over 6000 samples: the
    /// relaxation is over (below one noise sigma) by about `t = 300 ln(4 / 0.05) = 1300`.
    fn relaxing(seed: u64) -> Vec<f64> {
        around(0.0, 0.05, 6000, seed)
            .iter()
            .enumerate()
            .map(|(i, v)| 1.0 + 4.0 * (-(i as f64) / 300.0).exp() + v)
            .collect()
    }

    #[test]
    fn mser_finds_the_end_of_an_exponential_relaxation() {
        for seed in 0..10 {
            let (d, relaxed) = mser_truncation(&relaxing(seed));
            assert!(relaxed, "seed {seed}");
            assert!((600..=2000).contains(&d), "seed {seed}: truncation {d}");
        }
    }

    #[test]
    fn mser_keeps_a_stationary_series_and_rejects_a_steady_rise() {
        for seed in 0..20 {
            let x = around(1.0, 0.05, 4000, 100 + seed);
            let (d, relaxed) = mser_truncation(&x);
            assert!(relaxed && d < 2000, "seed {seed}: {d}");
            // A rise of 20 noise deviations: the statistic falls all the way to mid-run. (A
            // drift inside the noise is the trend test's to find, not MSER's.)
            let y: Vec<f64> = x
                .iter()
                .enumerate()
                .map(|(i, v)| v + 1.0 * i as f64 / 4000.0)
                .collect();
            assert!(!mser_truncation(&y).1, "seed {seed}: a rise relaxed");
        }
    }

    #[test]
    fn each_state_is_named_on_a_synthetic_history() {
        let n = 4000;
        let mut counts = std::collections::BTreeMap::<(&str, TrendState), usize>::new();
        for seed in 0..20 {
            let flat_t = around(0.5, 0.05, n, 200 + seed);
            let flat_d = around(0.2, 0.02, n, 300 + seed);
            let ramp = |x: &[f64], by: f64| -> Vec<f64> {
                x.iter()
                    .enumerate()
                    .map(|(i, v)| v * (1.0 + by * i as f64 / n as f64))
                    .collect()
            };
            let cases: [(&str, Vec<f64>, Vec<f64>); 4] = [
                ("stationary", flat_t.clone(), flat_d.clone()),
                // T_g doubles over the run (the elastic gas).
                ("heating", ramp(&flat_t, 1.0), flat_d.clone()),
                ("cooling", ramp(&flat_t, -0.5), flat_d.clone()),
                // The contrast grows by half, T_g flat.
                ("coarsening", flat_t.clone(), ramp(&flat_d, 0.5)),
            ];
            for (name, t, d) in cases {
                let s = state_of(&t, &d, 1000.0).state;
                *counts.entry((name, s)).or_default() += 1;
            }
        }
        let of = |name, s| counts.get(&(name, s)).copied().unwrap_or(0);
        // A trend of this size is named every time; a stationary history is called so at the
        // level of the block test (three sigmas on six pairs and a slope, 2 % tolerance).
        assert_eq!(of("heating", TrendState::Heating), 20, "{counts:?}");
        assert_eq!(of("cooling", TrendState::Cooling), 20, "{counts:?}");
        assert_eq!(of("coarsening", TrendState::Coarsening), 20, "{counts:?}");
        assert!(of("stationary", TrendState::Stationary) >= 18, "{counts:?}");
    }

    #[test]
    fn a_drift_slower_than_the_tolerance_per_window_is_caught_over_the_history() {
        // 1.5 % per window of 1000 samples, over 8 windows: each window alone passes the 2 %
        // tolerance, the history (12 %) does not.
        let n = 8000;
        let x: Vec<f64> = around(1.0, 0.01, n, 7)
            .iter()
            .enumerate()
            .map(|(i, v)| v * (1.0 + 0.015 * i as f64 / 1000.0))
            .collect();
        let last = &x[n - 1000..];
        let one_window = block_test(TEMPERATURE, last, 4, 3.0, 0.02, 0.01);
        assert!(one_window.ok(), "{one_window:?}");
        let d = vec![0.2; n];
        assert_eq!(
            state_of(&x, &d, (n - 1000) as f64).state,
            TrendState::Heating
        );
    }

    #[test]
    fn a_relaxation_reaching_into_the_window_is_not_stationary() {
        // Relaxed at about t = 1300; a window starting at 500 still holds the transient.
        let t = relaxing(11);
        let d = around(0.2, 0.02, 6000, 12);
        let early = state_of(&t, &d, 500.0);
        assert_ne!(early.state, TrendState::Stationary, "{early:?}");
        assert!(early.relaxed_at > 500.0);
        let late = state_of(&t, &d, 3000.0);
        assert_eq!(late.state, TrendState::Stationary, "{late:?}");
    }

    #[test]
    fn a_creep_below_the_tolerance_counts_as_relaxed() {
        // A solid's T_g: 0.0019 falling to 0.0012 (floor 0.01, 2 % tolerance: 2e-4), no noise.
        // MSER alone calls it unrelaxed; its halves differ by about 3e-4, so it is only relaxed
        // with a wider tolerance.
        let n = 2000;
        let t: Vec<f64> = (0..n)
            .map(|i| 0.0012 + 0.0007 * (-(i as f64) / 600.0).exp())
            .collect();
        assert!(!mser_truncation(&t).1);
        let d = vec![0.2; n];
        let strict = state_of(&t, &d, 0.0);
        assert!(!strict.relaxed, "{strict:?}");
        let time: Vec<f64> = (0..n).map(|i| i as f64).collect();
        let loose = assess(
            &time,
            &[Monitored {
                name: TEMPERATURE,
                floor: 0.05,
                values: &t,
            }],
            0.0,
            0.0,
            TEST,
        );
        assert!(loose.relaxed, "{loose:?}");
        assert_eq!(loose.state, TrendState::Stationary);
    }

    #[test]
    fn a_plateau_without_a_trend_is_undecided() {
        // Up for the middle half of the run and back down: no monotone drift, blocks disagree.
        let n = 4000;
        let t: Vec<f64> = around(0.5, 0.01, n, 21)
            .iter()
            .enumerate()
            .map(|(i, v)| {
                if (1000..3000).contains(&i) {
                    v + 0.3
                } else {
                    *v
                }
            })
            .collect();
        let d = around(0.2, 0.02, n, 22);
        assert_eq!(state_of(&t, &d, 0.0).state, TrendState::Undecided);
    }

    #[test]
    fn states_round_trip_their_names() {
        for s in TrendState::ALL {
            assert_eq!(TrendState::parse(s.name()), Some(s));
        }
        assert_eq!(TrendState::parse("boiling"), None);
    }
}
