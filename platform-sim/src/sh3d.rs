//! Sweet Home 3D importer (`Home.xml` and `.sh3d` archives).
//!
//! Units and axes: `Home.xml` is in centimetres and radians with plan x right,
//! plan y down and elevation up. The importer converts every coordinate to
//! metres, right-handed, z up: `(x, y, z) = (x_plan, -y_plan, elevation) / 100`,
//! so a top-down view with +y up looks like the plan.
//!
//! * **Walls** are extruded from their centre line with their `thickness`,
//!   `height` and `heightAtEnd` (sloping tops); curved walls (`arcExtent`) are
//!   split into straight pieces along the arc; joined ends are extended by half
//!   the thickness to close corners.
//! * **Doors and windows** (`doorOrWindow`) cut their opening (footprint x
//!   elevation range) through the walls they overlap. Doors, i.e. openings
//!   starting within 0.3 m of the floor and at least 1.8 m high, are left open
//!   (no geometry, passable); windows keep their model.
//! * **Rooms** (with at least three points; others are skipped) become floor
//!   slabs (`floorVisible`) and ceilings (`ceilingVisible`); staircases
//!   (pieces with a `staircaseCutOutShape`) cut their rectangular footprint
//!   (not the SVG cut-out shape itself) out of the floors and ceilings they
//!   pass through, so levels connect.
//! * **Staircases** keep their instance ([`InstanceKind::Stairs`]) and
//!   footprint, but their walkable geometry is rebuilt so that the agent's
//!   0.2 m step climbs them: Sweet Home 3D's staircase models rise about
//!   22 cm per tread (12 treads per 2.62 m storey in the example homes).
//!   Each tread is rebuilt on a 2.5 cm raster and cut across the direction
//!   of ascent, inferred from the model (each point's position between the
//!   tread below and the tread above, so winders and curved flights are
//!   followed), into sub-steps that rise at most [`MAX_SH3D_RISER`]
//!   (0.19 m) each (see `restep_staircase`). The top tread stays flush with
//!   the floor above; the model's risers, stringers and handrails below
//!   that floor are dropped.
//! * **Furniture** is placed from its OBJ model by Sweet Home 3D's rule: apply
//!   `modelRotation`, centre the model's bounds at the origin, scale to
//!   width x height x depth, mirror (`modelMirrored`), rotate by `angle`,
//!   translate to (x, y, level elevation + elevation). Groups are flattened
//!   (their children keep absolute coordinates). Categories come from
//!   [`crate::category::classify`] (name first, catalog id second).
//! * **Levels** are sorted by elevation (then `elevationIndex`). Content of
//!   hidden levels (`visible='false'`, e.g. roofs) is skipped unless
//!   [`Sh3dOptions::include_hidden_levels`] is set; the levels themselves are
//!   always listed.

use std::collections::HashMap;
use std::io::Read;
use std::path::Path;
use std::sync::Arc;

use nalgebra::{Matrix3, Point2, Point3, Vector2, Vector3};
use quick_xml::events::{BytesStart, Event};
use serde::{Deserialize, Serialize};

use crate::SceneError;
use crate::category::{classify, room_type_from_name};
use crate::geometry::{MeshBuilder, polygon_area, subtract_convex, triangulate};
use crate::obj::{ObjMesh, parse_obj};
use crate::scene::{InstanceKind, Level, Room, Scene};

/// Path prefix of the models bundled with Sweet Home 3D.
pub const RESOURCE_PREFIX: &str = "com/eteks/sweethome3d/io/resources/";

/// Import options.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Sh3dOptions {
    /// Also build the content of hidden levels (roofs, attics hidden in the design).
    pub include_hidden_levels: bool,
}

#[derive(Debug, Clone)]
struct XmlLevel {
    id: String,
    level: Level,
    index: i64,
    visible: bool,
}

#[derive(Debug, Clone)]
struct XmlWall {
    id: String,
    level: Option<String>,
    start: Point2<f64>,
    end: Point2<f64>,
    thickness: f64,
    height: Option<f64>,
    height_at_end: Option<f64>,
    arc_extent: Option<f64>,
    joined_start: bool,
    joined_end: bool,
}

#[derive(Debug, Clone)]
struct XmlRoom {
    name: String,
    level: Option<String>,
    points: Vec<Point2<f64>>,
    floor_visible: bool,
    ceiling_visible: bool,
}

#[derive(Debug, Clone)]
struct XmlPiece {
    element: String,
    level: Option<String>,
    name: String,
    catalog_id: Option<String>,
    model: Option<String>,
    x: f64,
    y: f64,
    elevation: f64,
    angle: f64,
    width: f64,
    depth: f64,
    height: f64,
    mirrored: bool,
    model_rotation: Option<Matrix3<f64>>,
    door_or_window: bool,
    staircase: bool,
    visible: bool,
}

#[derive(Debug, Default)]
struct XmlHome {
    wall_height: f64,
    levels: Vec<XmlLevel>,
    walls: Vec<XmlWall>,
    rooms: Vec<XmlRoom>,
    pieces: Vec<XmlPiece>,
}

fn element_label(e: &BytesStart<'_>) -> String {
    let name = String::from_utf8_lossy(e.name().as_ref()).to_string();
    let mut id = None;
    for a in e.attributes().flatten() {
        if matches!(a.key.as_ref(), b"id" | b"name") {
            id = Some(String::from_utf8_lossy(&a.value).to_string());
            break;
        }
    }
    match id {
        Some(i) => format!("{name} '{i}'"),
        None => name,
    }
}

fn attrs(e: &BytesStart<'_>) -> Result<HashMap<String, String>, SceneError> {
    let mut m = HashMap::new();
    for a in e.attributes() {
        let a = a.map_err(|err| SceneError::Xml {
            element: Some(element_label(e)),
            message: err.to_string(),
        })?;
        let v = a.unescape_value().map_err(|err| SceneError::Xml {
            element: Some(element_label(e)),
            message: err.to_string(),
        })?;
        m.insert(
            String::from_utf8_lossy(a.key.as_ref()).to_string(),
            v.to_string(),
        );
    }
    Ok(m)
}

struct Attrs<'a> {
    label: String,
    m: &'a HashMap<String, String>,
}

