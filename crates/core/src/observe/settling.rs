//! Whether a run's label is settled (docs/observables.md "Run to a settled label"): the history
//! of every region its label names, quantity by quantity, against the trends that cannot change
//! that region's phase. The verdict is the one answer to "did this run settle?": the run policy
//! stops on it (`observe::run_observed_from`), the reports read it, and it is recomputed whenever
//! a label changes (`reclassify`, the line rule), because what may drift depends on the label.
//!
//! **Regions.** A homogeneous label (s, f, g) names one region, the whole system. A coexistence
//! names two: its dense part, followed here by the grains that are members of bonded clusters
//! (`observe::clusters`, the grains the classifier describes the dense region by), and its
//! dilute part, followed by the grains that are not.
//!
//! **Series.** The whole system's `T_g / E_cb`, bridges per grain and `Delta n_cb` are sampled at
//! every observer sample (`observe::trend`). The regions' own quantities come from a lateral
//! observer that runs over the whole history from the transient floor on (not window by window),
//! one value per block of a driving period, or of a whole fraction of a slow drive's period no
//! longer than [`MAX_BLOCK_TIME`] and than a [`MIN_WINDOW_BLOCKS`]-th of the first window
//! (blocks merge as the history grows, `observe::lateral`): the member fraction, the members' and the other grains' temperatures,
//! the lateral mobility `D_lat` of all grains, of the members and of the others over the long
//! lag, and the fraction of members that stay in their cage (within `solid_diffusion` of the
//! grains they were bonded to, over the long lag). [`region_series`] builds them.
//!
//! **Directions.** Each quantity's block test over the tested history (`observe::trend`,
//! `observe::convergence::block_test`) reads as [`Direction::Flat`] (blocks agree and no drift
//! beyond its error and the tolerance), rising or falling (a drift beyond them), unsteady (blocks
//! disagree without a drift: steps, oscillations) or unknown (too few values to test).
//!
//! **Rule** ([`allowed`]): a region is settled when each of its quantities is flat or moves in a
//! direction that cannot change the region's phase:
//!
//! | region phase | temperature | mobility | members still | member fraction | bridges | `Delta n_cb` |
//! |---|---|---|---|---|---|---|
//! | solid | not rising | not rising | not falling | not falling | not falling | not rising |
//! | fluid | flat | flat | flat | flat | flat | flat |
//! | gas | not falling | not falling | | not rising | not rising | not rising |
//!
//! (The whole system of a homogeneous label is held to its temperature, mobility, member
//! fraction, bridges and `Delta n_cb`; a coexistence's dense part to its members' temperature,
//! mobility and members still; its dilute part to its grains' temperature and mobility.)
//! A solid still cooling, stiffening or bonding more is still solid; a fluid may freeze or boil,
//! so every quantity of a fluid region must be flat; a gas still heating stays a gas as long as
//! nothing condenses (member fraction, bridges per grain and `Delta n_cb` not rising). A
//! coexistence also needs its member fraction flat (the split between its regions has settled;
//! a growing drop may swallow its vapour, a shrinking one evaporate) and its `Delta n_cb` not
//! falling (drops may merge into fewer, larger ones, not dissolve).
//!
//! **Verdict** ([`Verdict`]): stationary when the history relaxed and every quantity the label
//! names is flat; label kept when every region is settled but some quantity still moves in an
//! allowed direction; not settled otherwise, with the regions and quantities that were not
//! ([`RegionSettling::unsettled`]).

use super::Phase;
use super::convergence::BlockTest;
use super::lateral::{Block, LateralObserver, field};
use super::trend::BlockSeries;
use serde::{Deserialize, Serialize};
use std::fmt;

/// The member fraction of the bonded clusters (members over grains), per block.
pub const MEMBER_FRACTION: &str = "member_fraction";
/// `D_lat` of all grains over the long lag, per block.
pub const MOBILITY: &str = "mobility";
/// `T_g / E_cb` of the members, each bin's members about their own mean velocity, per block.
pub const MEMBER_TEMPERATURE: &str = "member_temperature";
/// `D_lat` of the members (relative to their cluster's rigid motion), per block.
pub const MEMBER_MOBILITY: &str = "member_mobility";
/// The fraction of members that stay within `solid_diffusion` of their cage, per block.
pub const MEMBERS_STILL: &str = "members_still";
/// `T_g / E_cb` of the grains that are not members, per block.
pub const UNBONDED_TEMPERATURE: &str = "unbonded_temperature";
/// `D_lat` of the grains that are not members, per block.
pub const UNBONDED_MOBILITY: &str = "unbonded_mobility";

/// Longest first block of the regions' observer, time units: a slow drive's period is cut into
/// this many equal parts or more, so that a run of a few periods still gives the tests enough
/// values (the big blocks of the block test average the drive's oscillation out again).
pub(crate) const MAX_BLOCK_TIME: f64 = 1.0;

