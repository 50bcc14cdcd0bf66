//! Coexistence detection on prescribed configurations fed through the same observers a run
//! uses (`ObserverSet`): a 3D bed with a gas bubble in the middle of the plane is found by the
//! lateral-plane bins and missed by x-slabs of the same width; a dry bed with a dense cluster
//! and a dilute region is a coexistence by its packing profile; a homogeneous noisy state is
//! not a coexistence.

use rand::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;
use wetgran_core::observe::{Observables, ObserverSet, Phase, classify};
use wetgran_core::scene::Scene;
use wetgran_core::sim::Frame;

/// Seed of the prescribed configurations' noise.
const SEED: u64 = 11;
/// Samples fed per test (dt = 1 / 20 time units).
const SAMPLES: usize = 400;

fn scene(text: &str) -> Scene {
    Scene::from_toml_str(text, "test scene").expect("valid test scene")
}

/// Feeds `SAMPLES` frames made by `make(k, rng)` (sample `k`) and returns the observables.
fn observe(
    scene: &Scene,
    mut make: impl FnMut(usize, &mut Xoshiro256PlusPlus) -> Frame,
) -> Observables {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(SEED);
    let mut set = ObserverSet::new(scene);
    let dt = set.sample_interval();
    for k in 0..SAMPLES {
        let mut f = make(k, &mut rng);
        f.time = k as f64 * dt;
        set.observe(&f);
    }
    set.finish(scene)
}

/// A 3D monolayer of bonded grains on a square lattice over a 48 x 48 plane, jittering in place,
/// with a round hole of radius 8 in the middle filled by a few unbonded grains flying anywhere
/// inside it (a gas bubble).
fn bubble_frame(rng: &mut Xoshiro256PlusPlus, with_gas: usize) -> Frame {
    let (l, h) = (48.0, 3.0);
    let centre = (24.0, 24.0);
    let mut pos = Vec::new();
    let mut vel = Vec::new();
    let mut site = std::collections::HashMap::new();
    for iy in 0..48 {
        for ix in 0..48 {
            let (x, y) = (0.5 + ix as f64, 0.5 + iy as f64);
            if (x - centre.0).hypot(y - centre.1) < 8.0 {
                continue;
            }
            site.insert((ix, iy), pos.len() / 3);
            pos.extend([
                x + rng.gen_range(-0.02..0.02),
                y + rng.gen_range(-0.02..0.02),
                0.5,
            ]);
            vel.extend([rng.gen_range(-0.01..0.01), rng.gen_range(-0.01..0.01), 0.0]);
        }
    }
    let mut bridges = Vec::new();
    for (&(ix, iy), &i) in &site {
        for (dx, dy) in [(1, 0), (0, 1)] {
            if let Some(&j) = site.get(&((ix + dx) % 48, (iy + dy) % 48)) {
                bridges.push((i, j));
            }
        }
    }
    for _ in 0..with_gas {
        let r = 7.0 * rng.r#gen::<f64>().sqrt();
        let a = rng.gen_range(0.0..std::f64::consts::TAU);
        pos.extend([
            centre.0 + r * a.cos(),
            centre.1 + r * a.sin(),
            rng.gen_range(0.5..2.5),
        ]);
        vel.extend([
            rng.gen_range(-3.0..3.0),
            rng.gen_range(-3.0..3.0),
            rng.gen_range(-3.0..3.0),
        ]);
    }
    let n = pos.len() / 3;
    Frame::from_parts(
        3,
        vec![l, l, h],
        vec![true, true, false],
        pos,
        vel,
        vec![0.5; n],
        bridges,
    )
}

fn bubble_scene(bins_3d: &str, n: usize) -> Scene {
    scene(&format!(
        r#"
dimension = 3
gravity = 1.0
[box]
size = [48.0, 48.0, 3.0]
boundary = ["periodic", "periodic", "wall"]
[particles]
count = {n}
[capillary]
model = "thin_thread"
s_crit = 0.0711
e_cb = 0.2844
[initial]
temperature_over_ecb = 1.0
[run]
duration = 20.0
[observe]
bin_width = 4.0
mobility_lag = 2.0
bins_3d = "{bins_3d}"
"#
    ))
}

/// Seed of the one frame drawn only to count its grains (the frames observed are drawn from the
/// observer's own stream).
const FRAME_SIZE_SEED: u64 = 0;

