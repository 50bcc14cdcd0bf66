//! Stepping the time-driven engine: the neighbour-list update, one step (Gear or velocity
//! Verlet) on the serial path, split over rayon's threads, or on the spatial domains
//! (`domains.rs`), and the per-particle phase that follows the pair forces (walls, gathering
//! the pair forces in a fixed order, the integrator).

use super::*;

impl<const D: usize, const GRAV: bool, const WET: bool, B: BodyForce<D>>
    TimeEngine<D, GRAV, WET, B>
{
    /// Wraps periodic coordinates of `r[0]` into `[0, L)` (Verlet, and the first Gear
    /// prediction; afterwards the Gear loop wraps its own output).
    fn wrap(&mut self) {
        let n = self.n;
        for k in 0..D {
            if !self.p.periodic[k] {
                continue;
            }
            let l = self.p.size[k];
            for x in &mut self.r[0][k * n..(k + 1) * n] {
                if *x < 0.0 {
                    *x += l;
                } else if *x >= l {
                    *x -= l;
                }
            }
        }
    }

    /// Keeps the Verlet list valid: rebuilds it when some particle has moved more than
    /// `skin / 2` since the last build. The exact test (a pass over all positions,
    /// [`NeighbourList::needs_rebuild`]) runs only when the bound `moved_bound` reaches
    /// `skin / 2` (less a relative margin of `1e-6` for its round-off) or after
    /// [`EXACT_CHECK_EVERY`] steps; otherwise no particle can have moved that far (each
    /// particle's displacement is at most the sum of the per-step largest moves), so the
    /// decision is the one the exact test would take. After an exact test the bound restarts
    /// from the exact largest displacement.
    fn update_list(&mut self) {
        self.since_check += 1;
        let half_skin = 0.5 * self.list.skin();
        if self.moved_bound < half_skin * (1.0 - 1e-6) && self.since_check < EXACT_CHECK_EVERY {
            return;
        }
        self.since_check = 0;
        let worst = self.list.max_displacement_sq(&self.r[0]);
        if worst > half_skin * half_skin {
            self.list.build(&self.r[0], &self.radius);
            self.moved_bound = 0.0;
        } else {
            self.moved_bound = worst.sqrt();
        }
    }

    /// One time step of the scene's integrator.
    pub fn step(&mut self) {
        if self.predicted && self.uses_domains() {
            let target = self.steps + 1;
            self.domain_region(target);
            return;
        }
        self.step_alone();
    }

    /// One step of the serial (or rayon-split) path.
    fn step_alone(&mut self) {
        let dt = self.p.dt;
        let t1 = (self.steps + 1) as f64 * dt;
        match self.p.integrator {
            IntegratorKind::Gear5 => {
                if !self.predicted {
                    gear_predict(&mut self.r);
                    self.wrap();
                    // The predictor's moves are not tracked: force the exact test.
                    self.moved_bound = f64::INFINITY;
                }
                self.update_list();
                // Forces, then the corrector of this step, the predictor of the next, the wrap
                // of both positions and the largest move per axis, in one pass per chunk.
                let moved = self.forces_then(t1, 1.0 / dt, dt, Then::Gear);
                let mut moved2 = 0.0;
                for m in moved {
                    moved2 += m * m;
                }
                self.moved_bound += moved2.sqrt();
                self.predicted = true;
            }
            IntegratorKind::Verlet => {
                let moved = self.verlet_drift_wrap(dt);
                let mut moved2 = 0.0;
                for m in moved {
                    moved2 += m * m;
                }
                self.moved_bound += moved2.sqrt();
                self.update_list();
                self.forces_then(t1, 1.0, dt, Then::VerletKick);
            }
        }
        self.steps += 1;
    }

    /// Runs until the time is the multiple of `dt` nearest to `t_end`. Always returns true (the
    /// time engine has no event cap). Runs on the thread pool `sim::threads` chooses.
    pub fn run_until(&mut self, t_end: f64) -> bool {
        let target = (t_end / self.p.dt).round().max(0.0) as u64;
        if self.steps >= target {
            return true;
        }
        crate::sim::threads::install(|| {
            while self.steps < target {
                if self.predicted && self.uses_domains() {
                    self.domain_region(target);
                } else {
                    self.step_alone();
                }
            }
        });
        true
    }

    /// Chooses which Gear steps run on the spatial domains ([`DomainMode`]; tests and benches).
    pub fn set_domain_mode(&mut self, mode: DomainMode) {
        self.domain_mode = mode;
    }

    /// Gear steps so far that ran on the domains with a team of more than one thread (the
    /// others ran on one thread, which gives the same numbers).
    pub fn team_steps(&self) -> u64 {
        self.team_steps
    }

    /// Whether the Gear steps run on the spatial domains: Gear, no body force, and
    /// [`DOMAIN_MIN_PARTICLES`] particles or more (or as [`Self::set_domain_mode`] says). The
    /// number of threads plays no part, so the numbers do not depend on it.
    pub(super) fn uses_domains(&self) -> bool {
        self.p.integrator == IntegratorKind::Gear5
            && !B::ACTIVE
            && self.n >= DOMAINS
            && match self.domain_mode {
                DomainMode::Auto => self.n >= DOMAIN_MIN_PARTICLES,
                DomainMode::Always => true,
                DomainMode::Never => false,
            }
    }

    /// The arrays the domains copy from and to, and the list flags.
    fn domain_arrays(&mut self) -> (EngineArrays<'_>, &mut [u8]) {
        (
            EngineArrays {
                r: &mut self.r,
                acc: &mut self.acc,
                wall_contact: &mut self.wall_contact,
                radius: &self.radius,
                wall_kr: &self.wall_kr,
            },
            &mut self.list.flags,
        )
    }

    /// Runs Gear steps on the spatial domains (`domains.rs`) until `target` or until a list
    /// build calls for a new partition: the list check of the first step, the decomposition
    /// (kept from the last region, or made from the positions of the current build), the
    /// state copied into the domains, the steps on a team of up to [`DOMAINS`] threads of the
    /// current pool (or on the calling thread alone; the team rebuilds the list itself where
    /// the check asks for it), the state and the books copied back (the books step by step,
    /// domains in order, as one sum per step).
    fn domain_region(&mut self, target: u64) {
        let first = self.steps;
        // The last region's domains did the list check of this step already (counting it
        // again would move the exact tests with the region ends).
        let checked = matches!(&self.domains.0, Some(d)
            if d.holds_step == Some(first) && d.checked_for == Some(first));
        if !checked {
            self.update_list();
        }
        let builds = self.list.builds;
        let kept = match self.domains.0.take() {
            Some(d)
                if d.holds_step == Some(first)
                    && (d.built_for() == builds || !d.wants_new_partition(builds)) =>
            {
                Some(d)
            }
            Some(mut old) => {
                // The engine's arrays must hold the whole state before a new partition (the
                // flags came back at the end of the last region; the list is new since).
                if old.partial {
                    let (mut arrays, _) = self.domain_arrays();
                    old.store(&mut arrays, None, true);
                }
                None
            }
            None => None,
        };
        let own_checks = checked && kept.is_some();
        let mut dec = match kept {
            Some(d) => d,
            None => {
                self.partitions += 1;
                let mut d = Box::new(Decomposition::new(
                    builds,
                    self.p.size,
                    self.list.built_at(),
                ));
                let acc_is_start = self.acc_is_start;
                let (arrays, _) = self.domain_arrays();
                d.load(&arrays, acc_is_start, first);
                d
            }
        };
        // A new decomposition has no lists yet; a kept one re-splits after a build.
        if dec.built_for() != builds {
            dec.split_lists(&self.list, &self.radius);
        }
        dec.begin(self.moved_bound, self.since_check, first, own_checks);
        let init = self.force_start();
        let p = &self.p;
        let dt = p.dt;
        let c = StepConstants {
            periodic: p.periodic,
            size: p.size,
            stiffness: p.stiffness,
            damping: p.damping,
            bridge_force: p.bridge_force,
            s_crit: p.s_crit,
            dt,
            inv_mass: (p.mass != 1.0).then(|| 1.0 / p.mass),
            init,
            gear: p.gear,
            half_skin: 0.5 * self.list.skin(),
        };
        let walls_at = |s: u64| wall_axes(p, s as f64 * dt, 1.0 / dt, dt);
        let flush_at = |s: u64| s.is_multiple_of(GEAR_FLUSH_EVERY);
        self.regions += 1;
        let dec_ref: &Decomposition<D> = &dec;
        // The team rebuilds the list itself (its threads stay awake) and goes on.
        let build = TeamBuild::new(&mut self.list, &mut self.r[0], &self.radius);
        let member = |slot: usize, members: usize, wait: &dyn Fn()| {
            dec_ref.run_member::<WET>(
                &c, &walls_at, &flush_at, &build, slot, members, first, target, wait,
            )
        };
        let ((done, end), members) = if rayon::current_num_threads() > 1 {
            let out = crate::sim::time_driven::team::run_with_door(DOMAINS, self.team_door, |m| {
                (member(m.slot, m.members, &|| m.wait()), m.members)
            });
            out[0]
        } else {
            crate::sim::time_driven::team::solo(|m| (member(0, 1, &|| m.wait()), 1))
        };
        drop(build);
        self.acc_is_start = true;
        self.steps += done;
        if members > 1 {
            self.team_steps += done;
        }
        // Between regions of one run only the positions (for the list build) and the flags
        // come back; at the end of the run everything does.
        let full = end == RegionEnd::Target || self.steps >= target;
        // After a build for a new partition the domains' lists are those of the build before:
        // their flags are in the list already.
        let lists_current = dec.built_for() == self.list.builds;
        let (mut arrays, flags) = self.domain_arrays();
        dec.store(&mut arrays, lists_current.then_some(flags), full);
        dec.partial = !full;
        dec.holds_step = Some(self.steps);
        dec.checked_for = (end != RegionEnd::Rebuild).then_some(self.steps);
        let (books, bound, since) = dec.books();
        self.domains.0 = Some(dec);
        for s in 0..done as usize {
            for (_, steps) in &books {
                let [diss, ledger, work] = steps[s];
                self.dissipated_damping += diss;
                self.dissipated_bridges += ledger;
                self.work_by_drive += work;
            }
        }
        for (b, _) in &books {
            self.max_overlap = self.max_overlap.max(b.max_overlap);
            self.counts.pair_collisions += b.pair_onsets;
            self.counts.wall_collisions += b.wall_onsets;
            self.counts.bridge_formations += b.formations;
            self.counts.bridge_ruptures += b.ruptures;
        }
        match end {
            // The check of the next step found a particle beyond half the skin: the next
            // `update_list` runs the exact test (and rebuilds).
            RegionEnd::Rebuild => self.moved_bound = f64::INFINITY,
            // The team built the list (as `update_list` would have); the next region makes
            // the new partition.
            RegionEnd::Repartition => {
                self.moved_bound = 0.0;
                self.since_check = 0;
            }
            RegionEnd::Target => {
                self.moved_bound = bound;
                self.since_check = since;
            }
        }
    }

    /// Whether the loops of a step are split over threads: on a pool of more than one thread
    /// and from `parallel_min` particles on ([`TimeEngine::set_parallel_min_particles`]);
    /// otherwise the serial path runs on the calling thread, without the pool. The numbers are
    /// the same either way.
    fn parallel(&self) -> bool {
        self.n >= self.parallel_min && rayon::current_num_threads() > 1
    }

    /// The force every coordinate starts from: the weight `-m g` on the last axis (with
    /// gravity), 0 elsewhere.
    fn force_start(&self) -> [f64; D] {
        let mut start = [0.0; D];
        if GRAV {
            start[D - 1] = -self.p.mass * self.p.gravity;
        }
        start
    }

    /// Velocity Verlet's first half on every coordinate (`verlet_drift`), with the wrap of the
    /// periodic axes; returns the largest move per axis.
    fn verlet_drift_wrap(&mut self, dt: f64) -> [f64; D] {
        let n = self.n;
        let min_len = if self.parallel() { 1 } else { usize::MAX };
        let (periodic, size) = (self.p.periodic, self.p.size);
        let start = self.force_start();
        self.acc_is_start = true;
        let [x, v, ..] = &mut self.r;
        let drift = |e0: usize, x: &mut [f64], v: &mut [f64], acc: &mut [f64]| {
            let mut moved = [0.0; D];
            for_each_axis_segment(n, e0, x.len(), |k, o, m| {
                let (x, v, acc) = (&mut x[o..o + m], &mut v[o..o + m], &mut acc[o..o + m]);
                let step_move = verlet_drift(x, v, acc, start[k], dt);
                moved[k] = max_ignoring_nan(moved[k], step_move);
                if periodic[k] {
                    wrap_slice(x, size[k]);
                }
            });
            moved
        };
        (
            x.par_chunks_mut(PARTICLE_CHUNK),
            v.par_chunks_mut(PARTICLE_CHUNK),
            self.acc.par_chunks_mut(PARTICLE_CHUNK),
        )
            .into_par_iter()
            .enumerate()
            .with_min_len(min_len)
            .map(|(c, (x, v, acc))| drift(c * PARTICLE_CHUNK, x, v, acc))
            .reduce(
                || [0.0; D],
                |a, b| std::array::from_fn(|k| max_ignoring_nan(a[k], b[k])),
            )
    }

    /// Accelerations at positions `r[0]` and velocities `r[1] * vs` at time `t`, then `then`
    /// (the Gear corrector-predictor or Verlet's second half); books dissipation, drive work,
    /// contact onsets and bridge events with weight `dt` (0: a re-evaluation that is not a
    /// step). Returns the largest move per axis of the Gear update (zeros otherwise).
    ///
    /// Two parallel phases, each over fixed chunks whose results are combined in chunk order,
    /// so the numbers do not depend on the number of threads:
    ///
    /// 1. the pair forces of every Verlet-list entry (each pair once), into a buffer, with the
    ///    contact and bridge flags ([`pair_chunk`], chunks of [`ENTRY_CHUNK`] entries);
    /// 2. per chunk of [`PARTICLE_CHUNK`] coordinates: the weight, the pair forces gathered in
    ///    the order the half list's rows visit them (the partners' rows, ascending, then the
    ///    particle's own row), the walls, the body force, `1/m`, then `then`
    ///    ([`particle_chunk`]).
    ///
    /// The accelerations are the same bits as a single loop that scatters each pair force to
    /// both partners; the booked sums (dissipation, drive work, bridge energy) are summed per
    /// chunk, so they differ from a single running sum by round-off.
    pub(super) fn forces_then(&mut self, t: f64, vs: f64, dt: f64, then: Then) -> [f64; D] {
        if self.parallel() {
            self.forces_then_parallel(t, vs, dt, then)
        } else {
            self.forces_then_serial(t, vs, dt, then)
        }
    }

    /// [`Self::forces_then`] on the calling thread, as one loop per kind of force: the pair
    /// loop scatters each pair force to both partners (rows ascending, so every particle
    /// receives its partners' forces in the order the parallel gather adds them), then walls,
    /// body force, `1/m` and `then` per axis. The booked sums are taken per chunk as in the
    /// parallel path, so both paths give the same bits (`crates/core/tests/time_driven_pins.rs` runs each
    /// pin on one thread, this path, and on two, the parallel one); this one does less work
    /// (no per-entry force buffer, no gather).
    fn forces_then_serial(&mut self, t: f64, vs: f64, dt: f64, then: Then) -> [f64; D] {
        let n = self.n;
        let init = self.force_start();
        let p = &self.p;
        let f = &mut self.acc;
        if !self.acc_is_start {
            for k in 0..D {
                f[k * n..(k + 1) * n].fill(init[k]);
            }
        }
        // The integrator pass below leaves the start values for the next evaluation.
        self.acc_is_start = then == Then::Gear;
        let pc = PairConstants {
            periodic: p.periodic,
            size: p.size,
            stiffness: p.stiffness,
            damping: p.damping,
            bridge_force: p.bridge_force,
            s_crit: p.s_crit,
            vs,
            dt,
        };
        let list = &mut self.list;
        let pb = pair_forces_serial::<D, WET>(
            &pc,
            &self.r[0],
            &self.r[1],
            f,
            &self.radius,
            &list.start,
            &list.rows,
            &list.partner,
            &mut list.flags,
        );
        self.counts.pair_collisions += pb.onsets;
        self.counts.bridge_formations += pb.formations;
        self.counts.bridge_ruptures += pb.ruptures;
        self.dissipated_bridges += pb.bridge_ledger;
        let mut diss = pb.dissipated;
        let mut max_ov = self.max_overlap.max(pb.max_overlap);
        // Walls per chunk of coordinates, the chunks of the parallel path, each chunk's
        // dissipation and work summed on its own and added in order (a chunk that booked
        // nothing adds +0 and changes nothing).
        let mut work = 0.0;
        let walls = wall_axes(p, t, vs, dt);
        let x = &self.r[0];
        let v = &self.r[1];
        if p.periodic.iter().any(|&periodic| !periodic) {
            for e0 in (0..D * n).step_by(PARTICLE_CHUNK) {
                let mut part = WallBooks::default();
                for_each_axis_segment(n, e0, PARTICLE_CHUNK.min(D * n - e0), |k, o, m| {
                    if p.periodic[k] {
                        return;
                    }
                    let (e, i) = (e0 + o, e0 + o - k * n);
                    wall_forces(
                        &walls[k],
                        &x[e..e + m],
                        &v[e..e + m],
                        &self.radius[i..i + m],
                        &self.wall_kr[i..i + m],
                        &mut self.wall_contact[e..e + m],
                        &mut f[e..e + m],
                        &mut part,
                    );
                });
                diss += part.dissipated;
                work += part.work;
                max_ov = max_ov.max(part.max_overlap);
                self.counts.wall_collisions += part.onsets;
            }
        }
        if B::ACTIVE {
            let (mut part, mut part_chunk) = (0.0, 0usize);
            for i in 0..n {
                let xi: [f64; D] = std::array::from_fn(|k| x[k * n + i]);
                let fb = self.body.force(&xi, t);
                if i / PARTICLE_CHUNK != part_chunk {
                    work += part;
                    (part, part_chunk) = (0.0, i / PARTICLE_CHUNK);
                }
                for k in 0..D {
                    f[k * n + i] += fb[k];
                    part += fb[k] * v[k * n + i] * vs * dt;
                }
            }
            work += part;
        }
        // a = F / m.
        if p.mass != 1.0 {
            let inv_m = 1.0 / p.mass;
            for e in f.iter_mut() {
                *e *= inv_m;
            }
        }
        self.dissipated_damping += diss;
        self.work_by_drive += work;
        self.max_overlap = max_ov;
        let mut moved = [0.0; D];
        let flush = self.steps.is_multiple_of(GEAR_FLUSH_EVERY);
        match then {
            Then::Nothing => {}
            Then::Gear => {
                let c = p.gear;
                let [r0, r1, r2, r3, r4, r5] = &mut self.r;
                for k in 0..D {
                    let a = k * n..(k + 1) * n;
                    moved[k] = gear_correct_predict_axis(
                        [
                            &mut r0[a.clone()],
                            &mut r1[a.clone()],
                            &mut r2[a.clone()],
                            &mut r3[a.clone()],
                            &mut r4[a.clone()],
                            &mut r5[a.clone()],
                        ],
                        &mut f[a],
                        init[k],
                        0.5 * p.dt * p.dt,
                        &c,
                        p.periodic[k].then_some(p.size[k]),
                        flush,
                    );
                }
            }
            Then::VerletKick => verlet_kick(&mut self.r[1], f, dt),
        }
        moved
    }

    /// [`Self::forces_then`] split over the pool's threads (see there).
    fn forces_then_parallel(&mut self, t: f64, vs: f64, dt: f64, then: Then) -> [f64; D] {
        self.list.ensure_transposed();
        let n = self.n;
        let min_len = 1;
        let p = &self.p;
        let entries = self.list.partner.len();
        self.pair_f.resize(D * entries, 0.0);
        let pc = PairConstants {
            periodic: p.periodic,
            size: p.size,
            stiffness: p.stiffness,
            damping: p.damping,
            bridge_force: p.bridge_force,
            s_crit: p.s_crit,
            vs,
            dt,
        };
        {
            let (x, v, radius) = (&self.r[0], &self.r[1], &self.radius);
            let (row_of, partner) = (&self.list.row_of, &self.list.partner);
            self.list
                .flags
                .par_chunks_mut(ENTRY_CHUNK)
                .zip(self.pair_f.par_chunks_mut(ENTRY_CHUNK * D))
                .enumerate()
                .with_min_len(min_len)
                .map(|(c, (flags, pf))| {
                    let q0 = c * ENTRY_CHUNK;
                    pair_chunk::<D, WET>(
                        &pc,
                        x,
                        v,
                        radius,
                        &row_of[q0..],
                        &partner[q0..],
                        flags,
                        pf,
                    )
                })
                .collect_into_vec(&mut self.pair_books);
        }
        let mut diss = 0.0;
        let mut ledger = 0.0;
        let mut max_ov = self.max_overlap;
        for b in &self.pair_books {
            diss += b.dissipated;
            ledger += b.bridge_ledger;
            max_ov = max_ov.max(b.max_overlap);
            self.counts.pair_collisions += b.onsets;
            self.counts.bridge_formations += b.formations;
            self.counts.bridge_ruptures += b.ruptures;
        }
        self.dissipated_bridges += ledger;
        // The body force per particle (all axes at once), particle-major, with its work.
        self.body_work.clear();
        if B::ACTIVE {
            self.body_f.resize(D * n, 0.0);
            let (x, v, body) = (&self.r[0], &self.r[1], &self.body);
            self.body_f
                .par_chunks_mut(PARTICLE_CHUNK * D)
                .enumerate()
                .with_min_len(min_len)
                .map(|(c, bf)| {
                    let i0 = c * PARTICLE_CHUNK;
                    let mut work = 0.0;
                    for (m, out) in bf.chunks_mut(D).enumerate() {
                        let i = i0 + m;
                        let xi: [f64; D] = std::array::from_fn(|k| x[k * n + i]);
                        let fb = body.force(&xi, t);
                        for k in 0..D {
                            out[k] = fb[k];
                            work += fb[k] * v[k * n + i] * vs * dt;
                        }
                    }
                    work
                })
                .collect_into_vec(&mut self.body_work);
        }
        let init = self.force_start();
        // The Gear pass leaves the start values for the next evaluation.
        self.acc_is_start = then == Then::Gear;
        let cx = ChunkContext::<D> {
            n,
            pf: &self.pair_f,
            start: &self.list.start,
            row_of: &self.list.row_of,
            partner: &self.list.partner,
            in_start: &self.list.in_start,
            in_entry: &self.list.in_entry,
            radius: &self.radius,
            wall_kr: &self.wall_kr,
            body_f: if B::ACTIVE { &self.body_f } else { &[] },
            init,
            periodic: p.periodic,
            size: p.size,
            walls: wall_axes(p, t, vs, dt),
            inv_mass: (p.mass != 1.0).then(|| 1.0 / p.mass),
            dt,
            then,
            gear: p.gear,
            half_dt2: 0.5 * p.dt * p.dt,
            flush: self.steps.is_multiple_of(GEAR_FLUSH_EVERY),
        };
        let [r0, r1, r2, r3, r4, r5] = &mut self.r;
        (
            self.acc.par_chunks_mut(PARTICLE_CHUNK),
            r0.par_chunks_mut(PARTICLE_CHUNK),
            r1.par_chunks_mut(PARTICLE_CHUNK),
            r2.par_chunks_mut(PARTICLE_CHUNK),
            r3.par_chunks_mut(PARTICLE_CHUNK),
            r4.par_chunks_mut(PARTICLE_CHUNK),
            r5.par_chunks_mut(PARTICLE_CHUNK),
            self.wall_contact.par_chunks_mut(PARTICLE_CHUNK),
        )
            .into_par_iter()
            .enumerate()
            .with_min_len(min_len)
            .map(|(c, (acc, r0, r1, r2, r3, r4, r5, touch))| {
                particle_chunk(
                    &cx,
                    c * PARTICLE_CHUNK,
                    acc,
                    [r0, r1, r2, r3, r4, r5],
                    touch,
                )
            })
            .collect_into_vec(&mut self.chunk_books);
        let mut work = 0.0;
        let mut moved = [0.0; D];
        for b in &self.chunk_books {
            diss += b.walls.dissipated;
            work += b.walls.work;
            max_ov = max_ov.max(b.walls.max_overlap);
            self.counts.wall_collisions += b.walls.onsets;
            for k in 0..D {
                moved[k] = max_ignoring_nan(moved[k], b.moved[k]);
            }
        }
        for w in &self.body_work {
            work += w;
        }
        self.dissipated_damping += diss;
        self.work_by_drive += work;
        self.max_overlap = max_ov;
        moved
    }
}

