//! Arrival, remaining distance and stuck detection against references.

use std::time::Duration;

use nalgebra::{Point3, Vector2};
use proptest::prelude::*;
use sornav_executor::{
    ArrivalRule, Mission, MissionKind, ObjectId, RobotPose, StuckDetector, angle_difference,
    arrived, remaining_distance,
};

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn arrival_matches_reference(
        robot in (-5.0f64..5.0, -5.0f64..5.0, -2.0f64..2.0, -10.0f64..10.0),
        waypoint in (-5.0f64..5.0, -5.0f64..5.0, -2.0f64..2.0),
        look in proptest::option::of((-5.0f64..5.0, -5.0f64..5.0)),
        radius in 0.1f64..4.0,
        vertical in 0.0f64..2.0,
        heading in proptest::option::of(0.05f64..3.1),
    ) {
        let pose = RobotPose::new(Point3::new(robot.0, robot.1, robot.2), robot.3);
        let mut mission = Mission::new(
            MissionKind::NavToObject { object: ObjectId(1) },
            Point3::new(waypoint.0, waypoint.1, waypoint.2),
        );
        if let Some((x, y)) = look {
            mission = mission.with_look_at(Point3::new(x, y, 1.0));
        }
        let rule = ArrivalRule { radius_m: radius, vertical_tolerance_m: vertical, heading_tolerance_rad: heading };
        // Reference: squared distances and the cosine of the heading error.
        let dxy = Vector2::new(waypoint.0 - robot.0, waypoint.1 - robot.1);
        let near = (dxy.norm_squared() - radius * radius, (waypoint.2 - robot.2).abs() - vertical);
        prop_assume!(near.0.abs() > 1e-9 && near.1.abs() > 1e-9);
        let mut expected = near.0 < 0.0 && near.1 < 0.0;
        if let (Some(tol), Some((x, y))) = (heading, look) {
            let to = Vector2::new(x - robot.0, y - robot.1);
            if to.norm() >= 1e-3 {
                let facing = Vector2::new(robot.3.cos(), robot.3.sin());
                let cos = facing.dot(&to) / to.norm();
                prop_assume!((cos - tol.cos()).abs() > 1e-9);
                expected &= cos >= tol.cos();
            }
        }
        prop_assert_eq!(arrived(&pose, &mission, &rule), expected);
    }

    #[test]
    fn angle_difference_is_wrapped(a in -20.0f64..20.0, b in -20.0f64..20.0) {
        let d = angle_difference(a, b);
        prop_assert!((0.0..=std::f64::consts::PI + 1e-12).contains(&d));
        prop_assert!(((a - b).cos() - d.cos()).abs() < 1e-9);
    }

    /// On an x-monotone path (no self-intersection), a robot standing on
    /// the path at arc length `u` has `L - u + tail` left.
    #[test]
    fn remaining_on_monotone_path(
        steps in proptest::collection::vec((0.1f64..3.0, -2.0f64..2.0, -0.5f64..0.5), 1..8),
        frac in 0.0f64..1.0,
        tail in (-1.0f64..1.0, -1.0f64..1.0),
    ) {
        let mut path = vec![Point3::new(0.0, 0.0, 0.0)];
        for &(dx, dy, dz) in &steps {
            let p = path[path.len() - 1];
            path.push(Point3::new(p.x + dx, p.y + dy, p.z + dz));
        }
        let lengths: Vec<f64> = path.windows(2).map(|w| nalgebra::distance(&w[0], &w[1])).collect();
        let total: f64 = lengths.iter().sum();
        let u = frac * total;
        // Point at arc length u.
        let mut acc = 0.0;
        let mut on = path[path.len() - 1];
        for (i, &l) in lengths.iter().enumerate() {
            if acc + l >= u {
                let t = (u - acc) / l;
                on = path[i] + (path[i + 1] - path[i]) * t;
                break;
            }
            acc += l;
        }
        let last = path[path.len() - 1];
        let waypoint = Point3::new(last.x + tail.0, last.y + tail.1, last.z);
        let expected = total - u + nalgebra::distance(&last, &waypoint);
        let got = remaining_distance(&on, &waypoint, Some(&path));
        prop_assert!((got - expected).abs() < 1e-6, "got {} expected {}", got, expected);
        // Without a path: the straight line.
        let straight = remaining_distance(&on, &waypoint, None);
        prop_assert!((straight - nalgebra::distance(&on, &waypoint)).abs() < 1e-12);
    }

    /// The detector against a brute-force evaluation of its definition over
    /// the full history.
    #[test]
    fn stuck_detector_matches_brute_force(
        trace in proptest::collection::vec((0u64..2000, 0.0f64..20.0), 1..120),
        window_ms in 500u64..5000,
        min_progress in 0.0f64..2.0,
    ) {
        let window = Duration::from_millis(window_ms);
        let mut det = StuckDetector::new(window, min_progress);
        let mut history: Vec<(Duration, f64)> = Vec::new();
        let mut now = Duration::ZERO;
        for &(dt, remaining) in &trace {
            now += Duration::from_millis(dt);
            history.push((now, remaining));
            let got = det.record(now, remaining);
            let first = history[0].0;
            let best_at = |t: Duration| {
                history.iter().filter(|h| h.0 <= t).map(|h| h.1).fold(f64::INFINITY, f64::min)
            };
            let expected = if now >= first + window {
                let progress = best_at(now - window) - best_at(now);
                (progress <= min_progress).then_some(progress)
            } else {
                None
            };
            match (got, expected) {
                (Some(g), Some(e)) => prop_assert!((g - e).abs() < 1e-12),
                (g, e) => prop_assert_eq!(g, e),
            }
        }
    }
}

#[test]
fn stuck_detector_edge_cases() {
    let mut det = StuckDetector::new(Duration::from_secs(10), 0.5);
    // Not before a full window has passed.
    assert_eq!(det.record(Duration::from_secs(0), 10.0), None);
    assert_eq!(det.record(Duration::from_secs(9), 10.0), None);
    assert_eq!(det.record(Duration::from_secs(10), 10.0), Some(0.0));
    det.reset();
    // Progress of exactly the threshold is still "no more than" it: stuck.
    assert_eq!(det.record(Duration::from_secs(0), 10.0), None);
    assert_eq!(det.record(Duration::from_secs(10), 9.5), Some(0.5));
    det.reset();
    // Good progress: never stuck.
    for s in 0..30 {
        assert_eq!(det.record(Duration::from_secs(s), 30.0 - s as f64), None);
    }
    // Going backwards in time is clamped, not a panic.
    assert_eq!(det.record(Duration::from_secs(3), 0.5), None);
}

#[test]
fn degenerate_paths() {
    let w = Point3::new(3.0, 4.0, 0.0);
    let origin = Point3::origin();
    // Single point: straight line.
    assert!((remaining_distance(&origin, &w, Some(&[origin])) - 5.0).abs() < 1e-12);
    // Repeated points (zero-length segments).
    let path = [
        origin,
        origin,
        Point3::new(3.0, 0.0, 0.0),
        Point3::new(3.0, 0.0, 0.0),
    ];
    assert!((remaining_distance(&origin, &w, Some(&path)) - 7.0).abs() < 1e-12);
}
