//! Generates a procedural house, builds its walkable height field and saves a
//! top-down PNG of the walkable area.
//!
//! Run: `cargo run -p sornav-platform-sim --release --example procedural_house [seed] [out.png]`.

use std::path::PathBuf;
use std::time::Instant;

use sornav_platform_sim::{NavMesh, NavMeshConfig, ProceduralConfig, Scene};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let seed: u64 = args.next().map(|s| s.parse()).transpose()?.unwrap_or(0);
    let out = PathBuf::from(
        args.next()
            .unwrap_or_else(|| format!("target/procedural_{seed}.png")),
    );
    let t0 = Instant::now();
    let scene = Scene::procedural(seed, &ProceduralConfig::default())?;
    let t1 = Instant::now();
    let nav = NavMesh::build(&scene, &NavMeshConfig::default())?;
    let t2 = Instant::now();
    nav.save_topdown_png(&out)?;
    println!(
        "{}: {} levels, {} rooms, {} objects, {} triangles; walkable {:.1} m^2 in {} islands; generate {:.1} ms, height field {:.1} ms; wrote {}",
        scene.name(),
        scene.levels().len(),
        scene.rooms().len(),
        scene.objects().count(),
        scene.triangles().len(),
        nav.walkable_area(),
        nav.region_areas().len(),
        (t1 - t0).as_secs_f64() * 1e3,
        (t2 - t1).as_secs_f64() * 1e3,
        out.display()
    );
    Ok(())
}