/// The walls of every axis at time `t` (used on the non-periodic ones): Hertz with
/// `R_eff = R_i`; the last axis's walls move with the drive, `z_w(t) = A sin(omega t)`
/// (docs/model.md 4.1). `vs` turns the velocity array into velocities, `dt` weights the books.
fn wall_axes<const D: usize>(p: &Params<D>, t: f64, vs: f64, dt: f64) -> [WallAxis; D] {
    let (zw, vw) = match p.drive {
        Some((a, w)) => (a * (w * t).sin(), a * w * (w * t).cos()),
        None => (0.0, 0.0),
    };
    std::array::from_fn(|k| {
        let (shift, velocity) = if k == D - 1 { (zw, vw) } else { (0.0, 0.0) };
        WallAxis::new(
            shift,
            p.size[k] + shift,
            velocity,
            vs,
            p.wall_damping,
            dt,
            p.max_radius,
        )
    })
}

/// What the per-particle phase does after the forces ([`TimeEngine::forces_then`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Then {
    /// Nothing (the initial forces, a re-evaluation after `set_state`).
    Nothing,
    /// Gear's corrector of this step fused with the predictor of the next.
    Gear,
    /// Velocity Verlet's second half, `v += a dt / 2`.
    VerletKick,
}

/// What one chunk of the per-particle phase books.
#[derive(Debug, Clone, Copy)]
pub(super) struct ChunkBooks<const D: usize> {
    walls: WallBooks,
    /// Largest move of a predicted position per axis (Gear).
    moved: [f64; D],
}

