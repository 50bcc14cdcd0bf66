//! `wetgran bench barrier`: what two threads that meet at a barrier twice per step can gain on
//! this machine, whatever the engine.
//!
//! A time-driven step of the standard system takes about 9 us on one core (docs/performance.md,
//! `bench tdmd`), and any split of a step over two threads needs them to meet at least twice
//! per step (after the forces, after the integration). This benchmark measures the ceiling
//! that sets, with no engine in the way: each round, one thread does two units of a fixed
//! integer work (a multiply-xorshift chain, no memory traffic) while two threads do one unit
//! each and then meet at a spin barrier twice. Reported per unit size: the serial and the
//! two-thread time per round (median over the repetitions) and their ratio, the speed-up a
//! perfectly split step of that length could reach. If it is far below 2 at the step length of
//! an engine, no parallel algorithm of that engine can do better; if it is near 2, the
//! engine's parallel overhead (extra instructions, serial parts) is what is left to remove.

use super::Spread;
use std::hint::black_box;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

/// Units of work per thread per round (iterations of the chain), from about 0.4 us to 15 us.
pub const UNITS: [u64; 6] = [250, 500, 1000, 2000, 4000, 8000];

/// One unit of work: `n` dependent multiply-add-xorshift steps.
fn work(n: u64, seed: u64) -> u64 {
    let mut x = seed;
    for i in 0..n {
        x = x.wrapping_mul(6364136223846793005).wrapping_add(i);
        x ^= x >> 17;
    }
    x
}

/// A reusable spin barrier for a fixed number of threads: an arrival count and a generation
/// number; the last to arrive resets the count and opens the next generation.
#[derive(Debug)]
pub struct SpinBarrier {
    parties: u64,
    arrived: AtomicU64,
    generation: AtomicU64,
}

impl SpinBarrier {
    pub fn new(parties: u64) -> SpinBarrier {
        SpinBarrier {
            parties,
            arrived: AtomicU64::new(0),
            generation: AtomicU64::new(0),
        }
    }

    /// Returns once all `parties` threads have called it for this generation.
    pub fn wait(&self) {
        let g = self.generation.load(Ordering::Acquire);
        if self.arrived.fetch_add(1, Ordering::AcqRel) + 1 == self.parties {
            self.arrived.store(0, Ordering::Relaxed);
            self.generation.store(g + 1, Ordering::Release);
        } else {
            let mut spins = 0u32;
            while self.generation.load(Ordering::Acquire) == g {
                spins = spins.wrapping_add(1);
                if spins % 4096 == 0 {
                    // A machine with fewer free cores than threads must not livelock.
                    std::thread::yield_now();
                } else {
                    std::hint::spin_loop();
                }
            }
        }
    }
}

/// One unit size: time per round on one thread (two units) and on two (one unit each, two
/// barriers), in microseconds.
#[derive(Debug, Clone)]
pub struct Row {
    pub unit: u64,
    pub rounds: u64,
    pub serial_us: Spread,
    pub parallel_us: Spread,
}

/// Rounds per repetition for a unit size: about 0.15 s of serial work at `scale` 1.
fn rounds_for(unit: u64, scale: f64) -> u64 {
    ((150_000.0 * 1000.0 / unit as f64 / 3.7 * scale) as u64).max(100)
}

fn serial_round_us(unit: u64, rounds: u64) -> f64 {
    let t = Instant::now();
    let mut s = 0;
    for r in 0..rounds {
        s ^= work(unit, r);
        s ^= work(unit, r + 1);
    }
    black_box(s);
    t.elapsed().as_secs_f64() / rounds as f64 * 1e6
}

fn parallel_round_us(unit: u64, rounds: u64) -> f64 {
    let barrier = SpinBarrier::new(2);
    let t = Instant::now();
    std::thread::scope(|scope| {
        let b = &barrier;
        let other = scope.spawn(move || {
            let mut s = 0;
            for r in 0..rounds {
                s ^= work(unit, r + 1);
                b.wait();
                b.wait();
            }
            s
        });
        let mut s = 0;
        for r in 0..rounds {
            s ^= work(unit, r);
            b.wait();
            b.wait();
        }
        black_box(s ^ other.join().expect("barrier bench thread"));
    });
    t.elapsed().as_secs_f64() / rounds as f64 * 1e6
}

/// Measures every unit size of [`UNITS`], `repeat` times each (serial and two-thread runs
/// alternate).
pub fn measure(repeat: usize, scale: f64) -> Vec<Row> {
    UNITS
        .iter()
        .map(|&unit| {
            let rounds = rounds_for(unit, scale);
            let (mut s, mut p) = (Vec::new(), Vec::new());
            for _ in 0..repeat.max(1) {
                s.push(serial_round_us(unit, rounds));
                p.push(parallel_round_us(unit, rounds));
            }
            Row {
                unit,
                rounds,
                serial_us: Spread::of(s),
                parallel_us: Spread::of(p),
            }
        })
        .collect()
}

pub fn report(rows: &[Row], repeat: usize) -> String {
    let mut out = format!(
        "two threads meeting at a spin barrier twice per round ({} cores available), \
         medians of {} repetitions\n",
        std::thread::available_parallelism().map_or(1, |n| n.get()),
        repeat.max(1)
    );
    out.push_str(
        "unit    rounds   1 thread us/round   2 threads us/round   speed-up (median, min..max of 2-thread times)\n",
    );
    for r in rows {
        out.push_str(&format!(
            "{:>5} {:>9} {:>19.3} {:>20.3} {:>10.2}x  ({:.3}..{:.3} us)\n",
            r.unit,
            r.rounds,
            r.serial_us.median,
            r.parallel_us.median,
            r.serial_us.median / r.parallel_us.median,
            r.parallel_us.min,
            r.parallel_us.max
        ));
    }
    out.push_str(
        "1 thread: two units per round; 2 threads: one unit each, then two barriers. The speed-up \
         at a round as long as one engine step on one thread is the most any split of that step \
         over two threads can give here.\n",
    );
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn no_thread_passes_the_barrier_before_the_other_arrives() {
        // Each thread adds 1 before each barrier; after it, the count must be exactly twice the
        // rounds done, whatever the scheduling. Without the barrier (or with a barrier that
        // opens on the first arrival) a thread reads a count that the other has not reached.
        let barrier = SpinBarrier::new(2);
        let count = AtomicU64::new(0);
        std::thread::scope(|scope| {
            for _ in 0..2 {
                scope.spawn(|| {
                    for round in 1..=2000u64 {
                        count.fetch_add(1, Ordering::SeqCst);
                        barrier.wait();
                        assert_eq!(count.load(Ordering::SeqCst), 2 * round);
                        barrier.wait();
                    }
                });
            }
        });
        assert_eq!(count.load(Ordering::SeqCst), 4000);
    }

    #[test]
    fn the_work_unit_is_deterministic_and_depends_on_its_length() {
        assert_eq!(work(1000, 7), work(1000, 7));
        assert_ne!(work(1000, 7), work(1001, 7));
    }
}
