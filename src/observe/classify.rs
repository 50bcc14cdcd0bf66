//! Phase classification: maps [`Observables`] to one of s, f, g, sfc, sgc, fgc (MODEL.md 7)
//! with the thresholds of the scene's `[classify]` section, and records every number the
//! decision used so that a result can be re-classified later without re-simulating.
//!
//! The rule (docs/observables.md gives the reasoning behind the default thresholds):
//! 1. A region is *solid* when it is not mobile: its location-change frequency `f_lc` is at most
//!    `solid_flc` (or, with `mobility = "temperature"` or without `f_lc`, its `T_g / E_cb` is at
//!    most `solid_temperature`). A mobile region is *gas* when `T_g / E_cb > gas_temperature`,
//!    else *fluid*. A region hotter than `gas_temperature` is mobile whatever its `f_lc`: its
//!    bridges cannot hold (a dilute gas at high Gamma has a small `f_lc` per short period).
//! 2. If `Delta n_cb` (Eq. 3.3) is at most `coexistence_delta_n_cb`, the system is homogeneous
//!    and the whole system is classified by rule 1.
//! 3. Otherwise the lateral bins are split by their bridge density into a dense and a dilute
//!    region (two classes of maximal between-class variance, [`two_class_split`]); each region is classified by
//!    rule 1 from its own particle-weighted `f_lc` and `T_g / E_cb`. Two different phases give
//!    their coexistence (sfc, sgc or fgc); the same phase twice gives that phase.
//!
//! 4. A sheared scene (MODEL.md 4.2) is solid or fluidised by `E_par` alone: solid when the
//!    window mean of `E_par / E_cb` (`/ (m g d)` dry) is at most `shear_e_par`, else fluid
//!    (label f). The rules above are still evaluated and recorded, but do not decide.
//!
//! A value equal to a threshold stays on the calmer side (solid, not gas, homogeneous).

use super::Observables;
use serde::{Deserialize, Serialize};
use std::fmt;

/// The six phases of MODEL.md 7.
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

/// Which observable separates solid from mobile.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Mobility {
    /// The location-change frequency `f_lc` (falls back to temperature where it was not
    /// observed).
    #[default]
    LocationChanges,
    /// `T_g / E_cb`.
    Temperature,
}

/// Thresholds of the classifier (scene section `[classify]`); defaults and their reasoning are
/// in docs/observables.md.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Thresholds {
    /// Observable for solid versus mobile.
    #[serde(default)]
    pub mobility: Mobility,
    /// Largest `f_lc` (location changes per particle per period) of a solid.
    #[serde(default = "default_solid_flc")]
    pub solid_flc: f64,
    /// Largest `T_g / E_cb` of a solid (used with `mobility = "temperature"` or without `f_lc`).
    #[serde(default = "default_solid_temperature")]
    pub solid_temperature: f64,
    /// `T_g / E_cb` above which a mobile region is a gas.
    #[serde(default = "default_gas_temperature")]
    pub gas_temperature: f64,
    /// `Delta n_cb` (units `d^-(D-1)`) above which the system is split into a dense and a
    /// dilute region.
    #[serde(default = "default_coexistence_delta_n_cb")]
    pub coexistence_delta_n_cb: f64,
    /// Sheared scenes: largest window mean of `E_par / E_cb` (`/ (m g d)` dry) of a solid.
    #[serde(default = "default_shear_e_par")]
    pub shear_e_par: f64,
}

fn default_shear_e_par() -> f64 {
    0.1
}

fn default_solid_flc() -> f64 {
    0.02
}
fn default_solid_temperature() -> f64 {
    0.02
}
fn default_gas_temperature() -> f64 {
    2.0
}
fn default_coexistence_delta_n_cb() -> f64 {
    2.0
}

impl Default for Thresholds {
    fn default() -> Self {
        Self {
            mobility: Mobility::default(),
            solid_flc: default_solid_flc(),
            solid_temperature: default_solid_temperature(),
            gas_temperature: default_gas_temperature(),
            coexistence_delta_n_cb: default_coexistence_delta_n_cb(),
            shear_e_par: default_shear_e_par(),
        }
    }
}

