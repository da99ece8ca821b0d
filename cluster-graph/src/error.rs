//! Typed errors of the crate.

use thiserror::Error;

/// Everything that can go wrong at the public boundary of this crate.
///
/// Building a [`crate::ClusterGraph`] never panics on bad input: non-finite
/// or out-of-range positions, negative or non-finite edge costs, duplicate or
/// unknown frontier ids, inconsistent graphs and invalid configurations are all
/// reported here. Identifiers are rendered with their `Debug` form so that the
/// error type does not depend on the graph's id type.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum ClusterError {
    /// A configuration value is out of its documented range.
    #[error("invalid configuration: {0}")]
    InvalidConfig(String),
    /// A position is NaN or infinite, or beyond [`crate::MAX_ABS_COORD`].
    #[error("position of {what} is non-finite or out of range")]
    InvalidPosition {
        /// Which node carried the position (`"robot"` or the frontier id).
        what: String,
    },
    /// An edge cost is NaN, infinite or negative.
    #[error("edge {from} -> {to} has invalid cost {cost} (must be finite and >= 0)")]
    InvalidCost {
        /// One endpoint (`"robot"` or a frontier id).
        from: String,
        /// The other endpoint.
        to: String,
        /// The offending cost.
        cost: f64,
    },
    /// The graph listed the same frontier id twice.
    #[error("frontier {0} is listed more than once")]
    DuplicateFrontier(String),
    /// An edge names a frontier that the graph does not list.
    #[error("edge endpoint {0} is not a frontier of the graph")]
    UnknownFrontier(String),
    /// The graph reports a robot edge cost but no path for it.
    #[error("the graph has a robot edge to {0} but no path for it")]
    MissingPath(String),
    /// A cluster id that does not belong to this cluster graph.
    #[error("cluster {0} does not exist (the graph has {1} clusters)")]
    UnknownCluster(usize, usize),
}
