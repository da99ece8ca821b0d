//! The cluster graph G_C: clusters, cluster edges, relocation waypoints and
//! the geometric ranking.

use std::borrow::Cow;
use std::collections::BTreeMap;
use std::fmt::Debug;

use nalgebra::{Point2, Vector2};
use serde::{Deserialize, Serialize};

use crate::ranking::ranking_order;
use crate::{
    ClusterConfig, ClusterError, DecisionGraph, GraphNode, MAX_ABS_COORD, connected_groups,
    geometric_utility,
};

/// Index of a cluster inside one [`ClusterGraph`] (`0..len`).
///
/// Clusters are numbered by their smallest member frontier id, so the index
/// is only meaningful within the graph that produced it; across rebuilds,
/// identify a cluster by its members (frontier ids are stable).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub struct ClusterId(pub usize);

/// How the robot reaches a cluster: the member frontier closest by graph
/// cost and its executable path, reused from the decision graph.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Relocation<Id> {
    /// The relocation waypoint: the member frontier attaining `w_rk`
    /// (smallest id among equal costs).
    pub waypoint: Id,
    /// `w_rk = min over members i of w_ri`, also the cluster distance `d_k`.
    pub cost: f64,
    /// The decision graph's executable path from the robot to `waypoint`.
    pub path: Vec<Point2<f64>>,
}

/// A cluster `C_k`: frontiers joined by chains of edges of cost `<= rho_c`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Cluster<Id> {
    /// Index of the cluster in its graph.
    pub id: ClusterId,
    /// Member frontier ids, ascending.
    pub members: Vec<Id>,
    /// Positions (m) of the members, aligned with `members`.
    pub member_positions: Vec<Point2<f64>>,
    /// The cluster node: the mean of the member positions (m).
    pub centre: Point2<f64>,
    /// Spread `r_k` (m): the root-mean-square distance of the member
    /// positions `p_i` to the centre `c_k`,
    /// `r_k = sqrt((1 / n_k) * sum_i ||p_i - c_k||^2)`. Zero for a single
    /// frontier; never larger than the largest member-to-centre distance.
    pub spread: f64,
    /// Robot edge of the cluster; `None` when no member is reachable from the
    /// robot.
    pub relocation: Option<Relocation<Id>>,
    /// `U_geo(C_k) = n_k (1 + eta r_k) / (1 + d_k)`; 0 for an unreachable
    /// cluster.
    pub utility: f64,
    /// The level (floor) of the members (0 on single-floor graphs).
    #[serde(default)]
    pub level: u16,
}

impl<Id> Cluster<Id> {
    /// `n_k`, the number of member frontiers (at least 1).
    pub fn len(&self) -> usize {
        self.members.len()
    }

    /// Always `false`: a cluster has at least one member (provided for
    /// symmetry with [`len`](Self::len)).
    pub fn is_empty(&self) -> bool {
        self.members.is_empty()
    }

    /// `d_k = w_rk`, the robot-to-cluster graph distance; `None` when
    /// unreachable.
    pub fn distance(&self) -> Option<f64> {
        self.relocation.as_ref().map(|r| r.cost)
    }
}

/// An edge of the cluster graph between clusters `a < b`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ClusterEdge<Id> {
    /// The cluster with the smaller index.
    pub a: ClusterId,
    /// The cluster with the larger index.
    pub b: ClusterId,
    /// `w_kl = min over member pairs (i in a, j in b) of w_ij`. Always
    /// `> rho_c` (cheaper pairs would have been merged).
    pub cost: f64,
    /// The member pair `(i in a, j in b)` attaining `w_kl` (lexicographically
    /// smallest among equal costs); its path is the decision graph's edge
    /// between them, see [`ClusterGraph::edge_path`].
    pub via: (Id, Id),
}

