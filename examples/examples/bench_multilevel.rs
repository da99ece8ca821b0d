//! Multi-level frontier map timings on rendered depth (issue 18's two-floor
//! case): a camera at 640x480 tours every room of a two-floor house, first
//! downstairs, then up the stairs and through every room upstairs (navmesh
//! paths in 0.25 m steps looking ahead, a full turn of 12 views in each
//! room). Every frame is integrated by `MultiLevelMap::update` and G_F is
//! refreshed after it, as the agent does; at the end every level is rebuilt
//! from scratch. Prints one JSON line (medians over `REPS` tours): update
//! p50/p99 (ms per frame: scan, surfaces, one level's grid and frontiers),
//! refresh p50/p99 (ms: stair extraction, level graphs, the composed G_F),
//! rebuild (ms).
//!
//! Cases (first argument):
//! - `30x30` (default): a 30 m x 30 m two-floor house with 20 rooms per
//!   floor, the size of `bench_frontier_graph`'s single-floor case;
//! - `hm3d`: the largest of 20 procedural two-floor houses sized after
//!   HM3D validation houses (seeds `SEED..SEED+20`).
//!
//! The two-floor case lives here, not in frontier-graph's
//! `bench_frontier_graph`, because it renders depth with platform-sim
//! (which frontier-graph must not depend on).
//!
//! `cargo run --release -p sornav-examples --example bench_multilevel [30x30|hm3d] [SEED]`

use std::time::Instant;

use nalgebra::Point3;
use sornav_examples::walk::Walker;
use sornav_platform_sim::procedural::{HouseSize, HouseStats, generate_with_stats};
use sornav_platform_sim::{NavMesh, NavMeshConfig, ProceduralConfig, Scene};

/// Tours timed (medians reported) for the `hm3d` case; the `30x30` tour
/// (about 3,000 frames) is timed once. `SORNAV_BENCH_REPS` overrides.
const REPS: usize = 3;

fn percentile(v: &mut [f64], p: f64) -> f64 {
    v.sort_by(f64::total_cmp);
    v[((v.len() - 1) as f64 * p).round() as usize]
}

fn median(mut v: Vec<f64>) -> f64 {
    percentile(&mut v, 0.5)
}

fn area(s: &Scene) -> f64 {
    let b = s.bounds();
    (b.max.x - b.min.x) * (b.max.y - b.min.y)
}

/// A 30 m x 30 m two-floor house: one HM3D-like record with 20 rooms per
/// floor (plus the stairwell), the footprint fixed.
fn house_30x30(seed: u64) -> Result<Scene, String> {
    let mut stats: HouseStats = HouseStats::embedded().map_err(|e| e.to_string())?.clone();
    stats.houses = vec![HouseSize {
        scene: "bench-30x30".into(),
        floors: 2,
        rooms: 41,
        navigable_area: 2.0 * 900.0 / sornav_platform_sim::procedural::FOOTPRINT_PER_NAVIGABLE,
    }];
    generate_with_stats(
        seed,
        &ProceduralConfig {
            floors: Some(2),
            footprint: Some([30.0, 30.0]),
            ..ProceduralConfig::default()
        },
        &stats,
    )
    .map_err(|e| e.to_string())
}

/// The largest two-floor house among 20 seeds.
fn house_hm3d(seed: u64) -> Result<Scene, String> {
    (seed..seed + 20)
        .filter_map(|s| {
            Scene::procedural(
                s,
                &ProceduralConfig {
                    floors: Some(2),
                    ..ProceduralConfig::default()
                },
            )
            .ok()
        })
        .filter(|s| s.levels().len() >= 2)
        .max_by(|a, b| area(a).total_cmp(&area(b)))
        .ok_or_else(|| "no two-floor house".into())
}

/// The tour's stops: every room's centroid that is on the navmesh, level 0
/// first, each level in greedy nearest-neighbour order from the previous
/// stop (the first from the level-0 corner with the smallest x + y).
fn tour(scene: &Scene, nav: &NavMesh) -> Vec<Point3<f64>> {
    let mut stops = Vec::new();
    let mut at: Option<Point3<f64>> = None;
    for level in 0..scene.levels().len() {
        let mut left: Vec<Point3<f64>> = scene
            .rooms()
            .iter()
            .filter(|r| r.level == level && !r.polygon.is_empty())
            .filter_map(|r| {
                let n = r.polygon.len() as f64;
                let (x, y) = r
                    .polygon
                    .iter()
                    .fold((0.0, 0.0), |(x, y), p| (x + p.x / n, y + p.y / n));
                nav.snap(&Point3::new(x, y, r.floor_z), 1.0).ok()
            })
            .collect();
        while !left.is_empty() {
            let from = at.unwrap_or_else(|| Point3::new(f64::MIN / 4.0, f64::MIN / 4.0, 0.0));
            let key = |p: &Point3<f64>| match at {
                Some(_) => (p.xy() - from.xy()).norm(),
                None => p.x + p.y,
            };
            let k = (0..left.len())
                .min_by(|&a, &b| key(&left[a]).total_cmp(&key(&left[b])))
                .unwrap_or(0);
            let p = left.swap_remove(k);
            stops.push(p);
            at = Some(p);
        }
    }
    stops
}

