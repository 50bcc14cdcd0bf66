//! Which criterion decided a label ([`DecidedBy`]), read from a classification's
//! [`DecisionInputs`] alone, so that it works on stored results and after `wetgran reclassify`.
//!
//! A label is made of up to two decisions per region (docs/observables.md, "Classification"):
//! solid or mobile (rule 1: `D_lat` against `solid_diffusion`, the caged growth exponent, the
//! members still in their cage, `f_lc`, or `T_g / E_cb` against `solid_temperature`), and for a
//! mobile region fluid or gas (rule 5 along a line of constant Gamma: its jump, its inflection or
//! its fluid-gas coexistences; the per-point fallback `gas_temperature`; in a coexistence each
//! region by its own temperature, rule 3). A sheared scene is decided by `E_par` alone (rule 4).
//! The deciding regions are the whole system of a homogeneous point, or the dense and the
//! dilute region of a coexistence.
//!
//! The *criterion* of a label is one of those decisions:
//! - sheared: [`Criterion::EPar`];
//! - a region whose mobility was not measured (the thresholds asked for `D_lat` or `f_lc`, the
//!   run stored none): [`Criterion::TemperatureFallback`];
//! - else the deciding region (the whole system, or the dense region of a coexistence): its
//!   solid-or-mobile criterion when it is solid, else its fluid-or-gas criterion.
//!
//! A label rests on a *fallback* ([`DecidedBy::fallback`]) when a deciding region's mobility was
//! not measured, or a homogeneous mobile point's fluid-or-gas decision is the per-point
//! `gas_temperature` (no line, a line without a transition, or a point between the line's
//! fluid-gas coexistences).
//!
//! Which of the caged-motion test and the members-in-their-cage test made a region solid is
//! found by elimination (the classifier stores the growth exponent, not the lags the cage's
//! `MSD <= 1 d^2` bound reads): a solid region above `solid_diffusion` with at least
//! `still_members` of its members still is decided by them, any other by its cage. Whether a
//! point between a line's fluid-gas coexistences took the per-point fallback is read from the
//! line's words in `decided_on.reason` (the record has no field for it).

use super::classify::{DecisionInputs, FluidGasFrom, Mobility, Phase, RegionInputs, Thresholds};
use serde::{Deserialize, Serialize};

/// One criterion that decides (part of) a label.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Criterion {
    /// Solid or mobile by `D_lat` against `solid_diffusion`.
    Displacement,
    /// Solid by a caged mean-square displacement: growth exponent below `diffusive_exponent`
    /// within a diameter.
    Cage,
    /// Solid dense region: at least `still_members` of its members stay in their cage.
    MembersStill,
    /// Solid or mobile by `f_lc` against `solid_flc` (`mobility = "location_changes"`).
    LocationChanges,
    /// Solid or mobile by `T_g / E_cb` against `solid_temperature`, as the thresholds ask
    /// (`mobility = "temperature"`).
    Temperature,
    /// Solid or mobile by `T_g / E_cb` against `solid_temperature` because the mobility the
    /// thresholds ask for was not measured (no `D_lat`, or no `f_lc`, stored).
    TemperatureFallback,
    /// Fluid or gas by the jump of `T_g / E_cb` along the line of constant Gamma (elastic).
    LineJump,
    /// Fluid or gas by the inflection of `T_g / E_cb` along the line (inelastic).
    LineInflection,
    /// Fluid or gas by the line's fluid-gas coexistences (no transition on its curve).
    LineCoexistences,
    /// Fluid or gas by `T_g / E_cb` against the per-point `gas_temperature`: no line decided.
    GasTemperatureFallback,
    /// Fluid or gas by the point's own evidence against what its line said (rule 5: a gas's
    /// temperature and bridge count, or a fluid's, bound the line rule).
    OwnEvidence,
    /// A coexistence region fluid or gas by its own `T_g / E_cb` against `gas_temperature`
    /// (rule 3).
    RegionTemperature,
    /// A coexistence's dense region condensed although hotter than `gas_temperature`: its
    /// dilute region is at least `line_jump_ratio` times hotter (rule 3).
    DiluteHotter,
    /// A sheared scene: `E_par / E_cb` against `shear_e_par` (rule 4).
    EPar,
}

