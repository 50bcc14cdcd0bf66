//! The pair kernel of the time-driven engine: [`pair_kernel`] is the force of one Verlet-list
//! entry (the minimum image, the reach test, the damped Hertz contact of Eq. 2.7 and the minimal
//! capillary bridge of docs/model.md 3.1) with its new flags. The two loops over entries call it
//! and differ only in where the force goes: [`pair_forces_serial`] (scattered to both partners:
//! the serial strategy, a domain's inner pairs) and [`cross_forces`] (a domain's pairs with the
//! other domain, the partner read from its halo). The books are summed per [`ENTRY_CHUNK`]
//! entries.

use super::neighbours::{BOND, CONTACT};
use crate::physics::hertz;

/// Verlet-list entries per chunk of the pair loop: the unit of the booked sums, added in chunk
/// order.
pub(super) const ENTRY_CHUNK: usize = 128;

/// What the pair kernel needs besides the particles' state.
#[derive(Debug, Clone, Copy)]
pub(super) struct PairConstants<const D: usize> {
    pub periodic: [bool; D],
    pub size: [f64; D],
    /// Half the box size per axis (the minimum-image bound).
    pub half: [f64; D],
    pub stiffness: f64,
    pub damping: f64,
    pub(crate) bridge_force: f64,
    pub s_crit: f64,
    /// Factor turning the velocity array into velocities.
    pub vs: f64,
    /// Weight of the bookkeeping (the step, or 0).
    pub dt: f64,
}

/// What a loop over pairs or wall contacts books: its sums (run on in its order; the engine
/// keeps one per chunk), its counts and the largest overlap.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Books {
    /// Work of the damping part of Eq. 2.7, `sum F_damp xi_dot dt`.
    pub dissipated: f64,
    /// The bridge energy booked at formations and ruptures.
    pub(crate) bridge_ledger: f64,
    /// Work of the moving walls, `sum F_wall v_wall dt`.
    pub work: f64,
    pub max_overlap: f64,
    pub(crate) pair_onsets: u64,
    pub(crate) wall_onsets: u64,
    pub formations: u64,
    pub ruptures: u64,
}

