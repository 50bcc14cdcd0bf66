//! The event queue: an indexed binary min-heap with exactly one entry per particle, keyed by the
//! time of that particle's earliest predicted event.
//!
//! Re-predicting a particle changes its key in place (`O(log N)`), so the queue never holds
//! stale copies; events that became invalid through a partner's collision are detected lazily
//! with per-particle event counters (see `engine.rs`). [`NaiveQueue`] is the reference
//! implementation the tests compare against.

const NONE: u32 = u32::MAX;

/// Indexed binary min-heap over particle indices.
#[derive(Debug, Clone)]
pub struct EventQueue {
    heap: Vec<u32>,
    slot: Vec<u32>,
    key: Vec<f64>,
}

impl EventQueue {
    /// A queue for particles `0..n`, all with key `+inf`.
    pub fn new(n: usize) -> Self {
        Self {
            heap: (0..n as u32).collect(),
            slot: (0..n as u32).collect(),
            key: vec![f64::INFINITY; n],
        }
    }

    /// The particle with the earliest event and its time.
    #[inline]
    pub fn min(&self) -> Option<(usize, f64)> {
        self.heap.first().map(|&i| (i as usize, self.key[i as usize]))
    }

    /// The key of particle `i`.
    #[inline]
    pub fn key(&self, i: usize) -> f64 {
        self.key[i]
    }

    /// Sets the key of particle `i` and restores the heap order.
    #[inline]
    pub fn update(&mut self, i: usize, time: f64) {
        let old = self.key[i];
        self.key[i] = time;
        let s = self.slot[i] as usize;
        debug_assert!(s != NONE as usize);
        if time < old {
            self.sift_up(s);
        } else {
            self.sift_down(s);
        }
    }

    #[inline]
    fn less(&self, a: usize, b: usize) -> bool {
        // Ties broken by particle index so the order is deterministic.
        let (ia, ib) = (self.heap[a] as usize, self.heap[b] as usize);
        let (ka, kb) = (self.key[ia], self.key[ib]);
        ka < kb || (ka == kb && ia < ib)
    }

    #[inline]
    fn swap(&mut self, a: usize, b: usize) {
        self.heap.swap(a, b);
        self.slot[self.heap[a] as usize] = a as u32;
        self.slot[self.heap[b] as usize] = b as u32;
    }

    fn sift_up(&mut self, mut s: usize) {
        while s > 0 {
            let parent = (s - 1) / 2;
            if self.less(s, parent) {
                self.swap(s, parent);
                s = parent;
            } else {
                break;
            }
        }
    }

    fn sift_down(&mut self, mut s: usize) {
        let n = self.heap.len();
        loop {
            let l = 2 * s + 1;
            if l >= n {
                break;
            }
            let r = l + 1;
            let child = if r < n && self.less(r, l) { r } else { l };
            if self.less(child, s) {
                self.swap(s, child);
                s = child;
            } else {
                break;
            }
        }
    }
}

/// Reference queue: a linear scan. Slow, obviously correct; used to test [`EventQueue`].
#[derive(Debug, Clone)]
pub struct NaiveQueue {
    key: Vec<f64>,
}

impl NaiveQueue {
    pub fn new(n: usize) -> Self {
        Self { key: vec![f64::INFINITY; n] }
    }
    pub fn update(&mut self, i: usize, time: f64) {
        self.key[i] = time;
    }
    pub fn min(&self) -> Option<(usize, f64)> {
        let mut best: Option<(usize, f64)> = None;
        for (i, &k) in self.key.iter().enumerate() {
            if best.is_none_or(|(_, b)| k < b) {
                best = Some((i, k));
            }
        }
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    #[test]
    fn agrees_with_naive_queue_under_random_updates() {
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(3);
        let n = 257;
        let (mut q, mut r) = (EventQueue::new(n), NaiveQueue::new(n));
        for step in 0..200_000 {
            let i = rng.gen_range(0..n);
            // Mix of increases, decreases, repeated values and infinities.
            let t = match step % 7 {
                0 => f64::INFINITY,
                1 => (rng.gen_range(0..50) as f64) * 0.5,
                _ => rng.gen_range(0.0..100.0),
            };
            q.update(i, t);
            r.update(i, t);
            let (qi, qt) = q.min().unwrap();
            let (_, rt) = r.min().unwrap();
            assert_eq!(qt, rt, "step {step}");
            assert_eq!(q.key(qi), qt);
        }
    }
}