impl Thresholds {
    /// Checks every key of `[classify]`.
    pub fn validate(&self, origin: &str) -> Result<(), crate::scene::SceneError> {
        let checks = [
            ("solid_flc", self.solid_flc),
            ("solid_temperature", self.solid_temperature),
            ("gas_temperature", self.gas_temperature),
            ("coexistence_delta_n_cb", self.coexistence_delta_n_cb),
            ("shear_e_par", self.shear_e_par),
        ];
        for (key, v) in checks {
            if !(v.is_finite() && v >= 0.0) {
                return Err(crate::scene::SceneError::new(
                    origin,
                    &format!("classify.{key}"),
                    format!("= {v} is out of range: must be finite and >= 0"),
                ));
            }
        }
        if self.gas_temperature < self.solid_temperature {
            return Err(crate::scene::SceneError::new(
                origin,
                "classify.gas_temperature",
                format!(
                    "= {} is out of range: must be >= classify.solid_temperature = {} (a gas is \
                     hotter than a solid)",
                    self.gas_temperature, self.solid_temperature
                ),
            ));
        }
        Ok(())
    }
}

/// The numbers one region (whole system, dense part or dilute part) was classified on.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RegionInputs {
    /// Location changes per particle per period (`None` where not observed).
    pub flc: Option<f64>,
    /// `T_g / E_cb` (`T_g / (m g d)` for dry scenes).
    pub temperature: f64,
    /// Which observable decided solid versus mobile.
    pub mobility_from: Mobility,
    /// Lateral bins in the region (all bins for the whole system).
    pub bins: usize,
    /// The phase rule 1 gives this region.
    pub phase: Phase,
}

/// Everything a classification was decided on: the thresholds, the inputs and each step.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DecisionInputs {
    pub thresholds: Thresholds,
    /// The whole system by rule 1.
    pub whole: RegionInputs,
    /// `Delta n_cb` (Eq. 3.3), units `d^-(D-1)`.
    pub delta_n_cb: f64,
    /// Whether `Delta n_cb` exceeded its threshold (rule 3 applied).
    pub split: bool,
    /// The bridge density that separated dense from dilute bins.
    pub split_n_cb: Option<f64>,
    pub dense: Option<RegionInputs>,
    pub dilute: Option<RegionInputs>,
    /// Sheared scenes: the window mean of `E_par / E_cb` that decided (rule 4).
    #[serde(default)]
    pub shear_e_par: Option<f64>,
    /// The decision in words.
    pub reason: String,
}

/// A phase and the numbers it was decided on.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Classification {
    pub phase: Phase,
    pub decided_on: DecisionInputs,
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

/// Rule 1 for one region.
fn region(flc: Option<f64>, temperature: f64, bins: usize, th: &Thresholds) -> RegionInputs {
    let hot = temperature > th.gas_temperature;
    let (mobile, mobility_from) = match (th.mobility, flc) {
        (Mobility::LocationChanges, Some(f)) => {
            (f > th.solid_flc || hot, Mobility::LocationChanges)
        }
        _ => (temperature > th.solid_temperature, Mobility::Temperature),
    };
    let phase = if !mobile {
        Phase::S
    } else if temperature > th.gas_temperature {
        Phase::G
    } else {
        Phase::F
    };
    RegionInputs {
        flc,
        temperature,
        mobility_from,
        bins,
        phase,
    }
}

/// Particle-weighted mean over the bins `sel` of a per-bin quantity; bins without a value
/// (no particle, or too few for a temperature) are skipped.
fn weighted(sel: &[usize], weight: &[f64], value: &[Option<f64>]) -> Option<f64> {
    let (mut s, mut w) = (0.0, 0.0);
    for &b in sel {
        if let Some(v) = value[b] {
            s += v * weight[b];
            w += weight[b];
        }
    }
    (w > 0.0).then(|| s / w)
}