#[test]
fn a_gas_bubble_in_the_plane_is_seen_by_plane_bins_and_missed_by_slabs() {
    let gas = 40;
    let n = bubble_frame(&mut Xoshiro256PlusPlus::seed_from_u64(FRAME_SIZE_SEED), gas).len();
    let plane = bubble_scene("plane", n);
    let obs = observe(&plane, |_, rng| bubble_frame(rng, gas));
    assert_eq!(obs.profiles.grid, Some((12, 12)));
    let c = classify(&obs, &plane.classify);
    let test = c.decided_on.coexistence.clone().unwrap();
    assert!(test.significant, "{}", c.decided_on.reason);
    assert_eq!(c.phase, Phase::Sgc, "{}", c.decided_on.reason);
    // The bubble's cells hold no bridges; the bed's cells hold two per grain per unit area.
    let dense = c.decided_on.dense.as_ref().unwrap();
    let dilute = c.decided_on.dilute.as_ref().unwrap();
    assert_eq!(dense.grains, "clustered");
    assert!(dilute.bins >= 4 && dilute.bins <= 16, "{}", dilute.bins);

    let slabs = bubble_scene("x_slabs", n);
    let obs = observe(&slabs, |_, rng| bubble_frame(rng, gas));
    assert_eq!(obs.profiles.grid, None);
    assert_eq!(obs.profiles.n_cb.len(), 12);
    let c = classify(&obs, &slabs.classify);
    let test = c.decided_on.coexistence.clone().unwrap();
    // The slab through the bubble is still two thirds bed: a dip, not a second phase.
    assert!(!test.significant, "{}", c.decided_on.reason);
    assert!(test.contrast < 0.5, "{}", test.contrast);
    assert!(!c.decided_on.split);
    assert!(
        matches!(c.phase, Phase::S | Phase::F | Phase::G),
        "{}",
        c.decided_on.reason
    );
}

/// A dry 2D bed: x in [0, 32) a dense cluster (touching grains in rows, jittering), x in
/// [32, 64) a dilute gas of grains anywhere. Without bridges `Delta n_cb` is zero; the packing
/// profile shows the coexistence.
fn dry_frame(rng: &mut Xoshiro256PlusPlus) -> Frame {
    let mut pos = Vec::new();
    let mut vel = Vec::new();
    for iz in 0..6 {
        for ix in 0..31 {
            pos.extend([
                0.5 + 1.02 * ix as f64 + rng.gen_range(-0.005..0.005),
                0.5 + 1.02 * iz as f64,
            ]);
            vel.extend([rng.gen_range(-0.01..0.01), rng.gen_range(-0.01..0.01)]);
        }
    }
    for _ in 0..20 {
        pos.extend([rng.gen_range(33.0..63.0), rng.gen_range(0.5..7.5)]);
        vel.extend([rng.gen_range(-4.0..4.0), rng.gen_range(-4.0..4.0)]);
    }
    let n = pos.len() / 2;
    Frame::from_parts(
        2,
        vec![64.0, 8.0],
        vec![true, false],
        pos,
        vel,
        vec![0.5; n],
        vec![],
    )
}

fn dry_scene(n: usize) -> Scene {
    scene(&format!(
        r#"
dimension = 2
gravity = 1.0
[box]
size = [64.0, 8.0]
boundary = ["periodic", "wall"]
[particles]
count = {n}
[initial]
temperature = 1.0
[run]
duration = 20.0
[observe]
bin_width = 4.0
mobility_lag = 2.0
"#
    ))
}

#[test]
fn a_dry_bed_with_a_dense_cluster_and_a_dilute_region_coexists() {
    let n = dry_frame(&mut Xoshiro256PlusPlus::seed_from_u64(FRAME_SIZE_SEED)).len();
    let s = dry_scene(n);
    let obs = observe(&s, |_, rng| dry_frame(rng));
    assert_eq!(obs.profiles.delta_n_cb, 0.0);
    let c = classify(&obs, &s.classify);
    let test = c.decided_on.coexistence.clone().unwrap();
    assert_eq!(test.profile, "packing");
    assert!(test.significant, "{}", c.decided_on.reason);
    assert_eq!(c.phase, Phase::Sgc, "{}", c.decided_on.reason);
    // The cluster's grains are clustered by their close neighbours (>= 2 within 0.1 d).
    assert_eq!(c.decided_on.dense.as_ref().unwrap().grains, "clustered");
}

/// A homogeneous dry gas sampled anew at every sample: the packing profile fluctuates, and its
/// spread stays inside the noise baseline.
#[test]
fn a_homogeneous_gas_is_not_a_coexistence() {
    let make = |_: usize, rng: &mut Xoshiro256PlusPlus| {
        let n = 200;
        let pos: Vec<f64> = (0..n)
            .flat_map(|_| [rng.gen_range(0.0..64.0), rng.gen_range(0.5..7.5)])
            .collect();
        let vel: Vec<f64> = (0..2 * n).map(|_| rng.gen_range(-3.0..3.0)).collect();
        Frame::from_parts(
            2,
            vec![64.0, 8.0],
            vec![true, false],
            pos,
            vel,
            vec![0.5; n],
            vec![],
        )
    };
    let s = dry_scene(200);
    let obs = observe(&s, make);
    let c = classify(&obs, &s.classify);
    let test = c.decided_on.coexistence.clone().unwrap();
    assert!(!test.significant, "{}", c.decided_on.reason);
    assert!(test.delta > 0.0);
    // The measured spread is of the size the baseline expects (within a factor of 2).
    let ratio = test.delta / test.expected_noise.unwrap();
    assert!((0.5..2.0).contains(&ratio), "{ratio}");
    assert_eq!(c.phase, Phase::G, "{}", c.decided_on.reason);
}