impl Criterion {
    /// Every criterion, in declaration order.
    pub const ALL: [Criterion; 14] = [
        Criterion::Displacement,
        Criterion::Cage,
        Criterion::MembersStill,
        Criterion::LocationChanges,
        Criterion::Temperature,
        Criterion::TemperatureFallback,
        Criterion::LineJump,
        Criterion::LineInflection,
        Criterion::LineCoexistences,
        Criterion::GasTemperatureFallback,
        Criterion::OwnEvidence,
        Criterion::RegionTemperature,
        Criterion::DiluteHotter,
        Criterion::EPar,
    ];

    /// The snake_case name (as serialized).
    pub fn name(self) -> &'static str {
        match self {
            Criterion::Displacement => "displacement",
            Criterion::Cage => "cage",
            Criterion::MembersStill => "members_still",
            Criterion::LocationChanges => "location_changes",
            Criterion::Temperature => "temperature",
            Criterion::TemperatureFallback => "temperature_fallback",
            Criterion::LineJump => "line_jump",
            Criterion::LineInflection => "line_inflection",
            Criterion::LineCoexistences => "line_coexistences",
            Criterion::GasTemperatureFallback => "gas_temperature_fallback",
            Criterion::OwnEvidence => "own_evidence",
            Criterion::RegionTemperature => "region_temperature",
            Criterion::DiluteHotter => "dilute_hotter",
            Criterion::EPar => "e_par",
        }
    }

    /// One upper-case letter for a phase map's cells (phase names are lower case).
    pub fn letter(self) -> char {
        match self {
            Criterion::Displacement => 'D',
            Criterion::Cage => 'C',
            Criterion::MembersStill => 'M',
            Criterion::LocationChanges => 'L',
            Criterion::Temperature => 'K',
            Criterion::TemperatureFallback => 'T',
            Criterion::LineJump => 'J',
            Criterion::LineInflection => 'I',
            Criterion::LineCoexistences => 'X',
            Criterion::GasTemperatureFallback => 'G',
            Criterion::OwnEvidence => 'O',
            Criterion::RegionTemperature => 'R',
            Criterion::DiluteHotter => 'V',
            Criterion::EPar => 'E',
        }
    }

    /// The criterion in words, for a legend.
    pub fn words(self) -> &'static str {
        match self {
            Criterion::Displacement => "displacement (D_lat against solid_diffusion)",
            Criterion::Cage => "cage (MSD growth exponent below diffusive_exponent)",
            Criterion::MembersStill => "members still in their cage (against still_members)",
            Criterion::LocationChanges => "location changes (f_lc against solid_flc)",
            Criterion::Temperature => "temperature (T_g against solid_temperature, as asked)",
            Criterion::TemperatureFallback => {
                "temperature fallback (mobility not measured: T_g against solid_temperature)"
            }
            Criterion::LineJump => "line jump of T_g/E_cb",
            Criterion::LineInflection => "line inflection of T_g/E_cb",
            Criterion::LineCoexistences => "the line's fluid-gas coexistences",
            Criterion::GasTemperatureFallback => {
                "gas-temperature fallback (no line decided: T_g against gas_temperature)"
            }
            Criterion::OwnEvidence => {
                "the point's own T_g/E_cb and bridges overruled its line (rule 5)"
            }
            Criterion::RegionTemperature => "a coexistence region's T_g against gas_temperature",
            Criterion::DiluteHotter => {
                "dense region condensed: dilute region line_jump_ratio hotter"
            }
            Criterion::EPar => "E_par against shear_e_par (sheared)",
        }
    }

    /// Whether the criterion is a fallback for one that was not available.
    pub fn is_fallback(self) -> bool {
        matches!(
            self,
            Criterion::TemperatureFallback | Criterion::GasTemperatureFallback
        )
    }
}

impl std::fmt::Display for Criterion {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// The region a decision is about.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Region {
    /// The whole system of a homogeneous point.
    Whole,
    /// The dense region of a coexistence (its cluster members).
    Dense,
    /// The dilute region of a coexistence.
    Dilute,
}

/// The decisions of one deciding region.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RegionDecision {
    pub region: Region,
    /// The phase rule 1 (and rule 5 for a homogeneous point) gave it.
    pub phase: Phase,
    /// What decided solid or mobile.
    pub mobility: Criterion,
    /// What decided fluid or gas (`None` for a solid region).
    pub fluid_gas: Option<Criterion>,
}

/// Which criterion decided a label, with the numbers compared (module doc).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DecidedBy {
    /// The label these decisions give.
    pub phase: Phase,
    /// The criterion that decided it (module doc).
    pub criterion: Criterion,
    /// Whether a fallback decided part of the label (module doc).
    pub fallback: bool,
    /// The deciding regions (empty for a sheared scene).
    pub regions: Vec<RegionDecision>,
    /// One line: the label, its criterion and the numbers compared.
    pub summary: String,
}

