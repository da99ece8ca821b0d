//! What the platform tells the agent: the robot pose and one sensor frame.

use nalgebra::{Isometry3, Point2, Point3};
use serde::{Deserialize, Serialize};
use sornav_executor::RobotPose;
use sornav_semantic_map::{DepthOptions, LabelId, LabeledPoint, PinholeCamera};

use crate::error::ObservationError;
use crate::view::Viewer;

/// One labelled depth image with pinhole intrinsics.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DepthObservation {
    /// Intrinsics and image size.
    pub camera: PinholeCamera,
    /// Camera-to-world pose of the optical frame (z forward, x right, y
    /// down; see `sornav_semantic_map::optical_pose`).
    pub camera_pose: Isometry3<f64>,
    /// `width * height` z-depths (m), row-major; 0, NaN or infinity mark a
    /// missing return.
    pub depth: Vec<f32>,
    /// `width * height` semantic labels, row-major.
    pub labels: Vec<LabelId>,
}

/// A labelled point cloud already in the world frame (LiDAR plus a
/// segmentation, or a fused cloud).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CloudObservation {
    /// Sensor origin (world frame) the rays start from.
    pub origin: Point3<f64>,
    /// Labelled world-frame returns.
    pub points: Vec<LabeledPoint>,
}

/// Unlabelled world-frame returns for the occupancy grid only (a LiDAR
/// scan, a terrain map): they carve free space and mark obstacles but never
/// touch the semantic map or the target gate, so a 360-degree scan cannot
/// dilute the label evidence of voxels the segmentation saw.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct OccupancyObservation {
    /// Sensor origin (world frame) the rays start from.
    pub origin: Point3<f64>,
    /// World-frame returns.
    pub points: Vec<Point3<f64>>,
}

/// The sensor part of an [`Observation`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum Sensor {
    /// A depth + semantic image.
    Depth(DepthObservation),
    /// A labelled world-frame cloud.
    Cloud(CloudObservation),
    /// Unlabelled returns for the occupancy grid only.
    Occupancy(OccupancyObservation),
}

/// One observation: the robot's base pose (on the floor, yaw about z) and
/// the sensor frame taken there.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Observation {
    /// Robot base pose.
    pub pose: RobotPose,
    /// The sensor frame.
    pub sensor: Sensor,
}

/// What [`Agent::observe`](crate::Agent::observe) did with an observation.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct ObservationReport {
    /// Points (or visited pixels) in the frame.
    pub points: u64,
    /// Points fused into the semantic map.
    pub semantic_accepted: u64,
    /// Points the semantic map rejected (non-finite, out of range or
    /// bounds), counted, never fused.
    pub semantic_rejected: u64,
    /// Points given to the occupancy grid.
    pub occupancy_points: u64,
    /// Points kept out of the occupancy grid (non-finite, or a missing /
    /// too-near depth).
    pub occupancy_rejected: u64,
    /// Free-floor points added under the robot's footprint
    /// ([`AgentConfig::footprint_free_radius_m`](crate::AgentConfig::footprint_free_radius_m)).
    pub footprint_points: u64,
    /// Positions without floor given to the occupancy grid as drop-offs
    /// ([`AgentConfig::voids_from_missing_depth`](crate::AgentConfig::voids_from_missing_depth)).
    pub void_points: u64,
    /// Object clusters after the update.
    pub objects: usize,
    /// Clusters of the target category detected in this frame.
    pub target_detections: usize,
    /// Frontiers added by the update.
    pub frontiers_added: usize,
    /// Frontiers removed by the update.
    pub frontiers_removed: usize,
}

fn finite3(p: &Point3<f64>) -> bool {
    p.x.is_finite() && p.y.is_finite() && p.z.is_finite()
}

