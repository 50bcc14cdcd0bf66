//! [`Frame`]: a read-only copy of one configuration (positions, velocities, radii, bridges,
//! event counts) in scene order, independent of the engine's dimension and type parameters.
//! Observers and pictures work on frames; the engine never sees them.

use super::books::EventCounts;
use super::event_driven::queue::EventQueue;
use super::event_driven::{Engine, Vector};
use super::time_driven::{BodyForce, TimeEngine};
use crate::scene::{Boundary, Scene};
use serde::Serialize;

/// One sampled configuration, in scene order. Vectors are stored flat with stride
/// `dimension` (`x, z` in 2D, `x, y, z` in 3D; the last axis is vertical).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Frame {
    pub time: f64,
    pub dimension: usize,
    pub box_size: Vec<f64>,
    pub periodic: Vec<bool>,
    /// Vertical displacement of the container (floor and lid) at `time`: `A sin(omega t)`
    /// for a shaken scene (docs/model.md 4.1), 0 otherwise. The floor is at `z = wall_offset`, the lid
    /// at `z = H + wall_offset`.
    pub wall_offset: f64,
    /// Particle mass (the same for all).
    pub mass: f64,
    pub positions: Vec<f64>,
    pub velocities: Vec<f64>,
    pub radii: Vec<f64>,
    /// Capillary bridges as scene-index pairs `(i, j)`, `i < j`, sorted.
    pub bridges: Vec<(usize, usize)>,
    /// Events processed up to `time`.
    pub counts: EventCounts,
}

impl Frame {
    /// The first particle whose position or velocity is not finite, as a broken-invariant
    /// message; `None` for a sound frame. The observers need finite positions (a Delaunay
    /// triangulation of a NaN is undefined), so a blown-up run stops here.
    pub fn non_finite(&self) -> Option<String> {
        let d = self.dimension.max(1);
        let bad = |v: &[f64]| v.iter().position(|x| !x.is_finite()).map(|k| k / d);
        let (what, i) = match (bad(&self.positions), bad(&self.velocities)) {
            (Some(i), _) => ("position", i),
            (None, Some(i)) => ("velocity", i),
            (None, None) => return None,
        };
        Some(format!(
            "particle {i} has a non-finite {what} at t = {}: a blown-up run",
            self.time
        ))
    }

    /// Copies the current state of an engine.
    pub fn of_engine<const D: usize, const G: bool, const W: bool, const S: bool, Q: EventQueue>(
        engine: &Engine<D, G, W, S, Q>,
        scene: &Scene,
    ) -> Frame {
        let flat =
            |v: Vec<Vector<D>>| -> Vec<f64> { v.iter().flat_map(|x| x.iter().copied()).collect() };
        Frame::of_state(
            scene,
            D,
            engine.time(),
            [flat(engine.positions()), flat(engine.velocities())],
            engine.radii(),
            engine.bridges(),
            engine.counts().clone(),
        )
    }

    /// Copies the current state of a time-driven engine (its event counts are contact onsets,
    /// bridge formations and ruptures; see `time_driven::engine`).
    pub(crate) fn of_time_engine<const D: usize, const G: bool, const W: bool, B: BodyForce<D>>(
        engine: &TimeEngine<D, G, W, B>,
        scene: &Scene,
    ) -> Frame {
        Frame::of_state(
            scene,
            D,
            engine.time(),
            [engine.positions_flat(), engine.velocities_flat()],
            engine.radii().to_vec(),
            engine.bridges(),
            engine.counts().clone(),
        )
    }

    /// The frame of a saved state (a stored checkpoint) of a run of `scene`: what a report draws
    /// of a finished job without running it again.
    pub fn of_saved_state(state: &super::EngineState, scene: &Scene) -> Frame {
        Frame::of_state(
            scene,
            state.dimension,
            state.time,
            [state.positions.clone(), state.velocities.clone()],
            state.radii.clone(),
            state.bridges.clone(),
            state.counts.clone(),
        )
    }

    /// A frame from an engine's state (`[positions, velocities]` flat, particle-major) and the
    /// scene's box, boundaries, container motion and mass.
    fn of_state(
        scene: &Scene,
        dimension: usize,
        time: f64,
        [positions, velocities]: [Vec<f64>; 2],
        radii: Vec<f64>,
        bridges: Vec<(usize, usize)>,
        counts: EventCounts,
    ) -> Frame {
        Frame {
            time,
            dimension,
            box_size: scene.container.size.clone(),
            periodic: scene
                .boundaries()
                .iter()
                .map(|b| *b == Boundary::Periodic)
                .collect(),
            wall_offset: scene
                .drive_motion()
                .map_or(0.0, |(a, omega)| a * (omega * time).sin()),
            mass: scene.particles.mass,
            positions,
            velocities,
            radii,
            bridges,
            counts,
        }
    }

    pub fn len(&self) -> usize {
        self.radii.len()
    }

    pub fn is_empty(&self) -> bool {
        self.radii.is_empty()
    }

    pub fn x(&self, i: usize) -> &[f64] {
        &self.positions[i * self.dimension..(i + 1) * self.dimension]
    }

    pub fn v(&self, i: usize) -> &[f64] {
        &self.velocities[i * self.dimension..(i + 1) * self.dimension]
    }

    /// Height (last coordinate) of particle `i`.
    pub fn height(&self, i: usize) -> f64 {
        self.positions[(i + 1) * self.dimension - 1]
    }

    /// `dx` along axis `k` reduced to the nearest periodic image (unchanged on wall axes).
    pub fn min_image(&self, k: usize, dx: f64) -> f64 {
        if self.periodic[k] {
            let l = self.box_size[k];
            dx - l * (dx / l).round()
        } else {
            dx
        }
    }

    /// Coordinate `x` along axis `k` wrapped into `[0, L)` on periodic axes.
    pub fn wrap(&self, k: usize, x: f64) -> f64 {
        if self.periodic[k] {
            let l = self.box_size[k];
            let w = x.rem_euclid(l);
            if w >= l { 0.0 } else { w }
        } else {
            x
        }
    }

    /// A frame built by hand (tests, pictures of prescribed configurations): zero counts, no
    /// wall motion, unit mass.
    pub fn from_parts(
        dimension: usize,
        box_size: Vec<f64>,
        periodic: Vec<bool>,
        positions: Vec<f64>,
        velocities: Vec<f64>,
        radii: Vec<f64>,
        bridges: Vec<(usize, usize)>,
    ) -> Frame {
        assert_eq!(box_size.len(), dimension, "one box size per axis");
        assert_eq!(periodic.len(), dimension, "one boundary flag per axis");
        assert_eq!(positions.len(), radii.len() * dimension, "positions");
        assert_eq!(velocities.len(), radii.len() * dimension, "velocities");
        let mut bridges: Vec<(usize, usize)> = bridges
            .into_iter()
            .map(|(i, j)| (i.min(j), i.max(j)))
            .collect();
        bridges.sort_unstable();
        Frame {
            time: 0.0,
            dimension,
            box_size,
            periodic,
            wall_offset: 0.0,
            mass: 1.0,
            positions,
            velocities,
            radii,
            bridges,
            counts: EventCounts::default(),
        }
    }
}
