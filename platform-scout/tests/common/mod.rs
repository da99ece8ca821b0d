//! Helpers shared by the integration tests: the test room and odometry.
#![allow(dead_code)]

use sornav_platform_scout::msg::{
    Header, Odometry, Point, Pose, PoseWithCovariance, Quaternion, TwistWithCovariance,
};

/// Height of the LiDAR (the odometry frame) above the floor (m).
pub const LIDAR_Z: f64 = 0.55;

/// A 6 m x 4 m room centred on the origin with a doorway in the east wall,
/// a floor and a television (label 15) on the north wall: `[x, y, z,
/// label]`, walls 1, floor 2.
pub fn room() -> Vec<[f64; 4]> {
    let mut pts = Vec::new();
    for i in -60..=60 {
        for h in 0..18 {
            let (x, z) = (f64::from(i) * 0.05, f64::from(h) * 0.05);
            pts.push([x, 2.0, z, 1.0]);
            pts.push([x, -2.0, z, 1.0]);
        }
    }
    for j in -40..=40 {
        let y = f64::from(j) * 0.05;
        for h in 0..18 {
            let z = f64::from(h) * 0.05;
            pts.push([-3.0, y, z, 1.0]);
            if y.abs() > 0.6 {
                pts.push([3.0, y, z, 1.0]);
            }
        }
        for i in -55..=55 {
            pts.push([f64::from(i) * 0.05, y, 0.0, 2.0]);
        }
    }
    // Sampled at voxel centres (0.025 + k 0.05) so that f32 rounding never
    // puts two samples in one voxel and none in the next.
    for a in 0..10 {
        for b in 0..6 {
            let (x, z) = (-1.175 + f64::from(a) * 0.05, 0.575 + f64::from(b) * 0.05);
            pts.push([x, 1.875, z, 15.0]);
        }
    }
    pts
}

/// Odometry of the LiDAR frame (`sensor`) at `(x, y, LIDAR_Z)` heading
/// `yaw`, zero covariances and twist.
pub fn odometry(header: Header, x: f64, y: f64, yaw: f64) -> Odometry {
    Odometry {
        header,
        child_frame_id: "sensor".into(),
        pose: PoseWithCovariance {
            pose: Pose {
                position: Point::new(x, y, LIDAR_Z),
                orientation: Quaternion::from_yaw(yaw),
            },
            covariance: [0.0; 36],
        },
        twist: TwistWithCovariance::default(),
    }
}
