//! Benchmark of the frontier decision graph on a deterministic 30 m x 30 m
//! house-like map at 0.05 m (5 x 5 rooms, doors, furniture).
//!
//! A forward-looking depth camera reduced to one row (79° HFOV, 160 columns,
//! 5 m, at 0.5 m height) sweeps the house along a scripted route through
//! rooms and doors until at least 200 frontier nodes exist. The route then
//! continues with 60 typical incremental steps, each timed as sensor update,
//! frontier update and graph refresh at the new pose. The full rebuild
//! (frontiers and every edge from scratch) is timed on the state with 200
//! frontier nodes (median of 7). Prints one JSON line (medians):
//! `{"grid_cells","frontier_nodes","update_ms_p50","update_ms_p99","rebuild_ms"}`;
//! context goes to stderr.
//!
//! Run: `cargo run --release -p sornav-frontier-graph --example bench_frontier_graph`

use nalgebra::{Point2, Point3, Vector2};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use sornav_frontier_graph::{FrontierMap, FrontierMapConfig};
use std::time::Instant;

const SIZE: f64 = 30.0;
const TRUTH_RES: f64 = 0.025;
const ROOMS: usize = 5;

/// Ground-truth occupancy raster of the house.
struct House {
    n: usize,
    blocked: Vec<bool>,
    /// Room centres, row by row.
    centres: Vec<Point2<f64>>,
    /// Door centres between horizontally / vertically adjacent rooms.
    doors_x: Vec<Vec<f64>>,
    doors_y: Vec<Vec<f64>>,
}

impl House {
    fn generate(seed: u64) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let n = (SIZE / TRUTH_RES) as usize;
        let mut h = House {
            n,
            blocked: vec![false; n * n],
            centres: Vec::new(),
            doors_x: vec![vec![0.0; ROOMS]; ROOMS],
            doors_y: vec![vec![0.0; ROOMS]; ROOMS],
        };
        let room = SIZE / ROOMS as f64;
        let wall = 0.12;
        // Outer walls.
        h.fill(0.0, 0.0, SIZE, wall);
        h.fill(0.0, SIZE - wall, SIZE, SIZE);
        h.fill(0.0, 0.0, wall, SIZE);
        h.fill(SIZE - wall, 0.0, SIZE, SIZE);
        // Interior walls with one 0.9 m door per shared wall.
        for i in 1..ROOMS {
            let x = i as f64 * room;
            for j in 0..ROOMS {
                let y0 = j as f64 * room;
                let d = y0 + rng.random_range(1.0..room - 1.9);
                h.fill(x - wall / 2.0, y0, x + wall / 2.0, d);
                h.fill(x - wall / 2.0, d + 0.9, x + wall / 2.0, y0 + room);
                h.doors_x[i][j] = d + 0.45;
            }
        }
        for j in 1..ROOMS {
            let y = j as f64 * room;
            for i in 0..ROOMS {
                let x0 = i as f64 * room;
                let d = x0 + rng.random_range(1.0..room - 1.9);
                h.fill(x0, y - wall / 2.0, d, y + wall / 2.0);
                h.fill(d + 0.9, y - wall / 2.0, x0 + room, y + wall / 2.0);
                h.doors_y[i][j] = d + 0.45;
            }
        }
        // Furniture: a few boxes per room, away from the centre and the doors.
        for j in 0..ROOMS {
            for i in 0..ROOMS {
                let (x0, y0) = (i as f64 * room, j as f64 * room);
                h.centres
                    .push(Point2::new(x0 + room / 2.0, y0 + room / 2.0));
                for _ in 0..rng.random_range(3..7) {
                    let w = rng.random_range(0.3..1.4);
                    let d = rng.random_range(0.3..0.9);
                    // Along a random wall of the room.
                    let (bx, by, bw, bd) = match rng.random_range(0..4) {
                        0 => (rng.random_range(0.8..room - 2.2), 0.35, w, d),
                        1 => (rng.random_range(0.8..room - 2.2), room - 0.35 - d, w, d),
                        2 => (0.35, rng.random_range(0.8..room - 2.2), d, w),
                        _ => (room - 0.35 - d, rng.random_range(0.8..room - 2.2), d, w),
                    };
                    h.fill(x0 + bx, y0 + by, x0 + bx + bw, y0 + by + bd);
                }
                // A free-standing table somewhere off-centre.
                let tx = x0 + room / 2.0 + rng.random_range(0.8..1.6);
                let ty = y0 + room / 2.0 + rng.random_range(-1.5..1.0);
                h.fill(tx, ty, tx + 0.6, ty + 0.6);
            }
        }
        h
    }

    fn fill(&mut self, x0: f64, y0: f64, x1: f64, y1: f64) {
        let c = |v: f64| ((v / TRUTH_RES).floor().max(0.0) as usize).min(self.n - 1);
        for y in c(y0)..=c(y1) {
            for x in c(x0)..=c(x1) {
                self.blocked[y * self.n + x] = true;
            }
        }
    }

    fn is_blocked(&self, p: Point2<f64>) -> bool {
        if p.x < 0.0 || p.y < 0.0 || p.x >= SIZE || p.y >= SIZE {
            return true;
        }
        let (x, y) = ((p.x / TRUTH_RES) as usize, (p.y / TRUTH_RES) as usize);
        self.blocked[y * self.n + x]
    }

    /// A forward-looking depth camera reduced to one row: `beams` columns over
    /// the horizontal field of view `fov` around `heading`.
    fn scan(
        &self,
        o: Point2<f64>,
        heading: f64,
        fov: f64,
        beams: usize,
        range: f64,
    ) -> Vec<Point3<f64>> {
        (0..beams)
            .map(|k| {
                let a = heading - fov / 2.0 + fov * (k as f64 + 0.5) / beams as f64;
                let d = Vector2::new(a.cos(), a.sin());
                let mut t = 0.0;
                while t < range {
                    t += TRUTH_RES * 0.5;
                    let p = o + d * t;
                    if self.is_blocked(p) {
                        return Point3::new(p.x, p.y, 0.5);
                    }
                }
                let p = o + d * (range + 0.5);
                Point3::new(p.x, p.y, 0.5)
            })
            .collect()
    }

    /// A route visiting every room in serpentine order through its doors,
    /// sampled every `step` metres.
    fn route(&self, step: f64) -> Vec<Point2<f64>> {
        let room = SIZE / ROOMS as f64;
        let mut way = Vec::new();
        for j in 0..ROOMS {
            let cols: Vec<usize> = if j % 2 == 0 {
                (0..ROOMS).collect()
            } else {
                (0..ROOMS).rev().collect()
            };
            for (k, &i) in cols.iter().enumerate() {
                way.push(self.centres[j * ROOMS + i]);
                if k + 1 < cols.len() {
                    // Through the door towards the next room in this row.
                    let nx = cols[k + 1];
                    let wx = i.max(nx);
                    let dy = self.doors_x[wx][j];
                    let x = wx as f64 * room;
                    way.push(Point2::new(x - 0.6 * (nx as f64 - i as f64).signum(), dy));
                    way.push(Point2::new(x + 0.6 * (nx as f64 - i as f64).signum(), dy));
                }
            }
            if j + 1 < ROOMS {
                let i = *cols.last().unwrap_or(&0);
                let dx = self.doors_y[i][j + 1];
                let y = (j + 1) as f64 * room;
                way.push(Point2::new(dx, y - 0.6));
                way.push(Point2::new(dx, y + 0.6));
            }
        }
        let mut pts = vec![way[0]];
        for w in way.windows(2) {
            let d = w[1] - w[0];
            let n = (d.norm() / step).ceil().max(1.0) as usize;
            for k in 1..=n {
                pts.push(w[0] + d * (k as f64 / n as f64));
            }
        }
        pts
    }
}

