//! Semantic voxel mapping and persistent 3D object clusters for SOR-Nav.
//!
//! Labelled points (LiDAR returns, fused labelled clouds, or pixels of a
//! depth image back-projected with a per-pixel label image) are fused into a
//! sparse voxel map. Voxels that are 26-connected and share the same
//! dominant, non-ignored label form *object clusters*
//! o_j = (label l_j, voxel support N_j, centre p_j, bounds B_j): the semantic
//! memory that SOR-Nav's semantic contexts S_r / S_k and its target gate
//! read. Repeated views add support instead of new detections, disconnected
//! instances stay separate, and clusters persist after leaving the view.
//!
//! # Should I use this crate?
//! Use it when you need *object instances* (not a dense semantic mesh or an
//! occupancy map) out of labelled depth or LiDAR data, updated online at
//! sensor rate, with ids that stay stable while objects grow, merge and
//! split. It does no free-space carving and no ray casting: occupancy and
//! frontiers are `sornav-frontier-graph`'s job.
//!
//! # API themes
//! * **Storage**: [`SemanticMap`] holds hashed blocks of `8 x 8 x 8` voxels
//!   (unbounded extent, resolution in [`MapConfig`], default 0.05 m); each
//!   voxel is a 16-byte [`VoxelEvidence`] (three label/count slots with a
//!   Misra–Gries eviction rule and a hit total). Labels are [`LabelId`]s,
//!   named and marked "ignored for objects" by a [`LabelSet`].
//! * **Integration**: [`SemanticMap::integrate_points`] for world-frame
//!   [`LabeledPoint`]s, [`SemanticMap::integrate_depth`] for a
//!   [`DepthFrame`] (pinhole [`PinholeCamera`], `Isometry3` pose,
//!   [`DepthOptions`] window and stride). Invalid points are rejected and
//!   counted in [`IntegrationStats`], never fused and never a panic.
//! * **Clustering**: [`SemanticMap::update_clusters`] re-clusters only what
//!   the integrations since the last call could have changed, and keeps ids
//!   persistent (grow / shrink / merge keep the largest predecessor's id; on
//!   a split the largest part keeps it). It reports a [`ClusterUpdate`].
//! * **Queries**: by id, label, minimum support, horizontal radius, height
//!   band (one floor's objects), or a combined [`ClusterQuery`].
//! * **Persistence**: [`SemanticMap::snapshot`] / [`MapSnapshot`], and
//!   `SemanticMap` itself implements serde `Serialize` / `Deserialize`.
//! * **Benchmark input**: [`pcld`] reads the project's `SORPCLD1` files.
//!
//! # Example
//! ```
//! use nalgebra::Point3;
//! use sornav_semantic_map::{
//!     ClusterQuery, LabelId, LabelSet, LabeledPoint, MapConfig, SemanticMap,
//! };
//!
//! let labels = LabelSet::household(); // 1 wall, 2 floor, 3 ceiling ignored
//! let chair = labels.id("chair").unwrap();
//! let mut map = SemanticMap::new(MapConfig::default(), labels)?;
//!
//! // Two chairs 1 m apart, on a floor, seen twice.
//! let mut points = Vec::new();
//! for (cx, cy) in [(1.0f32, 1.0f32), (2.0, 1.0)] {
//!     for i in 0..5 {
//!         for j in 0..5 {
//!             let (x, y) = (cx + 0.05 * i as f32, cy + 0.05 * j as f32);
//!             points.push(LabeledPoint::new(x + 0.01, y + 0.01, 0.46, chair));
//!             points.push(LabeledPoint::new(x + 0.01, y + 0.01, 0.01, LabelId(2)));
//!         }
//!     }
//! }
//! let origin = Point3::new(0.0, 0.0, 0.88);
//! for _ in 0..2 {
//!     let stats = map.integrate_points(&origin, &points)?;
//!     assert_eq!(stats.rejected(), 0);
//!     map.update_clusters();
//! }
//!
//! // Two chair clusters of 25 voxels each, observed twice; floor is ignored.
//! let chairs = map.query(&ClusterQuery::default().label(chair).min_support(10));
//! assert_eq!(chairs.len(), 2);
//! assert!(chairs.iter().all(|c| c.support == 25 && c.observations == 2));
//! let near = map.clusters_within(Point3::new(1.1, 1.1, 0.0), 0.5).count();
//! assert_eq!(near, 1);
//!
//! // Round trip through serde.
//! let json = serde_json::to_string(&map).unwrap();
//! let back: SemanticMap = serde_json::from_str(&json).unwrap();
//! assert_eq!(back.snapshot(), map.snapshot());
//! # Ok::<(), sornav_semantic_map::MapError>(())
//! ```
//!
//! # Complexity
//! * Integration: O(n) expected for n points (one hash lookup per change of
//!   block between consecutive points, O(1) evidence update).
//! * Clustering: O((C + A) x 26) expected, C voxels whose object label
//!   changed and A voxels of the clusters they touch; independent of the
//!   map size (see [`SemanticMap::update_clusters`]).
//! * Queries: O(C) for C clusters; id and voxel lookups O(1) / O(log C).
//!
//! Measured figures against Bonxai and a C++ flood fill are in the crate
//! README.
#![forbid(unsafe_code)]
#![cfg_attr(docsrs, feature(doc_cfg))]
#![deny(missing_docs)]

/// The README's example is compiled and run as a doctest.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;

mod cluster;
mod config;
mod depth;
mod error;
mod evidence;
mod grid;
mod integrate;
mod key;
mod label;
mod map;
pub mod pcld;
mod query;
mod snapshot;

pub use cluster::{Aabb, ClusterId, ClusterUpdate, ObjectCluster, Retired};
pub use config::MapConfig;
pub use depth::{DepthFrame, DepthOptions, PinholeCamera, optical_pose};
pub use error::MapError;
pub use evidence::{EVIDENCE_SLOTS, VoxelEvidence};
pub use integrate::{IntegrationStats, LabeledPoint};
pub use key::{BLOCK_EDGE, BLOCK_VOXELS, VoxelKey};
pub use label::{LabelId, LabelSet};
pub use map::SemanticMap;
pub use query::{ClusterQuery, horizontal_distance};
pub use snapshot::{ClusterRecord, MapSnapshot};
