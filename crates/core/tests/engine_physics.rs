//! Physics of the event-driven engine against conservation laws, exact bookkeeping and kinetic
//! theory (Enskog collision frequency with the Henderson and Carnahan-Starling equations of
//! state). Run in release mode: `cargo test --release`.

use wetgran_testkit as common;

use common::{run_checked, run_events, scene, scene_with};
use std::f64::consts::PI;
use wetgran_core::scene::RuptureRule;
use wetgran_core::sim::event_driven::{Engine, Vector};
use wetgran_core::sim::run_scene;

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs().max(1e-300)
}

#[test]
fn elastic_dry_periodic_3d_conserves_energy_and_momentum_over_a_million_events() {
    let s = scene_with(3, 0.0, &[12.0, 12.0, 12.0], &["periodic"; 3], 1000, "");
    let mut e = Engine::<3, false, false>::new(&s);
    let e0 = e.energy().kinetic;
    let p0 = e.momentum();
    run_events(&mut e, 1_000_000, 250_000);
    let e1 = e.energy().kinetic;
    let p1 = e.momentum();
    assert!(e.counts().pair_collisions > 300_000, "{:?}", e.counts());
    assert!(rel(e1, e0) < 1e-12, "kinetic energy drift {}", rel(e1, e0));
    // Momentum starts at zero: compare with the momentum scale sqrt(N m T).
    assert!(
        (p1 - p0).norm() < 1e-11 * (1000.0f64).sqrt(),
        "momentum drift {}",
        (p1 - p0).norm()
    );
}

#[test]
fn elastic_dry_periodic_2d_conserves_energy_and_momentum_over_a_million_events() {
    let s = scene_with(2, 0.0, &[40.0, 40.0], &["periodic"; 2], 800, "");
    let mut e = Engine::<2, false, false>::new(&s);
    let e0 = e.energy().kinetic;
    run_events(&mut e, 1_000_000, 250_000);
    assert!(rel(e.energy().kinetic, e0) < 1e-12);
    assert!(e.momentum().norm() < 1e-11 * (800.0f64).sqrt());
}

#[test]
fn elastic_with_gravity_and_static_walls_conserves_total_energy() {
    for dim in [2usize, 3] {
        let (size, boundary): (Vec<f64>, Vec<&str>) = if dim == 2 {
            (vec![30.0, 15.0], vec!["periodic", "wall"])
        } else {
            (vec![10.0, 10.0, 12.0], vec!["periodic", "wall", "wall"])
        };
        let s = scene_with(dim, 1.0, &size, &boundary, 300, "polydispersity = 0.1");
        let (a, b) = if dim == 2 {
            let mut e = Engine::<2, true, false>::new(&s);
            let a = e.energy();
            run_events(&mut e, 400_000, 100_000);
            (a, e.energy())
        } else {
            let mut e = Engine::<3, true, false>::new(&s);
            let a = e.energy();
            run_events(&mut e, 400_000, 100_000);
            (a, e.energy())
        };
        let (t0, t1) = (a.kinetic + a.potential, b.kinetic + b.potential);
        assert!(
            rel(t1, t0) < 1e-9,
            "{dim}D: total energy drift {}",
            rel(t1, t0)
        );
        // Energy really moved between kinetic and potential.
        assert!((b.kinetic - a.kinetic).abs() > 1e-3 * t0);
        assert_eq!(b.dissipated_restitution, 0.0);
        assert_eq!(b.added_by_collapse_remedies, 0.0);
    }
}

/// Two disks on a line, no gravity; returns (kinetic energy lost, ledger's dissipation).
fn head_on(eps: f64, u: f64) -> (f64, f64, f64) {
    let mut s = scene_with(
        2,
        0.0,
        &[20.0, 20.0],
        &["periodic", "periodic"],
        2,
        &format!(
            "[contact]\nrestitution = {eps}\n[initial]\ntemperature = 0.0\n[run]\nduration = 1.0"
        ),
    );
    // Plain restitution: no collapse remedy (validation insists on one, so switch it off here).
    s.engine.min_rebound_speed = 0.0;
    let mut e = Engine::<2, false, false>::new(&s);
    e.set_position(0, Vector::<2>::new(5.0, 10.0));
    e.set_position(1, Vector::<2>::new(8.0, 10.3));
    e.set_velocity(0, Vector::<2>::new(u, 0.1));
    e.set_velocity(1, Vector::<2>::new(-0.5 * u, 0.0));
    let k0 = e.energy().kinetic;
    e.run_until(10.0, None);
    e.sanity_check().unwrap();
    assert_eq!(e.counts().pair_collisions, 1);
    let led = e.energy();
    (k0 - led.kinetic, led.dissipated_restitution, k0)
}

