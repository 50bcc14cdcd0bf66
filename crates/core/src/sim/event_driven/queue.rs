//! The event queue: one entry per particle, keyed by the time of that particle's earliest
//! predicted event, behind the [`EventQueue`] trait so that an engine runs on any
//! implementation (`Engine<.., Q: EventQueue>`, monomorphised: no dynamic dispatch in the loop).
//!
//! Re-predicting a particle changes its key in place, so a queue never holds stale copies
//! (invalid events are detected lazily, see `engine.rs`). [`CalendarQueue`] is the engines' queue;
//! the tests run whole engines on a linear scan too (`wetgran_testkit::NaiveQueue`,
//! `crates/core/tests/engine_pins.rs`). Both break ties of equal keys by the smaller particle
//! index, so the trajectory does not depend on the queue.

/// A priority queue over particles `0..n` with one key (event time) each.
pub trait EventQueue: Clone + std::fmt::Debug {
    /// A queue for particles `0..n`, all with key `+inf`.
    fn new(n: usize) -> Self;
    /// The particle with the earliest key (the smallest index among equal keys) and that key
    /// (`&mut`: a queue may move its cursor or re-tune itself on the way).
    fn min(&mut self) -> Option<(usize, f64)>;
    fn key(&self, i: usize) -> f64;
    fn update(&mut self, i: usize, time: f64);
    /// Heap bytes of the queue's arrays, by name (`wetgran-bench memory`).
    fn memory(&self) -> Vec<(&'static str, usize)>;
}

/// Pops between two re-estimations of the bucket width, per particle (8 executes fewer
/// instructions than 2 on all four reference systems: docs/performance.md, "Ideas kept and
/// rejected").
const CALENDAR_RETUNE_PER_PARTICLE: u64 = 8;
/// Keys sampled to estimate the width.
const CALENDAR_SAMPLE: usize = 512;
/// Bucket width in units of `(median sampled key - smallest key) / finite keys`: about
/// `WIDTH_FACTOR ln 2 ~ 1.4` keys per bucket near the front for exponentially spread keys.
const WIDTH_FACTOR: f64 = 2.0;

/// Calendar queue (R. Brown, Commun. ACM 31, 1220 (1988)) over particle indices. The key `t`
/// lies in the virtual bucket `floor(t / w)`, stored in list `floor(t / w) mod 2^k` (a "year"
/// of `2^k >= N` doubly linked lists). Infinite keys are in no list.
///
/// Order: `floor(t / w)` is monotone in `t`, so `min` walks the virtual buckets from the cursor
/// `cur` (no finite key lies before it) and takes the smallest `(key, index)` of the first
/// bucket that has a due entry: ties go to the smaller index as in the reference queue. The
/// width only changes how much is walked, never the answer: every `8 N` pops it is
/// re-estimated from a sample of the keys; after a year without a due entry the cursor jumps.
///
/// Every list ends in one sentinel node `n` (key `+inf`, linked to itself), so linking and
/// unlinking need no end-of-list test. The walk keeps its branches: a branch-free walk took more
/// CPU time (docs/performance.md, "Ideas kept and rejected").
#[derive(Debug, Clone)]
pub struct CalendarQueue {
    /// Keys of the particles `0..n`, then the sentinel's `+inf`.
    key: Vec<f64>,
    /// Links over one index space: `0..n` the particles, `n` the sentinel (`next[n] = n`),
    /// `n + 1 + b` the head of list `b`; `prev[i]` is the node before particle `i`, so that it
    /// leaves its list in `O(1)` (`prev[n]` is written and never read).
    next: Vec<u32>,
    prev: Vec<u32>,
    /// `n`: the sentinel, and the number of particles.
    end: usize,
    /// `n + 1`: where the list heads start in `next`.
    heads: usize,
    /// `1 / w`.
    inv_width: f64,
    /// `2^k - 1`.
    mask: u64,
    /// The virtual bucket the walk starts from.
    cur: u64,
    /// Finite keys.
    finite: usize,
    /// Pops left before the next re-estimation (the first `min` estimates at once).
    until_retune: u64,
}

impl CalendarQueue {
    /// Virtual bucket of key `t` (keys below 0 share bucket 0, huge ones saturate).
    #[inline(always)]
    fn bucket(&self, t: f64) -> u64 {
        (t * self.inv_width) as u64
    }

    /// Puts `i` (key `t`, finite) at the front of its list; returns its virtual bucket.
    #[inline(always)]
    fn link(&mut self, i: usize, t: f64) -> u64 {
        let bucket = self.bucket(t);
        let head = self.heads + (bucket & self.mask) as usize;
        let first = self.next[head];
        self.next[i] = first;
        self.prev[i] = head as u32;
        self.prev[first as usize] = i as u32;
        self.next[head] = i as u32;
        bucket
    }

    /// Takes `i` out of its list.
    #[inline(always)]
    fn unlink(&mut self, i: usize) {
        let (before, after) = (self.prev[i], self.next[i]);
        self.next[before as usize] = after;
        self.prev[after as usize] = before;
    }