impl Attrs<'_> {
    fn opt_f(&self, k: &str) -> Result<Option<f64>, SceneError> {
        match self.m.get(k) {
            None => Ok(None),
            Some(v) => {
                let x: f64 = v.trim().parse().map_err(|_| SceneError::Attribute {
                    element: self.label.clone(),
                    attribute: k.to_string(),
                    message: format!("`{v}` is not a number"),
                })?;
                if !x.is_finite() {
                    return Err(SceneError::NonFinite {
                        element: self.label.clone(),
                        attribute: k.to_string(),
                    });
                }
                Ok(Some(x))
            }
        }
    }
    fn f(&self, k: &str) -> Result<f64, SceneError> {
        self.opt_f(k)?.ok_or_else(|| SceneError::Attribute {
            element: self.label.clone(),
            attribute: k.to_string(),
            message: "missing".into(),
        })
    }
    fn s(&self, k: &str) -> Option<String> {
        self.m.get(k).cloned()
    }
    fn flag(&self, k: &str, default: bool) -> bool {
        self.m.get(k).map_or(default, |v| v == "true")
    }
}

/// Largest accepted `|arcExtent|` of a wall: an arc between two distinct
/// points sweeps less than a full turn. (Unbounded, `1e5` took 108 s and
/// 4 GB and `1e12` aborted allocating 91 TB of arc points.)
pub const MAX_ARC_EXTENT: f64 = std::f64::consts::TAU;

/// A wall's `arcExtent` (radians), checked against [`MAX_ARC_EXTENT`].
fn arc_extent(a: &Attrs<'_>) -> Result<Option<f64>, SceneError> {
    let extent = a.opt_f("arcExtent")?;
    if let Some(x) = extent
        && x.abs() >= MAX_ARC_EXTENT
    {
        return Err(SceneError::Attribute {
            element: a.label.clone(),
            attribute: "arcExtent".into(),
            message: format!("{x} radians: |arcExtent| must be below 2 pi (MAX_ARC_EXTENT)"),
        });
    }
    Ok(extent)
}

fn parse_xml(xml: &str) -> Result<XmlHome, SceneError> {
    let mut reader = quick_xml::Reader::from_str(xml);
    let mut home = XmlHome {
        wall_height: 250.0,
        ..Default::default()
    };
    let mut stack: Vec<String> = Vec::new();
    let mut group_levels: Vec<Option<String>> = Vec::new();
    let mut saw_home = false;
    let mut current_room: Option<XmlRoom> = None;
    loop {
        let ev = reader.read_event().map_err(|e| SceneError::Xml {
            element: stack.last().cloned(),
            message: e.to_string(),
        })?;
        let (e, empty) = match &ev {
            Event::Start(e) => (e.clone(), false),
            Event::Empty(e) => (e.clone(), true),
            Event::End(end) => {
                let name = String::from_utf8_lossy(end.name().as_ref()).to_string();
                if name == "room"
                    && let Some(r) = current_room.take()
                {
                    home.rooms.push(r);
                }
                if name == "furnitureGroup" {
                    group_levels.pop();
                }
                stack.pop();
                continue;
            }
            Event::Eof => break,
            _ => continue,
        };
        let name = String::from_utf8_lossy(e.name().as_ref()).to_string();
        let m = attrs(&e)?;
        let a = Attrs {
            label: element_label(&e),
            m: &m,
        };
        match name.as_str() {
            "home" => {
                saw_home = true;
                home.wall_height = a.opt_f("wallHeight")?.unwrap_or(250.0);
            }
            "level" => home.levels.push(XmlLevel {
                id: a.s("id").unwrap_or_default(),
                level: Level {
                    name: a.s("name").unwrap_or_default(),
                    elevation: a.f("elevation")? / 100.0,
                    height: a.f("height")? / 100.0,
                    floor_thickness: a.f("floorThickness")? / 100.0,
                },
                index: a.opt_f("elevationIndex")?.unwrap_or(0.0) as i64,
                visible: a.flag("visible", true),
            }),
            "wall" => home.walls.push(XmlWall {
                id: a.s("id").unwrap_or_default(),
                level: a.s("level"),
                start: Point2::new(a.f("xStart")?, a.f("yStart")?),
                end: Point2::new(a.f("xEnd")?, a.f("yEnd")?),
                thickness: a.f("thickness")?,
                height: a.opt_f("height")?,
                height_at_end: a.opt_f("heightAtEnd")?,
                arc_extent: arc_extent(&a)?,
                joined_start: m.contains_key("wallAtStart"),
                joined_end: m.contains_key("wallAtEnd"),
            }),
            "room" => {
                let r = XmlRoom {
                    name: a.s("name").unwrap_or_default(),
                    level: a.s("level"),
                    points: Vec::new(),
                    floor_visible: a.flag("floorVisible", true),
                    ceiling_visible: a.flag("ceilingVisible", true),
                };
                if empty {
                    home.rooms.push(r);
                } else {
                    current_room = Some(r);
                }
            }
            "point" => {
                if let Some(r) = current_room.as_mut() {
                    let a = Attrs {
                        label: format!("point of room '{}'", r.name),
                        m: &m,
                    };
                    r.points.push(Point2::new(a.f("x")?, a.f("y")?));
                }
            }
            "furnitureGroup" => {
                let lvl = a
                    .s("level")
                    .or_else(|| group_levels.last().cloned().flatten());
                if !empty {
                    group_levels.push(lvl);
                }
            }
            "pieceOfFurniture" | "doorOrWindow" | "light" => {
                let rot = match a.s("modelRotation") {
                    None => None,
                    Some(v) => {
                        let vals: Vec<f64> = v
                            .split_whitespace()
                            .filter_map(|t| t.parse().ok())
                            .collect();
                        if vals.len() != 9 || vals.iter().any(|x| !x.is_finite()) {
                            return Err(SceneError::Attribute {
                                element: a.label.clone(),
                                attribute: "modelRotation".into(),
                                message: format!("expected 9 numbers, got `{v}`"),
                            });
                        }
                        Some(Matrix3::from_row_slice(&vals))
                    }
                };
                home.pieces.push(XmlPiece {
                    element: a.label.clone(),
                    level: a
                        .s("level")
                        .or_else(|| group_levels.last().cloned().flatten()),
                    name: a.s("name").unwrap_or_default(),
                    catalog_id: a.s("catalogId"),
                    model: a.s("model"),
                    x: a.f("x")?,
                    y: a.f("y")?,
                    elevation: a.opt_f("elevation")?.unwrap_or(0.0),
                    angle: a.opt_f("angle")?.unwrap_or(0.0),
                    width: a.f("width")?,
                    depth: a.f("depth")?,
                    height: a.f("height")?,
                    mirrored: a.flag("modelMirrored", false),
                    model_rotation: rot,
                    door_or_window: name == "doorOrWindow",
                    staircase: m.contains_key("staircaseCutOutShape"),
                    visible: a.flag("visible", true),
                });
            }
            _ => {}
        }
        if !empty {
            stack.push(name);
        }
    }
    if !stack.is_empty() {
        return Err(SceneError::Xml {
            element: stack.last().cloned(),
            message: format!("document truncated: {} element(s) not closed", stack.len()),
        });
    }
    if !saw_home {
        return Err(SceneError::Xml {
            element: None,
            message: "no <home> element".into(),
        });
    }
    Ok(home)
}

