//! How far a stored result can be trusted, from its stored observables and label: the one place
//! the sweep commands (`sweep status`, `show`, `boundaries`, `plot`, `export`) read that verdict
//! from (docs/observables.md "Run to stationarity").
//!
//! A result with a trend state (`observe::trend`) is trusted when it is `stationary`; a heating
//! gas, a cooling solid and a coarsening coexistence are trusted *for their label* (more time
//! cannot change it) and marked [`LABEL_KEPT`]; cooling and undecided results are marked [`NOT_STATIONARY`]. A
//! result stored before trend states existed falls back to its convergence verdict, or its
//! first-half/second-half stationarity check.

use wetgran_core::observe::trend::{self, TrendState, Trust};

/// The mark of a result whose label may still change (not stationary, and no trend that keeps
/// its label).
pub const NOT_STATIONARY: char = '?';

/// The mark of a result that is not stationary but whose trend cannot change its label (a
/// heating gas, a cooling solid, a coarsening coexistence): the label is safe, its numbers
/// still drift.
pub const LABEL_KEPT: char = '~';

/// The stored trend state of a result (`observables.trend.state`), `None` for results stored
/// before trend states existed.
pub fn trend(observables: &serde_json::Value) -> Option<TrendState> {
    observables
        .get("trend")
        .and_then(|t| t.get("state"))
        .and_then(|s| s.as_str())
        .and_then(TrendState::parse)
}

/// Whether a result is stationary: the run-length policy's convergence verdict where the run
/// had one, else its stationarity check (`observe::converged_in_json`); `None` where the stored
/// observables carry no verdict (a result written before the check existed).
pub fn stationary(observables: &serde_json::Value) -> Option<bool> {
    wetgran_core::observe::converged_in_json(observables)
}

/// The trust mark of a result with label `phase`: `None` for a stationary one, [`LABEL_KEPT`]
/// for a trend that cannot change the label, [`NOT_STATIONARY`] otherwise (see the module doc).
pub fn trust_mark(observables: &serde_json::Value, phase: Option<&str>) -> Option<char> {
    let phase = phase.and_then(|p| p.parse::<wetgran_core::observe::Phase>().ok());
    mark(trend::trust(
        trend(observables),
        stationary(observables),
        phase,
    ))
}

/// The mark of a trust level.
pub fn mark(trust: Trust) -> Option<char> {
    match trust {
        Trust::Stationary => None,
        Trust::LabelKept => Some(LABEL_KEPT),
        Trust::MayChange => Some(NOT_STATIONARY),
    }
}

/// The failed checks of a result, in words (`T_g: first half 1.2, second half 1.5, +25 %`).
pub fn failed_checks(observables: &serde_json::Value) -> Vec<String> {
    let Some(checks) = observables
        .get("stationarity")
        .and_then(|s| s.get("checks"))
        .and_then(|c| c.as_array())
    else {
        return Vec::new();
    };
    checks
        .iter()
        .filter(|c| c.get("ok").and_then(|v| v.as_bool()) == Some(false))
        .map(|c| {
            let num = |k: &str| c.get(k).and_then(|v| v.as_f64()).unwrap_or(f64::NAN);
            format!(
                "{}: first half {:.4}, second half {:.4}, relative change {:.3}",
                c.get("quantity").and_then(|v| v.as_str()).unwrap_or("?"),
                num("first_half"),
                num("second_half"),
                num("relative_change")
            )
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn a_failed_stationarity_check_marks_the_result() {
        let bad = json!({"stationarity": {"tolerance": 0.1, "stationary": false, "checks": [
            {"quantity": "T_g", "first_half": 1.0, "second_half": 1.5,
             "relative_change": 0.5, "ok": false},
            {"quantity": "n_cb", "first_half": 2.0, "second_half": 2.0,
             "relative_change": 0.0, "ok": true}]}});
        assert_eq!(trust_mark(&bad, Some("g")), Some(NOT_STATIONARY));
        assert_eq!(stationary(&bad), Some(false));
        let failed = failed_checks(&bad);
        assert_eq!(failed.len(), 1);
        assert!(
            failed[0].starts_with("T_g: first half 1.0000"),
            "{failed:?}"
        );
        let good = json!({"stationarity": {"tolerance": 0.1, "stationary": true, "checks": []}});
        assert_eq!(trust_mark(&good, Some("g")), None);
        assert_eq!(stationary(&json!({})), None);
        assert_eq!(trust_mark(&json!({}), None), None);
    }

    #[test]
    fn a_trend_marks_by_what_it_can_change() {
        let with = |state: &str| {
            json!({"convergence": {"converged": state == "stationary"},
                   "trend": {"state": state}})
        };
        assert_eq!(trust_mark(&with("stationary"), Some("f")), None);
        // A heating gas keeps its label; a heating fluid may boil.
        assert_eq!(trust_mark(&with("heating"), Some("g")), Some(LABEL_KEPT));
        assert_eq!(
            trust_mark(&with("heating"), Some("f")),
            Some(NOT_STATIONARY)
        );
        assert_eq!(
            trust_mark(&with("coarsening"), Some("fgc")),
            Some(LABEL_KEPT)
        );
        assert_eq!(
            trust_mark(&with("coarsening"), Some("g")),
            Some(NOT_STATIONARY)
        );
        assert_eq!(
            trust_mark(&with("cooling"), Some("g")),
            Some(NOT_STATIONARY)
        );
        // A cooling solid only gets colder.
        assert_eq!(trust_mark(&with("cooling"), Some("s")), Some(LABEL_KEPT));
        assert_eq!(
            trust_mark(&with("undecided"), Some("s")),
            Some(NOT_STATIONARY)
        );
        assert_eq!(trend(&with("heating")), Some(TrendState::Heating));
    }
}
