//! Phase classification: maps [`Observables`] to one of s, f, g, sfc, sgc, fgc (docs/model.md 7)
//! with the thresholds of the scene's `[classify]` section, and records every number the
//! decision used so that a result can be re-classified later without re-simulating
//! (`wetgran reclassify`). docs/observables.md gives the reasoning and the evidence.
//!
//! The rule for one run (per point):
//! 1. A region is *solid* when it is not mobile: its lateral mobility `D_lat` over the long lag
//!    (`observe::lateral`) is at most `solid_diffusion`, or its mean-square displacement is
//!    caged: it grows like `tau^alpha` with `alpha < diffusive_exponent` between the short and
//!    the long lag while staying below [`CAGE_MSD`]. (`mobility = "location_changes"`: `f_lc`
//!    per period against `solid_flc`, a region hotter than `gas_temperature` counting as
//!    mobile; `mobility = "temperature"`, or where neither was observed: `T_g / E_cb` against
//!    `solid_temperature`.) A mobile region is *gas* when `T_g / E_cb > gas_temperature`, else
//!    *fluid*: this is the per-point fallback of the fluid-gas decision, which a sweep replaces
//!    by the line rule wherever the point lies on a line of constant Gamma.
//! 2. *Coexistence* needs a bonded dense part (at least `cluster_fraction` of the dense bins'
//!    grains are members of bonded clusters, `observe::clusters`) and a lateral profile that is
//!    significantly inhomogeneous: the profile (`n_cb` for wet scenes, the packing fraction for
//!    dry ones, `coexistence_by`) has a spread `Delta` (Eq. 3.3) above the `coexistence_level`
//!    quantile of the bootstrap null distribution stored with the result (`noise::NullRanges`;
//!    older results: the range of `B` independent normals with the bins' statistical error),
//!    above `coexistence_delta_n_cb`, and its dense and dilute classes differ by at least the
//!    fraction `coexistence_contrast` of the dense mean. Otherwise the system is homogeneous
//!    and rule 1 classifies it as a whole.
//! 3. A coexistence splits the bins into a dense and a dilute class (Otsu's rule,
//!    [`two_class_split`]). The dense region is described by its cluster members (bonded, or
//!    closely packed when dry: `observe::clusters`), the dilute region by all of its grains,
//!    each time-averaged over the samples; each is classified by rule 1, with the per-point
//!    gas threshold, except that the dense region also counts as condensed (not gas) when the
//!    dilute region is at least `line_jump_ratio` times hotter (a bonded drop in its vapour).
//!    Two different phases give their coexistence (sfc, sgc or fgc); the same phase twice
//!    gives that phase.
//! 4. A sheared scene (docs/model.md 4.2) is solid or fluidised by `E_par` alone: solid when the
//!    window mean of `E_par / E_cb` (`/ (m g d)` dry) is at most `shear_e_par`, else fluid
//!    (label f). The rules above are still evaluated and recorded, but do not decide.
//!
//! Along a line of constant Gamma (sweeps), fluid versus gas follows docs/model.md 7: the jump of
//! `T_g / E_cb(E*)` for elastic grains, its inflection for inelastic ones ([`super::line`]).
//!
//! A value equal to a threshold stays on the calmer side (solid, not gas, homogeneous).

use super::settling::{self, Settling, Verdict};
use super::{Observables, noise};
use serde::{Deserialize, Serialize};
use std::fmt;

mod evidence;

/// The six phases of docs/model.md 7.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Phase {
    /// Solid.
    S,
    /// Fluid.
    F,
    /// Gas.
    G,
    /// Solid-fluid coexistence.
    Sfc,
    /// Solid-gas coexistence.
    Sgc,
    /// Fluid-gas coexistence.
    Fgc,
}

impl Phase {
    /// Every phase, in the order s, f, g, sfc, sgc, fgc.
    pub const ALL: [Phase; 6] = [
        Phase::S,
        Phase::F,
        Phase::G,
        Phase::Sfc,
        Phase::Sgc,
        Phase::Fgc,
    ];

