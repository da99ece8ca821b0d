//! What the caller tells the gate at each update.

use nalgebra::Point3;
use serde::{Deserialize, Serialize};

use crate::ObjectId;

/// One object cluster of the map's current snapshot, as seen by the gate at
/// one update.
///
/// At every update the caller passes the map's clusters (at least all of the
/// requested category; others are ignored). A tracked candidate that is
/// missing from the snapshot, or that no longer matches the category or has
/// fewer than `N_min` voxels, receives a miss.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CandidateReport<C> {
    /// Cluster id in the map.
    pub object: ObjectId,
    /// The cluster's semantic category.
    pub category: C,
    /// Number of voxels `N_j` of the cluster.
    pub voxels: u32,
    /// Cluster centre `p_j` (world frame, metres).
    pub centre: Point3<f64>,
    /// Whether the sensor frame of this update contributed a detection of the
    /// cluster (the detector saw it now). Only such updates count as
    /// supporting observations, so a cluster that persists in the map after a
    /// single-frame false positive never accumulates support.
    pub detected: bool,
}
