//! The depth-frame path: back-projecting a pinhole depth image and its
//! per-pixel label image into the world frame.

use nalgebra::{Isometry3, Point3, Rotation3, Translation3, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

use crate::error::MapError;
use crate::integrate::{Inserter, IntegrationStats};
use crate::label::LabelId;
use crate::map::SemanticMap;

/// Pinhole intrinsics in the OpenCV convention: pixel `(u, v)` (column,
/// row, integers from 0) has image coordinates `(u, v)`, the optical frame
/// has x right, y down, z forward, and a point `(X, Y, Z)` projects to
/// `u = fx X / Z + cx`, `v = fy Y / Z + cy`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PinholeCamera {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Focal length along u (pixels).
    pub fx: f64,
    /// Focal length along v (pixels).
    pub fy: f64,
    /// Principal point u (pixels).
    pub cx: f64,
    /// Principal point v (pixels).
    pub cy: f64,
}

impl PinholeCamera {
    /// Square-pixel camera with horizontal field of view `hfov` (radians),
    /// principal point at the image centre (`(w - 1) / 2`, `(h - 1) / 2`).
    /// The paper's camera is `from_hfov(640, 480, 79f64.to_radians())`
    /// (fx = fy = 388.2).
    pub fn from_hfov(width: u32, height: u32, hfov: f64) -> Self {
        let f = f64::from(width) / 2.0 / (hfov / 2.0).tan();
        Self {
            width,
            height,
            fx: f,
            fy: f,
            cx: (f64::from(width) - 1.0) / 2.0,
            cy: (f64::from(height) - 1.0) / 2.0,
        }
    }

    /// Checks the intrinsics.
    ///
    /// # Errors
    /// [`MapError::InvalidIntrinsics`] for non-finite values or non-positive
    /// focal lengths.
    pub fn validate(&self) -> Result<(), MapError> {
        if !(self.fx.is_finite() && self.fy.is_finite() && self.fx > 0.0 && self.fy > 0.0) {
            return Err(MapError::InvalidIntrinsics(
                "focal lengths must be finite and > 0".into(),
            ));
        }
        if !(self.cx.is_finite() && self.cy.is_finite()) {
            return Err(MapError::InvalidIntrinsics(
                "principal point must be finite".into(),
            ));
        }
        Ok(())
    }

    /// Back-projects pixel `(u, v)` with z-depth `depth` into the optical frame.
    pub fn back_project(&self, u: f64, v: f64, depth: f64) -> Point3<f64> {
        Point3::new(
            (u - self.cx) / self.fx * depth,
            (v - self.cy) / self.fy * depth,
            depth,
        )
    }
}

/// Pose of a level camera (optical frame) in a z-up world: at `eye`,
/// looking along heading `yaw` (radians from +x towards +y), tilted down
/// by `pitch` (radians). Returns the camera-to-world isometry expected by
/// [`SemanticMap::integrate_depth`].
pub fn optical_pose(eye: &Point3<f64>, yaw: f64, pitch: f64) -> Isometry3<f64> {
    // Body frame: x forward, y left, z up. Optical: x right, y down, z forward.
    let optical_in_body = Rotation3::from_matrix_unchecked(nalgebra::Matrix3::new(
        0.0, 0.0, 1.0, //
        -1.0, 0.0, 0.0, //
        0.0, -1.0, 0.0,
    ));
    let body = Rotation3::from_axis_angle(&Vector3::z_axis(), yaw)
        * Rotation3::from_axis_angle(&Vector3::y_axis(), pitch);
    Isometry3::from_parts(
        Translation3::from(eye.coords),
        UnitQuaternion::from_rotation_matrix(&(body * optical_in_body)),
    )
}

