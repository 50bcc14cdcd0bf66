//! The reference event queue: a linear scan ([`NaiveQueue`]) implementing [`EventQueue`] with
//! ties broken by the smaller particle index, so that an engine takes the same trajectory on it
//! as on the calendar queue (`crates/core/tests/engine_pins.rs`, `event_queues.rs`).

use wetgran_core::sim::event_driven::queue::EventQueue;

/// Reference queue: a linear scan over the keys, `O(N)` per pop. Slow, obviously correct; the
/// tests run engines on it to check the calendar queue.
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
        vec![(
            "queue.key",
            self.key.capacity() * std::mem::size_of::<f64>(),
        )]
    }
    /// First index with the smallest key (strict `<`: ties go to the smaller index).
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
