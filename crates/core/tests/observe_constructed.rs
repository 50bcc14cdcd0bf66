//! Phase labels of constructed states whose phase is known by construction (issue 31, item 1),
//! fed through the same observers and classifier a run uses (`ObserverSet`, `classify`):
//!
//! - a crystal drop rattling at `T_g/E_cb = 0.2`, drifting and turning as a rigid body, in a hot
//!   gas whose grains touch it and bounce off: sgc;
//! - a liquid drop (bonded grains that diffuse among themselves) in a hot gas: fgc;
//! - a crystal slab next to a bonded liquid layer: sfc;
//! - a gas with a strong standing density wave, bridges at every contact, no bonded cluster:
//!   homogeneous g, although its `Delta n_cb` is far above the noise.
//!
//! Each state is a 2D box 200 d x 9 d sampled every 0.05 time units for 60 time units. Grains
//! of a gas take diffusive Langevin steps; grains of a crystal sit on a triangular lattice that
//! moves rigidly, plus an independent rattle per sample; grains of a liquid random-walk about
//! their lattice sites. Bridges: every lattice neighbour pair of a crystal; every pair of a
//! liquid or gas closer than `LIQUID_BOND` or in contact at that sample.

use rand::{Rng, SeedableRng};
use rand_distr::StandardNormal;
use rand_xoshiro::Xoshiro256PlusPlus;
use wetgran_core::observe::clusters::close_pairs;
use wetgran_core::observe::{Classification, ObserverSet, Phase, classify};
use wetgran_core::scene::Scene;
use wetgran_core::sim::Frame;

/// `E_cb` of the standard wet system (the temperature unit).
const E_CB: f64 = 0.2844;
const L: f64 = 200.0;
const H: f64 = 9.0;
const DT: f64 = 0.05;
const SAMPLES: usize = 1200;
/// Liquid grains closer than this (centre distance, units of `d`) are bridged.
const LIQUID_BOND: f64 = 1.15;

fn scene(n: usize) -> Scene {
    let text = format!(
        "dimension = 2\ngravity = 1.0\n[box]\nsize = [{L}, {H}]\nboundary = [\"periodic\", \
         \"wall\"]\n[particles]\ncount = {n}\n[capillary]\nmodel = \"thin_thread\"\ns_crit = \
         0.0711\ne_cb = {E_CB}\n[initial]\ntemperature_over_ecb = 1.0\n[run]\nduration = 60.0\n[observe]\nsamples_per_period = 20\n"
    );
    Scene::from_toml_str(&text, "constructed state").expect("valid scene")
}

/// How one group of grains moves.
enum Kind {
    /// A rigid triangular lattice: drift speed, turning rate (rad per time unit), rattle
    /// half-width per sample, temperature in `E_cb`.
    Crystal {
        drift: f64,
        turn: f64,
        rattle: f64,
        temperature: f64,
    },
    /// Lattice sites plus a random walk of diffusion coefficient `diffusion` each.
    Liquid { diffusion: f64, temperature: f64 },
    /// Langevin walkers in `U = -u cos(2 pi x / wave)` (`u = 0`: free), each diffusing with
    /// `diffusion`; heights uniform.
    Gas {
        diffusion: f64,
        temperature: f64,
        u: f64,
        wave: f64,
    },
}

/// One group: its grains' reference positions and how they move.
struct Group {
    kind: Kind,
    sites: Vec<(f64, f64)>,
    /// Current positions (liquid and gas walkers).
    pos: Vec<(f64, f64)>,
    /// Lattice neighbour pairs (crystal), indices within the group.
    lattice_bonds: Vec<(usize, usize)>,
}

/// Sites of a lattice and its neighbour pairs.
type Lattice = (Vec<(f64, f64)>, Vec<(usize, usize)>);

/// A triangular lattice of spacing 1 filling `x0 .. x0 + width`, heights `0.5 ..= top`.
fn lattice(x0: f64, width: f64, top: f64) -> Lattice {
    let dy = 3f64.sqrt() / 2.0;
    let mut sites = Vec::new();
    let mut row = 0;
    while 0.5 + row as f64 * dy <= top {
        let shift = if row % 2 == 1 { 0.5 } else { 0.0 };
        let mut x = x0 + 0.5 + shift;
        while x < x0 + width - 0.25 {
            sites.push((x, 0.5 + row as f64 * dy));
            x += 1.0;
        }
        row += 1;
    }
    let mut bonds = Vec::new();
    for i in 0..sites.len() {
        for j in i + 1..sites.len() {
            let d = (sites[i].0 - sites[j].0).hypot(sites[i].1 - sites[j].1);
            if d < 1.05 {
                bonds.push((i, j));
            }
        }
    }
    (sites, bonds)
}

