//! Property tests of the multi-level map on random two-floor scenes
//! (random stair position, direction, rise, tread, width, half landing,
//! walls or open sides, sheer drops, furniture), scanned by an analytic ray
//! caster from the robot's eye: levels, stairs, G_F costs against a
//! reference Dijkstra over the union of the level grids and the stairs;
//! stair extraction against a brute-force search over the surface columns;
//! single-floor inputs give exactly the single-floor map; bad inputs are
//! typed errors.

mod common;

use common::scene::{Scene, SceneParams};
use common::{World, config as world_config, reference_union_dijkstra, world_strategy};
use nalgebra::{Point2, Point3, Vector3};
use proptest::prelude::*;
use sornav_frontier_graph::{
    Cell, FrontierError, FrontierMap, FrontierMapConfig, LevelId, Location, MultiLevelMap, NodeId,
    OccupancyGrid, STAIR_FRONTIER_BASE, Stair, path_cells,
};
use std::cmp::Reverse;
use std::collections::{BTreeSet, BinaryHeap, HashMap, VecDeque};

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
    explore_first(scene, scene.feet.len())
}

/// [`explore`] with the scans from the first `n` feet positions only (a
/// partly seen stair when `n` stops on it).
fn explore_first(scene: &Scene, n: usize) -> MultiLevelMap {
    let mut map = MultiLevelMap::new(ml_config()).unwrap();
    let range = map.config().grid.max_range;
    for f in &scene.feet[..n] {
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

/// A walkable surface of the brute-force stair reference: its column, its
/// height (f32, as the surface map stores it) and the level it is on.
#[derive(Debug, Clone, Copy)]
struct RefNode {
    col: (i32, i32),
    z: f32,
    level: Option<usize>,
    walkable: bool,
}

/// Brute-force stair reference over the surface columns of a map, from the
/// definitions of `stairs.rs` (not its union-find and per-component
/// chains): every surface is a node; a node within `level_tolerance` of a
/// floor is on that level; two nodes of 8-neighbouring columns are
/// step-connected when their heights differ by at most the step height
/// (or, inside a flight, `max_stair_column_rise`: [`Self::connected`]);
/// an off-level node is walkable when every column within the robot radius
/// has a surface within two step heights of it.
struct StairReference {
    res: f64,
    step: f32,
    column_rise: f32,
    level_tolerance: f32,
    floors: Vec<f64>,
    nodes: Vec<RefNode>,
    by_col: HashMap<(i32, i32), Vec<usize>>,
}

use common::DIRS as DIRS8;

impl StairReference {
    /// Reads every surface column of `map` over the scene's extent through
    /// the public `surfaces_at`.
    fn new(map: &MultiLevelMap, scene: &Scene) -> Self {
        let cfg = map.config();
        let res = cfg.levels.surface_resolution;
        let step = cfg.grid.step_height as f32;
        let tol = f64::from(cfg.levels.level_tolerance as f32);
        let floors: Vec<f64> = map.levels().map(|l| l.floor_z).collect();
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for b in &scene.boxes {
            for a in 0..2 {
                lo[a] = lo[a].min(b.lo[a]);
                hi[a] = hi[a].max(b.hi[a]);
            }
        }
        let key = |v: f64| (v / res).floor() as i32;
        let mut nodes = Vec::new();
        let mut by_col: HashMap<(i32, i32), Vec<usize>> = HashMap::new();
        for kx in key(lo[0]) - 2..=key(hi[0]) + 2 {
            for ky in key(lo[1]) - 2..=key(hi[1]) + 2 {
                let (x, y) = ((f64::from(kx) + 0.5) * res, (f64::from(ky) + 0.5) * res);
                for z in map.surfaces_at(x, y) {
                    let level = floors
                        .iter()
                        .enumerate()
                        .filter(|(_, h)| (z - **h).abs() <= tol)
                        .min_by(|a, b| (z - a.1).abs().total_cmp(&(z - b.1).abs()))
                        .map(|(l, _)| l);
                    by_col.entry((kx, ky)).or_default().push(nodes.len());
                    nodes.push(RefNode {
                        col: (kx, ky),
                        z: z as f32,
                        level,
                        walkable: false,
                    });
                }
            }
        }
        // Walkable: the footprint disk is supported.
        let r = cfg.grid.robot_radius / res;
        let ri = r.ceil() as i32;
        for i in 0..nodes.len() {
            let RefNode { col, z, .. } = nodes[i];
            // No column of the disk holds only far surfaces; at least half
            // hold a near one (unobserved columns are neither).
            let (mut ok, mut held, mut total) = (true, 0usize, 0usize);
            for dy in -ri..=ri {
                for dx in -ri..=ri {
                    if f64::from(dx * dx + dy * dy) > r * r + 1e-9 {
                        continue;
                    }
                    total += 1;
                    if let Some(v) = by_col.get(&(col.0 + dx, col.1 + dy)) {
                        held += 1;
                        ok &= v.iter().any(|&j| (nodes[j].z - z).abs() <= 2.0 * step);
                    }
                }
            }
            nodes[i].walkable = ok && 2 * held >= total && nodes[i].level.is_none();
        }
        Self {
            res,
            step,
            column_rise: cfg.levels.max_stair_column_rise.max(cfg.grid.step_height) as f32,
            level_tolerance: cfg.levels.level_tolerance as f32,
            floors,
            nodes,
            by_col,
        }
    }

    fn point(&self, col: (i32, i32), z: f64) -> Point3<f64> {
        Point3::new(
            (f64::from(col.0) + 0.5) * self.res,
            (f64::from(col.1) + 0.5) * self.res,
            z,
        )
    }

    fn node_point(&self, i: usize) -> Point3<f64> {
        self.point(self.nodes[i].col, f64::from(self.nodes[i].z))
    }

    fn col_of(&self, p: &Point3<f64>) -> (i32, i32) {
        (
            (p.x / self.res).floor() as i32,
            (p.y / self.res).floor() as i32,
        )
    }

    /// The node at a stair path point (exact column and height).
    fn node_at(&self, p: &Point3<f64>) -> Option<usize> {
        let z = p.z as f32;
        self.by_col
            .get(&self.col_of(p))?
            .iter()
            .copied()
            .find(|&i| self.nodes[i].z == z)
    }

    /// Step-connected nodes of 8-neighbouring columns, and of columns two
    /// away in those directions across a column without any surface.
    fn steps(&self, i: usize) -> impl Iterator<Item = usize> + '_ {
        let RefNode { col, .. } = self.nodes[i];
        DIRS8.iter().flat_map(move |&(dx, dy)| {
            let near = (col.0 + dx, col.1 + dy);
            let mut cols = vec![near];
            if !self.by_col.contains_key(&near) {
                cols.push((col.0 + 2 * dx, col.1 + 2 * dy));
            }
            cols.into_iter()
                .flat_map(|c| self.by_col.get(&c).into_iter().flatten().copied())
                .filter(move |&j| self.connected(i, j))
        })
    }

    /// Step-connection of nodes `i` and `j` (neighbouring columns, or two
    /// apart across an empty one): within a step; or both off-level, in
    /// neighbouring columns, within a column rise, with the columns before
    /// `i` and after `j` on that line rising the same way by a step at most
    /// (and at least half the level tolerance) each.
    fn connected(&self, i: usize, j: usize) -> bool {
        let (a, b) = (self.nodes[i], self.nodes[j]);
        let jump = b.z - a.z;
        if jump.abs() <= self.step {
            return true;
        }
        let d = (b.col.0 - a.col.0, b.col.1 - a.col.1);
        if a.level.is_some()
            || b.level.is_some()
            || jump.abs() > self.column_rise
            || d.0.abs() > 1
            || d.1.abs() > 1
        {
            return false;
        }
        let rises = |lo: f32, hi: f32| {
            let r = (hi - lo) * jump.signum();
            r >= 0.5 * self.level_tolerance && r <= self.step
        };
        let at = |c: (i32, i32)| {
            self.by_col
                .get(&c)
                .into_iter()
                .flatten()
                .map(|&k| self.nodes[k].z)
        };
        at((a.col.0 - d.0, a.col.1 - d.1)).any(|z| rises(z, a.z))
            && at((b.col.0 + d.0, b.col.1 + d.1)).any(|z| rises(b.z, z))
    }

    /// The off-level nodes step-connected to off-level node `i` (its
    /// component, walkable or not), by breadth-first search.
    fn component(&self, i: usize) -> Vec<usize> {
        let mut seen = BTreeSet::from([i]);
        let mut queue = VecDeque::from([i]);
        while let Some(j) = queue.pop_front() {
            for k in self.steps(j) {
                if self.nodes[k].level.is_none() && seen.insert(k) {
                    queue.push_back(k);
                }
            }
        }
        seen.into_iter().collect()
    }

    /// How far (height, in direction `dir`: +1 up, -1 down) the flight of
    /// component `comp` reaches across unobserved columns (`stairs.rs`'s
    /// `gap_sighting`, by brute force over every off-level node and without
    /// its cap on sources, so never short of it): from a node of the
    /// component within a step of its top (bottom) that borders a column
    /// without surfaces, an off-level node at least two columns and at most
    /// 2 m away, rising (descending) at most 1 m per metre plus a step, with
    /// no surface in any column on the straight line between. The
    /// component's own extreme when nothing qualifies.
    fn gap_reach(&self, comp: &[usize], dir: f32) -> f32 {
        let edge = comp
            .iter()
            .map(|&i| self.nodes[i].z * dir)
            .fold(f32::NEG_INFINITY, f32::max)
            * dir;
        let empty = |c: (i32, i32)| !self.by_col.contains_key(&c);
        let g = (2.0 / self.res).ceil() as i32;
        let mut best = edge;
        for &s in comp {
            let RefNode { col: k, z, .. } = self.nodes[s];
            if (edge - z) * dir > self.step
                || !DIRS8.iter().any(|&(dx, dy)| empty((k.0 + dx, k.1 + dy)))
            {
                continue;
            }
            for (j, n) in self.nodes.iter().enumerate() {
                let (ddx, ddy) = (n.col.0 - k.0, n.col.1 - k.1);
                let cheb = ddx.abs().max(ddy.abs());
                if j == s || n.level.is_some() || cheb < 2 || cheb > g {
                    continue;
                }
                let d = self.res * f64::from(ddx * ddx + ddy * ddy).sqrt();
                let rise = (n.z - z) * dir;
                // a hair of slack: the reference may only reach farther
                let max_rise = d as f32 + self.step + 1e-4;
                if d > 2.0 + 1e-9 || rise <= 0.0 || rise > max_rise || (n.z - best) * dir <= 0.0 {
                    continue;
                }
                let unseen_between = (1..cheb).all(|t| {
                    let f = f64::from(t) / f64::from(cheb);
                    empty((
                        k.0 + (f64::from(ddx) * f).round() as i32,
                        k.1 + (f64::from(ddy) * f).round() as i32,
                    ))
                });
                if unseen_between {
                    best = n.z;
                }
            }
        }
        best
    }

    /// The surface height of `level` in column `col` (where a stair's end
    /// stands: the real surface, within the level tolerance of the floor).
    fn foot_z(&self, level: usize, col: (i32, i32)) -> Option<f64> {
        self.by_col
            .get(&col)?
            .iter()
            .find(|&&j| self.nodes[j].level == Some(level))
            .map(|&j| f64::from(self.nodes[j].z))
    }

    /// The level columns an off-level node is a foot of (walkable or not:
    /// a chain's first and last nodes need not be walkable, its inner ones
    /// must).
    fn feet(&self, i: usize) -> Vec<(usize, (i32, i32))> {
        if self.nodes[i].level.is_some() {
            return Vec::new();
        }
        self.steps(i)
            .filter_map(|j| self.nodes[j].level.map(|l| (l, self.nodes[j].col)))
            .collect()
    }

    /// Level pairs (lower floor first) joined by a walkable step-path
    /// through off-level surfaces: breadth-first search from every level's
    /// feet.
    fn joined_levels(&self) -> BTreeSet<(usize, usize)> {
        let mut out = BTreeSet::new();
        for a in 0..self.floors.len() {
            let mut seen = vec![false; self.nodes.len()];
            let mut queue: VecDeque<usize> = (0..self.nodes.len())
                .filter(|&i| self.feet(i).iter().any(|f| f.0 == a))
                .collect();
            for &i in &queue {
                seen[i] = true;
            }
            while let Some(i) = queue.pop_front() {
                for (b, _) in self.feet(i) {
                    if b != a {
                        let pair = if self.floors[a] <= self.floors[b] {
                            (a, b)
                        } else {
                            (b, a)
                        };
                        out.insert(pair);
                    }
                }
                // an unwalkable node ends a chain (a foot of another
                // level) or starts one (a foot of this one)
                if !self.nodes[i].walkable && !self.feet(i).iter().any(|f| f.0 == a) {
                    continue;
                }
                for j in self.steps(i) {
                    let enters = self.nodes[j].walkable || self.feet(j).iter().any(|f| f.0 != a);
                    if enters && !std::mem::replace(&mut seen[j], true) {
                        queue.push_back(j);
                    }
                }
            }
        }
        out
    }

    /// Shortest step-path lengths (3-D, column centres) from the floor
    /// point of `col` on `level` to every node a chain can reach: its first
    /// node is a foot there, its inner nodes are walkable and an unwalkable
    /// node off it ends it (a foot of another level). Dijkstra over all
    /// nodes.
    /// Columns from the edge of the walkable part of a flight, up to 3
    /// (`stairs.rs`'s `edge_depth`, by brute force): 0 for a walkable
    /// off-level node whose walkable off-level step neighbours do not come
    /// from all 8 directions, then breadth-first over walkable step
    /// neighbours; deeper nodes are left out.
    fn edge_depth(&self) -> HashMap<usize, u8> {
        let walkable_off = |j: usize| self.nodes[j].level.is_none() && self.nodes[j].walkable;
        let mut depth = HashMap::new();
        let mut queue = VecDeque::new();
        for i in (0..self.nodes.len()).filter(|&i| walkable_off(i)) {
            let c = self.nodes[i].col;
            let dirs: BTreeSet<(i32, i32)> = self
                .steps(i)
                .filter(|&j| walkable_off(j))
                .map(|j| {
                    let cj = self.nodes[j].col;
                    ((cj.0 - c.0).signum(), (cj.1 - c.1).signum())
                })
                .collect();
            if dirs.len() < 8 {
                depth.insert(i, 0u8);
                queue.push_back(i);
            }
        }
        while let Some(i) = queue.pop_front() {
            let d = depth[&i];
            if d + 1 >= 3 {
                continue;
            }
            for j in self.steps(i).filter(|&j| walkable_off(j)) {
                depth.entry(j).or_insert_with(|| {
                    queue.push_back(j);
                    d + 1
                });
            }
        }
        depth
    }

    /// The extra path cost of crossing node `i` near a flight's edge
    /// (0.15 m per column short of 3).
    fn edge_penalty(depth: &HashMap<usize, u8>, i: usize) -> f64 {
        depth.get(&i).map_or(0.0, |&d| 0.15 * f64::from(3 - d))
    }

    /// The path cost of a stair as the extraction minimises it: its length
    /// plus the edge penalties of its nodes after the first tread, from
    /// its `start` end on.
    fn stair_cost(&self, s: &Stair, from_lower: bool) -> f64 {
        let depth = self.edge_depth();
        let mut pts: Vec<Point3<f64>> = s.path.clone();
        if !from_lower {
            pts.reverse();
        }
        s.length
            + pts
                .iter()
                .skip(2)
                .filter_map(|p| self.node_at(p))
                .map(|i| Self::edge_penalty(&depth, i))
                .sum::<f64>()
    }

    fn paths_from_end(&self, level: usize, col: (i32, i32)) -> HashMap<usize, f64> {
        let depth = self.edge_depth();
        let start = self.point(col, self.foot_z(level, col).unwrap_or(self.floors[level]));
        let mut dist: HashMap<usize, f64> = HashMap::new();
        let mut heap = BinaryHeap::new();
        for i in 0..self.nodes.len() {
            if self.feet(i).contains(&(level, col)) {
                let d = (self.node_point(i) - start).norm();
                dist.insert(i, d);
                heap.push((Reverse(d.to_bits()), i));
            }
        }
        while let Some((Reverse(d), i)) = heap.pop() {
            let d = f64::from_bits(d);
            if dist[&i] < d {
                continue;
            }
            if !self.nodes[i].walkable && !self.feet(i).contains(&(level, col)) {
                continue;
            }
            for j in self.steps(i) {
                if !self.nodes[j].walkable && !self.feet(j).iter().any(|f| f.0 != level) {
                    continue;
                }
                let nd = d
                    + (self.node_point(j) - self.node_point(i)).norm()
                    + Self::edge_penalty(&depth, j);
                if dist.get(&j).is_none_or(|&old| nd < old) {
                    dist.insert(j, nd);
                    heap.push((Reverse(nd.to_bits()), j));
                }
            }
        }
        dist
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    /// Stair extraction against the brute-force reference on random
    /// two-floor scenes, fully or partly explored (the scans stop on the
    /// floor or on the stair):
    ///
    /// * the level pairs joined by the complete stairs are exactly the
    ///   pairs the reference joins by a walkable step-path;
    /// * every stair's path is a chain of walkable, step-connected,
    ///   off-level surfaces, with a level end next to a foot, on that
    ///   level's real surface there (not its nominal floor height);
    /// * a complete stair is at least as long as the reference's shortest
    ///   step-path between its two ends and at most one column hop longer
    ///   (the chain stops at the first foot of the upper level it reaches
    ///   and then steps onto that floor: at most `hypot(sqrt(2) res, step +
    ///   level_tolerance)` more than the best choice of last foot);
    /// * a partly seen stair is exactly as long as the reference's shortest
    ///   path from its level end to its open end, which rises at least
    ///   `min_stair_rise` (or only the level tolerance when the flight is
    ///   sighted: its surfaces, or what they sight across unobserved
    ///   columns, reach `min_stair_sighting_rise`) and is the
    ///   highest-rising node the reference reaches from that end.
    #[test]
    fn stairs_match_brute_force_reference(scene in scene_strategy(), cut in 0.0f64..1.6) {
        let n = ((cut * scene.feet.len() as f64).ceil() as usize).clamp(1, scene.feet.len());
        let map = explore_first(&scene, n);
        let cfg = map.config().clone();
        let r = StairReference::new(&map, &scene);
        let ctx = format!("{} scans {}", describe(&scene), n);
        // Extractions skipped while nothing they read changed: the stairs
        // equal a fresh extraction's.
        let mut fresh = map.clone();
        fresh.rebuild();
        fresh.frontier_graph(&scene.feet[0]).unwrap();
        prop_assert_eq!(fresh.stairs(), map.stairs(), "{}", ctx);
        let level_index = |l: Option<LevelId>| l.map(|l| usize::from(l.0));

        // Which levels the stairs join.
        let found: BTreeSet<(usize, usize)> = map
            .stairs()
            .iter()
            .filter(|s| s.is_complete())
            .map(|s| (level_index(s.lower.level).unwrap(), level_index(s.upper.level).unwrap()))
            .collect();
        let reference = r.joined_levels();
        if r.floors.len() <= 2 {
            prop_assert_eq!(&found, &reference, "{}", ctx);
        } else {
            // With three floors a stair joins its component's lowest and
            // highest; every pair it joins is still joined by the reference.
            prop_assert!(found.is_subset(&reference), "{:?} vs {:?}; {}", found, reference, ctx);
        }

        let res = r.res;
        let hop = (2f64.sqrt() * res).hypot(cfg.grid.step_height + cfg.levels.level_tolerance);
        for s in map.stairs() {
            // The path: level ends (if any) around a chain of nodes.
            let path = &s.path;
            prop_assert!(path.len() >= 2, "{:?}; {}", path, ctx);
            let lo_end = s.lower.level.is_some();
            let hi_end = s.upper.level.is_some();
            let inner = &path[usize::from(lo_end)..path.len() - usize::from(hi_end)];
            prop_assert!(!inner.is_empty(), "{}", ctx);
            let ids: Vec<usize> = inner
                .iter()
                .map(|p| r.node_at(p))
                .collect::<Option<Vec<_>>>()
                .ok_or_else(|| TestCaseError::fail(format!("stair point not a surface; {ctx}")))?;
            // inner nodes are walkable; a node next to a level end need
            // not be (a first tread beside a door's jambs)
            for (k, &i) in ids.iter().enumerate() {
                let beside_end = (k == 0 && lo_end) || (k + 1 == ids.len() && hi_end);
                prop_assert!(beside_end || r.nodes[i].walkable, "unwalkable stair node {:?}; {}", r.nodes[i], ctx);
            }
            for w in ids.windows(2) {
                prop_assert!(r.steps(w[0]).any(|j| j == w[1]), "not step-connected {:?}; {}", (r.nodes[w[0]], r.nodes[w[1]]), ctx);
            }
            let len: f64 = path.windows(2).map(|w| (w[1] - w[0]).norm()).sum();
            prop_assert!((len - s.length).abs() <= 1e-9 * len.max(1.0), "{}", ctx);
            let ends = [(&s.lower, ids[0]), (&s.upper, *ids.last().unwrap())];
            for (end, node) in ends {
                if let Some(l) = level_index(end.level) {
                    let foot = r.foot_z(l, r.col_of(&end.position));
                    prop_assert!(foot.is_some_and(|z| (end.position.z - z).abs() < 1e-9), "end {:?} not on its level's surface {:?}; {}", end.position, foot, ctx);
                    prop_assert!(r.feet(node).contains(&(l, r.col_of(&end.position))), "end not next to its foot; {}", ctx);
                }
            }

            // Lengths against the reference's shortest step-paths.
            let (start, far) = if lo_end { (&s.lower, &s.upper) } else { (&s.upper, &s.lower) };
            let sl = level_index(start.level).unwrap();
            let dist = r.paths_from_end(sl, r.col_of(&start.position));
            match level_index(far.level) {
                Some(fl) => {
                    let goal_col = r.col_of(&far.position);
                    let best = dist
                        .iter()
                        .filter(|(i, _)| r.feet(**i).contains(&(fl, goal_col)))
                        .map(|(i, d)| d + (r.node_point(*i) - far.position).norm())
                        .fold(f64::INFINITY, f64::min);
                    prop_assert!(best.is_finite(), "{}", ctx);
                    let cost = r.stair_cost(s, lo_end);
                    prop_assert!(cost >= best - 1e-9, "stair {} cheaper than the reference {}; {}", cost, best, ctx);
                    prop_assert!(cost <= best + hop + 1e-9, "stair {} dearer than the reference {} + {}; {}", cost, best, hop, ctx);
                }
                None => {
                    let open = r.node_at(&far.position).unwrap();
                    prop_assert!(r.nodes[open].walkable, "unwalkable open end; {}", ctx);
                    let d = dist.get(&open).copied().unwrap_or(f64::INFINITY);
                    let cost = r.stair_cost(s, lo_end);
                    prop_assert!((cost - d).abs() <= 1e-9 * d.max(1.0), "partial stair {} vs reference {}; {}", cost, d, ctx);
                    let hs = r.floors[sl];
                    let rise = |i: usize| (f64::from(r.nodes[i].z) - hs).abs();
                    // A sighted flight: the step-connected off-level
                    // surfaces around it (walkable or not), or what they
                    // sight across unobserved columns, reach
                    // `min_stair_sighting_rise` beyond the level; then any
                    // walkable tread off the level is an open end.
                    let dir = if far.position.z >= start.position.z { 1.0 } else { -1.0 };
                    let comp = r.component(ids[0]);
                    let own = comp.iter()
                        .map(|&i| (f64::from(r.nodes[i].z) - hs) * dir)
                        .fold(f64::NEG_INFINITY, f64::max);
                    // ... or across unobserved columns (a flight seen
                    // from its foot, the rest of it seen from elsewhere)
                    let gap = (f64::from(r.gap_reach(&comp, dir as f32)) - hs) * dir;
                    let reach = own.max(gap);
                    let min_rise = if reach >= cfg.levels.min_stair_sighting_rise {
                        f64::from(cfg.levels.level_tolerance as f32)
                    } else {
                        cfg.levels.min_stair_rise
                    };
                    prop_assert!(rise(open) >= min_rise, "open end rises {} < {}; {}", rise(open), min_rise, ctx);
                    let top = dist.keys().filter(|&&i| r.nodes[i].walkable).map(|&i| rise(i)).fold(0.0, f64::max);
                    prop_assert!(rise(open) >= top - 1e-6, "open end rises {} < {}; {}", rise(open), top, ctx);
                }
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    /// A robot on a stair's first treads (within the lower level's
    /// tolerance of its floor, but raised above it) is located on the
    /// stair, and its path up the stair never goes back down to the floor
    /// (planned on the level's grid, which takes a low tread for floor, it
    /// went back to the stair's foot first). Feet on the floor are on the
    /// level.
    #[test]
    fn a_robot_on_the_first_treads_is_on_the_stair(scene in scene_strategy()) {
        let mut map = explore(&scene);
        let ctx = describe(&scene);
        let tol = map.config().levels.robot_level_tolerance;
        let Some(s) = map.stairs().first().cloned() else {
            return Ok(());
        };
        for f in &scene.feet {
            if f.z.abs() <= 0.01 {
                prop_assert_eq!(map.locate(f), Some(Location::Level(LevelId(0))), "{:?}; {}", f, ctx);
            }
        }
        // The stair's own path points on its low treads (off the level:
        // above its tolerance; a level end stands on the floor surface,
        // which may be mapped up to that tolerance high, and is on the
        // level).
        let level_tol = map.config().levels.level_tolerance;
        let low: Vec<Point3<f64>> = s.path.iter().copied().filter(|q| q.z > level_tol && q.z <= tol).collect();
        for f in &low {
            prop_assert!(matches!(map.locate(f), Some(Location::Stair(_))), "{:?} located {:?}; {}", f, map.locate(f), ctx);
            let path = map.path(f, &s.upper.position).unwrap();
            let path = path.expect("a path up the stair");
            let lowest = path.path.iter().map(|q| q.z).fold(f64::INFINITY, f64::min);
            prop_assert!(lowest >= f.z - map.config().grid.step_height - 1e-6,
                "from {:?} the path goes down to {}; {}", f, lowest, ctx);
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(8))]

    /// A robot that starts on a stair's half landing takes it for level 0
    /// (its first pose); the floors half a storey below and above are
    /// closer to it than `min_level_separation`, but the landing is
    /// smaller than `min_level_area`, so both still become levels and
    /// complete stairs join the landing to each (before, the agent kept
    /// the floors as "stair surfaces" and never left the landing's flights).
    #[test]
    fn a_robot_starting_on_a_half_landing_finds_both_floors(
        (rise, tread, width, turn) in (0.12f64..0.19, 0.25f64..0.32, 0.9f64..1.2, 0u8..4),
        walls in (any::<bool>(), any::<bool>()),
    ) {
        let scene = Scene::new(SceneParams {
            rise,
            tread,
            width,
            turn,
            offset: (0.0, 0.0),
            landing: true,
            walls,
            platform: None,
            table: false,
            across: 0.5,
        });
        let ctx = describe(&scene);
        // feet: floor 0 (2), the stair at 1/4, 1/2 (the landing's height),
        // 3/4, floor 1 (2). Start on the landing, go up, then down.
        let order = [3usize, 4, 5, 6, 3, 2, 1, 0, 3];
        let mut map = MultiLevelMap::new(ml_config()).unwrap();
        let range = map.config().grid.max_range;
        for &i in &order {
            let f = scene.feet[i];
            let eye = f + Vector3::new(0.0, 0.0, EYE);
            let pts = scene.scan(&eye, 0.07, 4.8, range);
            map.update(&f, &eye, &pts).unwrap();
            map.frontier_graph(&f).unwrap();
        }
        let tol = map.config().levels.level_tolerance;
        let landing = scene.feet[3].z;
        let floors: Vec<f64> = map.levels().map(|l| l.floor_z).collect();
        prop_assert!((floors[0] - landing).abs() < 1e-9, "{:?}; {}", floors, ctx);
        let level_near = |z: f64| floors.iter().position(|f| (f - z).abs() <= tol);
        let (Some(low), Some(high)) = (level_near(0.0), level_near(scene.h)) else {
            return Err(TestCaseError::fail(format!("floors {floors:?} miss 0 or {}; {ctx}", scene.h)));
        };
        let joined: BTreeSet<(usize, usize)> = map
            .stairs()
            .iter()
            .filter(|s| s.is_complete())
            .map(|s| (usize::from(s.lower.level.unwrap().0), usize::from(s.upper.level.unwrap().0)))
            .collect();
        prop_assert!(joined.contains(&(low, 0)) && joined.contains(&(0, high)), "joined {:?}; {}", joined, ctx);
    }
}