impl DecidedBy {
    /// The criterion of a classification's record.
    pub fn of(d: &DecisionInputs) -> DecidedBy {
        let th = &d.thresholds;
        let unit = if d.reason.contains("T_g/m g d") {
            "m g d"
        } else {
            "E_cb"
        };
        if let Some(e_par) = d.shear_e_par {
            let phase = if e_par <= th.shear_e_par {
                Phase::S
            } else {
                Phase::F
            };
            return DecidedBy {
                phase,
                criterion: Criterion::EPar,
                fallback: false,
                regions: Vec::new(),
                summary: format!(
                    "{phase} by E_par (sheared): E_par/{unit} {} {} shear_e_par {}",
                    sig(e_par),
                    cmp(e_par, th.shear_e_par),
                    sig(th.shear_e_par)
                ),
            };
        }
        match (d.split, &d.dense, &d.dilute) {
            (true, Some(dense), Some(dilute)) => coexistence(d, dense, dilute, unit),
            _ => homogeneous(d, unit),
        }
    }

    /// The criterion of a stored `decided_on` (`None` where it is not readable as a
    /// [`DecisionInputs`]: another version's record).
    pub fn of_json(decided_on: &serde_json::Value) -> Option<DecidedBy> {
        DecisionInputs::deserialize(decided_on)
            .ok()
            .map(|d| DecidedBy::of(&d))
    }
}

/// A homogeneous point: the whole system decides.
fn homogeneous(d: &DecisionInputs, unit: &str) -> DecidedBy {
    let th = &d.thresholds;
    let w = &d.whole;
    let mobility = mobility_criterion(w, th);
    let fluid_gas = (w.phase != Phase::S).then(|| homogeneous_fluid_gas(d));
    let criterion = match fluid_gas {
        Some(f) if mobility != Criterion::TemperatureFallback => f,
        _ => mobility,
    };
    let mob = mobility_text(w, mobility, th, unit);
    let head = format!("{} by {}", w.phase, criterion.name().replace('_', " "));
    let summary = match fluid_gas {
        None => format!("{head}: {mob}"),
        Some(f) if f == criterion => {
            format!(
                "{head}: {}; mobile: {mob}",
                homogeneous_fluid_gas_text(d, f, unit)
            )
        }
        Some(f) => format!(
            "{head}: mobile: {mob}; {}",
            homogeneous_fluid_gas_text(d, f, unit)
        ),
    };
    DecidedBy {
        phase: w.phase,
        criterion,
        fallback: mobility.is_fallback() || fluid_gas.is_some_and(Criterion::is_fallback),
        regions: vec![RegionDecision {
            region: Region::Whole,
            phase: w.phase,
            mobility,
            fluid_gas,
        }],
        summary,
    }
}

/// A coexistence: its dense and dilute regions decide, each by rule 1 and rule 3.
fn coexistence(
    d: &DecisionInputs,
    dense: &RegionInputs,
    dilute: &RegionInputs,
    unit: &str,
) -> DecidedBy {
    let th = &d.thresholds;
    let phase = Phase::coexistence(dense.phase, dilute.phase).unwrap_or(dense.phase);
    let decide = |r: &RegionInputs, region: Region| {
        let mobility = mobility_criterion(r, th);
        let fluid_gas = (r.phase != Phase::S).then(|| {
            let condensed_by_vapour = region == Region::Dense
                && r.temperature > th.gas_temperature
                && r.phase != Phase::G;
            if condensed_by_vapour {
                Criterion::DiluteHotter
            } else {
                Criterion::RegionTemperature
            }
        });
        RegionDecision {
            region,
            phase: r.phase,
            mobility,
            fluid_gas,
        }
    };
    let regions = vec![decide(dense, Region::Dense), decide(dilute, Region::Dilute)];
    let fallback = regions.iter().any(|r| r.mobility.is_fallback());
    let first = &regions[0];
    let criterion = if fallback {
        Criterion::TemperatureFallback
    } else {
        first.fluid_gas.unwrap_or(first.mobility)
    };
    let words = |r: &RegionDecision, inputs: &RegionInputs, name: &str| {
        let mut s = format!(
            "{name} part {} ({})",
            r.phase,
            mobility_text(inputs, r.mobility, th, unit)
        );
        if let Some(f) = r.fluid_gas {
            let t = inputs.temperature;
            let ratio = dilute.temperature / t;
            s.push_str(&match f {
                Criterion::DiluteHotter => format!(
                    ", condensed: T_g/{unit} {} > gas_temperature {} but the dilute part is {} \
                     times hotter (>= line_jump_ratio {})",
                    sig(t),
                    sig(th.gas_temperature),
                    sig(ratio),
                    sig(th.line_jump_ratio)
                ),
                _ => format!(
                    ", {}: T_g/{unit} {} {} gas_temperature {}",
                    if r.phase == Phase::G { "gas" } else { "fluid" },
                    sig(t),
                    cmp(t, th.gas_temperature),
                    sig(th.gas_temperature)
                ),
            });
        }
        s
    };
    let summary = format!(
        "{phase} by {} (coexistence: dense and dilute parts differ): {}; {}",
        criterion.name().replace('_', " "),
        words(&regions[0], dense, "dense"),
        words(&regions[1], dilute, "dilute")
    );
    DecidedBy {
        phase,
        criterion,
        fallback,
        regions,
        summary,
    }
}

