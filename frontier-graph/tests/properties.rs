//! Property tests on random box worlds: frontier definition, reference
//! Dijkstra, executable paths, incremental == rebuild, triangle inequality.

mod common;

use common::{config, explore, reference_dijkstra, world_strategy};
use nalgebra::Point2;
use proptest::prelude::*;
use sornav_frontier_graph::{Cell, CellState, FrontierMap, NodeId, is_frontier_cell, path_cells};
use std::collections::{BTreeMap, BTreeSet};

fn all_cells(map: &FrontierMap) -> Vec<Cell> {
    let Some((lo, hi)) = map.grid().bounds() else {
        return Vec::new();
    };
    let mut v = Vec::new();
    for y in lo.y - 1..=hi.y + 1 {
        for x in lo.x - 1..=hi.x + 1 {
            v.push(Cell::new(x, y));
        }
    }
    v
}

/// Edge costs keyed by the nodes' cell sets (ids differ between maps).
/// Differences between the two cost maps (first few), empty when equal.
/// Brute-force reference of traversability: a cell is traversable exactly
/// when it is free and no occupied cell lies within the robot radius.
fn check_traversability(map: &FrontierMap) -> Result<(), TestCaseError> {
    let grid = map.grid();
    let res = grid.resolution();
    let r = map.config().grid.robot_radius;
    let ri = (r / res).ceil() as i32;
    for c in all_cells(map) {
        let blocked = (-ri..=ri).any(|dy| {
            (-ri..=ri).any(|dx| {
                f64::from(dx * dx + dy * dy) * res * res <= r * r + 1e-9
                    && grid.state(c.offset(dx, dy)) == CellState::Occupied
            })
        });
        let clear = grid.state(c) == CellState::Free && !blocked;
        prop_assert_eq!(grid.is_traversable(c), clear, "cell {:?}", c);
    }
    Ok(())
}

/// The incrementally maintained G_F of `map` equals a rebuild from scratch
/// at `robot`: the same nodes (by cells) and the same edge costs.
fn check_equals_rebuild(
    map: &FrontierMap,
    robot: &Point2<f64>,
    ctx: &str,
) -> Result<(), TestCaseError> {
    let mut rebuilt = map.clone();
    rebuilt.rebuild();
    rebuilt.frontier_graph(robot).unwrap();
    let a: BTreeSet<Vec<Cell>> = map.graph().nodes().map(|n| n.cells.clone()).collect();
    let b: BTreeSet<Vec<Cell>> = rebuilt.graph().nodes().map(|n| n.cells.clone()).collect();
    prop_assert_eq!(a, b, "{}", ctx);
    let diff = cost_diff(map, &rebuilt);
    prop_assert!(diff.is_empty(), "{}: {:?}", ctx, diff);
    Ok(())
}

fn cost_diff(a: &FrontierMap, b: &FrontierMap) -> Vec<String> {
    let (ca, cb) = (costs_by_cells(a), costs_by_cells(b));
    let keys: BTreeSet<_> = ca.keys().chain(cb.keys()).cloned().collect();
    keys.into_iter()
        .filter(|k| ca.get(k) != cb.get(k))
        .take(4)
        .map(|k| {
            format!(
                "{:?}..{:?}: {:?} vs {:?}",
                k.0.first(),
                k.1.first(),
                ca.get(&k),
                cb.get(&k)
            )
        })
        .collect()
}

