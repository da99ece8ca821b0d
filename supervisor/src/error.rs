//! Typed errors of the supervisor crate.

use thiserror::Error;

/// Everything that can go wrong at the crate's public boundaries.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum SupervisorError {
    /// The target category is empty or blank.
    #[error("the target category is empty")]
    EmptyTarget,
    /// A support or distance is NaN, infinite or negative.
    #[error("{what} must be finite and >= 0, got {value}")]
    InvalidNumber {
        /// Which quantity.
        what: &'static str,
        /// The offending value.
        value: f64,
    },
    /// Two candidates carry the same cluster id.
    #[error("cluster id {0} is offered twice")]
    DuplicateCandidate(u64),
    /// A configuration value is out of range.
    #[error("invalid configuration: {0}")]
    InvalidConfig(String),
    /// Reading a file failed.
    #[error("reading {path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// The cause.
        #[source]
        source: std::io::Error,
    },
    /// A CSV file of the HM3D statistics is malformed.
    #[error("malformed HM3D statistics file {path}: {message}")]
    MalformedStats {
        /// The file.
        path: String,
        /// What is wrong.
        message: String,
    },
    /// A prior table or a recording does not parse or is inconsistent.
    #[error("malformed data: {0}")]
    MalformedData(String),
}