/// What the per-particle phase reads (shared by every chunk).
struct ChunkContext<'a, const D: usize> {
    n: usize,
    /// Pair forces per list entry, `D` values each ([`pair_chunk`]).
    pf: &'a [f64],
    start: &'a [u32],
    row_of: &'a [u32],
    partner: &'a [u32],
    in_start: &'a [u32],
    in_entry: &'a [u32],
    radius: &'a [f64],
    wall_kr: &'a [f64],
    /// Body force per particle, particle-major (empty without one).
    body_f: &'a [f64],
    /// The force every coordinate starts from (the weight on the last axis).
    init: [f64; D],
    periodic: [bool; D],
    size: [f64; D],
    /// Per axis: the walls (used on the non-periodic axes).
    walls: [WallAxis; D],
    inv_mass: Option<f64>,
    dt: f64,
    then: Then,
    gear: [f64; 6],
    half_dt2: f64,
    /// Whether this step flushes the Gear derivatives ([`GEAR_FLUSH_EVERY`]).
    flush: bool,
}

/// Splits the flat coordinates `e0..e0 + len` (axis-major, `n` per axis) at the axis
/// boundaries and calls `f(k, offset, m)` for each piece: axis `k`, offset in the chunk, length.
#[inline(always)]
fn for_each_axis_segment(n: usize, e0: usize, len: usize, mut f: impl FnMut(usize, usize, usize)) {
    let mut o = 0;
    while o < len {
        let e = e0 + o;
        let m = (len - o).min(n - e % n);
        f(e / n, o, m);
        o += m;
    }
}

