//! The input: a frontier decision graph G_F seen through a small trait.

use std::borrow::Cow;
use std::collections::BTreeMap;
use std::fmt::Debug;

use nalgebra::Point2;
use serde::{Deserialize, Serialize};

/// Largest accepted absolute coordinate (m) of a robot or frontier position.
///
/// Positions beyond it (or NaN/infinite) are rejected with
/// [`crate::ClusterError::InvalidPosition`]; the bound keeps means, spreads and
/// utilities finite.
pub const MAX_ABS_COORD: f64 = 1.0e9;

/// A node of the decision graph as far as clustering is concerned: the robot
/// node `v_r` or a frontier node. (A home node, if the graph has one, plays no
/// part in clustering.)
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub enum GraphNode<Id> {
    /// The robot node `v_r`.
    Robot,
    /// A frontier node.
    Frontier(Id),
}

/// A frontier decision graph G_F: frontier nodes with stable ids and
/// positions, a robot node, and undirected edges carrying a traversal cost
/// `w_ij` and an executable path.
///
/// This is everything the cluster graph reads. It is implemented for
/// `sornav_frontier_graph::FrontierGraph` (see [`crate::frontier_adapter`]) and
/// for the in-memory [`SparseDecisionGraph`]; any planner's graph can
/// implement it.
///
/// # Contract
/// * Edges are undirected: `cost(a, b) == cost(b, a)`, and `path(b, a)` is
///   `path(a, b)` reversed. A missing edge means "unreachable".
/// * [`frontier_edges`](Self::frontier_edges) lists every frontier-frontier
///   edge once, with the cost [`cost`](Self::cost) reports.
/// * Whenever `cost(Robot, Frontier(f))` is `Some`, `path(Robot, Frontier(f))`
///   is `Some` too.
///
/// Violations of value ranges (NaN costs, unknown ids, ...) are detected by
/// [`crate::ClusterGraph::build`] and reported as typed errors.
pub trait DecisionGraph {
    /// Stable identifier of a frontier node.
    type FrontierId: Copy + Ord + Debug;

    /// Position (m) of the robot node.
    fn robot_position(&self) -> Point2<f64>;

    /// Every frontier node with its position (m), each id once.
    fn frontiers(&self) -> impl Iterator<Item = (Self::FrontierId, Point2<f64>)> + '_;

    /// Traversal cost `w_ab` of the edge between `a` and `b`, `None` when
    /// there is no edge (unreachable pair, or `a == b`).
    fn cost(&self, a: GraphNode<Self::FrontierId>, b: GraphNode<Self::FrontierId>) -> Option<f64>;

    /// Executable path of the edge, oriented from `from` to `to`; `None`
    /// when there is no edge.
    fn path(
        &self,
        from: GraphNode<Self::FrontierId>,
        to: GraphNode<Self::FrontierId>,
    ) -> Option<Cow<'_, [Point2<f64>]>>;

    /// The level (floor) of a node; frontiers are grouped only with
    /// frontiers of their own level, and semantic contexts count only
    /// objects of the same level. The default puts everything on level 0
    /// (single-floor graphs).
    fn level(&self, node: GraphNode<Self::FrontierId>) -> u16 {
        let _ = node;
        0
    }

    /// Every frontier-frontier edge `(a, b, w_ab)`, each unordered pair once.
    ///
    /// The default implementation queries [`cost`](Self::cost) for all pairs
    /// (O(n²)); graphs that store edges should list them directly.
    fn frontier_edges(
        &self,
    ) -> impl Iterator<Item = (Self::FrontierId, Self::FrontierId, f64)> + '_ {
        let ids: Vec<Self::FrontierId> = self.frontiers().map(|(id, _)| id).collect();
        let mut edges = Vec::new();
        for (i, &a) in ids.iter().enumerate() {
            for &b in &ids[i + 1..] {
                if let Some(c) = self.cost(GraphNode::Frontier(a), GraphNode::Frontier(b)) {
                    edges.push((a, b, c));
                }
            }
        }
        edges.into_iter()
    }
}

/// Sorted endpoint pair keying a stored edge.
type EdgeKey<Id> = (GraphNode<Id>, GraphNode<Id>);

/// One stored edge of a [`SparseDecisionGraph`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SparseEdge<Id> {
    /// Endpoint the path starts at.
    pub from: GraphNode<Id>,
    /// Endpoint the path ends at.
    pub to: GraphNode<Id>,
    /// Traversal cost `w`.
    pub cost: f64,
    /// Executable path from `from` to `to` (m).
    pub path: Vec<Point2<f64>>,
}

