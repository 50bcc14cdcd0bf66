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

    fn sift_up(&mut self, mut s: usize) {
        let entry = self.heap[s];
        while s > 0 {
            let parent = (s - 1) / ARITY;
            let p = self.heap[parent];
            if Self::less(entry, p) {
                self.heap[s] = p;
                self.slot[p.1 as usize] = s as u32;
                s = parent;
            } else {
                break;
            }
        }
        self.heap[s] = entry;
        self.slot[entry.1 as usize] = s as u32;
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
                self.heap[s] = c;
                self.slot[c.1 as usize] = s as u32;
                s = child;
            } else {
                break;
            }
        }
        self.heap[s] = entry;
        self.slot[entry.1 as usize] = s as u32;
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
