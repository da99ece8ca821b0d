//! Times `ClusterGraph::build` and the semantic contexts on a decision graph
//! of the size SOR-Nav meets in a house, and prints one JSON line of medians.
//!
//! Scene: a 30 m x 30 m floor of 4 x 4 rooms; 200 frontiers spread over
//! them, every pair connected as in G_F. Within a room, cost = Euclidean
//! distance x a detour factor in [1, 1.5); between rooms a door detour of
//! 20 m + 5 m per room step is added, so clusters roughly follow rooms.
//! Paths have three points. 300 objects for the contexts.
//!
//! `cargo run --release -p sornav-cluster-graph --example bench_cluster_graph [-- FRONTIERS OBJECTS]`

use std::time::Instant;

use nalgebra::{Point2, Point3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use sornav_cluster_graph::{
    ClusterConfig, ClusterGraph,
    GraphNode::{Frontier, Robot},
    ObjectSummary, SparseDecisionGraph,
};

const REPS: usize = 21;

fn median_ms(mut f: impl FnMut()) -> f64 {
    let mut t: Vec<f64> = (0..REPS)
        .map(|_| {
            let s = Instant::now();
            f();
            s.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    t.sort_by(f64::total_cmp);
    t[REPS / 2]
}

fn main() {
    let args: Vec<usize> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let n = args.first().copied().unwrap_or(200);
    let m = args.get(1).copied().unwrap_or(300);
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let point = |rng: &mut ChaCha8Rng| {
        Point2::new(rng.random_range(0.0..30.0), rng.random_range(0.0..30.0))
    };

    let robot = Point2::new(15.0, 15.0);
    let mut g = SparseDecisionGraph::new(robot);
    let pos: Vec<Point2<f64>> = (0..n).map(|_| point(&mut rng)).collect();
    let room = |p: Point2<f64>| ((p.x / 7.5) as i32, (p.y / 7.5) as i32);
    let door = |a: Point2<f64>, b: Point2<f64>| {
        let (ra, rb) = (room(a), room(b));
        let steps = (ra.0 - rb.0).abs() + (ra.1 - rb.1).abs();
        if steps == 0 {
            0.0
        } else {
            20.0 + 5.0 * f64::from(steps)
        }
    };
    let path = |a: Point2<f64>, b: Point2<f64>| vec![a, Point2::new(a.x, b.y), b];
    for (i, &p) in pos.iter().enumerate() {
        let id = i as u64;
        g.add_frontier(id, p);
        let detour = rng.random_range(1.0..1.5);
        g.set_edge(
            Robot,
            Frontier(id),
            (p - robot).norm() * detour + door(robot, p),
            path(robot, p),
        );
        for (j, &q) in pos.iter().enumerate().skip(i + 1) {
            let detour = rng.random_range(1.0..1.5);
            g.set_edge(
                Frontier(id),
                Frontier(j as u64),
                (p - q).norm() * detour + door(p, q),
                path(p, q),
            );
        }
    }
    const LABELS: [&str; 6] = ["bed", "toilet", "sofa", "tv", "chair", "plant"];
    let objects: Vec<ObjectSummary> = (0..m)
        .map(|_| {
            let p = point(&mut rng);
            ObjectSummary {
                level: None,
                label: LABELS[rng.random_range(0..LABELS.len())].into(),
                support: rng.random_range(0..500),
                centre: Point3::new(p.x, p.y, 0.8),
            }
        })
        .collect();

    let config = ClusterConfig::default();
    let cg = ClusterGraph::build(&g, &config).expect("valid graph");
    let build_ms = median_ms(|| {
        std::hint::black_box(ClusterGraph::build(&g, &config).expect("valid graph"));
    });
    let contexts_ms = median_ms(|| {
        std::hint::black_box(cg.candidate_contexts(&objects));
        std::hint::black_box(cg.robot_context(&objects));
    });
    println!(
        "{{\"frontiers\":{n},\"frontier_edges\":{},\"clusters\":{},\"objects\":{m},\"build_ms_p50\":{build_ms:.3},\"contexts_ms_p50\":{contexts_ms:.3}}}",
        n * (n - 1) / 2,
        cg.len(),
    );
}
