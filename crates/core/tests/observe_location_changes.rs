//! The location-change counter (`f_lc`, docs/model.md 7): zero for a static lattice, exact counts
//! for prescribed neighbour exchanges, a rate that grows with temperature in a dilute gas, and a
//! count that converges as the sampling gets finer.

use wetgran_testkit as common;

use wetgran_core::observe::bins::LateralBins;
use wetgran_core::observe::location_changes::{
    LocationChangeCounter, Method, compare, delaunay_edges, neighbour_shell_edges,
};
use wetgran_core::observe::run_observed;
use wetgran_core::sim::Frame;

const DELAUNAY: Method = Method::Delaunay {
    max_edge: 2.0,
    margin: 0.2,
};

/// A 2D frame at rest with the given centres, radius 0.5.
fn frame_2d(size: [f64; 2], periodic: [bool; 2], pos: &[[f64; 2]], time: f64) -> Frame {
    let n = pos.len();
    let mut f = Frame::from_parts(
        2,
        size.to_vec(),
        periodic.to_vec(),
        pos.iter().flat_map(|p| p.to_vec()).collect(),
        vec![0.0; 2 * n],
        vec![0.5; n],
        vec![],
    );
    f.time = time;
    f
}

/// A triangular (hexagonal) lattice of spacing 1 with `nx * nz` sites, offset from the origin.
fn hex_lattice(nx: usize, nz: usize) -> Vec<[f64; 2]> {
    let mut p = Vec::new();
    for r in 0..nz {
        for c in 0..nx {
            let shift = if r % 2 == 1 { 0.5 } else { 0.0 };
            p.push([2.0 + c as f64 + shift, 2.0 + r as f64 * 3f64.sqrt() / 2.0]);
        }
    }
    p
}

/// Feeds frames to a fresh counter (all inside the window); returns the changes counted.
fn count(frames: &[Frame], method: Method) -> u64 {
    let lx = frames[0].box_size[0];
    let mut c = LocationChangeCounter::new(method, LateralBins::new(1, lx), 1.0);
    for f in frames {
        c.observe(f, true);
    }
    c.window_count
}

#[test]
fn static_lattices_count_nothing() {
    // Hexagonal, and square (every quadrilateral co-circular: the degenerate case), in a closed
    // box and in a periodic one (ghost images across the seam).
    let hex = hex_lattice(10, 6);
    let mut square = Vec::new();
    for r in 0..5 {
        for c in 0..12 {
            square.push([0.5 + c as f64, 0.5 + r as f64]);
        }
    }
    for (pos, size, periodic) in [
        (&hex, [14.0, 9.0], [false, false]),
        (&hex, [10.0, 9.0], [true, false]),
        (&square, [12.0, 6.0], [true, false]),
        (&square, [12.0, 5.0], [true, true]),
    ] {
        let frames: Vec<Frame> = (0..5)
            .map(|k| frame_2d(size, periodic, pos, k as f64))
            .collect();
        assert_eq!(count(&frames, DELAUNAY), 0, "{size:?} {periodic:?}");
        assert_eq!(
            count(
                &frames,
                Method::Delaunay {
                    max_edge: 2.0,
                    margin: 0.0
                }
            ),
            0
        );
    }
    // 3D: a simple cubic lattice at rest, neighbour shells.
    let mut pos = Vec::new();
    for i in 0..4 {
        for j in 0..4 {
            for k in 0..4 {
                pos.extend([
                    0.5 + i as f64 * 1.05,
                    0.5 + j as f64 * 1.05,
                    0.5 + k as f64 * 1.05,
                ]);
            }
        }
    }
    let n = pos.len() / 3;
    let shell = Method::NeighbourShell {
        enter: 1.2,
        leave: 1.5,
    };
    let frames: Vec<Frame> = (0..4)
        .map(|t| {
            let mut f = Frame::from_parts(
                3,
                vec![4.2, 4.2, 6.0],
                vec![true, true, false],
                pos.clone(),
                vec![0.0; 3 * n],
                vec![0.5; n],
                vec![],
            );
            f.time = t as f64;
            f
        })
        .collect();
    assert_eq!(count(&frames, shell), 0);
    // Each site of the periodic 4x4 layers has 4 lateral neighbours and 1-2 vertical ones.
    let edges = neighbour_shell_edges(&frames[0], &[], 1.2, 1.5);
    assert_eq!(edges.len(), 4 * 16 * 2 + 3 * 16);
}

