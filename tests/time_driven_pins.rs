//! Trajectory pins of the time-driven engine: a digest of the exact state (every bit of every
//! position and velocity, the clock, the contact and bridge counts, the bridges and the energy
//! ledger) after a fixed number of steps, for one scene per engine configuration (Gear and
//! Verlet, dry and wet, 2D and 3D, gravity, shaken walls, the shear body force).
//!
//! The digests were recorded on the engine before the step was split into a parallel pair
//! phase and a per-particle phase (issue 15, branch `rayon`); a change of the loop structure
//! or of the threading must reproduce them bit for bit. A change that alters the numbers on
//! purpose must re-record them and say why in its commit.
//!
//! Every pinned run is made with one thread and with two (a rayon pool of that size installed
//! around the run), and the two runs must agree bit for bit: the engine's result does not
//! depend on the number of threads.

mod common;

use common::scene_with;
use wetgran::scene::Scene;
use wetgran::sim::time_driven::shear::CosineShear;
use wetgran::sim::time_driven::{BodyForce, TimeEngine};

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

/// Digest of the full observable state of an engine.
fn digest<const D: usize, const G: bool, const W: bool, B: BodyForce<D>>(
    e: &TimeEngine<D, G, W, B>,
) -> u64 {
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
    h.float(e.max_overlap());
    h.word(e.list_builds());
    h.0
}

/// Runs `run` on a rayon pool of `threads` threads and returns its digest.
fn on_threads(threads: usize, run: impl FnOnce() -> u64 + Send) -> u64 {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a thread pool")
        .install(run)
}

/// The pinned digest, checked on one and on two threads.
fn check(name: &str, want: u64, run: impl Fn() -> u64 + Send + Sync) {
    let one = on_threads(1, &run);
    let two = on_threads(2, &run);
    assert_eq!(
        one, two,
        "{name}: one thread {one:#018x}, two threads {two:#018x}"
    );
    assert_eq!(one, want, "{name}: digest {one:#018x}, pinned {want:#018x}");
}

/// The scene of `wetgran bench tdmd` (1200 dry disks, shaken floor and lid, damped contacts).
fn bench_scene(integrator: &str) -> Scene {
    wetgran::bench::tdmd::scene(integrator)
}

#[test]
fn bench_scene_gear() {
    let s = bench_scene("gear5");
    check("bench gear5", 0x3ff3_a2bc_0258_7589, || {
        let mut e = TimeEngine::<2, true, false>::new(&s);
        e.run_until(0.3);
        digest(&e)
    });
}

#[test]
fn bench_scene_verlet() {
    let s = bench_scene("verlet");
    check("bench verlet", 0x15f9_8344_746e_2c7a, || {
        let mut e = TimeEngine::<2, true, false>::new(&s);
        e.run_until(0.3);
        digest(&e)
    });
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
    check("wet 2D gear5", 0x1c53_d215_2e51_c62f, || {
        let mut e = TimeEngine::<2, true, true>::new(&s);
        e.run_until(1.5);
        assert!(e.counts().bridge_ruptures > 0, "the run ruptures bridges");
        digest(&e)
    });
}

#[test]
fn wet_2d_verlet() {
    let s = wet_2d("verlet");
    check("wet 2D verlet", 0xf635_fe23_4307_af2f, || {
        let mut e = TimeEngine::<2, true, true>::new(&s);
        e.run_until(1.5);
        digest(&e)
    });
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
    check("wet 3D gear5", 0x40b6_5925_7472_c498, || {
        let mut e = TimeEngine::<3, true, true>::new(&s);
        e.run_until(0.5);
        digest(&e)
    });
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
    check("sheared 3D gear5", 0xa8da_b82e_c538_834b, || {
        let mut e = TimeEngine::<3, false, false, CosineShear>::with_body_force(&s, field);
        e.run_until(0.5);
        digest(&e)
    });
}