    /// The short lowercase name ("s", "f", "g", "sfc", "sgc", "fgc").
    pub fn name(self) -> &'static str {
        match self {
            Phase::S => "s",
            Phase::F => "f",
            Phase::G => "g",
            Phase::Sfc => "sfc",
            Phase::Sgc => "sgc",
            Phase::Fgc => "fgc",
        }
    }

    /// The coexistence of two pure phases (`None` if equal or not both pure).
    pub fn coexistence(a: Phase, b: Phase) -> Option<Phase> {
        let (lo, hi) = if a <= b { (a, b) } else { (b, a) };
        match (lo, hi) {
            (Phase::S, Phase::F) => Some(Phase::Sfc),
            (Phase::S, Phase::G) => Some(Phase::Sgc),
            (Phase::F, Phase::G) => Some(Phase::Fgc),
            _ => None,
        }
    }
}

impl fmt::Display for Phase {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for Phase {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Phase::ALL
            .into_iter()
            .find(|p| p.name() == s)
            .ok_or_else(|| format!("unknown phase `{s}`: expected one of s, f, g, sfc, sgc, fgc"))
    }
}

pub use crate::scene::thresholds::{CoexistenceBy, LEGACY_DELTA_N_CB, Mobility, Thresholds};

/// How the fluid-versus-gas part of a label was decided.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "by")]
pub enum FluidGasFrom {
    /// Per point: `T_g / E_cb` against `gas_temperature` (no line decided it).
    #[default]
    PointFallback,
    /// A line of constant Gamma: the fluid-gas boundary at `e_star_boundary`.
    Line {
        gamma: f64,
        /// `"jump"` (elastic), `"inflection"`, or `"coexistence"` (no transition on the curve,
        /// the line's fluid-gas coexistences mark it: `observe::line`).
        method: String,
        e_star_boundary: f64,
    },
    /// A line of constant Gamma put the point on one side, and the point's own temperature and
    /// bridges said the other (rule 5, `observe::classify::evidence`): the point's evidence decided.
    OwnEvidence {
        gamma: f64,
        /// The line's method (`"jump"`, `"inflection"`, `"coexistence"`).
        method: String,
        e_star_boundary: f64,
        /// The phase the line gave.
        line_said: Phase,
    },
    /// A line of constant Gamma whose curve shows no fluid-gas transition that stands out of
    /// its scatter: the per-point fallback decided, and `reason` says why the line did not.
    LineWithoutTransition {
        gamma: f64,
        /// `"jump"` (elastic) or `"inflection"`: the test that found nothing.
        method: String,
        reason: String,
    },
}

/// The numbers one region (whole system, dense part or dilute part) was classified on.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RegionInputs {
    /// Location changes per particle per period (`None` where not observed).
    pub flc: Option<f64>,
    /// Lateral mobility `D_lat` over the long lag (`None` where not observed).
    pub diffusion: Option<f64>,
    /// `D_lat` over the short lag (`None` where not observed).
    pub diffusion_short: Option<f64>,
    /// Growth exponent `alpha` of the mean-square displacement between the two lags
    /// (`MSD ~ tau^alpha`; `None` without both).
    pub(crate) growth_exponent: Option<f64>,
    /// `T_g / E_cb` (`T_g / (m g d)` for dry scenes).
    pub temperature: f64,
    /// Which observable decided solid versus mobile.
    pub mobility_from: Mobility,
    /// Dense region: the fraction of its members' displacements over the long lag that stay
    /// within `solid_diffusion` of their cage, the grains they were bonded to (`None` for other
    /// regions and results stored before it was measured).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub members_still: Option<f64>,
    /// Lateral bins in the region (all bins for the whole system).
    pub bins: usize,
    /// `"all"` grains of the region's bins, or only the `"clustered"` ones.
    #[serde(default)]
    pub grains: String,
    /// The phase rule 1 gives this region.
    pub phase: Phase,
}

/// The coexistence test of rule 2.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CoexistenceTest {
    /// `"n_cb"` or `"packing"`.
    pub profile: String,
    /// Spread of the profile, `max - min` (Eq. 3.3).
    pub delta: f64,
    /// RMS statistical error of the bins' time averages (`None`: not measured).
    pub standard_error: Option<f64>,
    /// Expected spread of a homogeneous state: the bootstrap's median where stored, else
    /// `E[range of B normals] * standard_error`.
    pub expected_noise: Option<f64>,
    /// The `coexistence_level` quantile of that spread: from the bootstrap over the profile
    /// where stored (`noise::NullRanges`), else from the independent-bin range model.
    pub noise_threshold: Option<f64>,
    /// `"bootstrap"` or `"independent_bins"`: which null model gave `noise_threshold`.
    pub(crate) null_model: Option<String>,
    /// Fraction of the dense bins' grains that are members of bonded clusters (`None` for
    /// results stored before membership was measured).
    pub(crate) member_fraction: Option<f64>,
    /// `(dense - dilute) / dense` of the two classes' means.
    pub contrast: f64,
    pub significant: bool,
}

