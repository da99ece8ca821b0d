//! glTF 2.0 / GLB importer for users' own scenes.
//!
//! Node names carry the labels: `category` or `category_instance`
//! (`chair_3`, `tv_monitor_1`, `wall`). Every distinct labelled node becomes
//! one instance; unnamed nodes inherit the label of their closest named
//! ancestor (or `object`). Labels are mapped to the ObjectNav vocabulary with
//! [`crate::category::objectnav_category`] when possible; `wall`, `floor`,
//! `ceiling`, `door`, `window` and `stairs` become structure instances.
//!
//! glTF is y-up; scene coordinates are z-up: `(x, y, z)_scene = (x, -z, y)_gltf`.
//! Only triangle primitives are read; images are never decoded. Buffers come
//! from the GLB binary chunk or from files next to the `.gltf` (data URIs are
//! rejected with a typed error).

use std::path::Path;

use nalgebra::{Matrix4, Point3};

use crate::SceneError;
use crate::category::{normalise, objectnav_category, own_label};
use crate::geometry::MeshBuilder;
use crate::scene::{InstanceKind, Level, Scene};

fn err(node: Option<&str>, message: impl Into<String>) -> SceneError {
    SceneError::Gltf {
        node: node.map(str::to_string),
        message: message.into(),
    }
}

/// Splits `chair_3` into ("chair", Some(3)); `tv_monitor` stays whole.
pub fn parse_label(name: &str) -> (String, Option<u32>) {
    if let Some((head, tail)) = name.rsplit_once('_')
        && let Ok(n) = tail.parse::<u32>()
    {
        return (head.to_string(), Some(n));
    }
    (name.to_string(), None)
}

fn kind_and_category(label: &str) -> (InstanceKind, String) {
    let n = normalise(label).replace(' ', "_");
    let kind = match n.as_str() {
        "wall" => InstanceKind::Wall,
        "floor" => InstanceKind::Floor,
        "ceiling" => InstanceKind::Ceiling,
        "door" => InstanceKind::Door,
        "window" => InstanceKind::Window,
        "stairs" | "staircase" | "stair" => InstanceKind::Stairs,
        _ => InstanceKind::Object,
    };
    if kind != InstanceKind::Object {
        return (kind, n);
    }
    let cat = objectnav_category(label)
        .map(str::to_string)
        .or_else(|| own_label(label))
        .unwrap_or_else(|| "object".into());
    (kind, cat)
}

/// Loads a `.gltf` or `.glb` file.
///
/// # Errors
/// [`SceneError::Io`] when the file or a buffer cannot be read,
/// [`SceneError::Gltf`] (naming the node where relevant) for an external
/// buffer that is not a regular file or declares more than
/// [`MAX_GLTF_BUFFER_BYTES`], and for malformed files (references out of
/// range, accessors of the wrong type or outside their buffers, sparse
/// accessors, a node hierarchy that is not a set of strict
/// trees), non-triangle-list indices, non-finite positions or more than
/// [`MAX_GLTF_TRIANGLES`] triangles, [`SceneError::Empty`] when no triangles
/// are found.
///
/// # Complexity
/// O(V + T) in the vertices and triangles of all mesh instances.
pub fn load_gltf(path: &Path) -> Result<Scene, SceneError> {
    let bytes = std::fs::read(path).map_err(|e| SceneError::Io {
        path: path.to_path_buf(),
        source: e,
    })?;
    let base = path.parent().unwrap_or(Path::new("."));
    let name = path
        .file_stem()
        .map(|s| s.to_string_lossy().to_string())
        .unwrap_or_default();
    gltf_from_slice(&bytes, &name, Some(base))
}

