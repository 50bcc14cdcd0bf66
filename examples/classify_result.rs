//! Re-classifies saved `wetgran simulate --json` results with the current classifier (and an
//! optional `[classify]` TOML file): the study tool behind docs/validation.md
//! (`scripts/validation.sh table`).
//!
//! `cargo run --release --example classify_result -- [--classify FILE] [--json | --table] RESULT.json...`
//!
//! Default: one line per result, phase and reason. `--json`: the classification as JSON, one per
//! line. `--table`: a markdown table row per result, with `Gamma`, `E*` and `eps` read from the
//! scene file of the same name (`RESULT.toml`). `--line`: the results are one line of constant
//! Gamma; the fluid-gas line rule (docs/model.md 7, `observe::line`) labels them, as a sweep does.

use std::path::Path;
use wetgran_core::observe::{Observables, Thresholds, classify};
use wetgran_core::scene::Scene;

fn main() {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let mut th = Thresholds::default();
    if let Some(k) = args.iter().position(|a| a == "--classify") {
        let path = args.get(k + 1).expect("--classify FILE").clone();
        let text = std::fs::read_to_string(&path).expect("readable --classify file");
        th = toml::from_str(&text).expect("a [classify] table's keys");
        args.drain(k..k + 2);
    }
    let json = args.iter().any(|a| a == "--json");
    let table = args.iter().any(|a| a == "--table");
    let as_line = args.iter().any(|a| a == "--line");
    args.retain(|a| a != "--json" && a != "--table" && a != "--line");
    let scene_of = |path: &str| {
        Scene::load(&Path::new(path).with_extension("toml")).expect("the run's scene file")
    };
    let observables_of = |path: &str| -> Observables {
        let text = std::fs::read_to_string(path).expect("readable result file");
        let v: serde_json::Value = serde_json::from_str(&text).expect("JSON");
        serde_json::from_value(v["observables"].clone()).expect("observables")
    };
    // With --line: every result classified on the line first.
    let line_labels: Option<Vec<wetgran_core::observe::Classification>> = as_line.then(|| {
        let scenes: Vec<Scene> = args.iter().map(|a| scene_of(a)).collect();
        let obs: Vec<Observables> = args.iter().map(|a| observables_of(a)).collect();
        let pts: Vec<(f64, &Observables)> = scenes
            .iter()
            .zip(&obs)
            .map(|(s, o)| (s.drive.e_star.expect("E* given"), o))
            .collect();
        let gamma = scenes[0].drive.gamma.expect("Gamma given");
        let elastic = scenes[0].contact.restitution >= 1.0;
        wetgran_core::observe::line::classify_line(gamma, &pts, &th, elastic)
    });
    if table {
        println!(
            "| run | Gamma | E* | eps | T_g/E_cb | bridges/grain | D_lat | Delta n_cb | noise threshold | contrast | phase | fluid/gas by | borderline | halves agree |"
        );
        println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    }
    for (k, path) in args.iter().enumerate() {
        let obs = observables_of(path);
        let c = match &line_labels {
            Some(l) => l[k].clone(),
            None => classify(&obs, &th),
        };
        if json {
            println!(
                "{}",
                serde_json::to_string(&c).expect("a classification serializes")
            );
        } else if table {
            let p = Path::new(path);
            let scene = scene_of(path);
            let d = &c.decided_on;
            let test = d.coexistence.as_ref().expect("a coexistence test");
            let opt = |x: Option<f64>| x.map_or_else(|| "-".to_string(), |v| format!("{v:.3}"));
            println!(
                "| {} | {} | {} | {} | {:.3} | {:.2} | {} | {:.3} | {} | {:.2} | {} | {} | {} | {} |",
                p.file_stem().unwrap_or_default().to_string_lossy(),
                scene.drive.gamma.unwrap_or(f64::NAN),
                scene.drive.e_star.unwrap_or(f64::NAN),
                scene.contact.restitution,
                obs.granular_temperature_reduced,
                obs.bridges_per_particle,
                obs.mobility
                    .as_ref()
                    .map_or_else(|| "-".to_string(), |m| format!("{:.2e}", m.diffusion)),
                test.delta,
                opt(test.noise_threshold),
                test.contrast,
                c.phase,
                match &d.fluid_gas {
                    wetgran_core::observe::classify::FluidGasFrom::PointFallback =>
                        "point".to_string(),
                    wetgran_core::observe::classify::FluidGasFrom::Line {
                        method,
                        e_star_boundary,
                        ..
                    } => format!("{method} at E* = {e_star_boundary:.3}"),
                    wetgran_core::observe::classify::FluidGasFrom::LineWithoutTransition {
                        method,
                        ..
                    } => format!("point (line: no {method})"),
                    wetgran_core::observe::classify::FluidGasFrom::OwnEvidence {
                        method,
                        line_said,
                        ..
                    } => format!("own evidence ({method} said {line_said})"),
                },
                if d.borderline.is_empty() { "" } else { "yes" },
                c.verdict()
            );
        } else {
            println!("{path}: {} | {}", c.phase, c.decided_on.reason);
        }
    }
}