impl Observation {
    /// Checks the pose, intrinsics and buffer sizes.
    ///
    /// # Errors
    /// The matching [`ObservationError`].
    pub fn validate(&self) -> Result<(), ObservationError> {
        if !self.pose.is_finite() {
            return Err(ObservationError::NonFinitePose);
        }
        match &self.sensor {
            Sensor::Depth(d) => {
                d.camera
                    .validate()
                    .map_err(|e| ObservationError::InvalidIntrinsics(e.to_string()))?;
                let pose = &d.camera_pose;
                if !(pose.translation.vector.iter().all(|c| c.is_finite())
                    && pose.rotation.coords.iter().all(|c| c.is_finite()))
                {
                    return Err(ObservationError::NonFiniteSensorPose);
                }
                let n = (d.camera.width as usize).checked_mul(d.camera.height as usize);
                if n != Some(d.depth.len()) || n != Some(d.labels.len()) {
                    return Err(ObservationError::FrameSize {
                        width: d.camera.width,
                        height: d.camera.height,
                        depth: d.depth.len(),
                        labels: d.labels.len(),
                    });
                }
                if n == Some(0) {
                    return Err(ObservationError::Empty);
                }
            }
            Sensor::Cloud(c) => {
                if !finite3(&c.origin) {
                    return Err(ObservationError::NonFiniteSensorPose);
                }
                if c.points.is_empty() {
                    return Err(ObservationError::Empty);
                }
            }
            Sensor::Occupancy(o) => {
                if !finite3(&o.origin) {
                    return Err(ObservationError::NonFiniteSensorPose);
                }
                if o.points.is_empty() {
                    return Err(ObservationError::Empty);
                }
            }
        }
        Ok(())
    }

    /// The sensor origin of the frame.
    pub fn origin(&self) -> Point3<f64> {
        match &self.sensor {
            Sensor::Depth(d) => Point3::from(d.camera_pose.translation.vector),
            Sensor::Cloud(c) => c.origin,
            Sensor::Occupancy(o) => o.origin,
        }
    }

    /// How the frame's sensor sees, for the stop-in-view check: its height
    /// above the robot's feet and, for a depth camera, half its vertical
    /// field of view (`atan(height / 2 / fy)`, the camera held level). A
    /// labelled cloud has no vertical limit; an occupancy-only frame says
    /// nothing (`None`).
    pub(crate) fn viewer(&self) -> Option<Viewer> {
        let eye_height = self.origin().z - self.pose.position.z;
        match &self.sensor {
            Sensor::Depth(d) => Some(Viewer {
                eye_height,
                half_vfov: Some((f64::from(d.camera.height) / 2.0 / d.camera.fy).atan()),
            }),
            Sensor::Cloud(_) => Some(Viewer {
                eye_height,
                half_vfov: None,
            }),
            Sensor::Occupancy(_) => None,
        }
    }

    /// The frame's returns as world points for the occupancy grid, and the
    /// number left out.
    ///
    /// Depth pixels are back-projected with the depth window's stride, or
    /// a larger one so that at most `max_columns` columns are used (`0`: no
    /// limit; see [`occupancy_stride`]); a depth below `min_depth`, zero,
    /// NaN or infinite is left out (no information); a depth beyond
    /// `max_depth` is kept (the grid only carves free space along returns
    /// beyond its range). Non-finite cloud and occupancy points are left out.
    ///
    /// # Complexity
    /// O(pixels / stride^2) or O(points).
    pub fn occupancy_points(
        &self,
        options: &DepthOptions,
        max_columns: u32,
    ) -> (Vec<Point3<f64>>, u64) {
        let mut rejected = 0;
        let points = match &self.sensor {
            Sensor::Depth(d) => {
                let stride = occupancy_stride(options.stride, d.camera.width, max_columns);
                let (w, h) = (d.camera.width as usize, d.camera.height as usize);
                let mut out = Vec::with_capacity((w / stride + 1) * (h / stride + 1));
                for v in (0..h).step_by(stride) {
                    for u in (0..w).step_by(stride) {
                        let z = f64::from(d.depth[v * w + u]);
                        if !(z.is_finite() && z > 0.0 && z >= options.min_depth) {
                            rejected += 1;
                            continue;
                        }
                        let local = d.camera.back_project(u as f64, v as f64, z);
                        out.push(d.camera_pose * local);
                    }
                }
                out
            }
            Sensor::Cloud(c) => {
                let mut out = Vec::with_capacity(c.points.len());
                for p in &c.points {
                    let q = Point3::new(
                        f64::from(p.position.x),
                        f64::from(p.position.y),
                        f64::from(p.position.z),
                    );
                    if finite3(&q) {
                        out.push(q);
                    } else {
                        rejected += 1;
                    }
                }
                out
            }
            Sensor::Occupancy(o) => {
                let mut out = Vec::with_capacity(o.points.len());
                for q in &o.points {
                    if finite3(q) {
                        out.push(*q);
                    } else {
                        rejected += 1;
                    }
                }
                out
            }
        };
        (points, rejected)
    }