/// The cluster graph G_C built from a frontier decision graph.
///
/// Built in one pass by [`ClusterGraph::build`]; it copies what the supervisor
/// needs (members, centres, spreads, robot edges with paths, cluster edges,
/// the ranking) and issues no new path query. Serialisable; a deserialised
/// graph is trusted to be one that [`ClusterGraph::build`] produced.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ClusterGraph<Id> {
    config: ClusterConfig,
    robot: Point2<f64>,
    #[serde(default)]
    robot_level: u16,
    clusters: Vec<Cluster<Id>>,
    /// `(frontier, its cluster)`, sorted by frontier id.
    membership: Vec<(Id, ClusterId)>,
    /// Sorted by `(a, b)`.
    edges: Vec<ClusterEdge<Id>>,
    /// Reachable clusters by decreasing utility.
    ranking: Vec<ClusterId>,
}

fn valid_position(p: &Point2<f64>) -> bool {
    p.iter().all(|c| c.is_finite() && c.abs() <= MAX_ABS_COORD)
}

fn name<Id: Debug>(node: GraphNode<Id>) -> String {
    match node {
        GraphNode::Robot => "robot".to_owned(),
        GraphNode::Frontier(id) => format!("{id:?}"),
    }
}

fn checked_cost<Id: Debug + Copy>(
    cost: f64,
    a: GraphNode<Id>,
    b: GraphNode<Id>,
) -> Result<f64, ClusterError> {
    if cost.is_finite() && cost >= 0.0 {
        Ok(cost)
    } else {
        Err(ClusterError::InvalidCost {
            from: name(a),
            to: name(b),
            cost,
        })
    }
}

