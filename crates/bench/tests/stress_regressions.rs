//! Regressions found by the stress cases and the input fuzzer, built on their scenes and
//! their invariant-checked run (`wetgran_bench::stress`).

use wetgran_core::sim::run_scene;

/// Safeguard of the `table` solver, found by the sweep-file fuzzer (seed 7, after 3 328 cases):
/// three disks over a 16 x 16 wall table at Gamma = 0.3, E* = 11.5 (amplitude 38 d). A tabulated
/// floor hit 2.9e-3 late found a disk 0.021 d behind the floor, beyond the placement tolerance;
/// the re-check left it there (no later prediction can undo a late hit) and the invariant check
/// found it outside the box. A late hit (behind the wall, approaching) is now placed whatever its
/// depth; only early ones beyond the tolerance are re-checks. Fails without that rule.
#[test]
fn regression_late_tabulated_hit_is_placed_whatever_its_depth() {
    let s = wetgran_core::scene::Scene::from_toml_str(
        "dimension = 2\ngravity = 1.0\n[box]\nsize = [11.2961119195911, 4.986169866029122]\n\
         [particles]\ncount = 3\npolydispersity = 0.07414066405078824\n[contact]\nrestitution = 0.3\n\
         [drive]\nkind = \"sine\"\ngamma = 0.3\ne_star = 11.510145747008325\n\
         wall_solver = \"table\"\ntable_cells = [16, 16]\n[initial]\nseed = 107\n\
         temperature = 3.5518651948612208\n[run]\nduration = 1.0\n",
        "fuzz case",
    )
    .expect("valid scene");
    let m = wetgran_bench::stress::first_events(&s, 300, 10).expect("runs");
    assert_eq!(m.violation, None);
}

/// Bug found by `wetgran-bench stress time_largest_dt`: at `engine.dt = 0.01` (then admitted at the
/// default stiffness) the integrator blew up and a bonded pair moved out of the Verlet list
/// between two builds, and the list's rebuild panicked ("flagged pair left the neighbour
/// list"), taking `wetgran simulate` down. Validation now refuses such a step
/// (`Scene::largest_time_step`); a run that blows up all the same (here: the step forced past
/// validation) stops on a broken invariant, reported, not a panic.
#[test]
fn regression_blown_up_time_run_is_a_broken_invariant_not_a_panic() {
    let mut s = wetgran_bench::stress::StressCase::TimeLargestDt.scene();
    let mut bad = s.clone();
    bad.engine.dt = Some(0.01);
    assert!(bad.validate("t").is_err(), "dt = 0.01 must be refused");
    s.engine.dt = Some(0.01);
    s.run.duration = 20.0;
    s.run.sample_interval = 0.5;
    let r = run_scene(&s);
    let v = r.invariant_violation.expect("the blown-up run is stopped");
    assert!(
        v.contains("left the neighbour list")
            || v.contains("outside the box")
            || v.contains("overlap"),
        "{v}"
    );
}

/// Found by the input fuzzer through `wetgran simulate`: a run that blows up between two report
/// samples handed NaN positions to the location-change observer, whose triangulation panicked
/// ("finite particle positions"). The run loop now checks every observer frame and stops on a
/// broken invariant before the observers see it.
#[test]
fn regression_blown_up_frame_never_reaches_the_observers() {
    let mut s = wetgran_bench::stress::StressCase::TimeLargestDt.scene();
    s.engine.dt = Some(0.01);
    s.run.duration = 20.0;
    // One report sample at the end; observer frames every period until then.
    s.run.sample_interval = 20.0;
    s.observe.location_changes = Some(true);
    s.observe.transient_periods = 0.0;
    s.observe.samples_per_period = 20.0;
    let run = wetgran_core::observe::run_observed(&s, &Default::default(), &mut |_| {});
    let v = run
        .report
        .invariant_violation
        .expect("the blown-up run is stopped");
    assert!(run.report.simulated_time < 20.0, "stopped early: {v}");
}