/// Four grains: `c, d` on the short diagonal of a rhombus are neighbours; moving them apart and
/// `a, b` together, slowly and sampled finely, exchanges the neighbour pair once (one T1 step).
#[test]
fn one_neighbour_exchange_counts_exactly_one() {
    let rhombus = |h: f64, w: f64| {
        vec![
            [5.0 - w, 5.0],
            [5.0 + w, 5.0],
            [5.0, 5.0 + h],
            [5.0, 5.0 - h],
        ]
    };
    let steps = 200;
    let mut frames = Vec::new();
    for k in 0..=steps {
        let s = k as f64 / steps as f64;
        // c-d from 1.6 to 2.0 apart... a-b from 2.0 to 1.6: the diagonals exchange roles.
        let h = 0.8 + 0.2 * s;
        let w = 1.0 - 0.2 * s;
        frames.push(frame_2d(
            [10.0, 10.0],
            [false, false],
            &rhombus(h, w),
            k as f64,
        ));
    }
    let before = delaunay_edges(&frames[0], 8.0);
    let after = delaunay_edges(&frames[steps], 8.0);
    assert!(
        before.iter().any(|e| (e.i, e.j) == (2, 3)),
        "c-d is the Delaunay diagonal"
    );
    assert!(
        after.iter().any(|e| (e.i, e.j) == (0, 1)),
        "a-b is the Delaunay diagonal"
    );
    assert_eq!(count(&frames, DELAUNAY), 1);
    // Back again: a second exchange.
    let mut there_and_back = frames.clone();
    for (k, f) in frames.iter().rev().enumerate() {
        let mut f = f.clone();
        f.time = (steps + 1 + k) as f64;
        there_and_back.push(f);
    }
    assert_eq!(count(&there_and_back, DELAUNAY), 2);
    // Only the two end states, no intermediate sample: still one.
    assert_eq!(
        count(&[frames[0].clone(), frames[steps].clone()], DELAUNAY),
        1
    );
}

/// Hysteresis: a quadrilateral whose diagonal flips back and forth by less than the margin
/// counts nothing; without a margin every flip counts.
#[test]
fn rattling_near_square_counts_only_without_margin() {
    // A square of side 1: co-circular; the diagonal is decided by a wobble of +-0.02.
    let mut frames = Vec::new();
    for k in 0..20 {
        let e = if k % 2 == 0 { 0.02 } else { -0.02 };
        let pos = [[4.0, 4.0], [5.0, 4.0 + e], [5.0, 5.0], [4.0, 5.0 - e]];
        frames.push(frame_2d([10.0, 10.0], [false, false], &pos, k as f64));
    }
    assert_eq!(count(&frames, DELAUNAY), 0);
    let no_margin = Method::Delaunay {
        max_edge: 2.0,
        margin: 0.0,
    };
    assert_eq!(count(&frames, no_margin), 19);
}