/// Plan (cm, y down) to scene (m, y up).
fn to_scene(p: Point2<f64>) -> Point2<f64> {
    Point2::new(p.x / 100.0, -p.y / 100.0)
}

/// Footprint of a piece in scene coordinates (counter-clockwise quad).
fn footprint(p: &XmlPiece) -> Vec<Point2<f64>> {
    let (c, s) = (p.angle.cos(), p.angle.sin());
    let mut out: Vec<Point2<f64>> = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
        .iter()
        .map(|&(sx, sy)| {
            let (lx, ly) = (sx * p.width * 0.5, sy * p.depth * 0.5);
            to_scene(Point2::new(p.x + lx * c - ly * s, p.y + lx * s + ly * c))
        })
        .collect();
    if polygon_area(&out) < 0.0 {
        out.reverse();
    }
    out
}

/// A wall opening: along-wall interval and vertical range (absolute z).
struct Cut {
    lo: f64,
    hi: f64,
    z0: f64,
    z1: f64,
}

/// Model source: resolves a model path to OBJ text.
type Resolver<'a> = dyn FnMut(&str) -> Option<Result<String, SceneError>> + 'a;

/// Loads a `Home.xml` file; models resolve against `models_dir`
/// (paths relative to [`RESOURCE_PREFIX`]).
///
/// # Errors
/// [`SceneError`] naming the offending element for malformed XML, missing or
/// unparsable attributes, references to unknown levels, non-finite numbers or
/// missing models.
pub fn load_home_xml(
    path: &Path,
    models_dir: &Path,
    options: &Sh3dOptions,
) -> Result<Scene, SceneError> {
    let xml = std::fs::read_to_string(path).map_err(|e| SceneError::Io {
        path: path.to_path_buf(),
        source: e,
    })?;
    let name = path
        .file_stem()
        .map(|s| s.to_string_lossy().to_string())
        .unwrap_or_default();
    home_from_xml_str(&xml, &name, models_dir, options)
}

/// Builds a scene from `Home.xml` text; models resolve against `models_dir`.
///
/// # Errors
/// As [`load_home_xml`].
pub fn home_from_xml_str(
    xml: &str,
    name: &str,
    models_dir: &Path,
    options: &Sh3dOptions,
) -> Result<Scene, SceneError> {
    let mut resolve = |model: &str| -> Option<Result<String, SceneError>> {
        let rel = model.strip_prefix(RESOURCE_PREFIX).unwrap_or(model);
        let p = models_dir.join(rel);
        p.is_file().then(|| {
            std::fs::read_to_string(&p).map_err(|e| SceneError::Io {
                path: p.clone(),
                source: e,
            })
        })
    };
    build_home(xml, name, &mut resolve, options)
}

/// Most bytes one entry of a `.sh3d` archive (`Home.xml` or a model) may
/// decompress to.
pub const MAX_SH3D_ENTRY_BYTES: u64 = 64 << 20;

/// Loads a `.sh3d` archive (its `Home.xml` entry and embedded models).
///
/// # Errors
/// [`SceneError::Io`] when the file cannot be opened, [`SceneError::Zip`]
/// for an unreadable archive, one without `Home.xml` or an entry that
/// decompresses to more than [`MAX_SH3D_ENTRY_BYTES`], then as
/// [`load_home_xml`].
pub fn load_sh3d(path: &Path, options: &Sh3dOptions) -> Result<Scene, SceneError> {
    let file = std::fs::File::open(path).map_err(|e| SceneError::Io {
        path: path.to_path_buf(),
        source: e,
    })?;
    let name = path
        .file_stem()
        .map(|s| s.to_string_lossy().to_string())
        .unwrap_or_default();
    sh3d_from_reader(file, &name, options)
}

/// Builds a scene from the bytes of a `.sh3d` archive (as [`load_sh3d`],
/// without a file); `name` names the scene.
///
/// # Errors
/// As [`load_sh3d`].
///
/// # Examples
/// ```
/// use sornav_platform_sim::SceneError;
/// use sornav_platform_sim::sh3d::{Sh3dOptions, sh3d_from_slice};
/// let err = sh3d_from_slice(b"not a zip", "home", &Sh3dOptions::default()).unwrap_err();
/// assert!(matches!(err, SceneError::Zip(_)));
/// ```
pub fn sh3d_from_slice(
    bytes: &[u8],
    name: &str,
    options: &Sh3dOptions,
) -> Result<Scene, SceneError> {
    sh3d_from_reader(std::io::Cursor::new(bytes), name, options)
}