/// Times the rebuild of a map state written by `SORNAV_BENCH_DUMP` (median
/// of 7), with each level's refresh statistics: a quick loop for work on the
/// rebuild without rendering a tour.
fn rebuild_only(path: &std::ffi::OsStr) -> Result<(), String> {
    let f = std::fs::File::open(path).map_err(|e| e.to_string())?;
    let (map, at): (sornav::frontier_graph::MultiLevelMap, Point3<f64>) =
        serde_json::from_reader(std::io::BufReader::new(f)).map_err(|e| e.to_string())?;
    let mut times = Vec::new();
    for _ in 0..7 {
        let mut m = map.clone();
        let t = Instant::now();
        m.rebuild();
        m.frontier_graph(&at).map_err(|e| e.to_string())?;
        times.push(t.elapsed().as_secs_f64() * 1e3);
        for l in m.levels() {
            if let Some(lm) = m.level_map(l.id) {
                eprintln!("level {:?}: {:?}", l.id, lm.last_refresh());
            }
        }
    }
    println!(
        "{{\"bench\":\"multilevel-rebuild\",\"rebuild_ms\":{:.1},\"frontiers\":{}}}",
        median(times),
        map.graph().len()
    );
    Ok(())
}

fn main() -> Result<(), String> {
    let mut args = std::env::args().skip(1);
    let case = args.next().unwrap_or_else(|| "30x30".into());
    let seed: u64 = args.next().and_then(|s| s.parse().ok()).unwrap_or(0);
    if let Some(path) = std::env::var_os("SORNAV_BENCH_LOAD") {
        return rebuild_only(&path);
    }
    let scene = match case.as_str() {
        "30x30" => house_30x30(seed)?,
        "hm3d" => house_hm3d(seed)?,
        other => return Err(format!("unknown case {other:?} (30x30 or hm3d)")),
    };
    let nav = NavMesh::build(&scene, &NavMeshConfig::default()).map_err(|e| e.to_string())?;
    let stops = tour(&scene, &nav);
    // the legs between stops; unreachable stops are skipped
    let mut legs: Vec<Vec<Point3<f64>>> = Vec::new();
    let mut at = *stops.first().ok_or("no rooms on the navmesh")?;
    for s in &stops[1..] {
        if let Ok(Some(p)) = nav.path(&at, s) {
            legs.push(p);
            at = *s;
        }
    }
    let (mut upd50, mut upd99, mut ref50, mut ref99, mut rebuild) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let (mut frames, mut levels, mut stairs, mut frontiers) = (0, 0, 0, 0);
    let reps: usize = std::env::var("SORNAV_BENCH_REPS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(if case == "30x30" { 1 } else { REPS })
        .max(1);
    let progress = std::env::var_os("SORNAV_BENCH_PROGRESS").is_some();
    for _ in 0..reps {
        let mut w = Walker::new(
            &scene,
            640,
            480,
            sornav::frontier_graph::FrontierMapConfig::default(),
        )?;
        let e = |e: sornav::frontier_graph::FrontierError| e.to_string();
        w.turn_around(&stops[0]).map_err(e)?;
        for leg in &legs {
            w.walk(leg, 0.25).map_err(e)?;
            if let Some(end) = leg.last() {
                w.turn_around(end).map_err(e)?;
            }
            if progress {
                let st = |l: u16| {
                    w.map
                        .level_map(sornav::frontier_graph::LevelId(l))
                        .map(|m| {
                            let s = m.last_refresh();
                            (s.rows_recomputed, s.pairs_recomputed, s.gain_search)
                        })
                };
                eprintln!("  last refresh per level: {:?} {:?}", st(0), st(1));
                let sum =
                    |v: &[std::time::Duration]| v.iter().map(|d| d.as_secs_f64()).sum::<f64>();
                eprintln!(
                    "frames {:5} update {:7.1} s refresh {:7.1} s levels {} stairs {} frontiers {}",
                    w.frames,
                    sum(&w.update_times),
                    sum(&w.refresh_times),
                    w.map.levels().count(),
                    w.map.stairs().len(),
                    w.map.graph().len()
                );
            }
        }
        let ms = |d: &std::time::Duration| d.as_secs_f64() * 1e3;
        let mut upd: Vec<f64> = w.update_times.iter().map(ms).collect();
        let mut refresh: Vec<f64> = w.refresh_times.iter().map(ms).collect();
        upd50.push(percentile(&mut upd, 0.5));
        upd99.push(percentile(&mut upd, 0.99));
        ref50.push(percentile(&mut refresh, 0.5));
        ref99.push(percentile(&mut refresh, 0.99));
        if let Some(path) = std::env::var_os("SORNAV_BENCH_DUMP") {
            let f = std::fs::File::create(path).map_err(|e| e.to_string())?;
            serde_json::to_writer(std::io::BufWriter::new(f), &(&w.map, &at))
                .map_err(|e| e.to_string())?;
        }
        let t = Instant::now();
        w.map.rebuild();
        w.map.frontier_graph(&at).map_err(e)?;
        rebuild.push(t.elapsed().as_secs_f64() * 1e3);
        frames = w.frames;
        levels = w.map.levels().count();
        stairs = w.map.stairs().len();
        frontiers = w.map.graph().len();
    }
    let bounds = scene.bounds();
    println!(
        "{{\"bench\":\"multilevel\",\"case\":\"{case}\",\"house_m\":[{:.1},{:.1}],\"rooms\":{},\"stops\":{},\"frames\":{frames},\"levels\":{levels},\"stairs\":{stairs},\"frontiers\":{frontiers},\"update_ms_p50\":{:.2},\"update_ms_p99\":{:.2},\"refresh_ms_p50\":{:.2},\"refresh_ms_p99\":{:.2},\"rebuild_ms\":{:.1},\"reps\":{reps}}}",
        bounds.max.x - bounds.min.x,
        bounds.max.y - bounds.min.y,
        scene.rooms().len(),
        legs.len() + 1,
        median(upd50),
        median(upd99),
        median(ref50),
        median(ref99),
        median(rebuild)
    );
    Ok(())
}
