//! Height field and geodesic distance: properties and differential tests
//! against brute-force references.

use std::sync::OnceLock;

use nalgebra::Point3;
use proptest::prelude::*;
use sornav_platform_sim::geometry::MeshBuilder;
use sornav_platform_sim::{InstanceKind, NavMesh, NavMeshConfig, Scene};

mod common;

fn house() -> &'static (Scene, NavMesh) {
    static H: OnceLock<(Scene, NavMesh)> = OnceLock::new();
    H.get_or_init(|| {
        let s = common::house(11, 2);
        let n = NavMesh::build(&s, &NavMeshConfig::default()).unwrap();
        (s, n)
    })
}

/// A mesh with a 0.1 m thick floor plate `width` x 3 m (top at z = 0).
fn floor_plate(width: f64) -> MeshBuilder {
    let mut b = MeshBuilder::new();
    let f = b.add_instance(InstanceKind::Floor, "floor", "floor", 0);
    b.aabb_box(Point3::new(0.0, 0.0, -0.1), Point3::new(width, 3.0, 0.0), f);
    b
}

/// A floor plate with boxes of random size and height on it.
fn box_world(boxes: &[(f64, f64, f64, f64, f64)]) -> Scene {
    let mut b = floor_plate(4.0);
    for &(x, y, w, d, h) in boxes {
        let i = b.add_instance(InstanceKind::Object, "box", "box", 0);
        b.aabb_box(Point3::new(x, y, 0.0), Point3::new(x + w, y + d, h), i);
    }
    common::one_level_scene(b, "boxes")
}

/// Islands of any size kept (other options default).
fn all_islands() -> NavMeshConfig {
    NavMeshConfig {
        min_region_area: 0.0,
        ..Default::default()
    }
}

fn raw_config() -> NavMeshConfig {
    NavMeshConfig {
        agent_radius: 0.0,
        min_region_area: 0.0,
        max_step: 0.0,
        ..Default::default()
    }
}

/// Plain Dijkstra over the span graph with an O(n^2) scan (no heap), with the
/// same octile move rule, as the reference for the geodesic field.
fn reference_distances(nav: &NavMesh, source: u32) -> Vec<f64> {
    let spans = nav.spans();
    let n = spans.len();
    let cs = nav.config().cell_size;
    let mut dist = vec![f64::INFINITY; n];
    let mut done = vec![false; n];
    dist[source as usize] = 0.0;
    for _ in 0..n {
        let Some(u) = (0..n)
            .filter(|&i| !done[i] && dist[i].is_finite())
            .min_by(|&a, &b| dist[a].total_cmp(&dist[b]))
        else {
            break;
        };
        done[u] = true;
        let nb = spans[u].neighbours;
        let mut moves: Vec<(usize, f64)> = nb
            .iter()
            .filter(|&&v| v != u32::MAX)
            .map(|&v| (v as usize, cs))
            .collect();
        for d in 0..4 {
            let e = (d + 1) % 4;
            let (a, b) = (nb[d], nb[e]);
            if a != u32::MAX && b != u32::MAX {
                let (va, vb) = (
                    spans[a as usize].neighbours[e],
                    spans[b as usize].neighbours[d],
                );
                if va != u32::MAX && va == vb {
                    moves.push((va as usize, cs * std::f64::consts::SQRT_2));
                }
            }
        }
        for (v, h) in moves {
            let dz = f64::from(spans[v].floor - spans[u].floor);
            let nd = dist[u] + (h * h + dz * dz).sqrt();
            if nd < dist[v] {
                dist[v] = nd;
            }
        }
    }
    dist
}

#[test]
fn geodesic_field_matches_reference_dijkstra() {
    let scene = box_world(&[
        (1.0, 0.5, 0.6, 1.5, 1.0),
        (2.5, 1.2, 0.4, 1.8, 0.5),
        (0.3, 2.2, 1.0, 0.3, 0.15),
    ]);
    let nav = NavMesh::build(&scene, &all_islands()).unwrap();
    for src in [0u32, nav.span_count() as u32 / 2] {
        let goal = nav.span_center(src);
        let field = nav.geodesic_field(&[goal]).unwrap();
        let reference = reference_distances(&nav, src);
        for (s, r) in reference.iter().enumerate() {
            let f = field.span_distance(s as u32);
            assert!(
                (f - r).abs() < 1e-9 || (f.is_infinite() && r.is_infinite()),
                "span {s}: {f} vs {r}"
            );
        }
    }
}

