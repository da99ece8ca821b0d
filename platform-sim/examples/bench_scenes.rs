//! Scene benchmark: loads the largest shared Sweet Home 3D home (models
//! included), builds its walkable height field and a geodesic field, and
//! generates + builds procedural houses (seeds 0-19: default houses, floors
//! drawn from HM3D's shares, then 4-floor houses). Prints one JSON line of
//! medians (ms), the floor counts of the default houses, and the slowest
//! house of each set of 20 (with its floors for the default set).
//!
//! Run from the workspace root:
//! `cargo run -p sornav-platform-sim --release --example bench_scenes [sh3d-homes dir]`.

use std::path::PathBuf;
use std::time::Instant;

use sornav_platform_sim::{NavMesh, NavMeshConfig, ProceduralConfig, Scene};

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = PathBuf::from(
        std::env::args()
            .nth(1)
            .unwrap_or_else(|| "../shared/data/sh3d-homes".into()),
    );
    let home = dir.join("homes/2BedroomHouseWithBasement.xml");
    let models = dir.join("models");
    let cfg = NavMeshConfig::default();
    let (mut load, mut build, mut field) = (Vec::new(), Vec::new(), Vec::new());
    let mut info = (0, 0.0);
    for _ in 0..5 {
        let t0 = Instant::now();
        let scene = Scene::from_home_xml(&home, &models)?;
        let t1 = Instant::now();
        let nav = NavMesh::build(&scene, &cfg)?;
        let t2 = Instant::now();
        let main = nav.largest_region().ok_or("no walkable area")?;
        let goal = nav.span_center(
            nav.spans()
                .iter()
                .position(|s| s.region == main)
                .unwrap_or(0) as u32,
        );
        let _f = nav.geodesic_field(&[goal])?;
        let t3 = Instant::now();
        load.push((t1 - t0).as_secs_f64() * 1e3);
        build.push((t2 - t1).as_secs_f64() * 1e3);
        field.push((t3 - t2).as_secs_f64() * 1e3);
        info = (scene.triangles().len(), nav.walkable_area());
    }
    // default houses (floors drawn from HM3D's shares), then 4-floor houses
    let mut proc_ms = Vec::new();
    let mut floors = [0usize; 4];
    let mut slowest = (0.0, 0usize);
    for seed in 0..20 {
        let t0 = Instant::now();
        let scene = Scene::procedural(seed, &ProceduralConfig::default())?;
        let _nav = NavMesh::build(&scene, &cfg)?;
        let ms = t0.elapsed().as_secs_f64() * 1e3;
        let n = scene.levels().len().clamp(1, 4);
        floors[n - 1] += 1;
        if ms > slowest.0 {
            slowest = (ms, n);
        }
        proc_ms.push(ms);
    }
    let four = ProceduralConfig {
        floors: Some(4),
        ..ProceduralConfig::default()
    };
    let mut four_ms = Vec::new();
    for seed in 0..20 {
        let t0 = Instant::now();
        let scene = Scene::procedural(seed, &four)?;
        let _nav = NavMesh::build(&scene, &cfg)?;
        four_ms.push(t0.elapsed().as_secs_f64() * 1e3);
    }
    let four_max = four_ms.iter().copied().fold(0.0, f64::max);
    println!(
        "{{\"home\":\"2BedroomHouseWithBasement\",\"triangles\":{},\"walkable_m2\":{:.1},\"load_ms\":{:.1},\"heightfield_ms\":{:.1},\"geodesic_field_ms\":{:.1},\"procedural_floors_1_to_4\":{floors:?},\"procedural_generate_build_ms\":{:.1},\"procedural_generate_build_max_ms\":{:.1},\"procedural_slowest_floors\":{},\"procedural_4_floors_ms\":{:.1},\"procedural_4_floors_max_ms\":{four_max:.1}}}",
        info.0,
        info.1,
        median(load),
        median(build),
        median(field),
        median(proc_ms),
        slowest.0,
        slowest.1,
        median(four_ms),
    );
    Ok(())
}