/// Depth window and pixel stride for [`SemanticMap::integrate_depth`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct DepthOptions {
    /// Smallest accepted z-depth (metres; paper 0.5).
    pub min_depth: f64,
    /// Largest accepted z-depth (metres; paper 5.0).
    pub max_depth: f64,
    /// Use every `stride`-th pixel in u and v (1 = every pixel).
    pub stride: u32,
}

impl Default for DepthOptions {
    fn default() -> Self {
        Self {
            min_depth: 0.5,
            max_depth: 5.0,
            stride: 1,
        }
    }
}

impl DepthOptions {
    /// Checks `stride >= 1` and a finite window `0 <= min_depth < max_depth`.
    ///
    /// # Errors
    /// [`MapError::InvalidConfig`] naming the first bad field.
    pub fn validate(&self) -> Result<(), MapError> {
        if self.stride == 0 {
            return Err(MapError::InvalidConfig("depth stride must be >= 1".into()));
        }
        let (dmin, dmax) = (self.min_depth, self.max_depth);
        if !(dmin.is_finite() && dmax.is_finite() && dmin >= 0.0 && dmax > dmin) {
            return Err(MapError::InvalidConfig(
                "depth window must satisfy 0 <= min_depth < max_depth (finite)".into(),
            ));
        }
        Ok(())
    }
}

/// One labelled depth image: row-major z-depth (metres; 0, NaN or
/// infinity mark missing returns) and a label per pixel.
#[derive(Debug, Clone, Copy)]
pub struct DepthFrame<'a> {
    /// Intrinsics and image size.
    pub camera: &'a PinholeCamera,
    /// Camera-to-world pose of the optical frame.
    pub pose: &'a Isometry3<f64>,
    /// `width * height` z-depth values, row-major.
    pub depth: &'a [f32],
    /// `width * height` labels, row-major.
    pub labels: &'a [LabelId],
}

impl SemanticMap {
    /// Back-projects a labelled depth image and fuses the points.
    ///
    /// Pixel `(u, v)` with depth `d` in `[min_depth, max_depth]` becomes the
    /// world point `pose * camera.back_project(u, v, d)`. Pixels with a
    /// non-finite depth are counted in `rejected_non_finite`, depths outside
    /// the window (including 0) in `rejected_range`, world points beyond
    /// `max_abs_coordinate` in `rejected_bounds`. The map's `min_range` /
    /// `max_range` do not apply (the depth window replaces them).
    /// `stats.points` counts visited pixels (after the stride).
    ///
    /// # Errors
    /// [`MapError::FrameSize`] when the buffers do not hold
    /// `width * height` values, [`MapError::InvalidIntrinsics`],
    /// [`MapError::NonFinitePose`], or [`MapError::InvalidConfig`] for a bad
    /// depth window or a zero stride. Nothing is integrated on error.
    ///
    /// # Complexity
    /// O(width x height / stride^2); per pixel one fused multiply-add of
    /// precomputed row and column rays plus the point path's O(1) update.
    pub fn integrate_depth(
        &mut self,
        frame: &DepthFrame<'_>,
        options: &DepthOptions,
    ) -> Result<IntegrationStats, MapError> {
        let cam = frame.camera;
        cam.validate()?;
        let (w, h) = (cam.width as usize, cam.height as usize);
        let n = w.checked_mul(h);
        if n != Some(frame.depth.len()) || n != Some(frame.labels.len()) {
            return Err(MapError::FrameSize {
                width: cam.width,
                height: cam.height,
                depth: frame.depth.len(),
                labels: frame.labels.len(),
            });
        }
        let pose = frame.pose;
        let finite_pose = pose.translation.vector.iter().all(|c| c.is_finite())
            && pose.rotation.coords.iter().all(|c| c.is_finite());
        if !finite_pose {
            return Err(MapError::NonFinitePose);
        }
        options.validate()?;
        let window = (options.min_depth, options.max_depth);
        let rot = pose.rotation.to_rotation_matrix();
        let t = pose.translation.vector;
        let stride = options.stride as usize;
        // World-frame ray of pixel (u, v) per unit z-depth = cols[u] + rows[v].
        let cols: Vec<Vector3<f64>> = (0..w)
            .step_by(stride)
            .map(|u| rot * Vector3::new((u as f64 - cam.cx) / cam.fx, 0.0, 0.0))
            .collect();
        let rows: Vec<Vector3<f64>> = (0..h)
            .step_by(stride)
            .map(|v| rot * Vector3::new(0.0, (v as f64 - cam.cy) / cam.fy, 1.0))
            .collect();
        let mut ins = Inserter::new(self);
        let within = frame_within_bound(&t, &cols, &rows, window.1, ins.bound());
        for (v, row) in (0..h).step_by(stride).zip(&rows) {
            let depth_row = &frame.depth[v * w..(v + 1) * w];
            let label_row = &frame.labels[v * w..(v + 1) * w];
            ins.stats.points += cols.len() as u64;
            let ray = Ray { t: &t, row, window };
            if stride == 1 {
                ray.fuse(&mut ins, cols.iter().zip(depth_row).zip(label_row), within);
            } else {
                let pixels = cols
                    .iter()
                    .zip(depth_row.iter().step_by(stride))
                    .zip(label_row.iter().step_by(stride));
                ray.fuse(&mut ins, pixels, within);
            }
        }
        let stats = ins.finish();
        self.integrations += 1;
        Ok(stats)
    }
}

