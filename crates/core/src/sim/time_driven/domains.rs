//! Spatial domain decomposition of the time-driven Gear step (one job on two cores): the box is
//! cut across its longest axis into [`DOMAINS`] slabs of equal particle counts, each slab's
//! particles copied into a [`Domain`] of their own (contiguous local arrays), and a team of
//! threads (`team.rs`) runs whole steps on the domains with one barrier per step. Only the
//! **halo** crosses between the threads: position and velocity of the particles that some pair
//! of the other domain reaches (a few dozen near the two cuts), published into a double buffer.
//!
//! Per domain and step (docs/model.md 2.2, Eq. 2.7 and 3.1; the kernels of the serial step):
//!
//! 1. the pairs inside the domain, each once (`pair_forces_serial`);
//! 2. the **cross pairs** (one end in each domain), computed by *both* domains, each for its own
//!    particle, from the other end's halo copy. The arithmetic is exactly antisymmetric
//!    (`x_i - x_j` and `x_j - x_i` are exact negatives, every later operation is symmetric or
//!    multiplies by them), so both copies take the same contact and bond decisions and exert
//!    exactly opposite forces; only domain 0 books them;
//! 3. the walls, `1/m`, Gear's fused corrector-predictor (`integrator.rs`);
//! 4. the halo of the next step into the other parity of the double buffer, and the list check
//!    for the next step (`neighbours::needs_rebuild`, per domain).
//!
//! When a domain's check asks for a rebuild (every domain sees it after the barrier), the
//! **team builds the list itself** and goes on ([`Decomposition::build_in_team`]): the threads
//! stay awake (a build handed to a sleeping pool thread runs serially in effect), and the list
//! is the one the engine's `update_list` would build at that step. A region ends at the run's
//! target step, or when a build calls for a new partition; the engine then copies the state
//! back. The partition is made at a list build and kept over later builds ([`Decomposition`]),
//! so where regions end (samples, checkpoints) changes no number.
//!
//! **Determinism.** Which thread runs a domain changes no operation: one thread runs the
//! domains in turn with the same code (the halo double buffer makes the order irrelevant), so
//! one, two or three threads give the same bits. Against the serial step the force on a
//! particle is summed in another order (domain pairs, then cross pairs), a round-off change
//! (engine test `domains_change_the_serial_trajectory_by_round_off`), which is why the engine
//! chooses the path by the number of particles alone, never by the threads.

use super::integrator::{GEAR_FLUSH_EVERY, gear_correct_predict_axes};
use super::neighbours::{NeighbourList, RowScan, needs_rebuild, norm};
use super::pair_kernel::{Books, PairConstants, cross_forces, pair_forces_serial};
use super::walls::{WallAxis, wall_forces};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Mutex, RwLock};

/// Domains the box is cut into (fixed, so the numbers do not depend on the thread count; a
/// team has at most this many members).
pub(crate) const DOMAINS: usize = 2;

/// From this many particles on, every Gear step of a scene without a body force runs on the
/// domains, on any number of threads (below, a step is too short for two threads to gain:
/// docs/performance-history.md, "Sixth round: spatial domains").
pub(crate) const DOMAIN_MIN_PARTICLES: usize = 1024;

/// What a domain step needs besides its own arrays (the same for every domain of a step).
#[derive(Debug, Clone, Copy)]
pub(super) struct StepConstants<const D: usize> {
    /// The pair kernel's constants (velocity scale `1 / dt`, books weighted by `dt`).
    pub pair: PairConstants<D>,
    pub dt: f64,
    pub(crate) inv_mass: Option<f64>,
    /// The force every coordinate starts from (the weight on the last axis).
    pub(crate) init: [f64; D],
    pub(crate) gear: [f64; 6],
    /// Half the neighbour list's skin: the largest displacement the list tolerates.
    pub(crate) half_skin: f64,
}

/// What each domain booked in a region, in domain order: counts and largest overlap, and the
/// per-step sums (dissipation, bridge ledger, drive work).
pub(super) type RegionBooks = Vec<(Books, Vec<[f64; 3]>)>;

