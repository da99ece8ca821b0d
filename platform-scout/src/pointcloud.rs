//! A `sensor_msgs/PointCloud2` decoder generic over the field layout, and an
//! encoder for publishing clouds.
//!
//! A cloud is `height` rows of `width` points; point `(row, col)` starts at
//! byte `row * row_step + col * point_step`, and each named field sits at its
//! `offset` inside the point with its `datatype` (1 `INT8` ... 8 `FLOAT64`)
//! in the cloud's byte order. Drivers pad points (`x y z _ intensity` in 32
//! bytes) and rows, order fields as they like and may be big-endian, so
//! nothing about the layout is assumed: [`CloudView::new`] validates it once
//! (typed [`CloudError`]s for every inconsistency, never a panic or an
//! out-of-bounds read) and then reads any field of any point as `f64`.
//!
//! Points with a non-finite coordinate (allowed when `is_dense` is false)
//! are skipped by the typed readers and counted.
//!
//! # Example
//! ```
//! use sornav_platform_scout::msg::{Header, PointCloud2};
//! use sornav_platform_scout::pointcloud::{CloudView, Datatype, FieldSpec, encode_cloud};
//!
//! // x, y, z as f32 and a u16 label, padded to 16 bytes per point.
//! let fields = [
//!     FieldSpec::new("x", 0, Datatype::Float32),
//!     FieldSpec::new("y", 4, Datatype::Float32),
//!     FieldSpec::new("z", 8, Datatype::Float32),
//!     FieldSpec::new("label", 12, Datatype::Uint16),
//! ];
//! let rows = [[1.0, 2.0, 0.5, 15.0], [f64::NAN, 0.0, 0.0, 1.0]];
//! let cloud: PointCloud2 = encode_cloud(Header::default(), &fields, 16, false, rows.iter().map(|r| &r[..]))?;
//!
//! let view = CloudView::new(&cloud)?;
//! assert_eq!(view.len(), 2);
//! let labelled = view.labelled_points("label")?;
//! assert_eq!(labelled.points.len(), 1); // the NaN point is skipped ...
//! assert_eq!(labelled.non_finite, 1); // ... and counted
//! assert_eq!(labelled.points[0].label.0, 15);
//! # Ok::<(), sornav_platform_scout::pointcloud::CloudError>(())
//! ```

use nalgebra::Point3;
use sornav::semantic_map::{LabelId, LabeledPoint};

use crate::msg::{Header, PointCloud2, PointField};

/// A `PointField` datatype.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Datatype {
    /// `INT8` (1).
    Int8,
    /// `UINT8` (2).
    Uint8,
    /// `INT16` (3).
    Int16,
    /// `UINT16` (4).
    Uint16,
    /// `INT32` (5).
    Int32,
    /// `UINT32` (6).
    Uint32,
    /// `FLOAT32` (7).
    Float32,
    /// `FLOAT64` (8).
    Float64,
}

impl Datatype {
    /// All eight, by code.
    pub const ALL: [Datatype; 8] = [
        Datatype::Int8,
        Datatype::Uint8,
        Datatype::Int16,
        Datatype::Uint16,
        Datatype::Int32,
        Datatype::Uint32,
        Datatype::Float32,
        Datatype::Float64,
    ];

    /// From the `sensor_msgs/PointField` code.
    pub fn from_code(code: u8) -> Option<Self> {
        (1..=8)
            .contains(&code)
            .then(|| Self::ALL[usize::from(code - 1)])
    }

    /// The `sensor_msgs/PointField` code.
    pub fn code(self) -> u8 {
        Self::ALL.iter().position(|d| *d == self).unwrap_or(0) as u8 + 1
    }

    /// Size in bytes.
    pub fn size(self) -> usize {
        match self {
            Datatype::Int8 | Datatype::Uint8 => 1,
            Datatype::Int16 | Datatype::Uint16 => 2,
            Datatype::Int32 | Datatype::Uint32 | Datatype::Float32 => 4,
            Datatype::Float64 => 8,
        }
    }
}

