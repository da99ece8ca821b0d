//! Per-voxel label evidence: a few (label, count) slots and a hit total.

use serde::{Deserialize, Serialize};

use crate::label::LabelId;

/// Number of (label, count) slots per voxel.
pub const EVIDENCE_SLOTS: usize = 3;

/// The label evidence fused in one voxel: [`EVIDENCE_SLOTS`] (label, count)
/// slots plus the total number of points that fell in the voxel. 16 bytes.
///
/// # Eviction rule (Misra–Gries)
/// A point with label `l`:
/// * increments `l`'s slot if `l` holds one;
/// * else takes a free slot (count 0) with count 1;
/// * else (all slots busy with other labels) decrements every slot by one,
///   freeing the slots that reach zero, and is not stored itself.
///
/// This is the Misra–Gries frequent-items summary with `k = 3` counters:
/// every label seen in more than `hits / 4` of the voxel's points keeps a
/// slot, so the true majority label is always present, and each count
/// underestimates the true count by at most `hits / 4`. A count that would
/// overflow `u16` halves all counts first (ratios are kept).
///
/// The *dominant* label is the slot with the largest count (ties go to the
/// smaller label id); a voxel whose slots are all free has none.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct VoxelEvidence {
    labels: [u16; EVIDENCE_SLOTS],
    counts: [u16; EVIDENCE_SLOTS],
    hits: u32,
}

impl VoxelEvidence {
    /// A voxel that has never been hit.
    pub const EMPTY: Self = Self {
        labels: [0; EVIDENCE_SLOTS],
        counts: [0; EVIDENCE_SLOTS],
        hits: 0,
    };

    /// Total points that fell into this voxel (saturating).
    #[inline]
    pub fn hits(&self) -> u32 {
        self.hits
    }

    /// Whether any point ever fell into this voxel.
    #[inline]
    pub fn is_observed(&self) -> bool {
        self.hits > 0
    }