/// What decided solid or mobile in a region (module doc for the cage and the members).
fn mobility_criterion(r: &RegionInputs, th: &Thresholds) -> Criterion {
    match r.mobility_from {
        Mobility::Temperature if th.mobility == Mobility::Temperature => Criterion::Temperature,
        Mobility::Temperature => Criterion::TemperatureFallback,
        Mobility::LocationChanges => Criterion::LocationChanges,
        Mobility::Displacement => {
            let above = r.diffusion.is_some_and(|x| x > th.solid_diffusion);
            if r.phase != Phase::S || !above {
                Criterion::Displacement
            } else if r.members_still.is_some_and(|f| f >= th.still_members) {
                Criterion::MembersStill
            } else {
                Criterion::Cage
            }
        }
    }
}

/// A region's solid-or-mobile decision in words, with the numbers compared.
fn mobility_text(r: &RegionInputs, c: Criterion, th: &Thresholds, unit: &str) -> String {
    let d_lat = |x: f64| {
        format!(
            "D_lat {} {} solid_diffusion {}",
            sig(x),
            cmp(x, th.solid_diffusion),
            sig(th.solid_diffusion)
        )
    };
    let exponent = |a: f64| {
        format!(
            "MSD growth exponent {} {} diffusive_exponent {}",
            sig(a),
            if a < th.diffusive_exponent { "<" } else { ">=" },
            sig(th.diffusive_exponent)
        )
    };
    let still = |f: f64| {
        format!(
            "members still in their cage {} {} still_members {}",
            sig(f),
            if f >= th.still_members { ">=" } else { "<" },
            sig(th.still_members)
        )
    };
    let temperature = |what: &str| {
        format!(
            "T_g/{unit} {} {} solid_temperature {}{what}",
            sig(r.temperature),
            cmp(r.temperature, th.solid_temperature),
            sig(th.solid_temperature)
        )
    };
    let d = r.diffusion.unwrap_or(f64::NAN);
    match c {
        Criterion::Cage => format!(
            "{} within a diameter; {}",
            exponent(r.growth_exponent.unwrap_or(f64::NAN)),
            d_lat(d)
        ),
        Criterion::MembersStill => format!(
            "{}; {}",
            still(r.members_still.unwrap_or(f64::NAN)),
            d_lat(d)
        ),
        Criterion::Displacement => {
            let mut s = d_lat(d);
            if r.phase != Phase::S {
                if let Some(a) = r.growth_exponent {
                    s.push_str(", ");
                    s.push_str(&exponent(a));
                    if a < th.diffusive_exponent {
                        s.push_str(" but spread beyond a cage");
                    }
                }
                if let Some(f) = r.members_still {
                    s.push_str(", ");
                    s.push_str(&still(f));
                }
            }
            s
        }
        Criterion::LocationChanges => {
            let f = r.flc.unwrap_or(f64::NAN);
            let hot = r.phase != Phase::S && f <= th.solid_flc;
            format!(
                "f_lc {} {} solid_flc {}{}",
                sig(f),
                cmp(f, th.solid_flc),
                sig(th.solid_flc),
                if hot {
                    format!(" but T_g/{unit} above gas_temperature")
                } else {
                    String::new()
                }
            )
        }
        Criterion::TemperatureFallback => temperature(match th.mobility {
            Mobility::LocationChanges => " (mobility not measured: no f_lc counted)",
            _ => " (mobility not measured: no D_lat stored, e.g. a window shorter than the lag)",
        }),
        _ => temperature(""),
    }
}

