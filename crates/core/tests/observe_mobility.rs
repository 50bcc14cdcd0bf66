//! The mobility measure `D_lat` (lateral mean-square displacement over a fixed lag in time,
//! `observe::lateral`) on real shaken wet runs (N = 150, 50 d x 9 d: the standard system's three
//! layers): it does not depend on the sampling rate, and for a freely diffusing bed it does not
//! fall like 1/Gamma at fixed E*, unlike `f_lc` counted per driving period (issue: a diffusing
//! bed at Gamma = 20 read as solid).

use wetgran_core::observe::{Observables, run_observed};
use wetgran_core::scene::Scene;

/// Seed of every run here.
const SEED: u64 = 3;

/// The standard wet system reduced to 150 grains in 50 d x 9 d, eps = 0.9, shaken at
/// `(gamma, e_star)`, run for `duration` time units with a transient of `transient` time units.
fn shaken(gamma: f64, e_star: f64, duration: f64, transient: f64, spp: f64) -> Scene {
    let v_w = (2.0 * e_star * 0.2844f64).sqrt();
    let period = 2.0 * std::f64::consts::PI * v_w / gamma;
    let text = format!(
        r#"
dimension = 2
gravity = 1.0
[box]
size = [50.0, 9.0]
boundary = ["periodic", "wall"]
[particles]
count = 150
polydispersity = 0.06
[contact]
restitution = 0.9
[capillary]
model = "thin_thread"
s_crit = 0.0711
e_cb = 0.2844
[drive]
kind = "sine"
gamma = {gamma}
e_star = {e_star}
[engine]
min_rebound_speed = 0.03
[initial]
temperature_over_ecb = 20.0
seed = {SEED}
[run]
duration = {duration}
[observe]
transient_periods = {}
samples_per_period = {spp}
diffusion = false
time_series = false
"#,
        transient / period
    );
    Scene::from_toml_str(&text, "mobility test").expect("valid scene")
}

fn observed(scene: &Scene) -> Observables {
    run_observed(scene, &Default::default(), &mut |_| {}).observables
}

/// Doubling and quadrupling the sampling changes `D_lat` by less than 10 % (here far less: the
/// trajectory is the same and the lag is set in time), while `f_lc` moves more.
#[test]
fn mobility_does_not_depend_on_the_sampling_rate() {
    let d: Vec<f64> = [10.0, 20.0, 40.0]
        .iter()
        .map(|&spp| {
            observed(&shaken(2.0, 1.0, 60.0, 20.0, spp))
                .mobility
                .expect("window longer than the lag")
                .diffusion
        })
        .collect();
    for k in 1..3 {
        let change = (d[k] / d[0] - 1.0).abs();
        assert!(change < 0.10, "D_lat {:?}: {change}", d);
    }
    assert!(d[0] > 0.01, "a mobile state: {d:?}");
}

/// At fixed E* the grains of a fluid bed move about as fast whatever Gamma (the wall speed
/// `A omega` is fixed by E*), so `D_lat` per unit time stays of one size from Gamma = 2 to 50;
/// `f_lc` per driving period falls with the period, about like 1/Gamma.
#[test]
fn mobility_does_not_fall_like_one_over_gamma() {
    let runs: Vec<Observables> = [2.0, 10.0, 50.0]
        .iter()
        .map(|&g| {
            let mut s = shaken(g, 1.0, 60.0, 20.0, 20.0);
            s.observe.location_changes = Some(true);
            observed(&s)
        })
        .collect();
    let d: Vec<f64> = runs
        .iter()
        .map(|o| o.mobility.as_ref().unwrap().diffusion)
        .collect();
    let flc: Vec<f64> = runs
        .iter()
        .map(|o| o.location_changes.as_ref().unwrap().per_particle_per_period)
        .collect();
    // 1/Gamma would give 0.04 from Gamma = 2 to 50.
    assert!(d[2] / d[0] > 0.25, "D_lat {d:?}");
    assert!(d[1] / d[0] > 0.25, "D_lat {d:?}");
    assert!(flc[2] / flc[0] < 0.1, "f_lc per period {flc:?}");
    // And every one of them is mobile by the default threshold.
    let th = wetgran_core::observe::Thresholds::default();
    assert!(d.iter().all(|&x| x > 10.0 * th.solid_diffusion), "{d:?}");
}
