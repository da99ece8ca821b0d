//! Helpers shared by the integration tests: seeded procedural houses, a
//! simulator with a small camera, one generated episode per category, and an
//! independent visibility check.
#![allow(dead_code)]

use nalgebra::{Point3, Vector3};
use sornav_platform_sim::episodes::{GeneratorConfig, generate_episodes};
use sornav_platform_sim::geometry::MeshBuilder;
use sornav_platform_sim::procedural::ProceduralConfig;
use sornav_platform_sim::{
    CameraConfig, Episode, Level, ObjectInstance, Scene, SimConfig, Simulator,
};

/// The procedural house of `seed` with `floors` floors (other options
/// default).
pub fn house(seed: u64, floors: u32) -> Scene {
    Scene::procedural(
        seed,
        &ProceduralConfig {
            floors: Some(floors),
            ..ProceduralConfig::default()
        },
    )
    .unwrap()
}

/// The scene `name` of a mesh on one level "0" at elevation 0 (2.5 m high,
/// 0.1 m floor slab).
pub fn one_level_scene(b: MeshBuilder, name: &str) -> Scene {
    let level = Level {
        name: "0".into(),
        elevation: 0.0,
        height: 2.5,
        floor_thickness: 0.1,
    };
    Scene::from_description(b.finish(name, vec![level], vec![])).unwrap()
}

/// A simulator whose camera renders `width` x `height` pixels (other options
/// default).
pub fn simulator(scene: Scene, width: u32, height: u32) -> Simulator {
    let config = SimConfig {
        camera: CameraConfig {
            width,
            height,
            ..CameraConfig::default()
        },
        ..SimConfig::default()
    };
    Simulator::new(scene, config).unwrap()
}

/// One generated episode per object category (other generator options
/// default).
pub fn one_episode_per_category(sim: &Simulator) -> Vec<Episode> {
    generate_episodes(
        sim,
        &GeneratorConfig {
            episodes_per_category: 1,
            ..GeneratorConfig::default()
        },
    )
    .unwrap()
}

/// Whether some ray from `eye` to one of the generator's 27 sample points of
/// the object's bounds first hits the object (parry's ray cast on the scene,
/// independent of the generator's BVH).
pub fn sees(scene: &Scene, eye: &Point3<f64>, object: &ObjectInstance) -> bool {
    let b = object.bounds;
    const F: [f64; 3] = [1.0 / 6.0, 0.5, 5.0 / 6.0];
    F.iter().any(|&i| {
        F.iter().any(|&j| {
            F.iter().any(|&k| {
                let t = b.min
                    + Vector3::new(
                        (b.max.x - b.min.x) * i,
                        (b.max.y - b.min.y) * j,
                        (b.max.z - b.min.z) * k,
                    );
                let d = t - eye;
                scene
                    .cast_ray(eye, &d, d.norm() + 1e-3)
                    .is_some_and(|h| h.instance == object.id)
            })
        })
    })
}
