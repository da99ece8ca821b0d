//! SOR-Nav, the agent: search-or-relocate object navigation over the
//! project's algorithm crates.
//!
//! # Should I use this crate?
//! Use it to run the whole SOR-Nav system on a robot or in a simulator: it
//! owns one instance of each component, configured by one TOML file, and
//! turns sensor frames into missions. Use the algorithm crates directly
//! (`sornav-semantic-map`, `sornav-frontier-graph`, `sornav-cluster-graph`,
//! `sornav-tsp`, `sornav-target-gate`, `sornav-supervisor`,
//! `sornav-executor`) when you need only one piece.
//!
//! # API themes
//! * **Configuration**: [`AgentConfig`] holds every parameter of the paper
//!   as the components' own config types (serde, TOML,
//!   `deny_unknown_fields`, validated, cross-checked where two components
//!   share a parameter). [`AgentConfig::for_variant`] gives the evaluated
//!   [`Variant`]s: full SOR-Nav, no gate, nearest frontier, semantic
//!   ranking (the oracle is the simulator's own).
//! * **Targets**: [`Agent::set_target`] takes a category or a free-text
//!   request mapped onto the [`Vocabulary`] ("find the television" ->
//!   `tv_monitor`); several targets in a row keep the maps.
//! * **Loop**: [`Agent::observe`] an [`Observation`] (robot pose plus a
//!   depth/semantic image with pinhole intrinsics, or a labelled
//!   world-frame cloud), [`Agent::step`] at the control rate to get an
//!   [`AgentCommand`] (dispatch a mission, continue, verify, STOP,
//!   exhausted), [`Agent::on_mission_outcome`] for what the platform
//!   learns about a mission, and [`Agent::on_contact`] when the robot was
//!   stopped by something its sensor did not show.
//! * **Introspection**: [`Agent::snapshot`] (maps, frontiers, clusters,
//!   route, active mission, gate, last decision and its reason) and the
//!   [`Decision`] log, all serde.
//!
//! The agent's maps are built only from its observations.
//!
//! # Cargo features
//! * `llm` (default): [`PolicyConfig::Llm`] builds the supervisor's
//!   OpenAI-compatible LLM policy (an HTTP client). With
//!   `default-features = false` no HTTP or TLS crate is compiled and
//!   [`AgentConfig::validate`] rejects that policy.
//!
//! # Data
//! The default policy embeds the supervisor's commonsense prior, derived
//! from HM3D-Semantics train scenes and provided under HM3D's terms (see
//! [`supervisor`]'s "Data attribution").
//!
//! # Example
//! A robot in a 6 m x 4 m room with a doorway, looking for a television
//! that is in the room:
//! ```
//! use std::time::Duration;
//! use nalgebra::Point3;
//! use sornav::{Agent, AgentCommand, AgentConfig, CloudObservation, Observation, Sensor};
//! use sornav::executor::RobotPose;
//! use sornav::semantic_map::{LabelId, LabeledPoint};
//!
//! let mut agent = Agent::new(AgentConfig::default())?;
//! assert_eq!(agent.set_target("find the television")?.category, "tv_monitor");
//!
//! // A synthetic labelled scan: walls (label 1), floor (2), a TV (15).
//! let mut points = Vec::new();
//! for i in -60..=60 {
//!     for h in 0..18 {
//!         let (x, z) = (i as f32 * 0.05, h as f32 * 0.05);
//!         points.push(LabeledPoint::new(x, 2.0, z, LabelId(1)));
//!         points.push(LabeledPoint::new(x, -2.0, z, LabelId(1)));
//!     }
//! }
//! for j in -40..=40 {
//!     let y = j as f32 * 0.05;
//!     for h in 0..18 {
//!         let z = h as f32 * 0.05;
//!         points.push(LabeledPoint::new(-3.0, y, z, LabelId(1)));
//!         if y.abs() > 0.6 {
//!             points.push(LabeledPoint::new(3.0, y, z, LabelId(1))); // doorway
//!         }
//!     }
//!     for i in -55..=55 {
//!         points.push(LabeledPoint::new(i as f32 * 0.05, y, 0.0, LabelId(2)));
//!     }
//! }
//! for a in 0..6 {
//!     for b in 0..4 {
//!         points.push(LabeledPoint::new(-1.0 + a as f32 * 0.05, 1.9, 0.6 + b as f32 * 0.05, LabelId(15)));
//!     }
//! }
//! let pose = RobotPose::new(Point3::new(0.0, 0.0, 0.0), 0.0);
//! let sensor = Sensor::Cloud(CloudObservation { origin: Point3::new(0.0, 0.0, 0.88), points });
//! let observation = Observation { pose, sensor };
//!
//! // N_obs = 3 frames with the TV before it is pursued.
//! let mut command = None;
//! for t in 0..3 {
//!     agent.observe(&observation)?;
//!     command = Some(agent.step(Duration::from_secs(t))?);
//! }
//! match command {
//!     Some(AgentCommand::Dispatch { mission, .. }) => {
//!         assert_eq!(mission.kind.name(), "nav_to_object");
//!         assert!(mission.look_at.is_some());
//!     }
//!     other => panic!("expected NAV_TO_OBJECT, got {other:?}"),
//! }
//! let snapshot = agent.snapshot();
//! assert_eq!(snapshot.candidates.len(), 1);
//! assert!(serde_json::to_string(&snapshot).is_ok());
//! # Ok::<(), sornav::AgentError>(())
//! ```
#![forbid(unsafe_code)]
#![cfg_attr(docsrs, feature(doc_cfg))]
#![deny(missing_docs)]