/// How a region of domain steps ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum RegionEnd {
    /// At the run's target step.
    Target,
    /// At the run's target step, where a domain's check asks for a list build before the next
    /// step (the engine's `update_list` builds it when the run goes on).
    Rebuild,
    /// The team rebuilt the list and the build calls for a new partition
    /// ([`Decomposition::wants_new_partition`]); the domains still hold the lists of the
    /// build before.
    Repartition,
}

/// What a team needs to rebuild the neighbour list without leaving its region: the engine's
/// list and positions, the radii, the two parts of the row scan.
pub(super) struct TeamBuild<'a, const D: usize> {
    list: RwLock<&'a mut NeighbourList<D>>,
    x: Mutex<&'a mut [f64]>,
    radius: &'a [f64],
    scans: [Mutex<RowScan>; 2],
    /// Set by member 0 when the new build calls for a new partition.
    repartition: AtomicBool,
}

impl<'a, const D: usize> TeamBuild<'a, D> {
    /// The engine's list, its positions `x` (axis-major, written back before a build) and
    /// the radii.
    pub(super) fn new(list: &'a mut NeighbourList<D>, x: &'a mut [f64], radius: &'a [f64]) -> Self {
        Self {
            list: RwLock::new(list),
            x: Mutex::new(x),
            radius,
            scans: Default::default(),
            repartition: AtomicBool::new(false),
        }
    }
}

/// One domain: its particles' state in local order, its lists and its halo bookkeeping.
#[derive(Debug, Clone, Default)]
pub(super) struct Domain<const D: usize> {
    /// Scene index of each local particle.
    pub ids: Vec<u32>,
    /// Gear's scaled derivatives, local, axis-major (`r[q][k * m + i]`).
    pub r: [Vec<f64>; 6],
    /// Forces (start values between steps).
    pub(crate) acc: Vec<f64>,
    pub(crate) acc_is_start: bool,
    pub radius: Vec<f64>,
    pub(crate) wall_kr: Vec<f64>,
    pub(crate) wall_contact: Vec<u8>,
    /// Positions at the last list build (local, axis-major).
    pub(crate) built_at: Vec<f64>,
    /// The half list of the pairs inside the domain (compressed rows, local indices).
    pub start: Vec<u32>,
    pub rows: Vec<u32>,
    pub partner: Vec<u32>,
    pub flags: Vec<u8>,
    /// The engine's list entry of each inner entry.
    pub(crate) inner_src: Vec<u32>,
    /// Cross pairs: own local index (ascending), ghost number, flags, the engine's entry.
    pub(crate) cross_own: Vec<u32>,
    pub(crate) cross_ghost: Vec<u32>,
    pub(crate) cross_flags: Vec<u8>,
    pub(crate) cross_src: Vec<u32>,
    /// Radius of each ghost (the other domain's particles the cross pairs reach, read from its
    /// halo).
    pub(crate) ghost_radius: Vec<f64>,
    /// Own particles (local, ascending) that are ghosts of the other domain, in its ghost
    /// order: published into the halo after each step.
    pub(crate) halo_out: Vec<u32>,
    /// Whether this domain books the cross pairs (domain 0).
    pub(crate) books_cross: bool,
    /// Displacement bound and steps since the exact test (the engine's `update_list`).
    pub bound: f64,
    pub(crate) since_check: u32,
    /// Counts and largest overlap booked in the region (its sums stay zero: see
    /// `step_books`).
    pub books: Books,
    /// Per step of the region: dissipation, bridge ledger, drive work (the engine adds them
    /// step by step, domains in order, so where regions end changes no sum).
    pub(crate) step_books: Vec<[f64; 3]>,
}