impl<Id: Copy + Ord + Debug> ClusterGraph<Id> {
    /// Builds the cluster graph of `graph`.
    ///
    /// # Algorithm
    /// 1. Frontiers are grouped by [`connected_groups`] over the frontier
    ///    edges of cost `<= rho_c`; clusters are numbered by smallest member.
    /// 2. Each cluster node sits at the mean member position; its spread is
    ///    the RMS member-to-centre distance.
    /// 3. Robot edge: `w_rk = min_i w_ri` over members; the minimising member
    ///    is the relocation waypoint and its robot path is copied.
    /// 4. Cluster edges: one pass over the frontier edges keeps, per cluster
    ///    pair, the minimum `w_ij` and the member pair attaining it.
    /// 5. `U_geo` of every reachable cluster; ranking by decreasing utility
    ///    (ties: nearer first, then smaller index).
    ///
    /// # Errors
    /// * [`ClusterError::InvalidConfig`] when `config` fails
    ///   [`ClusterConfig::validate`].
    /// * [`ClusterError::InvalidPosition`] for a NaN, infinite or
    ///   out-of-range robot or frontier position.
    /// * [`ClusterError::DuplicateFrontier`], [`ClusterError::UnknownFrontier`]
    ///   for malformed node or edge lists.
    /// * [`ClusterError::InvalidCost`] for a NaN, infinite or negative cost.
    /// * [`ClusterError::MissingPath`] when a robot edge has no path.
    ///
    /// Self-edges (`a == b`) carry no information and are ignored.
    ///
    /// # Complexity
    /// O((n + E) log n + P) time for n frontiers, E frontier edges,
    /// C clusters and P points of copied robot paths; O(n + C²) space at
    /// most (one entry per connected cluster pair). The robot's costs are
    /// queried once per frontier (bounds assume edge queries in O(log n) or
    /// faster, as for both provided graphs).
    ///
    /// # Example
    /// ```
    /// use nalgebra::Point2;
    /// use sornav_cluster_graph::{
    ///     ClusterConfig, ClusterGraph, GraphNode::{Frontier, Robot}, SparseDecisionGraph,
    /// };
    ///
    /// let mut g = SparseDecisionGraph::new(Point2::new(0.0, 0.0));
    /// for (id, x) in [(1_u32, 4.0), (2, 6.0), (3, 7.0)] {
    ///     g.add_frontier(id, Point2::new(x, 0.0));
    ///     let path = vec![Point2::new(0.0, 0.0), Point2::new(x, 0.0)];
    ///     g.set_edge(Robot, Frontier(id), x, path);
    /// }
    /// g.set_edge(Frontier(1), Frontier(2), 2.0, vec![]);
    /// // 2 and 3 are 1 m apart, but a wall makes the path 40 m long.
    /// g.set_edge(Frontier(2), Frontier(3), 40.0, vec![]);
    ///
    /// let cg = ClusterGraph::build(&g, &ClusterConfig::default())?;
    /// assert_eq!(cg.len(), 2);
    /// assert_eq!(cg.clusters()[0].members, vec![1, 2]);
    /// assert_eq!(cg.clusters()[0].centre, Point2::new(5.0, 0.0));
    /// let reloc = cg.clusters()[0].relocation.as_ref().unwrap();
    /// assert_eq!((reloc.waypoint, reloc.cost), (1, 4.0));
    /// # Ok::<(), sornav_cluster_graph::ClusterError>(())
    /// ```
    pub fn build<G>(graph: &G, config: &ClusterConfig) -> Result<Self, ClusterError>
    where
        G: DecisionGraph<FrontierId = Id> + ?Sized,
    {
        config.validate()?;
        let robot = graph.robot_position();
        if !valid_position(&robot) {
            return Err(ClusterError::InvalidPosition {
                what: "robot".into(),
            });
        }

        let mut frontiers: Vec<(Id, Point2<f64>)> = graph.frontiers().collect();
        frontiers.sort_by_key(|f| f.0);
        for w in frontiers.windows(2) {
            if w[0].0 == w[1].0 {
                return Err(ClusterError::DuplicateFrontier(format!("{:?}", w[0].0)));
            }
        }
        if let Some((id, _)) = frontiers.iter().find(|(_, p)| !valid_position(p)) {
            return Err(ClusterError::InvalidPosition {
                what: format!("frontier {id:?}"),
            });
        }
        let index_of = |id: Id| {
            frontiers
                .binary_search_by(|f| f.0.cmp(&id))
                .map_err(|_| ClusterError::UnknownFrontier(format!("{id:?}")))
        };

        let mut edges: Vec<(usize, usize, f64)> = Vec::new();
        for (a, b, cost) in graph.frontier_edges() {
            let cost = checked_cost(cost, GraphNode::Frontier(a), GraphNode::Frontier(b))?;
            let (i, j) = (index_of(a)?, index_of(b)?);
            if i != j {
                edges.push((i, j, cost));
            }
        }

        let levels: Vec<u16> = frontiers
            .iter()
            .map(|f| graph.level(GraphNode::Frontier(f.0)))
            .collect();
        let groups = connected_groups(
            frontiers.len(),
            edges
                .iter()
                .copied()
                .filter(|&(i, j, _)| levels[i] == levels[j]),
            config.rho_c,
        );
        let mut cluster_of = vec![0_usize; frontiers.len()];
        for (k, group) in groups.iter().enumerate() {
            for &i in group {
                cluster_of[i] = k;
            }
        }

        let mut clusters = Vec::with_capacity(groups.len());
        for (k, group) in groups.iter().enumerate() {
            let mut cluster = Self::make_cluster(graph, config, ClusterId(k), group, &frontiers)?;
            cluster.level = group.first().map_or(0, |&i| levels[i]);
            clusters.push(cluster);
        }

        let edges = Self::cluster_edges(&edges, &cluster_of, &frontiers);

        let mut ranking: Vec<ClusterId> = clusters
            .iter()
            .filter(|c| c.relocation.is_some())
            .map(|c| c.id)
            .collect();
        ranking.sort_by(|a, b| {
            let key = |k: ClusterId| {
                let c = &clusters[k.0];
                (c.utility, c.distance().unwrap_or(f64::INFINITY), k.0)
            };
            ranking_order(key(*a), key(*b))
        });

        let membership = frontiers
            .iter()
            .zip(&cluster_of)
            .map(|((id, _), &k)| (*id, ClusterId(k)))
            .collect();

        Ok(Self {
            config: *config,
            robot,
            robot_level: graph.level(GraphNode::Robot),
            clusters,
            membership,
            edges,
            ranking,
        })
    }

