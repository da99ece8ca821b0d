//! Pose-based arrival test.

use crate::{ArrivalRule, Mission, RobotPose};

/// Absolute difference of two angles, wrapped to `[0, pi]`.
pub fn angle_difference(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(std::f64::consts::TAU);
    d.min(std::f64::consts::TAU - d)
}

/// Whether the robot at `pose` has reached `mission` under `rule`:
///
/// * horizontal distance to the waypoint `<= radius_m` (or the mission's
///   tighter [`arrival_radius_m`](Mission::arrival_radius_m)),
/// * vertical offset `<= vertical_tolerance_m`,
/// * and, when the rule has a heading tolerance and the mission a
///   [`look_at`](Mission::look_at) point, the heading toward that point (in
///   the horizontal plane) differs from the robot's yaw by at most the
///   tolerance. A look-at point horizontally within 1 mm of the robot
///   satisfies any heading.
///
/// # Complexity
/// `O(1)`.
///
/// # Example
/// ```
/// use nalgebra::Point3;
/// use sornav_executor::{arrived, ArrivalRule, Mission, MissionKind, ObjectId, RobotPose};
/// let rule = ArrivalRule { radius_m: 0.5, vertical_tolerance_m: 1.0, heading_tolerance_rad: Some(0.3) };
/// let m = Mission::new(MissionKind::NavToObject { object: ObjectId(1) }, Point3::new(1.0, 0.0, 0.0))
///     .with_look_at(Point3::new(2.0, 0.0, 0.5));
/// assert!(arrived(&RobotPose::new(Point3::new(0.8, 0.0, 0.0), 0.0), &m, &rule));
/// assert!(!arrived(&RobotPose::new(Point3::new(0.8, 0.0, 0.0), 3.0), &m, &rule)); // facing away
/// // A mission's own tighter radius applies.
/// let tight = m.clone().with_arrival_radius(0.1);
/// assert!(!arrived(&RobotPose::new(Point3::new(0.8, 0.0, 0.0), 0.0), &tight, &rule));
/// ```
pub fn arrived(pose: &RobotPose, mission: &Mission, rule: &ArrivalRule) -> bool {
    let d = mission.waypoint - pose.position;
    let radius = mission
        .arrival_radius_m
        .map_or(rule.radius_m, |r| r.min(rule.radius_m));
    if d.x.hypot(d.y) > radius || d.z.abs() > rule.vertical_tolerance_m {
        return false;
    }
    match (rule.heading_tolerance_rad, mission.look_at) {
        (Some(tolerance), Some(target)) => {
            let v = target - pose.position;
            if v.x.hypot(v.y) < 1e-3 {
                return true;
            }
            angle_difference(v.y.atan2(v.x), pose.yaw) <= tolerance
        }
        _ => true,
    }
}