#[test]
fn multi_goal_field_is_min_of_single_fields() {
    let (_, nav) = house();
    let goals = [
        nav.span_center(10),
        nav.span_center(nav.span_count() as u32 - 10),
    ];
    let both = nav.geodesic_field(&goals).unwrap();
    let a = nav.geodesic_field(&goals[..1]).unwrap();
    let b = nav.geodesic_field(&goals[1..]).unwrap();
    for s in (0..nav.span_count() as u32).step_by(97) {
        let m = a.span_distance(s).min(b.span_distance(s));
        let d = both.span_distance(s);
        assert!(
            (d.is_infinite() && m.is_infinite()) || (d - m).abs() < 1e-9,
            "{d} vs {m}"
        );
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    /// Walkable columns of a box world equal the brute-force answer: a column
    /// is walkable at floor level iff no box overlaps its square.
    #[test]
    fn rasterised_floor_matches_box_overlap(
        boxes in prop::collection::vec((0.1f64..3.0, 0.1f64..2.0, 0.1f64..1.0, 0.1f64..1.0, 0.05f64..1.5), 1..5)
    ) {
        let scene = box_world(&boxes);
        let nav = NavMesh::build(&scene, &raw_config()).unwrap();
        let cs = 0.05;
        let o = nav.origin();
        let (w, h) = nav.grid_size();
        for cy in 0..h {
            for cx in 0..w {
                let (x0, y0) = (o.x + cx as f64 * cs, o.y + cy as f64 * cs);
                let (xc, yc) = (x0 + cs / 2.0, y0 + cs / 2.0);
                // keep away from exact cell boundaries of the plate and boxes
                let near_edge = |a: f64| ((a / cs) - (a / cs).round()).abs() < 1e-6;
                if boxes.iter().any(|b| near_edge(b.0) || near_edge(b.1) || near_edge(b.0 + b.2) || near_edge(b.1 + b.3)) {
                    return Ok(());
                }
                let on_plate = xc > 0.0 && xc < 4.0 && yc > 0.0 && yc < 3.0;
                let covered = boxes.iter().any(|b| x0 < b.0 + b.2 && b.0 < x0 + cs && y0 < b.1 + b.3 && b.1 < y0 + cs);
                // (boxes are closed, so their interior is not walkable either)
                let floor_walkable = nav.heights_at(xc, yc).iter().any(|z| z.abs() < 1e-4);
                prop_assert_eq!(floor_walkable, on_plate && !covered, "column ({}, {})", cx, cy);
            }
        }
    }

    #[test]
    fn geodesic_distance_is_a_metric_above_euclidean(i in 0usize..1_000_000, j in 0usize..1_000_000, k in 0usize..1_000_000) {
        let (_, nav) = house();
        let main = nav.largest_region().unwrap();
        let ids: Vec<u32> = (0..nav.span_count() as u32).filter(|&s| nav.spans()[s as usize].region == main).collect();
        let p = |n: usize| {
            let c = nav.span_center(ids[n % ids.len()]);
            Point3::new(c.x + 0.01, c.y - 0.01, c.z)
        };
        let (a, b, c) = (p(i), p(j), p(k));
        let dab = nav.distance(&a, &b).unwrap();
        let dba = nav.distance(&b, &a).unwrap();
        let dbc = nav.distance(&b, &c).unwrap();
        let dac = nav.distance(&a, &c).unwrap();
        prop_assert_eq!(nav.distance(&a, &a).unwrap(), 0.0);
        prop_assert!((dab - dba).abs() < 1e-6, "{} vs {}", dab, dba);
        prop_assert!(dac <= dab + dbc + 1e-9);
        prop_assert!(dab + 1e-9 >= (b - a).norm());
        // the field agrees with the point-to-point query, except that it
        // measures a goal in walkable straight-line reach exactly
        let f = nav.geodesic_field(&[b]).unwrap();
        let fa = f.distance(nav, &a).unwrap();
        if (b - a).norm() > 0.5 {
            prop_assert!((fa - dab).abs() < 1e-6, "{} vs {}", fa, dab);
        } else {
            prop_assert!(fa <= dab + 1e-6 && fa + 1e-9 >= (b - a).norm(), "{} vs {}", fa, dab);
        }
        // the path is a polyline from a to b no shorter than the distance's straight-line bound
        let path = nav.path(&a, &b).unwrap().unwrap();
        prop_assert_eq!(path[0], a);
        prop_assert_eq!(*path.last().unwrap(), b);
        prop_assert!(path.iter().all(|q| nav.is_navigable(q)));
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    /// Near a goal the field is the exact straight-line distance (the
    /// success radius of 0.1 m is not distorted by the 5 cm spans); farther
    /// away it is the span field.
    #[test]
    fn field_is_exact_near_goals(gx in 0.5f64..3.5, gy in 0.5f64..2.5, r in 0.0f64..0.29, t in 0.0f64..std::f64::consts::TAU) {
        let scene = box_world(&[]);
        let nav = NavMesh::build(&scene, &raw_config()).unwrap();
        let g = Point3::new(gx, gy, 0.0);
        let p = Point3::new(gx + r * t.cos(), gy + r * t.sin(), 0.0);
        prop_assume!(p.x > 0.05 && p.x < 3.95 && p.y > 0.05 && p.y < 2.95);
        let field = nav.geodesic_field(&[g]).unwrap();
        prop_assert!((field.distance(&nav, &p).unwrap() - (p - g).norm()).abs() < 1e-9);
    }
}

/// A wall between a query point and a goal 0.2 m away: the straight line is
/// not walkable, so the field keeps the way around.
#[test]
fn field_near_goal_respects_walls() {
    let scene = box_world(&[(1.95, 0.0, 0.1, 2.5, 1.5)]);
    let nav = NavMesh::build(&scene, &raw_config()).unwrap();
    let g = Point3::new(2.15, 1.0, 0.0);
    let p = Point3::new(1.85, 1.0, 0.0);
    let field = nav.geodesic_field(&[g]).unwrap();
    let d = field.distance(&nav, &p).unwrap();
    assert!(d > 2.0, "around the wall's end, got {d}");
}

#[test]
fn erosion_keeps_agent_radius_from_walls() {
    // a single 1 m wide corridor: after erosion by 0.18 m about 0.6 m remain
    let scene = box_world(&[(0.0, 0.0, 4.0, 1.0, 2.0), (0.0, 2.0, 4.0, 1.0, 2.0)]);
    let nav = NavMesh::build(&scene, &all_islands()).unwrap();
    for y in [1.05, 1.15, 1.85, 1.95] {
        assert!(
            !nav.is_navigable(&Point3::new(2.0, y, 0.0)),
            "y = {y} too close to a wall"
        );
    }
    for y in [1.25, 1.5, 1.75] {
        assert!(
            nav.is_navigable(&Point3::new(2.0, y, 0.0)),
            "y = {y} should be free"
        );
    }
}

#[test]
fn steps_connect_only_up_to_max_step() {
    // platforms of 0.15 m and 0.3 m next to the floor
    let scene = box_world(&[(1.0, 0.5, 1.0, 2.0, 0.15), (2.5, 0.5, 1.0, 2.0, 0.3)]);
    let nav = NavMesh::build(&scene, &all_islands()).unwrap();
    let floor = Point3::new(0.5, 1.5, 0.0);
    let low = Point3::new(1.5, 1.5, 0.15);
    let high = Point3::new(3.0, 1.5, 0.3);
    assert!(nav.connected(&floor, &low).unwrap());
    assert!(!nav.connected(&floor, &high).unwrap());
    assert!(nav.distance(&floor, &high).unwrap().is_infinite());
}

/// A floor plate with solid boxes (x0, y0, z0, x1, y1, z1) and one-sided ramps
/// (x0, y0, width, run, slope in degrees) rising along +x from the floor.
fn world(boxes: &[[f64; 6]], ramps: &[(f64, f64, f64, f64, f64)]) -> Scene {
    let mut b = floor_plate(6.0);
    for q in boxes {
        let i = b.add_instance(InstanceKind::Object, "box", "box", 0);
        b.aabb_box(
            Point3::new(q[0], q[1], q[2]),
            Point3::new(q[3], q[4], q[5]),
            i,
        );
    }
    for &(x, y, w, run, deg) in ramps {
        let i = b.add_instance(InstanceKind::Stairs, "ramp", "ramp", 0);
        let h = run * deg.to_radians().tan();
        // counter-clockwise seen from above: the normal points up
        b.quad(
            Point3::new(x, y, 0.0),
            Point3::new(x + run, y, h),
            Point3::new(x + run, y + w, h),
            Point3::new(x, y + w, 0.0),
            i,
        );
    }
    common::one_level_scene(b, "world")
}

/// No erosion (agent radius 0); islands of at least `min_region_area`
/// (m^2) kept.
fn unshrunk(min_region_area: f64) -> NavMeshConfig {
    NavMeshConfig {
        agent_radius: 0.0,
        min_region_area,
        ..Default::default()
    }
}

/// Surfaces steeper than 45 deg are not walkable; gentler ones are, at the
/// surface's height.
#[test]
fn slopes_up_to_45_degrees_are_walkable() {
    let scene = world(
        &[],
        &[(0.5, 0.5, 1.0, 1.0, 40.0), (3.5, 0.5, 1.0, 1.0, 50.0)],
    );
    let cfg = unshrunk(0.0);
    let nav = NavMesh::build(&scene, &cfg).unwrap();
    // The column 0.50-0.55 m up the run (cells start at multiples of 0.05 m
    // from the scene's bounds): its surface is the ramp's highest point there.
    let on_ramp = |x: f64, deg: f64| {
        let t = deg.to_radians().tan();
        nav.heights_at(x, 1.0)
            .iter()
            .any(|z| (0.5 * t - 1e-3..=0.55 * t + 1e-3).contains(z))
    };
    assert!(on_ramp(1.025, 40.0), "{:?}", nav.heights_at(1.025, 1.0));
    assert!(!on_ramp(4.025, 50.0), "{:?}", nav.heights_at(4.025, 1.0));
    assert!(nav.heights_at(4.025, 1.0).iter().all(|z| *z < 0.1));
    // A steeper threshold lets the 50 deg ramp through.
    let steep = NavMeshConfig {
        max_slope_deg: 55.0,
        ..cfg
    };
    let nav = NavMesh::build(&scene, &steep).unwrap();
    assert!(
        nav.heights_at(4.025, 1.0).iter().any(|z| *z > 0.4),
        "{:?}",
        nav.heights_at(4.025, 1.0)
    );
}

/// A floor is walkable only where the free height above it is at least the
/// agent height (0.88 m); the top of what covers it is walkable too.
#[test]
fn clearance_needs_the_agent_height() {
    let scene = world(
        &[
            [0.5, 0.5, 0.6, 1.5, 1.5, 0.7],
            [2.5, 0.5, 1.0, 3.5, 1.5, 1.1],
        ],
        &[],
    );
    let cfg = unshrunk(0.0);
    let nav = NavMesh::build(&scene, &cfg).unwrap();
    let low = nav.heights_at(1.025, 1.025);
    let high = nav.heights_at(3.025, 1.025);
    assert!(!low.iter().any(|z| z.abs() < 1e-4), "0.6 m free: {low:?}");
    assert!(low.iter().any(|z| (z - 0.7).abs() < 1e-4), "{low:?}");
    assert!(high.iter().any(|z| z.abs() < 1e-4), "1.0 m free: {high:?}");
    assert!(high.iter().any(|z| (z - 1.1).abs() < 1e-4), "{high:?}");
    let taller = NavMeshConfig {
        agent_height: 1.2,
        ..cfg
    };
    let nav = NavMesh::build(&scene, &taller).unwrap();
    assert!(!nav.heights_at(3.025, 1.025).iter().any(|z| z.abs() < 1e-4));
}

/// Islands smaller than `min_region_area` are dropped, larger ones kept.
#[test]
fn small_islands_are_discarded() {
    // platform tops at 0.5 m (out of step reach): 0.8 x 0.8 = 0.64 m^2 and
    // 1.2 x 1.2 = 1.44 m^2
    let scene = world(
        &[
            [0.5, 0.5, 0.0, 1.3, 1.3, 0.5],
            [3.0, 0.5, 0.0, 4.2, 1.7, 0.5],
        ],
        &[],
    );
    let cfg = unshrunk(1.0);
    let nav = NavMesh::build(&scene, &cfg).unwrap();
    let top = |x: f64, y: f64| nav.heights_at(x, y).iter().any(|z| (z - 0.5).abs() < 1e-4);
    assert!(!top(0.925, 0.925), "small island kept");
    assert!(top(3.625, 1.125), "large island dropped");
    assert!(nav.region_areas().iter().all(|a| *a >= 1.0));
    assert_eq!(nav.region_areas().len(), 2, "floor and the large platform");
    let keep_all = NavMeshConfig {
        min_region_area: 0.0,
        ..cfg
    };
    let nav = NavMesh::build(&scene, &keep_all).unwrap();
    assert_eq!(nav.region_areas().len(), 3);
}

#[test]
fn top_down_png_is_written() {
    let (_, nav) = house();
    let out = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../target/walkable_procedural_11.png");
    nav.save_topdown_png(&out).unwrap();
    assert!(std::fs::metadata(&out).unwrap().len() > 100);
}