/// A small in-memory decision graph: the robot, frontiers and explicitly set
/// edges. Useful to run the cluster graph without a frontier map (tests,
/// other planners, recorded graphs). Serialises as plain lists.
///
/// # Example
/// ```
/// use nalgebra::Point2;
/// use sornav_cluster_graph::{DecisionGraph, GraphNode, SparseDecisionGraph};
///
/// let mut g = SparseDecisionGraph::new(Point2::new(0.0, 0.0));
/// g.add_frontier(7_u32, Point2::new(3.0, 4.0));
/// let path = vec![Point2::new(0.0, 0.0), Point2::new(3.0, 4.0)];
/// g.set_edge(GraphNode::Robot, GraphNode::Frontier(7), 5.0, path);
/// assert_eq!(g.cost(GraphNode::Frontier(7), GraphNode::Robot), Some(5.0));
/// let back = g.path(GraphNode::Frontier(7), GraphNode::Robot).unwrap();
/// assert_eq!(back[0], Point2::new(3.0, 4.0));
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(
    into = "SparseRepr<Id>",
    from = "SparseRepr<Id>",
    bound(
        serialize = "Id: Ord + Clone + Serialize",
        deserialize = "Id: Ord + Deserialize<'de>"
    )
)]
pub struct SparseDecisionGraph<Id: Ord> {
    robot: Point2<f64>,
    frontiers: BTreeMap<Id, Point2<f64>>,
    /// Keyed by the sorted endpoint pair; the path runs from key.0 to key.1.
    edges: BTreeMap<EdgeKey<Id>, (f64, Vec<Point2<f64>>)>,
}

/// Serialised form of [`SparseDecisionGraph`] (maps with composite keys are
/// not representable in JSON).
#[derive(Serialize, Deserialize)]
struct SparseRepr<Id> {
    robot: Point2<f64>,
    frontiers: Vec<(Id, Point2<f64>)>,
    edges: Vec<SparseEdge<Id>>,
}

impl<Id: Ord + Clone> From<SparseDecisionGraph<Id>> for SparseRepr<Id> {
    fn from(g: SparseDecisionGraph<Id>) -> Self {
        Self {
            robot: g.robot,
            frontiers: g.frontiers.into_iter().collect(),
            edges: g
                .edges
                .into_iter()
                .map(|((from, to), (cost, path))| SparseEdge {
                    from,
                    to,
                    cost,
                    path,
                })
                .collect(),
        }
    }
}

impl<Id: Ord> From<SparseRepr<Id>> for SparseDecisionGraph<Id> {
    fn from(r: SparseRepr<Id>) -> Self {
        let mut g = SparseDecisionGraph {
            robot: r.robot,
            frontiers: r.frontiers.into_iter().collect(),
            edges: BTreeMap::new(),
        };
        for e in r.edges {
            g.set_edge(e.from, e.to, e.cost, e.path);
        }
        g
    }
}

impl<Id: Ord> SparseDecisionGraph<Id> {
    /// An empty graph with the robot at `robot`.
    pub fn new(robot: Point2<f64>) -> Self {
        Self {
            robot,
            frontiers: BTreeMap::new(),
            edges: BTreeMap::new(),
        }
    }

    /// Moves the robot node. Robot edges are kept (set them anew when the
    /// robot's paths change).
    pub fn set_robot_position(&mut self, robot: Point2<f64>) {
        self.robot = robot;
    }

    /// Adds a frontier, or moves an existing one; returns its previous
    /// position.
    pub fn add_frontier(&mut self, id: Id, position: Point2<f64>) -> Option<Point2<f64>> {
        self.frontiers.insert(id, position)
    }

    /// Sets (or replaces) the undirected edge between `from` and `to` with
    /// its cost and its path from `from` to `to`. A self-edge (`from == to`)
    /// is ignored: a node is not its own neighbour. Values are validated when
    /// the cluster graph is built, not here.
    ///
    /// # Complexity
    /// O(log E + |path|).
    pub fn set_edge(
        &mut self,
        from: GraphNode<Id>,
        to: GraphNode<Id>,
        cost: f64,
        mut path: Vec<Point2<f64>>,
    ) {
        match from.cmp(&to) {
            std::cmp::Ordering::Equal => {}
            std::cmp::Ordering::Less => {
                self.edges.insert((from, to), (cost, path));
            }
            std::cmp::Ordering::Greater => {
                path.reverse();
                self.edges.insert((to, from), (cost, path));
            }
        }
    }

    /// Number of frontiers.
    pub fn frontier_count(&self) -> usize {
        self.frontiers.len()
    }

    /// Number of edges (robot edges included).
    pub fn edge_count(&self) -> usize {
        self.edges.len()
    }
}

