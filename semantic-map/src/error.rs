//! The crate's error type.

use thiserror::Error;

use crate::cluster::ClusterId;
use crate::key::VoxelKey;
use crate::label::LabelId;

/// Everything that can go wrong at the public boundary of this crate.
///
/// Invalid *points* are not errors: they are rejected and counted in
/// [`IntegrationStats`](crate::IntegrationStats). Errors are reserved for
/// invalid configurations, malformed frames and inconsistent snapshots.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum MapError {
    /// A configuration value is out of its domain.
    #[error("invalid configuration: {0}")]
    InvalidConfig(String),
    /// A depth frame's buffers do not match its declared size.
    #[error("depth frame is {width}x{height} but has {depth} depth and {labels} label values")]
    FrameSize {
        /// Declared width in pixels.
        width: u32,
        /// Declared height in pixels.
        height: u32,
        /// Number of depth values supplied.
        depth: usize,
        /// Number of label values supplied.
        labels: usize,
    },
    /// The camera intrinsics are not finite or the focal length is not positive.
    #[error("invalid pinhole intrinsics: {0}")]
    InvalidIntrinsics(String),
    /// A pose or origin contains NaN or infinity.
    #[error("sensor pose or origin is not finite")]
    NonFinitePose,
    /// A label name is already used by another id.
    #[error("label name {name:?} already names label {existing}")]
    DuplicateLabelName {
        /// The clashing name.
        name: String,
        /// The id that already carries it.
        existing: LabelId,
    },
    /// Label names must not be empty.
    #[error("label {0} has an empty name")]
    EmptyLabelName(LabelId),
    /// A snapshot is internally inconsistent.
    #[error("inconsistent snapshot: {0}")]
    Snapshot(String),
    /// A snapshot names a voxel twice.
    #[error("snapshot lists voxel {0:?} twice")]
    DuplicateVoxel(VoxelKey),
    /// A snapshot lists a cluster id twice.
    #[error("snapshot lists cluster {0} twice")]
    DuplicateCluster(ClusterId),
}