fn crystal(x0: f64, width: f64, top: f64, kind: Kind) -> Group {
    let (sites, lattice_bonds) = lattice(x0, width, top);
    Group {
        kind,
        pos: sites.clone(),
        sites,
        lattice_bonds,
    }
}

fn liquid(x0: f64, width: f64, top: f64, diffusion: f64, temperature: f64) -> Group {
    let (sites, _) = lattice(x0, width, top);
    Group {
        kind: Kind::Liquid {
            diffusion,
            temperature,
        },
        pos: sites.clone(),
        sites,
        lattice_bonds: Vec::new(),
    }
}

/// `n` gas grains drawn from the stationary density `exp(u cos(2 pi x / wave) / D)` over the box
/// outside `exclude` (an x interval, e.g. where a drop starts).
fn gas(
    rng: &mut Xoshiro256PlusPlus,
    n: usize,
    diffusion: f64,
    temperature: f64,
    (u, wave): (f64, f64),
    exclude: (f64, f64),
) -> Group {
    let mut sites = Vec::with_capacity(n);
    while sites.len() < n {
        let x = rng.gen_range(0.0..L);
        if x >= exclude.0 && x < exclude.1 {
            continue;
        }
        let w = (u * (std::f64::consts::TAU * x / wave).cos() / diffusion).exp();
        if rng.r#gen::<f64>() * (u.abs() / diffusion).exp() <= w {
            sites.push((x, rng.gen_range(0.5..H - 0.5)));
        }
    }
    Group {
        kind: Kind::Gas {
            diffusion,
            temperature,
            u,
            wave,
        },
        pos: sites.clone(),
        sites,
        lattice_bonds: Vec::new(),
    }
}

/// One step of a gas grain: a drift in the standing wave of amplitude `u` and wavelength
/// `wave` plus diffusion (`step` per axis), kept out of the drop's span `drop_span` and
/// reflected at the floor and the lid.
fn gas_step(
    p: &mut (f64, f64),
    u: f64,
    wave: f64,
    step: f64,
    drop_span: Option<(f64, f64)>,
    rng: &mut Xoshiro256PlusPlus,
) {
    let gauss = |rng: &mut Xoshiro256PlusPlus, s: f64| s * rng.sample::<f64, _>(StandardNormal);
    let force = -(std::f64::consts::TAU * u / wave) * (std::f64::consts::TAU * p.0 / wave).sin();
    let before = p.0;
    p.0 += force * DT + gauss(rng, step);
    if let Some((a, b)) = drop_span {
        // A step into the drop is not taken; a grain the drop has moved
        // onto is pushed out at the nearer edge.
        if inside(p.0, a, b) {
            p.0 = before;
        }
        if inside(p.0, a, b) {
            let into = (p.0 - a).rem_euclid(L);
            p.0 = if into < 0.5 * (b - a).rem_euclid(L) {
                a
            } else {
                b
            };
        }
    }
    let y = p.1 + gauss(rng, step);
    // Reflect at the floor and the lid.
    p.1 = if y < 0.5 {
        1.0 - y
    } else if y > H - 0.5 {
        2.0 * (H - 0.5) - y
    } else {
        y
    };
}