/// Which particle is in which domain, the domains, and the shared halo buffers.
///
/// The **partition** is made at a list build and kept until the cross pairs outnumber twice
/// those at the partition (plus [`REPARTITION_SLACK`]) or [`REPARTITION_EVERY`] builds have
/// passed: particles drift across the cut only slowly, any partition is valid (it only sets
/// which pairs are cross pairs), and a kept one keeps the state in the domains. Both rules
/// depend on the trajectory alone, so the numbers do not depend on the threads or on where
/// regions end.
#[derive(Debug)]
pub(super) struct Decomposition<const D: usize> {
    /// The list build whose entries the domains' lists hold (`NeighbourList::builds`).
    built_for: AtomicU64,
    /// The list build at which the partition was made.
    pub(crate) partitioned_at: u64,
    /// Cross entries (per domain, summed) right after the partition.
    pub(crate) cross_at_partition: usize,
    /// Domain and local index of each particle (scene order).
    pub(crate) dom: Vec<u8>,
    pub local: Vec<u32>,
    pub domains: Vec<Mutex<Domain<D>>>,
    /// Per domain, the halo of the two step parities: `2 D` values per halo particle
    /// (position, then the velocity array's value).
    pub(crate) halo: Vec<[RwLock<Vec<f64>>; 2]>,
    /// Per domain and step parity: the list must be rebuilt before the next step.
    pub stop: Vec<[AtomicBool; 2]>,
    /// The step whose state the domains hold (`None`: not loaded yet, or the engine's state
    /// was changed outside the domains).
    pub(crate) holds_step: Option<u64>,
    /// Whether the engine's arrays hold only the positions of that step (the rest is in the
    /// domains): between the regions of one run.
    pub partial: bool,
    /// The step whose list check is done already (by the domains' last step or the team's
    /// build): the next region skips the engine's `update_list` and keeps the domains' own
    /// bounds, so where regions end does not move the exact displacement tests (which decide
    /// the rebuilds caused by a periodic wrap).
    pub(crate) checked_for: Option<u64>,
}

/// A partition is remade when the cross entries exceed twice those at the partition plus this.
pub(super) const REPARTITION_SLACK: usize = 16;

/// A partition is remade at the latest this many list builds after it was made.
pub(super) const REPARTITION_EVERY: u64 = 64;

/// Locks a mutex, ignoring poisoning (a member that panicked poisons the team, which re-raises
/// the panic on the caller; the data is not used after that).
pub(super) fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(std::sync::PoisonError::into_inner)
}

fn read<T>(m: &RwLock<T>) -> std::sync::RwLockReadGuard<'_, T> {
    m.read().unwrap_or_else(std::sync::PoisonError::into_inner)
}

fn write<T>(m: &RwLock<T>) -> std::sync::RwLockWriteGuard<'_, T> {
    m.write().unwrap_or_else(std::sync::PoisonError::into_inner)
}

fn get<T>(m: &mut Mutex<T>) -> &mut T {
    m.get_mut()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
}

/// The engine's arrays a decomposition reads and writes (scene order, axis-major).
pub(super) struct EngineArrays<'a> {
    pub r: &'a mut [Vec<f64>; 6],
    pub(crate) acc: &'a mut [f64],
    pub(crate) wall_contact: &'a mut [u8],
    pub radius: &'a [f64],
    pub(crate) wall_kr: &'a [f64],
}

