//! The thin-thread capillary bridge (docs/model.md 3.2): a hysteretic square well of width `s_crit`
//! and depth `E_cb` that exists only after contact.

use serde::{Deserialize, Serialize};

/// The energy criterion at `s = s_crit` (docs/model.md 3.2); the scene's `capillary.rupture_rule`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RuptureRule {
    /// `1/2 mu (v_ij . n)^2 > E_cb` with `mu = m/2`; a rupture removes exactly `E_cb`.
    #[default]
    ReducedMass,
    /// The thesis appendix A: `1/2 m (v_ij . n)^2 > E_cb`; a rupture removes `E_cb / 2`.
    ThesisAppendix,
}

/// What happens when a bonded pair separates to `s = s_crit`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum WellOutcome {
    /// The bridge holds: the normal relative velocity is reversed (elastic reflection off the
    /// well wall). Carries the new normal relative speed (`-u`).
    Bounce(f64),
    /// The bridge ruptures. Carries the new normal relative speed and the energy removed.
    Rupture { new_normal_speed: f64, energy: f64 },
}

/// Decides bounce or rupture for normal relative speed `u = v_ij . n > 0` (n from j to i).
///
/// Reduced-mass rule (default): the normal kinetic energy is `mu u^2 / 2`, `mu = m/2`; if it
/// exceeds `E_cb` the bridge ruptures and exactly `E_cb` is removed:
/// `u' = sqrt(u^2 - 2 E_cb / mu)`.
/// Thesis-appendix rule: the criterion is `m u^2 / 2 > E_cb` and `u' = sqrt(u^2 - 2 E_cb / m)`,
/// which removes `E_cb / 2` of the system's energy.
#[inline]
pub(crate) fn well_outcome(mass: f64, u: f64, e_cb: f64, rule: RuptureRule) -> WellOutcome {
    let (inertia, removed_fraction) = match rule {
        RuptureRule::ReducedMass => (0.5 * mass, 1.0),
        RuptureRule::ThesisAppendix => (mass, 0.5),
    };
    let e_normal = 0.5 * inertia * u * u;
    if e_normal > e_cb {
        let u2 = (u * u - 2.0 * e_cb / inertia).max(0.0);
        WellOutcome::Rupture {
            new_normal_speed: u2.sqrt(),
            energy: removed_fraction * e_cb,
        }
    } else {
        WellOutcome::Bounce(-u)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_rule_removes_its_share_of_ecb_and_bounces_below_its_threshold() {
        let (m, e_cb) = (1.0, 0.2844);
        // Above each rule's threshold (reduced mass: mu u^2/2 = 1; thesis: m u^2/2 = 0.5).
        for (rule, u, removed) in [
            (RuptureRule::ReducedMass, 2.0, e_cb),
            (RuptureRule::ThesisAppendix, 1.0, 0.5 * e_cb),
        ] {
            match well_outcome(m, u, e_cb, rule) {
                WellOutcome::Rupture {
                    new_normal_speed: u2,
                    energy,
                } => {
                    assert_eq!(energy, removed);
                    // Equal masses, only the normal relative motion changes: dE = mu/2 (u2^2 - u^2).
                    assert!((0.25 * m * (u2 * u2 - u * u) + removed).abs() < 1e-14);
                }
                o => panic!("{rule:?}: expected rupture, got {o:?}"),
            }
        }
        // Just below threshold: mu u^2 / 2 = 0.9 E_cb -> bounce.
        let u = (0.9 * e_cb * 4.0 / m).sqrt();
        assert_eq!(
            well_outcome(m, u, e_cb, RuptureRule::ReducedMass),
            WellOutcome::Bounce(-u)
        );
        // Between the two thresholds the rules disagree: reduced mass bounces.
        let u = (3.0 * e_cb / m).sqrt(); // m u^2/2 = 1.5 E_cb, mu u^2/2 = 0.75 E_cb
        assert!(matches!(
            well_outcome(m, u, e_cb, RuptureRule::ReducedMass),
            WellOutcome::Bounce(_)
        ));
        assert!(matches!(
            well_outcome(m, u, e_cb, RuptureRule::ThesisAppendix),
            WellOutcome::Rupture { .. }
        ));
    }
}
