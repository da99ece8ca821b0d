//! Property tests of the multi-level map on random two-floor scenes
//! (random stair position, direction, rise, tread, width, half landing,
//! walls or open sides, sheer drops, furniture), scanned by an analytic ray
//! caster from the robot's eye: levels, stairs, G_F costs against a
//! reference Dijkstra over the union of the level grids and the stairs;
//! single-floor inputs give exactly the single-floor map; bad inputs are
//! typed errors.

mod common;

use common::scene::{Scene, SceneParams};
use common::{World, config as world_config, reference_union_dijkstra, world_strategy};
use nalgebra::{Point2, Point3, Vector3};
use proptest::prelude::*;
use sornav_frontier_graph::{
    Cell, FrontierError, FrontierMap, FrontierMapConfig, LevelId, MultiLevelMap, NodeId,
    OccupancyGrid, STAIR_FRONTIER_BASE, path_cells,
};

const EYE: f64 = 0.88;

fn ml_config() -> FrontierMapConfig {
    let mut cfg = FrontierMapConfig::default();
    cfg.grid.resolution = 0.1;
    cfg.frontier.max_extent = 1.5;
    cfg.frontier.min_cells = 3;
    cfg
}

fn scene_strategy() -> impl Strategy<Value = Scene> {
    (
        (0.12f64..0.19, 0.25f64..0.32, 0.9f64..1.2, 0u8..4),
        (-20.0f64..20.0, -20.0f64..20.0, any::<bool>(), 0.0f64..1.0),
        (any::<bool>(), any::<bool>()),
        prop::option::of(0.45f64..1.1),
        any::<bool>(),
    )
        .prop_map(
            |((rise, tread, width, turn), (ox, oy, landing, across), walls, platform, table)| {
                Scene::new(SceneParams {
                    rise,
                    tread,
                    width,
                    turn,
                    offset: (ox, oy),
                    landing,
                    walls,
                    platform,
                    table,
                    across,
                })
            },
        )
}

/// Explores the scene: one scan per feet position (floor 0, the stair,
/// floor 1), the graph after each, then the robot back at the first pose.
fn explore(scene: &Scene) -> MultiLevelMap {
    let mut map = MultiLevelMap::new(ml_config()).unwrap();
    let range = map.config().grid.max_range;
    for f in &scene.feet {
        let eye = f + Vector3::new(0.0, 0.0, EYE);
        let pts = scene.scan(&eye, 0.07, 4.8, range);
        map.update(f, &eye, &pts).unwrap();
        map.frontier_graph(f).unwrap();
    }
    map.frontier_graph(&scene.feet[0]).unwrap();
    map
}

/// The level grid's nearest traversable cell within `radius` of `p`
/// (ties by cell): where a stair end joins its level.
fn snap(grid: &OccupancyGrid, p: &Point2<f64>, radius: f64) -> Option<Cell> {
    let res = grid.resolution();
    let c = grid.cell_of(p).ok()?;
    if grid.is_traversable(c) {
        return Some(c);
    }
    let r = (radius / res).ceil() as i32;
    let mut best: Option<(f64, Cell)> = None;
    for dy in -r..=r {
        for dx in -r..=r {
            let n = c.offset(dx, dy);
            if !grid.is_traversable(n) {
                continue;
            }
            let d = (grid.cell_center(n) - p).norm();
            if d <= radius + 1e-12 && best.is_none_or(|(bd, bc)| (d, n) < (bd, bc)) {
                best = Some((d, n));
            }
        }
    }
    best.map(|b| b.1)
}

