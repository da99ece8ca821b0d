//! Typed errors of the crate.

use thiserror::Error;

/// Everything that can go wrong at the public boundary of this crate.
///
/// No operation panics on bad input: non-finite numbers, coordinates outside
/// the grid's numeric range, invalid configurations and grids that would grow
/// beyond the configured cell budget are all reported here, before any state is
/// modified.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum FrontierError {
    /// A coordinate was NaN or infinite.
    #[error("non-finite coordinate in {what} (index {index})")]
    NonFinite {
        /// Which input carried the value (`"origin"`, `"point"`, `"pose"`, ...).
        what: &'static str,
        /// Index of the offending element (0 for scalar inputs).
        index: usize,
    },
    /// A coordinate is finite but outside the grid's numeric range
    /// (`|coordinate / resolution|` must stay below [`crate::MAX_CELL_COORD`]).
    #[error("coordinate ({x}, {y}) of {what} is outside the grid's numeric range")]
    OutOfRange {
        /// Which input carried the value.
        what: &'static str,
        /// World x coordinate (m).
        x: f64,
        /// World y coordinate (m).
        y: f64,
    },
    /// A configuration value is invalid (non-positive resolution, inverted
    /// thresholds, ...).
    #[error("invalid configuration: {0}")]
    InvalidConfig(String),
    /// Growing the grid to contain an update would exceed the configured cell
    /// budget ([`crate::GridConfig::max_cells`]).
    #[error("grid would grow to {requested} cells, above the limit of {limit}")]
    GridTooLarge {
        /// Cells the grown grid would need.
        requested: u64,
        /// Configured limit.
        limit: u64,
    },
    /// A contact farther from the robot than [`crate::MAX_CONTACT_REACH_M`]:
    /// the body cannot have met it.
    #[error("contact {distance} m from the robot, farther than {limit} m")]
    ContactOutOfReach {
        /// Distance from the robot's feet to the contact (m).
        distance: f64,
        /// The limit (m).
        limit: f64,
    },
}
