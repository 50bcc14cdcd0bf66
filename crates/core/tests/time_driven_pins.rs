//! Trajectory pins of the time-driven engine: a digest of the exact state (every bit of every
//! position and velocity, the clock, the contact and bridge counts, the bridges and the energy
//! ledger) after a fixed number of steps, for one scene per engine configuration (Gear and
//! Verlet, dry and wet, 2D and 3D, gravity, shaken walls, the shear body force).
//!
//! The state digests were recorded on the engine before the step was split into a parallel
//! pair phase and a per-particle phase (issue 15, branch `rayon`, commit "crates/core/tests/time_driven_pins.rs");
//! the split reproduces them bit for bit. The books digests of the three wet scenes are also
//! the engine's before the split; those of the bench scenes and the sheared scene changed with
//! it, by round-off only: the dissipation and the drive work are now summed per chunk of 128
//! coordinates (or list entries) and the chunk sums added in order, so that they do not depend
//! on the number of threads (with chunks larger than the system, the split engine gave the
//! old books digests too). A change that alters the numbers on purpose must re-record them
//! and say why in its commit.
//!
//! Every pinned run is made with one thread and with two (a rayon pool of that size installed
//! around the run, as `sim::threads::Threads` does), and the two runs must agree bit for bit:
//! the engine's result does not depend on the number of threads.

use wetgran_testkit as common;

use common::scene_with;
use wetgran_core::scene::Scene;
use wetgran_core::sim::time_driven::shear::CosineShear;
use wetgran_core::sim::time_driven::{BodyForce, TimeEngine};

/// FNV-1a over 64-bit words.
struct Digest(u64);

impl Digest {
    fn new() -> Self {
        Digest(0xcbf2_9ce4_8422_2325)
    }
    fn word(&mut self, w: u64) {
        for b in w.to_le_bytes() {
            self.0 ^= u64::from(b);
            self.0 = self.0.wrapping_mul(0x0100_0000_01b3);
        }
    }
    fn float(&mut self, x: f64) {
        self.word(x.to_bits());
    }
}

/// Digests of an engine: the state (clock, every position and velocity, counts, bridges,
/// largest overlap, list builds) and the energy books.
fn digest<const D: usize, const G: bool, const W: bool, B: BodyForce<D>>(
    e: &TimeEngine<D, G, W, B>,
) -> (u64, u64) {
    let mut h = Digest::new();
    h.word(e.steps());
    h.float(e.time());
    for a in e.positions_flat() {
        h.float(a);
    }
    for a in e.velocities_flat() {
        h.float(a);
    }
    let c = e.counts();
    for w in [
        c.pair_collisions,
        c.wall_collisions,
        c.bridge_formations,
        c.bridge_ruptures,
    ] {
        h.word(w);
    }
    for (i, j) in e.bridges() {
        h.word(i as u64);
        h.word(j as u64);
    }
    h.float(e.max_overlap());
    h.word(e.list_builds());
    let state = h.0;
    let mut h = Digest::new();
    let l = e.energy();
    for x in [
        l.kinetic,
        l.potential,
        l.dissipated_restitution,
        l.dissipated_ruptures,
        l.work_by_drive,
    ] {
        h.float(x);
    }
    (state, h.0)
}

/// Runs `run` on a rayon pool of `threads` threads and returns its digests.
fn on_threads(threads: usize, run: impl FnOnce() -> (u64, u64) + Send) -> (u64, u64) {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a thread pool")
        .install(run)
}

/// The pinned digests (state, books), checked on one and on two threads.
fn check(name: &str, want: (u64, u64), run: impl Fn() -> (u64, u64) + Send + Sync) {
    let one = on_threads(1, &run);
    let two = on_threads(2, &run);
    assert_eq!(
        one, two,
        "{name}: one thread {one:#018x?}, two threads {two:#018x?}"
    );
    assert_eq!(
        one.0, want.0,
        "{name}: state digest {:#018x}, pinned {:#018x}",
        one.0, want.0
    );
    assert_eq!(
        one.1, want.1,
        "{name}: books digest {:#018x}, pinned {:#018x}",
        one.1, want.1
    );
}

/// The scene of `wetgran-bench tdmd` (1200 dry disks, shaken floor and lid, damped contacts).
///
/// Re-pinned on 2026-11-23 (issue 17): its `A_d` (restitution 0.9 at impact speed 1) now comes
/// from the scaled calibration of `physics::hertz::damping_for_restitution`,
/// 1.4713856731400212e-4 against 1.471385673140047e-4 before: 8 ulp apart, inside the old
/// bisection's own resolution (1e-2 / 2^50 = 9e-18 absolute). Both integrators' state and books
/// digests changed with it; nothing else did.
fn bench_scene(integrator: &str) -> Scene {
    wetgran_testkit::reference::dry_shaken_time_driven(integrator)
}