    /// One cluster from its member indices: centre, spread, robot edge and
    /// utility.
    fn make_cluster<G>(
        graph: &G,
        config: &ClusterConfig,
        id: ClusterId,
        group: &[usize],
        frontiers: &[(Id, Point2<f64>)],
    ) -> Result<Cluster<Id>, ClusterError>
    where
        G: DecisionGraph<FrontierId = Id> + ?Sized,
    {
        let members: Vec<Id> = group.iter().map(|&i| frontiers[i].0).collect();
        let member_positions: Vec<Point2<f64>> = group.iter().map(|&i| frontiers[i].1).collect();
        // Groups are never empty; member counts are far below 2^52.
        #[allow(clippy::cast_precision_loss)]
        let n = members.len() as f64;
        let sum: Vector2<f64> = member_positions.iter().map(|p| p.coords).sum();
        let centre = Point2::from(sum / n);
        let spread = (member_positions
            .iter()
            .map(|p| (p - centre).norm_squared())
            .sum::<f64>()
            / n)
            .sqrt();

        let mut best: Option<(f64, Id)> = None;
        for &m in &members {
            let node = GraphNode::Frontier(m);
            if let Some(cost) = graph.cost(GraphNode::Robot, node) {
                let cost = checked_cost(cost, GraphNode::Robot, node)?;
                // Members are ascending: a strict `<` keeps the smallest id on ties.
                if best.is_none_or(|(c, _)| cost < c) {
                    best = Some((cost, m));
                }
            }
        }
        let relocation = match best {
            None => None,
            Some((cost, waypoint)) => {
                let path = graph
                    .path(GraphNode::Robot, GraphNode::Frontier(waypoint))
                    .ok_or_else(|| ClusterError::MissingPath(format!("{waypoint:?}")))?;
                Some(Relocation {
                    waypoint,
                    cost,
                    path: path.into_owned(),
                })
            }
        };
        let utility = relocation.as_ref().map_or(0.0, |r| {
            geometric_utility(members.len(), spread, r.cost, config.eta)
        });
        Ok(Cluster {
            id,
            members,
            member_positions,
            centre,
            spread,
            relocation,
            utility,
            level: 0,
        })
    }

    /// Minimum frontier edge per cluster pair, with the attaining member pair.
    fn cluster_edges(
        edges: &[(usize, usize, f64)],
        cluster_of: &[usize],
        frontiers: &[(Id, Point2<f64>)],
    ) -> Vec<ClusterEdge<Id>> {
        let mut best: BTreeMap<(usize, usize), (f64, (Id, Id))> = BTreeMap::new();
        for &(i, j, cost) in edges {
            let (ki, kj) = (cluster_of[i], cluster_of[j]);
            if ki == kj {
                continue;
            }
            let (key, via) = if ki < kj {
                ((ki, kj), (frontiers[i].0, frontiers[j].0))
            } else {
                ((kj, ki), (frontiers[j].0, frontiers[i].0))
            };
            best.entry(key)
                .and_modify(|b| {
                    if cost < b.0 || (cost == b.0 && via < b.1) {
                        *b = (cost, via);
                    }
                })
                .or_insert((cost, via));
        }
        best.into_iter()
            .map(|((a, b), (cost, via))| ClusterEdge {
                a: ClusterId(a),
                b: ClusterId(b),
                cost,
                via,
            })
            .collect()
    }

    /// The configuration the graph was built with (also used for contexts).
    pub fn config(&self) -> &ClusterConfig {
        &self.config
    }

    /// Robot position (m) at build time.
    pub fn robot_position(&self) -> Point2<f64> {
        self.robot
    }

    /// The level (floor) of the robot the graph was built with.
    pub fn robot_level(&self) -> u16 {
        self.robot_level
    }

    /// Number of clusters.
    pub fn len(&self) -> usize {
        self.clusters.len()
    }

