//! The pair kernel of the time-driven engine: the force of one Verlet-list entry (damped Hertz
//! contact, Eq. 2.7; the minimal capillary bridge, docs/model.md 3.1) and its bookkeeping, and the
//! two loops over the list that every execution strategy uses: [`pair_chunk`] (one chunk of
//! entries, the parallel pair phase) and [`pair_forces_serial`] (the whole list on one thread,
//! the serial path and the spatial domains). Both call [`pair_response`] per entry and sum the
//! books per [`ENTRY_CHUNK`] entries, so every strategy gives the same bits.

use super::neighbours::{BOND, CONTACT};
use crate::physics::hertz;

/// Verlet-list entries per chunk of the pair phase of a step: the unit of work of a thread, and
/// the unit over which the booked sums are taken before they are added up in chunk order
/// (fixed, so the numbers do not depend on the number of threads).
pub const ENTRY_CHUNK: usize = 128;

/// What the pair loop needs besides the arrays.
pub(super) struct PairConstants<const D: usize> {
    pub periodic: [bool; D],
    pub size: [f64; D],
    pub stiffness: f64,
    pub damping: f64,
    pub bridge_force: f64,
    pub s_crit: f64,
    /// Factor turning the velocity array into velocities.
    pub vs: f64,
    /// Weight of the bookkeeping (the step, or 0).
    pub dt: f64,
}

/// What one chunk of the pair loop books.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct PairBooks {
    pub dissipated: f64,
    pub max_overlap: f64,
    pub bridge_ledger: f64,
    pub onsets: u64,
    pub formations: u64,
    pub ruptures: u64,
}

/// Pair forces (Eq. 2.7 and docs/model.md 3.1) of the Verlet-list entries of one chunk: entry `m`
/// is the pair `(row_of[m], partner[m])`; its force on the row's particle goes to
/// `pf[m * D..(m + 1) * D]` (zeros when the pair does not interact), and its contact and bond
/// flags are updated. A free function of slices so that the compiler keeps every array in a
/// register (no aliasing through `self`).
#[allow(clippy::too_many_arguments)]
pub(super) fn pair_chunk<const D: usize, const WET: bool>(
    pc: &PairConstants<D>,
    x: &[f64],
    v: &[f64],
    radius: &[f64],
    row_of: &[u32],
    partner: &[u32],
    flags: &mut [u8],
    pf: &mut [f64],
) -> PairBooks {
    let n = radius.len();
    let xs: [&[f64]; D] = std::array::from_fn(|k| &x[k * n..(k + 1) * n]);
    let vsl: [&[f64]; D] = std::array::from_fn(|k| &v[k * n..(k + 1) * n]);
    let mut half = [0.0; D];
    for k in 0..D {
        half[k] = 0.5 * pc.size[k];
    }
    let mut b = PairBooks::default();
    let len = flags.len();
    let (row_of, partner, pf) = (&row_of[..len], &partner[..len], &mut pf[..len * D]);
    for m in 0..len {
        let i = row_of[m] as usize;
        let j = partner[m] as usize;
        let out = &mut pf[m * D..(m + 1) * D];
        let mut d = [0.0; D];
        let mut r2 = 0.0;
        for k in 0..D {
            let mut dk = xs[k][i] - xs[k][j];
            if pc.periodic[k] {
                if dk > half[k] {
                    dk -= pc.size[k];
                } else if dk < -half[k] {
                    dk += pc.size[k];
                }
            }
            d[k] = dk;
            r2 += dk * dk;
        }
        let ri = radius[i];
        let rj = radius[j];
        let sig = ri + rj;
        let fl = flags[m];
        if r2 >= sig * sig && (!WET || fl & BOND == 0) {
            if fl & CONTACT != 0 {
                flags[m] = fl & !CONTACT;
            }
            out.fill(0.0);
            continue;
        }
        let pr = pair_response::<D, WET>(pc, &d, r2, ri, rj, fl, |k| vsl[k][i] - vsl[k][j]);
        b.book(&pr);
        if pr.flags != fl {
            flags[m] = pr.flags;
        }
        if pr.fmag != 0.0 {
            let s = pr.fmag * pr.inv;
            for k in 0..D {
                out[k] = s * d[k];
            }
        } else {
            out.fill(0.0);
        }
    }
    b
}

