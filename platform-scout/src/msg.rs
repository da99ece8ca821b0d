//! ROS 2 message types as serde structs whose field order and types follow
//! the `.msg` definitions, so that RustDDS's CDR (de)serialiser produces the
//! same bytes as `rmw` (see [`crate::cdr`]).
//!
//! Only the messages the CMU autonomy-stack contract needs are defined:
//! `builtin_interfaces`, `std_msgs`, `geometry_msgs`, `nav_msgs`,
//! `sensor_msgs` and `visualization_msgs` (ROS 2 Humble and later layouts).
//! Every type implements [`RosMessage`], which names its ROS type for topic
//! creation.
//!
//! Byte arrays (`uint8[]`) are (de)serialised as one byte buffer
//! ([`serde_bytes`]), which CDR encodes exactly like a sequence of `uint8`
//! (a 4-byte length then the bytes) but in one copy.

use std::time::{Duration, SystemTime, UNIX_EPOCH};

use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use serde_big_array::BigArray;

/// A ROS 2 message type: serde (CDR) plus its `package/msg/Name`.
pub trait RosMessage: Serialize + DeserializeOwned + Clone + Send + 'static {
    /// ROS package (`geometry_msgs`).
    const PACKAGE: &'static str;
    /// Message name (`PointStamped`).
    const NAME: &'static str;

    /// `package/msg/Name`, the name `ros2 topic info` shows.
    fn ros_type() -> String {
        format!("{}/msg/{}", Self::PACKAGE, Self::NAME)
    }
}

macro_rules! ros_message {
    ($t:ty, $pkg:literal, $name:literal) => {
        impl RosMessage for $t {
            const PACKAGE: &'static str = $pkg;
            const NAME: &'static str = $name;
        }
    };
}

/// Serde helpers that (de)serialise `Vec<u8>` as one byte buffer.
///
/// CDR writes a byte buffer as `uint32 length` followed by the bytes, which
/// is exactly the encoding of `sequence<uint8>`; self-describing formats
/// (JSON) still read a sequence of numbers.
pub mod serde_bytes {
    use serde::de::{self, SeqAccess, Visitor};
    use serde::{Deserializer, Serializer};

    /// Serialises the bytes with `serialize_bytes`.
    ///
    /// # Errors
    /// Those of the serializer.
    pub fn serialize<S: Serializer>(bytes: &[u8], serializer: S) -> Result<S::Ok, S::Error> {
        serializer.serialize_bytes(bytes)
    }

    struct BytesVisitor;

    impl<'de> Visitor<'de> for BytesVisitor {
        type Value = Vec<u8>;
        fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            f.write_str("a byte buffer")
        }
        fn visit_bytes<E: de::Error>(self, v: &[u8]) -> Result<Vec<u8>, E> {
            Ok(v.to_vec())
        }
        fn visit_byte_buf<E: de::Error>(self, v: Vec<u8>) -> Result<Vec<u8>, E> {
            Ok(v)
        }
        fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Vec<u8>, A::Error> {
            let mut out = Vec::with_capacity(seq.size_hint().unwrap_or(0).min(1 << 20));
            while let Some(b) = seq.next_element::<u8>()? {
                out.push(b);
            }
            Ok(out)
        }
    }

    /// Deserialises a byte buffer (or a sequence of `u8`).
    ///
    /// # Errors
    /// Those of the deserializer.
    pub fn deserialize<'de, D: Deserializer<'de>>(deserializer: D) -> Result<Vec<u8>, D::Error> {
        deserializer.deserialize_byte_buf(BytesVisitor)
    }
}

// ---------------------------------------------------------------- builtin

/// `builtin_interfaces/Time`: seconds and nanoseconds since the epoch.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
pub struct Time {
    /// Seconds.
    pub sec: i32,
    /// Nanoseconds in `[0, 1e9)`.
    pub nanosec: u32,
}

impl Time {
    /// The wall clock now (saturating at the `i32` range).
    pub fn now() -> Self {
        Self::from_system_time(SystemTime::now())
    }

    /// A system time (times before the epoch map to zero).
    pub fn from_system_time(t: SystemTime) -> Self {
        Self::from_duration(t.duration_since(UNIX_EPOCH).unwrap_or_default())
    }

    /// A duration since the epoch (saturating at `i32::MAX` seconds).
    pub fn from_duration(d: Duration) -> Self {
        Self {
            sec: i32::try_from(d.as_secs()).unwrap_or(i32::MAX),
            nanosec: d.subsec_nanos(),
        }
    }
}

ros_message!(Time, "builtin_interfaces", "Time");

/// `builtin_interfaces/Duration`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct RosDuration {
    /// Seconds.
    pub sec: i32,
    /// Nanoseconds in `[0, 1e9)`.
    pub nanosec: u32,
}

