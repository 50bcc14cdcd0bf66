//! The trust marks of stored results (docs/observables.md "Run to a settled label"): the verdict
//! on a result's label (`observe::settling::Verdict`, `PointRow::trust`) shows as no mark
//! (stationary), [`LABEL_KEPT`] (every region settled, some quantity still moving in a
//! direction that cannot change the label) or [`NOT_STATIONARY`] (not settled); and the regions
//! and quantities that did not settle, in words.

use wetgran_core::observe::Verdict;
use wetgran_core::observe::settling::Settling;

/// The mark of a result whose label may still change (not settled).
pub const NOT_STATIONARY: char = '?';

/// The mark of a result that is not stationary but whose regions have all settled: the label is
/// safe, its numbers still drift.
pub const LABEL_KEPT: char = '~';

/// The mark of a verdict.
pub fn mark(verdict: Verdict) -> Option<char> {
    match verdict {
        Verdict::Stationary => None,
        Verdict::LabelKept => Some(LABEL_KEPT),
        Verdict::NotSettled => Some(NOT_STATIONARY),
    }
}

/// The regions and quantities of a stored decision that did not settle, in words
/// (`dense (f): member_temperature falling`); empty where everything settled or the decision
/// carries no verdict.
pub fn unsettled(decided_on: &serde_json::Value) -> Vec<String> {
    decided_on
        .get("settling")
        .and_then(|s| serde_json::from_value::<Settling>(s.clone()).ok())
        .map(|s| s.unsettled_text())
        .unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn each_verdict_has_its_mark() {
        assert_eq!(mark(Verdict::Stationary), None);
        assert_eq!(mark(Verdict::LabelKept), Some(LABEL_KEPT));
        assert_eq!(mark(Verdict::NotSettled), Some(NOT_STATIONARY));
    }

    #[test]
    fn the_unsettled_quantities_are_named() {
        let d = json!({"settling": {"verdict": "not_settled", "regions": [
            {"region": "whole", "phase": "fgc", "quantities": [
                {"quantity": "member_fraction", "direction": "flat", "allowed": "flat"}]},
            {"region": "dense", "phase": "f", "quantities": [
                {"quantity": "member_temperature", "direction": "falling", "allowed": "flat"},
                {"quantity": "member_mobility", "direction": "flat", "allowed": "flat"}]}]}});
        assert_eq!(unsettled(&d), vec!["dense (f): member_temperature falling"]);
        assert!(unsettled(&json!({})).is_empty());
    }
}