/// One Verlet-list entry, the pair `(i, j)` at positions `xi`, `xj` with radii `ri`, `rj` and
/// the flags `flag` of the last evaluation; `vrel(k)` is `v_i - v_j` along axis `k` (velocity
/// array units). `None` when the pair is out of reach and not bonded (its contact flag is
/// cleared); otherwise its response, with `flag` updated, and the force on `i` (`-` that on
/// `j`; zeros when the response exerts none).
pub(super) fn pair_kernel<const D: usize, const WET: bool>(
    pc: &PairConstants<D>,
    xi: &[f64; D],
    xj: &[f64; D],
    ri: f64,
    rj: f64,
    flag: &mut u8,
    vrel: impl Fn(usize) -> f64,
) -> Option<(PairResponse, [f64; D])> {
    let mut d = [0.0; D];
    let mut r2 = 0.0;
    for k in 0..D {
        let mut dk = xi[k] - xj[k];
        if pc.periodic[k] {
            if dk > pc.half[k] {
                dk -= pc.size[k];
            } else if dk < -pc.half[k] {
                dk += pc.size[k];
            }
        }
        d[k] = dk;
        r2 += dk * dk;
    }
    let sig = ri + rj;
    let fl = *flag;
    if r2 >= sig * sig && (!WET || fl & BOND == 0) {
        if fl & CONTACT != 0 {
            *flag = fl & !CONTACT;
        }
        return None;
    }
    let r = r2.sqrt();
    let inv = 1.0 / r;
    let overlap = sig - r;
    let mut out = PairResponse {
        fmag: 0.0,
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
    if out.flags != fl {
        *flag = out.flags;
    }
    let mut force = [0.0; D];
    if out.fmag != 0.0 {
        let s = out.fmag * inv;
        for k in 0..D {
            force[k] = s * d[k];
        }
    }
    Some((out, force))
}

/// The response of one pair within reach ([`pair_kernel`]): force magnitude along the line of
/// centres, new contact and bond flags, and what the step books.
#[derive(Debug, Clone, Copy)]
pub(super) struct PairResponse {
    /// Force magnitude on `i` along `d / r` (0: no force).
    pub(crate) fmag: f64,
    /// The pair's new flags.
    pub flags: u8,
    /// `R_i + R_j - r` (booked as the largest overlap when positive).
    pub overlap: f64,
    pub onset: bool,
    pub(crate) formation: bool,
    pub rupture: bool,
    /// Whether the damping did work, and that work `(F - F_elastic) xi_dot dt`.
    pub damped: bool,
    pub dissipated: f64,
    /// The bridge energy booked at a formation (`F_B overlap`) or rupture (`F_B s`).
    pub ledger: f64,
}

impl Books {
    /// Adds `b`: its sums, then [`Self::add_counts`].
    pub(super) fn add(&mut self, b: &Books) {
        self.dissipated += b.dissipated;
        self.bridge_ledger += b.bridge_ledger;
        self.work += b.work;
        self.add_counts(b);
    }

    /// Adds the counts and the largest overlap of `b`.
    pub(super) fn add_counts(&mut self, b: &Books) {
        self.max_overlap = self.max_overlap.max(b.max_overlap);
        self.pair_onsets += b.pair_onsets;
        self.wall_onsets += b.wall_onsets;
        self.formations += b.formations;
        self.ruptures += b.ruptures;
    }

    /// Books one pair's response in full (the domains' cross pairs; the serial loop books the
    /// sums per chunk of entries itself).
    pub(super) fn book(&mut self, pr: &PairResponse) {
        self.book_counts(pr);
        if pr.damped {
            self.dissipated += pr.dissipated;
        }
        if pr.formation || pr.rupture {
            self.bridge_ledger += pr.ledger;
        }
    }

    /// Books the onset, formation and rupture counts and the largest overlap of a response.
    pub(super) fn book_counts(&mut self, pr: &PairResponse) {
        self.pair_onsets += u64::from(pr.onset);
        self.formations += u64::from(pr.formation);
        self.ruptures += u64::from(pr.rupture);
        if pr.overlap > 0.0 {
            self.max_overlap = self.max_overlap.max(pr.overlap);
        }
    }
}

/// The pair loop of the serial strategy and of a domain's inner pairs: [`pair_kernel`] over the
/// half list (`rows` the non-empty rows, `start` their entries), each pair once (Newton's third
/// law), added to `f` (the partner's share at once, the row's own sum at the end of its row).
/// The dissipation and bridge energy are summed per [`ENTRY_CHUNK`] entries.
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
) -> Books {
    let n = radius.len();
    let xs: [&[f64]; D] = std::array::from_fn(|k| &x[k * n..(k + 1) * n]);
    let vsl: [&[f64]; D] = std::array::from_fn(|k| &v[k * n..(k + 1) * n]);
    let mut b = Books::default();
    // Partial sums of the current chunk of entries.
    let (mut diss, mut ledger, mut boundary) = (0.0, 0.0, ENTRY_CHUNK);
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
            let j = partner[q] as usize;
            let xj: [f64; D] = std::array::from_fn(|k| xs[k][j]);
            let vrel = |k: usize| vsl[k][i] - vsl[k][j];
            let Some((pr, force)) =
                pair_kernel::<D, WET>(pc, &xi, &xj, ri, radius[j], &mut flags[q], vrel)
            else {
                continue;
            };
            b.book_counts(&pr);
            if pr.damped || pr.formation || pr.rupture {
                // Close the partial sums of the earlier chunks (only where something is
                // booked, off the common path; a chunk that booked nothing would add +0).
                if q >= boundary {
                    b.dissipated += diss;
                    b.bridge_ledger += ledger;
                    (diss, ledger) = (0.0, 0.0);
                    boundary = (q / ENTRY_CHUNK + 1) * ENTRY_CHUNK;
                }
                if pr.damped {
                    diss += pr.dissipated;
                }
                if pr.formation || pr.rupture {
                    ledger += pr.ledger;
                }
            }
            if pr.fmag != 0.0 {
                row_force = true;
                for k in 0..D {
                    fi[k] += force[k];
                    f[k * n + j] -= force[k];
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

/// Forces of a domain's cross pairs on its own particles ([`pair_kernel`] with the partner read
/// from the halo `ghosts`: `2 D` values per ghost, position then velocity array value); entry
/// `q` is the pair of own particle `own[q]` and ghost `ghost[q]`. Returns the books (the caller
/// keeps them in one domain only).
pub(super) fn cross_forces<const D: usize, const WET: bool>(
    pc: &PairConstants<D>,
    x: &[f64],
    v: &[f64],
    f: &mut [f64],
    radius: &[f64],
    ghosts: &[f64],
    ghost_radius: &[f64],
    own: &[u32],
    ghost: &[u32],
    flags: &mut [u8],
) -> Books {
    let m = radius.len();
    let mut b = Books::default();
    let (own, ghost) = (&own[..flags.len()], &ghost[..flags.len()]);
    for q in 0..flags.len() {
        let (i, g) = (own[q] as usize, ghost[q] as usize);
        let gs = &ghosts[g * 2 * D..(g + 1) * 2 * D];
        let xi: [f64; D] = std::array::from_fn(|k| x[k * m + i]);
        let xj: [f64; D] = std::array::from_fn(|k| gs[k]);
        let vrel = |k: usize| v[k * m + i] - gs[D + k];
        let rj = ghost_radius[g];
        let Some((pr, force)) =
            pair_kernel::<D, WET>(pc, &xi, &xj, radius[i], rj, &mut flags[q], vrel)
        else {
            continue;
        };
        b.book(&pr);
        if pr.fmag != 0.0 {
            for k in 0..D {
                f[k * m + i] += force[k];
            }
        }
    }
    b
}
