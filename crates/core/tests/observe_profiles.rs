//! Lateral profiles on hand-built configurations: bridge density against a hand count,
//! `Delta n_cb` of homogeneous and half-bonded lattices, and the packing fraction and bin
//! temperature a run reports (one frame fed through `ObserverSet`) against their formulas.

use std::f64::consts::PI;
use wetgran_core::observe::bins::LateralBins;
use wetgran_core::observe::profiles::{bridge_density, spread};
use wetgran_core::observe::temperature::granular_temperature;
use wetgran_core::observe::{ObserverSet, Profiles};
use wetgran_core::scene::Scene;
use wetgran_core::sim::Frame;

/// A 2D frame, periodic in x, walls in z.
fn frame(
    size: [f64; 2],
    pos: &[[f64; 2]],
    vel: &[[f64; 2]],
    r: f64,
    bridges: Vec<(usize, usize)>,
) -> Frame {
    Frame::from_parts(
        2,
        size.to_vec(),
        vec![true, false],
        pos.iter().flat_map(|p| p.to_vec()).collect(),
        vel.iter().flat_map(|p| p.to_vec()).collect(),
        vec![r; pos.len()],
        bridges,
    )
}

/// The profiles the observers report for the single frame `f` of a dry, weightless 2D scene
/// in the box 16 x 4 (periodic in x, walls in z) with bins of width 4: temperatures in units
/// of `m = 1`. The scene only sets up the observers (its own grains are never placed), so its
/// particle count need not be the frame's.
fn observed_profiles(f: &Frame) -> Profiles {
    let text = "dimension = 2\ngravity = 0.0\n[box]\nsize = [16.0, 4.0]\nboundary = [\"periodic\", \
         \"wall\"]\n[particles]\ncount = 1\n[initial]\ntemperature = 1.0\n[run]\n\
         duration = 1.0\n[observe]\nbin_width = 4.0\ndiffusion = false\n";
    let scene = Scene::from_toml_str(text, "profile frame").expect("valid scene");
    let mut set = ObserverSet::new(&scene);
    set.observe(f);
    let o = set.finish(&scene);
    assert_eq!(o.temperature_unit, 1.0);
    o.profiles
}

/// A square lattice of `cols x rows` sites of spacing 1 starting at (0.5, 0.5), at rest.
fn square(cols: usize, rows: usize) -> Vec<[f64; 2]> {
    let mut p = Vec::new();
    for r in 0..rows {
        for c in 0..cols {
            p.push([0.5 + c as f64, 0.5 + r as f64]);
        }
    }
    p
}

#[test]
fn bridge_density_equals_hand_count() {
    // Box 16 x 4, bins of 4: [0,4) [4,8) [8,12) [12,16).
    let pos = [
        [1.0, 1.0],  // 0
        [2.0, 1.0],  // 1: bridge 0-1, midpoint 1.5 -> bin 0
        [3.5, 2.0],  // 2
        [4.5, 2.0],  // 3: bridge 2-3, midpoint 4.0 -> bin 1 (left-closed bins)
        [9.0, 1.0],  // 4
        [10.0, 1.0], // 5: bridges 4-5 (9.5) and 5-6 (10.5) -> bin 2 twice
        [11.0, 1.0], // 6
        [0.3, 3.0],  // 7
        [15.8, 3.0], // 8: bridge 7-8 across the seam, midpoint 16.05 = 0.05 -> bin 0
        [14.0, 1.0], // 9: no bridge
    ];
    let vel = [[0.0; 2]; 10];
    let f = frame(
        [16.0, 4.0],
        &pos,
        &vel,
        0.5,
        vec![(0, 1), (3, 2), (4, 5), (5, 6), (8, 7)],
    );
    let bins = LateralBins::new(4, 16.0);
    // n_cb = bridges per bin (2, 1, 2, 0) over the bin area (width 4 x height 4: per unit
    // length of x, averaged over the height, docs/model.md 7), in units of 1/d^2 with d = 1,
    // then d = 2.
    assert_eq!(
        bridge_density(&f, &bins, 1.0),
        vec![0.125, 0.0625, 0.125, 0.0]
    );
    assert_eq!(bridge_density(&f, &bins, 2.0), vec![0.5, 0.25, 0.5, 0.0]);
    // Packing: bin 0 holds particles 0, 1, 2, 7 (4 disks of radius 0.5) in a 4 x 4 bin.
    let p = observed_profiles(&f);
    assert_eq!(p.particles, vec![4.0, 1.0, 3.0, 2.0]);
    let phi = &p.packing;
    let disk = PI * 0.25;
    let expected = [
        4.0 * disk / 16.0,
        1.0 * disk / 16.0,
        3.0 * disk / 16.0,
        2.0 * disk / 16.0,
    ];
    for b in 0..4 {
        assert!(
            (phi[b] - expected[b]).abs() < 1e-15,
            "bin {b}: {} vs {}",
            phi[b],
            expected[b]
        );
    }
}