impl<const D: usize> Decomposition<D> {
    /// Cuts the particles at positions `x` (axis-major, those of the list build) across the
    /// longest axis of `size` at the median (ties broken by the index) into 2 domains of
    /// `n / 2` and `n - n / 2` particles, each in ascending scene order (lists split by
    /// [`Self::split_lists`], state loaded by [`Self::load`]).
    pub(super) fn new(build: u64, size: [f64; D], x: &[f64]) -> Self {
        let n = x.len() / D;
        let axis = (0..D).fold(0, |a, k| if size[k] > size[a] { k } else { a });
        let xa = &x[axis * n..(axis + 1) * n];
        let mut order: Vec<u32> = (0..n as u32).collect();
        let half = n / 2;
        let mut dom = vec![1u8; n];
        if half > 0 {
            order.select_nth_unstable_by(half - 1, |&a, &b| {
                xa[a as usize].total_cmp(&xa[b as usize]).then(a.cmp(&b))
            });
            for &i in &order[..half] {
                dom[i as usize] = 0;
            }
        }
        let mut local = vec![0u32; n];
        let mut domains: Vec<Domain<D>> = (0..DOMAINS).map(|_| Domain::default()).collect();
        for i in 0..n {
            let d = dom[i] as usize;
            local[i] = domains[d].ids.len() as u32;
            domains[d].ids.push(i as u32);
        }
        for (d, dm) in domains.iter_mut().enumerate() {
            let m = dm.ids.len();
            dm.books_cross = d == 0;
            for q in &mut dm.r {
                *q = vec![0.0; D * m];
            }
            dm.acc = vec![0.0; D * m];
            dm.wall_contact = vec![0; D * m];
            dm.radius = vec![0.0; m];
            dm.wall_kr = vec![0.0; m];
            dm.built_at = vec![0.0; D * m];
        }
        Self {
            built_for: AtomicU64::new(0),
            partitioned_at: build,
            cross_at_partition: 0,
            dom,
            local,
            domains: domains.into_iter().map(Mutex::new).collect(),
            halo: (0..DOMAINS).map(|_| Default::default()).collect(),
            stop: (0..DOMAINS).map(|_| Default::default()).collect(),
            holds_step: None,
            partial: false,
            checked_for: None,
        }
    }

    /// Whether the partition is to be remade at list build `build` (see the type's doc).
    pub(super) fn wants_new_partition(&self, build: u64) -> bool {
        let cross: usize = self.domains.iter().map(|d| lock(d).cross_own.len()).sum();
        build >= self.partitioned_at + REPARTITION_EVERY
            || cross > 2 * self.cross_at_partition + REPARTITION_SLACK
    }

    /// Splits the half list of `list` (scene indices) into each domain's inner list and
    /// cross list, numbers the ghosts, and takes the positions of the build and the radii
    /// ([`Self::split_domain`] for every domain).
    pub(super) fn split_lists(&mut self, list: &NeighbourList<D>, radius: &[f64]) {
        for d in 0..DOMAINS {
            self.split_domain(d, list, radius);
        }
        if list.builds == self.partitioned_at {
            self.cross_at_partition = self
                .domains
                .iter_mut()
                .map(|d| get(d).cross_own.len())
                .sum();
        }
        self.built_for.store(list.builds, Ordering::Relaxed);
    }

    /// The list build whose entries the domains' lists hold (`NeighbourList::builds`; 0: none).
    pub(super) fn built_for(&self) -> u64 {
        self.built_for.load(Ordering::Relaxed)
    }

