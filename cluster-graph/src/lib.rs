//! SOR-Nav's cluster graph G_C: frontiers grouped into stable decision units,
//! ranked geometrically, with the semantic contexts the supervisor reasons
//! about.
//!
//! Individual frontiers appear, split and disappear as the map grows. SOR-Nav
//! decides *where to relocate* over clusters instead: frontiers `v_i ~ v_j`
//! belong to the same cluster iff a chain of decision-graph edges joins them
//! with every edge cost `w_e <= rho_c`. Frontiers that are close in space but
//! separated by a wall (a long detour, hence an expensive edge) stay apart.
//!
//! # Should I use this crate?
//! Use it if you have a frontier decision graph (frontier nodes, a robot node
//! and edges with traversal costs and executable paths, e.g.
//! `sornav-frontier-graph`'s `FrontierGraph`) and want region-level decision
//! units with relocation waypoints, a cheap geometric pre-ranking, and
//! compact semantic descriptions of each region for a language model.
//!
//! # API themes
//! * Input: the [`DecisionGraph`] trait (implemented for
//!   `sornav_frontier_graph::FrontierGraph`, see [`frontier_adapter`], and
//!   for the in-memory [`SparseDecisionGraph`]).
//! * Build: [`ClusterGraph::build`] groups frontiers ([`connected_groups`]),
//!   places cluster nodes at the mean member position with their spread
//!   `r_k`, reuses the decision graph's costs and paths for the cluster edges
//!   (`w_kl`) and robot edges (`w_rk`, relocation waypoint), and ranks
//!   clusters by [`geometric_utility`] `U_geo = n (1 + eta r) / (1 + d)`;
//!   [`ClusterGraph::top_k`] are the candidates. Cluster indices are
//!   per-build; [`ClusterGraph::matching_cluster`] follows a cluster across
//!   rebuilds through its (stable) frontier ids.
//! * Contexts: objects enter through the small [`LabelledObject`] trait
//!   (label, support, centre); [`ClusterGraph::cluster_context`] gives `S_k`,
//!   [`robot_context`] gives `S_r`. Both are serialisable.
//! * Parameters: [`ClusterConfig`] (`rho_c` 25, `eta` 0.1, `K` 10, `N_min` 10,
//!   `R_s` = `R_r` = 10 m), serde-serialisable.
//! * Errors: [`ClusterError`]; bad input never panics.
//!
//! # Example
//! ```
//! use nalgebra::{Point2, Point3};
//! use sornav_cluster_graph::{
//!     ClusterConfig, ClusterGraph, GraphNode::{Frontier, Robot}, ObjectSummary,
//!     SparseDecisionGraph,
//! };
//!
//! // Robot at the origin; frontiers 1 and 2 in a bedroom to the east, 3 in a
//! // bathroom to the north, behind a wall from 2 (a 35 m detour).
//! let mut g = SparseDecisionGraph::new(Point2::new(0.0, 0.0));
//! let frontiers = [(1_u32, (6.0, 0.0), 6.0), (2, (8.0, 2.0), 8.5), (3, (7.0, 5.0), 9.0)];
//! for (id, (x, y), cost) in frontiers {
//!     g.add_frontier(id, Point2::new(x, y));
//!     g.set_edge(Robot, Frontier(id), cost, vec![Point2::origin(), Point2::new(x, y)]);
//! }
//! g.set_edge(Frontier(1), Frontier(2), 3.0, vec![]);
//! g.set_edge(Frontier(2), Frontier(3), 35.0, vec![]);
//! g.set_edge(Frontier(1), Frontier(3), 38.0, vec![]);
//!
//! let cg = ClusterGraph::build(&g, &ClusterConfig::default())?;
//! assert_eq!(cg.len(), 2); // {1, 2} and {3}: the wall keeps them apart
//! let best = cg.cluster(cg.top_k()[0]).unwrap();
//! assert_eq!(best.members, vec![1, 2]);
//! assert_eq!(best.relocation.as_ref().unwrap().waypoint, 1);
//! assert_eq!(cg.edges()[0].cost, 35.0); // w_kl: cheapest member pair
//!
//! let objects = [ObjectSummary {
//!     label: "toilet".into(),
//!     support: 120,
//!     centre: Point3::new(7.5, 6.0, 0.4),
//!     level: None,
//! }];
//! let s_k = cg.cluster_context(cg.cluster_of(3).unwrap(), &objects)?;
//! assert_eq!(s_k.objects[0].label, "toilet");
//! println!("{}", serde_json::to_string(&s_k).unwrap());
//! # Ok::<(), sornav_cluster_graph::ClusterError>(())
//! ```
#![forbid(unsafe_code)]
#![cfg_attr(docsrs, feature(doc_cfg))]
#![deny(missing_docs)]

/// The README's example is compiled and run as a doctest.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;

mod cluster_graph;
mod config;
mod context;
mod decision_graph;
mod error;
pub mod frontier_adapter;
mod grouping;
mod ranking;

pub use cluster_graph::{Cluster, ClusterEdge, ClusterGraph, ClusterId, Relocation};
pub use config::{ClusterConfig, MAX_ETA};
pub use context::{
    ClusterContext, ClusterObject, LabelledObject, NearbyObject, ObjectSummary, RobotContext,
    robot_context, robot_context_on_level,
};
pub use decision_graph::{
    DecisionGraph, GraphNode, MAX_ABS_COORD, SparseDecisionGraph, SparseEdge,
};
pub use error::ClusterError;
pub use grouping::connected_groups;
pub use ranking::geometric_utility;
