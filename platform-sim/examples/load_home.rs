//! Loads a Sweet Home 3D home (`Home.xml` + model directory, or `.sh3d`),
//! builds its height field, prints a summary and saves a top-down PNG of the
//! walkable area.
//!
//! Run: `cargo run -p sornav-platform-sim --release --example load_home -- <home.xml|home.sh3d> [models dir] [out.png]`.

use std::path::PathBuf;

use sornav_platform_sim::{NavMesh, NavMeshConfig, Scene};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let path = PathBuf::from(
        args.next()
            .ok_or("usage: load_home <home.xml|home.sh3d> [models dir] [out.png]")?,
    );
    let scene = if path.extension().is_some_and(|e| e == "sh3d") {
        Scene::from_sh3d(&path)?
    } else {
        let models = PathBuf::from(
            args.next()
                .unwrap_or_else(|| "../shared/data/sh3d-homes/models".into()),
        );
        Scene::from_home_xml(&path, &models)?
    };
    let out = PathBuf::from(
        args.next()
            .unwrap_or_else(|| format!("target/{}.png", scene.name())),
    );
    let nav = NavMesh::build(&scene, &NavMeshConfig::default())?;
    nav.save_topdown_png(&out)?;
    let mut cats: std::collections::BTreeMap<&str, usize> = Default::default();
    for o in scene.objects() {
        *cats.entry(o.category.as_str()).or_default() += 1;
    }
    println!(
        "{}: {} levels, {} rooms, {} objects, {} triangles, walkable {:.1} m^2 ({} islands) -> {}",
        scene.name(),
        scene.levels().len(),
        scene.rooms().len(),
        scene.objects().count(),
        scene.triangles().len(),
        nav.walkable_area(),
        nav.region_areas().len(),
        out.display()
    );
    println!("{cats:?}");
    Ok(())
}
