//! Scripted scenes and bad-input handling.

mod common;

use common::{World, explore};
use nalgebra::{Point2, Point3};
use sornav_frontier_graph::{
    CellState, FrontierError, FrontierMap, FrontierMapConfig, NodeId, path_cells,
};

/// Two 4 m x 4 m rooms side by side, joined by a 0.8 m door in the shared
/// wall (x in [4.0, 4.1], door y in [1.6, 2.4]).
fn two_rooms() -> World {
    World {
        boxes: vec![
            [-0.1, -0.1, 8.2, 0.0],
            [-0.1, 4.0, 8.2, 4.1],
            [-0.1, -0.1, 0.0, 4.1],
            [8.1, -0.1, 8.2, 4.1],
            // shared wall with a door
            [4.0, -0.1, 4.1, 1.6],
            [4.0, 2.4, 4.1, 4.1],
        ],
    }
}

fn small_config() -> FrontierMapConfig {
    let mut cfg = FrontierMapConfig::default();
    cfg.grid.resolution = 0.05;
    cfg.grid.max_range = 5.0;
    cfg
}

#[test]
fn two_rooms_paths_go_through_the_door() {
    let world = two_rooms();
    let mut map = FrontierMap::new(small_config()).unwrap();
    // Room A from two poses, then a look through the door into room B.
    let origins = [
        Point2::new(1.0, 1.0),
        Point2::new(2.0, 3.0),
        Point2::new(3.0, 2.0),
    ];
    explore(&mut map, &world, &origins, 720);
    let robot = Point2::new(1.0, 2.0);
    map.frontier_graph(&robot).unwrap();
    let g = map.graph();
    let res = map.grid().resolution();
    let behind: Vec<_> = g.nodes().filter(|n| n.viewpoint.x > 4.1).collect();
    assert!(!behind.is_empty(), "expected frontiers inside room B");
    for n in &behind {
        let e = g
            .edge(NodeId::Robot, NodeId::Frontier(n.id))
            .expect("room B reachable through the door");
        let path = e.path_from(NodeId::Robot).unwrap();
        // Crossing the wall happens only in the doorway, shrunk by the robot
        // radius up to half a cell (inflation is measured between cell
        // centres; the wall's hit cell straddles its edge).
        let margin = 0.18 - 0.5 * res;
        let mut crossed = false;
        for c in path_cells(&path, res) {
            let p = map.grid().cell_center(c);
            if p.x > 3.95 && p.x < 4.15 {
                crossed = true;
                assert!(
                    p.y > 1.6 + margin - 1e-9 && p.y < 2.4 - margin + 1e-9,
                    "path crosses the wall outside the door at {p:?}"
                );
            }
        }
        assert!(crossed);
        // The cost reflects the detour, not the straight line.
        let straight = (n.viewpoint - robot).norm();
        let via_door =
            (Point2::new(4.05, 2.0) - robot).norm() + (n.viewpoint - Point2::new(4.05, 2.0)).norm();
        assert!(e.cost >= via_door - 0.05, "{} < {}", e.cost, via_door);
        assert!(e.cost >= straight);
    }
    // No frontier node behind the wall is adjacent to room A through it: the
    // wall cells themselves are occupied and their inflation is not traversable.
    for y in [0.5, 1.0, 3.0, 3.5] {
        let c = map.grid().cell_of(&Point2::new(4.05, y)).unwrap();
        assert_eq!(map.grid().state(c), CellState::Occupied);
        assert!(!map.grid().is_traversable(c));
    }
}

#[test]
fn closed_door_disconnects_the_rooms() {
    let mut world = two_rooms();
    let mut map = FrontierMap::new(small_config()).unwrap();
    let robot = Point2::new(3.0, 2.0);
    explore(&mut map, &world, &[robot], 720);
    let g = map.frontier_graph(&robot).unwrap();
    let in_b: Vec<_> = g
        .nodes()
        .filter(|n| n.viewpoint.x > 4.3)
        .map(|n| n.id)
        .collect();
    assert!(!in_b.is_empty());
    assert!(
        in_b.iter()
            .all(|&f| g.edge(NodeId::Robot, NodeId::Frontier(f)).is_some())
    );
    // Close the door and look at it many times: the doorway becomes occupied.
    world.boxes.push([4.0, 1.6, 4.1, 2.4]);
    for _ in 0..4 {
        explore(&mut map, &world, &[robot], 720);
    }
    let g = map.frontier_graph(&robot).unwrap();
    for n in g.nodes().filter(|n| n.viewpoint.x > 4.3) {
        assert!(
            g.edge(NodeId::Robot, NodeId::Frontier(n.id)).is_none(),
            "frontier {:?} behind a closed door still connected",
            n.viewpoint
        );
    }
}

