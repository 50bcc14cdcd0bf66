//! The wall table against the exact solver and an independent root scan, its safeguards one
//! by one, and the bits of a parallel build.

use super::build::{entering_count, tabulate};
use super::flight::{all_roots, gap3};
use super::*;
use crate::physics::shaken_wall::{WallRoot, exact_root};
use rand::{Rng, SeedableRng};

/// The shaken wall of the standard wet scene at `(Gamma, E*)` (`g = d = 1`).
pub(crate) fn standard_motion(gamma: f64, e_star: f64) -> WallMotion {
    let v_w = (2.0f64 * e_star * 0.2844).sqrt();
    WallMotion {
        amplitude: v_w * v_w / gamma,
        omega: gamma / v_w,
        g: 1.0,
    }
}

/// A square table of `cells` per axis with the default velocity map and corner check.
pub(crate) fn spec_for(w: &WallMotion, cells: usize) -> TableSpec {
    let vw = w.amplitude * w.omega;
    TableSpec {
        phase_cells: cells,
        velocity_cells: cells,
        v_min: DEFAULT_V_MIN_OVER_WALL_SPEED * vw,
        v_max: DEFAULT_V_MAX_OVER_WALL_SPEED * vw,
        corner_tolerance: Some(1e-3),
    }
}

/// Every number of a table as bits (cells in order, every field).
fn table_bits(t: &WallTable) -> Vec<u64> {
    let mut bits = Vec::new();
    for e in &t.edges {
        bits.extend(e.lo.iter().chain(&e.width).map(|x| x.to_bits()));
        bits.extend(e.n.iter().map(|&n| n as u64));
        for c in &e.cells {
            bits.extend(c.reference.iter().map(|x| x.to_bits()));
            bits.push(u64::from(c.starts_inside) | u64::from(c.exact_only) << 1);
            bits.push(u64::from(c.count));
            for r in &c.roots {
                bits.push(r.tau.to_bits());
                bits.push(r.vrel.to_bits());
                bits.extend(r.dtau.iter().chain(&r.dvrel).map(|x| x.to_bits()));
            }
        }
    }
    bits
}

/// The parallel build gives the same table, bit for bit, and the same counters on one
/// thread and on two (each a rayon pool installed around the build), for a fluid and a
/// strongly shaken motion whose safeguards all act.
#[test]
fn the_table_is_the_same_bits_on_one_and_two_threads() {
    for (gamma, e_star) in [(5.0, 10.0), (15.0, 1.0)] {
        let w = standard_motion(gamma, e_star);
        let spec = spec_for(&w, 48);
        let on = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("a pool")
                .install(|| WallTable::build(w, spec))
        };
        let (one, two) = (on(1), on(2));
        assert_eq!(table_bits(&one), table_bits(&two));
        assert_eq!(one.stats, two.stats);
        assert_eq!(one.stats.cells, 4 * 48 * 48);
        assert!(one.stats.exact_only_cells > 0 && one.stats.shrunk_derivatives > 0);
    }
}

#[test]
fn all_roots_finds_the_roots_of_a_static_wall_parabola() {
    let w = WallMotion {
        amplitude: 0.0,
        omega: 1.0,
        g: 1.0,
    };
    // h = 2, v = 0.5: one root at v + sqrt(v^2 + 2h).
    let (inside, roots) = all_roots(&w, (2.0, 0.5, 0.0), 10.0, false);
    assert!(!inside);
    assert_eq!(roots.len(), 1);
    assert!((roots[0] - (0.5 + (0.25f64 + 4.0).sqrt())).abs() < 1e-12);
}

/// `n` seeded flights `(h, v, t0)` in front of the wall: contact heights from the bottom of
/// the reach to three diameters above it, speeds in `[-3, 3]`, start times over 100 units.
fn random_shots(w: &WallMotion, n: usize) -> Vec<(f64, f64, f64)> {
    let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(5);
    (0..n)
        .map(|_| {
            let t0 = rng.gen_range(0.0..100.0);
            let h = rng
                .gen_range(-w.amplitude..w.amplitude + 3.0)
                .max(w.position(t0) + 1e-6);
            (h, rng.gen_range(-3.0..3.0), t0)
        })
        .collect()
}

