//! Typed errors of the solver and the receding-horizon planner.

use thiserror::Error;

/// Why a cost matrix, a solver configuration or a solve request was rejected.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum TspError {
    /// The matrix has no nodes.
    #[error("the cost matrix is empty")]
    Empty,
    /// The number of entries is not `n * n`.
    #[error("a {n}x{n} cost matrix needs {} entries, got {len}", n * n)]
    NotSquare {
        /// Requested side length.
        n: usize,
        /// Number of entries supplied.
        len: usize,
    },
    /// A row of a row-wise matrix has the wrong length.
    #[error("row {row} has {len} entries, expected {n}")]
    RaggedRow {
        /// Row index.
        row: usize,
        /// Its length.
        len: usize,
        /// Expected length.
        n: usize,
    },
    /// An entry is NaN or infinite.
    #[error("cost[{row}][{col}] = {value} is not finite")]
    NonFinite {
        /// Row (source node).
        row: usize,
        /// Column (target node).
        col: usize,
        /// The offending value.
        value: f64,
    },
    /// A finite entry is larger in magnitude than
    /// [`MAX_ABS_COST`](crate::MAX_ABS_COST) (route sums could overflow).
    #[error(
        "cost[{row}][{col}] = {value} exceeds the accepted magnitude {}",
        crate::MAX_ABS_COST
    )]
    CostOutOfRange {
        /// Row (source node).
        row: usize,
        /// Column (target node).
        col: usize,
        /// The offending value.
        value: f64,
    },
    /// A node index is outside `0..n`.
    #[error("node {node} is out of range for a matrix of {n} nodes")]
    NodeOutOfRange {
        /// The index.
        node: usize,
        /// Number of nodes.
        n: usize,
    },
    /// The fixed end of an open path equals its start (use a closed tour instead).
    #[error("the fixed end {0} equals the start; ask for a closed tour instead")]
    EndEqualsStart(usize),
    /// A warm-start order is not a permutation of the nodes with the required endpoints.
    #[error("invalid initial order: {0}")]
    InvalidInitialOrder(String),
    /// A configuration value is outside its documented range.
    #[error("invalid configuration: {0}")]
    InvalidConfig(String),
    /// The exact solver was asked for more nodes than it supports.
    #[error("Held-Karp supports at most {max} nodes, got {n}")]
    TooLargeForExact {
        /// Requested size.
        n: usize,
        /// Hard limit.
        max: usize,
    },
    /// Frontier ids, positions and the cost matrix of a planning problem disagree.
    #[error("planning problem is inconsistent: {0}")]
    InconsistentProblem(String),
}