/// Gear on this scene (1200 particles) runs on the spatial domains (`domains.rs`, issue 15
/// item 4) since 2026-11-26: the state digest is unchanged (within 0.3 time units the changed
/// order of the force sums changed no bit of this dilute, dry system), the books digest was
/// re-pinned (0xe665_810d_3efb_faf6 before): the dissipation and the drive work are now summed
/// per domain and step, not per chunk of 128 coordinates or entries, a round-off change.
#[test]
fn bench_scene_gear() {
    let s = bench_scene("gear5");
    check(
        "bench gear5",
        (0x4cef_122d_97f7_9569, 0x7a37_ea3b_3ce6_04de),
        || {
            let mut e = TimeEngine::<2, true, false>::new(&s);
            e.run_until(0.3);
            digest(&e)
        },
    );
}

#[test]
fn bench_scene_verlet() {
    let s = bench_scene("verlet");
    check(
        "bench verlet",
        (0xd19b_9c90_240d_9390, 0x056b_3114_7928_054a),
        || {
            let mut e = TimeEngine::<2, true, false>::new(&s);
            e.run_until(0.3);
            digest(&e)
        },
    );
}

/// A small shaken wet bed of disks (bridges form and rupture).
fn wet_2d(integrator: &str) -> Scene {
    scene_with(
        2,
        1.0,
        &[40.0, 9.0],
        &["periodic", "wall"],
        120,
        &format!(
            "[contact]\ndamping = 1.5e-4\n[capillary]\nmodel = \"thin_thread\"\ns_crit = 0.0711\ne_cb = 0.2844\n\
             [drive]\nkind = \"sine\"\ngamma = 5.0\ne_star = 10.0\n[initial]\ntemperature_over_ecb = 20.0\n\
             [engine]\nkind = \"time\"\nintegrator = \"{integrator}\"\n"
        ),
    )
}

#[test]
fn wet_2d_gear() {
    let s = wet_2d("gear5");
    check(
        "wet 2D gear5",
        (0x5cf0_9ae3_7594_a66a, 0x7b4d_fcee_2b9e_47bc),
        || {
            let mut e = TimeEngine::<2, true, true>::new(&s);
            e.run_until(1.5);
            assert!(e.counts().bridge_ruptures > 0, "the run ruptures bridges");
            digest(&e)
        },
    );
}

#[test]
fn wet_2d_verlet() {
    let s = wet_2d("verlet");
    check(
        "wet 2D verlet",
        (0xdaec_5b1f_afe8_a063, 0xbf20_8030_40b7_bcd9),
        || {
            let mut e = TimeEngine::<2, true, true>::new(&s);
            e.run_until(1.5);
            digest(&e)
        },
    );
}

/// A small shaken wet bed of spheres.
#[test]
fn wet_3d_gear() {
    let s = scene_with(
        3,
        1.0,
        &[8.0, 8.0, 8.0],
        &["periodic", "periodic", "wall"],
        150,
        "[contact]\ndamping = 1.5e-4\n[capillary]\nmodel = \"thin_thread\"\ns_crit = 0.0711\ne_cb = 0.2844\n\
         [drive]\nkind = \"sine\"\ngamma = 5.0\ne_star = 10.0\n[initial]\ntemperature_over_ecb = 20.0\n\
         [engine]\nkind = \"time\"\n",
    );
    check(
        "wet 3D gear5",
        (0x0d73_c090_5dd6_d1c1, 0xf150_4364_fc96_d60c),
        || {
            let mut e = TimeEngine::<3, true, true>::new(&s);
            e.run_until(0.5);
            digest(&e)
        },
    );
}

/// Dry spheres under the shear body force, no gravity (the body-force path).
#[test]
fn sheared_3d_gear() {
    let s = scene_with(
        3,
        0.0,
        &[12.0, 12.0, 6.0],
        &["periodic", "periodic", "wall"],
        200,
        "[contact]\ndamping = 1.5e-4\n[drive]\nkind = \"shear\"\nf_max = 0.5\n\
         [initial]\ntemperature = 1.0\n[engine]\nkind = \"time\"\n",
    );
    let field = CosineShear::of_scene(&s).expect("a shear scene");
    check(
        "sheared 3D gear5",
        (0xf930_23bd_a721_634c, 0xa188_7632_67d8_c325),
        || {
            let mut e = TimeEngine::<3, false, false, CosineShear>::with_body_force(&s, field);
            e.run_until(0.5);
            digest(&e)
        },
    );
}