/// Everything a classification was decided on: the thresholds, the inputs and each step.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DecisionInputs {
    pub thresholds: Thresholds,
    /// The whole system by rule 1.
    pub whole: RegionInputs,
    /// `Delta n_cb` (Eq. 3.3), units of `n_cb`.
    pub delta_n_cb: f64,
    /// The coexistence test (rule 2).
    pub coexistence: Option<CoexistenceTest>,
    /// Whether rule 3 applied.
    pub split: bool,
    /// The profile value that separated dense from dilute bins.
    pub split_n_cb: Option<f64>,
    pub dense: Option<RegionInputs>,
    pub dilute: Option<RegionInputs>,
    /// How fluid versus gas was decided.
    #[serde(default)]
    pub fluid_gas: FluidGasFrom,
    /// Sheared scenes: the window mean of `E_par / E_cb` that decided (rule 4).
    pub shear_e_par: Option<f64>,
    /// Decisions whose input lies close to its threshold (`observe::classify::evidence`): the label
    /// is uncertain there and should be read with replicas. Empty when every decision is clear.
    #[serde(default)]
    pub borderline: Vec<String>,
    /// The decision in words.
    pub reason: String,
    /// The verdict on the label (`observe::settling`): recomputed with the label, because what
    /// may still drift depends on it.
    pub settling: Settling,
}

/// A phase and the numbers it was decided on.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Classification {
    pub phase: Phase,
    pub decided_on: DecisionInputs,
}

impl Classification {
    /// The verdict on this label.
    pub fn verdict(&self) -> Verdict {
        self.decided_on.settling.verdict
    }
}

/// The bridge density separating dense from dilute bins: the split of the sorted values into
/// two classes that maximises the between-class variance `w_0 w_1 (mu_0 - mu_1)^2` (Otsu's
/// rule, every bin weighing the same), placed halfway between the two classes. Unlike the
/// midpoint of the range it does not hang on the two most extreme bins.
pub fn two_class_split(values: &[f64]) -> f64 {
    let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n < 2 {
        return v.first().copied().unwrap_or(0.0);
    }
    let total: f64 = v.iter().sum();
    let (mut best, mut split, mut low) = (f64::NEG_INFINITY, 0.5 * (v[0] + v[n - 1]), 0.0);
    for k in 1..n {
        low += v[k - 1];
        if v[k] == v[k - 1] {
            continue;
        }
        let (w0, w1) = (k as f64 / n as f64, (n - k) as f64 / n as f64);
        let (m0, m1) = (low / k as f64, (total - low) / (n - k) as f64);
        let between = w0 * w1 * (m0 - m1) * (m0 - m1);
        if between > best {
            best = between;
            split = 0.5 * (v[k - 1] + v[k]);
        }
    }
    split
}

/// What rule 1 reads for one region.
#[derive(Debug, Clone, Copy)]
struct RegionObservables {
    flc: Option<f64>,
    diffusion: Option<f64>,
    diffusion_short: Option<f64>,
    temperature: f64,
    /// Dense region: [`RegionInputs::members_still`].
    members_still: Option<f64>,
}

/// A region whose mean-square displacement over the long lag stays below this (units `d^2`) and
/// grows slower than `diffusive_exponent` is caged: its grains rattle without leaving their
/// neighbours. A gas confined to a narrow pocket also saturates, but at the pocket's size.
pub(crate) const CAGE_MSD: f64 = 1.0;

/// The two mobility lags of a result.
#[derive(Debug, Clone, Copy)]
struct Lags {
    /// The long lag, time units.
    long: f64,
    /// `tau_long / tau_short`.
    ratio: f64,
    /// Lateral dimensions (1 in 2D, 2 in 3D).
    n_lat: f64,
}

