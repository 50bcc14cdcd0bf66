//! Reference event queues for tests: an indexed 4-ary min-heap ([`HeapQueue`]) and a linear
//! scan ([`NaiveQueue`]), both implementing [`EventQueue`] with ties broken by the smaller
//! particle index, so that an engine takes the same trajectory on them as on the calendar queue
//! (`crates/core/tests/engine_pins.rs`). Compiled only for tests (`cfg(test)` and the feature
//! `testing`, which this crate's tests enable): engines run on the calendar queue.

use super::bodies::vec_bytes;
use super::queue::EventQueue;

/// Children per heap node.
const ARITY: usize = 4;

/// Indexed 4-ary min-heap over particle indices. Each heap slot stores its key next to the
/// particle index, so sifting compares without an indirection; four children of 16 bytes share
/// about one cache line, which makes the frequent sift-down (the processed particle's next event
/// is later) cheaper than in a binary heap.
#[derive(Debug, Clone)]
pub struct HeapQueue {
    heap: Vec<(f64, u32)>,
    slot: Vec<u32>,
}

impl EventQueue for HeapQueue {
    fn new(n: usize) -> Self {
        Self {
            heap: (0..n as u32).map(|i| (f64::INFINITY, i)).collect(),
            slot: (0..n as u32).collect(),
        }
    }

    #[inline]
    fn min(&mut self) -> Option<(usize, f64)> {
        self.heap.first().map(|&(k, i)| (i as usize, k))
    }

    #[inline]
    fn key(&self, i: usize) -> f64 {
        self.heap[self.slot[i] as usize].0
    }

    fn memory(&self) -> Vec<(&'static str, usize)> {
        vec![
            ("queue.heap", vec_bytes(&self.heap)),
            ("queue.slot", vec_bytes(&self.slot)),
        ]
    }

    /// Sets the key of particle `i` and restores the heap order.
    #[inline]
    fn update(&mut self, i: usize, time: f64) {
        let s = self.slot[i] as usize;
        let old = self.heap[s].0;
        self.heap[s].0 = time;
        if time < old {
            self.sift_up(s);
        } else if time > old {
            self.sift_down(s);
        }
    }
}

impl HeapQueue {
    /// Strict order on entries; ties broken by particle index so the order is deterministic.
    #[inline]
    fn less(a: (f64, u32), b: (f64, u32)) -> bool {
        a.0 < b.0 || (a.0 == b.0 && a.1 < b.1)
    }

    /// Puts `entry` into heap slot `s`.
    fn place(&mut self, s: usize, entry: (f64, u32)) {
        self.heap[s] = entry;
        self.slot[entry.1 as usize] = s as u32;
    }

    fn sift_up(&mut self, mut s: usize) {
        let entry = self.heap[s];
        while s > 0 {
            let parent = (s - 1) / ARITY;
            let p = self.heap[parent];
            if Self::less(entry, p) {
                self.place(s, p);
                s = parent;
            } else {
                break;
            }
        }
        self.place(s, entry);
    }

    fn sift_down(&mut self, mut s: usize) {
        let n = self.heap.len();
        let entry = self.heap[s];
        loop {
            let first = ARITY * s + 1;
            if first >= n {
                break;
            }
            let last = (first + ARITY).min(n);
            let mut child = first;
            for k in first + 1..last {
                if Self::less(self.heap[k], self.heap[child]) {
                    child = k;
                }
            }
            let c = self.heap[child];
            if Self::less(c, entry) {
                self.place(s, c);
                s = child;
            } else {
                break;
            }
        }
        self.place(s, entry);
    }
}

/// Reference queue: a linear scan over the keys, `O(N)` per pop. Slow, obviously correct; the
/// tests run engines on it to check [`HeapQueue`] (and any faster queue to come).
#[derive(Debug, Clone)]
pub struct NaiveQueue {
    key: Vec<f64>,
}

impl EventQueue for NaiveQueue {
    fn new(n: usize) -> Self {
        Self {
            key: vec![f64::INFINITY; n],
        }
    }
    fn key(&self, i: usize) -> f64 {
        self.key[i]
    }
    fn update(&mut self, i: usize, time: f64) {
        self.key[i] = time;
    }
    fn memory(&self) -> Vec<(&'static str, usize)> {
        vec![("queue.key", vec_bytes(&self.key))]
    }
    /// First index with the smallest key (strict `<`: ties go to the smaller index, as in the
    /// heap).
    fn min(&mut self) -> Option<(usize, f64)> {
        let mut best: Option<(usize, f64)> = None;
        for (i, &k) in self.key.iter().enumerate() {
            if best.is_none_or(|(_, b)| k < b) {
                best = Some((i, k));
            }
        }
        best
    }
}