fn describe(scene: &Scene) -> String {
    format!(
        "{:?} h={:.2} steps={} run={:.2}",
        scene.params, scene.h, scene.steps, scene.run
    )
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    /// Levels, the stair and G_F costs on random two-floor scenes.
    #[test]
    fn two_floor_scenes(scene in scene_strategy()) {
        let map = explore(&scene);
        let cfg = map.config().clone();
        let step = cfg.grid.step_height;
        let ctx = describe(&scene);

        // Levels = the true floors.
        let levels: Vec<f64> = map.levels().map(|l| l.floor_z).collect();
        prop_assert_eq!(levels.len(), 2, "levels {:?}; {}", levels, ctx);
        prop_assert!(levels[0].abs() <= 0.1, "{:?}; {}", levels, ctx);
        prop_assert!((levels[1] - scene.h).abs() <= 0.1, "{:?}; {}", levels, ctx);

        // Exactly one stair, joining level 0 and level 1.
        let stairs = map.stairs();
        prop_assert_eq!(stairs.len(), 1, "stairs {:?}; {}", stairs.iter().map(|s| (&s.lower, &s.upper)).collect::<Vec<_>>(), ctx);
        let s = &stairs[0];
        prop_assert_eq!(s.lower.level, Some(LevelId(0)), "{}", ctx);
        prop_assert_eq!(s.upper.level, Some(LevelId(1)), "{}", ctx);
        for w in s.path.windows(2) {
            prop_assert!((w[1].z - w[0].z).abs() <= step + 1e-6, "step {:?}; {}", w, ctx);
        }
        // Length: at least the straight climb over the run (less a column
        // at each end), at most an octile detour of the run plus the rise.
        let lo = (scene.run - 0.4).max(0.0).hypot(scene.h);
        let hi = 1.09 * (scene.run + 1.0) + scene.h;
        prop_assert!(s.length >= lo && s.length <= hi, "length {} not in [{}, {}]; {}", s.length, lo, hi, ctx);
        // Sheer drops and furniture tops are not stairs.
        for q in &s.path {
            for b in scene.platform.iter().chain(scene.table.iter()) {
                prop_assert!(!b.covers_xy(q.xy(), -0.15), "stair over furniture at {:?}; {}", q, ctx);
            }
        }

        // G_F costs = reference Dijkstra over the union graph.
        let g0 = map.level_map(LevelId(0)).unwrap().grid();
        let g1 = map.level_map(LevelId(1)).unwrap().grid();
        let grids = [g0, g1];
        let (Some(p0), Some(p1)) = (
            snap(g0, &s.lower.position.xy(), cfg.levels.portal_radius),
            snap(g1, &s.upper.position.xy(), cfg.levels.portal_radius),
        ) else {
            return Err(TestCaseError::fail(format!("stair ends not joined to their levels; {ctx}")));
        };
        let up = s.length + cfg.levels.stair_cost_up;
        let down = s.length + cfg.levels.stair_cost_down;
        let links = [((0, p0), (1, p1), up), ((1, p1), (0, p0), down)];
        let graph = map.graph();
        let robot = graph.robot().cell.expect("robot on a traversable cell");
        let from_robot = reference_union_dijkstra(&grids, &links, (0, robot));
        let mut other_level = 0;
        for f in graph.nodes() {
            if f.id.0 >= STAIR_FRONTIER_BASE {
                continue;
            }
            let l = usize::from(f.level.0);
            let expect = from_robot.get(&(l, f.viewpoint_cell)).copied();
            let got = graph.cost(NodeId::Robot, NodeId::Frontier(f.id));
            match (expect, got) {
                (None, None) => {}
                (Some(d), Some(c)) => {
                    prop_assert!((c - d).abs() <= 1e-6 * d.max(1.0), "robot -> {:?} (level {}): {} vs reference {}; {}", f.id, l, c, d, ctx);
                    let back = reference_union_dijkstra(&grids, &links, (l, f.viewpoint_cell))[&(0, robot)];
                    let rc = graph.cost(NodeId::Frontier(f.id), NodeId::Robot).unwrap();
                    prop_assert!((rc - back).abs() <= 1e-6 * back.max(1.0), "{:?} -> robot: {} vs {}; {}", f.id, rc, back, ctx);
                    other_level += usize::from(l == 1);
                }
                (e, g) => prop_assert!(false, "robot -> {:?} (level {}): reference {:?}, graph {:?}; {}", f.id, l, e, g, ctx),
            }
        }
        prop_assert!(other_level > 0, "no frontier of level 1 reached; {}", ctx);

        // Every edge path is continuous and executable: level runs over
        // traversable cells of their level, stair steps within the step
        // height, joins to the stair within the portal radius.
        let res = cfg.grid.resolution;
        for e in graph.edges() {
            prop_assert!(e.cost.is_finite() && e.length.is_finite());
            for w in e.path.windows(2) {
                let dz = (w[1].z - w[0].z).abs();
                prop_assert!(dz <= step + 1e-6, "edge {:?}-{:?} jumps {} m; {}", e.from, e.to, dz, ctx);
                let on = |z: f64| levels.iter().position(|h| (h - z).abs() < 1e-9);
                match (on(w[0].z), on(w[1].z)) {
                    (Some(a), Some(b)) if a == b && (w[1].xy() - w[0].xy()).norm() > cfg.levels.portal_radius + 2.0 * res => {
                        for c in path_cells(w, res) {
                            prop_assert!(grids[a].is_traversable(c), "edge {:?}-{:?}: cell {:?} of level {} blocked; {}", e.from, e.to, c, a, ctx);
                        }
                    }
                    _ => {
                        let gap = (w[1].xy() - w[0].xy()).norm();
                        prop_assert!(gap <= cfg.levels.portal_radius + 2.0 * res || (on(w[0].z).is_some() && on(w[0].z) == on(w[1].z)),
                            "edge {:?}-{:?} gap {} m at {:?}; {}", e.from, e.to, gap, w, ctx);
                    }
                }
            }
        }
    }
}

/// Everything of a graph that a caller sees: nodes (id, cells, level) and
/// edges (endpoints, cost both ways, path).
type GraphKey = (
    Vec<(u64, Vec<Cell>, u16)>,
    Vec<(NodeId, NodeId, u64, u64, usize)>,
);

