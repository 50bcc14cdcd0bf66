//! The domain strategy: regions of Gear steps on the spatial domains of `domains.rs` (see
//! there), each run by a team of up to [`DOMAINS`] threads of the current pool (`team.rs`; the
//! calling thread alone on a pool of one), the books added back step by step, domains in order.

use super::*;
use crate::sim::time_driven::domains::{
    DOMAINS, Decomposition, EngineArrays, RegionBooks, RegionEnd, StepConstants, TeamBuild,
};
use crate::sim::time_driven::team;
use stepping::wall_axes;

/// The domain strategy's state: the decomposition in use, if any, and what it counts.
#[derive(Debug)]
pub(super) struct Domains<const D: usize> {
    pub(super) decomposition: Option<Box<Decomposition<D>>>,
    /// Steps so far that ran on a team of more than one thread.
    pub(super) team_steps: u64,
    pub(super) partitions: u64,
    /// Regions run (a region goes on through list builds).
    pub(super) regions: u64,
    /// How long a region waits for the pool's threads to join its team ([`team::DOOR_WAIT`];
    /// the domain tests lengthen it).
    pub(super) door: std::time::Duration,
}

impl<const D: usize> Default for Domains<D> {
    fn default() -> Self {
        Self {
            decomposition: None,
            team_steps: 0,
            partitions: 0,
            regions: 0,
            door: team::DOOR_WAIT,
        }
    }
}

impl<const D: usize, const GRAV: bool, const WET: bool, B: BodyForce<D>> Strategy<D, GRAV, WET, B>
    for Domains<D>
{
    /// One region, from the engine's (predicted) step to `target` or to a list build that
    /// calls for a new partition.
    fn advance(&mut self, s: &mut State<D, GRAV, WET, B>, target: u64) {
        let first = s.steps;
        let (mut dec, own_checks) = self.decomposition_for(s);
        let builds = s.list.builds;
        // A new decomposition has no lists yet; a kept one re-splits after a build.
        if dec.built_for() != builds {
            dec.split_lists(&s.list, &s.radius);
        }
        dec.begin(s.moved_bound, s.since_check, first, own_checks);
        self.regions += 1;
        let (done, end, members) = run_region::<D, GRAV, WET, B>(&dec, s, first, target, self.door);
        s.acc_is_start = true;
        s.steps += done;
        if members > 1 {
            self.team_steps += done;
        }
        // Between regions of one run only the positions (for the list build) and the flags
        // come back; at the end of the run everything does.
        let full = end == RegionEnd::Target || s.steps >= target;
        // After a build for a new partition the domains' lists are those of the build before:
        // their flags are in the list already.
        let lists_current = dec.built_for() == s.list.builds;
        let (mut arrays, flags) = arrays(s);
        dec.store(&mut arrays, lists_current.then_some(flags), full);
        dec.partial = !full;
        dec.holds_step = Some(s.steps);
        dec.checked_for = (end != RegionEnd::Rebuild).then_some(s.steps);
        let (books, bound, since) = dec.books();
        self.decomposition = Some(dec);
        add_books(s, &books, done);
        match end {
            // The check of the next step found a particle beyond half the skin: the next
            // `update_list` runs the exact test (and rebuilds).
            RegionEnd::Rebuild => s.moved_bound = f64::INFINITY,
            // The team built the list (as `update_list` would have); the next region makes
            // the new partition.
            RegionEnd::Repartition => {
                s.moved_bound = 0.0;
                s.since_check = 0;
            }
            RegionEnd::Target => {
                s.moved_bound = bound;
                s.since_check = since;
            }
        }
    }
}

impl<const D: usize> Domains<D> {
    /// Drops the decomposition (the engine's state was changed outside the domains).
    pub(super) fn forget(&mut self) {
        self.decomposition = None;
    }

