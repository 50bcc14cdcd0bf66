//! How far a stored result can be trusted, from its stored observables: the one place the sweep
//! commands (`sweep status`, `show`, `boundaries`, `export`) read that verdict from. Today it is
//! the convergence verdict of the run-length policy where the run had one, else the
//! stationarity check (`observables.stationarity.stationary`, docs/observables.md).

/// The mark of a result whose stationarity check failed (its averages may still drift).
pub const NOT_STATIONARY: char = '?';

/// Whether a result is stationary: the run-length policy's convergence verdict where the run
/// had one, else its stationarity check (`observe::converged_in_json`); `None` where the stored
/// observables carry no verdict (a result written before the check existed).
pub fn stationary(observables: &serde_json::Value) -> Option<bool> {
    wetgran_core::observe::converged_in_json(observables)
}

/// The trust mark of a result: `None` for a trusted one, [`NOT_STATIONARY`] for a result whose
/// stationarity check failed.
pub fn trust_mark(observables: &serde_json::Value) -> Option<char> {
    match stationary(observables) {
        Some(false) => Some(NOT_STATIONARY),
        _ => None,
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
        assert_eq!(trust_mark(&bad), Some(NOT_STATIONARY));
        assert_eq!(stationary(&bad), Some(false));
        let failed = failed_checks(&bad);
        assert_eq!(failed.len(), 1);
        assert!(
            failed[0].starts_with("T_g: first half 1.0000"),
            "{failed:?}"
        );
        let good = json!({"stationarity": {"tolerance": 0.1, "stationary": true, "checks": []}});
        assert_eq!(trust_mark(&good), None);
        assert_eq!(stationary(&json!({})), None);
        assert_eq!(trust_mark(&json!({})), None);
    }
}