/// Teleporting two neighbours of a hexagonal lattice onto each other's sites: each takes over
/// the three neighbours the other had alone, 6 new neighbour pairs.
#[test]
fn swapping_two_lattice_neighbours_counts_six() {
    let a = hex_lattice(10, 7);
    let (i, j) = (3 * 10 + 4, 3 * 10 + 5); // two horizontal neighbours in the middle row
    let mut b = a.clone();
    b.swap(i, j);
    for periodic in [false, true] {
        let size = if periodic { [10.0, 10.0] } else { [14.0, 10.0] };
        let f0 = frame_2d(size, [periodic, false], &a, 0.0);
        let f1 = frame_2d(size, [periodic, false], &b, 1.0);
        assert_eq!(
            count(&[f0.clone(), f1.clone()], DELAUNAY),
            6,
            "periodic {periodic}"
        );
        let e0: Vec<(u32, u32)> = delaunay_edges(&f0, 8.0)
            .iter()
            .map(|e| (e.i, e.j))
            .collect();
        let (fresh, _) = compare(&e0, &delaunay_edges(&f1, 8.0), DELAUNAY);
        let mut got: Vec<(u32, u32)> = fresh.iter().map(|e| (e.i, e.j)).collect();
        got.sort_unstable();
        assert!(
            got.iter()
                .all(|&(p, q)| [p, q].contains(&(i as u32)) || [p, q].contains(&(j as u32)))
        );
    }
}

/// A dilute elastic gas (packing fraction 0.24) without gravity, fully periodic: the same
/// sampling interval, three temperatures; grains move faster, so neighbours change more often.
#[test]
fn dilute_gas_rate_grows_with_temperature() {
    let rate = |t: f64| {
        let s = common::scene(&format!(
            "dimension = 2\ngravity = 0.0\n[box]\nsize = [20.0, 20.0]\nboundary = [\"periodic\", \"periodic\"]\n\
             [particles]\ncount = 120\n[initial]\ntemperature = {t:?}\nseed = 3\n\
             [run]\nduration = 6.0\n[observe]\ntransient_periods = 1.0\nsamples_per_period = 20.0\nlocation_changes = true\n"
        ));
        let run = run_observed(&s, &Default::default(), &mut |_| {});
        run.observables
            .location_changes
            .expect("observed")
            .per_particle_per_period
    };
    let (cold, warm, hot) = (rate(0.05), rate(0.5), rate(5.0));
    assert!(cold > 0.0, "a gas changes neighbours: {cold}");
    assert!(
        warm > 1.5 * cold && hot > 1.5 * warm,
        "f_lc must grow with T: {cold} {warm} {hot}"
    );
}

/// Sampling: the same trajectory (observers never change it) sampled 2, 5, 20 and 80 times per
/// time unit. The count converges once the interval is short against the time a grain needs to
/// move a fraction of its diameter (speed ~ 0.14 here). A coarse sampling is off in either
/// direction: it misses exchanges undone between two samples, and it sees several flips at once,
/// which the hysteresis cannot judge one by one (here it overcounts).
#[test]
fn count_converges_with_finer_sampling() {
    let count_at = |samples: f64| {
        let s = common::scene(&format!(
            "dimension = 2\ngravity = 0.0\n[box]\nsize = [24.0, 24.0]\nboundary = [\"periodic\", \"periodic\"]\n\
             [particles]\ncount = 150\n[initial]\ntemperature = 0.02\nlattice_spacing = 1.5\nseed = 5\n\
             [run]\nduration = 20.0\n[observe]\nsamples_per_period = {samples:?}\nlocation_changes = true\n"
        ));
        run_observed(&s, &Default::default(), &mut |_| {})
            .observables
            .location_changes
            .expect("observed")
            .count
    };
    let c: Vec<f64> = [2.0, 5.0, 20.0, 80.0]
        .iter()
        .map(|&s| count_at(s) as f64)
        .collect();
    let converged = c[3];
    assert!(converged >= 10.0, "{c:?}");
    assert!(
        (c[2] - converged).abs() <= 0.05 * converged,
        "20 and 80 samples per unit agree within 5 %: {c:?}"
    );
    assert!(
        (c[0] - converged).abs() > 0.1 * converged,
        "2 samples per unit are too coarse for this system: {c:?}"
    );
}