impl<Id: Ord + Copy + Debug> DecisionGraph for SparseDecisionGraph<Id> {
    type FrontierId = Id;

    fn robot_position(&self) -> Point2<f64> {
        self.robot
    }

    fn frontiers(&self) -> impl Iterator<Item = (Id, Point2<f64>)> + '_ {
        self.frontiers.iter().map(|(&id, &p)| (id, p))
    }

    fn cost(&self, a: GraphNode<Id>, b: GraphNode<Id>) -> Option<f64> {
        let key = if a <= b { (a, b) } else { (b, a) };
        self.edges.get(&key).map(|(c, _)| *c)
    }

    fn path(&self, from: GraphNode<Id>, to: GraphNode<Id>) -> Option<Cow<'_, [Point2<f64>]>> {
        if from <= to {
            self.edges
                .get(&(from, to))
                .map(|(_, p)| Cow::Borrowed(&p[..]))
        } else {
            self.edges
                .get(&(to, from))
                .map(|(_, p)| Cow::Owned(p.iter().rev().copied().collect()))
        }
    }

    fn frontier_edges(&self) -> impl Iterator<Item = (Id, Id, f64)> + '_ {
        self.edges
            .iter()
            .filter_map(|((a, b), (c, _))| match (a, b) {
                (GraphNode::Frontier(a), GraphNode::Frontier(b)) => Some((*a, *b, *c)),
                _ => None,
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(x: f64, y: f64) -> Point2<f64> {
        Point2::new(x, y)
    }

    #[test]
    fn edges_are_undirected_and_paths_oriented() {
        let mut g = SparseDecisionGraph::new(p(0.0, 0.0));
        g.add_frontier(1_u8, p(1.0, 0.0));
        g.add_frontier(2, p(2.0, 0.0));
        g.set_edge(
            GraphNode::Frontier(2),
            GraphNode::Frontier(1),
            1.5,
            vec![p(2.0, 0.0), p(1.5, 0.5), p(1.0, 0.0)],
        );
        let f = GraphNode::Frontier;
        assert_eq!(g.cost(f(1), f(2)), Some(1.5));
        assert_eq!(g.cost(f(2), f(1)), Some(1.5));
        assert_eq!(g.path(f(1), f(2)).unwrap()[0], p(1.0, 0.0));
        assert_eq!(g.path(f(2), f(1)).unwrap()[0], p(2.0, 0.0));
        assert_eq!(g.cost(GraphNode::Robot, f(1)), None);
        assert_eq!(g.frontier_edges().collect::<Vec<_>>(), vec![(1, 2, 1.5)]);
        g.set_edge(f(1), f(1), 0.0, vec![]);
        assert_eq!(g.edge_count(), 1);
    }

    /// A graph relying on the trait's default `frontier_edges`.
    struct Dense(Vec<Vec<Option<f64>>>);

    impl DecisionGraph for Dense {
        type FrontierId = usize;
        fn robot_position(&self) -> Point2<f64> {
            Point2::origin()
        }
        fn frontiers(&self) -> impl Iterator<Item = (usize, Point2<f64>)> + '_ {
            (0..self.0.len()).map(|i| (i, Point2::origin()))
        }
        fn cost(&self, a: GraphNode<usize>, b: GraphNode<usize>) -> Option<f64> {
            match (a, b) {
                (GraphNode::Frontier(a), GraphNode::Frontier(b)) => self.0[a][b],
                _ => None,
            }
        }
        fn path(&self, _: GraphNode<usize>, _: GraphNode<usize>) -> Option<Cow<'_, [Point2<f64>]>> {
            None
        }
    }

    #[test]
    fn default_frontier_edges_lists_each_pair_once() {
        let g = Dense(vec![
            vec![None, Some(1.0), None],
            vec![Some(1.0), None, Some(2.0)],
            vec![None, Some(2.0), None],
        ]);
        let e: Vec<_> = g.frontier_edges().collect();
        assert_eq!(e, vec![(0, 1, 1.0), (1, 2, 2.0)]);
    }

    #[test]
    fn serde_round_trip() {
        let mut g = SparseDecisionGraph::new(p(0.5, 0.5));
        g.add_frontier(3_u64, p(1.0, 2.0));
        g.set_edge(
            GraphNode::Frontier(3),
            GraphNode::Robot,
            2.0,
            vec![p(1.0, 2.0), p(0.5, 0.5)],
        );
        let json = serde_json::to_string(&g).unwrap();
        let back: SparseDecisionGraph<u64> = serde_json::from_str(&json).unwrap();
        assert_eq!(back, g);
    }
}