    /// Domain `d`'s part of [`Self::split_lists`]: its inner half list (local indices, in list
    /// order), its cross entries sorted by own particle, ghost and entry, its ghosts (the
    /// other domain's particles in cross pairs, by local index), the own particles it publishes
    /// (those in cross pairs, ascending: the other domain's ghost order), and its halo buffers.
    /// Writes only domain `d`, so different threads can split the domains at once.
    pub(super) fn split_domain(&self, d: usize, list: &NeighbourList<D>, radius: &[f64]) {
        let (start, partner, flags) = (&list.start, &list.partner, &list.flags);
        let built_at = list.built_at();
        let n = start.len() - 1;
        let (dom, local) = (&self.dom, &self.local);
        let mut dm = lock(&self.domains[d]);
        let dm = &mut *dm;
        let m = dm.ids.len();
        // Inner entries are written at once (rows come ascending); cross entries are
        // collected as (own local, other's local, entry, other's scene index) and sorted.
        let mut cross: Vec<(u32, u32, u32, u32)> = Vec::new();
        dm.start.clear();
        dm.start.resize(m + 1, 0);
        dm.partner.clear();
        dm.inner_src.clear();
        dm.flags.clear();
        dm.rows.clear();
        let d8 = d as u8;
        for i in 0..n {
            let row = start[i] as usize..start[i + 1] as usize;
            if dom[i] == d8 {
                let li = local[i] as usize;
                for q in row {
                    let j = partner[q] as usize;
                    if dom[j] == d8 {
                        dm.partner.push(local[j]);
                        dm.inner_src.push(q as u32);
                        dm.flags.push(flags[q]);
                    } else {
                        cross.push((local[i], local[j], q as u32, j as u32));
                    }
                }
                dm.start[li + 1] = dm.partner.len() as u32;
                if dm.start[li + 1] > dm.start[li] {
                    dm.rows.push(li as u32);
                }
            } else {
                for q in row {
                    let j = partner[q] as usize;
                    if dom[j] == d8 {
                        cross.push((local[j], local[i], q as u32, i as u32));
                    }
                }
            }
        }
        cross.sort_unstable();
        // Ghost numbers: the other domain's locals, ascending.
        let mut ghosts: Vec<(u32, u32)> = cross.iter().map(|e| (e.1, e.3)).collect();
        ghosts.sort_unstable();
        ghosts.dedup();
        dm.ghost_radius.clear();
        dm.ghost_radius
            .extend(ghosts.iter().map(|&(_, j)| radius[j as usize]));
        dm.halo_out.clear();
        dm.halo_out.extend(cross.iter().map(|e| e.0));
        dm.halo_out.dedup();
        dm.cross_own.clear();
        dm.cross_own.extend(cross.iter().map(|e| e.0));
        dm.cross_ghost.clear();
        dm.cross_ghost.extend(cross.iter().map(|e| {
            ghosts
                .binary_search_by_key(&e.1, |g| g.0)
                .expect("ghost listed") as u32
        }));
        dm.cross_src.clear();
        dm.cross_src.extend(cross.iter().map(|e| e.2));
        dm.cross_flags.clear();
        dm.cross_flags
            .extend(cross.iter().map(|e| flags[e.2 as usize]));
        gather::<D, _>(&dm.ids, built_at, &mut dm.built_at, n);
        let len = 2 * D * dm.halo_out.len();
        for b in &self.halo[d] {
            let mut b = write(b);
            b.clear();
            b.resize(len, 0.0);
        }
    }

    /// Copies the engine's state into the domains (Gear derivatives, forces, wall contacts,
    /// radii) and marks them as holding step `step`.
    pub(super) fn load(&mut self, e: &EngineArrays<'_>, acc_is_start: bool, step: u64) {
        let n = e.radius.len();
        for dm in &mut self.domains {
            let dm = get(dm);
            for (src, dst) in e.r.iter().zip(&mut dm.r) {
                gather::<D, _>(&dm.ids, src, dst, n);
            }
            gather::<D, _>(&dm.ids, e.acc, &mut dm.acc, n);
            gather::<D, _>(&dm.ids, e.wall_contact, &mut dm.wall_contact, n);
            gather::<1, _>(&dm.ids, e.radius, &mut dm.radius, n);
            gather::<1, _>(&dm.ids, e.wall_kr, &mut dm.wall_kr, n);
            dm.acc_is_start = acc_is_start;
        }
        self.holds_step = Some(step);
    }

    /// Prepares a region starting at step `step`: the list check's bound and count (the
    /// engine's, unless `own_checks`: then each domain keeps its own, see
    /// [`Self::checked_for`]), empty books, and the halo of the step's parity.
    pub(super) fn begin(&mut self, bound: f64, since_check: u32, step: u64, own_checks: bool) {
        let parity = (step % 2) as usize;
        for (d, dm) in self.domains.iter_mut().enumerate() {
            let dm = get(dm);
            if !own_checks {
                dm.bound = bound;
                dm.since_check = since_check;
            }
            dm.books = Books::default();
            dm.step_books.clear();
            dm.publish(&mut write(&self.halo[d][parity]));
        }
    }

