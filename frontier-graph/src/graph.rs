//! The global frontier decision graph G_F = ({v_r, v_h} ∪ V_F, E_F).

use nalgebra::{Point2, Point3, Vector2};
use petgraph::graph::{NodeIndex, UnGraph};
use rustc_hash::FxHashMap;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

use crate::Cell;

/// Stable identifier of a frontier node.
///
/// An id is kept while its segment persists unchanged (same cells); a segment
/// that changes is replaced by new nodes with fresh ids. Ids are never reused.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub struct FrontierId(pub u64);

/// Identifier of a level (floor) of a multi-level map; level 0 is the floor
/// the robot started on, further levels are numbered in order of discovery
/// (their heights are in [`crate::Level`]). A single-level map has only
/// level 0.
#[derive(
    Debug, Clone, Copy, Default, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize,
)]
pub struct LevelId(pub u16);

/// A node of G_F.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub enum NodeId {
    /// The robot node v_r.
    Robot,
    /// The home node v_h (initial pose), when enabled.
    Home,
    /// A frontier node.
    Frontier(FrontierId),
    /// A stair portal: the point of a level's traversable grid where a stair
    /// starts (used inside [`crate::MultiLevelMap`]; never a node of the
    /// graphs it returns).
    Portal(u32),
}

/// A frontier node: a segment of frontier cells (traversable known-free cells
/// 4-adjacent to unknown cells).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FrontierNode {
    /// Stable id.
    pub id: FrontierId,
    /// The segment's cells, sorted.
    pub cells: Vec<Cell>,
    /// Mean of the cell centres (m).
    pub centroid: Point2<f64>,
    /// Unit principal axis of the cells (PCA).
    pub axis: Vector2<f64>,
    /// Extent of the segment along `axis` (m, cell centres span plus one cell).
    pub extent: f64,
    /// Executable viewpoint: centre of `viewpoint_cell`, a traversable cell of
    /// the segment (the one closest to the centroid). Graph paths to this
    /// node end here.
    pub viewpoint: Point2<f64>,
    /// Grid cell of `viewpoint`.
    pub viewpoint_cell: Cell,
    /// The level the frontier lies on (0 in a single-level map).
    #[serde(default)]
    pub level: LevelId,
    /// World height (m) of the viewpoint: the floor of its level, or the
    /// stair surface for the unexplored end of a stair.
    #[serde(default)]
    pub z: f64,
}

impl FrontierNode {
    /// The viewpoint in 3-D (`z` is the floor it stands on).
    pub fn viewpoint3(&self) -> Point3<f64> {
        Point3::new(self.viewpoint.x, self.viewpoint.y, self.z)
    }
}

/// The robot or home node.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AnchorNode {
    /// Nominal position (the pose given by the caller), m.
    pub position: Point2<f64>,
    /// Traversable cell the node's paths start from: the pose's cell, or the
    /// nearest traversable cell within [`crate::GraphConfig::snap_radius`].
    /// `None` when there is none (the node then has no edges).
    pub cell: Option<Cell>,
    /// The level the node is on (0 in a single-level map).
    #[serde(default)]
    pub level: LevelId,
    /// World height (m) of the surface the node stands on.
    #[serde(default)]
    pub z: f64,
}

impl AnchorNode {
    /// The nominal position in 3-D.
    pub fn position3(&self) -> Point3<f64> {
        Point3::new(self.position.x, self.position.y, self.z)
    }
}

/// An edge of G_F: an executable path and its cost.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Edge {
    /// Endpoint the path starts at (the smaller [`NodeId`]).
    pub from: NodeId,
    /// Endpoint the path ends at (the larger [`NodeId`]).
    pub to: NodeId,
    /// 3-D polyline from `from` to `to` (m). On one level it runs through
    /// cell centres at the level's floor height: consecutive points differ
    /// by a multiple of one of the 8 grid directions, and every cell on the
    /// straight run between them is traversable (no corner cutting), so the
    /// path is executable by the configured robot; only direction changes
    /// are stored; a path between nodes on the same cell has one point.
    /// Across levels it continues over the walkable surface of each stair
    /// (one point per surface cell, at the surface's height).
    pub path: Vec<Point3<f64>>,
    /// Path length (m: octile 8-connected on a level, 3-D along stairs),
    /// without the displacement term and the stair costs.
    pub length: f64,
    /// Traversal cost w_ij from `from` to `to`: `length` plus the optional
    /// displacement term plus the stair cost of every stair climbed or
    /// descended on the way.
    pub cost: f64,
    /// Cost from `to` back to `from` (differs from `cost` only when the
    /// path uses stairs and climbing and descending cost differently).
    #[serde(default = "f64_nan")]
    pub reverse_cost: f64,
    /// Bounding box (min, max) of the path's cells, for change detection.
    pub(crate) bbox: (Cell, Cell),
}