#[test]
fn delta_n_cb_homogeneous_is_zero_and_half_bonded_is_the_jump() {
    // 16 x 3 square lattice in a periodic box 16 x 4, bins of 4 columns.
    let pos = square(16, 3);
    let vel = vec![[0.0; 2]; pos.len()];
    let id = |c: usize, r: usize| r * 16 + c;
    let bins = LateralBins::new(4, 16.0);
    // Homogeneous: every horizontal bond (periodic, 16 per row) and every vertical bond.
    let mut all = Vec::new();
    for r in 0..3 {
        for c in 0..16 {
            all.push((id(c, r), id((c + 1) % 16, r)));
            if r + 1 < 3 {
                all.push((id(c, r), id(c, r + 1)));
            }
        }
    }
    let f = frame([16.0, 4.0], &pos, &vel, 0.5, all);
    let n = bridge_density(&f, &bins, 1.0);
    assert_eq!(spread(&n), 0.0, "{n:?}");
    // Per bin: 4 columns x (3 horizontal + 2 vertical bonds) = 20 bridges over the bin's area
    // 4 x 4.
    assert_eq!(n, vec![1.25; 4]);
    // Half-bonded: only the horizontal bonds whose midpoints lie in x < 8.
    let mut half = Vec::new();
    for r in 0..3 {
        for c in 0..16 {
            let mid = 0.5 + c as f64 + 0.5;
            if mid < 8.0 {
                half.push((id(c, r), id(c + 1, r)));
            }
        }
    }
    // Midpoints at 1, 2, ..., 7: columns 0..=6 -> bin 0 holds 3 (1, 2, 3) x 3 rows plus the
    // bond with midpoint 4.0 -> bin 1 takes midpoints 4, 5, 6, 7.
    let f = frame([16.0, 4.0], &pos, &vel, 0.5, half);
    let n = bridge_density(&f, &bins, 1.0);
    assert_eq!(n, vec![9.0 / 16.0, 12.0 / 16.0, 0.0, 0.0]);
    assert_eq!(spread(&n), 0.75);
    // The packing fraction of the lattice is the same in every bin: Delta n_area = 0.
    let p = observed_profiles(&f);
    assert_eq!(p.particles, vec![12.0; 4]);
    assert_eq!(spread(&p.packing), 0.0);
    assert_eq!(p.delta_n_area, 0.0);
}

#[test]
fn bin_temperature_follows_eq_3_2() {
    // Bin [0, 4): velocities (1, 0), (-1, 0), (0, 2), (0, -2) -> mean 0, <v^2> = 10/4,
    // T = m <v^2> / 2 = 1.25 (Eq. 3.2); the bin profile's unbiased estimate (observe::lateral)
    // is m sum |v - <v>|^2 / (D (n - 1)) = 10 / 6. Bin [4, 8): two particles moving together at
    // (3, 1): T = 0. Bin [8, 12): one particle: no temperature. Bin [12, 16): empty.
    let pos = [
        [1.0, 1.0],
        [2.0, 1.0],
        [3.0, 1.0],
        [1.0, 2.5],
        [5.0, 1.0],
        [6.0, 1.0],
        [9.0, 1.0],
    ];
    let vel = [
        [1.0, 0.0],
        [-1.0, 0.0],
        [0.0, 2.0],
        [0.0, -2.0],
        [3.0, 1.0],
        [3.0, 1.0],
        [7.0, 0.0],
    ];
    let f = frame([16.0, 4.0], &pos, &vel, 0.5, vec![]);
    assert_eq!(granular_temperature(&f, &[0, 1, 2, 3]), Some(1.25));
    assert_eq!(granular_temperature(&f, &[4, 5]), Some(0.0));
    assert_eq!(granular_temperature(&f, &[6]), None);
    assert_eq!(granular_temperature(&f, &[]), None);
    let p = observed_profiles(&f);
    assert_eq!(p.particles, vec![4.0, 2.0, 1.0, 0.0]);
    let t = &p.temperature_reduced;
    assert!((t[0].unwrap() - 10.0 / 6.0).abs() < 1e-15, "{t:?}");
    assert_eq!(t[1], Some(0.0));
    assert_eq!(t[2], None);
    assert_eq!(t[3], None);
    // Globally: mean v = (13, 2) / 7, <v^2> = (1 + 1 + 4 + 4 + 10 + 10 + 49) / 7 = 79 / 7.
    let all: Vec<usize> = (0..7).collect();
    let mean_sq = (13.0f64 / 7.0).powi(2) + (2.0f64 / 7.0).powi(2);
    let expected = (79.0 / 7.0 - mean_sq) / 2.0;
    let got = granular_temperature(&f, &all).unwrap();
    assert!((got - expected).abs() < 1e-14, "{got} vs {expected}");
}
