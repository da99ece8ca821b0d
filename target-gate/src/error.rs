//! Error type.

use thiserror::Error;

use crate::ObjectId;

/// Errors reported at the gate's public boundary.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum GateError {
    /// A configuration parameter is out of range.
    #[error("invalid gate configuration: {0}")]
    InvalidConfig(&'static str),
    /// A position given by the caller has a NaN or infinite coordinate.
    #[error("non-finite position: {0}")]
    NonFinite(&'static str),
    /// A protocol call names a candidate the gate is not verifying.
    #[error("{0} is not the candidate under verification")]
    NotActive(ObjectId),
    /// A protocol call arrived in a phase where it has no meaning.
    #[error("unexpected protocol call in phase {0}")]
    WrongPhase(&'static str),
}
