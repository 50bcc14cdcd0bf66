//! The sinusoidally shaken container (MODEL.md 4.1, 6) with the exact wall solver: exact energy
//! bookkeeping with the drive's work, the A = 0 limit, nothing leaving the box, re-checks.

mod common;

use common::{run_checked, scene, scene_with};
use wetgran::sim::event_driven::{Engine, Vector};

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs().max(1e-300)
}

fn shaken_wet(gamma: f64, e_star: f64, eps: f64, count: usize) -> wetgran::scene::Scene {
    scene(&format!(
        r#"
dimension = 2
gravity = 1.0
[box]
size = [60.0, 9.0]
boundary = ["periodic", "wall"]
[particles]
count = {count}
polydispersity = 0.06
[contact]
restitution = {eps:?}
[capillary]
model = "thin_thread"
s_crit = 0.0711
e_cb = 0.2844
[drive]
kind = "sine"
gamma = {gamma:?}
e_star = {e_star:?}
[initial]
temperature_over_ecb = 20.0
seed = 2
[run]
duration = 1.0
"#
    ))
}

#[test]
fn gamma_and_e_star_convert_as_in_model_4_1() {
    let s = shaken_wet(5.0, 10.0, 0.9, 100);
    let (a, w) = s.drive_motion().unwrap();
    let e_cb = 0.2844;
    // E* = m (A omega)^2 / (2 E_cb), Gamma = A omega^2 / g.
    assert!(rel(0.5 * (a * w).powi(2) / e_cb, 10.0) < 1e-12);
    assert!(rel(a * w * w, 5.0) < 1e-12);
}

#[test]
fn zero_amplitude_shaken_path_conserves_energy_like_the_static_wall() {
    let s = scene_with(
        2,
        1.0,
        &[20.0, 12.0],
        &["periodic", "wall"],
        120,
        "polydispersity = 0.06\n[drive]\nkind = \"sine\"\namplitude = 0.0\nomega = 3.0\n\
         [initial]\ntemperature = 2.0\nseed = 5\n[run]\nduration = 1.0",
    );
    let mut e = Engine::<2, true, false>::new(&s);
    let a = e.energy();
    run_checked(&mut e, 200.0, 20, None);
    let b = e.energy();
    assert!(e.counts().wall_collisions > 1000, "{:?}", e.counts());
    assert!(rel(b.kinetic + b.potential, a.kinetic + a.potential) < 1e-9);
    assert_eq!(b.work_by_drive, 0.0);
    assert_eq!(b.dissipated_restitution, 0.0);
}

#[test]
fn ledger_with_the_drive_balances_in_gas_and_bed() {
    // Gas point (Gamma 5, E* 10) and a point where the bed rides the plate (Gamma 0.5, E* 0.1):
    // every joule the walls put in is dissipated, stored or booked.
    for (gamma, e_star, eps, count, t_end) in [
        (5.0, 10.0, 0.9, 200, 60.0),
        (5.0, 10.0, 1.0, 200, 60.0),
        (0.5, 0.1, 0.9, 60, 20.0),
    ] {
        let s = shaken_wet(gamma, e_star, eps, count);
        let mut e = Engine::<2, true, true>::new(&s);
        let a = e.energy();
        run_checked(&mut e, t_end, 20, Some(5_000_000));
        let b = e.energy();
        assert!(e.time() >= t_end, "Gamma {gamma}: stalled at {}", e.time());
        let err = rel(b.total_accounted(), a.total_accounted());
        assert!(
            err < 1e-10,
            "Gamma {gamma} E* {e_star} eps {eps}: ledger off by {err}"
        );
        if gamma > 1.0 {
            assert!(b.work_by_drive > 0.0, "the plate must heat the gas");
        }
    }
}

#[test]
fn bed_below_gamma_one_rides_the_plate_with_a_bounded_event_rate() {
    let n = 60;
    let s = shaken_wet(0.5, 0.1, 0.9, n);
    let mut e = Engine::<2, true, true>::new(&s);
    run_checked(&mut e, 15.0, 15, None);
    let (a, _) = s.drive_motion().unwrap();
    let mut rates = vec![];
    for k in 1..=3 {
        let n0 = e.counts().total();
        run_checked(&mut e, 15.0 + 3.0 * k as f64, 3, None);
        rates.push((e.counts().total() - n0) as f64 / 3.0 / n as f64);
    }
    let max = rates.iter().cloned().fold(0.0, f64::max);
    let min = rates.iter().cloned().fold(f64::INFINITY, f64::min);
    assert!(
        max < 5e4 && max < 3.0 * min,
        "event rate per grain {rates:?}"
    );
    // The bed stays low: mean height within a few diameters of the plate's reach.
    let mean_z = e.positions().iter().map(|x| x[1]).sum::<f64>() / n as f64;
    assert!(mean_z < a + 3.0, "mean height {mean_z}");
}

#[test]
fn flights_longer_than_the_solver_horizon_get_rechecks() {
    // A fast plate (period 0.2) and one disk thrown high in a tall box: its flights last many
    // periods, so its wall prediction is a re-check at the horizon, again and again, and it
    // still lands and bounces.
    let s = scene_with(
        2,
        1.0,
        &[10.0, 60.0],
        &["periodic", "wall"],
        1,
        "[drive]\nkind = \"sine\"\namplitude = 0.001\nomega = 31.4\n\
         [initial]\ntemperature = 0.0\n[run]\nduration = 1.0",
    );
    let mut e = Engine::<2, true, false>::new(&s);
    e.set_velocity(0, Vector::<2>::new(0.3, 8.0));
    let a = e.energy();
    run_checked(&mut e, 100.0, 100, None);
    let b = e.energy();
    let c = e.counts();
    assert!(c.wall_rechecks > 50, "{c:?}");
    assert!(c.wall_collisions > 5, "{c:?}");
    assert!(rel(b.total_accounted(), a.total_accounted()) < 1e-10);
}

#[test]
fn strong_shaking_with_a_tiny_amplitude_stays_inside() {
    // Gamma = 1000 with a tiny amplitude, and a wall speed of 50 sqrt(g d): with and without
    // bridges nothing leaves the box (sanity checks every chunk) and no NaN appears.
    // (A, omega): Gamma = 1000 with A = 1e-4 (omega = 3162); wall speed A omega = 50 with
    // A = 2 (omega = 25, Gamma = 1250).
    for (amplitude, omega) in [(1e-4, (1000.0f64 / 1e-4).sqrt()), (2.0, 25.0)] {
        for wet in [false, true] {
            let cap = if wet {
                "[capillary]\nmodel = \"thin_thread\"\ns_crit = 0.0711\ne_cb = 0.2844\n"
            } else {
                ""
            };
            let s = scene_with(
                2,
                1.0,
                &[30.0, 9.0],
                &["periodic", "wall"],
                100,
                &format!(
                    "polydispersity = 0.06\n[contact]\nrestitution = 0.9\n{cap}[drive]\nkind = \"sine\"\n\
                     amplitude = {amplitude:?}\nomega = {omega:?}\n[initial]\ntemperature = 1.0\n\
                     seed = 3\n[run]\nduration = 1.0"
                ),
            );
            if wet {
                let mut e = Engine::<2, true, true>::new(&s);
                run_checked(&mut e, 5.0, 25, Some(3_000_000));
            } else {
                let mut e = Engine::<2, true, false>::new(&s);
                run_checked(&mut e, 5.0, 25, Some(3_000_000));
            }
        }
    }
}
