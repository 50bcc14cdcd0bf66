//! A bounded cache of the `table` wall solver's tables ([`WallTable`], docs/model.md 6, B.4-B.5):
//! one table per `(wall motion, table spec)`, built on first use, shared by every engine that
//! asks for it, and evicted least recently used first once the cached tables exceed a size cap
//! (a table larger than the cap is not cached). An engine gets its cache from its caller (the
//! sweep runner shares one among the jobs of a run); who holds which cache, and what the cap
//! bounds: ARCHITECTURE.md, "Wall tables".

use crate::physics::shaken_wall::WallMotion;
use crate::physics::wall_table::{TableSpec, WallTable};
use std::collections::HashMap;
use std::sync::{Arc, Mutex};

/// Default cap of a table cache, in MiB (2^20 bytes).
pub const DEFAULT_TABLE_CACHE_MIB: usize = 256;

/// Key of a cached table: the bit patterns of the motion and the spec.
type TableKey = [u64; 8];

fn table_key(w: &WallMotion, s: &TableSpec) -> TableKey {
    [
        w.amplitude.to_bits(),
        w.omega.to_bits(),
        w.g.to_bits(),
        s.phase_cells as u64,
        s.velocity_cells as u64,
        s.v_min.to_bits(),
        s.v_max.to_bits(),
        s.corner_tolerance.map_or(u64::MAX, f64::to_bits),
    ]
}

#[derive(Debug, Default)]
struct Entries {
    /// Table and the tick of its last use.
    map: HashMap<TableKey, (Arc<WallTable>, u64)>,
    bytes: usize,
    /// Use counter (the recency order).
    tick: u64,
    /// Tables built by this cache (a measure of what eviction cost).
    builds: u64,
    /// Largest `bytes` ever held.
    peak: usize,
}

impl Entries {
    /// The cached table of `key`, if any, marked as used now.
    fn touch(&mut self, key: &TableKey) -> Option<Arc<WallTable>> {
        self.tick += 1;
        let tick = self.tick;
        self.map.get_mut(key).map(|(t, used)| {
            *used = tick;
            Arc::clone(t)
        })
    }
}

/// A bounded, thread-safe cache of wall tables (least recently used out first). Cloning gives
/// another handle to the same cache.
#[derive(Debug, Clone)]
pub struct TableCache {
    cap: usize,
    entries: Arc<Mutex<Entries>>,
}

impl TableCache {
    /// An empty cache that keeps at most `cap_bytes` of tables.
    pub fn new(cap_bytes: usize) -> Self {
        Self {
            cap: cap_bytes,
            entries: Arc::new(Mutex::new(Entries::default())),
        }
    }

    pub fn with_cap_mib(mib: usize) -> Self {
        Self::new(mib.saturating_mul(1 << 20))
    }

    pub fn cap(&self) -> usize {
        self.cap
    }

    pub fn bytes(&self) -> usize {
        self.lock().bytes
    }

    /// Largest number of bytes held at any time.
    pub fn peak_bytes(&self) -> usize {
        self.lock().peak
    }

