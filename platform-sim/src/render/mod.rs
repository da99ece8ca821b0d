//! Ray-cast rendering: a compact BVH over plain triangle data ([`Bvh`]) and
//! Habitat's pinhole depth + semantic camera on top of it ([`Camera`]).

mod bvh;
mod camera;
mod lanes;
mod packet8;
mod quad;
mod tile;

pub use bvh::{Bvh, BvhHit, BvhTriangle, MAX_LEAF, MAX_PACKET, PreparedRay};
pub use camera::{Camera, CameraConfig, CameraPose, Frame, NO_INSTANCE, palette};
pub use lanes::RenderKernel;

use std::path::PathBuf;

/// Errors of BVH construction, camera configuration and image output.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RenderError {
    /// The mesh has no triangles.
    #[error("cannot build a BVH over an empty mesh")]
    EmptyMesh,
    /// The mesh is inconsistent (index out of range, non-finite vertex, ...).
    #[error("invalid mesh: {0}")]
    Mesh(String),
    /// A configuration value is out of range.
    #[error("invalid camera configuration `{field}`: {message}")]
    Config {
        /// The field.
        field: &'static str,
        /// What is wrong.
        message: String,
    },
    /// Writing an image failed.
    #[error("cannot write {path}: {message}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        message: String,
    },
}