/// `alpha` of `MSD ~ tau^alpha` from `D_lat` at the long and the short lag (`D = MSD / (2 n_lat
/// tau)`): `alpha = 1 + ln(D_long / D_short) / ln(tau_long / tau_short)`.
fn growth_exponent(long: f64, short: f64, lag_ratio: f64) -> Option<f64> {
    (long > 0.0 && short > 0.0 && lag_ratio > 1.0)
        .then(|| 1.0 + (long / short).ln() / lag_ratio.ln())
}

/// Rule 1 for one region; `gas` decides fluid versus gas of a mobile region; `lags`: the two
/// mobility lags (`None` without a short lag).
fn region(
    obs: RegionObservables,
    lags: Option<Lags>,
    bins: usize,
    grains: &str,
    th: &Thresholds,
    gas: &dyn Fn(f64) -> bool,
) -> RegionInputs {
    let RegionObservables {
        flc,
        diffusion,
        diffusion_short,
        temperature,
        members_still,
    } = obs;
    let hot = temperature > th.gas_temperature;
    let alpha = match (diffusion, diffusion_short, lags) {
        (Some(l), Some(s), Some(g)) => growth_exponent(l, s, g.ratio),
        _ => None,
    };
    let (mobile, mobility_from) = match (th.mobility, diffusion, flc) {
        // Mobile: displaced beyond the floor and not caged (saturating within a diameter).
        (Mobility::Displacement, Some(d), _) => {
            let caged = match (alpha, lags) {
                (Some(a), Some(g)) => {
                    a < th.diffusive_exponent && 2.0 * g.n_lat * g.long * d <= CAGE_MSD
                }
                _ => false,
            };
            let still = members_still.is_some_and(|f| f >= th.still_members);
            (
                d > th.solid_diffusion && !caged && !still,
                Mobility::Displacement,
            )
        }
        (Mobility::LocationChanges, _, Some(f)) => {
            (f > th.solid_flc || hot, Mobility::LocationChanges)
        }
        _ => (temperature > th.solid_temperature, Mobility::Temperature),
    };
    let phase = if !mobile {
        Phase::S
    } else if gas(temperature) {
        Phase::G
    } else {
        Phase::F
    };
    RegionInputs {
        flc,
        diffusion,
        diffusion_short,
        growth_exponent: alpha,
        temperature,
        mobility_from,
        members_still,
        bins,
        grains: grains.to_string(),
        phase,
    }
}

/// Weighted mean over the bins `sel` of a per-bin quantity; bins without a value or weight are
/// skipped.
fn weighted(sel: &[usize], weight: &[f64], value: &[Option<f64>]) -> Option<f64> {
    let (mut s, mut w) = (0.0, 0.0);
    for &b in sel {
        if let (Some(v), Some(&wb)) = (value.get(b).copied().flatten(), weight.get(b)) {
            s += v * wb;
            w += wb;
        }
    }
    (w > 0.0).then(|| s / w)
}

/// Classifies observables with the given thresholds (pure: the same inputs give the same
/// answer). Fluid versus gas is decided per point (`gas_temperature`); a sweep replaces that by
/// the line rule ([`super::line::classify_line`]).
pub fn classify(obs: &Observables, th: &Thresholds) -> Classification {
    let t_gas = th.gas_temperature;
    classify_with(obs, th, &|t| t > t_gas, FluidGasFrom::PointFallback)
}

/// [`classify`] with the fluid-gas decision `gas(T_g / E_cb)` of a homogeneous system given
/// from outside (the line rule); the regions of a coexistence keep rule 3.
pub fn classify_with(
    obs: &Observables,
    th: &Thresholds,
    gas: &dyn Fn(f64) -> bool,
    from: FluidGasFrom,
) -> Classification {
    let (mut phase, mut decided) = classify_unsheared(obs, th, gas);
    decided.fluid_gas = from;
    if let Some(own) = evidence::overrule_line(obs, &mut decided) {
        phase = own;
    }
    decided.borderline = evidence::borderline(&decided);
    if let Some(sh) = &obs.shear {
        phase = if sh.e_par <= th.shear_e_par {
            Phase::S
        } else {
            Phase::F
        };
        decided.reason = format!(
            "sheared: E_par/{} = {:.4} {} {} -> {phase} (rule 4; unsheared rules would say: {})",
            obs.temperature_unit_name,
            sh.e_par,
            above(sh.e_par, th.shear_e_par),
            th.shear_e_par,
            decided.reason
        );
        decided.shear_e_par = Some(sh.e_par);
    }
    let parts = match (&decided.dense, &decided.dilute) {
        (Some(d), Some(l))
            if decided.split && Phase::coexistence(d.phase, l.phase) == Some(phase) =>
        {
            Some((d.phase, l.phase))
        }
        _ => None,
    };
    if let Some(t) = &obs.trend {
        let tests: Vec<_> = t.all_tests().cloned().collect();
        decided.settling = settling::settle(phase, parts, &t.unrelaxed, &tests);
    }
    Classification {
        phase,
        decided_on: decided,
    }
}