/// The README's example is compiled and run as a doctest.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;

/// Implements `as_str`, `Display`, `PartialEq<str>` and `PartialEq<&str>`
/// for a fieldless enum from `Variant => "name"` pairs (its serde names),
/// so that the enum reads and compares like the string it replaces.
macro_rules! snake_case_names {
    ($ty:ident { $($variant:ident => $name:literal),+ $(,)? }) => {
        impl $ty {
            /// The snake-case name, as serialised.
            pub fn as_str(self) -> &'static str {
                match self {
                    $($ty::$variant => $name,)+
                }
            }
        }

        impl std::fmt::Display for $ty {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str(self.as_str())
            }
        }

        impl PartialEq<str> for $ty {
            fn eq(&self, other: &str) -> bool {
                self.as_str() == other
            }
        }

        impl PartialEq<&str> for $ty {
            fn eq(&self, other: &&str) -> bool {
                self.as_str() == *other
            }
        }
    };
}

mod agent;
mod approach;
mod back_off;
mod commitment;
mod config;
mod drop_edges;
mod error;
mod observation;
mod ordering;
mod path_cost;
mod revisit;
mod snapshot;
mod target;
pub mod toml_file;
mod view;

pub use agent::{Agent, AgentCommand, BoxedPolicy};
pub use commitment::CommitmentConfig;
pub use config::{
    AgentConfig, ApproachConfig, FrontierOrdering, LabelEntry, PolicyConfig, SemanticRankingConfig,
    Variant,
};
pub use error::{AgentError, ConfigError, ObservationError};
pub use observation::{
    CloudObservation, DepthObservation, FLOOR_EDGE_TOLERANCE_M, MIN_VOID_RUN_M, Observation,
    ObservationReport, OccupancyObservation, Sensor, occupancy_stride,
};
pub use ordering::{OrderingKind, Route};
pub use snapshot::{
    AgentSnapshot, AgentStats, Decision, DecisionAction, DecisionStep, ObjectRecord,
    OccupancyRaster, RelocationRecord, UnknownDecisionAction,
};
pub use target::{Target, Vocabulary};
pub use toml_file::TomlError;

/// The components, re-exported so that platforms and examples need only
/// this crate.
pub use sornav_cluster_graph as cluster_graph;
pub use sornav_executor as executor;
pub use sornav_frontier_graph as frontier_graph;
pub use sornav_semantic_map as semantic_map;
pub use sornav_supervisor as supervisor;
pub use sornav_target_gate as target_gate;
pub use sornav_tsp as tsp;
