//! The scene model: a labelled triangle mesh with levels, rooms and object instances.
//!
//! Every triangle of a [`Scene`] carries an [`InstanceId`]; every instance has a
//! [`InstanceKind`] (wall, floor, ..., or a furniture [`InstanceKind::Object`]), a
//! category label from the ObjectNav vocabulary (see [`crate::category`]), a
//! name, a level and an axis-aligned bounding box. Coordinates are right-handed,
//! z up, metres.
//!
//! The mesh is plain data (vertices, triangles, per-triangle instance:
//! [`Scene::vertices`], [`Scene::triangles`] and [`Scene::triangle_instances`]);
//! ray casting is the renderer's job ([`crate::Bvh`], [`crate::Camera`]).

use nalgebra::{Point2, Point3, Vector3};
use serde::{Deserialize, Serialize};

use crate::SceneError;

/// Index of an instance in [`Scene::instances`] (instance `i` has `id == i`).
pub type InstanceId = u32;

/// What an instance is: part of the building's structure or a piece of furniture.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum InstanceKind {
    /// A wall (one instance per wall).
    Wall,
    /// A floor slab (one per room, or per level).
    Floor,
    /// A ceiling.
    Ceiling,
    /// A door (the opening is passable).
    Door,
    /// A window.
    Window,
    /// A staircase (walkable geometry connecting levels).
    Stairs,
    /// A piece of furniture or any other object; a navigation target when its
    /// category belongs to the ObjectNav vocabulary.
    Object,
}

impl InstanceKind {
    /// True for building structure (everything except [`InstanceKind::Object`]).
    pub fn is_structure(self) -> bool {
        self != InstanceKind::Object
    }
}

/// An axis-aligned bounding box in metres.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Aabb {
    /// Minimum corner.
    pub min: Point3<f64>,
    /// Maximum corner.
    pub max: Point3<f64>,
}

impl Aabb {
    /// The empty box (min = +inf, max = -inf); grows with [`Aabb::include`].
    pub fn empty() -> Self {
        Aabb {
            min: Point3::new(f64::INFINITY, f64::INFINITY, f64::INFINITY),
            max: Point3::new(f64::NEG_INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY),
        }
    }
    /// True if no point was ever included.
    pub fn is_empty(&self) -> bool {
        !(self.min.x <= self.max.x && self.min.y <= self.max.y && self.min.z <= self.max.z)
    }
    /// Grows the box to contain `p`.
    pub fn include(&mut self, p: &Point3<f64>) {
        self.min = self.min.inf(p);
        self.max = self.max.sup(p);
    }
    /// The centre of the box.
    pub fn center(&self) -> Point3<f64> {
        nalgebra::center(&self.min, &self.max)
    }
    /// Extent along each axis.
    pub fn extents(&self) -> Vector3<f64> {
        self.max - self.min
    }
    /// True if `p` lies inside or on the box.
    pub fn contains(&self, p: &Point3<f64>) -> bool {
        (0..3).all(|i| p[i] >= self.min[i] && p[i] <= self.max[i])
    }
    /// Euclidean distance from `p` to the box (0 inside).
    pub fn distance_to(&self, p: &Point3<f64>) -> f64 {
        let d = Vector3::from_fn(|i, _| (self.min[i] - p[i]).max(p[i] - self.max[i]).max(0.0));
        d.norm()
    }
    /// Horizontal (xy) distance from `p` to the box footprint (0 inside).
    pub fn distance_xy(&self, p: &Point3<f64>) -> f64 {
        let dx = (self.min.x - p.x).max(p.x - self.max.x).max(0.0);
        let dy = (self.min.y - p.y).max(p.y - self.max.y).max(0.0);
        dx.hypot(dy)
    }
    /// Distance from an agent body (the vertical segment
    /// `[feet.z, feet.z + height]`) to the box (0 when they touch).
    pub fn body_distance(&self, feet: &Point3<f64>, height: f64) -> f64 {
        let dz = (self.min.z - (feet.z + height))
            .max(feet.z - self.max.z)
            .max(0.0);
        self.distance_xy(feet).hypot(dz)
    }
}

/// One storey of a building.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Level {
    /// Name of the level ("Ground floor", "Level 1", ...).
    pub name: String,
    /// Height of the walking surface (top of the floor slab) in metres.
    pub elevation: f64,
    /// Default wall height of the level in metres.
    pub height: f64,
    /// Thickness of the floor slab below `elevation`, in metres.
    pub floor_thickness: f64,
}

/// Room type, inferred from a room's name (see [`crate::category::room_type_from_name`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RoomType {
    /// Bedroom.
    Bedroom,
    /// Bathroom (with or without toilet).
    Bathroom,
    /// Separate toilet / WC.
    Toilet,
    /// Kitchen.
    Kitchen,
    /// Living room / lounge.
    LivingRoom,
    /// Dining room.
    DiningRoom,
    /// Hallway, corridor, entrance.
    Hallway,
    /// Office, study.
    Office,
    /// Laundry / utility room.
    Laundry,
    /// Closet, dressing, storage.
    Closet,
    /// Garage.
    Garage,
    /// Stairwell.
    Stairs,
    /// Balcony, terrace, porch, garden.
    Outdoor,
    /// Attic, basement, cellar.
    Storage,
    /// Anything else.
    Other,
}