fn percentile(v: &mut [f64], q: f64) -> f64 {
    v.sort_by(f64::total_cmp);
    let k = ((v.len() - 1) as f64 * q).round() as usize;
    v[k]
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let house = House::generate(7);
    let route = house.route(0.5);
    let cfg = FrontierMapConfig::default();
    let range = cfg.grid.max_range;
    let mut map = FrontierMap::new(cfg)?;
    let beams = 160;
    let fov = 79f64.to_radians();
    let heading = |k: usize| {
        let d = route[(k + 1).min(route.len() - 1)] - route[k.saturating_sub(1)];
        d.y.atan2(d.x)
    };
    let mut k = 0;
    // Sweep until 200 frontier nodes exist.
    while k < route.len() {
        let o = route[k];
        let pts = house.scan(o, heading(k), fov, beams, range);
        map.update(&Point3::new(o.x, o.y, 0.5), &pts)?;
        k += 1;
        if map.graph().len() >= 200 {
            break;
        }
    }
    let pose = route[k.min(route.len() - 1)];
    map.frontier_graph(&pose)?;
    let frontier_nodes = map.graph().len();
    // The state with 200 frontier nodes, for the rebuild timing below.
    let snapshot = map.clone();
    // Typical incremental steps along the route.
    let mut times = Vec::new();
    let mut rows = 0;
    let steps = 60;
    for s in 0..steps {
        let kk = (k + s) % route.len();
        let o = route[kk];
        let pts = house.scan(o, heading(kk), fov, beams, range);
        let t = Instant::now();
        map.update(&Point3::new(o.x, o.y, 0.5), &pts)?;
        map.frontier_graph(&o)?;
        times.push(t.elapsed().as_secs_f64() * 1e3);
        rows += map.last_refresh().rows_recomputed;
    }
    // Full rebuild from scratch (frontiers + every edge) with 200 frontier
    // nodes.
    let mut rebuild = Vec::new();
    for _ in 0..7 {
        let mut m = snapshot.clone();
        let t = Instant::now();
        m.rebuild();
        m.frontier_graph(&pose)?;
        rebuild.push(t.elapsed().as_secs_f64() * 1e3);
    }
    // Context on stderr (stdout carries only the JSON line).
    if let Some((lo, hi)) = snapshot.grid().bounds() {
        let mut trav = 0usize;
        for y in lo.y..=hi.y {
            for x in lo.x..=hi.x {
                trav += usize::from(
                    snapshot
                        .grid()
                        .is_traversable(sornav_frontier_graph::Cell::new(x, y)),
                );
            }
        }
        eprintln!(
            "200 nodes at route step {k} of {}: traversable {trav} cells ({:.0} m2); {:.1} rows per update; rebuild runs {rebuild:.1?} ms",
            route.len(),
            trav as f64 * 0.0025,
            rows as f64 / steps as f64
        );
    }
    let p50 = percentile(&mut times.clone(), 0.5);
    let p99 = percentile(&mut times, 0.99);
    println!(
        "{{\"grid_cells\":{},\"frontier_nodes\":{},\"update_ms_p50\":{:.3},\"update_ms_p99\":{:.3},\"rebuild_ms\":{:.3}}}",
        map.grid().cell_count(),
        frontier_nodes,
        p50,
        p99,
        percentile(&mut rebuild, 0.5)
    );
    Ok(())
}
