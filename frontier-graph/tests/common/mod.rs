//! Shared helpers of the integration tests: a ground-truth box world, a
//! simulated 2D scanner and an independent reference Dijkstra.
#![allow(dead_code)]

use nalgebra::{Point2, Point3};
use proptest::prelude::*;
use sornav_frontier_graph::FrontierMapConfig;
use sornav_frontier_graph::{Cell, FrontierMap, OccupancyGrid};
use std::collections::{BinaryHeap, HashMap};

/// Ground truth: axis-aligned boxes (x0, y0, x1, y1) in metres.
#[derive(Debug, Clone)]
pub struct World {
    pub boxes: Vec<[f64; 4]>,
}

impl World {
    pub fn blocked(&self, p: Point2<f64>) -> bool {
        self.boxes
            .iter()
            .any(|b| p.x >= b[0] && p.x <= b[2] && p.y >= b[1] && p.y <= b[3])
    }

    /// A 2D LiDAR at height 0.5 m: `beams` rays, max range `range`. Rays that
    /// hit nothing return a point beyond the range.
    pub fn scan(&self, origin: Point2<f64>, beams: usize, range: f64) -> Vec<Point3<f64>> {
        let step = 0.01;
        (0..beams)
            .map(|k| {
                let a = k as f64 * std::f64::consts::TAU / beams as f64;
                let d = nalgebra::Vector2::new(a.cos(), a.sin());
                let mut t = 0.0;
                while t < range {
                    t += step;
                    let p = origin + d * t;
                    if self.blocked(p) {
                        return Point3::new(p.x, p.y, 0.5);
                    }
                }
                let p = origin + d * (range + 1.0);
                Point3::new(p.x, p.y, 0.5)
            })
            .collect()
    }
}

/// The 8 neighbour offsets.
pub const DIRS: [(i32, i32); 8] = [
    (1, 0),
    (-1, 0),
    (0, 1),
    (0, -1),
    (1, 1),
    (1, -1),
    (-1, 1),
    (-1, -1),
];

/// Textbook Dijkstra (binary heap, octile, 8-connected, no corner cutting)
/// from `src` over `grid.is_traversable`; distances in metres.
pub fn reference_dijkstra(grid: &OccupancyGrid, src: Cell) -> HashMap<Cell, f64> {
    #[derive(PartialEq)]
    struct Item(f64, Cell);
    impl Eq for Item {}
    impl PartialOrd for Item {
        fn partial_cmp(&self, o: &Self) -> Option<std::cmp::Ordering> {
            Some(self.cmp(o))
        }
    }
    impl Ord for Item {
        fn cmp(&self, o: &Self) -> std::cmp::Ordering {
            o.0.total_cmp(&self.0)
        }
    }
    let mut dist = HashMap::new();
    if !grid.is_traversable(src) {
        return dist;
    }
    let mut heap = BinaryHeap::new();
    dist.insert(src, 0.0);
    heap.push(Item(0.0, src));
    while let Some(Item(d, c)) = heap.pop() {
        if d > dist[&c] {
            continue;
        }
        for (dx, dy) in DIRS {
            let n = c.offset(dx, dy);
            if !grid.is_traversable(n) {
                continue;
            }
            if dx != 0
                && dy != 0
                && (!grid.is_traversable(c.offset(dx, 0)) || !grid.is_traversable(c.offset(0, dy)))
            {
                continue;
            }
            let nd = d + if dx != 0 && dy != 0 { 2f64.sqrt() } else { 1.0 };
            if dist.get(&n).is_none_or(|&o| nd < o) {
                dist.insert(n, nd);
                heap.push(Item(nd, n));
            }
        }
    }
    let res = grid.resolution();
    dist.into_iter().map(|(c, d)| (c, d * res)).collect()
}

/// Scans the world from each origin in turn, asking for the graph after each.
pub fn explore(map: &mut FrontierMap, world: &World, origins: &[Point2<f64>], beams: usize) {
    for o in origins {
        let pts = world.scan(*o, beams, map.config().grid.max_range);
        map.update(&Point3::new(o.x, o.y, 0.5), &pts).unwrap();
        map.frontier_graph(o).unwrap();
    }
}

