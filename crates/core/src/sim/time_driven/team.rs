//! A team of threads that runs many time steps in one parallel region (SPMD) for the spatial
//! domains (`domains.rs`): one closure on every thread of the current rayon pool
//! ([`rayon::broadcast`]: no thread beyond the pool, so the run's `sim::threads::Threads` are
//! respected), the members synchronised once per step by a spin barrier ([`Member::wait`])
//! instead of handing work over through rayon twice per step.
//!
//! - **Admission** (the door): a pool thread joins when its copy of the closure starts; the
//!   door closes when every thread of the pool has joined or after [`DOOR_WAIT`] (the members
//!   that joined then do the others' work); a thread arriving later returns at once. So two
//!   regions started on one pool at once never wait for each other's threads.
//! - **Barrier**: an atomic arrival counter and a generation number; a waiting member spins up
//!   to [`SPIN_TIME`], then yields its core at every round, so an oversubscribed machine does
//!   not livelock.
//! - **Panics**: a member that panics sets the team's poison flag as it unwinds; every member
//!   waiting at the barrier or the door sees it and panics too, and `rayon::broadcast`
//!   re-raises the panic on the caller.
//!
//! A member's numbers must not depend on the number of members: the engine gives each member
//! fixed domains and combines their results in domain order.

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::{Duration, Instant};

/// How long a waiting member spins before it yields its core (a barrier takes well under a
/// microsecond on a quiet machine; longer means a member is not running).
pub(super) const SPIN_TIME: Duration = Duration::from_micros(50);

/// How long the first members wait at the door for the other threads of the pool to start.
pub(super) const DOOR_WAIT: Duration = Duration::from_millis(2);

/// The door's "closed" bit in [`Team::joined`].
const CLOSED: usize = 1 << (usize::BITS - 1);

/// The shared state of one region.
#[derive(Debug)]
pub(super) struct Team {
    /// Members joined so far (low bits) and [`CLOSED`].
    joined: AtomicUsize,
    /// Threads of the pool (the most members a team can have).
    threads: usize,
    /// How long the door stays open ([`DOOR_WAIT`]).
    door: Duration,
    /// Members arrived at the current barrier.
    arrived: AtomicUsize,
    /// Barriers passed.
    generation: AtomicUsize,
    /// Set by a member that panics.
    poison: AtomicBool,
}

/// One member's view of the team.
#[derive(Debug, Clone, Copy)]
pub(super) struct Member<'t> {
    team: &'t Team,
    /// This member's number, `0..members`.
    pub slot: usize,
    /// Members in the team (fixed once the door closed).
    pub members: usize,
}

/// Sets the poison flag if dropped during a panic.
struct PoisonOnUnwind<'t>(&'t AtomicBool);

impl Drop for PoisonOnUnwind<'_> {
    fn drop(&mut self) {
        if std::thread::panicking() {
            self.0.store(true, Ordering::Release);
        }
    }
}

/// The state of one wait: spin rounds so far, and when spinning began (read every 64 rounds).
#[derive(Default)]
struct Pause {
    rounds: u32,
    since: Option<Instant>,
    yielding: bool,
}

impl Pause {
    /// Waits a little: spins for up to [`SPIN_TIME`], then yields the core at every call.
    /// Panics if the team is poisoned.
    #[inline]
    fn pause(&mut self, team: &Team) {
        if team.poison.load(Ordering::Acquire) {
            panic!("another thread of the time-driven step panicked");
        }
        if self.yielding {
            std::thread::yield_now();
            return;
        }
        self.rounds += 1;
        std::hint::spin_loop();
        if self.rounds.is_multiple_of(64) {
            let since = *self.since.get_or_insert_with(Instant::now);
            if since.elapsed() >= SPIN_TIME {
                self.yielding = true;
            }
        }
    }
}

impl Member<'_> {
    /// Waits until every member has called `wait` as often as this one. Memory written by any
    /// member before its call is visible to every member after it.
    pub(super) fn wait(&self) {
        let team = self.team;
        let generation = team.generation.load(Ordering::Acquire);
        if team.arrived.fetch_add(1, Ordering::AcqRel) + 1 == self.members {
            // Last to arrive: nobody can arrive at the next barrier before the generation
            // moves on, so the counter is reset first.
            team.arrived.store(0, Ordering::Relaxed);
            team.generation.store(generation + 1, Ordering::Release);
            return;
        }
        let mut pause = Pause::default();
        while team.generation.load(Ordering::Acquire) == generation {
            pause.pause(team);
        }
    }
}