/// Rule 2: whether the deciding profile is significantly inhomogeneous and its dense bins are
/// made of bonded clusters; with the profile and the value splitting it into dense and dilute.
fn coexistence_test(obs: &Observables, th: &Thresholds) -> (CoexistenceTest, Vec<f64>, f64) {
    let p = &obs.profiles;
    let wet = obs.temperature_unit_name == "E_cb";
    let by_bridges = match th.coexistence_by {
        CoexistenceBy::Auto => wet,
        CoexistenceBy::Bridges => true,
        CoexistenceBy::Packing => false,
    };
    let (name, values, delta, se, null) = if by_bridges {
        (
            "n_cb",
            p.n_cb.clone(),
            p.delta_n_cb,
            p.n_cb_standard_error,
            p.n_cb_null.as_ref(),
        )
    } else {
        (
            "packing",
            p.packing.clone(),
            p.delta_n_area,
            p.packing_standard_error,
            p.packing_null.as_ref(),
        )
    };
    let bins = values.len();
    let split = two_class_split(&values);
    let (mut hi, mut nhi, mut lo, mut nlo) = (0.0, 0usize, 0.0, 0usize);
    let (mut members, mut grains) = (0.0, 0.0);
    for (b, &v) in values.iter().enumerate() {
        if v >= split {
            hi += v;
            nhi += 1;
            members += p.clustered.get(b).copied().unwrap_or(0.0);
            grains += p.particles.get(b).copied().unwrap_or(0.0);
        } else {
            lo += v;
            nlo += 1;
        }
    }
    let (mh, ml) = (hi / nhi.max(1) as f64, lo / nlo.max(1) as f64);
    let contrast = if mh > 0.0 && nlo > 0 {
        (mh - ml) / mh
    } else {
        0.0
    };
    // Membership is only known for results that measured bonded clusters.
    let member_fraction = (p.clusters.is_some() && grains > 0.0).then(|| members / grains);
    // The expected spread of a homogeneous profile and the level's quantile: from the stored
    // bootstrap (its median and quantile, cheap), else from the independent-bin range model
    // (two numerical integrals per call).
    let (expected, threshold, null_model) = match null {
        Some(n) => (
            Some(n.quantile(0.5)),
            Some(n.quantile(th.coexistence_level)),
            Some("bootstrap"),
        ),
        None => (
            se.map(|s| s * noise::range_mean(bins)),
            se.map(|s| s * noise::range_quantile(bins, th.coexistence_level)),
            se.map(|_| "independent_bins"),
        ),
    };
    let bonded = member_fraction.is_none_or(|f| f >= th.cluster_fraction);
    let significant = !delta.is_nan()
        && bonded
        && match threshold {
            Some(q) => {
                delta > q
                    && delta > th.coexistence_delta_n_cb
                    && contrast >= th.coexistence_contrast
            }
            // Stored before block statistics: the absolute threshold alone.
            None => {
                let floor = if th.coexistence_delta_n_cb > 0.0 {
                    th.coexistence_delta_n_cb
                } else {
                    LEGACY_DELTA_N_CB
                };
                delta > floor
            }
        };
    (
        CoexistenceTest {
            profile: name.to_string(),
            delta,
            standard_error: se,
            expected_noise: expected,
            noise_threshold: threshold,
            null_model: null_model.map(str::to_string),
            member_fraction,
            contrast,
            significant,
        },
        values,
        split,
    )
}

