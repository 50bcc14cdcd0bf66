//! [`EngineState`]: a snapshot of a run that an engine can be rebuilt from (`from_state`), so a
//! run can be continued on the same trajectory later: checkpoints of finished jobs
//! (`sweep resume --extend`), continuation along a sweep axis, and the cold start.
//!
//! It holds what the physics needs (time, positions, velocities, radii, bridges) and the
//! accumulated event counts and energy ledger. Cells, neighbour lists and predictions are
//! derived again on restore; the TC remedy's last-collision times are reset, and the time
//! engine's higher Gear derivatives re-initialised from the forces.

use super::Frame;
use super::books::{EnergyLedger, EventCounts};
use serde::{Deserialize, Serialize};

/// A restorable snapshot of a run, vectors flat with stride `dimension`, particles in scene
/// order.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EngineState {
    /// `"event"` or `"time"`: the engine that wrote it (either engine can read it).
    pub engine: String,
    pub dimension: usize,
    pub time: f64,
    pub positions: Vec<f64>,
    pub velocities: Vec<f64>,
    pub radii: Vec<f64>,
    /// Bonded pairs `(i, j)`, `i < j`, sorted.
    pub bridges: Vec<(usize, usize)>,
    pub counts: EventCounts,
    /// Ledger at the snapshot (dissipated and injected energy so far).
    pub ledger: EnergyLedger,
}

impl EngineState {
    /// The state of a frame plus the engine's ledger at the frame's time.
    pub(crate) fn of_frame(engine: &str, frame: Frame, ledger: EnergyLedger) -> EngineState {
        EngineState {
            engine: engine.to_string(),
            dimension: frame.dimension,
            time: frame.time,
            positions: frame.positions,
            velocities: frame.velocities,
            radii: frame.radii,
            bridges: frame.bridges,
            counts: frame.counts,
            ledger,
        }
    }

    pub fn len(&self) -> usize {
        self.radii.len()
    }

    pub fn is_empty(&self) -> bool {
        self.radii.is_empty()
    }

    /// The start state of a continuation job: this final state of the neighbouring sweep point,
    /// whose scene was `prev`, carried into the next point's container. Heights move into the
    /// container frame (`prev`'s walls were displaced by `z_w(t) = A sin(omega t)`, docs/model.md
    /// 4.1, the next run's are at `z_w(0) = 0`), so every grain keeps its distance to floor and
    /// lid. Velocities and bridges are kept; time, counts and ledger start from zero.
    pub fn continued(&self, prev: &crate::scene::Scene) -> EngineState {
        let d = self.dimension;
        let shift = prev
            .drive_motion()
            .map_or(0.0, |(a, w)| a * (w * self.time).sin());
        let mut next = EngineState {
            time: 0.0,
            counts: Default::default(),
            ledger: Default::default(),
            ..self.clone()
        };
        if d > 0 && shift != 0.0 {
            for x in next.positions.chunks_mut(d) {
                x[d - 1] -= shift;
            }
        }
        next
    }

    /// Whether the snapshot fits a scene: dimension and particle count.
    pub(crate) fn check_fits(&self, scene: &crate::scene::Scene) -> Result<(), String> {
        if self.dimension != scene.dimension || self.len() != scene.particles.count {
            return Err(format!(
                "the saved state ({}D, {} particles) does not fit the scene ({}D, {} particles)",
                self.dimension,
                self.len(),
                scene.dimension,
                scene.particles.count
            ));
        }
        let d = self.dimension;
        if self.positions.len() != d * self.len() || self.velocities.len() != d * self.len() {
            return Err("the saved state's vectors do not have dimension * count entries".into());
        }
        if let Some(&(i, j)) = self
            .bridges
            .iter()
            .find(|&&(i, j)| i >= j || j >= self.len())
        {
            return Err(format!("the saved state has a bad bridge ({i}, {j})"));
        }
        Ok(())
    }
}