ros_message!(RosDuration, "builtin_interfaces", "Duration");

// ---------------------------------------------------------------- std_msgs

/// `std_msgs/Header`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Header {
    /// Acquisition time.
    pub stamp: Time,
    /// Coordinate frame.
    pub frame_id: String,
}

impl Header {
    /// A header stamped `stamp` in `frame_id`.
    pub fn new(stamp: Time, frame_id: impl Into<String>) -> Self {
        Self {
            stamp,
            frame_id: frame_id.into(),
        }
    }
}

ros_message!(Header, "std_msgs", "Header");

/// `std_msgs/String`.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct RosString {
    /// The text.
    pub data: String,
}

ros_message!(RosString, "std_msgs", "String");

/// `std_msgs/Bool`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Bool {
    /// The value.
    pub data: bool,
}

ros_message!(Bool, "std_msgs", "Bool");

/// `std_msgs/Int8` (the CMU path follower's `/stop`: 0 run, 1 stop
/// translation, 2 stop everything).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Int8 {
    /// The value.
    pub data: i8,
}

ros_message!(Int8, "std_msgs", "Int8");

/// `std_msgs/Float32` (the CMU path follower's `/speed`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Float32 {
    /// The value.
    pub data: f32,
}

ros_message!(Float32, "std_msgs", "Float32");

/// `std_msgs/ColorRGBA`, components in `[0, 1]`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct ColorRGBA {
    /// Red.
    pub r: f32,
    /// Green.
    pub g: f32,
    /// Blue.
    pub b: f32,
    /// Alpha (0 is invisible).
    pub a: f32,
}

impl ColorRGBA {
    /// An opaque colour.
    pub const fn rgb(r: f32, g: f32, b: f32) -> Self {
        Self { r, g, b, a: 1.0 }
    }
}

ros_message!(ColorRGBA, "std_msgs", "ColorRGBA");

// ---------------------------------------------------------------- geometry

/// `geometry_msgs/Point` (f64).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Point {
    /// x (m).
    pub x: f64,
    /// y (m).
    pub y: f64,
    /// z (m).
    pub z: f64,
}

impl Point {
    /// A point.
    pub const fn new(x: f64, y: f64, z: f64) -> Self {
        Self { x, y, z }
    }
}

impl From<nalgebra::Point3<f64>> for Point {
    fn from(p: nalgebra::Point3<f64>) -> Self {
        Self::new(p.x, p.y, p.z)
    }
}

impl From<Point> for nalgebra::Point3<f64> {
    fn from(p: Point) -> Self {
        nalgebra::Point3::new(p.x, p.y, p.z)
    }
}

ros_message!(Point, "geometry_msgs", "Point");

/// `geometry_msgs/Point32` (f32).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Point32 {
    /// x (m).
    pub x: f32,
    /// y (m).
    pub y: f32,
    /// z (m).
    pub z: f32,
}

ros_message!(Point32, "geometry_msgs", "Point32");

/// `geometry_msgs/Vector3`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Vector3 {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
}

impl Vector3 {
    /// A vector.
    pub const fn new(x: f64, y: f64, z: f64) -> Self {
        Self { x, y, z }
    }
}

ros_message!(Vector3, "geometry_msgs", "Vector3");

/// `geometry_msgs/Quaternion` (defaults to the identity, as in ROS 2).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Quaternion {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
    /// w.
    pub w: f64,
}

impl Default for Quaternion {
    fn default() -> Self {
        Self::IDENTITY
    }
}

impl Quaternion {
    /// The identity rotation.
    pub const IDENTITY: Self = Self {
        x: 0.0,
        y: 0.0,
        z: 0.0,
        w: 1.0,
    };

    /// A rotation by `yaw` radians about z.
    pub fn from_yaw(yaw: f64) -> Self {
        let (s, c) = (yaw / 2.0).sin_cos();
        Self {
            x: 0.0,
            y: 0.0,
            z: s,
            w: c,
        }
    }

    /// As a nalgebra unit quaternion (normalised; `None` for a zero or
    /// non-finite quaternion).
    pub fn to_unit(&self) -> Option<nalgebra::UnitQuaternion<f64>> {
        let q = nalgebra::Quaternion::new(self.w, self.x, self.y, self.z);
        let n = q.norm();
        (n.is_finite() && n > 1e-9).then(|| nalgebra::UnitQuaternion::new_normalize(q))
    }
}

impl From<nalgebra::UnitQuaternion<f64>> for Quaternion {
    fn from(q: nalgebra::UnitQuaternion<f64>) -> Self {
        Self {
            x: q.i,
            y: q.j,
            z: q.k,
            w: q.w,
        }
    }
}

