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

/// parry3d's triangle mesh of a scene: the independent ray caster the tests
/// compare the simulator's own BVH and camera against. parry3d is only a
/// dev-dependency; the library ray-casts with its own [`sornav_platform_sim::Bvh`].
pub struct ParryMesh {
    mesh: parry3d::shape::TriMesh,
    instances: Vec<u32>,
}

/// A hit of [`ParryMesh::cast_ray`].
#[derive(Debug, Clone, Copy)]
pub struct ParryHit {
    /// Distance along the normalised ray direction, metres.
    pub distance: f64,
    /// Instance of the triangle hit.
    pub instance: u32,
}

impl ParryMesh {
    /// Builds parry's mesh (and its BVH) over the scene's triangles.
    pub fn new(scene: &Scene) -> ParryMesh {
        let vertices = scene
            .vertices()
            .iter()
            .map(|v| glam::Vec3::from_array(*v))
            .collect();
        let mesh = parry3d::shape::TriMesh::new(vertices, scene.triangles().to_vec())
            .expect("a validated scene is a valid parry mesh");
        ParryMesh {
            mesh,
            instances: scene.triangle_instances().to_vec(),
        }
    }

    /// First hit (either face) of the ray from `origin` along `dir` (any
    /// non-zero length) within `max_distance` metres.
    pub fn cast_ray(
        &self,
        origin: &Point3<f64>,
        dir: &Vector3<f64>,
        max_distance: f64,
    ) -> Option<ParryHit> {
        let d = dir.try_normalize(0.0)?;
        let ray = parry3d::query::Ray::new(
            glam::Vec3::new(origin.x as f32, origin.y as f32, origin.z as f32),
            glam::Vec3::new(d.x as f32, d.y as f32, d.z as f32),
        );
        let (triangle, hit) = parry3d::shape::CompositeShapeRef(&self.mesh)
            .cast_local_ray_and_get_normal(&ray, max_distance as f32, false)?;
        Some(ParryHit {
            distance: f64::from(hit.time_of_impact),
            instance: self.instances[triangle as usize],
        })
    }
}

/// Whether some ray from `eye` to one of the generator's 27 sample points of
/// the object's bounds first hits the object (parry's ray cast on the scene's
/// mesh, independent of the generator's BVH).
pub fn sees(mesh: &ParryMesh, eye: &Point3<f64>, object: &ObjectInstance) -> bool {
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
                mesh.cast_ray(eye, &d, d.norm() + 1e-3)
                    .is_some_and(|h| h.instance == object.id)
            })
        })
    })
}
