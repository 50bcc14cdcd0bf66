//! The trust marks of stored results (docs/observables.md "Run to stationarity"): a result's
//! `observe::trend::Trust` (`PointRow::trust`: its trend state, else its convergence verdict)
//! shows as no mark (stationary), [`LABEL_KEPT`] (a heating gas, a cooling solid, a coarsening
//! coexistence: more time cannot change the label) or [`NOT_STATIONARY`]; and the failed
//! stationarity checks of a result in words.

use wetgran_core::observe::trend::Trust;

/// The mark of a result whose label may still change (not stationary, and no trend that keeps
/// its label).
pub const NOT_STATIONARY: char = '?';

/// The mark of a result that is not stationary but whose trend cannot change its label (a
/// heating gas, a cooling solid, a coarsening coexistence): the label is safe, its numbers
/// still drift.
pub const LABEL_KEPT: char = '~';

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
    use wetgran_core::observe::Phase::{F, Fgc, G, S};
    use wetgran_core::observe::converged_in_json;
    use wetgran_core::observe::trend::{TrendState as T, trust};

    #[test]
    fn a_failed_stationarity_check_marks_the_result() {
        let bad = json!({"stationarity": {"tolerance": 0.1, "stationary": false, "checks": [
            {"quantity": "T_g", "first_half": 1.0, "second_half": 1.5,
             "relative_change": 0.5, "ok": false},
            {"quantity": "n_cb", "first_half": 2.0, "second_half": 2.0,
             "relative_change": 0.0, "ok": true}]}});
        assert_eq!(converged_in_json(&bad), Some(false));
        assert_eq!(
            mark(trust(None, Some(false), Some(G))),
            Some(NOT_STATIONARY)
        );
        let failed = failed_checks(&bad);
        assert_eq!(failed.len(), 1);
        assert!(
            failed[0].starts_with("T_g: first half 1.0000"),
            "{failed:?}"
        );
        // A result without a verdict is taken as stationary.
        assert_eq!(converged_in_json(&json!({})), None);
        assert_eq!(mark(trust(None, None, None)), None);
    }

    #[test]
    fn a_trend_marks_by_what_it_can_change() {
        // A heating gas keeps its label; a heating fluid may boil; a cooling solid only gets
        // colder.
        for (state, phase, want) in [
            (T::Stationary, F, None),
            (T::Heating, G, Some(LABEL_KEPT)),
            (T::Heating, F, Some(NOT_STATIONARY)),
            (T::Coarsening, Fgc, Some(LABEL_KEPT)),
            (T::Coarsening, G, Some(NOT_STATIONARY)),
            (T::Cooling, G, Some(NOT_STATIONARY)),
            (T::Cooling, S, Some(LABEL_KEPT)),
            (T::Undecided, S, Some(NOT_STATIONARY)),
        ] {
            let converged = Some(state == T::Stationary);
            assert_eq!(
                mark(trust(Some(state), converged, Some(phase))),
                want,
                "{state} {phase}"
            );
        }
    }
}