fn costs_by_cells(map: &FrontierMap) -> BTreeMap<(Vec<Cell>, Vec<Cell>), u64> {
    let g = map.graph();
    let key = |id: NodeId| -> Vec<Cell> {
        match id {
            NodeId::Frontier(f) => g.frontier(f).unwrap().cells.clone(),
            NodeId::Robot => vec![Cell::new(i32::MIN, 0)],
            NodeId::Home => vec![Cell::new(i32::MIN, 1)],
            NodeId::Portal(p) => vec![Cell::new(i32::MIN, 2 + p as i32)],
        }
    };
    g.edges()
        .map(|e| {
            let (a, b) = (key(e.from), key(e.to));
            let k = if a <= b { (a, b) } else { (b, a) };
            (k, (e.cost * 1e6).round() as u64)
        })
        .collect()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    #[test]
    fn grid_frontiers_and_graph_are_correct((world, origins) in world_strategy()) {
        prop_assume!(!origins.is_empty());
        let mut map = FrontierMap::new(config()).unwrap();
        explore(&mut map, &world, &origins, 180);
        let grid = map.grid();
        let res = grid.resolution();

        // Traversability = free and no occupied cell within the robot radius.
        check_traversability(&map)?;

        // Frontier cells: exactly the cells satisfying the definition.
        let reported: BTreeSet<Cell> = map.frontier_cells().collect();
        let expected: BTreeSet<Cell> = all_cells(&map)
            .into_iter()
            .filter(|&c| {
                grid.is_traversable(c)
                    && [(1, 0), (-1, 0), (0, 1), (0, -1)]
                        .iter()
                        .any(|&(dx, dy)| grid.state(c.offset(dx, dy)) == CellState::Unknown)
            })
            .collect();
        prop_assert_eq!(&reported, &expected);
        for &c in &reported {
            prop_assert!(is_frontier_cell(grid, c));
        }

        // Nodes: disjoint frontier cells, extent within the limit (or a
        // single cell), viewpoint in the segment.
        let g = map.graph();
        let mut seen = BTreeSet::new();
        for n in g.nodes() {
            prop_assert!(n.cells.len() >= map.config().frontier.min_cells);
            prop_assert!(n.extent <= map.config().frontier.max_extent + 1e-9);
            prop_assert!(n.cells.contains(&n.viewpoint_cell));
            for c in &n.cells {
                prop_assert!(reported.contains(c));
                prop_assert!(seen.insert(*c), "cell in two nodes");
            }
            // One traversable component (BFS over straight moves): the
            // viewpoint reaches every cell of its segment.
            let mut comp = BTreeSet::from([n.viewpoint_cell]);
            let mut queue = vec![n.viewpoint_cell];
            while let Some(c) = queue.pop() {
                for (dx, dy) in [(1, 0), (-1, 0), (0, 1), (0, -1)] {
                    let m = c.offset(dx, dy);
                    if grid.is_traversable(m) && comp.insert(m) {
                        queue.push(m);
                    }
                }
            }
            for c in &n.cells {
                prop_assert!(comp.contains(c), "{:?}: cell {:?} not reachable from the viewpoint {:?}", n.id, c, n.viewpoint_cell);
            }
        }

        // Edges vs reference Dijkstra; paths executable.
        let ids: Vec<NodeId> = g.node_ids().collect();
        let cell_of = |id: NodeId| -> Option<Cell> {
            match id {
                NodeId::Robot => g.robot().cell,
                NodeId::Home => g.home().and_then(|h| h.cell),
                NodeId::Frontier(f) => g.frontier(f).map(|n| n.viewpoint_cell),
                NodeId::Portal(_) => None,
            }
        };
        for (k, &a) in ids.iter().enumerate() {
            let Some(ca) = cell_of(a) else {
                for &b in &ids { prop_assert!(g.edge(a, b).is_none()); }
                continue;
            };
            let reference = reference_dijkstra(grid, ca);
            for &b in &ids[k + 1..] {
                let expect = cell_of(b).and_then(|cb| reference.get(&cb).copied());
                let got = g.edge(a, b);
                match (expect, got) {
                    (None, None) => {}
                    (Some(d), Some(e)) => {
                        prop_assert!((e.cost - d).abs() < 1e-6, "{:?}-{:?}: {} vs {}", a, b, e.cost, d);
                        let oriented = e.path_from(a).unwrap();
                        prop_assert_eq!(grid.cell_of(&oriented[0].xy()).unwrap(), ca);
                        prop_assert_eq!(grid.cell_of(&oriented.last().unwrap().xy()).unwrap(), cell_of(b).unwrap());
                        let cells: Vec<Cell> = path_cells(&e.path, res).collect();
                        for w in cells.windows(2) {
                            let (dx, dy) = (w[1].x - w[0].x, w[1].y - w[0].y);
                            prop_assert!(dx.abs() <= 1 && dy.abs() <= 1 && (dx, dy) != (0, 0));
                            if dx != 0 && dy != 0 {
                                prop_assert!(grid.is_traversable(w[0].offset(dx, 0)));
                                prop_assert!(grid.is_traversable(w[0].offset(0, dy)));
                            }
                        }
                        for c in cells {
                            prop_assert!(grid.is_traversable(c), "path cell {:?} blocked", c);
                        }
                    }
                    (x, y) => prop_assert!(false, "{:?}-{:?}: reference {:?}, graph {:?}", a, b, x, y.map(|e| e.cost)),
                }
            }
        }

        // Triangle inequality through the graph.
        for &a in &ids {
            for &b in &ids {
                for &c in &ids {
                    if let (Some(ab), Some(bc), Some(ac)) = (g.cost(a, b), g.cost(b, c), g.cost(a, c)) {
                        prop_assert!(ac <= ab + bc + 1e-6);
                    }
                }
            }
        }

        // Incremental == rebuild from scratch.
        let mut rebuilt = map.clone();
        rebuilt.rebuild();
        let robot = *origins.last().unwrap();
        rebuilt.frontier_graph(&robot).unwrap();
        let cells_inc: BTreeSet<Vec<Cell>> = map.graph().nodes().map(|n| n.cells.clone()).collect();
        let cells_reb: BTreeSet<Vec<Cell>> = rebuilt.graph().nodes().map(|n| n.cells.clone()).collect();
        prop_assert_eq!(cells_inc, cells_reb);
        let diff = cost_diff(&map, &rebuilt);
        prop_assert!(diff.is_empty(), "{:?}", diff);
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    /// After every step of a random exploration (random robot poses, home on
    /// or off, displacement weight on or off), the incrementally maintained
    /// map equals a rebuild from scratch.
    #[test]
    fn incremental_equals_rebuild_after_every_step(
        (world, origins) in world_strategy(),
        home in any::<bool>(),
        weighted in any::<bool>(),
        poses in prop::collection::vec((0.3f64..5.7, 0.3f64..5.7), 4),
    ) {
        prop_assume!(!origins.is_empty());
        let mut cfg = config();
        cfg.graph.home = home;
        cfg.graph.displacement_weight = if weighted { 0.5 } else { 0.0 };
        let mut map = FrontierMap::new(cfg).unwrap();
        for (k, o) in origins.iter().enumerate() {
            let pts = world.scan(*o, 120, map.config().grid.max_range);
            map.update(&nalgebra::Point3::new(o.x, o.y, 0.5), &pts).unwrap();
            let (px, py) = poses[k % poses.len()];
            let robot = Point2::new(px, py);
            map.frontier_graph(&robot).unwrap();
            check_equals_rebuild(&map, &robot, &format!("step {k}"))?;
        }
    }

    /// The path query on random (non-inflated) maps equals a reference
    /// Dijkstra, and its paths are executable.
    #[test]
    fn path_query_matches_reference(
        hits in prop::collection::vec((-2.0f64..2.0, -2.0f64..2.0), 0..80),
        floor in prop::collection::vec((-2.0f64..2.0, -2.0f64..2.0), 1..120),
        queries in prop::collection::vec((any::<prop::sample::Index>(), any::<prop::sample::Index>()), 1..8),
    ) {
        let mut cfg = config();
        cfg.grid.robot_radius = 0.0;
        cfg.grid.max_range = 10.0;
        let mut map = FrontierMap::new(cfg).unwrap();
        let o = nalgebra::Point3::new(0.05, 0.05, 0.5);
        let mut pts: Vec<_> = floor.iter().map(|&(x, y)| nalgebra::Point3::new(x, y, 0.05)).collect();
        map.update(&o, &pts).unwrap();
        pts = hits.iter().map(|&(x, y)| nalgebra::Point3::new(x, y, 0.5)).collect();
        // Obstacles from a different origin so they do not erase each other.
        map.update(&nalgebra::Point3::new(2.5, 2.5, 0.5), &pts).unwrap();
        let res = map.grid().resolution();
        // Query between floor returns (free unless an obstacle landed there).
        let mut checked = 0;
        for (qa, qb) in queries {
            let ((ax, ay), (bx, by)) = (*qa.get(&floor), *qb.get(&floor));
            let (a, b) = (Point2::new(ax, ay), Point2::new(bx, by));
            let (ca, cb) = (map.grid().cell_of(&a).unwrap(), map.grid().cell_of(&b).unwrap());
            if !map.grid().is_traversable(ca) || !map.grid().is_traversable(cb) {
                continue;
            }
            let expect = reference_dijkstra(map.grid(), ca).get(&cb).copied();
            let got = map.path(&a, &b).unwrap();
            checked += 1;
            match (expect, got) {
                (None, None) => {}
                (Some(d), Some(e)) => {
                    prop_assert!((e.cost - d).abs() < 1e-6);
                    let cells: Vec<Cell> = path_cells(&e.path, res).collect();
                    prop_assert_eq!(cells[0], ca);
                    prop_assert_eq!(*cells.last().unwrap(), cb);
                    prop_assert!(cells.iter().all(|c| map.grid().is_traversable(*c)));
                }
                (x, y) => prop_assert!(false, "reference {:?}, query {:?}", x, y.map(|e| e.cost)),
            }
        }
        // Floor returns stay free unless an obstacle lands on them: the test
        // is not vacuous.
        prop_assert!(checked > 0 || !hits.is_empty());
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    /// Frontier ids are stable while a segment persists: after every update
    /// a node whose cell set existed before keeps that node's id, fresh ids
    /// are larger than every id seen so far, and a vanished id never comes
    /// back.
    #[test]
    fn unchanged_segments_keep_their_ids((world, origins) in world_strategy()) {
        prop_assume!(!origins.is_empty());
        let mut map = FrontierMap::new(config()).unwrap();
        let mut seen: BTreeSet<sornav_frontier_graph::FrontierId> = BTreeSet::new();
        let mut vanished: BTreeSet<sornav_frontier_graph::FrontierId> = BTreeSet::new();
        let mut kept = 0usize;
        // Each origin twice: a repeated scan changes little, so many
        // segments survive and the rule is exercised.
        for o in origins.iter().flat_map(|o| [o, o]) {
            let before: BTreeMap<Vec<Cell>, sornav_frontier_graph::FrontierId> =
                map.graph().nodes().map(|n| (n.cells.clone(), n.id)).collect();
            let max_before = seen.iter().next_back().copied();
            let pts = world.scan(*o, 120, map.config().grid.max_range);
            map.update(&nalgebra::Point3::new(o.x, o.y, 0.5), &pts).unwrap();
            let now: BTreeSet<_> = map.graph().nodes().map(|n| n.id).collect();
            for n in map.graph().nodes() {
                prop_assert!(!vanished.contains(&n.id), "id {:?} came back", n.id);
                match before.get(&n.cells) {
                    Some(&old) => {
                        prop_assert_eq!(n.id, old, "unchanged segment changed id");
                        kept += 1;
                    }
                    None => {
                        // A changed segment never keeps an old id, and a
                        // fresh id is larger than every id seen so far.
                        prop_assert!(
                            !before.values().any(|&id| id == n.id),
                            "id {:?} now names different cells",
                            n.id
                        );
                        prop_assert!(
                            max_before.is_none_or(|m| n.id > m),
                            "fresh id {:?} reused",
                            n.id
                        );
                    }
                }
            }
            vanished.extend(before.values().filter(|id| !now.contains(id)).copied());
            seen.extend(now);
        }
        // Not vacuous on most worlds (a repeated scan keeps segments).
        prop_assert!(kept > 0 || seen.is_empty());
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 32, ..ProptestConfig::default() })]

    /// Contacts (obstacles the sensor did not show) interleaved with scans
    /// at random: every recorded contact cell stays occupied whatever the
    /// later scans show; traversability stays "free and no occupied cell within the
    /// robot radius" (brute force); the incremental map equals a rebuild
    /// from scratch; a serialised map restores its contacts.
    #[test]
    fn contacts_stay_occupied_and_the_map_stays_consistent(
        (world, origins) in world_strategy(),
        contacts in prop::collection::vec((0.3f64..5.7, 0.3f64..5.7, 0.0f64..6.3), 1..6),
    ) {
        prop_assume!(!origins.is_empty());
        let mut map = FrontierMap::new(config()).unwrap();
        let mut expected = BTreeSet::new();
        for (k, o) in origins.iter().enumerate() {
            let pts = world.scan(*o, 120, map.config().grid.max_range);
            map.update(&nalgebra::Point3::new(o.x, o.y, 0.5), &pts).unwrap();
            let (x, y, yaw) = contacts[k % contacts.len()];
            let p = Point2::new(x + 0.3 * yaw.cos(), y + 0.3 * yaw.sin());
            if map.contact(&nalgebra::Point3::new(x, y, 0.0), &p).unwrap().is_some() {
                expected.insert(map.grid().cell_of(&p).unwrap());
            }
            map.frontier_graph(o).unwrap();
        }
        // A last round of scans from every origin: rays cross the contacts.
        explore(&mut map, &world, &origins, 180);
        let grid = map.grid();
        let got: BTreeSet<Cell> = grid.contacts().collect();
        prop_assert_eq!(&got, &expected);
        for &c in &expected {
            prop_assert_eq!(grid.state(c), CellState::Occupied, "contact {:?}", c);
        }
        check_traversability(&map)?;
        let robot = *origins.last().unwrap();
        check_equals_rebuild(&map, &robot, "after the contacts")?;
        let json = serde_json::to_string(&map).unwrap();
        let back: FrontierMap = serde_json::from_str(&json).unwrap();
        let restored: BTreeSet<Cell> = back.grid().contacts().collect();
        prop_assert_eq!(restored, expected);
    }
}