#[test]
fn a_single_spurious_return_does_not_wall_off_a_doorway() {
    let world = two_rooms();
    let mut map = FrontierMap::new(small_config()).unwrap();
    for _ in 0..5 {
        explore(&mut map, &world, &[Point2::new(3.0, 2.0)], 720);
    }
    let door = Point2::new(4.05, 2.0);
    let c = map.grid().cell_of(&door).unwrap();
    assert!(map.grid().is_traversable(c));
    // One return inside the doorway.
    map.update(&Point3::new(3.0, 2.0, 0.5), &[Point3::new(4.05, 2.0, 0.5)])
        .unwrap();
    assert_eq!(map.grid().state(c), CellState::Free);
    assert!(map.grid().is_traversable(c));
}

#[test]
fn floor_and_ceiling_returns_do_not_create_obstacles() {
    let mut map = FrontierMap::new(small_config()).unwrap();
    let o = Point3::new(0.0, 0.0, 0.5);
    map.update(
        &o,
        &[Point3::new(2.0, 0.0, 0.05), Point3::new(0.0, 2.0, 2.5)],
    )
    .unwrap();
    let g = map.grid();
    let floor = g.cell_of(&Point2::new(2.0, 0.0)).unwrap();
    assert_eq!(g.state(floor), CellState::Free);
    // Ceiling return: the ray leaves the band at 0.38 / 2.0 of its length.
    let near = g.cell_of(&Point2::new(0.0, 0.3)).unwrap();
    let far = g.cell_of(&Point2::new(0.0, 1.5)).unwrap();
    assert_eq!(g.state(near), CellState::Free);
    assert_eq!(g.state(far), CellState::Unknown);
    // Obstacle band and drop-off returns are hits.
    map.update(
        &o,
        &[Point3::new(-1.0, 0.0, 0.5), Point3::new(0.0, -1.0, -0.5)],
    )
    .unwrap();
    let g = map.grid();
    assert_eq!(
        g.state(g.cell_of(&Point2::new(-1.0, 0.0)).unwrap()),
        CellState::Occupied
    );
    assert_eq!(
        g.state(g.cell_of(&Point2::new(0.0, -1.0)).unwrap()),
        CellState::Occupied
    );
}

#[test]
fn bad_inputs_are_typed_errors_and_change_nothing() {
    let mut map = FrontierMap::new(small_config()).unwrap();
    let o = Point3::new(0.0, 0.0, 0.5);
    let good = Point3::new(1.0, 0.0, 0.5);
    assert_eq!(
        map.update(&o, &[good, Point3::new(f64::NAN, 0.0, 0.5)]),
        Err(FrontierError::NonFinite {
            what: "point",
            index: 1
        })
    );
    assert_eq!(map.grid().cell_count(), 0, "nothing integrated on error");
    assert!(matches!(
        map.update(&Point3::new(0.0, f64::INFINITY, 0.5), &[good]),
        Err(FrontierError::NonFinite { what: "origin", .. })
    ));
    assert!(matches!(
        map.update(&o, &[Point3::new(1e12, 0.0, 0.5)]),
        Err(FrontierError::OutOfRange { .. })
    ));
    assert!(matches!(
        map.update(&o, &[Point3::new(1.0, 0.0, f64::NAN)]),
        Err(FrontierError::NonFinite { .. })
    ));
    assert!(matches!(
        map.frontier_graph(&Point2::new(f64::NAN, 0.0)),
        Err(FrontierError::NonFinite { .. })
    ));
    assert!(matches!(
        map.frontier_graph(&Point2::new(0.0, -1e300)),
        Err(FrontierError::OutOfRange { .. })
    ));
    assert!(matches!(
        map.path(&Point2::new(0.0, 0.0), &Point2::new(f64::NAN, 0.0)),
        Err(FrontierError::NonFinite { .. })
    ));
    // Grid budget.
    let mut cfg = small_config();
    cfg.grid.max_cells = 1000;
    let mut tiny = FrontierMap::new(cfg).unwrap();
    assert!(matches!(
        tiny.update(&o, &[good]),
        Err(FrontierError::GridTooLarge { .. })
    ));
    // Invalid configuration.
    let mut cfg = small_config();
    cfg.grid.resolution = f64::NAN;
    assert!(matches!(
        FrontierMap::new(cfg),
        Err(FrontierError::InvalidConfig(_))
    ));
    let mut cfg = small_config();
    cfg.frontier.min_cells = 0;
    assert!(matches!(
        FrontierMap::new(cfg),
        Err(FrontierError::InvalidConfig(_))
    ));
}

