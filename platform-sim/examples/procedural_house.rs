//! Generates a procedural house, builds its walkable height field and saves a
//! top-down PNG of the walkable area, and lists the rooms (level, type,
//! bounding box, floor height).
//!
//! Run: `cargo run -p sornav-platform-sim --release --example procedural_house [seed] [out.png] [--objects]`
//! (`--objects`: also list every object, door and stair with its level,
//! category and bounds).

use std::path::PathBuf;
use std::time::Instant;

use sornav_platform_sim::{InstanceKind, NavMesh, NavMeshConfig, ProceduralConfig, Scene};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let objects = std::env::args().any(|a| a == "--objects");
    let mut args = std::env::args().skip(1).filter(|a| a != "--objects");
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
    for room in scene.rooms() {
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for p in &room.polygon {
            lo = [lo[0].min(p.x), lo[1].min(p.y)];
            hi = [hi[0].max(p.x), hi[1].max(p.y)];
        }
        println!(
            "  level {} {:?} '{}': x {:.2}..{:.2}, y {:.2}..{:.2}, floor z {:.2}",
            room.level, room.room_type, room.name, lo[0], hi[0], lo[1], hi[1], room.floor_z
        );
    }
    if objects {
        let listed = |o: &&sornav_platform_sim::ObjectInstance| {
            matches!(
                o.kind,
                InstanceKind::Object | InstanceKind::Door | InstanceKind::Stairs
            )
        };
        for o in scene.instances().iter().filter(listed) {
            let (lo, hi) = (o.bounds.min, o.bounds.max);
            println!(
                "  level {} {} '{}': x {:.2}..{:.2}, y {:.2}..{:.2}, z {:.2}..{:.2}",
                o.level, o.category, o.name, lo.x, hi.x, lo.y, hi.y, lo.z, hi.z
            );
        }
    }
    Ok(())
}