#[test]
fn restitution_loses_the_energy_of_the_formula() {
    for eps in [1.0, 0.96, 0.9, 0.8, 0.0] {
        let (lost, ledger, _) = head_on(eps, 1.0);
        // Geometry of `head_on`: centres 3 apart in x, 0.3 in z, relative velocity (1.5, 0.1).
        // Contact normal at the collision, computed independently: solve |r + v t| = 1.
        let (r, v) = (Vector::<2>::new(-3.0, -0.3), Vector::<2>::new(1.5, 0.1));
        let (b, vv, c) = (r.dot(&v), v.norm_squared(), r.norm_squared() - 1.0);
        let t = (-b - (b * b - vv * c).sqrt()) / vv;
        let n = r + v * t; // unit length at contact, from particle 1 to particle 0
        let u = v.dot(&n);
        // E_normal (1 - eps^2) with E_normal = mu u^2 / 2, mu = m/2.
        let expected = 0.25 * u * u * (1.0 - eps * eps);
        assert!(
            (lost - expected).abs() < 1e-14,
            "eps {eps}: lost {lost}, expected {expected}"
        );
        assert!((ledger - expected).abs() < 1e-14);
    }
}

fn wet_scene(rule: &str, gravity: f64, eps: f64) -> wetgran_core::scene::Scene {
    scene(&format!(
        r#"
dimension = 2
gravity = {gravity:?}
[box]
size = [40.0, 12.0]
boundary = ["periodic", "wall"]
[particles]
count = 200
polydispersity = 0.06
[contact]
restitution = {eps:?}
[capillary]
model = "thin_thread"
s_crit = 0.0711
e_cb = 0.2844
rupture_rule = "{rule}"
[initial]
temperature_over_ecb = 4.0
seed = 5
[run]
duration = 1.0
"#
    ))
}

#[test]
fn thin_thread_elastic_loses_exactly_ecb_per_rupture_and_counts_agree() {
    let e_cb = 0.2844;
    for (rule, per_rupture) in [("reduced_mass", e_cb), ("thesis_appendix", 0.5 * e_cb)] {
        let s = wet_scene(rule, 1.0, 1.0);
        assert_eq!(
            s.rupture_rule(),
            if rule == "reduced_mass" {
                RuptureRule::ReducedMass
            } else {
                RuptureRule::ThesisAppendix
            }
        );
        let mut e = Engine::<2, true, true>::new(&s);
        let a = e.energy();
        run_checked(&mut e, 40.0, 20, None);
        let b = e.energy();
        let c = e.counts().clone();
        assert!(
            c.bridge_ruptures > 200,
            "{rule}: too few ruptures to test: {c:?}"
        );
        assert!(
            c.well_bounces > 200,
            "{rule}: too few bounces to test: {c:?}"
        );
        // Mechanical energy actually lost, from the particle states alone.
        // (The rebound floor may push a bonded pair grazing the well wall back inwards; that
        // energy is booked and is orders of magnitude below a rupture.)
        let lost =
            (a.kinetic + a.potential) - (b.kinetic + b.potential) + b.added_by_collapse_remedies;
        assert!(b.added_by_collapse_remedies < 1e-3 * e_cb, "{b:?}");
        let expected = per_rupture * c.bridge_ruptures as f64;
        assert!(
            (lost - expected).abs() < 1e-9 * expected,
            "{rule}: lost {lost}, {} ruptures x {per_rupture} = {expected}",
            c.bridge_ruptures
        );
        assert_eq!(b.dissipated_restitution, 0.0);
        // Bridge bookkeeping: formations - ruptures = bridges now.
        assert_eq!(
            c.bridge_formations - c.bridge_ruptures,
            e.bridge_count() as u64,
            "{rule}: {c:?}"
        );
    }
}