/// A glass wall across a corridor: the scans see through it (the far side
/// is free), so paths cross it until the robot's contacts along the glass
/// close the corridor; then none does, however often the far side is seen
/// again.
#[test]
fn contacts_close_a_corridor_the_sensor_sees_through() {
    let mut cfg = config();
    cfg.grid.max_range = 4.0;
    let mut map = FrontierMap::new(cfg).unwrap();
    // A corridor 1 m wide along x, walls at y = 0 and y = 1.
    let scan = || -> Vec<nalgebra::Point3<f64>> {
        let mut pts = Vec::new();
        for k in 0..60 {
            let x = f64::from(k) * 0.1 + 0.05;
            pts.push(nalgebra::Point3::new(x, -0.05, 0.5));
            pts.push(nalgebra::Point3::new(x, 1.05, 0.5));
            for j in 0..10 {
                pts.push(nalgebra::Point3::new(x, f64::from(j) * 0.1 + 0.05, 0.0));
            }
        }
        pts
    };
    map.update(&nalgebra::Point3::new(0.5, 0.5, 0.5), &scan())
        .unwrap();
    let (a, b) = (Point2::new(0.5, 0.5), Point2::new(3.5, 0.5));
    assert!(map.path(&a, &b).unwrap().is_some(), "open corridor");
    // Bumps along the glass at x = 2.5, heading +x, across the corridor:
    // those within the robot radius of a wall (or of an earlier contact)
    // are explained by it and not recorded.
    let mut recorded = 0;
    for (y, explained) in [
        (0.05, true),
        (0.25, false),
        (0.3, true),
        (0.45, false),
        (0.65, false),
        (0.85, false),
        (0.95, true),
    ] {
        let stats = map
            .contact(&nalgebra::Point3::new(2.2, y, 0.0), &Point2::new(2.45, y))
            .unwrap();
        assert_eq!(stats.is_none(), explained, "y {y}");
        recorded += usize::from(stats.is_some());
    }
    for _ in 0..5 {
        map.update(&nalgebra::Point3::new(0.5, 0.5, 0.5), &scan())
            .unwrap();
    }
    assert!(map.path(&a, &b).unwrap().is_none(), "the contacts close it");
    assert_eq!(map.grid().contacts().count(), recorded);
    // A contact metres away is no contact; NaN is no position.
    let feet = nalgebra::Point3::new(0.5, 0.5, 0.0);
    assert!(matches!(
        map.contact(&feet, &Point2::new(4.0, 0.5)),
        Err(sornav_frontier_graph::FrontierError::ContactOutOfReach { .. })
    ));
    assert!(matches!(
        map.contact(&feet, &Point2::new(f64::NAN, 0.5)),
        Err(sornav_frontier_graph::FrontierError::NonFinite { .. })
    ));
    assert_eq!(map.grid().contacts().count(), recorded);
}

