//! The incremental location-change counter (`observe::kinetic_delaunay`: the triangulation kept
//! between samples and repaired by edge flips) against the reference that triangulates every
//! sample from scratch (spade): on positions recorded from real runs of the wet shaken 2D
//! system, laterally periodic (ghost images enter and leave the band), every sample's Delaunay
//! edges are identical and so are the counts, per interval and per bin. The runs are chosen to
//! exercise every path: flips, held-back sites relocated, inserted and
//! deleted ghost images (a fluid sampled at 20 per period), failed repairs, rebuilds and the
//! back-off (a gas sampled coarsely).

use wetgran_core::observe::Observer;
use wetgran_core::observe::bins::LateralBins;
use wetgran_core::observe::kinetic_delaunay::KineticDelaunay;
use wetgran_core::observe::location_changes::{LocationChangeCounter, Method, delaunay_edges};
use wetgran_core::scene::Scene;
use wetgran_core::sim::{Frame, run_scene_observed};

const DELAUNAY: Method = Method::Delaunay {
    max_edge: 2.0,
    margin: 0.2,
};

/// The wet shaken 2D system (sigma_p 0.06, thin thread, hot start `T_g / E_cb = 20`) with `n`
/// grains in `lx x 9`, at `(gamma, e_star)`, for `duration` time units.
fn scene(n: usize, lx: f64, gamma: f64, e_star: f64, duration: f64) -> Scene {
    Scene::from_toml_str(
        &format!(
            r#"
dimension = 2
[box]
size = [{lx:?}, 9.0]
[particles]
count = {n}
polydispersity = 0.06
[contact]
restitution = 0.96
[capillary]
model = "thin_thread"
[drive]
kind = "sine"
gamma = {gamma:?}
e_star = {e_star:?}
[initial]
temperature_over_ecb = 20.0
seed = 1
[run]
duration = {duration:?}
"#
        ),
        "kinetic delaunay test",
    )
    .unwrap_or_else(|e| panic!("{e}"))
}

/// Frames of a run every `interval`, from `skip` on.
fn record(scene: &Scene, interval: f64, skip: f64) -> Vec<Frame> {
    let mut frames = Vec::new();
    run_scene_observed(
        scene,
        interval,
        &mut |f: &Frame| {
            if f.time >= skip {
                frames.push(f.clone());
            }
        },
        &mut |_| {},
    );
    frames
}

/// Feeds `frames` to the incremental and the rebuilding counter; asserts that every sample's
/// edges and all counts agree; returns the incremental counter's statistics.
fn compare(frames: &[Frame]) -> wetgran_core::observe::kinetic_delaunay::KineticStats {
    let lx = frames[0].box_size[0];
    let bins = LateralBins::new((lx / 4.0) as usize, lx);
    let mut kinetic = LocationChangeCounter::new(DELAUNAY, bins.clone(), 1.0);
    let mut reference = LocationChangeCounter::rebuilding(DELAUNAY, bins, 1.0);
    let mut edges = KineticDelaunay::new(8.0);
    for (k, f) in frames.iter().enumerate() {
        assert_eq!(edges.update(f), delaunay_edges(f, 8.0), "sample {k}");
        edges
            .links_consistent()
            .unwrap_or_else(|e| panic!("sample {k}: {e}"));
        edges
            .pairs_consistent()
            .unwrap_or_else(|e| panic!("sample {k}: {e}"));
        kinetic.observe(f, true);
        reference.observe(f, true);
    }
    assert_eq!(kinetic.window_count, reference.window_count);
    assert_eq!(kinetic.bin_count, reference.bin_count);
    assert_eq!(kinetic.series, reference.series);
    assert!(reference.window_count > 0, "the runs move grains");
    println!(
        "{} samples, {} changes, {:?}",
        frames.len(),
        kinetic.window_count,
        edges.stats
    );
    edges.stats
}

#[test]
fn incremental_counts_equal_rebuilt_counts_on_a_fluid() {
    // N = 300 in 100 x 9 at Gamma 30, E* 0.7 (period 0.13): 20 samples per period over 2 time
    // units after 3 units of cooling.
    let s = scene(300, 100.0, 30.0, 0.7, 5.0);
    let frames = record(&s, s.driving_period() / 20.0, 3.0);
    let st = compare(&frames);
    assert!(st.incremental as usize >= frames.len() * 9 / 10, "{st:?}");
    assert!(st.inserted > 0 && st.deleted > 0, "{st:?}");
    // Held sites are relocated (the halving fallback of hull sites has its unit test in
    // `observe::kinetic_delaunay`).
    assert!(st.held > 0, "{st:?}");
}