#[test]
fn inelastic_wet_ledger_balances() {
    let s = wet_scene("reduced_mass", 1.0, 0.8);
    let mut e = Engine::<2, true, true>::new(&s);
    let a = e.energy();
    run_checked(&mut e, 20.0, 10, None);
    let b = e.energy();
    assert!(b.dissipated_restitution > 0.0 && b.dissipated_ruptures > 0.0);
    assert!(rel(b.total_accounted(), a.total_accounted()) < 1e-10);
    let expected = 0.2844 * e.counts().bridge_ruptures as f64;
    assert!(rel(b.dissipated_ruptures, expected) < 1e-12);
}

#[test]
fn bonded_pair_bounces_many_times_and_never_stretches() {
    // Two disks bonded on first contact, elastic, no gravity: they shuttle between contact and
    // the well edge at constant relative speed u, so a contact-to-edge leg lasts s_crit / u.
    let (s_crit, u) = (0.0711, 0.05);
    let s = scene_with(
        2,
        0.0,
        &[10.0, 10.0],
        &["periodic", "periodic"],
        2,
        &format!(
            "[capillary]\nmodel = \"thin_thread\"\ns_crit = {s_crit}\ne_cb = 0.2844\n[initial]\ntemperature = 0.0\n[run]\nduration = 1.0"
        ),
    );
    let mut e = Engine::<2, false, true>::new(&s);
    e.set_position(0, Vector::<2>::new(4.0, 5.0));
    e.set_position(1, Vector::<2>::new(5.0 + 1e-3, 5.0));
    // Slightly oblique so the pair also rotates: the contact normal changes every leg.
    e.set_velocity(0, Vector::<2>::new(0.5 * u, 0.002));
    e.set_velocity(1, Vector::<2>::new(-0.5 * u, -0.002));
    let t_end = 2000.0;
    run_checked(&mut e, t_end, 200, None);
    let c = e.counts();
    assert_eq!(e.bridge_count(), 1);
    assert_eq!(c.bridge_formations, 1);
    assert_eq!(c.bridge_ruptures, 0);
    // Normal speed is not exactly u (tangential motion), so bound the count from both sides:
    // at most t_end / (s_crit / u) legs at normal speed <= |v_rel| ~ u.
    let legs = (c.well_bounces + c.pair_collisions) as f64;
    let v_rel = (u * u + 0.004f64 * 0.004).sqrt();
    let max_legs = t_end / (s_crit / v_rel) + 2.0;
    assert!(c.well_bounces > 500, "{c:?}");
    assert!(
        legs <= max_legs && legs > 0.8 * max_legs,
        "{legs} legs, at most {max_legs}"
    );
}

/// Enskog collision frequency per particle: 2D `2 n sigma g(sigma) sqrt(pi T / m)`,
/// 3D `4 n sigma^2 g(sigma) sqrt(pi T / m)`; `g(sigma)` from Henderson (2D),
/// `(1 - 7 phi / 16) / (1 - phi)^2`, or Carnahan-Starling (3D), `(1 - phi / 2) / (1 - phi)^3`.
fn enskog_frequency(dim: usize, phi: f64, temperature: f64) -> f64 {
    if dim == 2 {
        let n = phi * 4.0 / PI;
        let g = (1.0 - 7.0 * phi / 16.0) / (1.0 - phi).powi(2);
        2.0 * n * g * (PI * temperature).sqrt()
    } else {
        let n = phi * 6.0 / PI;
        let g = (1.0 - 0.5 * phi) / (1.0 - phi).powi(3);
        4.0 * n * g * (PI * temperature).sqrt()
    }
}

fn measured_frequency(dim: usize, phi: f64) -> f64 {
    let n_part = 2000usize;
    let density = if dim == 2 {
        phi * 4.0 / PI
    } else {
        phi * 6.0 / PI
    };
    let side = (n_part as f64 / density).powf(1.0 / dim as f64);
    let size = vec![side; dim];
    let boundary = vec!["periodic"; dim];
    let s = scene_with(
        dim,
        0.0,
        &size,
        &boundary,
        n_part,
        "[initial]\ntemperature = 1.0\nseed = 11\n[run]\nduration = 1.0",
    );
    macro_rules! measure {
        ($d:literal) => {{
            let mut e = Engine::<$d, false, false>::new(&s);
            // Melt the lattice: 30 collisions per particle.
            run_events(&mut e, 30 * n_part as u64, 1_000_000);
            let (c0, t0) = (e.counts().pair_collisions, e.time());
            run_events(&mut e, 300 * n_part as u64, 1_000_000);
            let (c1, t1) = (e.counts().pair_collisions, e.time());
            let temperature = e.granular_temperature();
            assert!(rel(temperature, 1.0) < 1e-9);
            // Each collision involves two particles.
            2.0 * (c1 - c0) as f64 / (n_part as f64 * (t1 - t0))
        }};
    }
    if dim == 2 { measure!(2) } else { measure!(3) }
}

