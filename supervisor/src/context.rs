//! The policy's inputs: the target, the robot's semantic context `S_r` and
//! the candidate clusters `{(k, d_k, S_k)}` (step 5 of Algorithm 1).
//!
//! These are the supervisor's own small types so that the crate is usable
//! without the cluster graph: the caller maps its clusters and objects onto
//! them.

use serde::{Deserialize, Serialize};

use crate::error::SupervisorError;

/// One object of the robot's local context `S_r`: a label and its support
/// (for example the voxel count `N_j` of the object cluster).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ContextObject {
    /// Object label (any spelling; policies normalise it).
    pub label: String,
    /// Evidence for the object, e.g. its voxel count. Finite and `>= 0`.
    pub support: f64,
}

impl ContextObject {
    /// A context object.
    pub fn new(label: impl Into<String>, support: f64) -> Self {
        Self {
            label: label.into(),
            support,
        }
    }
}

/// One object of a candidate's context `S_k`, with its distance to the
/// candidate cluster.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CandidateObject {
    /// Object label (any spelling; policies normalise it).
    pub label: String,
    /// Evidence for the object, e.g. its voxel count. Finite and `>= 0`.
    pub support: f64,
    /// Horizontal distance from the cluster to the object, metres. Finite and `>= 0`.
    pub distance_m: f64,
}

impl CandidateObject {
    /// A candidate-context object.
    pub fn new(label: impl Into<String>, support: f64, distance_m: f64) -> Self {
        Self {
            label: label.into(),
            support,
            distance_m,
        }
    }
}

/// A candidate frontier cluster `C_k` offered to the policy.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Candidate {
    /// The cluster's id `k` (unique within one snapshot).
    pub cluster_id: u64,
    /// Graph distance `d_k` from the robot to the cluster, metres. Finite and `>= 0`.
    pub distance_m: f64,
    /// The cluster's semantic context `S_k` (objects of its own floor).
    pub context: Vec<CandidateObject>,
    /// The cluster's floor relative to the robot's: 0 the same floor, +1
    /// the next floor up, -1 the next floor down (multi-level maps).
    #[serde(default)]
    pub floor: i32,
}

/// Everything a [`ContextPolicy`](crate::ContextPolicy) sees: the target `g`,
/// the robot's context `S_r` and the candidates. Never images or maps.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RegionSnapshot {
    /// The target category `g` (any spelling; policies normalise it).
    pub target: String,
    /// The robot's local context `S_r`.
    pub local_context: Vec<ContextObject>,
    /// The top-K candidate clusters.
    pub candidates: Vec<Candidate>,
}

fn check_number(what: &'static str, value: f64) -> Result<(), SupervisorError> {
    if value.is_finite() && value >= 0.0 {
        Ok(())
    } else {
        Err(SupervisorError::InvalidNumber { what, value })
    }
}

impl RegionSnapshot {
    /// Checks the snapshot at the public boundary.
    ///
    /// # Errors
    /// [`SupervisorError::EmptyTarget`] for a blank target,
    /// [`SupervisorError::InvalidNumber`] for a NaN, infinite or negative
    /// support or distance, [`SupervisorError::DuplicateCandidate`] when two
    /// candidates share a cluster id.
    ///
    /// # Complexity
    /// O(m + c log c) for m objects and c candidates.
    pub fn validate(&self) -> Result<(), SupervisorError> {
        if self.target.trim().is_empty() {
            return Err(SupervisorError::EmptyTarget);
        }
        for o in &self.local_context {
            check_number("local context support", o.support)?;
        }
        let mut ids = Vec::with_capacity(self.candidates.len());
        for c in &self.candidates {
            check_number("candidate distance", c.distance_m)?;
            for o in &c.context {
                check_number("candidate object support", o.support)?;
                check_number("candidate object distance", o.distance_m)?;
            }
            ids.push(c.cluster_id);
        }
        ids.sort_unstable();
        if let Some(w) = ids.windows(2).find(|w| w[0] == w[1]) {
            return Err(SupervisorError::DuplicateCandidate(w[0]));
        }
        Ok(())
    }

    /// The candidate with this cluster id, if offered.
    pub fn candidate(&self, cluster_id: u64) -> Option<&Candidate> {
        self.candidates.iter().find(|c| c.cluster_id == cluster_id)
    }
}