/// Whether every point a frame can produce, `t + (col + row) * d` with
/// `d <= max_depth` for any of the column and row rays, lies within
/// `bound` on every axis, by a relative margin far above the rounding of
/// the few operations that compute a point: then no point needs the
/// per-point bound check. Non-finite rays never pass.
fn frame_within_bound(
    t: &Vector3<f64>,
    cols: &[Vector3<f64>],
    rows: &[Vector3<f64>],
    max_depth: f64,
    bound: f64,
) -> bool {
    let reach = |rays: &[Vector3<f64>]| {
        rays.iter()
            .flat_map(|r| r.iter())
            .try_fold(0.0f64, |m, c| c.is_finite().then(|| m.max(c.abs())))
    };
    let (Some(col), Some(row)) = (reach(cols), reach(rows)) else {
        return false;
    };
    let extent = t.amax() + (col + row) * max_depth;
    extent.is_finite() && extent * (1.0 + 1e-9) <= bound
}

/// One image row's rays: the camera position `t`, the row's part of the
/// pixel rays and the depth window `(min, max)`.
struct Ray<'a> {
    t: &'a Vector3<f64>,
    row: &'a Vector3<f64>,
    window: (f64, f64),
}

impl Ray<'_> {
    /// Fuses a row's pixels (column ray, depth, label) in order; `within`:
    /// [`frame_within_bound`] holds, so no per-point bound check.
    #[inline(always)]
    fn fuse<'p>(
        &self,
        ins: &mut Inserter<'_>,
        pixels: impl Iterator<Item = ((&'p Vector3<f64>, &'p f32), &'p LabelId)>,
        within: bool,
    ) {
        if within {
            self.fuse_pixels::<false>(ins, pixels);
        } else {
            self.fuse_pixels::<true>(ins, pixels);
        }
    }

    /// [`fuse`](Self::fuse), with the per-point bound check when `CHECKED`.
    #[inline(always)]
    fn fuse_pixels<'p, const CHECKED: bool>(
        &self,
        ins: &mut Inserter<'_>,
        pixels: impl Iterator<Item = ((&'p Vector3<f64>, &'p f32), &'p LabelId)>,
    ) {
        let (t, row, (dmin, dmax)) = (self.t, self.row, self.window);
        for ((col, &depth), &label) in pixels {
            let d = f64::from(depth);
            // False for NaN and, the window being finite, for infinities.
            if !(dmin <= d && d <= dmax) {
                if d.is_finite() {
                    ins.stats.rejected_range += 1;
                } else {
                    ins.stats.rejected_non_finite += 1;
                }
                continue;
            }
            // `t + (col + row) * d`, operation for operation.
            let x = t.x + (col.x + row.x) * d;
            let y = t.y + (col.y + row.y) * d;
            let z = t.z + (col.z + row.z) * d;
            if CHECKED {
                ins.insert(x, y, z, label);
            } else {
                ins.insert_within_bound(x, y, z, label);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{LabelSet, MapConfig, VoxelKey};
    use approx::assert_relative_eq;
    use proptest::prelude::*;

    #[test]
    fn back_projection_hand_computed() {
        // fx = 100, fy = 50, cx = 2, cy = 1 on a 5x3 image.
        let cam = PinholeCamera {
            width: 5,
            height: 3,
            fx: 100.0,
            fy: 50.0,
            cx: 2.0,
            cy: 1.0,
        };
        // Principal pixel lies on the optical axis.
        assert_relative_eq!(cam.back_project(2.0, 1.0, 3.0), Point3::new(0.0, 0.0, 3.0));
        // (4, 0) at depth 2: X = (4-2)/100*2 = 0.04, Y = (0-1)/50*2 = -0.04.
        assert_relative_eq!(
            cam.back_project(4.0, 0.0, 2.0),
            Point3::new(0.04, -0.04, 2.0),
            epsilon = 1e-12
        );
        let c = PinholeCamera::from_hfov(640, 480, 79f64.to_radians());
        assert_relative_eq!(c.fx, 388.2, epsilon = 0.05);
        assert_relative_eq!(c.cx, 319.5);
    }

    #[test]
    fn optical_pose_axes() {
        // Looking along +y from (1, 2, 0.88): forward is +y, left is -x,
        // so optical x (right) is +x and optical y (down) is -z.
        let pose = optical_pose(
            &Point3::new(1.0, 2.0, 0.88),
            std::f64::consts::FRAC_PI_2,
            0.0,
        );
        let fwd = pose * Point3::new(0.0, 0.0, 1.0);
        assert_relative_eq!(fwd, Point3::new(1.0, 3.0, 0.88), epsilon = 1e-12);
        let right = pose * Point3::new(1.0, 0.0, 0.0);
        assert_relative_eq!(right, Point3::new(2.0, 2.0, 0.88), epsilon = 1e-12);
        let down = pose * Point3::new(0.0, 1.0, 0.0);
        assert_relative_eq!(down, Point3::new(1.0, 2.0, -0.12), epsilon = 1e-12);
    }

    #[test]
    fn depth_pixels_land_in_hand_computed_voxels() {
        let cam = PinholeCamera {
            width: 3,
            height: 2,
            fx: 10.0,
            fy: 10.0,
            cx: 1.0,
            cy: 0.5,
        };
        // Camera at (0.1, 0.1, 1) looking along +x (yaw 0): right = -y, down = -z.
        let pose = optical_pose(&Point3::new(0.1, 0.1, 1.0), 0.0, 0.0);
        let depth = [2.0, 2.0, f32::NAN, 0.0, 9.0, 2.0];
        let labels = [10, 11, 12, 13, 14, 15].map(LabelId);
        let frame = DepthFrame {
            camera: &cam,
            pose: &pose,
            depth: &depth,
            labels: &labels,
        };
        let mut map = SemanticMap::new(MapConfig::with_resolution(0.25), LabelSet::new()).unwrap();
        let s = map
            .integrate_depth(&frame, &DepthOptions::default())
            .unwrap();
        assert_eq!(s.points, 6);
        assert_eq!(s.accepted, 3);
        assert_eq!(s.rejected_non_finite, 1);
        assert_eq!(s.rejected_range, 2); // 0.0 and 9.0 outside [0.5, 5]
        // Pixel (0, 0), d = 2: optical (-0.2, -0.1, 2) -> world (2.1, 0.3, 1.1).
        assert_eq!(map.object_label(&VoxelKey::new(8, 1, 4)), Some(LabelId(10)));
        // Pixel (1, 0): optical (0, -0.1, 2) -> world (2.1, 0.1, 1.1).
        assert_eq!(map.object_label(&VoxelKey::new(8, 0, 4)), Some(LabelId(11)));
        // Pixel (2, 1): optical (0.2, 0.1, 2) -> world (2.1, -0.1, 0.9).
        assert_eq!(
            map.object_label(&VoxelKey::new(8, -1, 3)),
            Some(LabelId(15))
        );
        assert_eq!(map.voxel_count(), 3);

        // Stride 2 visits (0,0) and (2,0) only (rows 0).
        let mut map2 = SemanticMap::new(MapConfig::with_resolution(0.25), LabelSet::new()).unwrap();
        let opts = DepthOptions {
            stride: 2,
            ..DepthOptions::default()
        };
        let s = map2.integrate_depth(&frame, &opts).unwrap();
        assert_eq!((s.points, s.accepted, s.rejected_non_finite), (2, 1, 1));
    }

    /// The per-pixel path as first written (every pixel through the
    /// bound-checked [`Inserter::insert`], a range test per pixel, the
    /// rays summed as vectors): the reference the row kernel must
    /// reproduce, state and counters alike.
    fn reference_integrate_depth(
        map: &mut SemanticMap,
        frame: &DepthFrame<'_>,
        options: &DepthOptions,
    ) -> IntegrationStats {
        let cam = frame.camera;
        let (w, h) = (cam.width as usize, cam.height as usize);
        let (dmin, dmax) = (options.min_depth, options.max_depth);
        let rot = frame.pose.rotation.to_rotation_matrix();
        let t = frame.pose.translation.vector;
        let stride = options.stride as usize;
        let col: Vec<Vector3<f64>> = (0..w)
            .step_by(stride)
            .map(|u| rot * Vector3::new((u as f64 - cam.cx) / cam.fx, 0.0, 0.0))
            .collect();
        let mut ins = Inserter::new(map);
        for v in (0..h).step_by(stride) {
            let row = rot * Vector3::new(0.0, (v as f64 - cam.cy) / cam.fy, 1.0);
            for (ci, u) in (0..w).step_by(stride).enumerate() {
                ins.stats.points += 1;
                let d = f64::from(frame.depth[v * w + u]);
                if !d.is_finite() {
                    ins.stats.rejected_non_finite += 1;
                    continue;
                }
                if !(dmin..=dmax).contains(&d) {
                    ins.stats.rejected_range += 1;
                    continue;
                }
                let p = t + (col[ci] + row) * d;
                ins.insert(p.x, p.y, p.z, frame.labels[v * w + u]);
            }
        }
        let stats = ins.finish();
        map.integrations += 1;
        stats
    }

    /// A depth value: mostly in a window around `[0.5, 5]`, sometimes
    /// missing (0, NaN, infinities) or negative.
    fn depth_value() -> impl Strategy<Value = f32> {
        prop_oneof![
            6 => 0.3f32..6.0,
            1 => Just(0.0f32),
            1 => Just(f32::NAN),
            1 => Just(f32::INFINITY),
            1 => Just(f32::NEG_INFINITY),
            1 => -1.0f32..0.0,
        ]
    }

    proptest! {
        /// The row kernel (frame-wide bound test, per-row rays, merged
        /// window test) gives the same map, block order, pending changes
        /// and counters as the per-pixel reference, over frames with
        /// missing and out-of-window depths, strides, poses near and
        /// beyond the coordinate bound, and runs that continue across rows
        /// and frames.
        #[test]
        fn row_kernel_matches_per_pixel_reference(
            (w, h) in (1u32..12, 1u32..10),
            f in 2.0f64..40.0,
            centre in (-3.0f64..3.0, -3.0f64..3.0),
            eye in (-6.0f64..6.0, -6.0f64..6.0, -1.0f64..3.0),
            yaw in -3.2f64..3.2,
            pitch in -0.6f64..0.6,
            resolution in prop_oneof![Just(0.05), Just(0.25), Just(1.0)],
            bound in prop_oneof![Just(100_000.0), Just(4.0), Just(8.0)],
            stride in 1u32..4,
            frames in prop::collection::vec(
                (prop::collection::vec(depth_value(), 132), prop::collection::vec(0u16..4, 132)),
                1..3,
            ),
        ) {
            let cam = PinholeCamera {
                width: w,
                height: h,
                fx: f,
                fy: f * 1.1,
                cx: f64::from(w) / 2.0 + centre.0,
                cy: f64::from(h) / 2.0 + centre.1,
            };
            let pose = optical_pose(&Point3::new(eye.0, eye.1, eye.2), yaw, pitch);
            let config = MapConfig {
                max_abs_coordinate: bound,
                ..MapConfig::with_resolution(resolution)
            };
            let labels = LabelSet::household();
            let mut fast = SemanticMap::new(config, labels.clone()).unwrap();
            let mut slow = SemanticMap::new(config, labels).unwrap();
            let options = DepthOptions { stride, ..DepthOptions::default() };
            let n = (w * h) as usize;
            for (depth, label) in &frames {
                let label: Vec<LabelId> = label[..n].iter().map(|&l| LabelId(l)).collect();
                let frame = DepthFrame { camera: &cam, pose: &pose, depth: &depth[..n], labels: &label };
                let a = fast.integrate_depth(&frame, &options).unwrap();
                let b = reference_integrate_depth(&mut slow, &frame, &options);
                prop_assert_eq!(a, b);
                prop_assert_eq!(&fast.grid.keys, &slow.grid.keys);
                prop_assert_eq!(&fast.dirty, &slow.dirty);
                prop_assert_eq!(&fast.touched, &slow.touched);
                prop_assert_eq!(fast.snapshot(), slow.snapshot());
            }
        }
    }

    #[test]
    fn malformed_frames_are_errors() {
        let cam = PinholeCamera::from_hfov(4, 2, 1.0);
        let pose = Isometry3::identity();
        let mut map = SemanticMap::new(MapConfig::default(), LabelSet::new()).unwrap();
        let depth = [1.0f32; 8];
        let labels = [LabelId(1); 7];
        let f = DepthFrame {
            camera: &cam,
            pose: &pose,
            depth: &depth,
            labels: &labels,
        };
        assert!(matches!(
            map.integrate_depth(&f, &DepthOptions::default()),
            Err(MapError::FrameSize { .. })
        ));
        let labels = [LabelId(1); 8];
        let f = DepthFrame {
            labels: &labels,
            ..f
        };
        for opts in [
            DepthOptions {
                stride: 0,
                ..DepthOptions::default()
            },
            DepthOptions {
                min_depth: f64::NAN,
                ..DepthOptions::default()
            },
        ] {
            assert!(map.integrate_depth(&f, &opts).is_err());
        }
        let bad_cam = PinholeCamera { fx: 0.0, ..cam };
        let f2 = DepthFrame {
            camera: &bad_cam,
            ..f
        };
        assert!(map.integrate_depth(&f2, &DepthOptions::default()).is_err());
        let bad_pose = Isometry3::translation(f64::NAN, 0.0, 0.0);
        let f3 = DepthFrame {
            pose: &bad_pose,
            ..f
        };
        assert_eq!(
            map.integrate_depth(&f3, &DepthOptions::default()),
            Err(MapError::NonFinitePose)
        );
        assert_eq!(map.integrations(), 0);
        assert!(map.integrate_depth(&f, &DepthOptions::default()).is_ok());
    }
}
