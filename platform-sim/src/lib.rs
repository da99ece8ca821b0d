//! A CPU ObjectNav simulator: real and procedural houses as labelled
//! triangle meshes, a walkable height field and geodesic distances, a
//! ray-cast depth + semantic camera, Habitat's agent, episodes and metrics.
//!
//! # Should I use this crate?
//!
//! Use it to evaluate object-navigation methods without Habitat: it loads
//! Sweet Home 3D homes ([`sh3d`]), glTF/GLB meshes with labelled nodes
//! ([`gltf`]) or generates seeded procedural houses whose room and object
//! statistics follow HM3D-Semantics ([`procedural`]); every triangle carries an
//! object instance with an ObjectNav category ([`scene`], [`category`]). The
//! Recast-style multi-layer height field ([`navmesh`]) answers "is navigable",
//! snaps points to the floor, and gives geodesic distances and paths across
//! floors ([`geodesic`]).
//!
//! # API themes
//!
//! * **Scenes**: [`Scene`] (labelled mesh), [`SceneDescription`] (its
//!   serde form), [`ObjectInstance`], [`Level`], [`Room`].
//! * **Sources**: [`Scene::procedural`], [`Scene::from_home_xml`],
//!   [`Scene::from_sh3d`], [`Scene::from_gltf`].
//! * **Navigability**: [`NavMesh::build`], [`NavMesh::is_navigable`],
//!   [`NavMesh::snap`], [`NavMesh::geodesic_field`], [`NavMesh::distance`],
//!   [`NavMesh::path`]; floors: [`NavMesh::levels`], [`NavMesh::level_at`],
//!   [`floor_relation`] ([`levels`]).
//! * **Sensing and acting**: [`Camera`] over a packet-traced [`Bvh`] (depth,
//!   semantic, optional RGB), optional sensor [`noise`], Habitat's [`Agent`]
//!   and [`Action`]s; [`WaypointFollower`] ([`follow`]) drives the agent
//!   along any planner's 3-D paths.
//! * **Protocol**: Habitat episode files and a generator ([`episodes`]),
//!   [`Policy`], [`Simulator`], [`run_episode`], [`Summary`] of the
//!   [`metrics`] (success, SPL, soft SPL, failure taxonomy).
//!
//! Coordinates are right-handed, z up, metres, everywhere.
//!
//! # Data attribution
//!
//! The library embeds `data/hm3d_val_stats.json` ([`procedural::HouseStats::embedded`]):
//! floors, rooms, navigable area and per-room-type object counts derived
//! from the HM3D-Semantics v0.2 statistics (K. Yadav et al., "Habitat-Matterport
//! 3D Semantics Dataset", CVPR 2023; matterport/habitat-matterport-3dresearch),
//! validation scenes 00800-00899 only. No scan, mesh or raw statistics file is
//! shipped. HM3D-Semantics is distributed under the *Matterport End User
//! License Agreement for Academic Use of Model Data*; the derived figures are
//! provided under those terms (academic, non-commercial research). The crate's
//! MIT OR Apache-2.0 licence covers its code, not that data.
//!
//! # Example
//!
//! ```
//! use sornav_platform_sim::{NavMesh, NavMeshConfig, ProceduralConfig, Scene};
//!
//! let scene = Scene::procedural(42, &ProceduralConfig { floors: Some(1), ..Default::default() })?;
//! let nav = NavMesh::build(&scene, &NavMeshConfig::default())?;
//! // distance from somewhere walkable to the nearest bed
//! let start = nav.span_center(nav.spans().len() as u32 / 2);
//! let beds: Vec<_> = scene.objects_of("bed").map(|o| o.bounds.center()).collect();
//! assert!(!beds.is_empty());
//! let goals: Vec<_> = beds.iter().filter_map(|b| nav.snap(&nalgebra::Point3::new(b.x, b.y, 0.0), 1.5).ok()).collect();
//! if let Ok(field) = nav.geodesic_field(&goals) {
//!     let d = field.distance(&nav, &start)?;
//!     assert!(d >= 0.0);
//! }
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

#![forbid(unsafe_code)]
#![cfg_attr(docsrs, feature(doc_cfg))]
#![deny(missing_docs)]

/// The README's examples, compiled and run as doctests.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;

pub mod category;
pub mod error;
pub mod geodesic;
pub mod geometry;
pub mod gltf;
pub mod levels;
pub mod navmesh;
pub mod obj;
pub mod procedural;
pub mod scene;
pub mod sh3d;

pub use error::{NavError, SceneError};
pub use geodesic::GeodesicField;
pub use levels::{FloorRelation, NavLevel, floor_relation};
pub use navmesh::{NavMesh, NavMeshConfig, Span, SpanId};
pub use procedural::ProceduralConfig;
pub use scene::{
    Aabb, InstanceId, InstanceKind, Level, ObjectInstance, Room, RoomType, Scene, SceneDescription,
};
pub mod agent;
pub mod episodes;
pub mod follow;
pub mod metrics;
pub mod noise;
pub mod policy;
pub mod render;
pub mod run;

pub use agent::{Action, Agent, AgentConfig, AgentError};
pub use episodes::{Episode, EpisodeError, ObjectGoal, ViewPoint};
pub use follow::{FollowerConfig, MoveOutcome, WaypointFollower};
pub use metrics::{EpisodeResult, Outcome, Summary};
pub use noise::{NoiseConfig, NoiseModel, NoisePreset, UnknownNoisePreset};
pub use policy::{Oracle, Policy, RandomWalk, StopAtOnce};
pub use render::{Bvh, Camera, CameraConfig, CameraPose, Frame, RenderError};
pub use run::{Observation, RunConfig, SimConfig, SimError, Simulator, run_episode};

/// Writes an 8-bit RGB image (`data`: `width * height` pixels, row-major) as
/// a PNG file; encoder failures are wrapped with [`std::io::Error::other`].
pub(crate) fn write_rgb_png(
    path: &std::path::Path,
    width: u32,
    height: u32,
    data: &[u8],
) -> std::io::Result<()> {
    let file = std::fs::File::create(path)?;
    let mut enc = png::Encoder::new(std::io::BufWriter::new(file), width, height);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    let mut w = enc.write_header().map_err(std::io::Error::other)?;
    w.write_image_data(data).map_err(std::io::Error::other)
}