    /// Whether there is no cluster (no frontier).
    pub fn is_empty(&self) -> bool {
        self.clusters.is_empty()
    }

    /// All clusters, indexed by [`ClusterId`] (ordered by smallest member).
    pub fn clusters(&self) -> &[Cluster<Id>] {
        &self.clusters
    }

    /// The cluster with this index.
    pub fn cluster(&self, id: ClusterId) -> Option<&Cluster<Id>> {
        self.clusters.get(id.0)
    }

    /// The cluster a frontier belongs to.
    ///
    /// # Complexity
    /// O(log n).
    pub fn cluster_of(&self, frontier: Id) -> Option<ClusterId> {
        self.membership
            .binary_search_by(|m| m.0.cmp(&frontier))
            .ok()
            .map(|i| self.membership[i].1)
    }

    /// The cluster that continues a cluster of an earlier graph: the one
    /// holding the most of `previous_members` (smaller index on ties), with
    /// that count; `None` when none of them is still a frontier.
    ///
    /// Cluster indices are renumbered at every build, while frontier ids are
    /// stable; this is how a caller follows a decision unit (an active
    /// relocation target) across rebuilds.
    ///
    /// # Complexity
    /// O(m log n) for m previous members.
    pub fn matching_cluster(&self, previous_members: &[Id]) -> Option<(ClusterId, usize)> {
        let mut found: Vec<ClusterId> = previous_members
            .iter()
            .filter_map(|&m| self.cluster_of(m))
            .collect();
        found.sort_unstable();
        found
            .chunk_by(|a, b| a == b)
            .map(|run| (run[0], run.len()))
            .max_by(|a, b| a.1.cmp(&b.1).then(b.0.cmp(&a.0)))
    }

    /// All cluster edges, sorted by `(a, b)`.
    pub fn edges(&self) -> &[ClusterEdge<Id>] {
        &self.edges
    }

    /// The edge between clusters `k` and `l` (either order), `None` when no
    /// member pair is connected.
    ///
    /// # Complexity
    /// O(log E_C).
    pub fn edge(&self, k: ClusterId, l: ClusterId) -> Option<&ClusterEdge<Id>> {
        let key = if k <= l { (k, l) } else { (l, k) };
        self.edges
            .binary_search_by(|e| (e.a, e.b).cmp(&key))
            .ok()
            .map(|i| &self.edges[i])
    }

