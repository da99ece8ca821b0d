//! SOR-Nav's supervisor: decide whether the region being searched is still
//! worth searching *before* choosing where to go next.
//!
//! # Should I use this crate?
//! Use it when an object-search robot needs a context gate between "explore
//! the next frontier" and "relocate to another region": it implements
//! Algorithm 1 of SOR-Nav (target first, keep an active relocation,
//! rate-limit, then ask a policy) over any clock, with three policies:
//!
//! * [`CommonsensePolicy`] — the embedded default, no network: a prior
//!   `P(target | objects seen)` (logistic regression over the observed
//!   labels, fitted on partial views of HM3D-Semantics train regions;
//!   [`CooccurrencePrior`]). It relocates only on `Conflict(g, S_r)`.
//! * `LlmPolicy` (cargo feature `llm`, on by default) — an OpenAI-compatible
//!   chat-completions client with strict JSON-schema answers, validation,
//!   caching, an asynchronous mode and JSONL record/replay.
//! * [`NeverRelocate`] — the ablation without the relocation gate.
//!
//! The inputs are the crate's own small types (target label, local context
//! as label/support pairs, candidates as cluster id, graph distance and
//! context), so the crate does not need the rest of sornav.
//!
//! # Data attribution
//! The library embeds `data/hm3d_cooccurrence_prior.json`
//! ([`CooccurrencePrior::embedded`]): per-label region counts derived from the
//! HM3D-Semantics v0.2 statistics (K. Yadav et al., "Habitat-Matterport 3D
//! Semantics Dataset", CVPR 2023; matterport/habitat-matterport-3dresearch),
//! train scenes only. No scan, mesh or raw statistics file is shipped.
//! HM3D-Semantics is distributed under the *Matterport End User License
//! Agreement for Academic Use of Model Data*; the derived table is provided
//! under those terms (academic, non-commercial research), see [`ATTRIBUTION`].
//! The crate's MIT OR Apache-2.0 licence covers its code, not that data; a
//! prior built from other statistics ([`CooccurrencePrior::build`]) avoids it.
//!
//! # API themes
//! * Algorithm 1: [`Supervisor::step`] with [`StepInput`], [`RegionContext`]
//!   → [`SupervisorCommand`].
//! * Policies: [`ContextPolicy::decide`] with [`RegionSnapshot`] →
//!   [`PolicyDecision`] (an action plus a reason).
//! * The prior and its evaluation: [`CooccurrencePrior`], [`Hm3dStats`],
//!   [`evaluate_prior`], [`roc_auc`].
//!
//! # Example
//! ```
//! use sornav_supervisor::{
//!     Candidate, CandidateObject, ClusterCandidate, CommonsensePolicy, ContextObject,
//!     ActiveMissionKind, MissionState, RegionContext, StepInput, Supervisor, SupervisorCommand,
//!     SupervisorConfig,
//! };
//! use nalgebra::Point3;
//! use std::time::Duration;
//!
//! let mut sup = Supervisor::new(CommonsensePolicy::default(), SupervisorConfig::default())?;
//! let input = StepInput {
//!     target: "toilet",
//!     target_accepted: None,
//!     mission: MissionState { id: 1, kind: ActiveMissionKind::Explore },
//!     first_frontier: Some(Point3::new(1.0, 0.0, 0.0)),
//! };
//! // The robot searches a bedroom; a cluster 6 m away shows a sink and a bathtub.
//! let region = || RegionContext {
//!     local_context: ["bed", "wardrobe", "nightstand", "pillow"]
//!         .map(|l| ContextObject::new(l, 200.0))
//!         .to_vec(),
//!     clusters: vec![ClusterCandidate {
//!         candidate: Candidate { floor: 0,
//!             cluster_id: 7,
//!             distance_m: 6.0,
//!             context: vec![
//!                 CandidateObject::new("sink", 80.0, 2.0),
//!                 CandidateObject::new("bathtub", 300.0, 3.0),
//!             ],
//!         },
//!         u_geo: 3.0,
//!         waypoint: Point3::new(6.0, 0.0, 0.0),
//!     }],
//! };
//! match sup.step(Duration::ZERO, &input, region)? {
//!     SupervisorCommand::Relocate { cluster_id, reason, .. } => {
//!         assert_eq!(cluster_id, 7);
//!         println!("relocate: {reason}");
//!     }
//!     other => panic!("expected a relocation, got {other:?}"),
//! }
//! # Ok::<(), sornav_supervisor::SupervisorError>(())
//! ```
#![forbid(unsafe_code)]
#![cfg_attr(docsrs, feature(doc_cfg))]
#![deny(missing_docs)]

mod clock;
mod commonsense;
mod context;
mod error;
mod evaluation;
mod hm3d;
mod label;
#[cfg(feature = "llm")]
#[cfg_attr(docsrs, doc(cfg(feature = "llm")))]
pub mod llm;
mod llm_config;
mod logistic;
mod policy;
mod prior;
mod supervisor;

pub use clock::Timestamp;
pub use commonsense::{
    CommonsenseConfig, CommonsensePolicy, ConflictAssessment, REGIONS_PER_FLOOR,
};
pub use context::{Candidate, CandidateObject, ContextObject, RegionSnapshot};
pub use error::SupervisorError;
pub use evaluation::{TargetAuc, evaluate_prior, roc_auc};
pub use hm3d::{Hm3dRegion, Hm3dStats, METADATA_FILE, REGIONS_FILE, Split};
pub use label::{OBJECTNAV_CATEGORIES, STRUCTURAL_LABELS, normalize_label};
#[cfg(feature = "llm")]
#[cfg_attr(docsrs, doc(cfg(feature = "llm")))]
pub use llm::LlmPolicy;
pub use llm_config::{LlmConfig, LlmLatency, LlmStats};
pub use policy::{ContextPolicy, NeverRelocate, PolicyAction, PolicyDecision, Situation};
pub use prior::{
    ATTRIBUTION, CooccurrencePrior, LogisticRow, MAX_SUBSETS_PER_REGION, MP3D_EXTRA_TARGETS,
    Posterior, PriorBuildConfig, PriorModel, TargetRow,
};
/// The README's example, compiled and run as a doc test.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;

pub use supervisor::{
    ActiveMissionKind, AlgorithmStep, ClusterCandidate, MissionState, RegionContext, StepInput,
    Supervisor, SupervisorCommand, SupervisorConfig, SupervisorStats,
};