/// `b` if it is larger, else `a` (a NaN `b` is ignored): the running maximum of the integrator
/// loops (`integrator::lane_max`), exact and so independent of the order of the chunks.
#[inline(always)]
fn max_ignoring_nan(a: f64, b: f64) -> f64 {
    if b > a { b } else { a }
}

/// `x < 0: x + L; x >= L: x - L` on every element.
fn wrap_slice(xs: &mut [f64], l: f64) {
    for x in xs {
        if *x < 0.0 {
            *x += l;
        } else if *x >= l {
            *x -= l;
        }
    }
}

/// The per-particle phase on the flat coordinates `e0..e0 + acc.len()` (one chunk, see
/// [`TimeEngine::forces_then`]): `acc` is computed (start value, pair forces gathered in the
/// half list's order, walls, body force, `1/m`), then `cx.then` updates `r`.
fn particle_chunk<const D: usize>(
    cx: &ChunkContext<D>,
    e0: usize,
    acc: &mut [f64],
    r: [&mut [f64]; 6],
    touch: &mut [u8],
) -> ChunkBooks<D> {
    let mut walls = WallBooks::default();
    let mut moved = [0.0; D];
    let n = cx.n;
    let [r0, r1, r2, r3, r4, r5] = r;
    for_each_axis_segment(n, e0, acc.len(), |k, o, m| {
        let i0 = (e0 + o) % n;
        let acc = &mut acc[o..o + m];
        acc.fill(cx.init[k]);
        // The partners' rows, ascending: `f_j -= f_ij`.
        for &q in &cx.in_entry[cx.in_start[i0] as usize..cx.in_start[i0 + m] as usize] {
            let q = q as usize;
            acc[cx.partner[q] as usize - i0] -= cx.pf[q * D + k];
        }
        // The particle's own row, summed first: `f_i += sum_j f_ij`.
        let (mut q, end) = (cx.start[i0] as usize, cx.start[i0 + m] as usize);
        while q < end {
            let i = cx.row_of[q] as usize;
            let row_end = cx.start[i + 1] as usize;
            let mut own = 0.0;
            while q < row_end {
                own += cx.pf[q * D + k];
                q += 1;
            }
            acc[i - i0] += own;
        }
        if !cx.periodic[k] {
            let radius = &cx.radius[i0..i0 + m];
            let wall_kr = &cx.wall_kr[i0..i0 + m];
            let (x, v, touching) = (&r0[o..o + m], &r1[o..o + m], &mut touch[o..o + m]);
            wall_forces(
                &cx.walls[k],
                x,
                v,
                radius,
                wall_kr,
                touching,
                acc,
                &mut walls,
            );
        }
        if !cx.body_f.is_empty() {
            for i in 0..m {
                acc[i] += cx.body_f[(i0 + i) * D + k];
            }
        }
        // a = F / m.
        if let Some(inv_m) = cx.inv_mass {
            for a in acc.iter_mut() {
                *a *= inv_m;
            }
        }
        match cx.then {
            Then::Nothing => {}
            Then::Gear => {
                let s = o..o + m;
                let step_move = gear_correct_predict_axis(
                    [
                        &mut r0[s.clone()],
                        &mut r1[s.clone()],
                        &mut r2[s.clone()],
                        &mut r3[s.clone()],
                        &mut r4[s.clone()],
                        &mut r5[s],
                    ],
                    acc,
                    cx.init[k],
                    cx.half_dt2,
                    &cx.gear,
                    cx.periodic[k].then_some(cx.size[k]),
                    cx.flush,
                );
                moved[k] = max_ignoring_nan(moved[k], step_move);
            }
            Then::VerletKick => verlet_kick(&mut r1[o..o + m], acc, cx.dt),
        }
    });
    ChunkBooks { walls, moved }
}
