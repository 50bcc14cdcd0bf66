//! Invariance of the phase labels on the 2D standard wet system itself (MODEL.md 1: N = 1200 in
//! 400 d x 9 d, sigma_p = 0.06, thin thread, hot start T_g/E_cb = 20), not on a shrunken
//! stand-in. In CI: the fluid-gas coexistence of the line Gamma = 30 (E* = 1.1, eps = 1) keeps
//! its label when the run is doubled. Opt-in (`cargo test --release --test standard_invariance
//! -- --ignored`, about 15 min on one core): three points of that line (a fluid at E* = 0.5,
//! the coexistence at 1.1, a gas at 2.6) with the run doubled, another seed, sampling halved and doubled, and the
//! box doubled at the same number of layers (800 d x 9 d, N = 2400); docs/validation.md has the
//! study over five seeds with the run-length policy.

use wetgran::observe::run_observed;
use wetgran::scene::Scene;

/// Seeds of the runs (named, so a failure can be reproduced with the same numbers).
const SEED: u64 = 1;
const OTHER_SEED: u64 = 2;

/// The standard system at `(Gamma, E*)`, eps = 1: `duration` and `transient` in time units,
/// `spp` observer samples per period.
fn standard(
    e_star: f64,
    n: usize,
    l_x: f64,
    seed: u64,
    duration: f64,
    transient: f64,
    spp: f64,
) -> Scene {
    let gamma = 30.0;
    // One period T = 2 pi v_w / (Gamma g), v_w = sqrt(2 E* E_cb / m) (MODEL.md 4.1).
    let period = 2.0 * std::f64::consts::PI * (2.0 * e_star * 0.2844f64).sqrt() / gamma;
    let text = format!(
        "dimension = 2\ngravity = 1.0\n[box]\nsize = [{l_x:?}, 9.0]\nboundary = [\"periodic\", \"wall\"]\n\
         [particles]\ncount = {n}\npolydispersity = 0.06\n[contact]\nrestitution = 1.0\nwall_restitution = 1.0\n\
         [capillary]\nmodel = \"thin_thread\"\ns_crit = 0.0711\ne_cb = 0.2844\n\
         [drive]\nkind = \"sine\"\ngamma = {gamma:?}\ne_star = {e_star:?}\n\
         [engine]\nmin_rebound_speed = 0.03\n[initial]\ntemperature_over_ecb = 20.0\nseed = {seed}\n\
         [run]\nduration = {duration:?}\nsample_interval = 10.0\n\
         [observe]\ntransient_periods = {:?}\nsamples_per_period = {spp:?}\n",
        transient / period
    );
    Scene::from_toml_str(&text, "standard system").unwrap_or_else(|e| panic!("{e}"))
}

/// The per-point label (fluid vs gas by the per-point fallback: these runs have no line).
fn label(scene: &Scene) -> (String, f64) {
    let run = run_observed(scene, &mut |_| {});
    assert_eq!(run.report.invariant_violation, None);
    (
        run.classification.phase.to_string(),
        run.observables.granular_temperature_reduced,
    )
}

#[test]
fn the_coexistence_of_the_standard_system_survives_a_doubled_run() {
    // 120 time units (window from 40) against 240 (window from 80). Shorter is too short: at 60
    // time units (window from 20) this point still reads `g`, the transient of the hot start
    // (the complaint about labels that change with run length).
    let (short, t_short) = label(&standard(1.1, 1200, 400.0, SEED, 120.0, 40.0, 20.0));
    let (long, t_long) = label(&standard(1.1, 1200, 400.0, SEED, 240.0, 80.0, 20.0));
    println!("E* = 1.1: {short} (T_g/E_cb {t_short:.2}) at 120, {long} ({t_long:.2}) at 240");
    assert_eq!(short, "fgc");
    assert_eq!(long, "fgc");
}

#[test]
#[ignore]
fn standard_system_labels_are_invariant() {
    // E* = 0.5, not 0.7: at 0.7 T_g/E_cb is 1.9-2.03 across seeds, on the per-point fallback
    // threshold of 2 (these runs have no line; docs/validation.md).
    for (e_star, expected) in [(0.5, "f"), (1.1, "fgc"), (2.6, "g")] {
        let runs = [
            (
                "base",
                standard(e_star, 1200, 400.0, SEED, 300.0, 100.0, 20.0),
            ),
            (
                "doubled run",
                standard(e_star, 1200, 400.0, SEED, 600.0, 100.0, 20.0),
            ),
            (
                "other seed",
                standard(e_star, 1200, 400.0, OTHER_SEED, 300.0, 100.0, 20.0),
            ),
            (
                "sampling halved",
                standard(e_star, 1200, 400.0, SEED, 300.0, 100.0, 10.0),
            ),
            (
                "sampling doubled",
                standard(e_star, 1200, 400.0, SEED, 300.0, 100.0, 40.0),
            ),
            (
                "box doubled",
                standard(e_star, 2400, 800.0, SEED, 300.0, 100.0, 20.0),
            ),
        ];
        for (what, scene) in runs {
            let (phase, t) = label(&scene);
            println!("E* = {e_star}, {what}: {phase} (T_g/E_cb {t:.3})");
            assert_eq!(phase, expected, "E* = {e_star}, {what}");
        }
    }
}