impl RoomType {
    /// All room types, in declaration order.
    pub const ALL: [RoomType; 15] = [
        RoomType::Bedroom,
        RoomType::Bathroom,
        RoomType::Toilet,
        RoomType::Kitchen,
        RoomType::LivingRoom,
        RoomType::DiningRoom,
        RoomType::Hallway,
        RoomType::Office,
        RoomType::Laundry,
        RoomType::Closet,
        RoomType::Garage,
        RoomType::Stairs,
        RoomType::Outdoor,
        RoomType::Storage,
        RoomType::Other,
    ];
    /// Lower-case label ("bedroom", "living_room", ...).
    pub fn label(self) -> &'static str {
        match self {
            RoomType::Bedroom => "bedroom",
            RoomType::Bathroom => "bathroom",
            RoomType::Toilet => "toilet",
            RoomType::Kitchen => "kitchen",
            RoomType::LivingRoom => "living_room",
            RoomType::DiningRoom => "dining_room",
            RoomType::Hallway => "hallway",
            RoomType::Office => "office",
            RoomType::Laundry => "laundry",
            RoomType::Closet => "closet",
            RoomType::Garage => "garage",
            RoomType::Stairs => "stairs",
            RoomType::Outdoor => "outdoor",
            RoomType::Storage => "storage",
            RoomType::Other => "other",
        }
    }
}

/// A named room: a floor polygon on a level.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Room {
    /// The room's name as written in the source ("Bedroom 2"), possibly empty.
    pub name: String,
    /// Room type inferred from the name.
    pub room_type: RoomType,
    /// Index into [`Scene::levels`].
    pub level: usize,
    /// Floor polygon (counter-clockwise seen from above, metres).
    pub polygon: Vec<Point2<f64>>,
    /// Height of the room's floor surface.
    pub floor_z: f64,
}

/// One labelled instance: a wall, floor, door, ... or a piece of furniture.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ObjectInstance {
    /// Instance id (its index in [`Scene::instances`]).
    pub id: InstanceId,
    /// Structure or object.
    pub kind: InstanceKind,
    /// Category label: ObjectNav vocabulary when mapped ("chair", "tv_monitor"),
    /// otherwise the piece's own lower-case label ("lamp", "wall").
    pub category: String,
    /// The name in the source (furniture name, node name).
    pub name: String,
    /// Index into [`Scene::levels`].
    pub level: usize,
    /// Index into [`Scene::rooms`] of the room containing the instance's centre.
    pub room: Option<usize>,
    /// Bounds of the instance's triangles.
    pub bounds: Aabb,
}

/// The serialisable content of a [`Scene`] (everything but the BVH).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SceneDescription {
    /// Scene name.
    pub name: String,
    /// Levels, sorted by elevation.
    pub levels: Vec<Level>,
    /// Rooms.
    pub rooms: Vec<Room>,
    /// Instances; `instances[i].id == i`.
    pub instances: Vec<ObjectInstance>,
    /// Mesh vertices (x, y, z in metres).
    pub vertices: Vec<[f32; 3]>,
    /// Triangles as vertex indices.
    pub triangles: Vec<[u32; 3]>,
    /// Instance of each triangle.
    pub triangle_instances: Vec<InstanceId>,
}

/// A validated, labelled triangle-mesh scene.
///
/// Build one with [`Scene::procedural`], [`Scene::from_home_xml`],
/// [`Scene::from_sh3d`], [`Scene::from_gltf`] or [`Scene::from_description`].
/// Serialises as its [`SceneDescription`].
#[derive(Clone, Serialize, Deserialize)]
#[serde(try_from = "SceneDescription", into = "SceneDescription")]
pub struct Scene {
    desc: SceneDescription,
}

impl std::fmt::Debug for Scene {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Scene")
            .field("name", &self.desc.name)
            .field("levels", &self.desc.levels.len())
            .field("rooms", &self.desc.rooms.len())
            .field("instances", &self.desc.instances.len())
            .field("triangles", &self.desc.triangles.len())
            .finish()
    }
}

impl PartialEq for Scene {
    fn eq(&self, other: &Self) -> bool {
        self.desc == other.desc
    }
}

impl TryFrom<SceneDescription> for Scene {
    type Error = SceneError;
    fn try_from(desc: SceneDescription) -> Result<Self, SceneError> {
        Scene::from_description(desc)
    }
}

impl From<Scene> for SceneDescription {
    fn from(s: Scene) -> Self {
        s.desc
    }
}