fn f64_nan() -> f64 {
    f64::NAN
}

impl Edge {
    /// The cost of travelling the edge starting at `start` (one of the
    /// endpoints); `None` if `start` is not an endpoint.
    pub fn cost_from(&self, start: NodeId) -> Option<f64> {
        if start == self.from {
            Some(self.cost)
        } else if start == self.to {
            Some(if self.reverse_cost.is_nan() {
                self.cost
            } else {
                self.reverse_cost
            })
        } else {
            None
        }
    }

    /// The path oriented to start at `start` (one of the endpoints); `None` if
    /// `start` is not an endpoint.
    pub fn path_from(&self, start: NodeId) -> Option<Vec<Point3<f64>>> {
        if start == self.from {
            Some(self.path.clone())
        } else if start == self.to {
            Some(self.path.iter().rev().copied().collect())
        } else {
            None
        }
    }
}

/// Canonical (sorted) key of an undirected pair.
pub(crate) fn pair(a: NodeId, b: NodeId) -> (NodeId, NodeId) {
    if a <= b { (a, b) } else { (b, a) }
}

/// The global frontier decision graph.
///
/// Nodes: the robot, the optional home and the frontier nodes. An edge exists
/// for every pair connected through the traversable grid; unreachable pairs
/// have none. Obtained from [`crate::FrontierMap::frontier_graph`], which keeps
/// it up to date incrementally.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct FrontierGraph {
    pub(crate) robot: Option<AnchorNode>,
    pub(crate) home: Option<AnchorNode>,
    pub(crate) frontiers: BTreeMap<FrontierId, FrontierNode>,
    /// Stair portals (inside a multi-level map's per-level graphs only).
    #[serde(default)]
    pub(crate) portals: BTreeMap<u32, AnchorNode>,
    #[serde(with = "edge_list")]
    pub(crate) edges: FxHashMap<(NodeId, NodeId), Edge>,
}