    /// The smallest finite key and a new bucket width from a sample of the keys; relinks every
    /// entry and puts the cursor on the smallest key's bucket.
    fn retune(&mut self) {
        let n = self.end;
        self.until_retune = (CALENDAR_RETUNE_PER_PARTICLE * n as u64).max(1024);
        let lo = self.key[..n].iter().copied().fold(f64::INFINITY, f64::min);
        if !lo.is_finite() {
            return;
        }
        let stride = (n / CALENDAR_SAMPLE).max(1);
        let mut sample: Vec<f64> = self.key[..n]
            .iter()
            .step_by(stride)
            .copied()
            .filter(|t| t.is_finite())
            .collect();
        let spread = if sample.is_empty() {
            0.0
        } else {
            let mid = sample.len() / 2;
            let (_, m, _) = sample.select_nth_unstable_by(mid, f64::total_cmp);
            *m - lo
        };
        let width = WIDTH_FACTOR * spread / self.finite.max(1) as f64;
        // A width of 0 (all keys equal) or one too small for the keys' magnitude keeps the old
        // one; the order never depends on it.
        if width.is_finite() && width > 1e-12 * lo.abs() && width > 0.0 {
            self.inv_width = 1.0 / width;
        }
        self.next[n..].fill(n as u32);
        for i in 0..n {
            let t = self.key[i];
            if t.is_finite() {
                self.link(i, t);
            }
        }
        self.cur = self.bucket(lo);
    }
    /// `min` when no key is finite (the first particle, as in the other queues; `None` for
    /// no particle) or a re-estimation of the width is due.
    #[cold]
    #[inline(never)]
    fn min_rare(&mut self) -> Option<(usize, f64)> {
        if self.end == 0 {
            return None;
        }
        if self.finite == 0 {
            return Some((0, self.key[0]));
        }
        self.retune();
        self.until_retune -= 1;
        self.walk_a_year().or_else(|| self.min_after_empty_year())
    }

    /// Walks at most one year of virtual buckets from the cursor and returns the smallest
    /// `(key, index)` of the first bucket holding a due entry, the cursor left on it.
    #[inline(always)]
    fn walk_a_year(&mut self) -> Option<(usize, f64)> {
        let end_node = self.end as u32;
        for _ in 0..=self.mask {
            let list = (self.cur & self.mask) as usize;
            // An entry of this list is due iff its virtual bucket is `cur` (none is earlier),
            // i.e. iff `t / w < cur + 1` before truncation: one product and one compare,
            // exact while `cur + 1` is an integer an f64 holds exactly.
            let exact = self.cur < (1 << 52);
            let end = (self.cur + 1) as f64;
            let cur = self.cur;
            let inv_width = self.inv_width;
            let due = |t: f64| {
                if exact {
                    t * inv_width < end
                } else {
                    (t * inv_width) as u64 == cur
                }
            };
            // The smallest `(key, index)` among the due entries.
            let mut k = self.next[self.heads + list];
            let mut best = end_node;
            let mut best_t = f64::INFINITY;
            while k != end_node {
                let t = self.key[k as usize];
                if due(t) && (best == end_node || t < best_t || (t == best_t && k < best)) {
                    best = k;
                    best_t = t;
                }
                k = self.next[k as usize];
            }
            if best != end_node {
                return Some((best as usize, best_t));
            }
            self.cur = self.cur.saturating_add(1);
        }
        None
    }

    /// A year without a due entry: jump to the smallest key's bucket (without the jump the
    /// walk would take `(gap / w)` steps), walk from there, and re-estimate the width at the
    /// next pop.
    #[cold]
    #[inline(never)]
    fn min_after_empty_year(&mut self) -> Option<(usize, f64)> {
        loop {
            let lo = self.key[..self.end]
                .iter()
                .copied()
                .fold(f64::INFINITY, f64::min);
            self.cur = self.bucket(lo);
            self.until_retune = 1;
            if let Some(found) = self.walk_a_year() {
                return Some(found);
            }
        }
    }
}

impl EventQueue for CalendarQueue {
    fn new(n: usize) -> Self {
        let lists = n.max(1).next_power_of_two();
        Self {
            key: vec![f64::INFINITY; n + 1],
            next: vec![n as u32; n + 1 + lists],
            prev: vec![n as u32; n + 1],
            end: n,
            heads: n + 1,
            inv_width: 1.0,
            mask: lists as u64 - 1,
            cur: 0,
            finite: 0,
            until_retune: 0,
        }
    }

    #[inline]
    fn key(&self, i: usize) -> f64 {
        self.key[i]
    }

    #[inline]
    fn update(&mut self, i: usize, time: f64) {
        let old = self.key[i];
        if old.is_finite() {
            self.unlink(i);
            self.finite -= 1;
        }
        self.key[i] = time;
        if time.is_finite() {
            let b = self.link(i, time);
            self.finite += 1;
            if b < self.cur {
                self.cur = b;
            }
        }
    }

    /// The walk from the cursor, inlined; the rare cases are out of line.
    #[inline]
    fn min(&mut self) -> Option<(usize, f64)> {
        if self.finite == 0 || self.until_retune == 0 {
            return self.min_rare();
        }
        self.until_retune -= 1;
        self.walk_a_year().or_else(|| self.min_after_empty_year())
    }

    fn memory(&self) -> Vec<(&'static str, usize)> {
        use super::bodies::vec_bytes;
        vec![
            ("queue.key", vec_bytes(&self.key)),
            ("queue.next (per particle and list)", vec_bytes(&self.next)),
            ("queue.prev", vec_bytes(&self.prev)),
        ]
    }
}