#[test]
fn table_agrees_with_exact_solver_on_random_shots() {
    let w = standard_motion(5.0, 10.0);
    let table = WallTable::build(w, spec_for(&w, 256));
    let (mut wrong, mut n, mut max_err, mut sum_err) = (0, 0, 0.0f64, 0.0);
    for (h, v, t0) in random_shots(&w, 5000) {
        let reference = exact_root(&w, h, v, t0, 1e-15, 4.0 * w.period());
        let ours = table.next_hit(h, v, t0, 4.0 * w.period());
        match (reference, ours) {
            (WallRoot::Hit(r), TableHit::Hit { dt, v_rel }) => {
                n += 1;
                assert!(v_rel > 0.0);
                let e = (dt - r).abs();
                if e > 1e-2 * w.period() {
                    wrong += 1;
                    eprintln!("reference {r} table {dt} h {h} v {v} t0 {t0}");
                } else {
                    max_err = max_err.max(e);
                    sum_err += e;
                }
            }
            (_, TableHit::OutOfRange) => {}
            (WallRoot::Hit(r), TableHit::Now) if r < 1e-3 * w.period() => {
                n += 1;
                max_err = max_err.max(r);
                sum_err += r;
            }
            (r, o) => {
                wrong += 1;
                eprintln!("reference {r:?} table {o:?} h {h} v {v} t0 {t0}");
            }
        }
    }
    eprintln!(
        "n {n} wrong {wrong} max err {max_err:e} mean {:e} stats {:?} bytes {} build {}",
        sum_err / n as f64,
        table.stats,
        table.bytes(),
        table.build_seconds
    );
    // The corner-checked table finds the earliest root on every shot, within the check's
    // tolerance (plus the second-order error inside a cell).
    assert_eq!(wrong, 0);
    assert!(max_err < 2e-3 * w.period(), "{max_err}");
}

#[test]
fn without_the_corner_check_the_printed_table_takes_wrong_roots() {
    // The safeguard's own test: the same shots through the table as printed (no corner
    // check) give wrong roots, which the checked table does not (previous test).
    let w = standard_motion(5.0, 10.0);
    let spec = TableSpec {
        corner_tolerance: None,
        ..spec_for(&w, 64)
    };
    let table = WallTable::build(w, spec);
    let mut wrong = 0;
    for (h, v, t0) in random_shots(&w, 5000) {
        let reference = exact_root(&w, h, v, t0, 1e-15, 4.0 * w.period());
        if let (WallRoot::Hit(r), TableHit::Hit { dt, .. }) =
            (reference, table.next_hit(h, v, t0, 4.0 * w.period()))
            && (dt - r).abs() > 1e-2 * w.period()
        {
            wrong += 1;
        }
    }
    assert!(wrong > 10, "{wrong}");
}

#[test]
fn every_cell_extrapolates_to_positive_times_and_approach_speeds_at_its_corners() {
    // B.5.4 and B.5.5 over every cell of every edge: the stored model gives tau >= 0 and
    // v_rel > 0 at all four corners, and a cell that escapes has no corner that hits.
    let w = standard_motion(2.0, 1.0);
    let spec = spec_for(&w, 48);
    let table = WallTable::build(w, spec);
    assert!(table.stats.shrunk_derivatives > 0 && table.stats.rereferenced_cells > 0);
    let period = w.period();
    for (e, edge) in table.edges.iter().zip(EDGES) {
        for i0 in 0..e.n[0] {
            for i1 in 0..e.n[1] {
                let cell = &e.cells[i0 * e.n[1] + i1];
                for c0 in [0.0, 1.0] {
                    for c1 in [0.0, 1.0] {
                        let p = [
                            e.lo[0] + (i0 as f64 + c0) * e.width[0],
                            e.lo[1] + (i1 as f64 + c1) * e.width[1],
                        ];
                        let d = [p[0] - cell.reference[0], p[1] - cell.reference[1]];
                        for k in 0..cell.count as usize {
                            let r = &cell.roots[k];
                            assert!(extrapolate(r.tau, r.dtau, d) >= 0.0);
                            if (k % 2 == 0) != cell.starts_inside {
                                assert!(extrapolate(r.vrel, r.dvrel, d) > 0.0);
                            }
                        }
                        if entering_count(cell) == 0 {
                            let at_corner = tabulate(&w, &spec, edge, p, period);
                            assert_eq!(entering_count(&at_corner), 0, "{edge:?} {p:?}");
                        }
                    }
                }
            }
        }
    }
}

