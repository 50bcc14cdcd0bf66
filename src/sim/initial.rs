//! The initial state of a scene: diameters drawn from the size distribution, centres on the
//! lattice of `scene::lattice`, Gaussian velocities with zero total momentum rescaled to the exact
//! requested granular temperature. Deterministic for a given seed.

use crate::physics::size::draw_diameters;
use crate::scene::{Scene, lattice};
use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use rand_xoshiro::Xoshiro256PlusPlus;

/// Particle radii, positions and velocities, flattened per particle (`dim` numbers each).
#[derive(Debug, Clone, PartialEq)]
pub struct InitialState {
    pub radius: Vec<f64>,
    pub position: Vec<Vec<f64>>,
    pub velocity: Vec<Vec<f64>>,
}

/// Builds the initial state of a validated scene.
pub fn initial_state(scene: &Scene) -> InitialState {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(scene.initial.seed);
    let p = &scene.particles;
    let dim = scene.dimension;
    let diameters = draw_diameters(&mut rng, p.count, p.diameter, p.polydispersity);
    let (_, d_max) = scene.diameter_range();
    let min_spacing = scene.initial.lattice_spacing * d_max;
    let size = &scene.container.size;
    let from_floor = scene.gravity > 0.0;
    let spacing = if from_floor {
        min_spacing
    } else {
        lattice::uniform_spacing(size, min_spacing, p.count)
    };
    let position = lattice::site_positions(size, spacing, p.count, from_floor);

    let temperature = scene.initial_temperature();
    let mut velocity: Vec<Vec<f64>> = (0..p.count)
        .map(|_| (0..dim).map(|_| StandardNormal.sample(&mut rng)).collect())
        .collect();
    // Zero total momentum, then rescale to T_g = m (<v^2> - <v>^2) / f_d exactly (Eq. 3.2).
    let n = p.count as f64;
    let mut mean = vec![0.0; dim];
    for v in &velocity {
        for k in 0..dim {
            mean[k] += v[k] / n;
        }
    }
    let mut sum_sq = 0.0;
    for v in &mut velocity {
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
    for v in &mut velocity {
        for x in v.iter_mut() {
            *x *= scale;
        }
    }
    InitialState {
        radius: diameters.iter().map(|d| 0.5 * d).collect(),
        position,
        velocity,
    }
}