/// Builds a scene from glTF JSON or GLB bytes; external buffers resolve
/// against `base` (none when `None`).
///
/// # Errors
/// As [`load_gltf`].
pub fn gltf_from_slice(bytes: &[u8], name: &str, base: Option<&Path>) -> Result<Scene, SceneError> {
    let g = parse_and_validate(bytes)?;
    let mut buffers: Vec<Vec<u8>> = Vec::new();
    for b in g.buffers() {
        let data = match b.source() {
            gltf::buffer::Source::Bin => g
                .blob
                .clone()
                .ok_or_else(|| err(None, "GLB without binary chunk"))?,
            gltf::buffer::Source::Uri(uri) => {
                if uri.starts_with("data:") {
                    return Err(err(
                        None,
                        "data URIs are not supported; use a GLB or an external .bin",
                    ));
                }
                let base = base.ok_or_else(|| {
                    err(None, format!("external buffer `{uri}` without a base path"))
                })?;
                read_external_buffer(&base.join(uri), b.length())?
            }
        };
        if data.len() < b.length() {
            return Err(err(
                None,
                format!("buffer {} shorter than declared", b.index()),
            ));
        }
        buffers.push(data);
    }
    let mut builder = MeshBuilder::new();
    let mut instances: std::collections::HashMap<String, u32> = std::collections::HashMap::new();
    let scene = g
        .default_scene()
        .or_else(|| g.scenes().next())
        .ok_or_else(|| err(None, "no scene"))?;
    let mut stack: Vec<(gltf::Node<'_>, Matrix4<f64>, Option<String>)> = scene
        .nodes()
        .map(|n| (n, Matrix4::identity(), None))
        .collect();
    // y-up to z-up
    let to_z_up = Matrix4::new(
        1.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0,
    );
    // glTF requires the node hierarchy to be disjoint strict trees: a node
    // reached twice (a cycle, a shared child, a root that is also a child)
    // would append its meshes again on every visit.
    let mut seen = vec![false; g.nodes().len()];
    while let Some((node, parent, inherited)) = stack.pop() {
        if std::mem::replace(&mut seen[node.index()], true) {
            return Err(err(
                node.name(),
                format!(
                    "node {} is reached twice (a cycle or a shared child): glTF node hierarchies must be strict trees",
                    node.index()
                ),
            ));
        }
        let m = node.transform().matrix();
        let local = Matrix4::from_fn(|r, c| f64::from(m[c][r]));
        let world = parent * local;
        let label = node
            .name()
            .filter(|n| !n.trim().is_empty())
            .map(str::to_string)
            .or(inherited);
        if let Some(mesh) = node.mesh() {
            let key = label.clone().unwrap_or_else(|| "object".into());
            let inst = *instances.entry(key.clone()).or_insert_with(|| {
                let (kind, cat) = kind_and_category(&parse_label(&key).0);
                builder.add_instance(kind, &cat, &key, 0)
            });
            let node_name = label.as_deref();
            let full = to_z_up * world;
            let flip = full.fixed_view::<3, 3>(0, 0).determinant() < 0.0;
            for prim in mesh.primitives() {
                if prim.mode() != gltf::mesh::Mode::Triangles {
                    continue;
                }
                let positions = prim
                    .get(&gltf::Semantic::Positions)
                    .ok_or_else(|| err(node_name, "primitive without positions"))?;
                check_accessor(&positions, "POSITION", &buffers, node_name)?;
                if let Some(indices) = prim.indices() {
                    check_accessor(&indices, "indices", &buffers, node_name)?;
                }
                let reader = prim.reader(|b| buffers.get(b.index()).map(Vec::as_slice));
                let pos: Vec<Point3<f64>> = reader
                    .read_positions()
                    .ok_or_else(|| err(node_name, "primitive without positions"))?
                    .map(|p| {
                        let v = full
                            * nalgebra::Vector4::new(
                                f64::from(p[0]),
                                f64::from(p[1]),
                                f64::from(p[2]),
                                1.0,
                            );
                        Point3::new(v.x, v.y, v.z)
                    })
                    .collect();
                // finite after the node transforms, and within f32 (the
                // scene's vertex type)
                if pos.iter().any(|p| {
                    !p.coords
                        .iter()
                        .all(|&c| c.is_finite() && (c as f32).is_finite())
                }) {
                    return Err(err(node_name, "non-finite vertex position"));
                }
                let idx: Vec<u32> = match reader.read_indices() {
                    Some(i) => i.into_u32().collect(),
                    None => (0..pos.len() as u32).collect(),
                };
                if !idx.len().is_multiple_of(3) {
                    return Err(err(node_name, "index count is not a multiple of 3"));
                }
                if builder.triangle_count() + idx.len() / 3 > MAX_GLTF_TRIANGLES {
                    return Err(err(
                        node_name,
                        format!("more than {MAX_GLTF_TRIANGLES} triangles (MAX_GLTF_TRIANGLES)"),
                    ));
                }
                for t in idx.chunks_exact(3) {
                    let get = |i: u32| {
                        pos.get(i as usize)
                            .copied()
                            .ok_or_else(|| err(node_name, format!("index {i} out of range")))
                    };
                    let (a, b, c) = (get(t[0])?, get(t[1])?, get(t[2])?);
                    if flip {
                        builder.triangle(a, c, b, inst);
                    } else {
                        builder.triangle(a, b, c, inst);
                    }
                }
            }
        }
        for child in node.children() {
            stack.push((child, world, label.clone()));
        }
    }
    if builder.triangle_count() == 0 {
        return Err(SceneError::Empty(format!("glTF `{name}` has no triangles")));
    }
    let zmin = builder
        .instances()
        .iter()
        .filter(|i| i.kind == InstanceKind::Floor)
        .map(|i| i.bounds.max.z)
        .fold(f64::INFINITY, f64::min);
    let all_min = builder
        .instances()
        .iter()
        .map(|i| i.bounds.min.z)
        .fold(f64::INFINITY, f64::min);
    let elevation = if zmin.is_finite() { zmin } else { all_min };
    let level = Level {
        name: "Level 0".into(),
        elevation,
        height: 2.5,
        floor_thickness: 0.0,
    };
    Scene::from_description(builder.finish(name, vec![level], Vec::new()))
}

/// Parses glTF JSON or GLB bytes and runs the `gltf` crate's validation,
/// after checking the references that validation itself reads unchecked
/// (a primitive's `POSITION` accessor: an index out of range panicked).
fn parse_and_validate(bytes: &[u8]) -> Result<gltf::Gltf, SceneError> {
    // gltf 1.4 subtracts the 12-byte GLB header from the declared total
    // length unchecked (an overflow panic in debug builds): check it first.
    if let Some(head) = bytes.get(..12).filter(|h| h.starts_with(b"glTF")) {
        let declared = u32::from_le_bytes([head[8], head[9], head[10], head[11]]);
        if declared < 12 {
            return Err(err(
                None,
                format!("GLB header declares a total length of {declared} bytes (under 12)"),
            ));
        }
    }
    let g =
        gltf::Gltf::from_slice_without_validation(bytes).map_err(|e| err(None, e.to_string()))?;
    let json = g.document.as_json();
    for (m, mesh) in json.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            let out_of_range = prim
                .attributes
                .values()
                .chain(prim.indices.iter())
                .find(|a| a.value() >= json.accessors.len());
            if let Some(a) = out_of_range {
                return Err(err(
                    None,
                    format!(
                        "mesh {m} primitive {p} refers to accessor {} of {}",
                        a.value(),
                        json.accessors.len()
                    ),
                ));
            }
        }
    }
    let blob = g.blob;
    let document =
        gltf::Document::from_json(g.document.into_json()).map_err(|e| err(None, e.to_string()))?;
    Ok(gltf::Gltf { document, blob })
}

