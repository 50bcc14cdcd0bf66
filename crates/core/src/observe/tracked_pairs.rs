//! The location-change counter's per-pair records (MODEL.md 7, the hysteresis of
//! [`super::location_changes::compare`]) kept between samples and updated only for the pairs
//! whose Delaunay edge appeared or disappeared ([`super::pair_edges`]), instead of listing,
//! sorting and comparing every edge at every sample.
//!
//! `compare` turns the current edges `E` and the tracked pairs `P` of the previous sample into
//! the new tracked pairs `P' = (E ∩ P) ∪ S ∪ F`: every new edge `ab` in `E \ P` either counts
//! (`F`, tracked from now on; counted when at most `max_edge` long) or, where it replaced a
//! tracked edge `cd` by an indecisive flip (`pi - (angle_c + angle_d) <= margin`), leaves `cd`
//! tracked in its place (`S`). Here the same result is kept as three sets:
//!
//! - `tracked` = `P`;
//! - `pending` = `E \ P`: edges held back by the hysteresis (their `cd` stays tracked);
//! - `stale` = `P \ E`: tracked pairs that are no edge (the `cd` kept for them).
//!
//! With `changed` the pairs whose membership in `E` changed since the last sample,
//! `E' \ P ⊆ changed ∪ pending` (an edge not new since the last sample and not tracked was
//! pending) and `P \ E' ⊆ changed ∪ stale`, so one sample costs the number of changes, not the
//! number of edges. The decisions read the previous `P` only, as `compare` does, and the count
//! does not depend on the order the pairs are visited in.

use super::location_changes::Edge;
use super::pair_edges::{PairKey, PairSet, pair_key};

/// The tracked pairs and the two difference sets (module header).
#[derive(Debug, Clone, Default)]
pub struct TrackedPairs {
    tracked: PairSet,
    pending: Vec<PairKey>,
    stale: Vec<PairKey>,
    // Scratch lists reused between samples.
    candidates: Vec<PairKey>,
    substitutes: Vec<PairKey>,
    fresh_pairs: Vec<PairKey>,
    held_back: Vec<PairKey>,
}

impl TrackedPairs {
    /// Starts tracking: every current edge is tracked.
    pub fn start(&mut self, current: impl Iterator<Item = PairKey>) {
        self.tracked.clear();
        self.tracked.extend(current);
        self.pending.clear();
        self.stale.clear();
    }

    /// Number of tracked pairs.
    pub fn len(&self) -> usize {
        self.tracked.len()
    }

    /// Whether nothing is tracked.
    pub fn is_empty(&self) -> bool {
        self.tracked.is_empty()
    }

    /// The tracked pairs, sorted (for tests: `compare` returns the same list).
    pub fn sorted(&self) -> Vec<(u32, u32)> {
        let mut v: Vec<(u32, u32)> = self
            .tracked
            .iter()
            .map(|&k| super::pair_edges::pair_of(k))
            .collect();
        v.sort_unstable();
        v
    }

    /// One sample. `changed`: the pairs whose edge may have appeared or disappeared since the
    /// last sample (duplicates allowed); `is_edge`: whether a pair is an edge now; `edge_of`:
    /// the edge of a pair that is one (its shortest copy, with the vertices opposite it).
    /// Returns the location changes (the new edges that count), as `compare` would.
    pub fn advance(
        &mut self,
        changed: &[PairKey],
        is_edge: impl Fn(PairKey) -> bool,
        mut edge_of: impl FnMut(PairKey) -> Edge,
        max_edge: f64,
        margin: f64,
    ) -> Vec<Edge> {
        // E' \ P: changed or pending pairs that are edges now and not tracked.
        self.candidates.clear();
        self.candidates
            .extend(changed.iter().chain(&self.pending).copied());
        self.candidates.sort_unstable();
        self.candidates.dedup();
        let tracked = &self.tracked;
        self.candidates
            .retain(|&k| is_edge(k) && !tracked.contains(&k));
        let mut fresh = Vec::new();
        self.substitutes.clear();
        self.fresh_pairs.clear();
        self.held_back.clear();
        for &k in &self.candidates {
            let e = edge_of(k);
            if let Some((c, d, sum)) = e.opposite {
                let old = pair_key(c, d);
                if c != d && tracked.contains(&old) && std::f64::consts::PI - sum <= margin {
                    self.substitutes.push(old);
                    self.held_back.push(k);
                    continue;
                }
            }
            self.fresh_pairs.push(k);
            if e.length <= max_edge {
                fresh.push(e);
            }
        }
        self.substitutes.sort_unstable();
        self.substitutes.dedup();
        // P \ (E' ∪ S): tracked pairs that are no edge any more and were kept for no new edge.
        let substitutes = &self.substitutes;
        let mut dropped: Vec<PairKey> = changed
            .iter()
            .chain(&self.stale)
            .copied()
            .filter(|&k| {
                !is_edge(k) && tracked.contains(&k) && substitutes.binary_search(&k).is_err()
            })
            .collect();
        dropped.sort_unstable();
        dropped.dedup();
        for k in dropped {
            self.tracked.remove(&k);
        }
        self.tracked.extend(self.fresh_pairs.iter().copied());
        // The new difference sets: E' \ P' (the held-back edges), P' \ E' (substitutes that
        // are no edge).
        std::mem::swap(&mut self.pending, &mut self.held_back);
        self.stale.clear();
        self.stale
            .extend(self.substitutes.iter().copied().filter(|&k| !is_edge(k)));
        fresh
    }
}