fn sh3d_from_reader<R: Read + std::io::Seek>(
    reader: R,
    name: &str,
    options: &Sh3dOptions,
) -> Result<Scene, SceneError> {
    let mut zip = zip::ZipArchive::new(reader).map_err(|e| SceneError::Zip(e.to_string()))?;
    let read = |zip: &mut zip::ZipArchive<R>, n: &str| -> Result<String, SceneError> {
        let mut f = zip
            .by_name(n)
            .map_err(|e| SceneError::Zip(format!("{n}: {e}")))?;
        let mut buf = Vec::new();
        // Inflate at most one byte past the limit: a small archive may
        // decompress a thousandfold.
        (&mut f)
            .take(MAX_SH3D_ENTRY_BYTES + 1)
            .read_to_end(&mut buf)
            .map_err(|e| SceneError::Zip(format!("{n}: {e}")))?;
        if buf.len() as u64 > MAX_SH3D_ENTRY_BYTES {
            return Err(SceneError::Zip(format!(
                "{n}: decompresses to more than {MAX_SH3D_ENTRY_BYTES} bytes (MAX_SH3D_ENTRY_BYTES)"
            )));
        }
        Ok(String::from_utf8_lossy(&buf).to_string())
    };
    let xml = read(&mut zip, "Home.xml")?;
    let names: Vec<String> = zip.file_names().map(str::to_string).collect();
    let mut resolve = |model: &str| -> Option<Result<String, SceneError>> {
        let entry = if names.iter().any(|n| n == model) {
            model.to_string()
        } else {
            names
                .iter()
                .find(|n| n.starts_with(&format!("{model}/")) && n.ends_with(".obj"))?
                .clone()
        };
        Some(read(&mut zip, &entry))
    };
    build_home(&xml, name, &mut resolve, options)
}

impl Scene {
    /// Loads a Sweet Home 3D `Home.xml` (see [`crate::sh3d`]).
    ///
    /// # Errors
    /// See [`load_home_xml`].
    pub fn from_home_xml(path: &Path, models_dir: &Path) -> Result<Scene, SceneError> {
        load_home_xml(path, models_dir, &Sh3dOptions::default())
    }
    /// Loads a Sweet Home 3D `.sh3d` archive (see [`crate::sh3d`]).
    ///
    /// # Errors
    /// See [`load_sh3d`].
    pub fn from_sh3d(path: &Path) -> Result<Scene, SceneError> {
        load_sh3d(path, &Sh3dOptions::default())
    }
}

/// Staircase footprints with the vertical range they cut through slabs.
type StairCutout = (Vec<Point2<f64>>, f64, f64);

/// The floor and ceiling slabs of room `r` (outline `poly`, on level `l`
/// described by `lv`), as visible in the home, with the footprints of the
/// staircases that pass through each slab cut out.
fn room_surfaces(
    b: &mut MeshBuilder,
    r: &XmlRoom,
    poly: &[Point2<f64>],
    l: usize,
    lv: &Level,
    stairs: &[StairCutout],
) {
    let label = if r.name.is_empty() {
        "room".to_string()
    } else {
        r.name.clone()
    };
    let holes_at = |z: f64| -> Vec<&Vec<Point2<f64>>> {
        stairs
            .iter()
            .filter(|(_, z0, z1)| z > z0 + 0.01 && z <= z1 + 0.01)
            .map(|(f, _, _)| f)
            .collect()
    };
    let triangles: Vec<Vec<Point2<f64>>> = triangulate(poly)
        .into_iter()
        .map(|t| t.iter().map(|&i| poly[i]).collect())
        .collect();
    let pieces = |z: f64| -> Vec<Vec<Point2<f64>>> {
        let mut out = triangles.clone();
        for h in holes_at(z) {
            out = out
                .into_iter()
                .flat_map(|p| subtract_convex(&p, h))
                .collect();
        }
        out
    };
    if r.floor_visible {
        let inst = b.add_instance(InstanceKind::Floor, "floor", &label, l);
        for p in pieces(lv.elevation) {
            b.horizontal_polygon(&p, lv.elevation, true, inst);
            b.horizontal_polygon(&p, lv.elevation - lv.floor_thickness, false, inst);
        }
    }
    if r.ceiling_visible {
        let zc = lv.elevation + lv.height;
        let inst = b.add_instance(InstanceKind::Ceiling, "ceiling", &label, l);
        for p in pieces(zc) {
            b.horizontal_polygon(&p, zc, false, inst);
        }
    }
}

/// A door or window of the home: its level, the piece and its footprint.
type WallOpening<'a> = (usize, &'a XmlPiece, Vec<Point2<f64>>);