/// The dense region's observables over its bins `sel`: over its clustered grains when the
/// profiles have them, else over all grains; with the name of the grains it counted.
fn dense_observables(
    obs: &Observables,
    sel: &[usize],
    flc: Option<f64>,
    th: &Thresholds,
) -> (RegionObservables, &'static str) {
    let p = &obs.profiles;
    let has_clusters = !p.clustered.is_empty() && !p.temperature_clustered.is_empty();
    let (w, t_bins, d_bins, s_bins, grains) = if has_clusters {
        (
            &p.clustered,
            &p.temperature_clustered,
            &p.diffusion_clustered,
            &p.diffusion_clustered_short,
            "clustered",
        )
    } else {
        (
            &p.particles,
            &p.temperature_reduced,
            &p.diffusion,
            &p.diffusion_short,
            "all",
        )
    };
    let obs_dense = RegionObservables {
        flc,
        diffusion: weighted(sel, w, d_bins),
        diffusion_short: weighted(sel, w, s_bins),
        temperature: weighted(sel, w, t_bins).unwrap_or(obs.granular_temperature_reduced),
        members_still: p
            .member_cages
            .as_ref()
            .filter(|_| has_clusters)
            .and_then(|c| c.fraction_within(sel, th.solid_diffusion)),
    };
    (obs_dense, grains)
}

/// Rules 1-3.
fn classify_unsheared(
    obs: &Observables,
    th: &Thresholds,
    gas: &dyn Fn(f64) -> bool,
) -> (Phase, DecisionInputs) {
    let p = &obs.profiles;
    let flc_whole = obs
        .location_changes
        .as_ref()
        .map(|l| l.per_particle_per_period);
    let lag_ratio = obs.mobility.as_ref().and_then(|m| {
        m.short_lag.map(|s| Lags {
            long: m.lag,
            ratio: m.lag / s,
            n_lat: (obs.dimension.max(2) - 1) as f64,
        })
    });
    let whole = region(
        RegionObservables {
            flc: flc_whole,
            diffusion: obs.mobility.as_ref().map(|m| m.diffusion),
            diffusion_short: obs.mobility.as_ref().and_then(|m| m.diffusion_short),
            temperature: obs.granular_temperature_reduced,
            members_still: None,
        },
        lag_ratio,
        p.n_cb.len(),
        "all",
        th,
        gas,
    );
    let (test, values, mid) = coexistence_test(obs, th);
    let mut decided = DecisionInputs {
        thresholds: th.clone(),
        whole: whole.clone(),
        delta_n_cb: p.delta_n_cb,
        coexistence: Some(test.clone()),
        split: false,
        split_n_cb: None,
        dense: None,
        dilute: None,
        fluid_gas: FluidGasFrom::PointFallback,
        shear_e_par: None,
        borderline: Vec::new(),
        reason: String::new(),
        settling: Settling {
            verdict: Verdict::NotSettled,
            regions: Vec::new(),
        },
    };
    if !test.significant {
        decided.reason = format!(
            "homogeneous ({}): {}",
            describe_test(&test, th),
            describe(&whole, th, &obs.temperature_unit_name)
        );
        return (whole.phase, decided);
    }
    let (dense_bins, dilute_bins): (Vec<usize>, Vec<usize>) =
        (0..values.len()).partition(|&b| values[b] >= mid);
    // f_lc per bin is stored per time unit; rule 1 compares per period.
    let flc_bins: Option<Vec<Option<f64>>> = p
        .flc
        .as_ref()
        .map(|f| f.iter().map(|&x| Some(x * obs.period)).collect());
    let flc_of = |sel: &[usize]| {
        flc_bins
            .as_ref()
            .and_then(|fb| weighted(sel, &p.particles, fb))
    };
    let (dense_obs, grains) = dense_observables(obs, &dense_bins, flc_of(&dense_bins), th);
    let dilute = {
        let sel = &dilute_bins;
        let o = RegionObservables {
            flc: flc_of(sel),
            diffusion: weighted(sel, &p.particles, &p.diffusion),
            diffusion_short: weighted(sel, &p.particles, &p.diffusion_short),
            temperature: weighted(sel, &p.particles, &p.temperature_reduced)
                .unwrap_or(obs.granular_temperature_reduced),
            members_still: None,
        };
        region(o, lag_ratio, sel.len(), "all", th, &|t| {
            t > th.gas_temperature
        })
    };
    // The dense region is condensed (solid or fluid) when its clustered grains are no hotter
    // than the gas threshold, or when the dilute region is hotter by the fluid-gas jump
    // `line_jump_ratio` (a bonded drop in its vapour); else it is gas-like too.
    let t_dilute = dilute.temperature;
    let dense = region(dense_obs, lag_ratio, dense_bins.len(), grains, th, &|t| {
        t > th.gas_temperature && t_dilute < th.line_jump_ratio * t
    });
    let phase = Phase::coexistence(dense.phase, dilute.phase).unwrap_or(dense.phase);
    decided.reason = format!(
        "coexistence test passed ({}): split at {} = {mid:.4}; dense part ({} bins, {} grains): \
         {}; dilute part ({} bins): {}; so {phase}",
        describe_test(&test, th),
        test.profile,
        dense.bins,
        dense.grains,
        describe(&dense, th, &obs.temperature_unit_name),
        dilute.bins,
        describe(&dilute, th, &obs.temperature_unit_name)
    );
    decided.split = true;
    decided.split_n_cb = Some(mid);
    decided.dense = Some(dense);
    decided.dilute = Some(dilute);
    (phase, decided)
}