    /// Where a depth frame shows *no floor* ("voids", for
    /// `sornav_frontier_graph::MultiLevelMap::update_with_voids`): the
    /// edge of a floor with nothing beyond it (a terrace or mezzanine over
    /// nothing, a hole in a mesh).
    ///
    /// In each image column sampled as by
    /// [`occupancy_points`](Self::occupancy_points), a run of pixels without
    /// a return (zero, NaN or infinite depth; a return nearer than
    /// `min_depth` is a return) is a void when
    /// * the pixel just below it (nearer along the floor) returns the
    ///   floor (within [`FLOOR_EDGE_TOLERANCE_M`] of `floor_z`): the floor
    ///   is seen to end there, where it would have gone on returning;
    /// * every pixel of the run has its ray cross the floor height
    ///   `floor_z` between `min_depth` and 90 % of `max_depth` (z-depth): a
    ///   floor there would have returned;
    /// * its crossings span at least [`MIN_VOID_RUN_M`] along the view: a
    ///   narrower gap in the floor (under a door's threshold, between two
    ///   rooms' floors of a modelled home, a seam of a scanned mesh) is no
    ///   drop-off for a robot;
    /// * the return that closes the run above (if any) is not nearer than
    ///   the run's first crossing: a surface nearer than where the floor
    ///   would have been hid it (the edge of a table top the camera looks
    ///   past, nearer than `min_depth` so that it returns nothing); beyond
    ///   a real edge the next return (the far side of a stairwell) lies
    ///   further.
    ///
    /// The crossings of the run's pixels are the voids. A floor the camera
    /// does not return at all (a missing model, a camera that does not
    /// see it) shows no edge and gives no void. Point clouds and occupancy
    /// returns have no voids (a cloud does not carry its misses). Sound
    /// only for a camera that returns every surface within `max_depth` (a
    /// simulator's; a stereo camera also misses textureless or shiny
    /// floors), hence
    /// [`AgentConfig::voids_from_missing_depth`](crate::AgentConfig::voids_from_missing_depth).
    ///
    /// # Complexity
    /// O(pixels / stride^2).
    pub fn void_points(
        &self,
        options: &DepthOptions,
        max_columns: u32,
        floor_z: f64,
    ) -> Vec<Point2<f64>> {
        let Sensor::Depth(d) = &self.sensor else {
            return Vec::new();
        };
        let stride = occupancy_stride(options.stride, d.camera.width, max_columns);
        let (w, h) = (d.camera.width as usize, d.camera.height as usize);
        let origin = d.camera_pose.translation.vector;
        let far = 0.9 * options.max_depth;
        let mut out = Vec::new();
        let mut run: Vec<Point2<f64>> = Vec::new();
        for u in (0..w).step_by(stride) {
            // From the bottom row up: nearer floor first.
            let mut edge = false;
            run.clear();
            // The z-depth of the run's first (nearest) floor crossing.
            let mut run_near = f64::INFINITY;
            for v in (0..h).step_by(stride).rev() {
                let z = d.depth[v * w + u];
                let (x, y) = (u as f64, v as f64);
                if z.is_finite() && z > 0.0 {
                    // A return above the run nearer than where the floor
                    // would have been: something between the camera and
                    // the floor (a table top nearer than `min_depth`
                    // returns nothing) hid it, no floor ended.
                    if edge && void_run_is_deep(&run) && f64::from(z) >= run_near {
                        out.append(&mut run);
                    }
                    run.clear();
                    run_near = f64::INFINITY;
                    let p = d.camera_pose * d.camera.back_project(x, y, f64::from(z));
                    edge = (p.z - floor_z).abs() <= FLOOR_EDGE_TOLERANCE_M;
                    continue;
                }
                if !edge {
                    continue;
                }
                // The ray at z-depth 1: the crossing's parameter is its
                // z-depth.
                let ray = d.camera_pose.rotation * d.camera.back_project(x, y, 1.0).coords;
                let t = (floor_z - origin.z) / ray.z;
                if ray.z < 0.0 && t >= options.min_depth && t <= far {
                    let p = origin + t * ray;
                    run_near = run_near.min(t);
                    run.push(Point2::new(p.x, p.y));
                } else {
                    // Out of the window: the run cannot be told from a gap.
                    if void_run_is_deep(&run) {
                        out.append(&mut run);
                    }
                    run.clear();
                    run_near = f64::INFINITY;
                    edge = false;
                }
            }
            if edge && void_run_is_deep(&run) {
                out.append(&mut run);
            }
        }
        out
    }
}

