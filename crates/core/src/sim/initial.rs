//! The initial state of a scene: diameters drawn from the size distribution, centres on the
//! lattice of `scene::lattice`, Gaussian velocities with zero total momentum rescaled to the exact
//! requested granular temperature. Deterministic for a given seed. The cold start
//! ([`cold_state`], `initial.start = "cold"`) is the same lattice at rest with its close pairs
//! bonded.

use crate::physics::size::draw_diameters;
use crate::scene::{Scene, lattice};
use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use rand_xoshiro::Xoshiro256PlusPlus;

/// Particle radii, positions and velocities, each flattened into one array (`dim` numbers per
/// particle in `position` and `velocity`): what both engines build from, without a heap
/// allocation per particle (`wetgran-bench memory`).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct FlatInitialState {
    pub radius: Vec<f64>,
    pub position: Vec<f64>,
    pub velocity: Vec<f64>,
}

impl FlatInitialState {
    /// The particles of a saved state.
    pub(crate) fn of_state(state: &super::EngineState) -> Self {
        Self {
            radius: state.radii.clone(),
            position: state.positions.clone(),
            velocity: state.velocities.clone(),
        }
    }
}

/// Builds the initial state of a validated scene, flattened.
pub(crate) fn initial_state_flat(scene: &Scene) -> FlatInitialState {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(scene.initial.seed);
    let p = &scene.particles;
    let dim = scene.dimension;
    let radius: Vec<f64> = draw_diameters(&mut rng, p.count, p.diameter, p.polydispersity)
        .iter()
        .map(|d| 0.5 * d)
        .collect();
    let (_, d_max) = scene.diameter_range();
    let min_spacing = scene.initial.lattice_spacing * d_max;
    let size = &scene.container.size;
    let from_floor = scene.gravity > 0.0;
    let spacing = if from_floor {
        min_spacing
    } else {
        lattice::uniform_spacing(size, min_spacing, p.count)
    };
    let position = lattice::site_positions(size, spacing, p.count, from_floor).concat();

    let temperature = scene.initial_temperature();
    // Drawn particle by particle, axis by axis.
    let mut velocity: Vec<f64> = (0..p.count * dim)
        .map(|_| StandardNormal.sample(&mut rng))
        .collect();
    // Zero total momentum, then rescale to T_g = m (<v^2> - <v>^2) / f_d exactly (Eq. 3.2).
    let n = p.count as f64;
    let mut mean = vec![0.0; dim];
    for v in velocity.chunks(dim) {
        for k in 0..dim {
            mean[k] += v[k] / n;
        }
    }
    let mut sum_sq = 0.0;
    for v in velocity.chunks_mut(dim) {
        for k in 0..dim {
            v[k] -= mean[k];
            sum_sq += v[k] * v[k];
        }
    }
    let current = p.mass * sum_sq / (n * dim as f64);
    let scale = if current > 0.0 && temperature > 0.0 {
        (temperature / current).sqrt()
    } else {
        0.0
    };
    velocity.iter_mut().for_each(|x| *x *= scale);
    FlatInitialState {
        radius,
        position,
        velocity,
    }
}

/// The cold start (`initial.start = "cold"`): the hot start's lattice and radii, every velocity
/// zero, and a capillary bridge between every pair whose surface separation
/// `|x_i - x_j| - r_i - r_j` (nearest image on periodic axes) is below `s_crit`: a bonded bed at
/// rest that settles under gravity. Time 0, counts and ledger zero.
pub fn cold_state(scene: &Scene) -> super::EngineState {
    let init = initial_state_flat(scene);
    let dim = scene.dimension;
    let x = |i: usize| &init.position[i * dim..(i + 1) * dim];
    let n = init.radius.len();
    let s_crit = if scene.is_wet() { scene.s_crit() } else { 0.0 };
    let (_, d_max) = scene.diameter_range();
    let cell = d_max + s_crit;
    let periodic: Vec<bool> = scene
        .boundaries()
        .iter()
        .map(|b| *b == crate::scene::Boundary::Periodic)
        .collect();
    let size = &scene.container.size;
    // Cells of edge >= d_max + s_crit: bonded pairs are in neighbouring cells. On a periodic
    // axis the last cell absorbs the remainder, so cells wrap exactly.
    let ncells: Vec<i64> = size
        .iter()
        .map(|l| ((l / cell).floor() as i64).max(1))
        .collect();
    let cell_of = |i: usize, offset: &[i64]| -> Vec<i64> {
        (0..dim)
            .map(|k| {
                let c = (x(i)[k] / cell).floor() as i64;
                if periodic[k] {
                    (c.clamp(0, ncells[k] - 1) + offset[k]).rem_euclid(ncells[k])
                } else {
                    c + offset[k]
                }
            })
            .collect()
    };
    let mut grid: std::collections::HashMap<Vec<i64>, Vec<usize>> = Default::default();
    for i in 0..n {
        grid.entry(cell_of(i, &vec![0; dim])).or_default().push(i);
    }
    let offsets: Vec<Vec<i64>> = (0..3i64.pow(dim as u32))
        .map(|m| (0..dim).map(|k| m / 3i64.pow(k as u32) % 3 - 1).collect())
        .collect();
    let mut bridges = Vec::new();
    for i in (0..n).filter(|_| s_crit > 0.0) {
        // The neighbour cells, each once (a periodic axis of fewer than 3 cells repeats some).
        let mut hood: Vec<Vec<i64>> = offsets.iter().map(|o| cell_of(i, o)).collect();
        hood.sort_unstable();
        hood.dedup();
        let partners = hood.iter().filter_map(|c| grid.get(c)).flatten();
        for &j in partners.filter(|&&j| j > i) {
            let mut r2 = 0.0;
            for k in 0..dim {
                let mut d = x(i)[k] - x(j)[k];
                if periodic[k] {
                    d -= size[k] * (d / size[k]).round();
                }
                r2 += d * d;
            }
            if r2.sqrt() - init.radius[i] - init.radius[j] < s_crit {
                bridges.push((i, j));
            }
        }
    }
    bridges.sort_unstable();
    super::EngineState {
        engine: "cold start".to_string(),
        dimension: dim,
        time: 0.0,
        positions: init.position,
        velocities: vec![0.0; dim * n],
        radii: init.radius,
        bridges,
        counts: Default::default(),
        ledger: Default::default(),
    }
}