/// A floor platform over nothing (a terrace with no ground modelled beyond
/// it): the scans return its floor and nothing past the edge, so the edge
/// borders unknown cells that no return will ever show — a frontier for
/// ever. The voids of the rays that crossed the floor's height past the
/// edge make it an edge: the cells beyond are drop-offs and no frontier is
/// left there. A non-finite void is refused and changes nothing.
#[test]
fn voids_make_a_floor_edge_over_nothing_an_edge() {
    let floor = || -> Vec<nalgebra::Point3<f64>> {
        let mut pts = Vec::new();
        for kx in 0..30 {
            for ky in 0..20 {
                let (x, y) = (f64::from(kx) * 0.1 + 0.05, f64::from(ky) * 0.1 + 0.05);
                pts.push(nalgebra::Point3::new(x, y, 0.0));
            }
        }
        pts
    };
    let voids: Vec<Point2<f64>> = (0..20)
        .flat_map(|ky| (0..8).map(move |kx| (kx, ky)))
        .map(|(kx, ky)| Point2::new(3.05 + f64::from(kx) * 0.1, f64::from(ky) * 0.1 + 0.05))
        .collect();
    let origin = nalgebra::Point3::new(0.5, 1.0, 0.88);
    let mut cfg = config();
    cfg.grid.max_range = 5.0;
    let beyond = |map: &FrontierMap| {
        map.frontier_cells()
            .filter(|c| {
                let (x, y) = (
                    f64::from(c.x) * cfg.grid.resolution,
                    f64::from(c.y) * cfg.grid.resolution,
                );
                x > 2.5 && (0.3..1.7).contains(&y)
            })
            .count()
    };
    let states = |map: &FrontierMap| -> Vec<CellState> {
        all_cells(map)
            .into_iter()
            .map(|c| map.grid().state(c))
            .collect()
    };

    let mut plain = FrontierMap::new(cfg.clone()).unwrap();
    plain.update(&origin, &floor()).unwrap();
    assert!(beyond(&plain) > 0, "the edge is a frontier without voids");

    let mut map = FrontierMap::new(cfg.clone()).unwrap();
    map.update_with_voids(&origin, &floor(), &voids).unwrap();
    assert_eq!(beyond(&map), 0, "the edge is an edge with voids");
    for v in &voids {
        let c = map.grid().cell_of(v).unwrap();
        assert_eq!(map.grid().state(c), CellState::Occupied, "void {v:?}");
    }
    // The same as returns below the drop-off depth at the voids.
    let mut reference = FrontierMap::new(cfg.clone()).unwrap();
    let mut pts = floor();
    let drop = cfg.grid.floor_z - cfg.grid.drop_off_depth - 0.01;
    pts.extend(voids.iter().map(|v| nalgebra::Point3::new(v.x, v.y, drop)));
    reference.update(&origin, &pts).unwrap();
    assert_eq!(states(&reference), states(&map));

    let before = states(&map);
    let bad = [Point2::new(f64::NAN, 1.0)];
    assert!(matches!(
        map.update_with_voids(&origin, &floor(), &bad),
        Err(sornav_frontier_graph::FrontierError::NonFinite { what: "void", .. })
    ));
    assert_eq!(states(&map), before);
}
