//! Property and differential tests of the cluster graph against simple
//! references (BFS components, brute-force minima, direct formula
//! evaluation, brute-force context filters) on random decision graphs.

use std::borrow::Cow;
use std::collections::BTreeSet;

mod common;

use nalgebra::{Point2, Point3};
use proptest::prelude::*;
use sornav_cluster_graph::{
    ClusterConfig, ClusterGraph, ClusterId, DecisionGraph, GraphNode, ObjectSummary,
    SparseDecisionGraph, geometric_utility,
};

use GraphNode::{Frontier, Robot};

/// A random decision graph: frontier ids (sparse, sorted), positions, a
/// symmetric optional cost per pair, an optional robot cost per frontier.
#[derive(Debug, Clone)]
struct Case {
    ids: Vec<u32>,
    positions: Vec<Point2<f64>>,
    costs: Vec<Vec<Option<f64>>>,
    robot_costs: Vec<Option<f64>>,
    config: ClusterConfig,
}

/// Costs and coordinates on a 0.5 grid, so that ties (equal costs, equal
/// utilities) occur and exercise the tie-breaking rules.
fn half(max: u32) -> impl Strategy<Value = f64> {
    (0..=max).prop_map(|v| f64::from(v) * 0.5)
}

/// Coarse costs (multiples of 5): many equal-cost member pairs and robot
/// edges, so that the tie-breaking rules are exercised.
fn coarse(max: u32) -> impl Strategy<Value = f64> {
    (0..=max / 5).prop_map(|v| f64::from(v) * 5.0)
}

fn coord() -> impl Strategy<Value = f64> {
    (-60_i32..=60).prop_map(|v| f64::from(v) * 0.5)
}

fn case() -> impl Strategy<Value = Case> {
    (
        proptest::collection::btree_set(0_u32..500, 0..16),
        half(120),
    )
        .prop_flat_map(|(ids, rho_c)| {
            let n = ids.len();
            let ids: Vec<u32> = ids.into_iter().collect();
            (
                Just(ids),
                proptest::collection::vec((coord(), coord()), n),
                proptest::collection::vec(proptest::option::weighted(0.6, coarse(60)), n * n),
                proptest::collection::vec(proptest::option::weighted(0.8, coarse(80)), n),
                Just(rho_c),
                (0_u32..=20).prop_map(|e| f64::from(e) * 0.05),
                1_usize..6,
            )
        })
        .prop_map(|(ids, pos, raw, robot_costs, rho_c, eta, top_k)| {
            let n = ids.len();
            let mut costs = vec![vec![None; n]; n];
            for i in 0..n {
                for j in i + 1..n {
                    costs[i][j] = raw[i * n + j];
                    costs[j][i] = raw[i * n + j];
                }
            }
            Case {
                ids,
                positions: pos.into_iter().map(|(x, y)| Point2::new(x, y)).collect(),
                costs,
                robot_costs,
                config: ClusterConfig {
                    rho_c,
                    eta,
                    top_k,
                    ..ClusterConfig::default()
                },
            }
        })
}

/// A path that identifies its edge: robot -> frontier i ends at a point
/// unique to i.
fn robot_path(case: &Case, i: usize) -> Vec<Point2<f64>> {
    vec![
        Point2::new(-1.0, -1.0),
        case.positions[i],
        Point2::new(i as f64, 1e3),
    ]
}

fn sparse(case: &Case) -> SparseDecisionGraph<u32> {
    let mut g = SparseDecisionGraph::new(Point2::new(0.25, -0.75));
    for (i, &id) in case.ids.iter().enumerate() {
        g.add_frontier(id, case.positions[i]);
        if let Some(c) = case.robot_costs[i] {
            g.set_edge(Robot, Frontier(id), c, robot_path(case, i));
        }
        for j in i + 1..case.ids.len() {
            if let Some(c) = case.costs[i][j] {
                let path = vec![case.positions[i], case.positions[j]];
                g.set_edge(Frontier(id), Frontier(case.ids[j]), c, path);
            }
        }
    }
    g
}

/// The same graph behind the trait's default `frontier_edges` (all-pairs
/// cost queries) instead of the stored edge list.
struct AllPairs<'a>(&'a SparseDecisionGraph<u32>);

