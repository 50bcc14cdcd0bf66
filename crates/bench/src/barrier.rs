//! `wetgran-bench barrier`: what two threads that meet at a barrier twice per step can gain on
//! this machine, whatever the engine.
//!
//! A time-driven step of the standard system takes about 9 us on one core
//! (docs/performance-history.md, "Fifth round: slab accumulators"), and any split of a step over
//! two threads needs them to meet at least twice
//! per step (after the forces, after the integration). This benchmark measures the ceiling
//! that sets, with no engine in the way: each round, one thread does two units of a fixed
//! integer work (a multiply-xorshift chain, no memory traffic) while two threads do one unit
//! each and then meet at a spin barrier twice. A second table adds the hand-over of data: each
//! thread writes its half of a shared buffer (as a split step publishes its particles'
//! positions and velocities), the barrier, then it reads the other thread's half (the cache
//! lines move between the cores), the barrier; the serial round writes and reads both halves.
//! Reported per row: the serial and the two-thread time per round (median over the
//! repetitions) and their ratio, the speed-up a perfectly split step of that length and
//! hand-over could reach. If it is far below 2 at the step length of an engine, no parallel
//! algorithm of that engine that hands over that much per step can do better; if it is near 2,
//! the engine's parallel overhead (extra instructions, serial parts) is what is left to remove.

use super::Spread;
use std::hint::black_box;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

/// Units of work per thread per round (iterations of the chain), from about 0.4 us to 15 us.
pub(crate) const UNITS: [u64; 6] = [250, 500, 1000, 2000, 4000, 8000];

/// The unit of the exchange rows: about 4 us per thread, so that a round of one thread (two
/// units) is about as long as a Gear step of the standard N = 1200 system on one core.
pub(crate) const EXCHANGE_UNIT: u64 = 1000;

/// Data each thread publishes per round in the exchange rows, in KiB, read by the other after
/// the first barrier. A split Gear step of the 2D N = 1200 system publishes positions and
/// velocities of its half: 600 x 2 x 2 x 8 B = 19 KiB per thread; N = 4800: 75 KiB.
pub(crate) const EXCHANGE_KIB: [usize; 4] = [4, 19, 38, 75];

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
pub(crate) struct SpinBarrier {
    parties: u64,
    arrived: AtomicU64,
    generation: AtomicU64,
}

impl SpinBarrier {
    pub(crate) fn new(parties: u64) -> SpinBarrier {
        SpinBarrier {
            parties,
            arrived: AtomicU64::new(0),
            generation: AtomicU64::new(0),
        }
    }

