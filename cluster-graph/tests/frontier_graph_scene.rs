//! End-to-end on `sornav-frontier-graph`: a U-shaped pair of corridors,
//! scanned by a simulated range sensor. The west ends of the two corridors
//! are 3 m apart in space but ~35 m apart by path (around the dividing
//! wall): their frontiers must not share a cluster at `rho_c = 25`.

use std::collections::BTreeSet;

mod common;

use nalgebra::{Point2, Point3};
use sornav_cluster_graph::{ClusterConfig, ClusterGraph, DecisionGraph, GraphNode};
use sornav_frontier_graph::{FrontierId, FrontierMap, FrontierMapConfig, NodeId};

/// Wall segments (x0, y0, x1, y1): two corridors, y in [0, 3] and [3, 6],
/// joined at the east end (x in [14, 16]) and open to unexplored space in
/// the west (beyond the sensor's range).
const WALLS: [(f64, f64, f64, f64); 4] = [
    (-30.0, 0.0, 16.0, 0.0),
    (-30.0, 6.0, 16.0, 6.0),
    (16.0, 0.0, 16.0, 6.0),
    (-30.0, 3.02, 14.0, 3.02),
];

/// Distance along the unit ray (o, d) to the nearest wall, if any.
fn cast(o: Point2<f64>, d: (f64, f64)) -> Option<f64> {
    let mut best: Option<f64> = None;
    for (x0, y0, x1, y1) in WALLS {
        let (ex, ey) = (x1 - x0, y1 - y0);
        let den = d.0 * ey - d.1 * ex;
        if den.abs() < 1e-12 {
            continue;
        }
        let (wx, wy) = (x0 - o.x, y0 - o.y);
        let t = (wx * ey - wy * ex) / den;
        let s = (wx * d.1 - wy * d.0) / den;
        if t > 0.0 && (0.0..=1.0).contains(&s) && best.is_none_or(|b| t < b) {
            best = Some(t);
        }
    }
    best
}

/// A 360-degree scan at obstacle height: wall hits within range, otherwise a
/// point beyond the sensor's range (free space carved up to the range).
fn scan(o: Point2<f64>, max_range: f64) -> Vec<Point3<f64>> {
    (0..1440)
        .map(|k| {
            let a = f64::from(k) * std::f64::consts::TAU / 1440.0;
            let d = (a.cos(), a.sin());
            let t = cast(o, d)
                .filter(|&t| t <= max_range)
                .unwrap_or(max_range + 2.0);
            Point3::new(o.x + t * d.0, o.y + t * d.1, 0.5)
        })
        .collect()
}

fn explored_map() -> (FrontierMap, Point2<f64>) {
    let mut map = FrontierMap::new(FrontierMapConfig::default()).unwrap();
    let range = map.config().grid.max_range;
    let route = [
        (1.0, 1.5),
        (5.0, 1.5),
        (9.0, 1.5),
        (13.0, 1.5),
        (15.0, 3.0),
        (13.0, 4.5),
        (9.0, 4.5),
        (5.0, 4.5),
        (1.0, 4.5),
    ];
    for (x, y) in route {
        let o = Point2::new(x, y);
        map.update(&Point3::new(x, y, 0.5), &scan(o, range))
            .unwrap();
    }
    (map, Point2::new(1.0, 1.5))
}