/// Fewest blocks of the regions' observer in the first window: a block test of 4 blocks needs
/// at least 8 values, and the test of a history that has not relaxed takes its second half.
pub(crate) const MIN_WINDOW_BLOCKS: f64 = 16.0;

/// The regions' first block length for a drive of period `period` and a first window `window`
/// time units long: the period, or the largest whole fraction of it no longer than
/// [`MAX_BLOCK_TIME`] and than `window / MIN_WINDOW_BLOCKS`.
pub(crate) fn block_time(period: f64, window: f64) -> f64 {
    let longest = if window > 0.0 {
        MAX_BLOCK_TIME.min(window / MIN_WINDOW_BLOCKS)
    } else {
        MAX_BLOCK_TIME
    };
    period / (period / longest).ceil().max(1.0)
}

/// Tolerance floor of the member fractions (a change of a few hundredths of the grains joining
/// or leaving clusters is nothing to the phase).
pub(crate) const FLOOR_FRACTION: f64 = 0.05;

/// The region quantities of the blocks of `monitor` (module doc), `solid_diffusion` the
/// mobility at which a member counts as still, `temperature_floor` the tolerance floor of the
/// temperatures.
pub(crate) fn region_series(
    monitor: &LateralObserver,
    dimension: usize,
    solid_diffusion: f64,
    temperature_floor: f64,
) -> Vec<BlockSeries> {
    // The open last block is kept once it holds half the samples of the others.
    let mut counts: Vec<u64> = monitor.blocks.iter().map(|b| b.samples).collect();
    counts.pop();
    counts.sort_unstable();
    let typical = counts.get(counts.len() / 2).copied().unwrap_or(0);
    let last = monitor.blocks.len().saturating_sub(1);
    let blocks: Vec<&Block> = monitor
        .blocks
        .iter()
        .enumerate()
        .filter(|&(i, b)| i < last || 2 * b.samples >= typical)
        .map(|(_, b)| b)
        .collect();
    let nb = monitor.bins().n;
    let total = |b: &Block, f: usize| -> f64 { (0..nb).map(|k| b.get(k, f)).sum() };
    let ratio = |a: f64, w: f64| if w > 0.0 { a / w } else { f64::NAN };
    let n_lat = (dimension.max(2) - 1) as f64;
    let d_scale = 1.0 / (2.0 * n_lat * monitor.lag());
    let still = |b: &Block| -> f64 {
        let cages = crate::observe::profiles::CageCounts {
            edges: super::lateral::CAGE_EDGES.to_vec(),
            measured: vec![total(b, field::CAGE_N)],
            within: vec![
                (0..super::lateral::CAGE_EDGES.len())
                    .map(|k| total(b, field::CAGE_WITHIN + k))
                    .collect(),
            ],
        };
        cages
            .fraction_within(&[0], solid_diffusion)
            .unwrap_or(f64::NAN)
    };
    type Of<'a> = Box<dyn Fn(&Block) -> f64 + 'a>;
    let quantities: Vec<(&'static str, f64, Of<'_>)> = vec![
        (
            MEMBER_FRACTION,
            FLOOR_FRACTION,
            Box::new(|b| ratio(total(b, field::CLUSTERED), total(b, field::PARTICLES))),
        ),
        (
            MOBILITY,
            solid_diffusion,
            Box::new(|b| d_scale * ratio(total(b, field::MSD_ALL), total(b, field::MSD_ALL_N))),
        ),
        (
            MEMBER_TEMPERATURE,
            temperature_floor,
            Box::new(|b| ratio(total(b, field::T_CL), total(b, field::T_CL_W))),
        ),
        (
            MEMBER_MOBILITY,
            solid_diffusion,
            Box::new(|b| d_scale * ratio(total(b, field::MSD_CL), total(b, field::MSD_CL_N))),
        ),
        (MEMBERS_STILL, FLOOR_FRACTION, Box::new(still)),
        (
            UNBONDED_TEMPERATURE,
            temperature_floor,
            Box::new(|b| ratio(total(b, field::T_UB), total(b, field::T_UB_W))),
        ),
        (
            UNBONDED_MOBILITY,
            solid_diffusion,
            Box::new(|b| {
                let msd = total(b, field::MSD_ALL) - total(b, field::MSD_CL);
                let n = total(b, field::MSD_ALL_N) - total(b, field::MSD_CL_N);
                d_scale * ratio(msd, n)
            }),
        ),
    ];
    quantities
        .into_iter()
        .map(|(name, floor, of)| {
            let (time, values) = blocks
                .iter()
                .map(|b| (0.5 * (b.t0 + b.t1), of(b)))
                .filter(|(_, v)| v.is_finite())
                .unzip();
            BlockSeries {
                name,
                floor,
                time,
                values,
            }
        })
        .collect()
}

