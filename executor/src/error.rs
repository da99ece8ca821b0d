//! Error types.

use thiserror::Error;

/// Errors at the executor's public boundary. Nothing is changed when one is
/// returned.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum ExecError {
    /// A configuration parameter is out of range.
    #[error("invalid executor configuration: {0}")]
    InvalidConfig(&'static str),
    /// A mission has a non-finite coordinate or an empty path.
    #[error("invalid mission: {0}")]
    InvalidMission(&'static str),
    /// A robot pose has a non-finite component.
    #[error("non-finite robot pose")]
    InvalidPose,
}

/// Error a [`MotionStack`](crate::MotionStack) returns when it cannot accept a
/// mission.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
#[error("motion stack refused the mission: {0}")]
pub struct MotionError(pub String);