fn graph_key(g: &sornav_frontier_graph::FrontierGraph) -> GraphKey {
    let nodes = g
        .nodes()
        .map(|n| (n.id.0, n.cells.clone(), n.level.0))
        .collect();
    let mut edges: Vec<_> = g
        .edges()
        .map(|e| {
            (
                e.from,
                e.to,
                e.cost.to_bits(),
                e.cost_from(e.to).unwrap().to_bits(),
                e.path.len(),
            )
        })
        .collect();
    edges.sort();
    (nodes, edges)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    /// Single-floor inputs give exactly the single-floor map's graph, with
    /// stairs allowed or not.
    #[test]
    fn single_floor_equals_frontier_map((world, origins) in world_strategy(), allow in any::<bool>()) {
        prop_assume!(!origins.is_empty());
        let mut cfg = world_config();
        cfg.levels.allow_stairs = allow;
        let mut single = FrontierMap::new(cfg.clone()).unwrap();
        let mut multi = MultiLevelMap::new(cfg).unwrap();
        let range = single.config().grid.max_range;
        for o in &origins {
            let pts = World::scan(&world, *o, 180, range);
            let eye = Point3::new(o.x, o.y, 0.5);
            let a = single.update(&eye, &pts).unwrap();
            let b = multi.update(&Point3::new(o.x, o.y, 0.0), &eye, &pts).unwrap();
            prop_assert_eq!(a, b);
            let ga = graph_key(single.frontier_graph(o).unwrap());
            let gb = graph_key(multi.frontier_graph(&Point3::new(o.x, o.y, 0.0)).unwrap());
            prop_assert_eq!(ga, gb);
        }
        prop_assert_eq!(multi.levels().count(), 1);
        prop_assert!(multi.stairs().is_empty());
        prop_assert_eq!(single.graph(), multi.graph());
    }
}

/// NaN / infinite feet, origin or points are typed errors and modify
/// nothing.
#[test]
fn bad_inputs_are_typed_errors_and_change_nothing() {
    let scene = Scene::new(SceneParams {
        rise: 0.17,
        tread: 0.28,
        width: 1.0,
        turn: 1,
        offset: (2.0, -3.0),
        landing: true,
        walls: (true, false),
        platform: Some(0.6),
        table: true,
        across: 0.4,
    });
    let mut map = explore(&scene);
    // The map round-trips through JSON: the restored map gives the same
    // levels, stairs and G_F nodes.
    let json = serde_json::to_string(&map).expect("serialise");
    let mut restored: MultiLevelMap = serde_json::from_str(&json).expect("deserialise");
    let feet = scene.feet[0];
    let a: Vec<_> = map
        .frontier_graph(&feet)
        .unwrap()
        .nodes()
        .map(|n| n.id)
        .collect();
    let b: Vec<_> = restored
        .frontier_graph(&feet)
        .unwrap()
        .nodes()
        .map(|n| n.id)
        .collect();
    assert_eq!(a, b);
    // (JSON floats round-trip to within an ulp.)
    assert_eq!(map.stairs().len(), restored.stairs().len());
    for (x, y) in map.stairs().iter().zip(restored.stairs()) {
        assert!((x.length - y.length).abs() < 1e-9);
        assert!((x.lower.position - y.lower.position).norm() < 1e-9);
    }
    assert_eq!(
        map.levels().collect::<Vec<_>>(),
        restored.levels().collect::<Vec<_>>()
    );
    let before = format!("{map:?}");
    let f = scene.feet[0];
    let eye = f + Vector3::new(0.0, 0.0, EYE);
    let good = scene.scan(&eye, 0.2, 3.0, 5.0);
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        for axis in 0..3 {
            let mut p = f;
            p[axis] = bad;
            let e = map.update(&p, &eye, &good).unwrap_err();
            assert!(
                matches!(
                    e,
                    FrontierError::NonFinite { .. } | FrontierError::OutOfRange { .. }
                ),
                "{e:?}"
            );
            let mut o = eye;
            o[axis] = bad;
            let e = map.update(&f, &o, &good).unwrap_err();
            assert!(
                matches!(
                    e,
                    FrontierError::NonFinite { .. } | FrontierError::OutOfRange { .. }
                ),
                "{e:?}"
            );
            let mut pts = good.clone();
            pts[7][axis] = bad;
            let e = map.update(&f, &eye, &pts).unwrap_err();
            assert!(
                matches!(
                    e,
                    FrontierError::NonFinite { index: 7, .. } | FrontierError::OutOfRange { .. }
                ),
                "{e:?}"
            );
            assert!(map.frontier_graph(&p).is_err());
            assert!(map.path(&p, &f).is_err());
        }
    }
    assert_eq!(format!("{map:?}"), before);
}