    /// Copies the domains' state back into the engine's arrays: all of it (`full`), or only
    /// the positions (`r[0]`, what a list build reads); and the list flags where `flags` is
    /// given (the list of the domains' build; cross pairs from the booking domain).
    pub(super) fn store(&mut self, e: &mut EngineArrays<'_>, flags: Option<&mut [u8]>, full: bool) {
        let mut flags = flags;
        let n = e.radius.len();
        for dm in &mut self.domains {
            let dm = get(dm);
            let arrays = if full { 6 } else { 1 };
            for (src, dst) in dm.r.iter().zip(e.r.iter_mut()).take(arrays) {
                dm.scatter(src, dst, n);
            }
            if full {
                dm.scatter(&dm.acc, e.acc, n);
                dm.scatter(&dm.wall_contact, e.wall_contact, n);
            }
            if let Some(flags) = flags.as_deref_mut() {
                dm.scatter_flags(flags);
            }
        }
    }

    /// The books of every domain in order (counts and largest overlap; per-step sums), and
    /// the largest displacement bound and step count since the exact test.
    pub(super) fn books(&mut self) -> (RegionBooks, f64, u32) {
        let (mut bound, mut since) = (0.0f64, 0u32);
        let mut books = Vec::with_capacity(DOMAINS);
        for dm in &mut self.domains {
            let dm = get(dm);
            books.push((dm.books, std::mem::take(&mut dm.step_books)));
            bound = bound.max(dm.bound);
            since = since.max(dm.since_check);
        }
        (books, bound, since)
    }

    #[cfg(test)]
    /// Test aid: whether both copies of every cross pair hold the same flags (they must: the
    /// two domains take the same decisions on exactly antisymmetric numbers).
    pub(super) fn cross_flags_agree(&mut self) -> bool {
        let mut copies = self.domains.iter_mut().map(|dm| {
            let dm = get(dm);
            let mut v: Vec<(u32, u8)> = dm
                .cross_src
                .iter()
                .copied()
                .zip(dm.cross_flags.iter().copied())
                .collect();
            v.sort_unstable();
            v
        });
        copies.next() == copies.next()
    }

    /// Runs the steps of one member of a team of `members` (domains `slot`, `slot + members`,
    /// ...) from global step `first` until `target`; where some domain's check asks for a list
    /// build, the team builds it ([`Self::build_in_team`]) and goes on unless a new partition
    /// is due. `wait` is the team's barrier. Returns (the same on every member) the steps
    /// taken and how the region ended.
    pub(super) fn run_member<const WET: bool>(
        &self,
        c: &StepConstants<D>,
        walls_at: &(dyn Fn(u64) -> [WallAxis; D] + Sync),
        build: &TeamBuild<'_, D>,
        slot: usize,
        members: usize,
        first: u64,
        target: u64,
        wait: &dyn Fn(),
    ) -> (u64, RegionEnd) {
        let mine: Vec<usize> = (slot..DOMAINS).step_by(members.max(1)).collect();
        let mut s = first;
        loop {
            let mut guards: Vec<_> = mine.iter().map(|&d| lock(&self.domains[d])).collect();
            let rebuild = loop {
                let parity = (s % 2) as usize;
                let walls = walls_at(s + 1);
                let flush = s.is_multiple_of(GEAR_FLUSH_EVERY);
                for (g, &d) in guards.iter_mut().zip(&mine) {
                    let other = 1 - d;
                    let ghosts = read(&self.halo[other][parity]);
                    let mut next = write(&self.halo[d][1 - parity]);
                    let stop = g.step::<WET>(c, &walls, flush, &ghosts, &mut next);
                    self.stop[d][1 - parity].store(stop, Ordering::Relaxed);
                }
                wait();
                s += 1;
                let rebuild =
                    (0..DOMAINS).any(|d| self.stop[d][1 - parity].load(Ordering::Relaxed));
                if rebuild || s >= target {
                    break rebuild;
                }
            };
            drop(guards);
            if s >= target {
                let end = if rebuild {
                    RegionEnd::Rebuild
                } else {
                    RegionEnd::Target
                };
                return (s - first, end);
            }
            if !self.build_in_team(build, &mine, slot, members, s, wait) {
                return (s - first, RegionEnd::Repartition);
            }
        }
    }