ros_message!(Quaternion, "geometry_msgs", "Quaternion");

/// `geometry_msgs/Pose`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Pose {
    /// Position.
    pub position: Point,
    /// Orientation.
    pub orientation: Quaternion,
}

ros_message!(Pose, "geometry_msgs", "Pose");

/// `geometry_msgs/PoseStamped`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct PoseStamped {
    /// Header.
    pub header: Header,
    /// Pose.
    pub pose: Pose,
}

ros_message!(PoseStamped, "geometry_msgs", "PoseStamped");

/// `geometry_msgs/PoseWithCovariance`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PoseWithCovariance {
    /// Pose.
    pub pose: Pose,
    /// Row-major 6x6 covariance (x, y, z, roll, pitch, yaw).
    #[serde(with = "BigArray")]
    pub covariance: [f64; 36],
}

impl Default for PoseWithCovariance {
    fn default() -> Self {
        Self {
            pose: Pose::default(),
            covariance: [0.0; 36],
        }
    }
}

ros_message!(PoseWithCovariance, "geometry_msgs", "PoseWithCovariance");

/// `geometry_msgs/Twist`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Twist {
    /// Linear velocity (m/s).
    pub linear: Vector3,
    /// Angular velocity (rad/s).
    pub angular: Vector3,
}

ros_message!(Twist, "geometry_msgs", "Twist");

/// `geometry_msgs/TwistWithCovariance`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TwistWithCovariance {
    /// Twist.
    pub twist: Twist,
    /// Row-major 6x6 covariance.
    #[serde(with = "BigArray")]
    pub covariance: [f64; 36],
}

impl Default for TwistWithCovariance {
    fn default() -> Self {
        Self {
            twist: Twist::default(),
            covariance: [0.0; 36],
        }
    }
}

ros_message!(TwistWithCovariance, "geometry_msgs", "TwistWithCovariance");

/// `geometry_msgs/TwistStamped` (what the CMU path follower publishes on
/// `/cmd_vel`).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct TwistStamped {
    /// Header.
    pub header: Header,
    /// Twist.
    pub twist: Twist,
}

ros_message!(TwistStamped, "geometry_msgs", "TwistStamped");

/// `geometry_msgs/PointStamped` (the CMU local planner's `/way_point`).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct PointStamped {
    /// Header.
    pub header: Header,
    /// Point.
    pub point: Point,
}

ros_message!(PointStamped, "geometry_msgs", "PointStamped");

/// `geometry_msgs/Polygon`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Polygon {
    /// Vertices.
    pub points: Vec<Point32>,
}

ros_message!(Polygon, "geometry_msgs", "Polygon");

/// `geometry_msgs/PolygonStamped`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct PolygonStamped {
    /// Header.
    pub header: Header,
    /// Polygon.
    pub polygon: Polygon,
}

ros_message!(PolygonStamped, "geometry_msgs", "PolygonStamped");

// ---------------------------------------------------------------- nav_msgs

/// `nav_msgs/Odometry` (the CMU stack's `/state_estimation`).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Odometry {
    /// Header (`frame_id`: the map / odometry frame).
    pub header: Header,
    /// Frame of the twist (the vehicle / sensor frame).
    pub child_frame_id: String,
    /// Pose in `header.frame_id`.
    pub pose: PoseWithCovariance,
    /// Twist in `child_frame_id`.
    pub twist: TwistWithCovariance,
}

ros_message!(Odometry, "nav_msgs", "Odometry");

/// `nav_msgs/Path`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Path {
    /// Header.
    pub header: Header,
    /// Poses along the path.
    pub poses: Vec<PoseStamped>,
}

ros_message!(Path, "nav_msgs", "Path");

// ---------------------------------------------------------------- sensor_msgs

/// `sensor_msgs/PointField`: one named channel of a [`PointCloud2`].
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct PointField {
    /// Channel name (`x`, `intensity`, `label`).
    pub name: String,
    /// Byte offset inside a point.
    pub offset: u32,
    /// Datatype code (1 `INT8` ... 8 `FLOAT64`, see
    /// [`crate::pointcloud::Datatype`]).
    pub datatype: u8,
    /// Number of elements (1 for scalars).
    pub count: u32,
}

ros_message!(PointField, "sensor_msgs", "PointField");

/// `sensor_msgs/PointCloud2`; decode it with [`crate::pointcloud`].
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct PointCloud2 {
    /// Header (`frame_id`: the frame of the points).
    pub header: Header,
    /// Rows (1 for unorganised clouds).
    pub height: u32,
    /// Points per row.
    pub width: u32,
    /// Channels.
    pub fields: Vec<PointField>,
    /// Whether the data is big-endian.
    pub is_bigendian: bool,
    /// Bytes per point.
    pub point_step: u32,
    /// Bytes per row.
    pub row_step: u32,
    /// `row_step * height` bytes.
    #[serde(with = "serde_bytes")]
    pub data: Vec<u8>,
    /// True when no point is invalid (NaN).
    pub is_dense: bool,
}

