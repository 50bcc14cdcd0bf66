//! The invariant checks of a run (`sim::checks`): the quick check sees each particle on its
//! own, the full check adds the pairs; a run under a wall-time share runs the full check at
//! its first sample, at the end of every stretch and at its end whatever stopped it, and
//! otherwise only while the share allows; the report's one-pass sample equals the engine's
//! energies and temperature bit for bit.

use wetgran_testkit as common;

use common::scene_with;
use wetgran_core::scene::Scene;
use wetgran_core::sim::event_driven::{Engine, Vector};
use wetgran_core::sim::{CheckPolicy, EngineState, RunSettings, run_scene_watched};

/// Two disks in a periodic 20 x 20 box, at rest.
fn two_disks_scene(run: &str) -> Scene {
    scene_with(
        2,
        0.0,
        &[20.0, 20.0],
        &["periodic", "periodic"],
        2,
        &format!("[initial]\ntemperature = 0.0\n[run]\n{run}"),
    )
}

/// Two disks overlapping by 0.1 and separating slowly: the overlap lasts 10 time units.
fn overlapping(scene: &Scene) -> EngineState {
    let e = Engine::<2, false, false>::new(scene);
    EngineState {
        engine: "event".into(),
        dimension: 2,
        time: 0.0,
        positions: vec![5.0, 5.0, 5.9, 5.0],
        velocities: vec![-0.005, 0.0, 0.005, 0.0],
        radii: e.radii(),
        bridges: vec![],
        counts: Default::default(),
        ledger: Default::default(),
    }
}

struct NoWatch;

impl wetgran_core::sim::Watcher for NoWatch {
    fn observe(&mut self, _: &wetgran_core::sim::Frame) {}
}

fn run(scene: &Scene, start: &EngineState, checks: CheckPolicy) -> wetgran_core::sim::RunReport {
    let settings = RunSettings {
        checks,
        ..RunSettings::default()
    };
    run_scene_watched(
        scene,
        Some(start),
        &settings,
        1e3,
        &mut NoWatch,
        &mut |_| {},
    )
}

#[test]
fn the_quick_check_sees_each_particle_and_the_full_check_the_pairs() {
    let s = two_disks_scene("duration = 1.0");
    let mut e = Engine::<2, false, false>::new(&s);
    assert_eq!(e.radii(), vec![0.5, 0.5], "monodisperse unit disks");
    e.set_position(0, Vector::<2>::new(5.0, 5.0));
    e.set_position(1, Vector::<2>::new(5.9, 5.0));
    e.set_velocity(0, Vector::<2>::new(-0.005, 0.0));
    e.set_velocity(1, Vector::<2>::new(0.005, 0.0));
    assert_eq!(e.quick_check(), Ok(()), "an overlap is a pair's fault");
    let full = e.sanity_check().unwrap_err();
    assert!(full.contains("overlap by"), "{full}");
    // A non-finite velocity is one particle's fault: the quick check says no.
    e.set_velocity(1, Vector::<2>::new(f64::NAN, 0.0));
    let quick = e.quick_check().unwrap_err();
    assert!(quick.contains("non-finite"), "{quick}");
}

#[test]
fn a_run_stopped_on_its_event_cap_gets_the_full_check() {
    // The cap stops the run before its first report sample: only the check at the end of the
    // run can see the overlap (the quick check cannot). Regression: the loop used to stop on
    // the cap without any check.
    let s = two_disks_scene("duration = 5.0\nsample_interval = 5.0\nmax_events = 1");
    let start = overlapping(&s);
    for policy in [CheckPolicy::WallShare(0.01), CheckPolicy::EverySample] {
        let r = run(&s, &start, policy);
        assert!(r.stopped_on_event_cap && r.samples.len() == 2, "{r:?}");
        let v = r
            .invariant_violation
            .expect("the end of the run checks the pairs");
        assert!(v.contains("overlap by"), "{policy:?}: {v}");
        assert_eq!(r.timing.full_checks, 1, "{policy:?}");
    }
}

#[test]
fn a_wall_time_share_says_no_to_most_samples_and_every_sample_to_none() {
    // 2000 report samples of a quiet gas: a share of a millionth of the run allows the full
    // check at the first sample and at the end of the stretch, and no other (a further one
    // would need the run to last a million times one check); every sample runs it at each.
    let s = scene_with(
        2,
        0.0,
        &[40.0, 40.0],
        &["periodic", "periodic"],
        200,
        "[initial]\ntemperature = 1.0\n[run]\nduration = 20.0\nsample_interval = 0.01",
    );
    let start = hot_start(&s);
    let shared = run(&s, &start, CheckPolicy::WallShare(1e-6));
    let every = run(&s, &start, CheckPolicy::EverySample);
    assert_eq!(shared.invariant_violation, None);
    assert_eq!(every.invariant_violation, None);
    assert_eq!(shared.samples.len(), 2001);
    assert!(
        shared.timing.full_checks <= 3,
        "{} full checks under a share of 1e-6",
        shared.timing.full_checks
    );
    assert_eq!(every.timing.full_checks, 2000, "one per report sample");
    // The checks never change the run.
    assert_eq!(shared.samples, every.samples);
    assert_eq!(shared.events, every.events);
}

/// The scene's own hot start as a saved state (no overlap).
fn hot_start(scene: &Scene) -> EngineState {
    let mut s = scene.clone();
    s.run.duration = 0.0;
    let r = wetgran_core::sim::run_scene(&s);
    r.final_state.expect("every run reports its final state")
}

#[test]
fn the_report_sample_equals_the_engine_energies_bit_for_bit() {
    // A shaken wet bed (gravity, bridges): the one-pass sample against `energy` and
    // `granular_temperature`, at several times.
    let s = scene_with(
        2,
        1.0,
        &[40.0, 9.0],
        &["periodic", "wall"],
        120,
        "[contact]\nrestitution = 0.9\n[capillary]\nmodel = \"thin_thread\"\ns_crit = 0.0711\n\
         e_cb = 0.2844\n[drive]\nkind = \"sine\"\ngamma = 3.0\ne_star = 0.7\n[initial]\n\
         temperature_over_ecb = 5.0\n[run]\nduration = 1.0",
    );
    let mut e = Engine::<2, true, true>::new(&s);
    for k in 1..=5 {
        e.run_until(0.3 * k as f64, None);
        let (kinetic, potential, t_g) = e.sample_energies();
        let energy = e.energy();
        assert_eq!(kinetic.to_bits(), energy.kinetic.to_bits());
        assert_eq!(potential.to_bits(), energy.potential.to_bits());
        assert_eq!(t_g.to_bits(), e.granular_temperature().to_bits());
    }
}
