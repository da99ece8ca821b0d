//! Helpers shared by the integration tests: seeded procedural houses, a
//! simulator with a small camera, and one generated episode per category.
#![allow(dead_code)]

use sornav_platform_sim::episodes::{GeneratorConfig, generate_episodes};
use sornav_platform_sim::procedural::ProceduralConfig;
use sornav_platform_sim::{CameraConfig, Episode, Scene, SimConfig, Simulator};

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
