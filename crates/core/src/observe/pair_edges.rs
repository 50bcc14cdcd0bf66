//! The particle pairs joined by Delaunay edges, kept with the triangulation
//! ([`super::kinetic_delaunay`]) and changed edge by edge: a flip removes one edge and adds
//! one, an inserted site adds its edges, a deleted one removes them, a rebuild is diffed
//! against the set kept. A pair can be joined through several periodic images, so each pair
//! holds the number of site edges (copies) that join it; it is an edge while that number is
//! positive. The pairs whose membership changed since the last
//! [`take_changed`](PairEdges::take_changed) are listed (each once, with its membership before
//! the first change, so that a pair that left and came back, as the edges of a relocated site
//! mostly do, is not listed), so that the location-change counter ([`super::tracked_pairs`])
//! looks at those only.

use std::collections::{HashMap, HashSet};
use std::hash::{BuildHasherDefault, Hasher};

/// A particle pair `i < j` as one key: `i << 32 | j`.
pub type PairKey = u64;

/// The key of the pair `{i, j}`.
#[inline]
pub fn pair_key(i: u32, j: u32) -> PairKey {
    let (a, b) = if i < j { (i, j) } else { (j, i) };
    ((a as u64) << 32) | b as u64
}

/// The pair `(i, j)`, `i < j`, of a key.
#[inline]
pub fn pair_of(key: PairKey) -> (u32, u32) {
    ((key >> 32) as u32, key as u32)
}

/// Hashes a [`PairKey`] by one multiplication (Fibonacci hashing): the keys are already
/// well spread integers and the default SipHash would cost more than the rest of an update.
#[derive(Debug, Default, Clone, Copy)]
pub struct PairHasher(u64);

impl Hasher for PairHasher {
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0.rotate_left(8) ^ b as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15);
        }
    }

    #[inline]
    fn write_u64(&mut self, x: u64) {
        self.0 = (x ^ (x >> 32)).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    }

    #[inline]
    fn finish(&self) -> u64 {
        self.0 ^ (self.0 >> 29)
    }
}

/// A hash map keyed by pairs.
pub type PairMap<V> = HashMap<PairKey, V, BuildHasherDefault<PairHasher>>;
/// A hash set of pairs.
pub type PairSet = HashSet<PairKey, BuildHasherDefault<PairHasher>>;

/// The pairs joined by edges, with their number of copies, and the pairs changed since the
/// last look.
#[derive(Debug, Clone, Default)]
pub struct PairEdges {
    copies: PairMap<u32>,
    /// Each pair whose membership changed since the last look, with its membership then (the
    /// first change records it; a pair that left and came back is dropped at the look).
    changed: PairMap<bool>,
    /// The pairs a rebuild's diff changed while `changed` was empty (nothing else changed since
    /// the last look): listed as they are, without a map entry each; moved into `changed`
    /// before any further change.
    diffed: Vec<PairKey>,
    /// A copy was removed that was not there: the bookkeeping is wrong (a bug), and the owner
    /// must rebuild and [`replace_all`](Self::replace_all).
    broken: bool,
}

impl PairEdges {
    /// One more copy of `key`.
    #[inline]
    pub fn add(&mut self, key: PairKey) {
        self.settle_diff();
        let c = self.copies.entry(key).or_insert(0);
        *c += 1;
        if *c == 1 {
            self.changed.entry(key).or_insert(false);
        }
    }

    /// One copy of `key` less.
    #[inline]
    pub fn remove(&mut self, key: PairKey) {
        self.settle_diff();
        match self.copies.get_mut(&key) {
            Some(c) if *c > 1 => *c -= 1,
            Some(_) => {
                self.copies.remove(&key);
                self.changed.entry(key).or_insert(true);
            }
            None => self.broken = true,
        }
    }

    /// Moves the pairs of a rebuild's diff into `changed` (each with its membership before the
    /// diff, the opposite of now), before a further change.
    #[inline]
    fn settle_diff(&mut self) {
        if self.diffed.is_empty() {
            return;
        }
        for k in std::mem::take(&mut self.diffed) {
            let now = self.copies.contains_key(&k);
            self.changed.insert(k, !now);
        }
    }