/// Errors of [`CloudView::new`] and the field readers.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum CloudError {
    /// A field has a datatype code outside 1..=8.
    #[error("field `{field}` has unknown datatype code {code}")]
    UnknownDatatype {
        /// The field.
        field: String,
        /// The code.
        code: u8,
    },
    /// A field has `count == 0`.
    #[error("field `{0}` has count 0")]
    ZeroCount(String),
    /// Two fields share a name.
    #[error("field `{0}` appears twice")]
    DuplicateField(String),
    /// A field does not fit inside `point_step`.
    #[error("field `{field}` (offset {offset}, {size} bytes) overruns point_step {point_step}")]
    FieldOverrun {
        /// The field.
        field: String,
        /// Its offset.
        offset: u32,
        /// Its size in bytes (`count * datatype size`).
        size: u64,
        /// The point step.
        point_step: u32,
    },
    /// `point_step` is zero while the cloud has points.
    #[error("point_step is 0 for a cloud of {0} points")]
    ZeroPointStep(u64),
    /// A row of `width` points does not fit in `row_step`.
    #[error("row_step {row_step} is shorter than width {width} x point_step {point_step}")]
    RowStepTooShort {
        /// Row step.
        row_step: u32,
        /// Width.
        width: u32,
        /// Point step.
        point_step: u32,
    },
    /// `data` is not `row_step * height` bytes long.
    #[error("data has {actual} bytes, expected row_step x height = {expected}")]
    DataLength {
        /// Expected length.
        expected: u64,
        /// Actual length.
        actual: usize,
    },
    /// The cloud has more points than this platform can index.
    #[error("cloud too large ({height} x {width})")]
    TooLarge {
        /// Rows.
        height: u32,
        /// Columns.
        width: u32,
    },
    /// A field the reader needs is missing.
    #[error("cloud has no field `{0}`")]
    MissingField(String),
}

/// One validated field: where it is and how to read it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Field {
    /// Name.
    pub name: String,
    /// Byte offset in a point.
    pub offset: usize,
    /// Datatype.
    pub datatype: Datatype,
    /// Elements.
    pub count: usize,
}

/// A validated, zero-copy view of a [`PointCloud2`].
#[derive(Debug, Clone)]
pub struct CloudView<'a> {
    cloud: &'a PointCloud2,
    fields: Vec<Field>,
    len: usize,
}

/// Points with a label, as decoded by [`CloudView::labelled_points`].
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LabelledPoints {
    /// Valid points.
    pub points: Vec<LabeledPoint>,
    /// Points skipped for a non-finite coordinate.
    pub non_finite: usize,
    /// Points skipped for a label that is not an integer in `0..=65535`.
    pub bad_label: usize,
}

/// Points with one scalar channel, as decoded by [`CloudView::points_with`].
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ScalarPoints {
    /// Valid points and their channel value.
    pub points: Vec<(Point3<f32>, f32)>,
    /// Points skipped for a non-finite coordinate or value.
    pub non_finite: usize,
}

impl<'a> CloudView<'a> {
    /// Validates the layout of `cloud`.
    ///
    /// # Errors
    /// Every [`CloudError`] except `MissingField`.
    ///
    /// # Complexity
    /// O(F^2) for F fields (duplicate check; F is tiny).
    pub fn new(cloud: &'a PointCloud2) -> Result<Self, CloudError> {
        let mut fields: Vec<Field> = Vec::with_capacity(cloud.fields.len());
        for f in &cloud.fields {
            let datatype =
                Datatype::from_code(f.datatype).ok_or_else(|| CloudError::UnknownDatatype {
                    field: f.name.clone(),
                    code: f.datatype,
                })?;
            if f.count == 0 {
                return Err(CloudError::ZeroCount(f.name.clone()));
            }
            if fields.iter().any(|g| g.name == f.name) {
                return Err(CloudError::DuplicateField(f.name.clone()));
            }
            let size = u64::from(f.count) * datatype.size() as u64;
            if u64::from(f.offset) + size > u64::from(cloud.point_step) {
                return Err(CloudError::FieldOverrun {
                    field: f.name.clone(),
                    offset: f.offset,
                    size,
                    point_step: cloud.point_step,
                });
            }
            fields.push(Field {
                name: f.name.clone(),
                offset: f.offset as usize,
                datatype,
                count: f.count as usize,
            });
        }
        let n = u64::from(cloud.width) * u64::from(cloud.height);
        if n > 0 && cloud.point_step == 0 {
            return Err(CloudError::ZeroPointStep(n));
        }
        if cloud.height > 0
            && u64::from(cloud.row_step) < u64::from(cloud.width) * u64::from(cloud.point_step)
        {
            return Err(CloudError::RowStepTooShort {
                row_step: cloud.row_step,
                width: cloud.width,
                point_step: cloud.point_step,
            });
        }
        let expected = u64::from(cloud.row_step) * u64::from(cloud.height);
        if expected != cloud.data.len() as u64 {
            return Err(CloudError::DataLength {
                expected,
                actual: cloud.data.len(),
            });
        }
        let len = usize::try_from(n).map_err(|_| CloudError::TooLarge {
            height: cloud.height,
            width: cloud.width,
        })?;
        Ok(Self { cloud, fields, len })
    }