    /// Returns once all `parties` threads have called it for this generation.
    pub(crate) fn wait(&self) {
        let g = self.generation.load(Ordering::Acquire);
        if self.arrived.fetch_add(1, Ordering::AcqRel) + 1 == self.parties {
            self.arrived.store(0, Ordering::Relaxed);
            self.generation.store(g + 1, Ordering::Release);
        } else {
            let mut spins = 0u32;
            while self.generation.load(Ordering::Acquire) == g {
                spins = spins.wrapping_add(1);
                if spins.is_multiple_of(4096) {
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
pub(crate) struct Row {
    pub unit: u64,
    /// KiB each thread publishes per round for the other to read (0: none).
    pub(crate) exchange_kib: usize,
    pub rounds: u64,
    pub(crate) serial_us: Spread,
    pub(crate) parallel_us: Spread,
}

/// Rounds per repetition for a unit size: about 0.15 s of serial work at `scale` 1.
fn rounds_for(unit: u64, scale: f64) -> u64 {
    ((150_000.0 * 1000.0 / unit as f64 / 3.7 * scale) as u64).max(100)
}

fn serial_round_us(unit: u64, rounds: u64, words: usize) -> f64 {
    let shared: Vec<AtomicU64> = (0..2 * words).map(|_| AtomicU64::new(0)).collect();
    let t = Instant::now();
    let mut s = 0;
    for r in 0..rounds {
        s ^= work(unit, r);
        s ^= work(unit, r + 1);
        publish(&shared, s);
        s ^= read_back(&shared);
    }
    black_box(s);
    t.elapsed().as_secs_f64() / rounds as f64 * 1e6
}

/// Writes `words` values derived from `s` (relaxed stores, plain moves on x86, as the engines
/// publish positions and velocities to the other thread).
fn publish(half: &[AtomicU64], s: u64) {
    for (k, w) in half.iter().enumerate() {
        w.store(s.wrapping_add(k as u64), Ordering::Relaxed);
    }
}

fn read_back(half: &[AtomicU64]) -> u64 {
    half.iter()
        .fold(0u64, |a, w| a.wrapping_add(w.load(Ordering::Relaxed)))
}

fn parallel_round_us(unit: u64, rounds: u64, words: usize) -> f64 {
    let barrier = SpinBarrier::new(2);
    let shared: Vec<AtomicU64> = (0..2 * words).map(|_| AtomicU64::new(0)).collect();
    let (first, second) = shared.split_at(words);
    let t = Instant::now();
    std::thread::scope(|scope| {
        let b = &barrier;
        let other = scope.spawn(move || {
            let mut s = 0;
            for r in 0..rounds {
                s ^= work(unit, r + 1);
                publish(second, s);
                b.wait();
                s ^= read_back(first);
                b.wait();
            }
            s
        });
        let mut s = 0;
        for r in 0..rounds {
            s ^= work(unit, r);
            publish(first, s);
            b.wait();
            s ^= read_back(second);
            b.wait();
        }
        black_box(s ^ other.join().expect("barrier bench thread"));
    });
    t.elapsed().as_secs_f64() / rounds as f64 * 1e6
}

fn measure_one(unit: u64, exchange_kib: usize, repeat: usize, scale: f64) -> Row {
    let rounds = rounds_for(unit, scale);
    let words = exchange_kib * 1024 / 8;
    let (mut s, mut p) = (Vec::new(), Vec::new());
    for _ in 0..repeat.max(1) {
        s.push(serial_round_us(unit, rounds, words));
        p.push(parallel_round_us(unit, rounds, words));
    }
    Row {
        unit,
        exchange_kib,
        rounds,
        serial_us: Spread::of(s),
        parallel_us: Spread::of(p),
    }
}

/// Measures every unit size of [`UNITS`] without data exchange, then [`EXCHANGE_UNIT`] with
/// every size of [`EXCHANGE_KIB`]; `repeat` times each (serial and two-thread runs alternate).
pub(crate) fn measure(repeat: usize, scale: f64) -> Vec<Row> {
    let plain = UNITS.iter().map(|&u| measure_one(u, 0, repeat, scale));
    let exchange = EXCHANGE_KIB
        .iter()
        .map(|&k| measure_one(EXCHANGE_UNIT, k, repeat, scale));
    plain.chain(exchange).collect()
}

pub(crate) fn report(rows: &[Row], repeat: usize) -> String {
    let mut out = format!(
        "two threads meeting at a spin barrier twice per round ({} cores available), \
         medians of {} repetitions\n",
        std::thread::available_parallelism().map_or(1, |n| n.get()),
        repeat.max(1)
    );
    out.push_str(
        "unit  KiB/thread    rounds   1 thread us/round   2 threads us/round   speed-up (min..max of 2-thread times)\n",
    );
    for r in rows {
        out.push_str(&format!(
            "{:>5} {:>10} {:>9} {:>19.3} {:>20.3} {:>10.2}x  ({:.3}..{:.3} us)\n",
            r.unit,
            r.exchange_kib,
            r.rounds,
            r.serial_us.median,
            r.parallel_us.median,
            r.serial_us.median / r.parallel_us.median,
            r.parallel_us.min,
            r.parallel_us.max
        ));
    }
    out.push_str(
        "1 thread: two units per round and both halves written and read; 2 threads: one unit \
         each, its half written (KiB/thread), barrier, the other's half read, barrier. The \
         speed-up at a round as long as one engine step on one thread, with the data that step \
         must hand over, is the most any split of that step over two threads can give here.\n",
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
}