    /// The list build of step `step` by the team (every member calls it with its domains
    /// `mine`): member 0 writes the positions and flags back and bins the particles, the
    /// members scan the two parts of the rows, member 0 joins them and decides on the
    /// partition; unless a new one is due, each member splits the new list for its domains,
    /// resets their list checks and publishes their halo. Returns whether the region goes on.
    fn build_in_team(
        &self,
        b: &TeamBuild<'_, D>,
        mine: &[usize],
        slot: usize,
        members: usize,
        step: u64,
        wait: &dyn Fn(),
    ) -> bool {
        wait();
        if slot == 0 {
            let mut list = write(&b.list);
            let mut x = lock(&b.x);
            self.store_positions_and_flags(&mut x, &mut list.flags);
            list.begin_build(&x, b.radius);
            let [lo, hi] = list.take_scans();
            *lock(&b.scans[0]) = lo;
            *lock(&b.scans[1]) = hi;
        }
        wait();
        {
            let list = read(&b.list);
            for part in (slot..2).step_by(members.max(1)) {
                list.scan_part(b.radius, part, &mut lock(&b.scans[part]));
            }
        }
        wait();
        if slot == 0 {
            let mut list = write(&b.list);
            let parts = [
                std::mem::take(&mut *lock(&b.scans[0])),
                std::mem::take(&mut *lock(&b.scans[1])),
            ];
            list.finish_build(parts);
            let again = self.wants_new_partition(list.builds);
            b.repartition.store(again, Ordering::Relaxed);
            if !again {
                self.built_for.store(list.builds, Ordering::Relaxed);
            }
        }
        wait();
        if b.repartition.load(Ordering::Relaxed) {
            return false;
        }
        {
            let list = read(&b.list);
            let parity = (step % 2) as usize;
            for &d in mine {
                self.split_domain(d, &list, b.radius);
                let mut dm = lock(&self.domains[d]);
                dm.bound = 0.0;
                dm.since_check = 0;
                dm.publish(&mut write(&self.halo[d][parity]));
            }
        }
        wait();
        true
    }

    /// Writes the domains' positions into `x` (scene order, axis-major) and the flags of
    /// their lists into the engine list's `flags` (cross pairs from the booking domain).
    fn store_positions_and_flags(&self, x: &mut [f64], flags: &mut [u8]) {
        let n = x.len() / D;
        for dm in &self.domains {
            let dm = lock(dm);
            dm.scatter(&dm.r[0], x, n);
            dm.scatter_flags(flags);
        }
    }
}

/// Reads the scene-order axis-major array `src` (`n` particles) into the local array `dst` of
/// the particles `ids` (the inverse of [`Domain::scatter`]).
fn gather<const D: usize, T: Copy>(ids: &[u32], src: &[T], dst: &mut [T], n: usize) {
    let m = ids.len();
    for k in 0..D {
        let src = &src[k * n..(k + 1) * n];
        for (o, &i) in dst[k * m..(k + 1) * m].iter_mut().zip(ids) {
            *o = src[i as usize];
        }
    }
}

impl<const D: usize> Domain<D> {
    /// Writes the local axis-major array `src` into the scene-order array `dst` (`n`
    /// particles).
    fn scatter<T: Copy>(&self, src: &[T], dst: &mut [T], n: usize) {
        let m = self.ids.len();
        for k in 0..D {
            let dst = &mut dst[k * n..(k + 1) * n];
            for (&v, &i) in src[k * m..(k + 1) * m].iter().zip(&self.ids) {
                dst[i as usize] = v;
            }
        }
    }

