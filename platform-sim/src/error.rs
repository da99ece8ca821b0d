//! Typed errors of scene loading and navigability queries.

use std::path::PathBuf;

/// Everything that can go wrong while loading or building a scene.
///
/// Importer errors name the offending element (XML element and attribute,
/// OBJ file and line, glTF node) so that a user can fix the input.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// Reading a file failed.
    #[error("cannot read {path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// The XML document is malformed (truncated, garbled).
    #[error("malformed XML{}: {message}", element.as_deref().map(|e| format!(" in <{e}>")).unwrap_or_default())]
    Xml {
        /// The element being read when the error occurred, if known.
        element: Option<String>,
        /// What the parser reported.
        message: String,
    },
    /// A required attribute is missing or does not parse.
    #[error("<{element}> attribute `{attribute}`: {message}")]
    Attribute {
        /// The element (with its id when it has one).
        element: String,
        /// The attribute name.
        attribute: String,
        /// What is wrong with it.
        message: String,
    },
    /// A coordinate or size is NaN or infinite.
    #[error("{element}: non-finite value in `{attribute}`")]
    NonFinite {
        /// The element (with its id when it has one).
        element: String,
        /// The attribute or field.
        attribute: String,
    },
    /// The ZIP archive (`.sh3d`) cannot be read.
    #[error("invalid .sh3d archive: {0}")]
    Zip(String),
    /// A model referenced by a piece of furniture cannot be found.
    #[error("<{element}>: model `{model}` not found")]
    MissingModel {
        /// The furniture element (name and id).
        element: String,
        /// The model path as written in the home.
        model: String,
    },
    /// An OBJ model is malformed.
    #[error("OBJ `{file}` line {line}: {message}")]
    Obj {
        /// The model file or archive entry.
        file: String,
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// A glTF/GLB file is malformed.
    #[error("glTF{}: {message}", node.as_deref().map(|n| format!(" node `{n}`")).unwrap_or_default())]
    Gltf {
        /// The node, if the error concerns one.
        node: Option<String>,
        /// What is wrong.
        message: String,
    },
    /// The home or scene has no geometry to build a scene from.
    #[error("empty scene: {0}")]
    Empty(String),
    /// A scene description is inconsistent (index out of range, unknown id).
    #[error("invalid scene description: {0}")]
    Invalid(String),
    /// A configuration value is out of its valid range.
    #[error("invalid configuration `{field}`: {message}")]
    Config {
        /// The configuration field.
        field: &'static str,
        /// What is wrong.
        message: String,
    },
}

/// Errors of navigability and geodesic queries.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum NavError {
    /// A query point is NaN or infinite.
    #[error("non-finite query point")]
    NonFinite,
    /// No walkable span lies near the query point.
    #[error("point ({x:.3}, {y:.3}, {z:.3}) is not on or near the walkable surface")]
    NotNavigable {
        /// x of the query.
        x: f64,
        /// y of the query.
        y: f64,
        /// z of the query.
        z: f64,
    },
    /// A geodesic field needs at least one goal on the walkable surface.
    #[error("no goal point lies on the walkable surface")]
    NoGoals,
}