/// Which way a quantity went over the tested history.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Direction {
    /// The blocks agree and there is no drift beyond the errors and the tolerance.
    Flat,
    Rising,
    Falling,
    /// The blocks disagree without a drift (steps, oscillations).
    Unsteady,
    /// Too few values to test.
    Unknown,
}

impl Direction {
    /// The direction a block test reads as.
    pub fn of(test: &BlockTest) -> Direction {
        if test.block_means.len() < 2 || !test.drift.is_finite() {
            Direction::Unknown
        } else if test.ok() {
            Direction::Flat
        } else if !test.no_trend {
            if test.drift > 0.0 {
                Direction::Rising
            } else {
                Direction::Falling
            }
        } else {
            Direction::Unsteady
        }
    }

    /// The stored name.
    pub fn name(self) -> &'static str {
        match self {
            Direction::Flat => "flat",
            Direction::Rising => "rising",
            Direction::Falling => "falling",
            Direction::Unsteady => "unsteady",
            Direction::Unknown => "unknown",
        }
    }
}

impl fmt::Display for Direction {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// What a quantity may do without changing a region's phase.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Allowed {
    Flat,
    NotRising,
    NotFalling,
}

impl Allowed {
    /// Whether `d` is allowed.
    pub fn admits(self, d: Direction) -> bool {
        match self {
            Allowed::Flat => d == Direction::Flat,
            Allowed::NotRising => matches!(d, Direction::Flat | Direction::Falling),
            Allowed::NotFalling => matches!(d, Direction::Flat | Direction::Rising),
        }
    }
}

/// The part of the system a region of a label is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Region {
    /// A homogeneous label's only region.
    Whole,
    /// A coexistence's dense part (the members of bonded clusters).
    Dense,
    /// A coexistence's dilute part (the other grains).
    Dilute,
}

impl Region {
    /// The stored name.
    pub fn name(self) -> &'static str {
        match self {
            Region::Whole => "whole",
            Region::Dense => "dense",
            Region::Dilute => "dilute",
        }
    }
}

/// The roles a quantity plays for a region's phase.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Role {
    Temperature,
    Mobility,
    Still,
    Members,
    Bridges,
    Contrast,
    /// A sheared scene's `E_par`, the shear drive's order parameter.
    Drive,
}

/// The quantity that plays `role` for `region` (`None`: that region has none).
fn quantity(region: Region, role: Role) -> Option<&'static str> {
    use super::trend::{BRIDGES, DELTA_N_CB, TEMPERATURE};
    match (region, role) {
        (Region::Whole, Role::Temperature) => Some(TEMPERATURE),
        (Region::Whole, Role::Mobility) => Some(MOBILITY),
        (Region::Whole, Role::Members) => Some(MEMBER_FRACTION),
        (Region::Whole, Role::Bridges) => Some(BRIDGES),
        (Region::Whole, Role::Contrast) => Some(DELTA_N_CB),
        (Region::Whole, Role::Drive) => Some(super::trend::E_PAR),
        (Region::Dense, Role::Temperature) => Some(MEMBER_TEMPERATURE),
        (Region::Dense, Role::Mobility) => Some(MEMBER_MOBILITY),
        (Region::Dense, Role::Still) => Some(MEMBERS_STILL),
        (Region::Dilute, Role::Temperature) => Some(UNBONDED_TEMPERATURE),
        (Region::Dilute, Role::Mobility) => Some(UNBONDED_MOBILITY),
        _ => None,
    }
}

/// What `role` may do in a region of `phase` (`None`: no constraint). The module doc's table.
fn allowed_for(phase: Phase, role: Role) -> Option<Allowed> {
    use Allowed::{Flat, NotFalling, NotRising};
    match (phase, role) {
        (Phase::S, Role::Temperature | Role::Mobility | Role::Contrast | Role::Drive) => {
            Some(NotRising)
        }
        (Phase::S, Role::Still | Role::Members | Role::Bridges) => Some(NotFalling),
        (Phase::F, _) => Some(Flat),
        (Phase::G, Role::Temperature | Role::Mobility | Role::Drive) => Some(NotFalling),
        (Phase::G, Role::Members | Role::Bridges | Role::Contrast) => Some(NotRising),
        _ => None,
    }
}

/// The quantities a region of `phase` is held to, with what each may do.
pub fn allowed(region: Region, phase: Phase) -> Vec<(&'static str, Allowed)> {
    const ROLES: [Role; 7] = [
        Role::Temperature,
        Role::Mobility,
        Role::Still,
        Role::Members,
        Role::Bridges,
        Role::Contrast,
        Role::Drive,
    ];
    ROLES
        .into_iter()
        .filter_map(|r| Some((quantity(region, r)?, allowed_for(phase, r)?)))
        .collect()
}

