//! The event engine's running sums of the energy that left or entered the particles other than
//! by free flight ([`Ledger`]); the books both engines report ([`EventCounts`],
//! [`EnergyLedger`]) are in `sim::books`.

/// Running sums of the energy exchanged at events (the shear field's work on flights is kept
/// by `Bodies`, which does the flights).
#[derive(Debug, Clone, Default)]
pub struct Ledger {
    pub dissipated_restitution: f64,
    pub dissipated_ruptures: f64,
    /// Energy the collapse remedies kept or added compared with plain restitution.
    pub added: f64,
    /// Work of the shaken walls.
    pub work_by_drive: f64,
    /// Potential energy added by wall placement (`table` solver).
    pub placement: f64,
}

impl Ledger {
    /// Books a collision of normal speed `u_in` (in the frame of the partner or wall) with
    /// coefficient `e` that left at `u_out`: plain restitution dissipates
    /// `inertia/2 (u_in^2 - e^2 u_in^2)`; what the collapse remedies kept or added on top,
    /// `inertia/2 (u_out^2 - e^2 u_in^2) >= 0`, is booked apart (`inertia` = `m/2` for pairs,
    /// `m` for walls).
    #[inline]
    pub(crate) fn book_restitution(&mut self, inertia: f64, u_in: f64, e: f64, u_out: f64) {
        let plain = e * u_in;
        self.dissipated_restitution += 0.5 * inertia * (u_in * u_in - plain * plain);
        self.added += 0.5 * inertia * (u_out * u_out - plain * plain);
    }
}