impl DecisionGraph for AllPairs<'_> {
    type FrontierId = u32;
    fn robot_position(&self) -> Point2<f64> {
        self.0.robot_position()
    }
    fn frontiers(&self) -> impl Iterator<Item = (u32, Point2<f64>)> + '_ {
        self.0.frontiers()
    }
    fn cost(&self, a: GraphNode<u32>, b: GraphNode<u32>) -> Option<f64> {
        self.0.cost(a, b)
    }
    fn path(&self, a: GraphNode<u32>, b: GraphNode<u32>) -> Option<Cow<'_, [Point2<f64>]>> {
        self.0.path(a, b)
    }
}

/// The same graph listing its frontier edges in reverse order with swapped
/// endpoints: results must not depend on edge order or orientation.
struct Reversed<'a>(&'a SparseDecisionGraph<u32>);

impl DecisionGraph for Reversed<'_> {
    type FrontierId = u32;
    fn robot_position(&self) -> Point2<f64> {
        self.0.robot_position()
    }
    fn frontiers(&self) -> impl Iterator<Item = (u32, Point2<f64>)> + '_ {
        let mut v: Vec<_> = self.0.frontiers().collect();
        v.reverse();
        v.into_iter()
    }
    fn cost(&self, a: GraphNode<u32>, b: GraphNode<u32>) -> Option<f64> {
        self.0.cost(a, b)
    }
    fn path(&self, a: GraphNode<u32>, b: GraphNode<u32>) -> Option<Cow<'_, [Point2<f64>]>> {
        self.0.path(a, b)
    }
    fn frontier_edges(&self) -> impl Iterator<Item = (u32, u32, f64)> + '_ {
        let mut v: Vec<_> = self.0.frontier_edges().map(|(a, b, c)| (b, a, c)).collect();
        v.reverse();
        v.into_iter()
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    #[test]
    fn grouping_equals_bfs_components(case in case()) {
        let g = sparse(&case);
        let cg = ClusterGraph::build(&g, &case.config).unwrap();
        let got: BTreeSet<Vec<u32>> = cg.clusters().iter().map(|c| c.members.clone()).collect();
        prop_assert_eq!(got.len(), cg.len(), "clusters are disjoint");
        prop_assert_eq!(got, common::bfs_components(&case.ids, |a, b| {
            g.cost(Frontier(a), Frontier(b)).is_some_and(|c| c <= case.config.rho_c)
        }));
        // Every frontier maps to the cluster that lists it; clusters are
        // numbered by smallest member.
        for (k, c) in cg.clusters().iter().enumerate() {
            prop_assert_eq!(c.id, ClusterId(k));
            prop_assert!(c.members.windows(2).all(|w| w[0] < w[1]));
            for &m in &c.members {
                prop_assert_eq!(cg.cluster_of(m), Some(c.id));
            }
        }
        prop_assert!(cg.clusters().windows(2).all(|w| w[0].members[0] < w[1].members[0]));
    }

    #[test]
    fn centre_and_spread_follow_their_definitions(case in case()) {
        let g = sparse(&case);
        let cg = ClusterGraph::build(&g, &case.config).unwrap();
        for c in cg.clusters() {
            let n = c.len() as f64;
            let pos: Vec<Point2<f64>> = c.members.iter()
                .map(|m| case.positions[case.ids.binary_search(m).unwrap()])
                .collect();
            prop_assert_eq!(&pos, &c.member_positions);
            let cx = pos.iter().map(|p| p.x).sum::<f64>() / n;
            let cy = pos.iter().map(|p| p.y).sum::<f64>() / n;
            prop_assert!((c.centre.x - cx).abs() < 1e-9 && (c.centre.y - cy).abs() < 1e-9);
            let sq: f64 = pos.iter().map(|p| (p.x - cx).powi(2) + (p.y - cy).powi(2)).sum();
            prop_assert!((c.spread - (sq / n).sqrt()).abs() < 1e-9);
            let max = pos.iter().map(|p| ((p.x - cx).powi(2) + (p.y - cy).powi(2)).sqrt())
                .fold(0.0, f64::max);
            prop_assert!(c.spread <= max + 1e-9);
        }
    }

    #[test]
    fn cluster_edges_equal_brute_force_minima(case in case()) {
        let g = sparse(&case);
        let cg = ClusterGraph::build(&g, &case.config).unwrap();
        let mut expected_edges = 0;
        for k in cg.clusters() {
            for l in cg.clusters().iter().filter(|l| l.id > k.id) {
                // Brute force: minimum over all member pairs, smallest pair on ties.
                let mut best: Option<(f64, (u32, u32))> = None;
                for &i in &k.members {
                    for &j in &l.members {
                        if let Some(c) = g.cost(Frontier(i), Frontier(j))
                            && best.is_none_or(|b| (c, (i, j)) < b) {
                            best = Some((c, (i, j)));
                        }
                    }
                }
                let edge = cg.edge(l.id, k.id);
                prop_assert_eq!(edge.is_some(), best.is_some());
                if let (Some(e), Some((cost, via))) = (edge, best) {
                    expected_edges += 1;
                    prop_assert_eq!((e.a, e.b), (k.id, l.id));
                    prop_assert_eq!(e.cost, cost);
                    prop_assert_eq!(e.via, via);
                    prop_assert!(e.cost > case.config.rho_c, "cheap pairs are merged");
                    let path = cg.edge_path(&g, k.id, l.id).unwrap();
                    let want = g.path(Frontier(via.0), Frontier(via.1)).unwrap();
                    prop_assert_eq!(&path[..], &want[..]);
                }
            }
        }
        prop_assert_eq!(cg.edges().len(), expected_edges);
    }

    #[test]
    fn waypoint_attains_the_robot_minimum(case in case()) {
        let g = sparse(&case);
        let cg = ClusterGraph::build(&g, &case.config).unwrap();
        for c in cg.clusters() {
            let best = c.members.iter()
                .filter_map(|&m| g.cost(Robot, Frontier(m)).map(|w| (w, m)))
                .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            match (&c.relocation, best) {
                (None, None) => prop_assert_eq!(c.utility, 0.0),
                (Some(r), Some((w, m))) => {
                    prop_assert_eq!(r.cost, w);
                    prop_assert_eq!(r.waypoint, m);
                    prop_assert_eq!(g.cost(Robot, Frontier(r.waypoint)), Some(r.cost));
                    let i = case.ids.binary_search(&m).unwrap();
                    prop_assert_eq!(&r.path, &robot_path(&case, i));
                }
                (r, b) => prop_assert!(false, "relocation {:?} vs brute force {:?}", r, b),
            }
        }
    }

    #[test]
    fn ranking_is_consistent_with_the_formula(case in case()) {
        let g = sparse(&case);
        let cg = ClusterGraph::build(&g, &case.config).unwrap();
        let reachable: BTreeSet<ClusterId> = cg.clusters().iter()
            .filter(|c| c.relocation.is_some()).map(|c| c.id).collect();
        let ranked: BTreeSet<ClusterId> = cg.ranking().iter().copied().collect();
        prop_assert_eq!(ranked.len(), cg.ranking().len());
        prop_assert_eq!(ranked, reachable);
        let eta = case.config.eta;
        let u = |k: ClusterId| {
            let c = cg.cluster(k).unwrap();
            c.len() as f64 * (1.0 + eta * c.spread) / (1.0 + c.distance().unwrap())
        };
        for &k in cg.ranking() {
            let c = cg.cluster(k).unwrap();
            prop_assert!((c.utility - u(k)).abs() <= 1e-12 * u(k).max(1.0));
            prop_assert_eq!(c.utility, geometric_utility(c.len(), c.spread, c.distance().unwrap(), eta));
        }
        for w in cg.ranking().windows(2) {
            let (a, b) = (cg.cluster(w[0]).unwrap(), cg.cluster(w[1]).unwrap());
            prop_assert!(a.utility >= b.utility);
            if a.utility == b.utility {
                let key = |c: &sornav_cluster_graph::Cluster<u32>| (c.distance().unwrap(), c.id);
                prop_assert!(key(a) < key(b));
            }
        }
        let k = case.config.top_k.min(cg.ranking().len());
        prop_assert_eq!(cg.top_k(), &cg.ranking()[..k]);
    }

    #[test]
    fn result_is_independent_of_edge_listing(case in case()) {
        let g = sparse(&case);
        let a = ClusterGraph::build(&g, &case.config).unwrap();
        let b = ClusterGraph::build(&AllPairs(&g), &case.config).unwrap();
        prop_assert_eq!(&a, &b);
        let c = ClusterGraph::build(&Reversed(&g), &case.config).unwrap();
        prop_assert_eq!(&a, &c);
    }

    #[test]
    fn matching_cluster_holds_the_most_previous_members(
        case in case(),
        previous in proptest::collection::vec(0_u32..500, 0..12),
    ) {
        let g = sparse(&case);
        let cg = ClusterGraph::build(&g, &case.config).unwrap();
        // Brute force: count the previous members inside every cluster.
        let best = cg.clusters().iter()
            .map(|c| (c.id, previous.iter().filter(|p| c.members.contains(p)).count()))
            .filter(|&(_, n)| n > 0)
            .max_by(|a, b| a.1.cmp(&b.1).then(b.0.cmp(&a.0)));
        prop_assert_eq!(cg.matching_cluster(&previous), best);
        for c in cg.clusters() {
            prop_assert_eq!(cg.matching_cluster(&c.members), Some((c.id, c.len())));
        }
    }

    #[test]
    fn serde_round_trip_is_exact(case in case()) {
        let g = sparse(&case);
        let cg = ClusterGraph::build(&g, &case.config).unwrap();
        let json = serde_json::to_string(&cg).unwrap();
        let back: ClusterGraph<u32> = serde_json::from_str(&json).unwrap();
        prop_assert_eq!(back, cg);
        let gj = serde_json::to_string(&g).unwrap();
        prop_assert_eq!(serde_json::from_str::<SparseDecisionGraph<u32>>(&gj).unwrap(), g);
    }

    #[test]
    fn contexts_contain_exactly_the_qualifying_objects(
        case in case(),
        raw in proptest::collection::vec(
            (0_usize..4, 0_usize..25, coord(), coord(), 0_u8..12), 0..30),
    ) {
        const LABELS: [&str; 4] = ["bed", "toilet", "sofa", "tv"];
        let objects: Vec<ObjectSummary> = raw.iter().map(|&(l, n, x, y, nan)| ObjectSummary {
            level: None,
            label: LABELS[l].into(),
            support: n,
            centre: Point3::new(if nan == 0 { f64::NAN } else { x }, y, f64::from(nan)),
        }).collect();
        let nan_count = raw.iter().filter(|r| r.4 == 0).count();
        let g = sparse(&case);
        let cg = ClusterGraph::build(&g, &case.config).unwrap();
        let cfg = cg.config();

        // S_r: brute force over all objects.
        let robot = g.robot_position();
        let mut want: Vec<(String, usize)> = objects.iter()
            .filter(|o| o.centre.x.is_finite() && o.support >= cfg.n_min)
            .filter(|o| ((o.centre.x - robot.x).powi(2) + (o.centre.y - robot.y).powi(2)).sqrt() <= cfg.r_r)
            .map(|o| (o.label.clone(), o.support)).collect();
        let s_r = cg.robot_context(&objects);
        let mut got: Vec<(String, usize)> = s_r.objects.iter().map(|o| (o.label.clone(), o.support)).collect();
        want.sort();
        got.sort();
        prop_assert_eq!(got, want);
        prop_assert_eq!(s_r.rejected_non_finite, nan_count);

        // S_k for every cluster.
        for c in cg.clusters() {
            let s_k = cg.cluster_context(c.id, &objects).unwrap();
            prop_assert_eq!(s_k.cluster, c.id);
            prop_assert_eq!(s_k.rejected_non_finite, nan_count);
            let mut want: Vec<(String, usize, f64)> = Vec::new();
            for o in objects.iter().filter(|o| o.centre.x.is_finite() && o.support >= cfg.n_min) {
                let d = c.member_positions.iter()
                    .map(|p| ((o.centre.x - p.x).powi(2) + (o.centre.y - p.y).powi(2)).sqrt())
                    .fold(f64::INFINITY, f64::min);
                if d <= cfg.r_s {
                    want.push((o.label.clone(), o.support, d));
                }
            }
            prop_assert!(s_k.objects.windows(2).all(|w| w[0].distance <= w[1].distance));
            let mut got: Vec<(String, usize, f64)> = s_k.objects.iter()
                .map(|o| (o.label.clone(), o.support, o.distance)).collect();
            let cmp = |a: &(String, usize, f64), b: &(String, usize, f64)| {
                (&a.0, a.1).cmp(&(&b.0, b.1)).then(a.2.total_cmp(&b.2))
            };
            want.sort_by(cmp);
            got.sort_by(cmp);
            prop_assert_eq!(got.len(), want.len());
            for (a, b) in got.iter().zip(&want) {
                prop_assert_eq!((&a.0, a.1), (&b.0, b.1));
                prop_assert!((a.2 - b.2).abs() < 1e-9);
            }
        }
        let candidates = cg.candidate_contexts(&objects);
        let order: Vec<ClusterId> = candidates.iter().map(|s| s.cluster).collect();
        prop_assert_eq!(&order[..], cg.top_k());
    }
}