/// Classifies observables with the given thresholds (pure: the same inputs give the same
/// answer).
pub fn classify(obs: &Observables, th: &Thresholds) -> Classification {
    let mut c = classify_unsheared(obs, th);
    if let Some(sh) = &obs.shear {
        let phase = if sh.e_par <= th.shear_e_par {
            Phase::S
        } else {
            Phase::F
        };
        c.decided_on.reason = format!(
            "sheared: E_par/{} = {:.4} {} {} -> {phase} (rule 4; unsheared rules would say: {})",
            obs.temperature_unit_name,
            sh.e_par,
            if phase == Phase::S { "<=" } else { ">" },
            th.shear_e_par,
            c.decided_on.reason
        );
        c.decided_on.shear_e_par = Some(sh.e_par);
        c.phase = phase;
    }
    c
}

/// Rules 1-3.
fn classify_unsheared(obs: &Observables, th: &Thresholds) -> Classification {
    let p = &obs.profiles;
    let whole = region(
        obs.location_changes
            .as_ref()
            .map(|l| l.per_particle_per_period),
        obs.granular_temperature_reduced,
        p.n_cb.len(),
        th,
    );
    let delta = p.delta_n_cb;
    let mut decided = DecisionInputs {
        thresholds: th.clone(),
        whole: whole.clone(),
        delta_n_cb: delta,
        split: false,
        split_n_cb: None,
        dense: None,
        dilute: None,
        shear_e_par: None,
        reason: String::new(),
    };
    if delta.is_nan() || delta <= th.coexistence_delta_n_cb {
        decided.reason = format!(
            "homogeneous (Delta n_cb = {delta:.4} <= {}): {}",
            th.coexistence_delta_n_cb,
            describe(&whole, th)
        );
        return Classification {
            phase: whole.phase,
            decided_on: decided,
        };
    }
    let mid = two_class_split(&p.n_cb);
    let (dense_bins, dilute_bins): (Vec<usize>, Vec<usize>) =
        (0..p.n_cb.len()).partition(|&b| p.n_cb[b] >= mid);
    let flc_bins: Option<Vec<Option<f64>>> =
        p.flc.as_ref().map(|f| f.iter().map(|&x| Some(x)).collect());
    let part = |sel: &[usize]| {
        let t = weighted(sel, &p.particles, &p.temperature_reduced)
            .unwrap_or(obs.granular_temperature_reduced);
        let f = flc_bins
            .as_ref()
            .and_then(|fb| weighted(sel, &p.particles, fb));
        region(f, t, sel.len(), th)
    };
    let dense = part(&dense_bins);
    let dilute = part(&dilute_bins);
    let phase = Phase::coexistence(dense.phase, dilute.phase).unwrap_or(dense.phase);
    decided.reason = format!(
        "Delta n_cb = {delta:.4} > {}: split at n_cb = {mid:.4}; dense part ({} bins): {}; \
         dilute part ({} bins): {}; so {phase}",
        th.coexistence_delta_n_cb,
        dense.bins,
        describe(&dense, th),
        dilute.bins,
        describe(&dilute, th)
    );
    decided.split = true;
    decided.split_n_cb = Some(mid);
    decided.dense = Some(dense);
    decided.dilute = Some(dilute);
    Classification {
        phase,
        decided_on: decided,
    }
}

/// One region's decision in words.
fn describe(r: &RegionInputs, th: &Thresholds) -> String {
    let mobility = match (r.mobility_from, r.flc) {
        (Mobility::LocationChanges, Some(f)) if f <= th.solid_flc && r.phase != Phase::S => {
            format!("f_lc = {f:.4} <= {} but too hot for bridges", th.solid_flc)
        }
        (Mobility::LocationChanges, Some(f)) => format!(
            "f_lc = {f:.4} {} {}",
            if f > th.solid_flc { ">" } else { "<=" },
            th.solid_flc
        ),
        _ => format!(
            "T_g/E_cb = {:.4} {} {}",
            r.temperature,
            if r.temperature > th.solid_temperature {
                ">"
            } else {
                "<="
            },
            th.solid_temperature
        ),
    };
    if r.phase == Phase::S {
        return format!("{mobility} -> s");
    }
    format!(
        "{mobility}, T_g/E_cb = {:.4} {} {} -> {}",
        r.temperature,
        if r.temperature > th.gas_temperature {
            ">"
        } else {
            "<="
        },
        th.gas_temperature,
        r.phase
    )
}