impl Team {
    fn new(threads: usize, door: Duration) -> Self {
        Self {
            joined: AtomicUsize::new(0),
            threads,
            door,
            arrived: AtomicUsize::new(0),
            generation: AtomicUsize::new(0),
            poison: AtomicBool::new(false),
        }
    }

    /// Admits the calling thread (None: the door is closed) and waits for the door to close.
    fn join(&self) -> Option<Member<'_>> {
        let mut c = self.joined.load(Ordering::Acquire);
        let slot = loop {
            if c & CLOSED != 0 {
                return None;
            }
            match self
                .joined
                .compare_exchange_weak(c, c + 1, Ordering::AcqRel, Ordering::Acquire)
            {
                Ok(_) => break c,
                Err(now) => c = now,
            }
        };
        if slot + 1 == self.threads {
            self.joined.fetch_or(CLOSED, Ordering::AcqRel);
        }
        let since = Instant::now();
        let mut pause = Pause::default();
        let members = loop {
            let c = self.joined.load(Ordering::Acquire);
            if c & CLOSED != 0 {
                break c & !CLOSED;
            }
            if since.elapsed() >= self.door {
                self.joined.fetch_or(CLOSED, Ordering::AcqRel);
                continue;
            }
            pause.pause(self);
        };
        Some(Member {
            team: self,
            slot,
            members,
        })
    }
}

/// Runs `work` as the only member of a team on the calling thread (no pool thread, no door;
/// its barriers return at once): the same code as [`run`] on one thread.
pub(super) fn solo<R>(work: impl FnOnce(Member<'_>) -> R) -> R {
    let team = Team::new(1, Duration::ZERO);
    work(Member {
        team: &team,
        slot: 0,
        members: 1,
    })
}

/// Runs `work` once per member of a team of at most `max_members` of the current pool's threads,
/// the door open for `door` ([`DOOR_WAIT`]; tests use a long one), and returns the members'
/// results in slot order (at least one). A member's panic is re-raised here.
pub(crate) fn run_with_door<R: Send>(
    max_members: usize,
    door: Duration,
    work: impl Fn(Member<'_>) -> R + Sync,
) -> Vec<R> {
    let team = Team::new(rayon::current_num_threads().min(max_members.max(1)), door);
    let mut out: Vec<(usize, R)> = rayon::broadcast(|_| {
        let _poison = PoisonOnUnwind(&team.poison);
        let member = team.join()?;
        Some((member.slot, work(member)))
    })
    .into_iter()
    .flatten()
    .collect();
    out.sort_by_key(|(slot, _)| *slot);
    out.into_iter().map(|(_, r)| r).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A rayon pool of `threads` threads.
    fn pool(threads: usize) -> rayon::ThreadPool {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("a pool")
    }

    #[test]
    fn members_pass_barriers_in_step() {
        let counter = AtomicUsize::new(0);
        let seen = pool(3).install(|| {
            run_with_door(usize::MAX, DOOR_WAIT, |m| {
                let mut seen = Vec::new();
                for round in 0..200 {
                    counter.fetch_add(1, Ordering::Relaxed);
                    m.wait();
                    // Every member has added its count of this round.
                    seen.push(counter.load(Ordering::Relaxed) >= (round + 1) * m.members);
                    m.wait();
                }
                (m.members, seen.iter().all(|&s| s))
            })
        });
        assert!(!seen.is_empty());
        for (members, ok) in seen {
            assert!((1..=3).contains(&members));
            assert!(ok);
        }
    }

    #[test]
    fn a_panicking_member_does_not_hang_the_others() {
        let p = pool(2);
        // A long door wait: both threads are members, so one waits for the one that panics
        // (without the poison flag it would wait forever).
        let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            p.install(|| {
                run_with_door(usize::MAX, Duration::from_secs(60), |m| {
                    assert_eq!(m.members, 2);
                    for round in 0..100 {
                        if round == 50 && m.slot == 1 {
                            panic!("forced");
                        }
                        m.wait();
                    }
                })
            })
        }));
        assert!(r.is_err());
    }

    #[test]
    fn two_regions_on_one_pool_do_not_wait_for_each_other() {
        let p = pool(2);
        // Two callers start regions on the same two-thread pool at once; each region's members
        // spin at barriers, so without the door one member of each would wait forever.
        p.install(|| {
            rayon::join(
                || run_with_door(usize::MAX, DOOR_WAIT, |m| (0..1000).for_each(|_| m.wait())).len(),
                || run_with_door(usize::MAX, DOOR_WAIT, |m| (0..1000).for_each(|_| m.wait())).len(),
            )
        });
    }
}
