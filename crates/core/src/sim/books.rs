//! The books both engines keep and report: work done by kind ([`EventCounts`]: events of the
//! event engine; the time-driven engine counts bridge formations and ruptures in the same
//! fields) and the full energy balance at one time ([`EnergyLedger`], which is also the event
//! engine's running sum of the energy exchanged at events).

use serde::{Deserialize, Serialize};

/// Events processed, by kind.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct EventCounts {
    pub pair_collisions: u64,
    pub wall_collisions: u64,
    pub cell_crossings: u64,
    pub bridge_formations: u64,
    pub bridge_ruptures: u64,
    pub well_bounces: u64,
    /// Shaken walls: scheduled re-checks of a particle that did not reach a wall within the
    /// solver's horizon (no velocity change).
    pub wall_rechecks: u64,
    /// Pair events found stale when popped (partner changed course) and re-predicted.
    pub invalidated: u64,
    /// Shear drive: crossings of a slab face (the force on the particle changes).
    pub slab_crossings: u64,
}

impl EventCounts {
    /// All processed events, stale ones included.
    pub fn total(&self) -> u64 {
        self.pair_collisions
            + self.wall_collisions
            + self.cell_crossings
            + self.well_bounces
            + self.bridge_ruptures
            + self.invalidated
            + self.wall_rechecks
            + self.slab_crossings
    }
}

/// Energy bookkeeping in units of `m g d` (or the scene's energy unit).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct EnergyLedger {
    pub kinetic: f64,
    pub potential: f64,
    /// Net energy removed by particle-particle and particle-wall restitution.
    pub dissipated_restitution: f64,
    /// Energy removed by bridge ruptures (`E_cb` each with the reduced-mass rule).
    pub dissipated_ruptures: f64,
    /// Energy added by the rebound floor (collapse remedy); zero in elastic systems.
    pub added_by_collapse_remedies: f64,
    /// Potential energy added by placing particles exactly on the wall at tabulated hits
    /// (`table` solver, B.5.1); zero for the other solvers.
    pub added_by_wall_placement: f64,
    /// Work done on the particles by the drive: the shaken walls, or the shear field
    /// (`sum m a_k dy` over every flight in slab `k`, docs/model.md 4.2).
    pub work_by_drive: f64,
}

impl EnergyLedger {
    /// Books a collision of normal speed `u_in` (in the frame of the partner or wall) with
    /// coefficient `e` that left at `u_out` (event engine): plain restitution dissipates
    /// `inertia/2 (u_in^2 - e^2 u_in^2)`; what the collapse remedies kept or added on top,
    /// `inertia/2 (u_out^2 - e^2 u_in^2) >= 0`, is booked apart (`inertia` = `m/2` for pairs,
    /// `m` for walls).
    #[inline]
    pub(crate) fn book_restitution(&mut self, inertia: f64, u_in: f64, e: f64, u_out: f64) {
        let plain = e * u_in;
        self.dissipated_restitution += 0.5 * inertia * (u_in * u_in - plain * plain);
        self.added_by_collapse_remedies += 0.5 * inertia * (u_out * u_out - plain * plain);
    }

    /// `kinetic + potential + dissipated - injected`: constant in exact arithmetic.
    pub fn total_accounted(&self) -> f64 {
        self.kinetic + self.potential + self.dissipated_restitution + self.dissipated_ruptures
            - self.added_by_collapse_remedies
            - self.added_by_wall_placement
            - self.work_by_drive
    }
}