    /// Writes the flags of the inner entries, and of the cross entries if this domain books
    /// them, into the engine list's `flags`.
    fn scatter_flags(&self, flags: &mut [u8]) {
        for (&f, &q) in self.flags.iter().zip(&self.inner_src) {
            flags[q as usize] = f;
        }
        if self.books_cross {
            for (&f, &q) in self.cross_flags.iter().zip(&self.cross_src) {
                flags[q as usize] = f;
            }
        }
    }

    /// Writes the halo (position, then velocity array value, per published particle).
    fn publish(&self, out: &mut [f64]) {
        let m = self.ids.len();
        for (h, &li) in out.chunks_exact_mut(2 * D).zip(&self.halo_out) {
            let li = li as usize;
            for k in 0..D {
                h[k] = self.r[0][k * m + li];
                h[D + k] = self.r[1][k * m + li];
            }
        }
    }

    /// One Gear step of this domain (see the module doc); `ghosts` holds the other domain's
    /// halo of this step, `next` receives this domain's halo of the next. Returns whether the
    /// neighbour list must be rebuilt before the next step.
    fn step<const WET: bool>(
        &mut self,
        c: &StepConstants<D>,
        walls: &[WallAxis; D],
        flush: bool,
        ghosts: &[f64],
        next: &mut [f64],
    ) -> bool {
        let m = self.ids.len();
        if !self.acc_is_start {
            for k in 0..D {
                self.acc[k * m..(k + 1) * m].fill(c.init[k]);
            }
        }
        self.acc_is_start = true;
        let mut sums = self.pair_forces::<WET>(&c.pair, ghosts);
        for k in 0..D {
            if c.pair.periodic[k] {
                continue;
            }
            let a = k * m..(k + 1) * m;
            let mut part = Books::default();
            wall_forces(
                &walls[k],
                &self.r[0][a.clone()],
                &self.r[1][a.clone()],
                &self.radius,
                &self.wall_kr,
                &mut self.wall_contact[a.clone()],
                &mut self.acc[a],
                &mut part,
            );
            sums[0] += part.dissipated;
            sums[2] += part.work;
            self.books.add_counts(&part);
        }
        self.step_books.push(sums);
        if let Some(inv_m) = c.inv_mass {
            for e in &mut self.acc {
                *e *= inv_m;
            }
        }
        let p = &c.pair;
        let moved = gear_correct_predict_axes(
            &mut self.r,
            &mut self.acc,
            c.init,
            0.5 * c.dt * c.dt,
            &c.gear,
            std::array::from_fn(|k| p.periodic[k].then_some(p.size[k])),
            flush,
        );
        self.publish(next);
        self.bound += norm(moved);
        let (x, built_at) = (&self.r[0], &self.built_at);
        needs_rebuild::<D>(
            &mut self.bound,
            &mut self.since_check,
            c.half_skin,
            x,
            built_at,
        )
    }

    /// The inner pairs and the cross pairs of this domain ([`pair_forces_serial`],
    /// [`cross_forces`]): their forces added to `acc`, the counts and largest overlap booked
    /// (the cross pairs' only where this domain books them); returns the step's sums
    /// (dissipation, bridge ledger, drive work).
    fn pair_forces<const WET: bool>(&mut self, pc: &PairConstants<D>, ghosts: &[f64]) -> [f64; 3] {
        let pb = pair_forces_serial::<D, WET>(
            pc,
            &self.r[0],
            &self.r[1],
            &mut self.acc,
            &self.radius,
            &self.start,
            &self.rows,
            &self.partner,
            &mut self.flags,
        );
        let mut sums = [pb.dissipated, pb.bridge_ledger, 0.0];
        self.books.add_counts(&pb);
        let cb = cross_forces::<D, WET>(
            pc,
            &self.r[0],
            &self.r[1],
            &mut self.acc,
            &self.radius,
            ghosts,
            &self.ghost_radius,
            &self.cross_own,
            &self.cross_ghost,
            &mut self.cross_flags,
        );
        if self.books_cross {
            sums[0] += cb.dissipated;
            sums[1] += cb.bridge_ledger;
            self.books.add_counts(&cb);
        }
        sums
    }
}