#[test]
fn wall_separated_corridor_ends_form_separate_clusters() {
    let (mut map, robot) = explored_map();
    let g = map.frontier_graph(&robot).unwrap().clone();
    let config = ClusterConfig::default();
    let cg = ClusterGraph::build(&g, &config).unwrap();

    // The frontiers at the west ends of the two corridors.
    let west = |south: bool| {
        g.nodes()
            .filter(|n| n.centroid.x < 0.0 && (n.centroid.y < 3.0) == south)
            .map(|n| n.id)
            .collect::<Vec<_>>()
    };
    let (south, north) = (west(true), west(false));
    assert!(
        !south.is_empty() && !north.is_empty(),
        "both corridor ends are frontiers"
    );
    for &s in &south {
        for &n in &north {
            let (ps, pn) = (
                g.frontier(s).unwrap().centroid,
                g.frontier(n).unwrap().centroid,
            );
            assert!((ps - pn).norm() < 5.0, "close in space");
            let cost = g.cost(NodeId::Frontier(s), NodeId::Frontier(n)).unwrap();
            assert!(cost > config.rho_c, "but far by path ({cost})");
            assert_ne!(cg.cluster_of(s), cg.cluster_of(n));
        }
    }

    // With a threshold above the detour they merge.
    let loose = ClusterConfig {
        rho_c: 60.0,
        ..config
    };
    let merged = ClusterGraph::build(&g, &loose).unwrap();
    assert_eq!(merged.cluster_of(south[0]), merged.cluster_of(north[0]));

    // The nearest cluster (the robot's own corridor end) ranks first.
    let first = cg.cluster(cg.top_k()[0]).unwrap();
    assert!(south.contains(&first.members[0]), "{first:?}");
}

#[test]
fn cluster_graph_of_a_real_frontier_graph_matches_the_references() {
    let (mut map, robot) = explored_map();
    let g = map.frontier_graph(&robot).unwrap();
    for rho_c in [0.0, 5.0, 25.0, 40.0] {
        let config = ClusterConfig {
            rho_c,
            ..ClusterConfig::default()
        };
        let cg = ClusterGraph::build(g, &config).unwrap();
        let groups: BTreeSet<Vec<FrontierId>> =
            cg.clusters().iter().map(|c| c.members.clone()).collect();
        let ids: Vec<FrontierId> = g.nodes().map(|n| n.id).collect();
        let joined = |a, b| {
            g.cost(NodeId::Frontier(a), NodeId::Frontier(b))
                .is_some_and(|c| c <= rho_c)
        };
        assert_eq!(groups, common::bfs_components(&ids, joined));
        for c in cg.clusters() {
            // Waypoint: the member with the cheapest robot edge; its path is
            // the frontier graph's, from the robot to the viewpoint.
            let r = c.relocation.as_ref().expect("everything is reachable here");
            let min = c
                .members
                .iter()
                .filter_map(|&m| g.cost(NodeId::Robot, NodeId::Frontier(m)))
                .fold(f64::INFINITY, f64::min);
            assert_eq!(r.cost, min);
            let edge = g.edge(NodeId::Robot, NodeId::Frontier(r.waypoint)).unwrap();
            let xy = |p: Vec<nalgebra::Point3<f64>>| p.iter().map(|q| q.xy()).collect::<Vec<_>>();
            assert_eq!(Some(r.path.clone()), edge.path_from(NodeId::Robot).map(xy));
            let viewpoint = g.frontier(r.waypoint).unwrap().viewpoint;
            assert!((r.path.last().unwrap() - viewpoint).norm() < 1e-9);
        }
        for e in cg.edges() {
            let (k, l) = (cg.cluster(e.a).unwrap(), cg.cluster(e.b).unwrap());
            let min = k
                .members
                .iter()
                .flat_map(|&i| l.members.iter().map(move |&j| (i, j)))
                .filter_map(|(i, j)| g.cost(NodeId::Frontier(i), NodeId::Frontier(j)))
                .fold(f64::INFINITY, f64::min);
            assert_eq!(e.cost, min);
            let path = cg.edge_path(g, e.a, e.b).unwrap();
            let want = g
                .edge(NodeId::Frontier(e.via.0), NodeId::Frontier(e.via.1))
                .unwrap();
            assert_eq!(
                Some(path.into_owned()),
                want.path_from(NodeId::Frontier(e.via.0))
                    .map(|p| p.iter().map(|q| q.xy()).collect::<Vec<_>>())
            );
        }
        // The adapter lists each frontier edge once with the graph's cost.
        let listed = DecisionGraph::frontier_edges(g).count();
        let expected = g
            .edges()
            .filter(|e| matches!((e.from, e.to), (NodeId::Frontier(_), NodeId::Frontier(_))))
            .count();
        assert_eq!(listed, expected);
        assert_eq!(
            DecisionGraph::cost(g, GraphNode::Robot, GraphNode::Robot),
            None
        );
    }
}
