//! `wetgran-bench stress` through the binary: every hard case for a few thousand events (time
//! steps) with the invariant checks on, and the harness's self-check, a planted overlap, which
//! must be reported as a failure (exit status 3).

use std::process::Command;

/// Runs `wetgran-bench stress ARGS --json`; the exit status and the rows.
fn stress(args: &[&str]) -> (Option<i32>, Vec<serde_json::Value>) {
    let out = Command::new(env!("CARGO_BIN_EXE_wetgran-bench"))
        .arg("stress")
        .args(args)
        .arg("--json")
        .output()
        .expect("wetgran runs");
    let text = String::from_utf8_lossy(&out.stdout);
    let rows: Vec<serde_json::Value> = serde_json::from_str(&text).unwrap_or_else(|e| {
        panic!(
            "not JSON ({e}): {text}\n{}",
            String::from_utf8_lossy(&out.stderr)
        )
    });
    (out.status.code(), rows)
}

#[test]
fn every_hard_case_keeps_its_invariants_for_a_few_thousand_events() {
    let events = 3000u64;
    let (code, rows) = stress(&["--events", &events.to_string()]);
    let names: Vec<&str> = rows.iter().map(|r| r["case"].as_str().unwrap()).collect();
    assert_eq!(
        names,
        [
            "resting_bed",
            "bonded_collapse",
            "grazing_walls",
            "gamma_1000",
            "wall_speed_50",
            "jammed",
            "shear_double_roots",
            "time_largest_dt"
        ]
    );
    for r in &rows {
        let case = r["case"].as_str().unwrap();
        assert_eq!(r["violation"], serde_json::Value::Null, "{case}: {r}");
        assert_eq!(r["nan_count"], 0, "{case}: {r}");
        assert_eq!(r["work"], events, "{case}: {r}");
        assert_eq!(r["checks"], 100, "{case}: {r}");
        assert!(r["simulated_time"].as_f64().unwrap() > 0.0, "{case}: {r}");
        let overlap = r["max_overlap"].as_f64().unwrap();
        let ledger = r["ledger_error"].as_f64().unwrap();
        if r["unit"] == "steps" {
            // Soft spheres: overlaps are physics, bounded by the sanity check's 5 % of d; the
            // ledger error is the integrator's (docs/accuracy.md: ~3e-4 of the throughput).
            assert!(overlap > 0.0 && overlap < 0.05, "{case}: {r}");
            assert!(ledger < 1e-2, "{case}: {r}");
        } else {
            // Hard spheres: overlaps and ledger errors are round-off.
            assert!(overlap < 1e-9, "{case}: {r}");
            assert!(ledger < 1e-10, "{case}: {r}");
        }
    }
    assert_eq!(code, Some(0));
}

#[test]
fn a_planted_overlap_is_reported_as_a_failed_case() {
    let (code, rows) = stress(&["planted_overlap", "--events", "1000"]);
    assert_eq!(code, Some(3));
    assert_eq!(rows.len(), 1);
    let r = &rows[0];
    let v = r["violation"].as_str().unwrap_or_else(|| panic!("{r}"));
    assert!(v.contains("particles 0 and 1 overlap by"), "{v}");
    // Found at the first check, 10 events in.
    assert_eq!(r["checks"], 1, "{r}");
    assert!(
        (r["max_overlap"].as_f64().unwrap() - 0.1).abs() < 1e-9,
        "{r}"
    );
}

#[test]
fn an_unknown_case_is_refused() {
    let out = Command::new(env!("CARGO_BIN_EXE_wetgran-bench"))
        .args(["stress", "no_such_case"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("unknown stress case `no_such_case`") && err.contains("jammed"),
        "{err}"
    );
}