/// The coexistence test in words.
fn describe_test(t: &CoexistenceTest, th: &Thresholds) -> String {
    match t.noise_threshold {
        Some(q) => format!(
            "Delta {} = {:.4} against noise {:.4} (level {} threshold {:.4}, {}), contrast {:.2} \
             (min {}){}",
            t.profile,
            t.delta,
            t.expected_noise.unwrap_or(f64::NAN),
            th.coexistence_level,
            q,
            t.null_model.as_deref().unwrap_or("independent_bins"),
            t.contrast,
            th.coexistence_contrast,
            match t.member_fraction {
                Some(f) => format!(
                    ", cluster members {:.2} of the dense bins' grains (min {})",
                    f, th.cluster_fraction
                ),
                None => String::new(),
            }
        ),
        None => format!(
            "Delta {} = {:.4}, no statistical error stored: legacy threshold",
            t.profile, t.delta
        ),
    }
}

/// The operator that holds between `x` and threshold `t`: `>` or `<=`.
pub(crate) fn above(x: f64, t: f64) -> &'static str {
    if x > t { ">" } else { "<=" }
}

/// One region's decision in words (`unit`: the temperature unit's name, `E_cb` or `m g d`).
fn describe(r: &RegionInputs, th: &Thresholds, unit: &str) -> String {
    let mobility = match (r.mobility_from, r.diffusion, r.flc) {
        (Mobility::Displacement, Some(d), _) => {
            let floor = format!(
                "D_lat = {d:.3e} {} {}",
                above(d, th.solid_diffusion),
                th.solid_diffusion
            );
            match r.growth_exponent {
                Some(a) => {
                    let diffusive = a >= th.diffusive_exponent;
                    format!(
                        "{floor}, MSD growth exponent {a:.2} {} {}{}",
                        if diffusive { ">=" } else { "<" },
                        th.diffusive_exponent,
                        if !diffusive && r.phase != Phase::S {
                            " but spread beyond a cage"
                        } else {
                            ""
                        }
                    )
                }
                None => floor,
            }
        }
        (Mobility::LocationChanges, _, Some(f)) if f <= th.solid_flc && r.phase != Phase::S => {
            format!("f_lc = {f:.4} <= {} but too hot for bridges", th.solid_flc)
        }
        (Mobility::LocationChanges, _, Some(f)) => {
            format!("f_lc = {f:.4} {} {}", above(f, th.solid_flc), th.solid_flc)
        }
        _ => format!(
            "T_g/{unit} = {:.4} {} {}",
            r.temperature,
            above(r.temperature, th.solid_temperature),
            th.solid_temperature
        ),
    };
    let mobility = match (r.mobility_from, r.members_still) {
        (Mobility::Displacement, Some(f)) => format!(
            "{mobility}, members still in their cage {f:.2} {} {}",
            if f >= th.still_members { ">=" } else { "<" },
            th.still_members
        ),
        _ => mobility,
    };
    if r.phase == Phase::S {
        return format!("{mobility} -> s");
    }
    format!(
        "{mobility}, T_g/{unit} = {:.4} -> {}",
        r.temperature, r.phase
    )
}
