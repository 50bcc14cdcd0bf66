//! Re-classifies saved `wetgran simulate --json` results with the current classifier (and an
//! optional `[classify]` TOML file), one line each: the study tool behind docs/validation.md.
//!
//! `cargo run --release --example classify_result -- [--classify FILE] RESULT.json...`

use wetgran::observe::{Observables, Thresholds, classify};

fn main() {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let mut th = Thresholds::default();
    if let Some(k) = args.iter().position(|a| a == "--classify") {
        let path = args.get(k + 1).expect("--classify FILE").clone();
        let text = std::fs::read_to_string(&path).expect("readable --classify file");
        th = toml::from_str(&text).expect("a [classify] table's keys");
        args.drain(k..k + 2);
    }
    for path in args {
        let text = std::fs::read_to_string(&path).expect("readable result file");
        let v: serde_json::Value = serde_json::from_str(&text).expect("JSON");
        let obs: Observables =
            serde_json::from_value(v["observables"].clone()).expect("observables");
        let c = classify(&obs, &th);
        println!("{path}: {} | {}", c.phase, c.decided_on.reason);
    }
}