/// The response of one pair within reach (Eq. 2.7 and docs/model.md 3.1): force magnitude along the
/// line of centres, new contact and bond flags, and what the step books. Shared by every pair
/// loop (the serial loop, the parallel chunks, the spatial domains' cross pairs), so that they
/// take the same decisions with the same arithmetic; `vrel(k)` is `v_i - v_j` along axis `k`
/// (velocity array units), `d` the nearest-image `x_i - x_j`.
#[derive(Debug, Clone, Copy)]
pub(super) struct PairResponse {
    /// Force magnitude on `i` along `d / r` (0: no force).
    pub fmag: f64,
    /// `1 / r`.
    pub inv: f64,
    /// The pair's new flags.
    pub flags: u8,
    /// `R_i + R_j - r` (booked as the largest overlap when positive).
    pub overlap: f64,
    pub onset: bool,
    pub formation: bool,
    pub rupture: bool,
    /// Whether the damping did work, and that work `(F - F_elastic) xi_dot dt`.
    pub damped: bool,
    pub dissipated: f64,
    /// The bridge energy booked at a formation (`F_B overlap`) or rupture (`F_B s`).
    pub ledger: f64,
}

impl PairBooks {
    /// Books one pair's response in full (the parallel chunks and the domains' cross pairs;
    /// the serial loop books the sums per chunk of entries itself).
    #[inline(always)]
    pub(super) fn book(&mut self, pr: &PairResponse) {
        if pr.onset {
            self.onsets += 1;
        }
        if pr.overlap > 0.0 {
            self.max_overlap = self.max_overlap.max(pr.overlap);
        }
        if pr.damped {
            self.dissipated += pr.dissipated;
        }
        if pr.formation {
            self.formations += 1;
            self.bridge_ledger += pr.ledger;
        }
        if pr.rupture {
            self.ruptures += 1;
            self.bridge_ledger += pr.ledger;
        }
    }
}

/// See [`PairResponse`]; `fl` the pair's flags at the last evaluation.
#[inline(always)]
pub(super) fn pair_response<const D: usize, const WET: bool>(
    pc: &PairConstants<D>,
    d: &[f64; D],
    r2: f64,
    ri: f64,
    rj: f64,
    fl: u8,
    vrel: impl Fn(usize) -> f64,
) -> PairResponse {
    let sig = ri + rj;
    let r = r2.sqrt();
    let inv = 1.0 / r;
    let overlap = sig - r;
    let mut out = PairResponse {
        fmag: 0.0,
        inv,
        flags: fl,
        overlap,
        onset: false,
        formation: false,
        rupture: false,
        damped: false,
        dissipated: 0.0,
        ledger: 0.0,
    };
    if overlap > 0.0 {
        if fl & CONTACT == 0 {
            out.flags |= CONTACT;
            out.onset = true;
        }
        // xi_dot = -(v_i - v_j) . n, n = d / r.
        let mut vn = 0.0;
        for k in 0..D {
            vn += vrel(k) * d[k];
        }
        let xi_dot = -vn * inv * pc.vs;
        let kr = pc.stiffness * (ri * rj / sig).sqrt();
        // Eq. 2.7: k sqrt(R_eff) (xi^(3/2) + A_d sqrt(xi) dxi/dt), never a pull.
        let total = hertz::force(kr, overlap, xi_dot, pc.damping);
        if pc.damping > 0.0 {
            let elastic = kr * overlap * overlap.sqrt();
            out.damped = true;
            out.dissipated = (total - elastic) * xi_dot * pc.dt;
        }
        out.fmag = total;
        if WET && fl & BOND == 0 {
            // docs/model.md 3.1: a bridge forms at contact; its energy F_B s starts at
            // F_B (-overlap).
            out.flags |= BOND;
            out.formation = true;
            out.ledger = pc.bridge_force * overlap;
        }
    } else {
        out.flags &= !CONTACT;
    }
    if WET && out.flags & BOND != 0 {
        let s = -overlap;
        if s > pc.s_crit {
            // Rupture: the bridge energy F_B s leaves the system.
            out.flags &= !BOND;
            out.rupture = true;
            out.ledger = pc.bridge_force * s;
        } else {
            // docs/model.md 3.1: constant attraction F_B along the line of centres.
            out.fmag -= pc.bridge_force;
        }
    }
    out
}