    /// The (label, count) slots in use, in slot order.
    pub fn evidence(&self) -> impl Iterator<Item = (LabelId, u16)> + '_ {
        self.labels
            .iter()
            .zip(self.counts.iter())
            .filter(|(_, c)| **c > 0)
            .map(|(l, c)| (LabelId(*l), *c))
    }

    /// The count held for `label` (0 when it holds no slot).
    pub fn count(&self, label: LabelId) -> u16 {
        self.evidence()
            .find(|(l, _)| *l == label)
            .map_or(0, |(_, c)| c)
    }

    /// The label with the largest count (ties: smaller id), if any slot is used.
    #[inline]
    pub fn dominant(&self) -> Option<LabelId> {
        let mut best: Option<(u16, u16)> = None; // (count, label)
        for i in 0..EVIDENCE_SLOTS {
            let c = self.counts[i];
            if c == 0 {
                continue;
            }
            let l = self.labels[i];
            best = match best {
                Some((bc, bl)) if bc > c || (bc == c && bl < l) => Some((bc, bl)),
                _ => Some((c, l)),
            };
        }
        best.map(|(_, l)| LabelId(l))
    }

    /// Adds one point with `label` (see the eviction rule) and returns the
    /// dominant label before and after.
    ///
    /// # Complexity
    /// O([`EVIDENCE_SLOTS`]).
    #[inline]
    pub fn add(&mut self, label: LabelId) -> (Option<LabelId>, Option<LabelId>) {
        self.hits = self.hits.saturating_add(1);
        let mut free = None;
        for i in 0..EVIDENCE_SLOTS {
            if self.counts[i] == 0 {
                if free.is_none() {
                    free = Some(i);
                }
            } else if self.labels[i] == label.0 {
                // Fast path: the label already dominates, so it still does.
                if self.dominates(i) {
                    self.increment(i);
                    return (Some(label), Some(label));
                }
                let before = self.dominant();
                self.increment(i);
                return (before, self.dominant());
            }
        }
        let before = self.dominant();
        match free {
            Some(i) => {
                self.labels[i] = label.0;
                self.counts[i] = 1;
            }
            None => {
                for c in &mut self.counts {
                    *c -= 1;
                }
            }
        }
        (before, self.dominant())
    }

    /// Adds `n` points with `label`: the same state as `n` calls of
    /// [`add`](Self::add), returning the dominant label before and after.
    ///
    /// # Complexity
    /// O(1) when `label` holds a slot without overflowing, else O(n).
    #[inline]
    pub(crate) fn add_n(&mut self, label: LabelId, n: u16) -> (Option<LabelId>, Option<LabelId>) {
        let slot = (0..EVIDENCE_SLOTS).find(|&i| self.counts[i] != 0 && self.labels[i] == label.0);
        if let Some(i) = slot
            && self.counts[i] <= u16::MAX - n
        {
            let dominated = self.dominates(i);
            let before = if dominated {
                Some(label)
            } else {
                self.dominant()
            };
            self.hits = self.hits.saturating_add(u32::from(n));
            self.counts[i] += n;
            let after = if dominated { before } else { self.dominant() };
            return (before, after);
        }
        let before = self.dominant();
        for _ in 0..n {
            self.add(label);
        }
        (before, self.dominant())
    }

    /// Whether busy slot `i` is the dominant one.
    #[inline]
    fn dominates(&self, i: usize) -> bool {
        let (c, l) = (self.counts[i], self.labels[i]);
        (0..EVIDENCE_SLOTS)
            .all(|j| j == i || self.counts[j] < c || (self.counts[j] == c && self.labels[j] > l))
    }

    /// Increments busy slot `i`, halving every count first on overflow.
    #[inline]
    fn increment(&mut self, i: usize) {
        if self.counts[i] == u16::MAX {
            for c in &mut self.counts {
                *c = c.div_ceil(2);
            }
        }
        self.counts[i] += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn majority_and_ties() {
        let mut v = VoxelEvidence::EMPTY;
        assert_eq!(v.dominant(), None);
        assert_eq!(v.add(LabelId(5)), (None, Some(LabelId(5))));
        assert_eq!(v.add(LabelId(3)), (Some(LabelId(5)), Some(LabelId(3))));
        assert_eq!(v.add(LabelId(5)), (Some(LabelId(3)), Some(LabelId(5))));
        assert_eq!(v.hits(), 3);
        assert_eq!(v.count(LabelId(5)), 2);
    }

    #[test]
    fn eviction_decrements_all() {
        let mut v = VoxelEvidence::EMPTY;
        for l in [1, 2, 3] {
            v.add(LabelId(l));
        }
        v.add(LabelId(1));
        // All slots busy: a fourth label decrements everyone.
        v.add(LabelId(4));
        assert_eq!(v.evidence().collect::<Vec<_>>(), vec![(LabelId(1), 1)]);
        assert_eq!(v.hits(), 5);
        // Freed slots are reused.
        v.add(LabelId(4));
        assert_eq!(v.count(LabelId(4)), 1);
    }

    #[test]
    fn saturation_halves() {
        let mut v = VoxelEvidence::EMPTY;
        for _ in 0..u32::from(u16::MAX) {
            v.add(LabelId(1));
        }
        v.add(LabelId(2));
        v.add(LabelId(1));
        assert_eq!(v.count(LabelId(1)), u16::MAX / 2 + 2);
        assert_eq!(v.count(LabelId(2)), 1);
        assert_eq!(v.dominant(), Some(LabelId(1)));
    }

    proptest! {
        /// `add_n` is `n` sequential `add`s.
        #[test]
        fn add_n_equals_repeated_add(runs in prop::collection::vec((0u16..5, 1u16..6), 1..40)) {
            let (mut a, mut b) = (VoxelEvidence::EMPTY, VoxelEvidence::EMPTY);
            for (l, n) in runs {
                let before = a.dominant();
                let (rb, ra) = b.add_n(LabelId(l), n);
                for _ in 0..n {
                    a.add(LabelId(l));
                }
                prop_assert_eq!(a, b);
                prop_assert_eq!((rb, ra), (before, a.dominant()));
            }
        }

        /// Misra–Gries guarantee: a label with more than hits/4 points keeps a
        /// slot, and counts never exceed true counts.
        #[test]
        fn misra_gries_guarantee(labels in prop::collection::vec(0u16..6, 1..200)) {
            let mut v = VoxelEvidence::EMPTY;
            let mut truth = [0u32; 6];
            for &l in &labels {
                v.add(LabelId(l));
                truth[usize::from(l)] += 1;
            }
            let n = labels.len() as u32;
            prop_assert_eq!(v.hits(), n);
            for l in 0..6u16 {
                let t = truth[usize::from(l)];
                let c = u32::from(v.count(LabelId(l)));
                prop_assert!(c <= t);
                prop_assert!(t - c <= n / 4);
                if t * 4 > n {
                    prop_assert!(c > 0);
                }
            }
            if let Some(d) = v.dominant() {
                prop_assert!(v.evidence().all(|(l, c)| c < v.count(d) || (c == v.count(d) && l >= d)));
            }
        }
    }
}
