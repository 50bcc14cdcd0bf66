//! Invariance of the phase labels on the 2D standard wet system itself (docs/model.md 1: N = 1200 in
//! 400 d x 9 d, sigma_p = 0.06, thin thread, hot start T_g/E_cb = 20), not on a shrunken
//! stand-in. In CI: the fluid-gas coexistence of the line Gamma = 30 (E* = 1.1, eps = 1) keeps
//! its label when the run is doubled. Opt-in (`cargo test --release --test standard_invariance
//! -- --ignored`, about 15 min on one core): three points of that line (a fluid at E* = 0.5,
//! the coexistence at 1.1, a gas at 2.6) with the run doubled, another seed, sampling halved and doubled, and the
//! box doubled at the same number of layers (800 d x 9 d, N = 2400); docs/validation.md has the
//! study over five seeds with the run-length policy.

use wetgran_core::observe::run_observed;
use wetgran_core::scene::{Boundary, Scene};

use common::standard::{OTHER_SEED, STANDARD_SEED as SEED, StandardWet, Transient};
use wetgran_testkit as common;

/// The standard system at `(Gamma = 30, E*)`, eps = 1: `duration` and `transient` in time units,
/// `spp` observer samples per period.
fn standard(e_star: f64, seed: u64, duration: f64, transient: f64, spp: f64) -> StandardWet {
    let mut s =
        StandardWet::new(30.0, e_star, 1.0, duration, Transient::Time(transient)).seed(seed);
    s.min_rebound_speed = Some(0.03);
    s.sample_interval = Some(10.0);
    s.samples_per_period = Some(spp);
    s
}

/// The per-point label (fluid vs gas by the per-point fallback: these runs have no line).
fn label(scene: &Scene) -> (String, f64) {
    let run = run_observed(scene, &Default::default(), &mut |_| {});
    assert_eq!(run.report.invariant_violation, None);
    (
        run.classification.phase.to_string(),
        run.observables.granular_temperature_reduced,
    )
}

/// The builder leaves the standard values that are scene defaults out of its text: they must
/// stay the standard system's (docs/model.md 1).
#[test]
fn standard_defaults_are_the_standard_system() {
    let s = StandardWet::new(30.0, 1.1, 1.0, 10.0, Transient::Periods(1.0)).scene();
    assert_eq!(s.gravity, 1.0);
    assert_eq!(s.boundaries(), vec![Boundary::Periodic, Boundary::Wall]);
    assert_eq!(s.contact.wall_restitution, 1.0);
    assert_eq!(s.s_crit(), 0.0711);
    assert_eq!(s.e_cb(), common::standard::E_CB);
    assert_eq!(
        (s.particles.count, s.container.size.clone()),
        (1200, vec![400.0, 9.0])
    );
}

#[test]
fn the_coexistence_of_the_standard_system_survives_a_doubled_run() {
    // 120 time units (window from 40) against 240 (window from 80). Shorter is too short: at 60
    // time units (window from 20) this point still reads `g`, the transient of the hot start
    // (the complaint about labels that change with run length).
    let (short, t_short) = label(&standard(1.1, SEED, 120.0, 40.0, 20.0).scene());
    let (long, t_long) = label(&standard(1.1, SEED, 240.0, 80.0, 20.0).scene());
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
            ("base", standard(e_star, SEED, 300.0, 100.0, 20.0).scene()),
            (
                "doubled run",
                standard(e_star, SEED, 600.0, 100.0, 20.0).scene(),
            ),
            (
                "other seed",
                standard(e_star, OTHER_SEED, 300.0, 100.0, 20.0).scene(),
            ),
            (
                "sampling halved",
                standard(e_star, SEED, 300.0, 100.0, 10.0).scene(),
            ),
            (
                "sampling doubled",
                standard(e_star, SEED, 300.0, 100.0, 40.0).scene(),
            ),
            (
                "box doubled",
                standard(e_star, SEED, 300.0, 100.0, 20.0)
                    .sized(2400, 800.0)
                    .scene(),
            ),
        ];
        for (what, scene) in runs {
            let (phase, t) = label(&scene);
            println!("E* = {e_star}, {what}: {phase} (T_g/E_cb {t:.3})");
            assert_eq!(phase, expected, "E* = {e_star}, {what}");
        }
    }
}