    /// Number of points (`width * height`).
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether the cloud has no point.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The validated fields, in message order.
    pub fn fields(&self) -> &[Field] {
        &self.fields
    }

    /// The field called `name`.
    ///
    /// # Errors
    /// [`CloudError::MissingField`].
    pub fn field(&self, name: &str) -> Result<&Field, CloudError> {
        self.fields
            .iter()
            .find(|f| f.name == name)
            .ok_or_else(|| CloudError::MissingField(name.to_owned()))
    }

    /// Byte offset of point `i` (row-major).
    fn base(&self, i: usize) -> usize {
        let w = self.cloud.width as usize;
        let (row, col) = (i / w, i % w);
        row * self.cloud.row_step as usize + col * self.cloud.point_step as usize
    }

    /// Byte offset of every point, in index order (row-major): the
    /// `base(i)` of `i` in `0..len()`, without a division per point.
    fn bases(&self) -> impl Iterator<Item = usize> {
        let (row_step, point_step) = (self.cloud.row_step as usize, self.cloud.point_step as usize);
        let width = self.cloud.width as usize;
        // No row is visited when there is no point (width 0).
        let height = if self.len == 0 {
            0
        } else {
            self.cloud.height as usize
        };
        (0..height)
            .flat_map(move |row| (0..width).map(move |col| row * row_step + col * point_step))
    }

    /// Element `element` of `field` at point `i`, as `f64` (`None` when
    /// `i >= len()` or `element >= count`).
    pub fn get(&self, field: &Field, i: usize, element: usize) -> Option<f64> {
        if i >= self.len || element >= field.count {
            return None;
        }
        self.read(field, self.base(i) + element * field.datatype.size())
    }

    /// The `field` value `field.offset` bytes after `base` (the start of a
    /// point from [`bases`](Self::bases), plus the element's offset), or
    /// `None` when it lies outside `data`.
    fn read(&self, field: &Field, base: usize) -> Option<f64> {
        let start = base + field.offset;
        let bytes = self.cloud.data.get(start..start + field.datatype.size())?;
        Some(read_scalar(bytes, field.datatype, self.cloud.is_bigendian))
    }

    /// The `x`, `y`, `z` fields.
    ///
    /// # Errors
    /// [`CloudError::MissingField`].
    fn xyz_fields(&self) -> Result<[&Field; 3], CloudError> {
        Ok([self.field("x")?, self.field("y")?, self.field("z")?])
    }

    /// The finite `x`, `y`, `z` of the point starting at byte `base`.
    fn xyz_at(&self, f: &[&Field; 3], base: usize) -> Option<Point3<f64>> {
        let p = Point3::new(
            self.read(f[0], base)?,
            self.read(f[1], base)?,
            self.read(f[2], base)?,
        );
        p.iter().all(|c| c.is_finite()).then_some(p)
    }

    /// All points with finite `x`, `y`, `z`, and the number skipped.
    ///
    /// # Errors
    /// [`CloudError::MissingField`] for a missing coordinate.
    ///
    /// # Complexity
    /// O(points).
    pub fn xyz(&self) -> Result<(Vec<Point3<f64>>, usize), CloudError> {
        let f = self.xyz_fields()?;
        let mut out = Vec::with_capacity(self.len);
        let mut skipped = 0;
        for base in self.bases() {
            match self.xyz_at(&f, base) {
                Some(p) => out.push(p),
                None => skipped += 1,
            }
        }
        Ok((out, skipped))
    }

