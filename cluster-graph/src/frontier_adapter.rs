//! [`DecisionGraph`] for `sornav-frontier-graph`'s [`FrontierGraph`].
//!
//! * Frontier ids are [`FrontierId`]s (stable while a frontier persists).
//! * A frontier's position is its [`FrontierNode::centroid`] (the mean of its
//!   cells): cluster centres, spreads and context distances describe where
//!   the unexplored boundary is. Paths end at the frontier's executable
//!   viewpoint, as the frontier graph stores them.
//! * The robot is [`FrontierGraph::robot`]; the home node plays no part.
//! * Costs and paths are the frontier graph's edges (no new path query);
//!   paths are their horizontal projection (a multi-level graph's 3-D
//!   paths stay available from the frontier graph itself).
//! * A frontier's level is its node's level; frontiers of different levels
//!   are never grouped together.
//!
//! [`FrontierNode::centroid`]: sornav_frontier_graph::FrontierNode::centroid

use std::borrow::Cow;

use nalgebra::Point2;
use sornav_frontier_graph::{FrontierGraph, FrontierId, NodeId};

use crate::{DecisionGraph, GraphNode};

fn node_id(node: GraphNode<FrontierId>) -> NodeId {
    match node {
        GraphNode::Robot => NodeId::Robot,
        GraphNode::Frontier(f) => NodeId::Frontier(f),
    }
}

impl DecisionGraph for FrontierGraph {
    type FrontierId = FrontierId;

    fn robot_position(&self) -> Point2<f64> {
        self.robot().position
    }

    fn frontiers(&self) -> impl Iterator<Item = (FrontierId, Point2<f64>)> + '_ {
        self.nodes().map(|n| (n.id, n.centroid))
    }

    fn cost(&self, a: GraphNode<FrontierId>, b: GraphNode<FrontierId>) -> Option<f64> {
        FrontierGraph::cost(self, node_id(a), node_id(b))
    }

    fn path(
        &self,
        from: GraphNode<FrontierId>,
        to: GraphNode<FrontierId>,
    ) -> Option<Cow<'_, [Point2<f64>]>> {
        let (from, to) = (node_id(from), node_id(to));
        let path = self.edge(from, to)?.path_from(from)?;
        Some(Cow::Owned(path.iter().map(|p| p.xy()).collect()))
    }

    fn level(&self, node: GraphNode<FrontierId>) -> u16 {
        FrontierGraph::level(self, node_id(node)).map_or(0, |l| l.0)
    }

    fn frontier_edges(&self) -> impl Iterator<Item = (FrontierId, FrontierId, f64)> + '_ {
        self.edges().filter_map(|e| match (e.from, e.to) {
            (NodeId::Frontier(a), NodeId::Frontier(b)) => Some((a, b, e.cost)),
            _ => None,
        })
    }
}