impl FrontierGraph {
    /// Frontier nodes, in increasing id order.
    pub fn nodes(&self) -> impl ExactSizeIterator<Item = &FrontierNode> + '_ {
        self.frontiers.values()
    }

    /// Number of frontier nodes.
    pub fn len(&self) -> usize {
        self.frontiers.len()
    }

    /// Whether there is no frontier node.
    pub fn is_empty(&self) -> bool {
        self.frontiers.is_empty()
    }

    /// The frontier node with this id.
    pub fn frontier(&self, id: FrontierId) -> Option<&FrontierNode> {
        self.frontiers.get(&id)
    }

    /// The robot node (set by [`crate::FrontierMap::frontier_graph`]). Before
    /// the first call it is a robot at the origin with no cell (no edges).
    pub fn robot(&self) -> &AnchorNode {
        static NONE: AnchorNode = AnchorNode {
            position: Point2::new(0.0, 0.0),
            cell: None,
            level: LevelId(0),
            z: 0.0,
        };
        self.robot.as_ref().unwrap_or(&NONE)
    }

    /// The home node, if enabled.
    pub fn home(&self) -> Option<&AnchorNode> {
        self.home.as_ref()
    }

    /// Nominal position of a node (robot/home pose, frontier viewpoint).
    pub fn position(&self, id: NodeId) -> Option<Point2<f64>> {
        match id {
            NodeId::Robot => self.robot.as_ref().map(|r| r.position),
            NodeId::Home => self.home.as_ref().map(|h| h.position),
            NodeId::Frontier(f) => self.frontiers.get(&f).map(|n| n.viewpoint),
            NodeId::Portal(p) => self.portals.get(&p).map(|a| a.position),
        }
    }

    /// Nominal 3-D position of a node (robot/home pose, frontier viewpoint
    /// at its floor height).
    pub fn position3(&self, id: NodeId) -> Option<Point3<f64>> {
        match id {
            NodeId::Robot => self.robot.as_ref().map(AnchorNode::position3),
            NodeId::Home => self.home.as_ref().map(AnchorNode::position3),
            NodeId::Frontier(f) => self.frontiers.get(&f).map(FrontierNode::viewpoint3),
            NodeId::Portal(p) => self.portals.get(&p).map(AnchorNode::position3),
        }
    }

    /// The level of a node.
    pub fn level(&self, id: NodeId) -> Option<LevelId> {
        match id {
            NodeId::Robot => self.robot.as_ref().map(|a| a.level),
            NodeId::Home => self.home.as_ref().map(|a| a.level),
            NodeId::Frontier(f) => self.frontiers.get(&f).map(|n| n.level),
            NodeId::Portal(p) => self.portals.get(&p).map(|a| a.level),
        }
    }

    /// All node ids: robot, home (if any), then frontiers by id (then
    /// portals, which only the per-level graphs of a multi-level map have).
    pub fn node_ids(&self) -> impl Iterator<Item = NodeId> + '_ {
        std::iter::once(NodeId::Robot)
            .chain(self.home.as_ref().map(|_| NodeId::Home))
            .chain(self.frontiers.keys().map(|&f| NodeId::Frontier(f)))
            .chain(self.portals.keys().map(|&p| NodeId::Portal(p)))
    }

    /// The edge between `a` and `b` (either order), or `None` when they are
    /// not connected (or equal, or unknown).
    ///
    /// # Complexity
    /// O(1) expected.
    pub fn edge(&self, a: NodeId, b: NodeId) -> Option<&Edge> {
        self.edges.get(&pair(a, b))
    }

    /// Cost of travelling from `a` to `b`, `None` when unreachable. Costs
    /// are symmetric on one level; over stairs they depend on the direction
    /// when climbing and descending cost differently.
    pub fn cost(&self, a: NodeId, b: NodeId) -> Option<f64> {
        self.edge(a, b).and_then(|e| e.cost_from(a))
    }

    /// All edges (each undirected pair once, in arbitrary order).
    pub fn edges(&self) -> impl Iterator<Item = &Edge> + '_ {
        self.edges.values()
    }

    /// Number of edges.
    pub fn edge_count(&self) -> usize {
        self.edges.len()
    }

    /// Exports G_F to petgraph: node weights are [`NodeId`]s (robot first,
    /// then home, then frontiers by id), edge weights are costs. Also returns
    /// the index of every node. The graph types are those of the
    /// re-exported [`crate::petgraph`] (a 0.x crate: its version is part of
    /// this crate's API).
    ///
    /// # Complexity
    /// O(V + E).
    pub fn to_petgraph(
        &self,
    ) -> (
        UnGraph<NodeId, f64>,
        std::collections::HashMap<NodeId, NodeIndex>,
    ) {
        let mut g = UnGraph::with_capacity(self.frontiers.len() + 2, self.edges.len());
        let mut index = std::collections::HashMap::new();
        for id in self.node_ids() {
            index.insert(id, g.add_node(id));
        }
        let mut keys: Vec<_> = self.edges.keys().copied().collect();
        keys.sort_unstable();
        for k in keys {
            if let (Some(&a), Some(&b)) = (index.get(&k.0), index.get(&k.1)) {
                g.add_edge(a, b, self.edges[&k].cost);
            }
        }
        (g, index)
    }
}

/// Serialises the edge map as a list (JSON maps need string keys).
mod edge_list {
    use super::{Edge, NodeId, pair};
    use rustc_hash::FxHashMap;
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    pub(super) fn serialize<S: Serializer>(
        m: &FxHashMap<(NodeId, NodeId), Edge>,
        s: S,
    ) -> Result<S::Ok, S::Error> {
        let mut v: Vec<&Edge> = m.values().collect();
        v.sort_by_key(|e| (e.from, e.to));
        v.serialize(s)
    }

    pub(super) fn deserialize<'de, D: Deserializer<'de>>(
        d: D,
    ) -> Result<FxHashMap<(NodeId, NodeId), Edge>, D::Error> {
        let v = Vec::<Edge>::deserialize(d)?;
        Ok(v.into_iter().map(|e| (pair(e.from, e.to), e)).collect())
    }
}