/// The mesh of wall `w` on level `l` (described by `lv`): straight or arc
/// segments with their thickness, a height that may slope from start to end
/// (`default_height` in centimetres when the wall has none), joined ends
/// extended by half the thickness, and the doors and windows on that level
/// that cross it cut out.
///
/// # Errors
/// [`SceneError::Attribute`] for a wall thickness that is not positive.
fn wall_mesh(
    b: &mut MeshBuilder,
    w: &XmlWall,
    (l, lv): (usize, &Level),
    default_height: f64,
    openings: &[WallOpening<'_>],
) -> Result<(), SceneError> {
    let h0 = w.height.unwrap_or(default_height) / 100.0;
    let h1 = w.height_at_end.map_or(h0, |h| h / 100.0);
    let t = w.thickness / 100.0;
    if t <= 0.0 {
        return Err(SceneError::Attribute {
            element: format!("wall '{}'", w.id),
            attribute: "thickness".into(),
            message: "must be > 0".into(),
        });
    }
    let (s, e) = (to_scene(w.start), to_scene(w.end));
    // pieces along the wall (arc split into straight segments)
    let pts: Vec<Point2<f64>> = match w.arc_extent {
        Some(a) if a.abs() > 1e-3 && (e - s).norm() > 1e-6 => arc_points(s, e, -a),
        _ => vec![s, e],
    };
    let total: f64 = pts.windows(2).map(|p| (p[1] - p[0]).norm()).sum();
    if total < 1e-6 {
        return Ok(());
    }
    let inst = b.add_instance(InstanceKind::Wall, "wall", &format!("wall {}", w.id), l);
    let mut acc = 0.0;
    let n_seg = pts.len() - 1;
    for k in 0..n_seg {
        let (a, c) = (pts[k], pts[k + 1]);
        let len = (c - a).norm();
        if len < 1e-9 {
            continue;
        }
        let u = (c - a) / len;
        let ext_s = if k == 0 && w.joined_start {
            t * 0.5
        } else {
            0.0
        };
        let ext_e = if k + 1 == n_seg && w.joined_end {
            t * 0.5
        } else {
            0.0
        };
        let height_at = |d: f64| h0 + (h1 - h0) * ((acc + d) / total).clamp(0.0, 1.0);
        let mut cuts = Vec::new();
        for (ol, p, fp) in openings {
            if *ol != l {
                continue;
            }
            let nrm = Vector2::new(-u.y, u.x);
            let (mut lo, mut hi, mut nlo, mut nhi) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
            for q in fp {
                let v = q - a;
                lo = lo.min(v.dot(&u));
                hi = hi.max(v.dot(&u));
                nlo = nlo.min(v.dot(&nrm));
                nhi = nhi.max(v.dot(&nrm));
            }
            if nhi < -t * 0.5 || nlo > t * 0.5 || hi <= 0.0 || lo >= len {
                continue;
            }
            let z0 = lv.elevation + p.elevation / 100.0;
            cuts.push(Cut {
                lo: lo.max(-ext_s),
                hi: hi.min(len + ext_e),
                z0,
                z1: z0 + p.height / 100.0,
            });
        }
        wall_with_cuts(
            b,
            inst,
            a,
            u,
            len,
            ext_s,
            ext_e,
            t,
            lv.elevation,
            &height_at,
            &cuts,
        );
        acc += len;
    }
    Ok(())
}

/// Builds a scene from `Home.xml` text with a model resolver.
fn build_home(
    xml: &str,
    name: &str,
    resolve: &mut Resolver<'_>,
    options: &Sh3dOptions,
) -> Result<Scene, SceneError> {
    let home = parse_xml(xml)?;
    let mut levels = home.levels.clone();
    levels.sort_by(|a, b| {
        a.level
            .elevation
            .total_cmp(&b.level.elevation)
            .then(a.index.cmp(&b.index))
    });
    if levels.is_empty() {
        levels.push(XmlLevel {
            id: String::new(),
            level: Level {
                name: "Level 0".into(),
                elevation: 0.0,
                height: home.wall_height / 100.0,
                floor_thickness: 0.12,
            },
            index: 0,
            visible: true,
        });
    }
    // `element` names the referring element in the error.
    let level_of = |id: &Option<String>, element: &dyn Fn() -> String| match id {
        None => Ok(0),
        Some(i) => levels
            .iter()
            .position(|l| &l.id == i)
            .ok_or_else(|| SceneError::Attribute {
                element: element(),
                attribute: "level".into(),
                message: format!("unknown level `{i}`"),
            }),
    };
    let built = |l: usize| options.include_hidden_levels || levels[l].visible;
    if home.walls.is_empty() && home.rooms.is_empty() && home.pieces.is_empty() {
        return Err(SceneError::Empty(format!(
            "home `{name}` has no walls, rooms or furniture"
        )));
    }

    let mut b = MeshBuilder::new();
    // the level of each piece (the first unknown one is the error)
    let piece_levels: Vec<usize> = home
        .pieces
        .iter()
        .map(|p| level_of(&p.level, &|| p.element.clone()))
        .collect::<Result<_, SceneError>>()?;
    // staircase footprints with their vertical range
    let mut stairs: Vec<StairCutout> = Vec::new();
    for (p, &l) in home.pieces.iter().zip(&piece_levels) {
        if p.staircase && p.visible && built(l) {
            let z0 = levels[l].level.elevation + p.elevation / 100.0;
            stairs.push((footprint(p), z0, z0 + p.height / 100.0));
        }
    }

    // rooms: floors and ceilings
    let mut rooms = Vec::new();
    for r in &home.rooms {
        let l = level_of(&r.level, &|| format!("room '{}'", r.name))?;
        let lv = &levels[l].level;
        let poly: Vec<Point2<f64>> = r.points.iter().map(|p| to_scene(*p)).collect();
        if poly.len() < 3 {
            continue;
        }
        rooms.push(Room {
            name: r.name.clone(),
            room_type: room_type_from_name(&r.name),
            level: l,
            polygon: if polygon_area(&poly) < 0.0 {
                poly.iter().rev().copied().collect()
            } else {
                poly.clone()
            },
            floor_z: lv.elevation,
        });
        if !built(l) {
            continue;
        }
        room_surfaces(&mut b, r, &poly, l, lv, &stairs);
    }

    // walls with openings: (level, piece, footprint)
    let openings: Vec<WallOpening<'_>> = home
        .pieces
        .iter()
        .zip(&piece_levels)
        .filter(|(p, _)| p.door_or_window && p.visible)
        .map(|(p, &l)| (l, p, footprint(p)))
        .collect();
    for w in &home.walls {
        let l = level_of(&w.level, &|| format!("wall '{}'", w.id))?;
        if !built(l) {
            continue;
        }
        wall_mesh(
            &mut b,
            w,
            (l, &levels[l].level),
            home.wall_height,
            &openings,
        )?;
    }

    // furniture, doors, windows
    let mut cache: HashMap<String, Arc<ObjMesh>> = HashMap::new();
    for (p, &l) in home.pieces.iter().zip(&piece_levels) {
        if !p.visible || !built(l) {
            continue;
        }
        let lv = &levels[l].level;
        let is_door = p.door_or_window && p.elevation < 30.0 && p.height >= 180.0;
        let (kind, category) = if p.staircase {
            (InstanceKind::Stairs, "stairs".to_string())
        } else if p.door_or_window {
            if is_door {
                (InstanceKind::Door, "door".to_string())
            } else {
                (InstanceKind::Window, "window".to_string())
            }
        } else {
            (
                InstanceKind::Object,
                classify(&p.name, p.catalog_id.as_deref()),
            )
        };
        let inst = b.add_instance(kind, &category, &p.name, l);
        let z0 = lv.elevation + p.elevation / 100.0;
        if is_door {
            for q in footprint(p) {
                b.include_in_bounds(inst, Point3::new(q.x, q.y, z0));
                b.include_in_bounds(inst, Point3::new(q.x, q.y, z0 + p.height / 100.0));
            }
            continue;
        }
        let Some(model) = p.model.as_deref() else {
            return Err(SceneError::Attribute {
                element: p.element.clone(),
                attribute: "model".into(),
                message: "missing".into(),
            });
        };
        let mesh = match cache.get(model) {
            Some(m) => m.clone(),
            None => {
                let text = resolve(model).ok_or_else(|| SceneError::MissingModel {
                    element: p.element.clone(),
                    model: model.to_string(),
                })??;
                let m = Arc::new(parse_obj(&text, model)?);
                cache.insert(model.to_string(), m.clone());
                m
            }
        };
        if p.staircase {
            // the floor the staircase climbs to: the next level above its
            // foot within its height
            let z_top = levels
                .iter()
                .map(|l| l.level.elevation)
                .filter(|&e| e > z0 + 0.5 && e <= z0 + p.height / 100.0 + 0.05)
                .fold(f64::INFINITY, f64::min);
            let z_top = if z_top.is_finite() {
                z_top
            } else {
                z0 + p.height / 100.0
            };
            let tris = placed_triangles(&mesh, p, z0);
            if !restep_staircase(&mut b, inst, &tris, z0, z_top) {
                for [v0, v1, v2] in tris {
                    b.triangle(v0, v1, v2, inst);
                }
            }
            continue;
        }
        place_model(&mut b, inst, &mesh, p, z0);
    }
    let desc = b.finish(name, levels.into_iter().map(|l| l.level).collect(), rooms);
    if desc.triangles.is_empty() {
        return Err(SceneError::Empty(format!(
            "home `{name}` produced no geometry"
        )));
    }
    Scene::from_description(desc)
}

/// Points along a circular arc from `s` to `e` sweeping `extent` radians
/// (counter-clockwise when positive), one point per 10 degrees at least.
fn arc_points(s: Point2<f64>, e: Point2<f64>, extent: f64) -> Vec<Point2<f64>> {
    let chord = e - s;
    let l = chord.norm();
    let m = s + chord * 0.5;
    let perp = Vector2::new(-chord.y, chord.x) / l;
    let dist = (l * 0.5) / (extent * 0.5).tan();
    let c = m + perp * dist;
    let n = ((extent.abs() / (std::f64::consts::PI / 18.0)).ceil() as usize).max(2);
    let r0 = s - c;
    (0..=n)
        .map(|k| {
            let a = extent * k as f64 / n as f64;
            let (sn, cs) = a.sin_cos();
            if k == n {
                e
            } else {
                c + Vector2::new(r0.x * cs - r0.y * sn, r0.x * sn + r0.y * cs)
            }
        })
        .collect()
}

/// Extrudes one straight wall piece with rectangular openings cut out.
#[allow(clippy::too_many_arguments)]
fn wall_with_cuts(
    b: &mut MeshBuilder,
    inst: u32,
    a: Point2<f64>,
    u: Vector2<f64>,
    len: f64,
    ext_s: f64,
    ext_e: f64,
    t: f64,
    floor: f64,
    height_at: &dyn Fn(f64) -> f64,
    cuts: &[Cut],
) {
    let mut xs = vec![-ext_s, len + ext_e];
    for c in cuts {
        xs.push(c.lo);
        xs.push(c.hi);
    }
    xs.sort_by(f64::total_cmp);
    xs.dedup_by(|p, q| (*p - *q).abs() < 1e-6);
    let nrm = Vector2::new(-u.y, u.x);
    for win in xs.windows(2) {
        let (x0, x1) = (win[0], win[1]);
        let mid = 0.5 * (x0 + x1);
        let (top0, top1) = (
            floor + height_at(x0.max(0.0)),
            floor + height_at(x1.min(len)),
        );
        // vertical solid ranges: [floor, top] minus openings covering this interval
        let mut open: Vec<(f64, f64)> = cuts
            .iter()
            .filter(|c| c.lo <= mid && c.hi >= mid)
            .map(|c| (c.z0, c.z1))
            .collect();
        open.sort_by(|p, q| p.0.total_cmp(&q.0));
        let mut z = floor;
        let mut solids = Vec::new();
        for (o0, o1) in open {
            if o0 > z + 1e-6 {
                solids.push((z, o0, false));
            }
            z = z.max(o1);
        }
        solids.push((z, f64::INFINITY, true));
        for (za, zb, to_top) in solids {
            let (zb0, zb1) = if to_top {
                (top0, top1)
            } else {
                (zb.min(top0), zb.min(top1))
            };
            if zb0 <= za + 1e-6 && zb1 <= za + 1e-6 {
                continue;
            }
            let p = |x: f64, side: f64, zz: f64| {
                let q = a + u * x + nrm * side * t * 0.5;
                Point3::new(q.x, q.y, zz)
            };
            let c = [
                p(x0, -1.0, za),
                p(x1, -1.0, za),
                p(x1, 1.0, za),
                p(x0, 1.0, za),
                p(x0, -1.0, zb0.max(za)),
                p(x1, -1.0, zb1.max(za)),
                p(x1, 1.0, zb1.max(za)),
                p(x0, 1.0, zb0.max(za)),
            ];
            b.hexahedron(&c, inst);
        }
    }
}

/// The triangles of an OBJ model placed by Sweet Home 3D's rule (see the
/// module docs), wound so that their normals face outwards.
fn placed_triangles(mesh: &ObjMesh, p: &XmlPiece, z0: f64) -> Vec<[Point3<f64>; 3]> {
    let rot = p.model_rotation.unwrap_or_else(Matrix3::identity);
    let verts: Vec<Vector3<f64>> = mesh.vertices.iter().map(|v| rot * v.coords).collect();
    let mut lo = Vector3::repeat(f64::MAX);
    let mut hi = Vector3::repeat(f64::MIN);
    for t in &mesh.triangles {
        for &i in t {
            lo = lo.inf(&verts[i as usize]);
            hi = hi.sup(&verts[i as usize]);
        }
    }
    if lo.x > hi.x {
        return Vec::new();
    }
    let centre = (lo + hi) * 0.5;
    let ext = hi - lo;
    let scale = |target: f64, e: f64| if e > 1e-9 { target / e } else { 1.0 };
    let s = Vector3::new(
        scale(p.width, ext.x),
        scale(p.height, ext.y),
        scale(p.depth, ext.z),
    );
    let (sn, cs) = p.angle.sin_cos();
    let flip = p.mirrored != (rot.determinant() < 0.0);
    let tr = |v: &Vector3<f64>| -> Point3<f64> {
        let mut q = (v - centre).component_mul(&s);
        if p.mirrored {
            q.x = -q.x;
        }
        // SH3D 3-D space: x = plan x, y = up, z = plan y; rotate by `angle` in plan
        let px = p.x + q.x * cs - q.z * sn;
        let py = p.y + q.x * sn + q.z * cs;
        Point3::new(px / 100.0, -py / 100.0, z0 + (q.y + p.height * 0.5) / 100.0)
    };
    mesh.triangles
        .iter()
        .map(|t| {
            let (v0, v1, v2) = (
                tr(&verts[t[0] as usize]),
                tr(&verts[t[1] as usize]),
                tr(&verts[t[2] as usize]),
            );
            if flip { [v0, v2, v1] } else { [v0, v1, v2] }
        })
        .collect()
}

/// Places an OBJ model by Sweet Home 3D's rule (see the module docs).
fn place_model(b: &mut MeshBuilder, inst: u32, mesh: &ObjMesh, p: &XmlPiece, z0: f64) {
    for [v0, v1, v2] in placed_triangles(mesh, p, z0) {
        b.triangle(v0, v1, v2, inst);
    }
}

/// Highest riser (m) of a re-stepped Sweet Home 3D staircase
/// (`restep_staircase`): under the agent's 0.2 m step.
pub const MAX_SH3D_RISER: f64 = 0.19;

/// Treads narrower than this (m, triangle height over its longest edge) are
/// nosings, stringer tops or handrails, not treads.
const MIN_TREAD_WIDTH: f64 = 0.03;

/// Cell (m) of the raster a staircase's treads are rebuilt on.
const RESTEP_CELL: f64 = 0.025;

/// Rebuilds the walkable geometry of a placed staircase model (`tris`,
/// climbing from `z0` to the floor at `z_top`) with risers of at most
/// [`MAX_SH3D_RISER`]; returns `false` (nothing built) when the model shows
/// fewer than two treads.
///
/// # Algorithm
/// 1. **Treads**: the up-facing triangles (normal within 25 deg of +z) whose
///    height lies in `(z0, z_top]`, at least [`MIN_TREAD_WIDTH`] wide,
///    grouped by height (a gap above 2 cm starts a new tread); narrower
///    triangles of a tread's height inside its bounds (slivers, nosings)
///    join it, others (stringer tops, handrails) are dropped. A tread's
///    height is its highest triangle.
/// 2. **Raster**: the treads' bounds are cut into [`RESTEP_CELL`] (2.5 cm)
///    cells; a cell belongs to the highest tread holding its centre.
/// 3. **Direction of ascent**, per cell of tread i: the fraction
///    `f = d_low / (d_low + d_high)` of the way from tread i - 1 to tread
///    i + 1 (distances in plan to their triangles; for the first tread
///    `d_low` is the distance to the outside of the staircase, where the
///    floor is, for the last tread `d_high`). It follows straight, winding
///    and curved flights alike (a winder is split along its bisector).
/// 4. **Sub-steps**: tread i, rising `r` above tread i - 1 (the floor for
///    the first), gets `k = ceil(r / MAX_SH3D_RISER)` sub-steps; a cell with
///    fraction f lies on sub-step `j = floor(k f)`, whose top is
///    `r (j + 1) / k` above tread i - 1. Cells of one row with the same
///    sub-step are merged into one box `r / k` (+ 3 cm) thick. The back of
///    the last tread keeps its height, flush with the floor above.
/// 5. The model's other triangles below `z_top` (risers, stringers,
///    handrails, undersides) are dropped: they would leave the original
///    risers standing; those above `z_top` (the balustrade around the
///    opening upstairs) are kept.
///
/// # Complexity
/// O(T log T + C G) for T model triangles, C raster cells and G triangles
/// per tread.
fn restep_staircase(
    b: &mut MeshBuilder,
    inst: u32,
    tris: &[[Point3<f64>; 3]],
    z0: f64,
    z_top: f64,
) -> bool {
    let up = |t: &[Point3<f64>; 3]| {
        let n = (t[1] - t[0]).cross(&(t[2] - t[0]));
        let l = n.norm();
        (l > 1e-12 && n.z / l >= 0.9).then_some(0.5 * l)
    };
    // up-facing triangles in (z0, z_top]: (height, triangle, wide enough)
    let mut ups: Vec<(f64, &[Point3<f64>; 3], bool)> = tris
        .iter()
        .filter_map(|t| {
            let area = up(t)?;
            let z = t.iter().map(|p| p.z).fold(f64::MIN, f64::max);
            let longest = (0..3)
                .map(|i| (t[(i + 1) % 3] - t[i]).xy().norm())
                .fold(0.0, f64::max);
            let wide = 2.0 * area / longest.max(1e-9) >= MIN_TREAD_WIDTH;
            (z > z0 + 0.02 && z <= z_top + 0.02).then_some((z, t, wide))
        })
        .collect();
    ups.sort_by(|a, b| a.0.total_cmp(&b.0));
    // treads: wide triangles grouped by height
    let mut groups: Vec<(f64, Vec<&[Point3<f64>; 3]>)> = Vec::new();
    for &(z, t, wide) in &ups {
        if !wide {
            continue;
        }
        match groups.last_mut() {
            Some(g) if z - g.0 <= 0.02 => {
                g.0 = z;
                g.1.push(t);
            }
            _ => groups.push((z, vec![t])),
        }
    }
    if groups.len() < 2 {
        return false;
    }
    // narrow triangles (slivers of a tread's triangulation, nosings) join a
    // tread of their height when they touch its wide triangles; others
    // (stringer tops, handrails) are dropped
    let bbox = |g: &[&[Point3<f64>; 3]]| {
        let (mut lo, mut hi) = (Vector2::repeat(f64::MAX), Vector2::repeat(f64::MIN));
        for t in g {
            for p in t.iter() {
                lo = lo.inf(&p.coords.xy());
                hi = hi.sup(&p.coords.xy());
            }
        }
        (lo, hi)
    };
    let boxes: Vec<(Vector2<f64>, Vector2<f64>)> = groups.iter().map(|g| bbox(&g.1)).collect();
    for &(z, t, wide) in &ups {
        if wide {
            continue;
        }
        let (lo, hi) = bbox(&[t]);
        if let Some(k) = groups.iter().zip(&boxes).position(|(g, (glo, ghi))| {
            (g.0 - z).abs() <= 0.02
                && lo.x >= glo.x - 0.02
                && lo.y >= glo.y - 0.02
                && hi.x <= ghi.x + 0.02
                && hi.y <= ghi.y + 0.02
        }) {
            groups[k].1.push(t);
        }
    }
    // distance from a plan point to a tread (0 inside)
    let dist = |p: Vector2<f64>, g: &[&[Point3<f64>; 3]]| -> f64 {
        g.iter()
            .map(|t| {
                let v = [t[0].coords.xy(), t[1].coords.xy(), t[2].coords.xy()];
                let side = |a: Vector2<f64>, b: Vector2<f64>| {
                    (b - a).x * (p - a).y - (b - a).y * (p - a).x
                };
                let (s0, s1, s2) = (side(v[0], v[1]), side(v[1], v[2]), side(v[2], v[0]));
                if (s0 >= 0.0 && s1 >= 0.0 && s2 >= 0.0) || (s0 <= 0.0 && s1 <= 0.0 && s2 <= 0.0) {
                    return 0.0;
                }
                (0..3)
                    .map(|i| {
                        let (a, b) = (v[i], v[(i + 1) % 3]);
                        let ab = b - a;
                        let u = ((p - a).dot(&ab) / ab.norm_squared().max(1e-18)).clamp(0.0, 1.0);
                        (a + ab * u - p).norm()
                    })
                    .fold(f64::INFINITY, f64::min)
            })
            .fold(f64::INFINITY, f64::min)
    };
    // raster of the treads: per cell the highest tread whose triangles hold
    // its centre
    let (mut lo, mut hi) = (Vector2::repeat(f64::MAX), Vector2::repeat(f64::MIN));
    for (l, h) in &boxes {
        lo = lo.inf(l);
        hi = hi.sup(h);
    }
    let nx = (((hi.x - lo.x) / RESTEP_CELL).ceil() as usize).clamp(1, 4000);
    let ny = (((hi.y - lo.y) / RESTEP_CELL).ceil() as usize).clamp(1, 4000);
    let centre = |i: usize, j: usize| {
        Vector2::new(
            lo.x + (i as f64 + 0.5) * RESTEP_CELL,
            lo.y + (j as f64 + 0.5) * RESTEP_CELL,
        )
    };
    let n = groups.len();
    let mut cell_tread = vec![usize::MAX; nx * ny];
    for (k, (_, g)) in groups.iter().enumerate() {
        let (glo, ghi) = boxes[k];
        let i0 = (((glo.x - lo.x) / RESTEP_CELL).floor().max(0.0) as usize).min(nx - 1);
        let i1 = (((ghi.x - lo.x) / RESTEP_CELL).ceil().max(0.0) as usize).min(nx);
        let j0 = (((glo.y - lo.y) / RESTEP_CELL).floor().max(0.0) as usize).min(ny - 1);
        let j1 = (((ghi.y - lo.y) / RESTEP_CELL).ceil().max(0.0) as usize).min(ny);
        for j in j0..j1 {
            for i in i0..i1 {
                if dist(centre(i, j), g) == 0.0 {
                    cell_tread[j * nx + i] = k; // groups rise: the last wins
                }
            }
        }
    }
    // distance to the nearest cell outside the staircase's treads (the floor
    // below the first tread and above the last one): two-pass chamfer
    let mut out_d: Vec<f64> = cell_tread
        .iter()
        .map(|&k| if k == usize::MAX { 0.0 } else { f64::INFINITY })
        .collect();
    let diag = RESTEP_CELL * std::f64::consts::SQRT_2;
    for pass in 0..2 {
        for step in 0..nx * ny {
            let c = if pass == 0 { step } else { nx * ny - 1 - step };
            let (i, j) = ((c % nx) as i64, (c / nx) as i64);
            let sgn = if pass == 0 { -1 } else { 1 };
            let mut best = out_d[c];
            for (di, dj, w) in [
                (sgn, 0, RESTEP_CELL),
                (0, sgn, RESTEP_CELL),
                (sgn, sgn, diag),
                (-sgn, sgn, diag),
            ] {
                let (a, bj) = (i + di, j + dj);
                // beyond the raster lies the outside
                let d = if a < 0 || bj < 0 || a >= nx as i64 || bj >= ny as i64 {
                    0.5 * RESTEP_CELL
                } else {
                    out_d[bj as usize * nx + a as usize]
                };
                best = best.min(d + w);
            }
            out_d[c] = best;
        }
    }
    // fraction of the way from the tread below (the outside for the first
    // tread) to the tread above (the outside for the last)
    let frac: Vec<f64> = cell_tread
        .iter()
        .enumerate()
        .map(|(c, &k)| {
            if k == usize::MAX {
                return 0.0;
            }
            let p = centre(c % nx, c / nx);
            let d_low = if k > 0 {
                dist(p, &groups[k - 1].1)
            } else {
                out_d[c]
            };
            let d_high = if k + 1 < n {
                dist(p, &groups[k + 1].1)
            } else {
                out_d[c]
            };
            if d_low + d_high > 1e-12 {
                d_low / (d_low + d_high)
            } else {
                0.5
            }
        })
        .collect();
    // sub-steps, merged into runs along x
    let step_of = |c: usize| -> Option<(usize, usize, usize)> {
        let k = cell_tread[c];
        if k == usize::MAX {
            return None;
        }
        let below = if k == 0 { z0 } else { groups[k - 1].0 };
        let r = groups[k].0 - below;
        let m = ((r / MAX_SH3D_RISER) - 1e-9).ceil().max(1.0) as usize;
        let j = ((frac[c] * m as f64).floor().max(0.0) as usize).min(m - 1);
        Some((k, j, m))
    };
    for j in 0..ny {
        let mut i = 0;
        while i < nx {
            let Some(key) = step_of(j * nx + i) else {
                i += 1;
                continue;
            };
            let mut e = i + 1;
            while e < nx && step_of(j * nx + e) == Some(key) {
                e += 1;
            }
            let (k, sub, m) = key;
            let below = if k == 0 { z0 } else { groups[k - 1].0 };
            let r = groups[k].0 - below;
            let top = below + r * (sub + 1) as f64 / m as f64;
            let (x0, y0) = (lo.x + i as f64 * RESTEP_CELL, lo.y + j as f64 * RESTEP_CELL);
            b.aabb_box(
                Point3::new(x0, y0, top - r / m as f64 - 0.03),
                Point3::new(lo.x + e as f64 * RESTEP_CELL, y0 + RESTEP_CELL, top),
                inst,
            );
            i = e;
        }
    }
    for t in tris {
        if t.iter().all(|p| p.z > z_top + 0.05) {
            b.triangle(t[0], t[1], t[2], inst);
        }
    }
    true
}