/// Advances every group to sample `k` and returns the frame: positions, velocities, bridges
/// (plus `bounces` single-sample bridges between random gas grains and random grains of the
/// first group, the drop they touch).
fn frame(k: usize, groups: &mut [Group], bounces: usize, rng: &mut Xoshiro256PlusPlus) -> Frame {
    let t = k as f64 * DT;
    let (mut x, mut v, mut bridges) = (Vec::new(), Vec::new(), Vec::new());
    let mut offsets = Vec::new();
    let gauss = |rng: &mut Xoshiro256PlusPlus, s: f64| s * rng.sample::<f64, _>(StandardNormal);
    // The x interval the first group (the drop) covers now: gas grains bounce off it.
    let mut drop_span: Option<(f64, f64)> = None;
    for g in groups.iter_mut() {
        let first = x.len() / 2;
        offsets.push(first);
        let n = g.sites.len();
        match g.kind {
            Kind::Crystal {
                drift,
                turn,
                rattle,
                temperature,
            } => {
                let cx = g.sites.iter().map(|p| p.0).sum::<f64>() / n as f64;
                let cy = g.sites.iter().map(|p| p.1).sum::<f64>() / n as f64;
                let (s, c) = (turn * t).sin_cos();
                let sd = (temperature * E_CB).sqrt();
                for p in &g.sites {
                    let (dx, dy) = (p.0 - cx, p.1 - cy);
                    let px = cx + c * dx - s * dy + drift * t + rng.gen_range(-rattle..rattle);
                    let py = cy + s * dx + c * dy + rng.gen_range(-rattle..rattle);
                    x.extend([px.rem_euclid(L), py]);
                    v.extend([
                        drift - turn * (s * dx + c * dy) + gauss(rng, sd),
                        turn * (c * dx - s * dy) + gauss(rng, sd),
                    ]);
                }
                bridges.extend(g.lattice_bonds.iter().map(|&(i, j)| (first + i, first + j)));
                if first == 0 {
                    drop_span = Some(span(&x));
                }
            }
            Kind::Liquid {
                diffusion,
                temperature,
            } => {
                let step = (2.0 * diffusion * DT).sqrt();
                let sd = (temperature * E_CB).sqrt();
                for p in g.pos.iter_mut() {
                    if k > 0 {
                        p.0 += gauss(rng, step);
                        p.1 = (p.1 + gauss(rng, step)).clamp(0.5, H - 0.5);
                    }
                    x.extend([p.0.rem_euclid(L), p.1]);
                    v.extend([gauss(rng, sd), gauss(rng, sd)]);
                }
                if first == 0 {
                    drop_span = Some(span(&x));
                }
            }
            Kind::Gas {
                diffusion,
                temperature,
                u,
                wave,
            } => {
                let step = (2.0 * diffusion * DT).sqrt();
                let sd = (temperature * E_CB).sqrt();
                for p in g.pos.iter_mut() {
                    if k > 0 {
                        gas_step(p, u, wave, step, drop_span, rng);
                    }
                    x.extend([p.0.rem_euclid(L), p.1]);
                    v.extend([gauss(rng, sd), gauss(rng, sd)]);
                }
            }
        }
    }
    let n = x.len() / 2;
    let mut f = Frame::from_parts(2, vec![L, H], vec![true, false], x, v, vec![0.5; n], vec![]);
    // Liquid and gas grains: a bridge at every contact (liquid: within LIQUID_BOND).
    let kinds: Vec<u8> = groups
        .iter()
        .flat_map(|g| {
            let k = match g.kind {
                Kind::Crystal { .. } => 0,
                Kind::Liquid { .. } => 1,
                Kind::Gas { .. } => 2,
            };
            std::iter::repeat_n(k, g.sites.len())
        })
        .collect();
    for (i, j) in close_pairs(&f, LIQUID_BOND - 1.0) {
        let d2: f64 = (0..2)
            .map(|a| f.min_image(a, f.x(j)[a] - f.x(i)[a]).powi(2))
            .sum();
        let liquid_pair = kinds[i] == 1 && kinds[j] == 1;
        let liquid_crystal = kinds[i].min(kinds[j]) == 0 && kinds[i].max(kinds[j]) == 1;
        if liquid_pair || liquid_crystal || d2 < 1.0 {
            bridges.push((i, j));
        }
    }
    let gas_range: Vec<usize> = (0..n).filter(|&i| kinds[i] == 2).collect();
    let drop = groups[0].sites.len();
    for _ in 0..bounces.min(gas_range.len()) {
        let a = gas_range[rng.gen_range(0..gas_range.len())];
        bridges.push((a, rng.gen_range(0..drop)));
    }
    bridges.sort_unstable();
    bridges.dedup();
    f.bridges = bridges
        .into_iter()
        .map(|(i, j)| (i.min(j), i.max(j)))
        .filter(|&(i, j)| i != j)
        .collect();
    f.bridges.sort_unstable();
    f.bridges.dedup();
    f.time = t;
    f
}

/// The x interval `(a, b)` (periodic, `b` may be below `a` across the edge) covered by the
/// grains of flat positions `x`, widened by one diameter.
fn span(x: &[f64]) -> (f64, f64) {
    let xs: Vec<f64> = x.iter().step_by(2).copied().collect();
    // Unwrap about the first grain.
    let r = xs[0];
    let rel = xs.iter().map(|&v| {
        let d = v - r;
        d - L * (d / L).round()
    });
    let (lo, hi) = rel.fold((f64::MAX, f64::MIN), |(lo, hi), d| (lo.min(d), hi.max(d)));
    ((r + lo - 1.0).rem_euclid(L), (r + hi + 1.0).rem_euclid(L))
}