    /// Points with the value of scalar channel `name` (for example the
    /// terrain map's `intensity`, its height above the ground).
    ///
    /// # Errors
    /// [`CloudError::MissingField`].
    ///
    /// # Complexity
    /// O(points).
    pub fn points_with(&self, name: &str) -> Result<ScalarPoints, CloudError> {
        let f = self.xyz_fields()?;
        let v = self.field(name)?;
        let mut out = ScalarPoints {
            points: Vec::with_capacity(self.len),
            non_finite: 0,
        };
        for base in self.bases() {
            match (self.xyz_at(&f, base), self.read(v, base)) {
                (Some(p), Some(value)) if value.is_finite() => {
                    out.points.push((p.cast::<f32>(), value as f32))
                }
                _ => out.non_finite += 1,
            }
        }
        Ok(out)
    }

    /// Points with their semantic label read from channel `label_field` (any
    /// datatype; a float label must be an integer value). Points with a
    /// non-finite coordinate or a label outside `0..=65535` are skipped and
    /// counted.
    ///
    /// # Errors
    /// [`CloudError::MissingField`].
    ///
    /// # Complexity
    /// O(points).
    pub fn labelled_points(&self, label_field: &str) -> Result<LabelledPoints, CloudError> {
        let f = self.xyz_fields()?;
        let l = self.field(label_field)?;
        let mut out = LabelledPoints {
            points: Vec::with_capacity(self.len),
            ..LabelledPoints::default()
        };
        for base in self.bases() {
            let Some(p) = self.xyz_at(&f, base) else {
                out.non_finite += 1;
                continue;
            };
            let label = self.read(l, base).unwrap_or(f64::NAN);
            if !(label.fract() == 0.0 && (0.0..=f64::from(u16::MAX)).contains(&label)) {
                out.bad_label += 1;
                continue;
            }
            out.points.push(LabeledPoint::new(
                p.x as f32,
                p.y as f32,
                p.z as f32,
                LabelId(label as u16),
            ));
        }
        Ok(out)
    }
}

fn read_scalar(b: &[u8], t: Datatype, big: bool) -> f64 {
    macro_rules! num {
        ($ty:ty, $n:literal) => {{
            let mut a = [0u8; $n];
            a.copy_from_slice(&b[..$n]);
            if big {
                <$ty>::from_be_bytes(a)
            } else {
                <$ty>::from_le_bytes(a)
            }
        }};
    }
    match t {
        Datatype::Int8 => f64::from(b[0] as i8),
        Datatype::Uint8 => f64::from(b[0]),
        Datatype::Int16 => f64::from(num!(i16, 2)),
        Datatype::Uint16 => f64::from(num!(u16, 2)),
        Datatype::Int32 => f64::from(num!(i32, 4)),
        Datatype::Uint32 => f64::from(num!(u32, 4)),
        Datatype::Float32 => f64::from(num!(f32, 4)),
        Datatype::Float64 => num!(f64, 8),
    }
}

fn write_scalar(out: &mut [u8], t: Datatype, big: bool, v: f64) {
    macro_rules! put {
        ($val:expr) => {{
            let val = $val;
            let bytes = if big {
                val.to_be_bytes()
            } else {
                val.to_le_bytes()
            };
            out[..bytes.len()].copy_from_slice(&bytes);
        }};
    }
    // `as` saturates out-of-range floats and maps NaN to 0 for integers.
    match t {
        Datatype::Int8 => put!(v as i8),
        Datatype::Uint8 => put!(v as u8),
        Datatype::Int16 => put!(v as i16),
        Datatype::Uint16 => put!(v as u16),
        Datatype::Int32 => put!(v as i32),
        Datatype::Uint32 => put!(v as u32),
        Datatype::Float32 => put!(v as f32),
        Datatype::Float64 => put!(v),
    }
}

/// A scalar field of a cloud to encode.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FieldSpec {
    /// Name.
    pub name: String,
    /// Byte offset inside a point.
    pub offset: u32,
    /// Datatype.
    pub datatype: Datatype,
}

impl FieldSpec {
    /// A scalar field.
    pub fn new(name: impl Into<String>, offset: u32, datatype: Datatype) -> Self {
        Self {
            name: name.into(),
            offset,
            datatype,
        }
    }
}