pub mod scene;

/// A directed link between two levels' cells: (from, to, weight).
pub type Link = ((usize, Cell), (usize, Cell), f64);

/// Textbook Dijkstra over the union of several levels' grids (8-connected
/// octile, no corner cutting, as [`reference_dijkstra`]) joined by directed
/// links `((level, cell), (level, cell), weight)`; distances in metres.
pub fn reference_union_dijkstra(
    grids: &[&OccupancyGrid],
    links: &[Link],
    src: (usize, Cell),
) -> HashMap<(usize, Cell), f64> {
    #[derive(PartialEq)]
    struct Item(f64, (usize, Cell));
    impl Eq for Item {}
    impl PartialOrd for Item {
        fn partial_cmp(&self, o: &Self) -> Option<std::cmp::Ordering> {
            Some(self.cmp(o))
        }
    }
    impl Ord for Item {
        fn cmp(&self, o: &Self) -> std::cmp::Ordering {
            o.0.total_cmp(&self.0)
        }
    }
    let mut dist = HashMap::new();
    if !grids[src.0].is_traversable(src.1) {
        return dist;
    }
    let mut heap = BinaryHeap::new();
    dist.insert(src, 0.0);
    heap.push(Item(0.0, src));
    while let Some(Item(d, (l, c))) = heap.pop() {
        if d > dist[&(l, c)] {
            continue;
        }
        let g = grids[l];
        let res = g.resolution();
        let mut next: Vec<((usize, Cell), f64)> = Vec::new();
        for (dx, dy) in DIRS {
            let n = c.offset(dx, dy);
            if !g.is_traversable(n) {
                continue;
            }
            if dx != 0
                && dy != 0
                && (!g.is_traversable(c.offset(dx, 0)) || !g.is_traversable(c.offset(0, dy)))
            {
                continue;
            }
            next.push((
                (l, n),
                res * if dx != 0 && dy != 0 { 2f64.sqrt() } else { 1.0 },
            ));
        }
        for &(a, b, w) in links {
            if a == (l, c) {
                next.push((b, w));
            }
        }
        for (n, w) in next {
            let nd = d + w;
            if dist.get(&n).is_none_or(|&o| nd < o) {
                dist.insert(n, nd);
                heap.push(Item(nd, n));
            }
        }
    }
    dist
}

/// The configuration of the random single-floor worlds.
pub fn config() -> FrontierMapConfig {
    let mut cfg = FrontierMapConfig::default();
    cfg.grid.resolution = 0.1;
    cfg.grid.max_range = 2.5;
    cfg.grid.robot_radius = 0.15;
    cfg.frontier.max_extent = 1.0;
    cfg.frontier.min_cells = 3;
    cfg
}

/// A 6 m x 6 m room with outer walls and random boxes, plus origins that lie
/// in free space.
pub fn world_strategy() -> impl Strategy<Value = (World, Vec<Point2<f64>>)> {
    let boxes = prop::collection::vec((0.3f64..5.0, 0.3f64..5.0, 0.2f64..1.5, 0.1f64..1.0), 0..6);
    let origins = prop::collection::vec((0.4f64..5.6, 0.4f64..5.6), 2..5);
    (boxes, origins).prop_map(|(bs, os)| {
        let mut boxes = vec![
            [-0.1, -0.1, 6.1, 0.0],
            [-0.1, 6.0, 6.1, 6.1],
            [-0.1, -0.1, 0.0, 6.1],
            [6.0, -0.1, 6.1, 6.1],
        ];
        for (x, y, w, h) in bs {
            boxes.push([x, y, x + w, y + h]);
        }
        let world = World { boxes };
        let origins = os
            .into_iter()
            .map(|(x, y)| Point2::new(x, y))
            .filter(|p| {
                // keep origins with clearance
                (0..16).all(|k| {
                    let a = f64::from(k) * std::f64::consts::TAU / 16.0;
                    !world.blocked(p + nalgebra::Vector2::new(a.cos(), a.sin()) * 0.25)
                }) && !world.blocked(*p)
            })
            .collect();
        (world, origins)
    })
}
