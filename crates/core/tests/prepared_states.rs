//! Phase labels of prepared initial states run by the event engine (issue 31, item 1): a state
//! whose phase is known from how it was built, run without a drive, observed and classified
//! like any run.
//!
//! A bonded crystal strip (a triangular lattice of touching grains, every neighbour pair
//! bridged, at rest on the floor) inside a dilute gas hot against the bridge energy
//! (`T_g/E_cb = 10`, elastic grains and walls). What the strip does, measured per grain over
//! the window: with seed 1 its interior stays caged (mean-square displacement over 10 time
//! units 0.006-0.009 d^2 against the strip's mean, growth exponent between the lags 2.5 and 10
//! below 0.45) while its ends erode (a few grains leave their rows, 0.3-1.8 d^2, one
//! evaporates) and a few gas grains condense on it and slide along its surface; with seed 2 it
//! also cracks into four crystalline blocks, 2-3 d apart at the end, that slide apart on the
//! frictionless floor. The mean over the members grows with the lag (alpha 1.25 and 1.37), but
//! 0.96 and 0.92 of its members' displacements stay in their cage (against the grains each is
//! bonded to): a solid in a gas, sgc. The gas alone, without the strip, is a homogeneous gas.

use rand::{Rng, SeedableRng};
use rand_distr::StandardNormal;
use rand_xoshiro::Xoshiro256PlusPlus;
use wetgran_core::observe::{Phase, run_observed_from};
use wetgran_core::scene::Scene;
use wetgran_core::sim::books::EnergyLedger;
use wetgran_core::sim::{EngineState, EventCounts};

const L: f64 = 100.0;
const H: f64 = 9.0;
const E_CB: f64 = 0.2844;
/// Initial `T_g / E_cb` of the gas.
const GAS_TEMPERATURE: f64 = 10.0;

fn scene(n: usize) -> Scene {
    let text = format!(
        "dimension = 2\ngravity = 1.0\n[box]\nsize = [{L}, {H}]\nboundary = [\"periodic\", \
         \"wall\"]\n[particles]\ncount = {n}\n[contact]\nrestitution = 1.0\nwall_restitution = \
         1.0\n[engine]\nmin_rebound_speed = 0.03\n[capillary]\nmodel = \"thin_thread\"\ns_crit = 0.0711\ne_cb = {E_CB}\n[initial]\n\
         temperature_over_ecb = 1.0\n[run]\nduration = 40.0\n[observe]\nsamples_per_period = 20\n\
         transient_time = 10.0\n"
    );
    Scene::from_toml_str(&text, "prepared state").expect("valid scene")
}

/// A strip of `rows` rows from `x0` to `x0 + width` (touching grains, all neighbours bridged,
/// at rest) and `gas` grains at `T_g/E_cb = 30` placed without overlap elsewhere.
fn prepared(x0: f64, width: f64, rows: usize, gas: usize, seed: u64) -> EngineState {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let dy = 3f64.sqrt() / 2.0;
    let mut pos: Vec<(f64, f64)> = Vec::new();
    for r in 0..rows {
        let shift = if r % 2 == 1 { 0.5 } else { 0.0 };
        let mut x = x0 + 0.5 + shift;
        while x < x0 + width - 0.5 {
            pos.push((x, 0.5 + r as f64 * dy));
            x += 1.0;
        }
    }
    let strip = pos.len();
    let mut bridges = Vec::new();
    for i in 0..strip {
        for j in i + 1..strip {
            if (pos[i].0 - pos[j].0).hypot(pos[i].1 - pos[j].1) < 1.0 + 1e-9 {
                bridges.push((i, j));
            }
        }
    }
    while pos.len() < strip + gas {
        let p = (rng.gen_range(0.0..L), rng.gen_range(0.6..H - 0.6));
        let clear = pos.iter().all(|q| {
            let dx = (p.0 - q.0) - L * ((p.0 - q.0) / L).round();
            dx.hypot(p.1 - q.1) > 1.2
        });
        if clear {
            pos.push(p);
        }
    }
    let sd = (GAS_TEMPERATURE * E_CB).sqrt();
    let mut vel = vec![0.0; 2 * strip];
    for _ in strip..pos.len() {
        vel.push(sd * rng.sample::<f64, _>(StandardNormal));
        vel.push(sd * rng.sample::<f64, _>(StandardNormal));
    }
    EngineState {
        engine: "event".into(),
        dimension: 2,
        time: 0.0,
        positions: pos.iter().flat_map(|p| [p.0, p.1]).collect(),
        velocities: vel,
        radii: vec![0.5; pos.len()],
        bridges,
        counts: EventCounts::default(),
        ledger: EnergyLedger::default(),
    }
}

#[test]
fn a_bonded_crystal_strip_in_a_hot_dilute_gas_is_sgc() {
    for seed in 1..=2 {
        let state = prepared(30.0, 30.0, 3, 15, seed);
        let n = state.radii.len();
        let (run, _) = run_observed_from(&scene(n), Some(&state), &Default::default(), &mut |_| {});
        let c = &run.classification;
        eprintln!("seed {seed}: {}", c.decided_on.reason);
        let dense = c.decided_on.dense.as_ref().expect("a coexistence");
        // The strip's members stay in their cages: measured, not assumed.
        let still = dense
            .members_still
            .expect("cage-relative displacements measured");
        assert!(still >= 0.8, "seed {seed}: {}", c.decided_on.reason);
        assert_eq!(c.phase, Phase::Sgc, "seed {seed}: {}", c.decided_on.reason);
    }
}

#[test]
fn the_hot_dilute_gas_alone_is_a_homogeneous_gas() {
    let state = prepared(0.0, 0.0, 0, 40, 3);
    let n = state.radii.len();
    let (run, _) = run_observed_from(&scene(n), Some(&state), &Default::default(), &mut |_| {});
    let c = &run.classification;
    assert!(!c.decided_on.split, "{}", c.decided_on.reason);
    assert_eq!(c.phase, Phase::G, "{}", c.decided_on.reason);
}