/// Encodes an unorganised cloud (`height = 1`): one row of `values`
/// (aligned with `fields`) per point, `point_step` bytes per point (bytes
/// not covered by a field are zero), in the given byte order. `is_dense` is
/// set when every coordinate written is finite.
///
/// # Errors
/// The layout errors of [`CloudView::new`] (overrunning or duplicate
/// fields), and [`CloudError::MissingField`] when a row is shorter than
/// `fields`.
///
/// # Complexity
/// O(points x fields).
pub fn encode_cloud<'v>(
    header: Header,
    fields: &[FieldSpec],
    point_step: u32,
    big_endian: bool,
    rows: impl IntoIterator<Item = &'v [f64]>,
) -> Result<PointCloud2, CloudError> {
    let mut cloud = PointCloud2 {
        header,
        height: 1,
        width: 0,
        fields: fields
            .iter()
            .map(|f| PointField {
                name: f.name.clone(),
                offset: f.offset,
                datatype: f.datatype.code(),
                count: 1,
            })
            .collect(),
        is_bigendian: big_endian,
        point_step,
        row_step: 0,
        data: Vec::new(),
        is_dense: true,
    };
    // Validate the layout on an empty cloud first.
    CloudView::new(&cloud)?;
    let step = point_step as usize;
    // Whether each field is a coordinate (a non-finite one clears is_dense).
    let coordinate: Vec<bool> = fields
        .iter()
        .map(|f| matches!(f.name.as_str(), "x" | "y" | "z"))
        .collect();
    let mut width: u32 = 0;
    for row in rows {
        if row.len() < fields.len() {
            let missing = &fields[row.len()].name;
            return Err(CloudError::MissingField(missing.clone()));
        }
        let start = cloud.data.len();
        cloud.data.resize(start + step, 0);
        for ((f, &v), &coordinate) in fields.iter().zip(row).zip(&coordinate) {
            if coordinate && !v.is_finite() {
                cloud.is_dense = false;
            }
            let o = start + f.offset as usize;
            write_scalar(&mut cloud.data[o..], f.datatype, big_endian, v);
        }
        width = width.checked_add(1).ok_or(CloudError::TooLarge {
            height: 1,
            width: u32::MAX,
        })?;
    }
    cloud.width = width;
    cloud.row_step =
        u32::try_from(cloud.data.len()).map_err(|_| CloudError::TooLarge { height: 1, width })?;
    Ok(cloud)
}

/// A cloud in the [`xyzl_fields`] layout (little-endian) from
/// `[x, y, z, label]` rows: what `/semantic_scan` publishers send.
///
/// # Errors
/// As [`encode_cloud`] (only [`CloudError::TooLarge`] can occur).
pub fn encode_xyzl(header: Header, rows: &[[f64; 4]]) -> Result<PointCloud2, CloudError> {
    encode_cloud(
        header,
        &xyzl_fields(),
        16,
        false,
        rows.iter().map(|r| &r[..]),
    )
}

/// A cloud in PCL's padded [`xyzi_fields`] layout (little-endian) from
/// `[x, y, z, intensity]` rows: what the CMU stack sends on
/// `/registered_scan` and `/terrain_map`.
///
/// # Errors
/// As [`encode_cloud`] (only [`CloudError::TooLarge`] can occur).
pub fn encode_xyzi(header: Header, rows: &[[f64; 4]]) -> Result<PointCloud2, CloudError> {
    let (fields, step) = xyzi_fields();
    encode_cloud(header, &fields, step, false, rows.iter().map(|r| &r[..]))
}

/// The packed `x y z label` layout of `/semantic_scan` as published by
/// this crate: three `FLOAT32` and a `UINT32` label, 16 bytes (PCL's
/// `PointXYZL`; the decoder accepts a label of any datatype).
pub fn xyzl_fields() -> Vec<FieldSpec> {
    vec![
        FieldSpec::new("x", 0, Datatype::Float32),
        FieldSpec::new("y", 4, Datatype::Float32),
        FieldSpec::new("z", 8, Datatype::Float32),
        FieldSpec::new("label", 12, Datatype::Uint32),
    ]
}

/// PCL's `PointXYZI` layout (what the CMU stack publishes on
/// `/registered_scan` and `/terrain_map`): x, y, z, 4 bytes of padding,
/// intensity, padded to 32 bytes.
pub fn xyzi_fields() -> (Vec<FieldSpec>, u32) {
    (
        vec![
            FieldSpec::new("x", 0, Datatype::Float32),
            FieldSpec::new("y", 4, Datatype::Float32),
            FieldSpec::new("z", 8, Datatype::Float32),
            FieldSpec::new("intensity", 16, Datatype::Float32),
        ],
        32,
    )
}