/// A return within this height (m) of the floor is the floor, for
/// [`Observation::void_points`].
pub const FLOOR_EDGE_TOLERANCE_M: f64 = 0.1;

/// Whether the floor crossings of one run of missing pixels span at least
/// [`MIN_VOID_RUN_M`].
fn void_run_is_deep(run: &[Point2<f64>]) -> bool {
    match (run.first(), run.last()) {
        (Some(a), Some(b)) => (b - a).norm() >= MIN_VOID_RUN_M,
        _ => false,
    }
}

/// The smallest depth (m, along the view) of a hole in the floor that
/// [`Observation::void_points`] reports: wider than a robot's body, wider
/// than the floor gaps of modelled homes and scanned meshes (wall
/// thresholds are 0.1-0.3 m).
pub const MIN_VOID_RUN_M: f64 = 0.4;

/// The pixel stride of a depth frame for the occupancy grid: the depth
/// window's `stride`, raised so that at most `max_columns` of the `width`
/// columns are used (`max_columns == 0`: no limit). A 2-D grid at 5 cm
/// needs far fewer rays than a 640-pixel-wide camera gives (0.12 degrees
/// apart, 1 cm at 5 m), and each ray costs its length in cells.
pub fn occupancy_stride(stride: u32, width: u32, max_columns: u32) -> usize {
    let base = stride.max(1) as usize;
    if max_columns == 0 {
        return base;
    }
    base.max((width as usize).div_ceil(max_columns as usize))
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn occupancy_stride_examples() {
        assert_eq!(occupancy_stride(1, 640, 160), 4);
        assert_eq!(occupancy_stride(1, 160, 160), 1);
        assert_eq!(occupancy_stride(1, 161, 160), 2);
        assert_eq!(occupancy_stride(3, 160, 160), 3);
        assert_eq!(occupancy_stride(0, 640, 0), 1);
    }

    /// A camera at 0.88 m, tilted down, over a floor that ends 2 m ahead
    /// with nothing beyond (depth 0 there), one dropped return inside the
    /// floor: the voids lie past the edge, within 90 % of the depth window,
    /// and the dropped return gives none; a table top whose near edge is
    /// nearer than `min_depth` gives none either.
    #[test]
    fn voids_lie_past_a_floor_edge_over_nothing() {
        let camera = PinholeCamera {
            width: 64,
            height: 48,
            fx: 32.0,
            fy: 32.0,
            cx: 31.5,
            cy: 23.5,
        };
        let eye = Point3::new(0.0, 0.0, 0.88);
        let pose = sornav_semantic_map::optical_pose(&eye, 0.0, 0.3);
        // A depth frame of a floor present where `floor(x)` says.
        let frame = |floor: &dyn Fn(f64) -> bool| {
            let mut depth = vec![0.0f32; 64 * 48];
            for v in 0..48 {
                for u in 0..64 {
                    let ray =
                        pose.rotation * camera.back_project(f64::from(u), f64::from(v), 1.0).coords;
                    if ray.z < 0.0 {
                        let t = -0.88 / ray.z;
                        if t <= 5.0 && floor(ray.x * t) {
                            #[allow(clippy::cast_possible_truncation)]
                            {
                                depth[v as usize * 64 + u as usize] = t as f32;
                            }
                        }
                    }
                }
            }
            depth
        };
        let observe = |depth: Vec<f32>| Observation {
            pose: RobotPose::new(Point3::new(0.0, 0.0, 0.0), 0.0),
            sensor: Sensor::Depth(DepthObservation {
                camera,
                camera_pose: pose,
                depth,
                labels: vec![LabelId(0); 64 * 48],
            }),
        };
        let options = DepthOptions::default();
        // The floor ends 2 m ahead; one return dropped inside it.
        let mut depth = frame(&|x| x < 2.0);
        let dropped = 44 * 64 + 32;
        assert!(depth[dropped] > 0.0);
        depth[dropped] = 0.0;
        let voids = observe(depth).void_points(&options, 0, 0.0);
        assert!(voids.len() > 20, "{}", voids.len());
        for v in &voids {
            let z_depth = (pose.inverse() * Point3::new(v.x, v.y, 0.0)).z;
            assert!(
                v.x > 2.0 && (0.5..=0.9 * 5.0 + 1e-9).contains(&z_depth),
                "{v:?}"
            );
        }
        // A 0.2 m gap in the floor (a threshold between two rooms' floors)
        // is no void, nor is a floor the camera does not return at all.
        let gap = observe(frame(&|x| !(2.0..2.2).contains(&x)));
        assert!(gap.void_points(&options, 0, 0.0).is_empty());
        let unseen = observe(frame(&|_| false));
        assert!(unseen.void_points(&options, 0, 0.0).is_empty());
        // A table top (0.74 m high, from 0.4 m to 2.4 m ahead) over a
        // floor that goes on: rays past its near edge hit it nearer than
        // `min_depth` and return nothing, but the top returns above them:
        // no void.
        let mut table = vec![0.0f32; 64 * 48];
        let mut hidden = 0;
        for v in 0..48 {
            for u in 0..64 {
                let ray =
                    pose.rotation * camera.back_project(f64::from(u), f64::from(v), 1.0).coords;
                if ray.z >= 0.0 {
                    continue;
                }
                let top = -0.14 / ray.z;
                let t = if (0.4..2.4).contains(&(ray.x * top)) {
                    top
                } else {
                    -0.88 / ray.z
                };
                if t < 0.5 {
                    hidden += 1;
                } else if t <= 5.0 {
                    #[allow(clippy::cast_possible_truncation)]
                    {
                        table[v as usize * 64 + u as usize] = t as f32;
                    }
                }
            }
        }
        assert!(
            hidden > 50,
            "the table's edge hides part of the floor: {hidden}"
        );
        assert!(observe(table).void_points(&options, 0, 0.0).is_empty());
        // A cloud has no voids.
        let cloud = Observation {
            pose: RobotPose::new(Point3::new(0.0, 0.0, 0.0), 0.0),
            sensor: Sensor::Occupancy(OccupancyObservation {
                origin: eye,
                points: vec![Point3::new(1.0, 0.0, 0.0)],
            }),
        };
        assert!(cloud.void_points(&options, 0, 0.0).is_empty());
    }

    proptest! {
        /// The stride never drops below the depth window's, and leaves at
        /// most `max_columns` columns, and is the smallest that does.
        #[test]
        fn occupancy_stride_is_the_smallest_sufficient(stride in 0u32..8, width in 1u32..4000, max in 1u32..1000) {
            let s = occupancy_stride(stride, width, max);
            prop_assert!(s >= stride.max(1) as usize);
            prop_assert!((width as usize).div_ceil(s) <= max as usize);
            if s > stride.max(1) as usize {
                prop_assert!((width as usize).div_ceil(s - 1) > max as usize);
            }
        }
    }
}