impl Scene {
    /// Validates a description.
    ///
    /// # Errors
    /// [`SceneError::Empty`] without triangles; [`SceneError::Invalid`] for
    /// out-of-range indices, instance ids that are not their index, levels or
    /// rooms out of range, or non-finite vertices.
    ///
    /// # Complexity
    /// O(V + T + I) for V vertices, T triangles and I instances.
    pub fn from_description(desc: SceneDescription) -> Result<Scene, SceneError> {
        if desc.triangles.is_empty() {
            return Err(SceneError::Empty(format!(
                "scene `{}` has no triangles",
                desc.name
            )));
        }
        if desc.levels.is_empty() {
            return Err(SceneError::Invalid("no levels".into()));
        }
        if desc.triangle_instances.len() != desc.triangles.len() {
            return Err(SceneError::Invalid(format!(
                "{} triangles but {} triangle instances",
                desc.triangles.len(),
                desc.triangle_instances.len()
            )));
        }
        if let Some(i) = desc
            .vertices
            .iter()
            .position(|v| v.iter().any(|c| !c.is_finite()))
        {
            return Err(SceneError::Invalid(format!("vertex {i} is not finite")));
        }
        let nv = desc.vertices.len() as u64;
        if let Some(t) = desc
            .triangles
            .iter()
            .position(|t| t.iter().any(|&i| u64::from(i) >= nv))
        {
            return Err(SceneError::Invalid(format!(
                "triangle {t} indexes a missing vertex"
            )));
        }
        for (i, inst) in desc.instances.iter().enumerate() {
            if inst.id as usize != i {
                return Err(SceneError::Invalid(format!(
                    "instance {i} has id {}",
                    inst.id
                )));
            }
            if inst.level >= desc.levels.len() {
                return Err(SceneError::Invalid(format!(
                    "instance {i} on unknown level {}",
                    inst.level
                )));
            }
            if inst.room.is_some_and(|r| r >= desc.rooms.len()) {
                return Err(SceneError::Invalid(format!("instance {i} in unknown room")));
            }
        }
        if let Some(r) = desc.rooms.iter().position(|r| r.level >= desc.levels.len()) {
            return Err(SceneError::Invalid(format!("room {r} on unknown level")));
        }
        let ni = desc.instances.len() as u64;
        if let Some(t) = desc
            .triangle_instances
            .iter()
            .position(|&i| u64::from(i) >= ni)
        {
            return Err(SceneError::Invalid(format!(
                "triangle {t} has unknown instance"
            )));
        }
        Ok(Scene { desc })
    }

    /// The serialisable description.
    pub fn description(&self) -> &SceneDescription {
        &self.desc
    }
    /// Scene name.
    pub fn name(&self) -> &str {
        &self.desc.name
    }
    /// Mesh vertices (metres, z up).
    pub fn vertices(&self) -> &[[f32; 3]] {
        &self.desc.vertices
    }
    /// Triangles as indices into [`Scene::vertices`].
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.desc.triangles
    }
    /// Instance of each triangle (parallel to [`Scene::triangles`]).
    pub fn triangle_instances(&self) -> &[InstanceId] {
        &self.desc.triangle_instances
    }
    /// All instances (structure and objects); `instances()[id]` has that id.
    pub fn instances(&self) -> &[ObjectInstance] {
        &self.desc.instances
    }
    /// The instance with this id.
    pub fn instance(&self, id: InstanceId) -> Option<&ObjectInstance> {
        self.desc.instances.get(id as usize)
    }
    /// Instances of kind [`InstanceKind::Object`] (furniture).
    pub fn objects(&self) -> impl Iterator<Item = &ObjectInstance> {
        self.desc
            .instances
            .iter()
            .filter(|i| i.kind == InstanceKind::Object)
    }
    /// Objects of one category.
    pub fn objects_of(&self, category: &str) -> impl Iterator<Item = &ObjectInstance> {
        self.objects().filter(move |o| o.category == category)
    }
    /// Levels, sorted by elevation.
    pub fn levels(&self) -> &[Level] {
        &self.desc.levels
    }
    /// Rooms.
    pub fn rooms(&self) -> &[Room] {
        &self.desc.rooms
    }
    /// The level whose walking surface is the highest one at or below `z + 0.5`
    /// (the level an agent standing at height `z` is on).
    pub fn level_at(&self, z: f64) -> usize {
        let mut best = 0;
        for (i, l) in self.desc.levels.iter().enumerate() {
            if l.elevation <= z + 0.5 {
                best = i;
            }
        }
        best
    }
    /// The room whose polygon contains `(x, y)` on `level`.
    pub fn room_at(&self, level: usize, x: f64, y: f64) -> Option<usize> {
        let p = Point2::new(x, y);
        self.desc
            .rooms
            .iter()
            .position(|r| r.level == level && crate::geometry::point_in_polygon(&p, &r.polygon))
    }
    /// Bounds of the whole mesh.
    pub fn bounds(&self) -> Aabb {
        let mut b = Aabb::empty();
        for v in &self.desc.vertices {
            b.include(&Point3::new(
                f64::from(v[0]),
                f64::from(v[1]),
                f64::from(v[2]),
            ));
        }
        b
    }
}