    /// The decomposition for a region starting at the engine's step, after the list check of
    /// that step: the last region's if it holds this step and its partition is still wanted,
    /// else a new one loaded from the engine's arrays; and whether the domains keep their own
    /// list checks (their last step did this step's check: counting it again would move the
    /// exact tests with the region ends).
    fn decomposition_for<const GRAV: bool, const WET: bool, B: BodyForce<D>>(
        &mut self,
        s: &mut State<D, GRAV, WET, B>,
    ) -> (Box<Decomposition<D>>, bool) {
        let first = s.steps;
        let checked = matches!(&self.decomposition, Some(d)
            if d.holds_step == Some(first) && d.checked_for == Some(first));
        if !checked {
            s.update_list();
        }
        let builds = s.list.builds;
        match self.decomposition.take() {
            Some(d)
                if d.holds_step == Some(first)
                    && (d.built_for() == builds || !d.wants_new_partition(builds)) =>
            {
                return (d, checked);
            }
            // The engine's arrays must hold the whole state before a new partition (the flags
            // came back at the end of the last region; the list is new since).
            Some(mut old) if old.partial => {
                let (mut arrays, _) = arrays(s);
                old.store(&mut arrays, None, true);
            }
            Some(_) | None => {}
        }
        self.partitions += 1;
        let mut d = Box::new(Decomposition::new(builds, s.p.size, s.list.built_at()));
        let acc_is_start = s.acc_is_start;
        let (arrays, _) = arrays(s);
        d.load(&arrays, acc_is_start, first);
        (d, false)
    }
}

/// Runs the steps of a region on a team of the current pool's threads (on the calling thread
/// alone on a pool of one): returns the steps taken, how the region ended and the team's size.
fn run_region<const D: usize, const GRAV: bool, const WET: bool, B: BodyForce<D>>(
    dec: &Decomposition<D>,
    s: &mut State<D, GRAV, WET, B>,
    first: u64,
    target: u64,
    door: std::time::Duration,
) -> (u64, RegionEnd, usize) {
    let p = &s.p;
    let dt = p.dt;
    let c = StepConstants {
        pair: p.pair_constants(1.0 / dt, dt),
        dt,
        inv_mass: (p.mass != 1.0).then(|| 1.0 / p.mass),
        init: s.force_start(),
        gear: p.gear,
        half_skin: 0.5 * s.list.skin(),
    };
    let walls_at = |step: u64| wall_axes(p, step as f64 * dt, 1.0 / dt, dt);
    // The team rebuilds the list itself (its threads stay awake) and goes on.
    let build = TeamBuild::new(&mut s.list, &mut s.r[0], &s.radius);
    let member = |slot: usize, members: usize, wait: &dyn Fn()| {
        dec.run_member::<WET>(&c, &walls_at, &build, slot, members, first, target, wait)
    };
    let ((done, end), members) = if rayon::current_num_threads() > 1 {
        let out = team::run_with_door(DOMAINS, door, |m| {
            (member(m.slot, m.members, &|| m.wait()), m.members)
        });
        out[0]
    } else {
        team::solo(|m| (member(0, 1, &|| m.wait()), 1))
    };
    (done, end, members)
}

/// The arrays a decomposition copies from and to, and the list flags.
fn arrays<const D: usize, const GRAV: bool, const WET: bool, B>(
    s: &mut State<D, GRAV, WET, B>,
) -> (EngineArrays<'_>, &mut [u8]) {
    (
        EngineArrays {
            r: &mut s.r,
            acc: &mut s.acc,
            wall_contact: &mut s.wall_contact,
            radius: &s.radius,
            wall_kr: &s.wall_kr,
        },
        &mut s.list.flags,
    )
}

/// Adds the books of the `done` steps of a region to the engine's: the sums step by step,
/// domains in order, then the counts and the largest overlap.
fn add_books<const D: usize, const GRAV: bool, const WET: bool, B>(
    s: &mut State<D, GRAV, WET, B>,
    books: &RegionBooks,
    done: u64,
) {
    for step in 0..done as usize {
        for (_, steps) in books {
            let [diss, ledger, work] = steps[step];
            s.dissipated_damping += diss;
            s.dissipated_bridges += ledger;
            s.work_by_drive += work;
        }
    }
    for (b, _) in books {
        s.add_counts(b);
    }
}