/// The queues against each other: the calendar queue and the heap against the naive scan under
/// random updates, and the calendar queue's own edge cases.
#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::event_driven::queue::CalendarQueue;
    use rand::{Rng, SeedableRng};

    /// Random updates on `Q` and on the naive queue; the two must pop the same particle with
    /// the same key after every update.
    fn agrees_with_naive_queue<Q: EventQueue>(
        n: usize,
        seed: u64,
        draw: impl Fn(usize, &mut rand_xoshiro::Xoshiro256PlusPlus) -> f64,
    ) {
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(seed);
        let (mut q, mut r) = (Q::new(n), NaiveQueue::new(n));
        for step in 0..200_000 {
            let i = rng.gen_range(0..n);
            let t = draw(step, &mut rng);
            q.update(i, t);
            r.update(i, t);
            let (qi, qt) = q.min().unwrap();
            let (ri, rt) = r.min().unwrap();
            assert_eq!(qt, rt, "step {step}");
            // Same tie-break: the same particle, so engines on either queue agree bitwise.
            assert_eq!(qi, ri, "step {step}");
            assert_eq!(q.key(qi), qt);
        }
    }

    /// Mix of increases, decreases, repeated values and infinities.
    fn mixed(step: usize, rng: &mut rand_xoshiro::Xoshiro256PlusPlus) -> f64 {
        match step % 7 {
            0 => f64::INFINITY,
            1 => (rng.gen_range(0..50) as f64) * 0.5,
            _ => rng.gen_range(0.0..100.0),
        }
    }

    #[test]
    fn heap_agrees_with_naive_queue_under_random_updates() {
        agrees_with_naive_queue::<HeapQueue>(257, 3, mixed);
    }

    #[test]
    fn calendar_agrees_with_naive_queue_under_random_updates() {
        agrees_with_naive_queue::<CalendarQueue>(257, 3, mixed);
        // A clock that advances like an engine's, with keys spread over many decades ahead of
        // it (a year of buckets without a due entry, saturated buckets), exact ties, keys in
        // the past and 0.
        let clock = std::cell::Cell::new(0.0f64);
        agrees_with_naive_queue::<CalendarQueue>(100, 5, |step, rng| {
            clock.set(clock.get() + 1e-3);
            let now = clock.get();
            match step % 11 {
                0 => f64::INFINITY,
                1 => now + 10f64.powi(rng.gen_range(-8..12)),
                2 => now.floor(),
                3 => 0.0,
                4 => now - 1e-12,
                5 => 1e300,
                _ => now + rng.gen_range(0.0..1.0),
            }
        });
        // Every key infinite, then one finite.
        let mut q = CalendarQueue::new(3);
        assert_eq!(q.min(), Some((0, f64::INFINITY)));
        q.update(2, 5.0);
        assert_eq!(q.min(), Some((2, 5.0)));
        assert_eq!(CalendarQueue::new(0).min(), None);
    }

    #[test]
    fn calendar_jumps_over_a_long_gap_instead_of_walking_it() {
        // Width 0.1 from keys 0.1..0.4, then every key moved 10^15 ahead: 10^16 empty buckets to
        // walk without the jump (the thread would not finish), one year of 4 lists with it.
        let (done, finished) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            let mut q = CalendarQueue::new(4);
            for i in 0..4 {
                q.update(i, 0.1 * (i + 1) as f64);
            }
            assert_eq!(q.min(), Some((0, 0.1)));
            for i in (0..4).rev() {
                q.update(i, 1e15 + i as f64);
            }
            let first = q.min();
            q.update(0, f64::INFINITY);
            let _ = done.send((first, q.min()));
        });
        let got = finished
            .recv_timeout(std::time::Duration::from_secs(20))
            .expect("the calendar queue walked the gap bucket by bucket");
        assert_eq!(got, (Some((0, 1e15)), Some((1, 1e15 + 1.0))));
    }
}