/// Checks what the `gltf` crate's readers assume but never check (they
/// panic or hit `unreachable!` otherwise): the component type and
/// dimensions of a `POSITION` (`f32` VEC3) or `indices` (unsigned SCALAR)
/// accessor, no sparse storage, at least one element, and the accessor's
/// bytes inside its buffer view and the view inside its buffer (computed
/// without overflow).
fn check_accessor(
    a: &gltf::Accessor<'_>,
    what: &str,
    buffers: &[Vec<u8>],
    node: Option<&str>,
) -> Result<(), SceneError> {
    use gltf::accessor::{DataType, Dimensions};
    let fail = |message: String| err(node, format!("{what} accessor {}: {message}", a.index()));
    let (ty, dims) = (a.data_type(), a.dimensions());
    let ok_type = if what == "POSITION" {
        ty == DataType::F32 && dims == Dimensions::Vec3
    } else {
        matches!(ty, DataType::U8 | DataType::U16 | DataType::U32) && dims == Dimensions::Scalar
    };
    if !ok_type {
        let want = if what == "POSITION" {
            "FLOAT VEC3"
        } else {
            "an unsigned integer SCALAR"
        };
        return Err(fail(format!("is {ty:?} {dims:?}, must be {want}")));
    }
    if a.sparse().is_some() {
        return Err(fail("sparse accessors are not supported".into()));
    }
    let view = a.view().ok_or_else(|| fail("has no buffer view".into()))?;
    if a.count() == 0 {
        return Err(fail("has no elements (count 0)".into()));
    }
    let size = a.size();
    let stride = view.stride().unwrap_or(size);
    if stride < size {
        return Err(fail(format!(
            "byte stride {stride} below the element size {size}"
        )));
    }
    let buffer_len = buffers.get(view.buffer().index()).map_or(0, Vec::len);
    let view_end = view.offset().checked_add(view.length());
    if view_end.is_none_or(|e| e > buffer_len) {
        return Err(fail(format!(
            "buffer view {} lies outside its buffer of {buffer_len} bytes",
            view.index()
        )));
    }
    let end = (a.count() - 1)
        .checked_mul(stride)
        .and_then(|x| x.checked_add(size))
        .and_then(|x| x.checked_add(a.offset()));
    if end.is_none_or(|e| e > view.length()) {
        return Err(fail(format!(
            "{} elements from byte {} overrun buffer view {} ({} bytes)",
            a.count(),
            a.offset(),
            view.index(),
            view.length()
        )));
    }
    Ok(())
}