ros_message!(PointCloud2, "sensor_msgs", "PointCloud2");

/// `sensor_msgs/Joy`. The CMU local planner and path follower read
/// `axes[2]` (autonomy mode when below -0.1), `axes[3]`/`axes[4]` (manual
/// speed; in autonomy mode `axes[4]` must be positive or the speed is 0) and
/// `axes[5]` (obstacle checking when above -0.1).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Joy {
    /// Header.
    pub header: Header,
    /// Axes in `[-1, 1]`.
    pub axes: Vec<f32>,
    /// Buttons.
    pub buttons: Vec<i32>,
}

ros_message!(Joy, "sensor_msgs", "Joy");

/// `sensor_msgs/CompressedImage` (part of [`Marker`]).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct CompressedImage {
    /// Header.
    pub header: Header,
    /// `jpeg` or `png`.
    pub format: String,
    /// Compressed bytes.
    #[serde(with = "serde_bytes")]
    pub data: Vec<u8>,
}

ros_message!(CompressedImage, "sensor_msgs", "CompressedImage");

// ---------------------------------------------------------------- visualization_msgs

/// `visualization_msgs/UVCoordinate`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct UvCoordinate {
    /// u in `[0, 1]`.
    pub u: f32,
    /// v in `[0, 1]`.
    pub v: f32,
}

ros_message!(UvCoordinate, "visualization_msgs", "UVCoordinate");

/// `visualization_msgs/MeshFile`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct MeshFile {
    /// File name (with extension).
    pub filename: String,
    /// File contents.
    #[serde(with = "serde_bytes")]
    pub data: Vec<u8>,
}

ros_message!(MeshFile, "visualization_msgs", "MeshFile");

/// `visualization_msgs/Marker` (ROS 2 Humble and later layout).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Marker {
    /// Header.
    pub header: Header,
    /// Namespace.
    pub ns: String,
    /// Id, unique within `ns`.
    pub id: i32,
    /// Shape ([`Marker::SPHERE_LIST`], ...).
    pub r#type: i32,
    /// [`Marker::ADD`], [`Marker::DELETE`] or [`Marker::DELETEALL`].
    pub action: i32,
    /// Pose of the marker.
    pub pose: Pose,
    /// Scale (m).
    pub scale: Vector3,
    /// Colour.
    pub color: ColorRGBA,
    /// How long the marker lives (0: forever).
    pub lifetime: RosDuration,
    /// Re-transform every frame.
    pub frame_locked: bool,
    /// Points of list and line types.
    pub points: Vec<Point>,
    /// Per-point colours.
    pub colors: Vec<ColorRGBA>,
    /// Texture URI.
    pub texture_resource: String,
    /// Embedded texture.
    pub texture: CompressedImage,
    /// Texture coordinates.
    pub uv_coordinates: Vec<UvCoordinate>,
    /// Text of [`Marker::TEXT_VIEW_FACING`] markers.
    pub text: String,
    /// Mesh URI.
    pub mesh_resource: String,
    /// Embedded mesh.
    pub mesh_file: MeshFile,
    /// Use the mesh's materials.
    pub mesh_use_embedded_materials: bool,
}

impl Marker {
    /// Arrow.
    pub const ARROW: i32 = 0;
    /// Cube.
    pub const CUBE: i32 = 1;
    /// Sphere.
    pub const SPHERE: i32 = 2;
    /// Cylinder.
    pub const CYLINDER: i32 = 3;
    /// Line strip.
    pub const LINE_STRIP: i32 = 4;
    /// Line list.
    pub const LINE_LIST: i32 = 5;
    /// Cube list.
    pub const CUBE_LIST: i32 = 6;
    /// Sphere list.
    pub const SPHERE_LIST: i32 = 7;
    /// Points.
    pub const POINTS: i32 = 8;
    /// Text facing the viewer.
    pub const TEXT_VIEW_FACING: i32 = 9;
    /// Add or modify.
    pub const ADD: i32 = 0;
    /// Delete one.
    pub const DELETE: i32 = 2;
    /// Delete all (in every namespace).
    pub const DELETEALL: i32 = 3;
}

ros_message!(Marker, "visualization_msgs", "Marker");

/// `visualization_msgs/MarkerArray`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct MarkerArray {
    /// Markers.
    pub markers: Vec<Marker>,
}

ros_message!(MarkerArray, "visualization_msgs", "MarkerArray");