/// Sign changes of the gap on a fine grid: an independent count of the roots.
fn scanned_roots(w: &WallMotion, base: (f64, f64, f64), window: f64) -> Vec<f64> {
    let n = 200_000;
    let mut out = vec![];
    let mut prev = gap3(w, base, 0.0).0;
    for k in 1..=n {
        let tau = window * k as f64 / n as f64;
        let s = gap3(w, base, tau).0;
        if (s > 0.0) != (prev > 0.0) {
            out.push(tau);
        }
        prev = s;
    }
    out
}

#[test]
fn four_roots_in_one_period_from_behind_the_wall() {
    // Edge II flights start behind the wall (z = -A, moving up): they leave, re-enter,
    // leave and re-enter within one period. Find one, check its roots against a fine scan,
    // and query the table between the roots: outside the wall the next entering root comes
    // back; inside it, the flight collides now (approaching) or at the next entering root.
    let w = standard_motion(5.0, 10.0);
    let period = w.period();
    let mut found = None;
    'search: for i in 0..400 {
        for j in 1..200 {
            let phase = TAU * i as f64 / 400.0;
            let v = 0.02 * j as f64;
            let base = (-w.amplitude, v, phase);
            let (inside, roots) = all_roots(&w, base, period, false);
            if roots.len() == 4 && roots[3] < 0.95 * period {
                assert!(inside);
                found = Some((phase, v, roots));
                break 'search;
            }
        }
    }
    let (phase, v, roots) = found.expect("a four-root flight exists at Gamma = 5");
    let base = (-w.amplitude, v, phase);
    let scanned = scanned_roots(&w, base, period);
    assert_eq!(scanned.len(), 4, "{scanned:?} vs {roots:?}");
    for (a, b) in roots.iter().zip(&scanned) {
        assert!((a - b).abs() <= period / 200_000.0 + 1e-12, "{a} vs {b}");
    }
    let table = WallTable::build(w, spec_for(&w, 256));
    // The base point at the start of period 7.
    let t_base = 7.0 * period + phase / w.omega;
    let state = |tau: f64| {
        (
            -w.amplitude + v * tau - 0.5 * w.g * tau * tau,
            v - w.g * tau,
            t_base + tau,
        )
    };
    let tol = 5e-3 * period;
    // Between roots 1 and 2, and 3 and 4: in front of the wall.
    for (k, next) in [(0, 1), (2, 3)] {
        let now = 0.5 * (roots[k] + roots[next]);
        let (z, vz, t) = state(now);
        assert!(z - w.position(t) > 0.0);
        match table.next_hit(z, vz, t, 2.0 * period) {
            TableHit::Hit { dt, v_rel } => {
                assert!((now + dt - roots[next]).abs() < tol, "root {next}: {dt}");
                assert!(v_rel > 0.0);
            }
            TableHit::OutOfRange => {
                let r = exact_root(&w, z, vz, t, 1e-13, 2.0 * period);
                assert!(matches!(r, WallRoot::Hit(dt) if (now + dt - roots[next]).abs() < tol));
            }
            other => panic!("between roots {k} and {next}: {other:?}"),
        }
    }
    // Between roots 2 and 3: behind the wall; the latest root before now entered it.
    let now = 0.5 * (roots[1] + roots[2]);
    let (z, vz, t) = state(now);
    assert!(z - w.position(t) < 0.0);
    let approaching = w.velocity(t) - vz > 0.0;
    match table.next_hit(z, vz, t, 2.0 * period) {
        TableHit::Now => assert!(approaching),
        TableHit::Hit { dt, .. } => {
            assert!(!approaching);
            assert!((now + dt - roots[3]).abs() < tol);
        }
        TableHit::OutOfRange => {}
        other => panic!("behind the wall: {other:?}"),
    }
}