    /// The executable path of the cluster edge from `from` to `to`, taken
    /// from `graph` (which must be the graph this cluster graph was built
    /// from): the decision graph's path between the member pair
    /// [`ClusterEdge::via`], oriented from the member of `from`.
    pub fn edge_path<'g, G>(
        &self,
        graph: &'g G,
        from: ClusterId,
        to: ClusterId,
    ) -> Option<Cow<'g, [Point2<f64>]>>
    where
        G: DecisionGraph<FrontierId = Id> + ?Sized,
    {
        let e = self.edge(from, to)?;
        let (s, t) = if from == e.a {
            (e.via.0, e.via.1)
        } else {
            (e.via.1, e.via.0)
        };
        graph.path(GraphNode::Frontier(s), GraphNode::Frontier(t))
    }

    /// Every cluster reachable from the robot, by decreasing `U_geo` (ties:
    /// smaller `d_k`, then smaller index). Unreachable clusters are not
    /// ranked: there is no path to relocate along.
    pub fn ranking(&self) -> &[ClusterId] {
        &self.ranking
    }

    /// The first `K` ([`ClusterConfig::top_k`]) clusters of the
    /// [`ranking`](Self::ranking): the candidates passed to the supervisor.
    pub fn top_k(&self) -> &[ClusterId] {
        &self.ranking[..self.ranking.len().min(self.config.top_k)]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::SparseDecisionGraph;
    use GraphNode::{Frontier, Robot};

    fn p(x: f64, y: f64) -> Point2<f64> {
        Point2::new(x, y)
    }

    #[test]
    fn empty_graph_gives_empty_cluster_graph() {
        let g = SparseDecisionGraph::<u32>::new(p(0.0, 0.0));
        let cg = ClusterGraph::build(&g, &ClusterConfig::default()).unwrap();
        assert!(cg.is_empty());
        assert!(cg.top_k().is_empty());
        assert!(cg.edges().is_empty());
    }

    #[test]
    fn unreachable_cluster_is_kept_but_not_ranked() {
        let mut g = SparseDecisionGraph::new(p(0.0, 0.0));
        g.add_frontier(1_u32, p(1.0, 0.0));
        g.add_frontier(2, p(9.0, 0.0));
        g.set_edge(Robot, Frontier(1), 1.0, vec![p(0.0, 0.0), p(1.0, 0.0)]);
        let cg = ClusterGraph::build(&g, &ClusterConfig::default()).unwrap();
        assert_eq!(cg.len(), 2);
        assert_eq!(cg.ranking(), &[ClusterId(0)]);
        assert_eq!(cg.clusters()[1].utility, 0.0);
        assert!(cg.clusters()[1].distance().is_none());
        assert!(cg.edge(ClusterId(0), ClusterId(1)).is_none());
    }

    #[test]
    fn cluster_edge_keeps_the_cheapest_pair_and_its_path() {
        let mut g = SparseDecisionGraph::new(p(0.0, 0.0));
        for (id, x) in [(1_u32, 0.0), (2, 1.0), (3, 50.0), (4, 51.0)] {
            g.add_frontier(id, p(x, 0.0));
        }
        g.set_edge(Frontier(1), Frontier(2), 1.0, vec![]);
        g.set_edge(Frontier(3), Frontier(4), 1.0, vec![]);
        g.set_edge(Frontier(1), Frontier(3), 60.0, vec![]);
        g.set_edge(
            Frontier(4),
            Frontier(2),
            50.0,
            vec![p(51.0, 0.0), p(1.0, 0.0)],
        );
        let cg = ClusterGraph::build(&g, &ClusterConfig::default()).unwrap();
        let e = cg.edge(ClusterId(1), ClusterId(0)).unwrap();
        assert_eq!((e.cost, e.via), (50.0, (2, 4)));
        let path = cg.edge_path(&g, ClusterId(0), ClusterId(1)).unwrap();
        assert_eq!(&path[..], &[p(1.0, 0.0), p(51.0, 0.0)]);
        let back = cg.edge_path(&g, ClusterId(1), ClusterId(0)).unwrap();
        assert_eq!(back[0], p(51.0, 0.0));
        assert_eq!(cg.cluster_of(4), Some(ClusterId(1)));
        assert_eq!(cg.cluster_of(9), None);
    }

    #[test]
    fn equal_cost_cluster_edges_pick_the_smallest_member_pair() {
        // k = {2, 5, 9}, l = {3, 8}; (9, 3) and (5, 8) both cost 30. Edge
        // listings visit (3, 9) before (5, 8), but (5, 8) is the smaller pair.
        let mut g = SparseDecisionGraph::new(p(0.0, 0.0));
        for id in [2_u32, 3, 5, 8, 9] {
            g.add_frontier(id, p(f64::from(id), 0.0));
        }
        g.set_edge(Frontier(2), Frontier(5), 1.0, vec![]);
        g.set_edge(Frontier(5), Frontier(9), 1.0, vec![]);
        g.set_edge(Frontier(3), Frontier(8), 1.0, vec![]);
        g.set_edge(Frontier(9), Frontier(3), 30.0, vec![]);
        g.set_edge(Frontier(5), Frontier(8), 30.0, vec![]);
        let cg = ClusterGraph::build(&g, &ClusterConfig::default()).unwrap();
        assert_eq!(cg.len(), 2);
        assert_eq!(cg.edges()[0].via, (5, 8));
    }

    #[test]
    fn waypoint_ties_pick_the_smallest_id() {
        let mut g = SparseDecisionGraph::new(p(0.0, 0.0));
        for id in [5_u32, 3, 4] {
            g.add_frontier(id, p(f64::from(id), 0.0));
            g.set_edge(Robot, Frontier(id), 7.0, vec![p(0.0, 0.0)]);
        }
        g.set_edge(Frontier(3), Frontier(4), 1.0, vec![]);
        g.set_edge(Frontier(4), Frontier(5), 1.0, vec![]);
        let cg = ClusterGraph::build(&g, &ClusterConfig::default()).unwrap();
        assert_eq!(cg.len(), 1);
        assert_eq!(cg.clusters()[0].relocation.as_ref().unwrap().waypoint, 3);
        approx::assert_relative_eq!(cg.clusters()[0].spread, (2.0_f64 / 3.0).sqrt());
    }

    #[test]
    fn bad_inputs_are_typed_errors() {
        let cfg = ClusterConfig::default();
        let mut g = SparseDecisionGraph::new(p(0.0, 0.0));
        g.add_frontier(1_u32, p(0.0, 1.0));
        g.add_frontier(2, p(0.0, 2.0));

        let mut nan_cost = g.clone();
        nan_cost.set_edge(Frontier(1), Frontier(2), f64::NAN, vec![]);
        assert!(matches!(
            ClusterGraph::build(&nan_cost, &cfg),
            Err(ClusterError::InvalidCost { .. })
        ));
        let mut neg_robot = g.clone();
        neg_robot.set_edge(Robot, Frontier(2), -1.0, vec![]);
        assert!(matches!(
            ClusterGraph::build(&neg_robot, &cfg),
            Err(ClusterError::InvalidCost { .. })
        ));
        let mut unknown = g.clone();
        unknown.set_edge(Frontier(1), Frontier(9), 1.0, vec![]);
        assert_eq!(
            ClusterGraph::build(&unknown, &cfg),
            Err(ClusterError::UnknownFrontier("9".into()))
        );
        let mut nan_pos = g.clone();
        nan_pos.add_frontier(2, p(f64::NAN, 0.0));
        assert!(matches!(
            ClusterGraph::build(&nan_pos, &cfg),
            Err(ClusterError::InvalidPosition { .. })
        ));
        let mut far = g.clone();
        far.set_robot_position(p(0.0, 2.0 * MAX_ABS_COORD));
        assert!(matches!(
            ClusterGraph::build(&far, &cfg),
            Err(ClusterError::InvalidPosition { .. })
        ));
        let bad_cfg = ClusterConfig {
            rho_c: f64::NAN,
            ..cfg
        };
        assert!(matches!(
            ClusterGraph::build(&g, &bad_cfg),
            Err(ClusterError::InvalidConfig(_))
        ));
    }

    /// A graph that lists a frontier twice and has a robot cost without a path.
    struct Broken {
        duplicate: bool,
    }

    impl DecisionGraph for Broken {
        type FrontierId = u8;
        fn robot_position(&self) -> Point2<f64> {
            Point2::origin()
        }
        fn frontiers(&self) -> impl Iterator<Item = (u8, Point2<f64>)> + '_ {
            let n = if self.duplicate { 2 } else { 1 };
            std::iter::repeat_n((1, Point2::origin()), n)
        }
        fn cost(&self, a: GraphNode<u8>, _: GraphNode<u8>) -> Option<f64> {
            (a == Robot).then_some(1.0)
        }
        fn path(&self, _: GraphNode<u8>, _: GraphNode<u8>) -> Option<Cow<'_, [Point2<f64>]>> {
            None
        }
    }

    #[test]
    fn inconsistent_graphs_are_typed_errors() {
        let cfg = ClusterConfig::default();
        assert_eq!(
            ClusterGraph::build(&Broken { duplicate: true }, &cfg),
            Err(ClusterError::DuplicateFrontier("1".into()))
        );
        assert_eq!(
            ClusterGraph::build(&Broken { duplicate: false }, &cfg),
            Err(ClusterError::MissingPath("1".into()))
        );
    }
}