/// Largest external buffer (`byteLength`) a glTF file may declare.
pub const MAX_GLTF_BUFFER_BYTES: usize = 1 << 30;

/// Reads the `declared` bytes of an external buffer, only from a regular
/// file and never more than declared (a URI naming `/dev/zero` was read
/// without end; a FIFO would block).
fn read_external_buffer(p: &Path, declared: usize) -> Result<Vec<u8>, SceneError> {
    use std::io::Read;
    let io = |e: std::io::Error| SceneError::Io {
        path: p.to_path_buf(),
        source: e,
    };
    if declared > MAX_GLTF_BUFFER_BYTES {
        return Err(err(
            None,
            format!(
                "buffer `{}` declares {declared} bytes (MAX_GLTF_BUFFER_BYTES is {MAX_GLTF_BUFFER_BYTES})",
                p.display()
            ),
        ));
    }
    if !std::fs::metadata(p).map_err(io)?.is_file() {
        return Err(err(
            None,
            format!("buffer `{}` is not a regular file", p.display()),
        ));
    }
    let mut data = Vec::new();
    std::fs::File::open(p)
        .and_then(|f| f.take(declared as u64).read_to_end(&mut data))
        .map_err(io)?;
    Ok(data)
}

/// Most triangles a glTF scene may expand to (after node instancing): a
/// small file whose nodes reuse a large mesh would otherwise allocate
/// without bound.
pub const MAX_GLTF_TRIANGLES: usize = 10_000_000;

impl Scene {
    /// Loads a glTF/GLB scene with labelled nodes (see [`crate::gltf`]).
    ///
    /// # Errors
    /// See [`load_gltf`].
    pub fn from_gltf(path: &Path) -> Result<Scene, SceneError> {
        load_gltf(path)
    }
}
