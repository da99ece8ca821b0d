//! Typed errors of the agent.

use thiserror::Error;

use sornav_cluster_graph::ClusterError;
use sornav_executor::{ExecError, MissionId};
use sornav_frontier_graph::FrontierError;
use sornav_semantic_map::MapError;
use sornav_supervisor::SupervisorError;
use sornav_target_gate::GateError;
use sornav_tsp::TspError;

/// An invalid [`AgentConfig`](crate::AgentConfig).
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum ConfigError {
    /// Reading, parsing (malformed TOML, unknown field) or writing the
    /// TOML document failed.
    #[error("agent configuration: {0}")]
    Toml(#[from] crate::toml_file::TomlError),
    /// One component's configuration is out of range.
    #[error("invalid {component} configuration: {message}")]
    Component {
        /// Which component (`semantic_map`, `frontier`, ...).
        component: &'static str,
        /// The component's own message.
        message: String,
    },
    /// Two components disagree on one paper parameter.
    #[error("inconsistent paper parameter {parameter}: {message}")]
    Inconsistent {
        /// The parameter (`voxel size`, `N_min`, `K`, `R_s`).
        parameter: &'static str,
        /// The disagreeing values.
        message: String,
    },
    /// The label vocabulary is malformed (duplicate id or name, empty name).
    #[error("invalid label vocabulary: {0}")]
    Labels(String),
    /// The variant cannot be run by the agent.
    #[error("variant {0} is not an agent configuration: {1}")]
    NotAnAgentVariant(&'static str, &'static str),
}

/// An observation the agent refuses (nothing is integrated then).
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum ObservationError {
    /// The robot pose (position or yaw) is NaN or infinite.
    #[error("robot pose is not finite")]
    NonFinitePose,
    /// The camera pose or cloud origin is NaN or infinite.
    #[error("sensor pose is not finite")]
    NonFiniteSensorPose,
    /// Intrinsics are not finite or the focal length is not positive.
    #[error("invalid pinhole intrinsics: {0}")]
    InvalidIntrinsics(String),
    /// The depth or label buffer does not match the image size.
    #[error("depth frame is {width}x{height} but has {depth} depth and {labels} label values")]
    FrameSize {
        /// Declared width in pixels.
        width: u32,
        /// Declared height in pixels.
        height: u32,
        /// Depth values supplied.
        depth: usize,
        /// Label values supplied.
        labels: usize,
    },
    /// The frame holds no point or pixel at all.
    #[error("empty observation")]
    Empty,
}

/// Everything that can go wrong at the agent's public boundary.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum AgentError {
    /// Invalid configuration.
    #[error(transparent)]
    Config(#[from] ConfigError),
    /// Invalid observation.
    #[error(transparent)]
    Observation(#[from] ObservationError),
    /// The target request names no category of the vocabulary.
    #[error("unknown target {request:?}: no category of the vocabulary ({known}) matches")]
    UnknownTarget {
        /// The request as given.
        request: String,
        /// The accepted categories, comma separated.
        known: String,
    },
    /// [`Agent::step`](crate::Agent::step) was called before a target was set.
    #[error("no target set")]
    NoTarget,
    /// [`Agent::step`](crate::Agent::step) was called before any observation.
    #[error("no observation yet: the robot pose is unknown")]
    NoObservation,
    /// `now` is earlier than a previous step's clock reading.
    #[error("clock went backwards: {now:?} < {previous:?}")]
    ClockBackwards {
        /// This call's reading.
        now: std::time::Duration,
        /// The previous reading.
        previous: std::time::Duration,
    },
    /// A mission outcome names a mission that is not active.
    #[error("mission {0:?} is not the active mission")]
    UnknownMission(MissionId),
    /// Semantic map error.
    #[error(transparent)]
    Map(#[from] MapError),
    /// Frontier map error.
    #[error(transparent)]
    Frontier(#[from] FrontierError),
    /// Cluster graph error.
    #[error(transparent)]
    Cluster(#[from] ClusterError),
    /// Route planning error.
    #[error(transparent)]
    Tsp(#[from] TspError),
    /// Target gate error.
    #[error(transparent)]
    Gate(#[from] GateError),
    /// Supervisor error.
    #[error(transparent)]
    Supervisor(#[from] SupervisorError),
    /// Executor error.
    #[error(transparent)]
    Executor(#[from] ExecError),
}