/// The pair loop of the serial path ([`TimeEngine::forces_then_serial`]): forces (Eq. 2.7 and
/// docs/model.md 3.1) over the Verlet list, each pair once (Newton's third law), added to `f` (the
/// partner's share at once, the row's own sum at the end of its row); updates the contact and
/// bond flags. The same arithmetic as [`pair_chunk`] and the gather of [`particle_chunk`]; the
/// dissipation and bridge energy are summed per [`ENTRY_CHUNK`] entries as there.
#[allow(clippy::too_many_arguments)]
pub(super) fn pair_forces_serial<const D: usize, const WET: bool>(
    pc: &PairConstants<D>,
    x: &[f64],
    v: &[f64],
    f: &mut [f64],
    radius: &[f64],
    start: &[u32],
    rows: &[u32],
    partner: &[u32],
    flags: &mut [u8],
) -> PairBooks {
    let n = radius.len();
    let xs: [&[f64]; D] = std::array::from_fn(|k| &x[k * n..(k + 1) * n]);
    let vsl: [&[f64]; D] = std::array::from_fn(|k| &v[k * n..(k + 1) * n]);
    let mut half = [0.0; D];
    for k in 0..D {
        half[k] = 0.5 * pc.size[k];
    }
    let mut b = PairBooks::default();
    // Partial sums of the current chunk of entries.
    let (mut diss, mut ledger, mut boundary) = (0.0, 0.0, ENTRY_CHUNK);
    let radius = &radius[..n];
    let periodic = pc.periodic;
    for &i in rows {
        let i = i as usize;
        let (p0, p1) = (start[i] as usize, start[i + 1] as usize);
        let xi: [f64; D] = std::array::from_fn(|k| xs[k][i]);
        let mut fi = [0.0; D];
        // Whether some pair of the row exerts a force (else the row adds nothing to `f[i]`:
        // `f[i] + 0` is `f[i]`, as a force sum is never -0).
        let mut row_force = false;
        let ri = radius[i];
        for q in p0..p1 {
            // Before booking at entry `q`: close the partial sums of the earlier chunks (only
            // where something is booked, off the common path; a chunk that booked nothing
            // would add +0).
            macro_rules! chunk_of_q {
                () => {
                    if q >= boundary {
                        b.dissipated += diss;
                        b.bridge_ledger += ledger;
                        (diss, ledger) = (0.0, 0.0);
                        boundary = (q / ENTRY_CHUNK + 1) * ENTRY_CHUNK;
                    }
                };
            }
            let j = partner[q] as usize;
            let mut d = [0.0; D];
            let mut r2 = 0.0;
            for k in 0..D {
                let mut dk = xi[k] - xs[k][j];
                if periodic[k] {
                    if dk > half[k] {
                        dk -= pc.size[k];
                    } else if dk < -half[k] {
                        dk += pc.size[k];
                    }
                }
                d[k] = dk;
                r2 += dk * dk;
            }
            let rj = radius[j];
            let sig = ri + rj;
            let fl = flags[q];
            if r2 >= sig * sig && (!WET || fl & BOND == 0) {
                if fl & CONTACT != 0 {
                    flags[q] = fl & !CONTACT;
                }
                continue;
            }
            let pr = pair_response::<D, WET>(pc, &d, r2, ri, rj, fl, |k| vsl[k][i] - vsl[k][j]);
            if pr.onset {
                b.onsets += 1;
            }
            if pr.overlap > 0.0 {
                b.max_overlap = b.max_overlap.max(pr.overlap);
            }
            if pr.damped {
                chunk_of_q!();
                diss += pr.dissipated;
            }
            if pr.formation {
                b.formations += 1;
                chunk_of_q!();
                ledger += pr.ledger;
            }
            if pr.rupture {
                b.ruptures += 1;
                chunk_of_q!();
                ledger += pr.ledger;
            }
            if pr.flags != fl {
                flags[q] = pr.flags;
            }
            if pr.fmag != 0.0 {
                row_force = true;
                let s = pr.fmag * pr.inv;
                for k in 0..D {
                    let fk = s * d[k];
                    fi[k] += fk;
                    f[k * n + j] -= fk;
                }
            }
        }
        if row_force {
            for k in 0..D {
                f[k * n + i] += fi[k];
            }
        }
    }
    b.dissipated += diss;
    b.bridge_ledger += ledger;
    b
}
