//! Identifier of an object cluster.

use serde::{Deserialize, Serialize};

/// Identifier of a persistent object cluster `o_j`, as assigned by the
/// semantic map.
///
/// The gate keys all of its per-candidate state by this id. When the map
/// merges or splits clusters it reports the id changes, and the gate follows
/// them with [`CandidateTracker::apply_remap`](crate::CandidateTracker::apply_remap).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(transparent)]
pub struct ObjectId(pub u64);

impl std::fmt::Display for ObjectId {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "object#{}", self.0)
    }
}