    pub fn len(&self) -> usize {
        self.lock().map.len()
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Tables built through this cache so far.
    pub fn builds(&self) -> u64 {
        self.lock().builds
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Entries> {
        // Every update leaves the map consistent, so a poisoned lock is still usable.
        self.entries.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// The table for `(motion, spec)`: the cached one, or a new one (built outside the lock:
    /// two threads may build the same table once each; the first one cached is kept).
    pub fn get(&self, motion: WallMotion, spec: TableSpec) -> Arc<WallTable> {
        let key = table_key(&motion, &spec);
        if let Some(t) = self.lock().touch(&key) {
            return t;
        }
        let table = Arc::new(WallTable::build(motion, spec));
        let size = table.bytes();
        let mut e = self.lock();
        e.builds += 1;
        if size > self.cap {
            return table;
        }
        if let Some(t) = e.touch(&key) {
            return t;
        }
        let tick = e.tick;
        e.map.insert(key, (Arc::clone(&table), tick));
        e.bytes += size;
        while e.bytes > self.cap {
            let oldest = e
                .map
                .iter()
                .filter(|(k, _)| **k != key)
                .min_by_key(|(_, (_, used))| *used)
                .map(|(k, _)| *k);
            let Some(k) = oldest else { break };
            let (t, _) = e.map.remove(&k).expect("key just found");
            e.bytes -= t.bytes();
        }
        e.peak = e.peak.max(e.bytes);
        table
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::wall_table::tests::{spec_for as spec, standard_motion as motion};

    #[test]
    fn one_table_per_drive_is_shared_across_threads() {
        let cache = TableCache::with_cap_mib(64);
        let w = motion(3.0, 2.0);
        let s = spec(&w, 16);
        let handles: Vec<_> = (0..4)
            .map(|_| {
                let c = cache.clone();
                std::thread::spawn(move || c.get(w, s))
            })
            .collect();
        let tables: Vec<Arc<WallTable>> = handles.into_iter().map(|h| h.join().unwrap()).collect();
        assert!(tables.iter().all(|t| Arc::ptr_eq(t, &tables[0])));
        // Another drive or resolution is another table.
        let other = cache.get(WallMotion { g: -1.0, ..w }, s);
        assert!(!Arc::ptr_eq(&other, &tables[0]));
        let finer = cache.get(w, spec(&w, 20));
        assert!(!Arc::ptr_eq(&finer, &tables[0]));
        assert_eq!(cache.len(), 3);
        assert!(Arc::ptr_eq(&cache.get(w, s), &tables[0]));
    }

    #[test]
    fn a_sweep_over_many_drives_stays_under_the_cap() {
        // Room for three tables of this resolution, then forty drives (a small (Gamma, E*)
        // grid) asked for in turn, each twice (floor, then again as a replica would).
        let one = WallTable::build(motion(2.0, 1.0), spec(&motion(2.0, 1.0), 12)).bytes();
        let cache = TableCache::new(3 * one + one / 2);
        let mut drives = 0;
        for gamma in [1.5, 2.0, 3.0, 4.0, 5.0, 6.0, 8.0, 10.0] {
            for e_star in [0.5, 1.0, 2.0, 5.0, 10.0] {
                let w = motion(gamma, e_star);
                let a = cache.get(w, spec(&w, 12));
                assert_eq!(
                    a.bytes(),
                    one,
                    "every table of this resolution has one size"
                );
                let b = cache.get(w, spec(&w, 12));
                assert!(Arc::ptr_eq(&a, &b), "a table just used is kept");
                assert!(
                    cache.bytes() <= cache.cap(),
                    "{} > {}",
                    cache.bytes(),
                    cache.cap()
                );
                drives += 1;
            }
        }
        assert_eq!(drives, 40);
        assert_eq!(cache.len(), 3, "the cache stays full, not emptier");
        assert!(cache.peak_bytes() <= cache.cap());
        assert_eq!(cache.builds(), 40, "each drive built once");
        // Least recently used out first: the last three drives are still there, the first not.
        let last = motion(10.0, 10.0);
        let kept = cache.get(last, spec(&last, 12));
        assert_eq!(cache.builds(), 40);
        drop(kept);
        let first = motion(1.5, 0.5);
        let _ = cache.get(first, spec(&first, 12));
        assert_eq!(cache.builds(), 41);
        assert!(cache.bytes() <= cache.cap());
    }

    #[test]
    fn recently_used_tables_survive_eviction() {
        let w = |g: f64| motion(g, 2.0);
        let one = WallTable::build(w(2.0), spec(&w(2.0), 10)).bytes();
        let cache = TableCache::new(2 * one);
        let _ = cache.get(w(2.0), spec(&w(2.0), 10));
        let _ = cache.get(w(3.0), spec(&w(3.0), 10));
        // Touch the first: the second is now the least recently used and goes.
        let _ = cache.get(w(2.0), spec(&w(2.0), 10));
        let _ = cache.get(w(4.0), spec(&w(4.0), 10));
        assert_eq!(cache.builds(), 3);
        let _ = cache.get(w(2.0), spec(&w(2.0), 10));
        assert_eq!(cache.builds(), 3, "the recently used table was kept");
        let _ = cache.get(w(3.0), spec(&w(3.0), 10));
        assert_eq!(
            cache.builds(),
            4,
            "the least recently used table was evicted"
        );
    }

    #[test]
    fn a_cap_of_zero_caches_nothing() {
        let cache = TableCache::new(0);
        let w = motion(3.0, 2.0);
        let a = cache.get(w, spec(&w, 8));
        let b = cache.get(w, spec(&w, 8));
        assert!(!Arc::ptr_eq(&a, &b));
        assert!(cache.is_empty());
        assert_eq!(cache.builds(), 2);
    }
}
