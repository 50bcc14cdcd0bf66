//! Trend states on the real system (docs/observables.md "Run to a settled label"): the 2D standard
//! wet system (N = 1200, 400 d x 9 d, eps = 1) on the line Gamma = 30, under the run policy of the
//! shipped validation sweep `sweeps/validation/gamma30_seeds.toml`. The elastic gas heats without
//! bound and must read `heating` (docs/validation.md), its label kept while nothing condenses,
//! and stop before the cap; the fluid-gas coexistence's drops grow and it must read `coarsening`
//! with its coexistence label.

use std::path::Path;
use wetgran::sweep::file::SweepFile;
use wetgran_core::observe::trend::TrendState;
use wetgran_core::observe::{Ending, Phase, run_observed};
use wetgran_core::scene::Scene;

/// The five seeds of the shipped sweep's point `E* = e_star`.
fn seeds_at(e_star: f64) -> Vec<Scene> {
    let file = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/sweeps/validation/gamma30_seeds.toml"
    );
    let sweep = SweepFile::load(Path::new(file)).unwrap_or_else(|e| panic!("{e}"));
    let scenes: Vec<Scene> = sweep
        .expand()
        .unwrap_or_else(|e| panic!("{e}"))
        .into_iter()
        .filter(|j| j.spec.scene.drive.e_star == Some(e_star))
        .map(|j| j.spec.scene)
        .collect();
    assert_eq!(scenes.len(), 5, "five replicas at E* = {e_star}");
    scenes
}

/// `(phase, trend, ending, simulated time)` of each seed, run two at a time.
fn outcomes(scenes: &[Scene]) -> Vec<(Phase, TrendState, Option<Ending>, f64)> {
    use rayon::prelude::*;
    scenes
        .par_iter()
        .map(|s| {
            let run = run_observed(s, &Default::default(), &mut |_| {});
            let o = &run.observables;
            (
                run.classification.phase,
                o.trend.as_ref().expect("every run has a trend").state,
                o.trend.as_ref().and_then(|t| t.policy).map(|p| p.ending),
                run.report.simulated_time,
            )
        })
        .collect()
}

#[test]
fn the_elastic_gas_at_gamma_30_reads_heating_and_stops_early() {
    let scenes = seeds_at(2.6);
    let cap = scenes[0]
        .convergence
        .as_ref()
        .unwrap()
        .schedule(&scenes[0])
        .cap;
    let got = outcomes(&scenes);
    let heating = got
        .iter()
        .filter(|(p, t, e, time)| {
            *p == Phase::G
                && *t == TrendState::Heating
                && *e == Some(Ending::Settled)
                && *time < cap
        })
        .count();
    assert!(heating >= 4, "{got:?}");
}

#[test]
fn the_coexistence_at_gamma_30_reads_coarsening_and_keeps_its_label() {
    let got = outcomes(&seeds_at(1.1));
    let coarsening = got
        .iter()
        .filter(|(p, t, _, _)| matches!(p, Phase::Fgc | Phase::Sgc) && *t == TrendState::Coarsening)
        .count();
    assert!(coarsening >= 4, "{got:?}");
}
