//! The shear drive in the time-driven engine (docs/model.md 4.2, Eq. 2.20): the continuous force
//! `F_max cos(2 pi x / L_x)` along `y`. A single particle follows the analytic trajectory; in
//! elastic dry runs the booked work of the field equals the change of kinetic energy; the small
//! wet shear scene is solid below and fluidised above the chain-model force (docs/model.md 8).

use wetgran_testkit as common;

use common::scene_with;
use wetgran_core::scene::Scene;
use wetgran_core::sim::time_driven::TimeEngine;
use wetgran_core::sim::time_driven::shear::CosineShear;

fn time_shear_scene(gravity: f64, count: usize, f_max: f64, extra: &str) -> Scene {
    scene_with(
        3,
        gravity,
        &[12.0, 12.0, 6.0],
        &["periodic", "periodic", "wall"],
        count,
        &format!("[drive]\nkind = \"shear\"\nf_max = {f_max}\n[engine]\nkind = \"time\"\n{extra}"),
    )
}

/// Nearest-image difference along a periodic axis of length `l`.
fn periodic_diff(a: f64, b: f64, l: f64) -> f64 {
    let d = a - b;
    d - l * (d / l).round()
}

#[test]
fn single_particle_follows_the_analytic_cosine_trajectory() {
    let f_max = 0.5;
    let s = time_shear_scene(0.0, 1, f_max, "");
    let field = CosineShear::of_scene(&s).expect("shear scene");
    let mut e = TimeEngine::<3, false, false, CosineShear>::with_body_force(&s, field);
    let (x0, y0, z0) = (2.0, 5.0, 3.0);
    let (vx, vy) = (0.3, 0.1);
    e.set_state(0, [x0, y0, z0], [vx, vy, 0.0]);
    let k = 2.0 * std::f64::consts::PI / 12.0;
    let (a, b) = (k * x0, k * vx);
    let t_end = 10.0;
    assert!(e.run_until(t_end));
    let t = e.time();
    assert!((t - t_end).abs() < 1e-9);
    // y'' = F cos(a + b t):  y' = vy + (F/b)(sin(a+bt) - sin a),
    // y = y0 + vy t - (F/b^2)(cos(a+bt) - cos a) - (F/b) t sin a.
    let vy_exact = vy + f_max / b * ((a + b * t).sin() - a.sin());
    let y_exact =
        y0 + vy * t - f_max / (b * b) * ((a + b * t).cos() - a.cos()) - f_max / b * t * a.sin();
    let [x, y, z] = e.position(0);
    let [ux, uy, uz] = e.velocity(0);
    assert!(periodic_diff(x, x0 + vx * t, 12.0).abs() < 1e-9, "x = {x}");
    assert!((z - z0).abs() < 1e-12 && uz.abs() < 1e-12 && (ux - vx).abs() < 1e-12);
    // The momentum change along y is the integrated force (the particle crossed most of a
    // wavelength, so the force changed sign on the way).
    assert!(
        (uy - vy_exact).abs() < 1e-7,
        "v_y = {uy}, exact {vy_exact} (momentum change {})",
        vy_exact - vy
    );
    assert!(
        (vy_exact - vy).abs() > 0.1,
        "the field must change the momentum"
    );
    assert!(
        periodic_diff(y, y_exact, 12.0).abs() < 1e-6,
        "y = {y}, exact {y_exact} (mod 12)"
    );
    // Booked work = kinetic energy change (first-order rectangle rule in dt).
    let led = e.energy();
    let dk = led.kinetic - 0.5 * (vx * vx + vy * vy);
    assert!(
        (led.work_by_drive - dk).abs() < 1e-3 * dk.abs().max(1e-3),
        "work {} against dK {dk}",
        led.work_by_drive
    );
}

#[test]
fn elastic_dry_runs_book_the_work_of_the_field() {
    for gravity in [0.0, 1.0] {
        let s = time_shear_scene(
            gravity,
            120,
            0.8,
            "[initial]\ntemperature = 1.0\nseed = 4\n[run]\nduration = 8.0\nsample_interval = 1.0\n",
        );
        let report = wetgran_core::sim::run_scene(&s);
        assert!(
            report.invariant_violation.is_none(),
            "{:?}",
            report.invariant_violation
        );
        let (e0, e1) = (&report.energy_initial, &report.energy_final);
        let work = e1.work_by_drive - e0.work_by_drive;
        let de = (e1.kinetic + e1.potential) - (e0.kinetic + e0.potential);
        assert_eq!(e1.dissipated_restitution, 0.0);
        assert!(work.abs() > 0.05 * e0.kinetic, "g = {gravity}: work {work}");
        // The ledger closes to the integrator's accuracy (rectangle rule, first order in dt).
        assert!(
            (de - work).abs() < 2e-3 * work.abs(),
            "g = {gravity}: dE = {de}, work = {work}"
        );
    }
}

#[test]
fn small_wet_scene_is_solid_below_and_fluid_above_the_chain_model_force() {
    // scenes/shear_small_3d_time.toml: L_x = 12, F_B = 6: the chain model (Eq. 7.9) puts the
    // transition at F_max = 0.9229 * 6 / 12 = 0.46.
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../scenes/shear_small_3d_time.toml"
    ))
    .expect("scene file");
    for (f_max, want) in [(0.3, "s"), (1.0, "f")] {
        let text = text
            .replace("f_max = 1.0", &format!("f_max = {f_max}"))
            .replace("duration = 40.0", "duration = 12.0")
            .replace("transient_periods = 20", "transient_periods = 6");
        let s =
            Scene::from_toml_str(&text, "shear_small_3d_time").unwrap_or_else(|e| panic!("{e}"));
        let run = wetgran_core::observe::run_observed(&s, &Default::default(), &mut |_| {});
        assert!(run.report.invariant_violation.is_none());
        assert!(run.report.max_overlap.expect("time engine") < 0.05);
        assert_eq!(
            run.classification.phase.to_string(),
            want,
            "F_max = {f_max}: {:?}",
            run.classification.decided_on
        );
    }
}