/// Whether `x` lies in the periodic interval from `a` to `b`.
fn inside(x: f64, a: f64, b: f64) -> bool {
    (x - a).rem_euclid(L) < (b - a).rem_euclid(L)
}

/// Feeds `SAMPLES` frames of `groups` through the observers and classifies the result.
fn label(mut groups: Vec<Group>, bounces: usize, seed: u64) -> Classification {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let n: usize = groups.iter().map(|g| g.sites.len()).sum();
    let sc = scene(n);
    let mut set = ObserverSet::new(&sc);
    assert!((set.sample_interval() - DT).abs() < 1e-12);
    for k in 0..SAMPLES {
        set.observe(&frame(k, &mut groups, bounces, &mut rng));
    }
    let obs = set.finish(&sc);
    classify(&obs, &sc.classify)
}

fn hot_gas(rng: &mut Xoshiro256PlusPlus, n: usize, exclude: (f64, f64)) -> Group {
    gas(rng, n, 2.0, 50.0, (0.0, 1.0), exclude)
}

#[test]
fn a_drifting_turning_crystal_drop_in_a_hot_gas_is_sgc() {
    for seed in 1..=3 {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(100 + seed);
        let drop = crystal(
            60.0,
            24.0,
            8.5,
            Kind::Crystal {
                drift: 0.2,
                turn: 0.005,
                rattle: 0.05,
                temperature: 0.2,
            },
        );
        let groups = vec![drop, hot_gas(&mut rng, 250, (55.0, 90.0))];
        let c = label(groups, 10, seed);
        eprintln!("seed {seed}: {}", c.decided_on.reason);
        let dense = c.decided_on.dense.as_ref().expect("a coexistence");
        let still = dense
            .members_still
            .expect("cage-relative displacements measured");
        assert!(still > 0.8, "{}", c.decided_on.reason);
        assert_eq!(c.phase, Phase::Sgc, "{}", c.decided_on.reason);
    }
}

#[test]
fn a_liquid_drop_in_a_hot_gas_is_fgc() {
    for seed in 1..=3 {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(200 + seed);
        let drop = liquid(60.0, 24.0, 8.5, 0.02, 1.0);
        let groups = vec![drop, hot_gas(&mut rng, 250, (55.0, 90.0))];
        let c = label(groups, 10, seed);
        eprintln!("seed {seed}: {}", c.decided_on.reason);
        // Its grains leave their neighbours: most members are not in their cage.
        let dense = c.decided_on.dense.as_ref().expect("a coexistence");
        let still = dense
            .members_still
            .expect("cage-relative displacements measured");
        assert!(still < 0.35, "{}", c.decided_on.reason);
        assert_eq!(c.phase, Phase::Fgc, "{}", c.decided_on.reason);
    }
}

#[test]
fn a_crystal_slab_next_to_a_bonded_liquid_is_sfc() {
    for seed in 1..=3 {
        let slab = crystal(
            0.0,
            100.0,
            8.5,
            Kind::Crystal {
                drift: 0.0,
                turn: 0.0,
                rattle: 0.05,
                temperature: 0.1,
            },
        );
        let layer = liquid(100.0, 100.0, 4.0, 0.02, 1.0);
        let c = label(vec![slab, layer], 0, seed);
        eprintln!("seed {seed}: {}", c.decided_on.reason);
        assert_eq!(c.phase, Phase::Sfc, "{}", c.decided_on.reason);
    }
}

#[test]
fn a_gas_with_a_density_wave_and_no_bonded_cluster_is_homogeneous() {
    for seed in 1..=3 {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(300 + seed);
        // Density contrast exp(2 u / D) = 4 between the wave's crests and troughs.
        let wavy = gas(&mut rng, 300, 2.0, 50.0, (0.7, 100.0), (0.0, 0.0));
        let c = label(vec![wavy], 0, seed);
        let test = c.decided_on.coexistence.as_ref().expect("the test ran");
        // The profile is far from homogeneous by the noise test alone ...
        assert!(
            test.delta > test.noise_threshold.expect("block statistics"),
            "{}",
            c.decided_on.reason
        );
        // ... but no bonded cluster holds its dense part: one homogeneous gas.
        assert!(!c.decided_on.split, "{}", c.decided_on.reason);
        assert_eq!(c.phase, Phase::G, "{}", c.decided_on.reason);
    }
}