#[test]
fn path_query_and_petgraph_export() {
    let world = two_rooms();
    let mut map = FrontierMap::new(small_config()).unwrap();
    explore(
        &mut map,
        &world,
        &[Point2::new(3.0, 2.0), Point2::new(5.0, 2.0)],
        720,
    );
    let e = map
        .path(&Point2::new(3.0, 1.0), &Point2::new(5.0, 1.0))
        .unwrap()
        .expect("connected through the door");
    assert!(e.cost > 2.0 + 0.5, "detour through the door: {}", e.cost);
    assert!(path_cells(&e.path, 0.05).all(|c| map.grid().is_traversable(c)));
    // Unknown target: no path.
    assert!(
        map.path(&Point2::new(3.0, 1.0), &Point2::new(30.0, 1.0))
            .unwrap()
            .is_none()
    );

    let g = map.frontier_graph(&Point2::new(5.0, 2.0)).unwrap();
    let (pg, index) = g.to_petgraph();
    assert_eq!(pg.node_count(), g.len() + 2);
    assert_eq!(pg.edge_count(), g.edge_count());
    let home = index[&NodeId::Home];
    let robot = index[&NodeId::Robot];
    let e = pg.find_edge(home, robot).unwrap();
    approx::assert_relative_eq!(pg[e], g.cost(NodeId::Home, NodeId::Robot).unwrap());
    // Serde round trip of the graph.
    let json = serde_json::to_string(g).unwrap();
    let back: sornav_frontier_graph::FrontierGraph = serde_json::from_str(&json).unwrap();
    assert_eq!(&back, g);
}

#[test]
fn ids_are_stable_for_unchanged_segments() {
    let world = two_rooms();
    let mut map = FrontierMap::new(small_config()).unwrap();
    explore(&mut map, &world, &[Point2::new(1.0, 1.0)], 720);
    let before: Vec<_> = map
        .graph()
        .nodes()
        .map(|n| (n.id, n.cells.clone()))
        .collect();
    // A scan far away in room B touches none of room A's frontiers... but the
    // robot stays in A: rescan the same place, the map does not change.
    explore(&mut map, &world, &[Point2::new(1.0, 1.0)], 720);
    let after: Vec<_> = map
        .graph()
        .nodes()
        .map(|n| (n.id, n.cells.clone()))
        .collect();
    let unchanged = before.iter().filter(|b| after.contains(b)).count();
    assert!(
        unchanged * 2 >= before.len(),
        "{unchanged} of {}",
        before.len()
    );
}

#[test]
fn every_return_of_a_fresh_scan_is_occupied() {
    // A hit wins over misses of other rays in the same scan, also when a
    // neighbouring cell's occupancy flips in the same scan.
    let world = two_rooms();
    let mut map = FrontierMap::new(small_config()).unwrap();
    let o = Point2::new(2.0, 1.5);
    let pts = world.scan(o, 1440, 5.0);
    map.update(&Point3::new(o.x, o.y, 0.5), &pts).unwrap();
    let mut hits = 0;
    for p in &pts {
        if (p.xy() - o).norm() <= 5.0 {
            hits += 1;
            let c = map.grid().cell_of(&p.xy()).unwrap();
            assert_eq!(map.grid().state(c), CellState::Occupied, "{p:?}");
        }
    }
    assert!(hits > 1000);
}