#[test]
fn hard_disk_collision_frequency_matches_enskog_henderson() {
    for phi in [0.1, 0.3] {
        let (m, t) = (measured_frequency(2, phi), enskog_frequency(2, phi, 1.0));
        eprintln!(
            "2D phi {phi}: measured {m:.5}, Enskog-Henderson {t:.5}, ratio {:.4}",
            m / t
        );
        assert!(
            rel(m, t) < 0.02,
            "2D phi {phi}: measured {m}, Enskog {t}, off by {:.3}",
            rel(m, t)
        );
    }
}

#[test]
fn hard_sphere_collision_frequency_matches_enskog_carnahan_starling() {
    for phi in [0.1, 0.3] {
        let (m, t) = (measured_frequency(3, phi), enskog_frequency(3, phi, 1.0));
        eprintln!(
            "3D phi {phi}: measured {m:.5}, Enskog-Carnahan-Starling {t:.5}, ratio {:.4}",
            m / t
        );
        assert!(
            rel(m, t) < 0.02,
            "3D phi {phi}: measured {m}, Enskog {t}, off by {:.3}",
            rel(m, t)
        );
    }
}

#[test]
fn same_scene_and_seed_give_identical_runs() {
    let mut s = wet_scene("reduced_mass", 1.0, 0.9);
    s.run.duration = 5.0;
    s.run.sample_interval = 1.0;
    let (mut a, mut b) = (run_scene(&s), run_scene(&s));
    assert_eq!(a.invariant_violation, None);
    a.wall_seconds = 0.0;
    b.wall_seconds = 0.0;
    // Where the wall time went is not part of a run's numbers.
    a.timing = Default::default();
    b.timing = Default::default();
    assert_eq!(a, b);
    // And a different seed gives a different run.
    s.initial.seed += 1;
    let mut c = run_scene(&s);
    c.wall_seconds = 0.0;
    assert_ne!(a.samples, c.samples);
}

#[test]
fn bridge_across_the_periodic_seam_holds_and_bounces() {
    // The same shuttling pair as above, but straddling x = 0 = L: minimum-image separations must
    // make the bridge, its well wall and its contact work across the seam, in 3D too.
    let (s_crit, u) = (0.0711, 0.05);
    let s = scene_with(
        3,
        0.0,
        &[6.0, 6.0, 6.0],
        &["periodic"; 3],
        2,
        &format!(
            "[capillary]\nmodel = \"thin_thread\"\ns_crit = {s_crit}\ne_cb = 0.2844\n[initial]\ntemperature = 0.0\n[run]\nduration = 1.0"
        ),
    );
    let mut e = Engine::<3, false, true>::new(&s);
    e.set_position(0, Vector::<3>::new(0.3, 3.0, 3.0));
    e.set_position(1, Vector::<3>::new(6.0 - 0.7 - 1e-3, 3.0, 3.0));
    // A common drift along y carries the pair through cells while it shuttles.
    e.set_velocity(0, Vector::<3>::new(-0.5 * u, 0.03, 0.001));
    e.set_velocity(1, Vector::<3>::new(0.5 * u, 0.03, -0.001));
    let k0 = e.energy().kinetic;
    run_checked(&mut e, 500.0, 50, None);
    let c = e.counts();
    assert_eq!((c.bridge_formations, c.bridge_ruptures), (1, 0), "{c:?}");
    assert!(c.well_bounces > 100, "{c:?}");
    assert!(
        c.cell_crossings > 0,
        "the pair should drift across cells: {c:?}"
    );
    assert_eq!(e.bridge_count(), 1);
    assert!(rel(e.energy().kinetic, k0) < 1e-12);
}