/// One quantity of a region's verdict.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct QuantityVerdict {
    pub quantity: String,
    pub direction: Direction,
    pub allowed: Allowed,
}

impl QuantityVerdict {
    /// Whether the direction is allowed.
    pub fn settled(&self) -> bool {
        self.allowed.admits(self.direction)
    }
}

/// One region of a label and its quantities.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RegionSettling {
    pub region: Region,
    pub phase: Phase,
    pub quantities: Vec<QuantityVerdict>,
}

impl RegionSettling {
    /// Every quantity flat or moving in an allowed direction.
    pub fn settled(&self) -> bool {
        self.quantities.iter().all(QuantityVerdict::settled)
    }

    /// The quantities that were not settled.
    pub fn unsettled(&self) -> impl Iterator<Item = &QuantityVerdict> {
        self.quantities.iter().filter(|q| !q.settled())
    }
}

/// The one answer to "did this run settle?".
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// The history relaxed and every quantity the label names is flat.
    Stationary,
    /// Every region is settled, some quantity still moves in a direction that cannot change
    /// its region's phase: the label is safe, its numbers still drift.
    LabelKept,
    /// Some region is not settled: more time may change the label.
    NotSettled,
}

impl Verdict {
    /// Every verdict, in storage order.
    pub const ALL: [Verdict; 3] = [Verdict::Stationary, Verdict::LabelKept, Verdict::NotSettled];

    /// The stored name.
    pub fn name(self) -> &'static str {
        match self {
            Verdict::Stationary => "stationary",
            Verdict::LabelKept => "label_kept",
            Verdict::NotSettled => "not_settled",
        }
    }

    /// Parses a stored name.
    pub fn parse(s: &str) -> Option<Verdict> {
        Self::ALL.into_iter().find(|v| v.name() == s)
    }

    /// Whether the label may carry a phase boundary.
    pub fn label_trusted(self) -> bool {
        self != Verdict::NotSettled
    }
}

impl fmt::Display for Verdict {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A label's verdict with the regions it rests on.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Settling {
    pub verdict: Verdict,
    pub regions: Vec<RegionSettling>,
}

impl Settling {
    /// The regions and quantities that did not settle, in words (`dense (f): member_temperature
    /// falling`), empty when settled.
    pub fn unsettled_text(&self) -> Vec<String> {
        self.regions
            .iter()
            .flat_map(|r| {
                r.unsettled().map(move |q| {
                    format!(
                        "{} ({}): {} {}",
                        r.region.name(),
                        r.phase,
                        q.quantity,
                        q.direction
                    )
                })
            })
            .collect()
    }
}

/// The verdict of a label: `phase` the label, `parts` the phases of its dense and dilute regions
/// for a coexistence, `unrelaxed` the quantities whose history had not relaxed
/// (`observe::trend`), `tests` every tested quantity (sampled and per block). A quantity the label names without a test (not
/// observed: a dry scene's bridges, a gas without members) is left out; one with a test that
/// could not decide reads unknown and is not settled.
pub fn settle(
    phase: Phase,
    parts: Option<(Phase, Phase)>,
    unrelaxed: &[String],
    tests: &[BlockTest],
) -> Settling {
    let direction = |q: &str| tests.iter().find(|t| t.quantity == q).map(Direction::of);
    let region = |region: Region, phase: Phase, extra: &[(&'static str, Allowed)]| {
        let quantities = allowed(region, phase)
            .into_iter()
            .chain(extra.iter().copied())
            .filter_map(|(q, allowed)| {
                Some(QuantityVerdict {
                    quantity: q.to_string(),
                    direction: direction(q)?,
                    allowed,
                })
            })
            .collect();
        RegionSettling {
            region,
            phase,
            quantities,
        }
    };
    let regions = match parts {
        None => vec![region(Region::Whole, phase, &[])],
        Some((dense, dilute)) => vec![
            region(
                Region::Whole,
                phase,
                &[
                    (MEMBER_FRACTION, Allowed::Flat),
                    (super::trend::DELTA_N_CB, Allowed::NotFalling),
                ],
            ),
            region(Region::Dense, dense, &[]),
            region(Region::Dilute, dilute, &[]),
        ],
    };
    let named = || regions.iter().flat_map(|r| &r.quantities);
    let all_flat = named().all(|q| q.direction == Direction::Flat);
    let relaxed = named().all(|q| !unrelaxed.contains(&q.quantity));
    let verdict = if !regions.iter().all(RegionSettling::settled) {
        Verdict::NotSettled
    } else if relaxed && all_flat {
        Verdict::Stationary
    } else {
        Verdict::LabelKept
    };
    Settling { verdict, regions }
}

#[cfg(test)]
mod tests;