#[test]
fn serde_round_trip_continues_identically_and_rejects_garbage() {
    let world = two_rooms();
    let mut map = FrontierMap::new(small_config()).unwrap();
    explore(
        &mut map,
        &world,
        &[Point2::new(1.0, 1.0), Point2::new(3.0, 2.0)],
        360,
    );
    let json = serde_json::to_string(&map).unwrap();
    let mut back: FrontierMap = serde_json::from_str(&json).unwrap();
    let next = Point2::new(5.0, 2.0);
    for m in [&mut map, &mut back] {
        explore(m, &world, &[next], 360);
    }
    assert_eq!(map.graph(), back.graph());
    // Malformed: a traversable layer that disagrees with the log-odds.
    let mut v: serde_json::Value = serde_json::from_str(&json).unwrap();
    let trav = v["grid"]["trav"].as_array_mut().unwrap();
    let k = trav
        .iter()
        .position(|t| t == &serde_json::Value::Bool(false))
        .unwrap();
    trav[k] = serde_json::Value::Bool(true);
    assert!(serde_json::from_value::<FrontierMap>(v).is_err());
    // Malformed: truncated layer.
    let mut v: serde_json::Value = serde_json::from_str(&json).unwrap();
    v["grid"]["log_odds"].as_array_mut().unwrap().pop();
    assert!(serde_json::from_value::<FrontierMap>(v).is_err());
}

#[test]
fn default_config_incremental_equals_rebuild_through_a_door_closing() {
    let mut world = two_rooms();
    let mut map = FrontierMap::new(small_config()).unwrap();
    let route = [
        Point2::new(1.0, 1.0),
        Point2::new(2.5, 2.0),
        Point2::new(3.5, 2.0),
        Point2::new(5.0, 2.0),
        Point2::new(6.5, 3.0),
    ];
    let check = |map: &FrontierMap, robot: Point2<f64>| {
        let mut rebuilt = map.clone();
        rebuilt.rebuild();
        rebuilt.frontier_graph(&robot).unwrap();
        let cells = |m: &FrontierMap| {
            m.graph()
                .nodes()
                .map(|n| (n.cells.clone(), n.viewpoint_cell))
                .collect::<std::collections::BTreeSet<_>>()
        };
        assert_eq!(cells(map), cells(&rebuilt));
        let vp = |m: &FrontierMap, id: NodeId| match id {
            NodeId::Frontier(f) => Some(m.graph().frontier(f).unwrap().viewpoint_cell),
            NodeId::Robot => m.graph().robot().cell,
            NodeId::Home => m.graph().home().and_then(|h| h.cell),
            NodeId::Portal(_) => None,
        };
        let costs = |m: &FrontierMap| {
            m.graph()
                .edges()
                .map(|e| {
                    let (a, b) = (vp(m, e.from), vp(m, e.to));
                    ((a.min(b), a.max(b)), (e.cost * 1e6).round() as i64)
                })
                .collect::<std::collections::BTreeSet<_>>()
        };
        assert_eq!(costs(map), costs(&rebuilt));
    };
    explore(&mut map, &world, &route, 360);
    check(&map, route[4]);
    // Close the door while the robot is in room B and look at it.
    world.boxes.push([4.0, 1.6, 4.1, 2.4]);
    let back = [
        Point2::new(5.0, 2.0),
        Point2::new(4.6, 2.0),
        Point2::new(4.6, 1.5),
    ];
    for p in back {
        explore(&mut map, &world, &[p], 360);
        check(&map, p);
    }
    // The robot in room B can no longer reach home in room A.
    let g = map.frontier_graph(&Point2::new(4.6, 1.5)).unwrap();
    assert!(g.edge(NodeId::Robot, NodeId::Home).is_none());
}

#[test]
fn many_searches_on_one_map_stay_exact() {
    // The search buffers are reused with generation stamps that wrap
    // periodically; hundreds of queries must keep giving identical answers.
    let world = two_rooms();
    let mut map = FrontierMap::new(small_config()).unwrap();
    explore(
        &mut map,
        &world,
        &[Point2::new(3.0, 2.0), Point2::new(5.0, 2.0)],
        360,
    );
    let a = Point2::new(3.0, 1.0);
    let b = Point2::new(5.0, 3.0);
    let c = Point2::new(2.0, 3.0);
    let ab = map.path(&a, &b).unwrap().unwrap().cost;
    let ac = map.path(&a, &c).unwrap().unwrap().cost;
    for k in 0..700 {
        let (to, expect) = if k % 2 == 0 { (b, ab) } else { (c, ac) };
        let e = map.path(&a, &to).unwrap().unwrap();
        assert_eq!(e.cost, expect, "query {k}");
    }
}
