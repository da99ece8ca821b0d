//! Following the map's cluster id changes (merges, splits, renames).

use std::collections::{BTreeMap, BTreeSet};

use serde::{Deserialize, Serialize};

use crate::{CandidateTracker, Evidence, ObjectId, Track};

/// Result of [`CandidateTracker::apply_remap`]: where each previously tracked
/// candidate went.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct RemapSummary {
    /// For every tracked id named as an old id: the new ids that received its
    /// evidence (one for a rename or merge, several for a split).
    pub moved: BTreeMap<ObjectId, Vec<ObjectId>>,
}

/// Combines the tracks of several sources that became one cluster.
///
/// Support is the maximum, not the sum (two fragments seen in the same frame
/// are one observation of one object); misses are the minimum (a detection of
/// any fragment is a detection of the merged object); the centre and size come
/// from the largest fragment.
fn combine(into: ObjectId, sources: &[&Track]) -> Option<Track> {
    let largest = sources
        .iter()
        .copied()
        .max_by(|a, b| a.voxels.cmp(&b.voxels).then(b.object.cmp(&a.object)))?;
    Some(Track {
        object: into,
        evidence: Evidence {
            support: sources.iter().map(|t| t.evidence.support).max()?,
            misses: sources.iter().map(|t| t.evidence.misses).min()?,
        },
        centre: largest.centre,
        voxels: largest.voxels,
        first_seen: sources.iter().map(|t| t.first_seen).min()?,
        last_detected: sources.iter().map(|t| t.last_detected).max()?,
    })
}

impl<C: PartialEq> CandidateTracker<C> {
    /// Applies a cluster id change reported by the map, given as `(old, new)`
    /// pairs.
    ///
    /// * rename: `(a, b)`;
    /// * merge of `a` into `b` (`b` keeps its id): `(a, b)`; merge of `a` and
    ///   `b` into a new `c`: `(a, c), (b, c)`;
    /// * split of `a` into `b` and `c`: `(a, b), (a, c)` (each part inherits
    ///   `a`'s evidence; a part that is not the object loses it through
    ///   misses).
    ///
    /// Every old id that appears in a pair stops existing unless it is also a
    /// new id. A new id collects the evidence of all tracked old ids mapped to
    /// it, plus its own track when it is tracked and not itself remapped; the
    /// combination rule is: support = max, misses = min, centre of the
    /// largest fragment. Untracked old ids contribute no evidence.
    ///
    /// Rejection marks ([`reject`](Self::reject)) follow the same mapping: a
    /// new id stays rejected (until the earliest release) only when every
    /// fragment the gate knows (tracked or marked) was rejected, so a rejected
    /// false positive merged into a real object does not block the object.
    ///
    /// # Complexity
    /// `O((p + n) log n)` for `p` pairs and `n` tracked candidates.
    pub fn apply_remap(&mut self, pairs: &[(ObjectId, ObjectId)]) -> RemapSummary {
        let old_ids: BTreeSet<ObjectId> = pairs.iter().map(|&(o, _)| o).collect();
        // Every id that exists after the remap, with all its sources (tracked
        // or not): each new id, and each untouched id that is a merge target.
        let mut sources: BTreeMap<ObjectId, BTreeSet<ObjectId>> = BTreeMap::new();
        for &(old, new) in pairs {
            sources.entry(new).or_default().insert(old);
        }
        for (new, srcs) in &mut sources {
            if !old_ids.contains(new) {
                srcs.insert(*new);
            }
        }
        let mut summary = RemapSummary::default();
        for &(old, new) in pairs {
            if self.track(old).is_some() {
                let moved = summary.moved.entry(old).or_default();
                if !moved.contains(&new) {
                    moved.push(new);
                }
            }
        }
        let now = self.updates();
        let marks: Vec<(ObjectId, Option<u64>)> = sources
            .iter()
            .map(|(new, srcs)| {
                // Only fragments the gate knows (tracked or marked) count.
                let known: Vec<Option<u64>> = srcs
                    .iter()
                    .filter(|s| self.track(**s).is_some() || self.rejected_until(**s).is_some())
                    .map(|s| self.rejected_until(*s))
                    .collect();
                let until = if known.is_empty() {
                    None
                } else {
                    known
                        .into_iter()
                        .try_fold(u64::MAX, |acc, r| r.map(|r| acc.min(r)))
                };
                (*new, until)
            })
            .collect();
        let (tracks, rejected) = self.parts_mut();
        let combined: Vec<Track> = sources
            .iter()
            .filter_map(|(new, srcs)| {
                let refs: Vec<&Track> = srcs.iter().filter_map(|s| tracks.get(s)).collect();
                combine(*new, &refs)
            })
            .collect();
        for old in &old_ids {
            tracks.remove(old);
            rejected.remove(old);
        }
        for track in combined {
            tracks.insert(track.object, track);
        }
        for (id, until) in marks {
            match until {
                Some(until) if until > now => {
                    rejected.insert(id, until);
                }
                _ => {
                    rejected.remove(&id);
                }
            }
        }
        summary
    }
}