#[test]
fn incremental_counts_equal_rebuilt_counts_on_a_coarsely_sampled_gas() {
    // Gamma 2, E* 3 (period 4.1): 5 samples per period, 0.8 time units apart, grains move about a
    // diameter between samples: repairs fail, samples are rebuilt.
    let s = scene(300, 100.0, 2.0, 3.0, 40.0);
    let frames = record(&s, s.driving_period() / 5.0, 10.0);
    let st = compare(&frames);
    assert!(st.rebuild_inverted + st.rebuild_check > 0, "{st:?}");
    assert!(st.rebuild_backoff > 0, "{st:?}");
}

#[test]
fn incremental_counts_equal_rebuilt_counts_in_a_doubly_periodic_gas() {
    // 120 disks in a 20 x 20 box periodic on both axes (ghost images on all four sides and in
    // the corners), no gravity, T = 0.5, 20 samples per time unit.
    let s = Scene::from_toml_str(
        "dimension = 2\ngravity = 0.0\n[box]\nsize = [20.0, 20.0]\nboundary = [\"periodic\", \"periodic\"]\n\
         [particles]\ncount = 120\n[initial]\ntemperature = 0.5\nseed = 3\n[run]\nduration = 6.0\n",
        "doubly periodic gas",
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let frames = record(&s, 0.05, 1.0);
    let st = compare(&frames);
    assert!(
        st.incremental > 0 && st.inserted > 0 && st.deleted > 0,
        "{st:?}"
    );
}

/// Two consecutive frames of a shaken run, read from `crates/core/tests/data/tangled_delaunay_frames.txt`.
fn tangled_frames() -> [Frame; 2] {
    let text = include_str!("data/tangled_delaunay_frames.txt");
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let head: Vec<&str> = lines.next().expect("header").split_whitespace().collect();
    let (lx, ly): (f64, f64) = (head[1].parse().unwrap(), head[2].parse().unwrap());
    let n: usize = head[7].parse().unwrap();
    let mut positions: Vec<f64> = lines
        .flat_map(|l| l.split_whitespace().map(|x| x.parse::<f64>().unwrap()))
        .collect();
    assert_eq!(positions.len(), 4 * n);
    let second = positions.split_off(2 * n);
    let frame = |p: Vec<f64>| {
        Frame::from_parts(
            2,
            vec![lx, ly],
            vec![true, false],
            p,
            vec![0.0; 2 * n],
            vec![0.5; n],
            Vec::new(),
        )
    };
    [frame(positions), frame(second)]
}

/// Regression: in `sweeps/shaken_2d_elastic.toml` at `Gamma = 0.71, E* = 17.8` the kept
/// triangulation, advancing a held-back site, flipped an edge that joined two sites joined
/// already; the doubled edge broke the next walk around a site ("v in its star") and the job
/// failed. From the triangulation of the first frame, the step to the second must give the
/// edges triangulated from scratch (before the held sites were relocated, it panicked or
/// corrupted the structure with `Safeguards::joined_flip_check` off).
#[test]
fn a_tangled_step_never_doubles_an_edge() {
    use wetgran_core::observe::kinetic_delaunay::Safeguards;
    let [a, b] = tangled_frames();
    let step = |safeguards: Safeguards| {
        std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            let mut k = KineticDelaunay::with_safeguards(8.0, safeguards);
            k.advance(&a);
            let same = k.update(&b) == delaunay_edges(&b, 8.0);
            (
                same,
                k.links_consistent().is_ok() && k.pairs_consistent().is_ok(),
            )
        }))
    };
    assert_eq!(step(Safeguards::default()).ok(), Some((true, true)));
    // With the held sites relocated (round 3 of docs/performance.md) instead of unfolded and
    // halved, this recorded step no longer reaches the doubling flip even with
    // `joined_flip_check` off: the check stays as a guard of the structure, and this test
    // keeps the recorded step that once failed. The check itself fails a test without it on
    // a built tangle: `joined_flip_check_stops_lawson_before_it_doubles_an_edge` (unit test).
    assert_eq!(
        step(Safeguards {
            joined_flip_check: false,
            ..Safeguards::default()
        })
        .ok(),
        Some((true, true))
    );
}