/// What decided fluid or gas of a homogeneous mobile point.
fn homogeneous_fluid_gas(d: &DecisionInputs) -> Criterion {
    match &d.fluid_gas {
        FluidGasFrom::Line { method, .. } => match method.as_str() {
            "jump" => Criterion::LineJump,
            "inflection" => Criterion::LineInflection,
            // Between the coexistences in E* or T_g the per-point fallback decides
            // (`observe::line`); the record says so in the reason only.
            _ if d.reason.contains("per-point fallback") => Criterion::GasTemperatureFallback,
            _ => Criterion::LineCoexistences,
        },
        FluidGasFrom::PointFallback | FluidGasFrom::LineWithoutTransition { .. } => {
            Criterion::GasTemperatureFallback
        }
        FluidGasFrom::OwnEvidence { .. } => Criterion::OwnEvidence,
    }
}

/// A homogeneous point's fluid-or-gas decision in words.
fn homogeneous_fluid_gas_text(d: &DecisionInputs, c: Criterion, unit: &str) -> String {
    let th = &d.thresholds;
    let t = d.whole.temperature;
    let what = if d.whole.phase == Phase::G {
        "gas"
    } else {
        "fluid"
    };
    let fallback = format!(
        "{what}: T_g/{unit} {} {} gas_temperature {}",
        sig(t),
        cmp(t, th.gas_temperature),
        sig(th.gas_temperature)
    );
    match (&d.fluid_gas, c) {
        (
            FluidGasFrom::Line {
                gamma,
                method,
                e_star_boundary,
            },
            Criterion::LineJump | Criterion::LineInflection | Criterion::LineCoexistences,
        ) => format!(
            "{what} by the line at Gamma {}: {} boundary at E* {} (T_g/{unit} {})",
            sig(*gamma),
            method,
            sig(*e_star_boundary),
            sig(t)
        ),
        (FluidGasFrom::Line { gamma, .. }, _) => format!(
            "{fallback} (between the fluid-gas coexistences of the line at Gamma {})",
            sig(*gamma)
        ),
        (FluidGasFrom::LineWithoutTransition { gamma, method, .. }, _) => format!(
            "{fallback} (the line at Gamma {} shows no {method})",
            sig(*gamma)
        ),
        (FluidGasFrom::PointFallback, _) => format!("{fallback} (no line of constant Gamma)"),
        (
            FluidGasFrom::OwnEvidence {
                gamma,
                method,
                line_said,
                ..
            },
            _,
        ) => format!(
            "{what} by its own T_g/{unit} {} and bridges per grain, although the {} of the \
             line at Gamma {} said {}",
            sig(t),
            method,
            sig(*gamma),
            line_said
        ),
    }
}

/// The operator that holds between `x` and threshold `t` (a value equal to a threshold stays
/// on the calmer side).
fn cmp(x: f64, t: f64) -> &'static str {
    if x > t { ">" } else { "<=" }
}

/// `x` to 3 significant digits, without trailing zeros or float noise (`0.49999999999999994`
/// reads `0.5`); an exponent below `1e-3` and from `1e5` on.
pub fn sig(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let e = x.abs().log10().floor() as i32;
    // The rounding may carry into the next decade (9.996 -> 10.0).
    let rounded: f64 = format!("{x:.2e}").parse().unwrap_or(x);
    let e = if rounded.abs() >= 10f64.powi(e + 1) {
        e + 1
    } else {
        e
    };
    let trim = |s: String| {
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        }
    };
    if !(-3..5).contains(&e) {
        let text = format!("{x:.2e}");
        let (mantissa, exp) = text.split_once('e').unwrap_or((&text, "0"));
        return format!("{}e{exp}", trim(mantissa.to_string()));
    }
    let decimals = (2 - e).max(0) as usize;
    trim(format!("{rounded:.decimals$}"))
}

#[cfg(test)]
mod tests {
    use super::sig;

    #[test]
    fn three_significant_digits_without_float_noise() {
        assert_eq!(sig(0.49999999999999994), "0.5");
        assert_eq!(sig(1.046), "1.05");
        assert_eq!(sig(30.000000001), "30");
        assert_eq!(sig(0.001), "0.001");
        assert_eq!(sig(2.2e-4), "2.2e-4");
        assert_eq!(sig(1e-3 * 0.5), "5e-4");
        assert_eq!(sig(9.996), "10");
        assert_eq!(sig(123456.0), "1.23e5");
        assert_eq!(sig(-0.0213), "-0.0213");
        assert_eq!(sig(0.0), "0");
    }
}