    /// Whether the pair is joined by at least one edge.
    #[inline]
    pub fn contains(&self, key: PairKey) -> bool {
        self.copies.contains_key(&key)
    }

    /// Number of pairs joined.
    pub fn len(&self) -> usize {
        self.copies.len()
    }

    /// Whether no pair is joined.
    pub fn is_empty(&self) -> bool {
        self.copies.is_empty()
    }

    /// The pairs joined, in no particular order.
    pub fn keys(&self) -> impl Iterator<Item = PairKey> + '_ {
        self.copies.keys().copied()
    }

    /// The copies per pair.
    pub fn copies(&self) -> &PairMap<u32> {
        &self.copies
    }

    /// Whether a removal found no copy (see [`PairEdges::replace_all`]).
    pub fn is_broken(&self) -> bool {
        self.broken
    }

    /// Replaces the whole set (after a rebuild): the pairs that appear or disappear are listed
    /// as changed (a hash diff, linear in the number of pairs).
    pub fn replace_all(&mut self, new: PairMap<u32>) {
        self.settle_diff();
        if self.changed.is_empty() {
            // Nothing changed since the last look: the diff is the exact list.
            self.diffed
                .extend(self.copies.keys().filter(|k| !new.contains_key(k)));
            self.diffed
                .extend(new.keys().filter(|k| !self.copies.contains_key(k)));
            self.copies = new;
            self.broken = false;
            return;
        }
        for k in self.copies.keys() {
            if !new.contains_key(k) {
                self.changed.entry(*k).or_insert(true);
            }
        }
        for k in new.keys() {
            if !self.copies.contains_key(k) {
                self.changed.entry(*k).or_insert(false);
            }
        }
        self.copies = new;
        self.broken = false;
    }

    /// The pairs whose membership changed since the last call (each once; a pair that left
    /// and came back is not listed), in `out` (cleared first), in no particular order.
    pub fn take_changed(&mut self, out: &mut Vec<PairKey>) {
        out.clear();
        out.append(&mut self.diffed);
        let copies = &self.copies;
        out.extend(
            self.changed
                .drain()
                .filter(|&(k, before)| copies.contains_key(&k) != before)
                .map(|(k, _)| k),
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn copies_count_and_changes_are_listed() {
        let mut p = PairEdges::default();
        let k = pair_key(7, 3);
        assert_eq!(pair_of(k), (3, 7));
        p.add(k);
        p.add(k);
        p.remove(k);
        assert!(p.contains(k));
        let mut out = Vec::new();
        p.take_changed(&mut out);
        assert_eq!(out, vec![k]);
        // Left and came back: no change.
        p.remove(k);
        p.add(k);
        p.take_changed(&mut out);
        assert!(out.is_empty());
        p.remove(k);
        assert!(!p.contains(k));
        p.take_changed(&mut out);
        assert_eq!(out, vec![k]);
        assert!(!p.is_broken());
        p.remove(k);
        assert!(p.is_broken());
        let mut new = PairMap::default();
        new.insert(pair_key(1, 2), 1);
        p.replace_all(new);
        assert!(!p.is_broken());
        p.take_changed(&mut out);
        assert_eq!(out, vec![pair_key(1, 2)]);
        // A rebuild's diff, then changes before the look: (1, 2) left and came back.
        let mut new = PairMap::default();
        new.insert(pair_key(3, 4), 1);
        p.replace_all(new.clone());
        p.add(pair_key(1, 2));
        p.add(pair_key(5, 6));
        p.remove(pair_key(3, 4));
        p.take_changed(&mut out);
        assert_eq!(out, vec![pair_key(5, 6)]);
        p.replace_all(new);
        p.take_changed(&mut out);
        out.sort_unstable();
        assert_eq!(out, vec![pair_key(1, 2), pair_key(3, 4), pair_key(5, 6)]);
    }
}
