//! Drop edges: where the robot sees through its floor into a deep hole
//! (a stairwell going down), it goes to the floor's end and looks down
//! before exploring on; not for a shallow drop, nor for a robot that
//! cannot climb stairs.

use std::time::Duration;

use nalgebra::Point3;
use sornav::executor::RobotPose;
use sornav::semantic_map::{LabelId, LabeledPoint};
use sornav::{Agent, AgentCommand, AgentConfig, CloudObservation, Observation, Sensor};

/// A 6 m x 6 m room around the robot (feet at the origin, sensor 0.88 m
/// up): floor seen up to x = 1 m, walls all round, and `depth` m under the
/// floor, through a hole east of the robot, the floor below (its rays pass
/// the floor's height 1.5-1.9 m east of the robot).
fn scene(depth: f64) -> Observation {
    let wall = LabelId(1);
    let mut points = Vec::new();
    // Floor seen from above, x in [-2.9, 1.0].
    for i in 0..40 {
        for j in -29..=29 {
            points.push(lp(-2.9 + 0.1 * f64::from(i), 0.1 * f64::from(j), 0.0, wall));
        }
    }
    // Walls at x = -3, y = +-3 and x = 3 (obstacle band).
    for k in -30..=30 {
        let t = 0.1 * f64::from(k);
        for z in [0.3, 0.8, 1.2] {
            points.push(lp(-3.0, t, z, wall));
            points.push(lp(t, 3.0, z, wall));
            points.push(lp(t, -3.0, z, wall));
            if t.abs() > 1.0 {
                points.push(lp(3.0, t, z, wall));
            }
        }
    }
    // The floor below, seen through the hole: its rays pass the floor's
    // height where x = 0.88 * x_far / (0.88 + depth).
    let x_far = 1.7 * (0.88 + depth) / 0.88;
    for j in -5..=5 {
        points.push(lp(x_far, 0.1 * f64::from(j), -depth, wall));
    }
    Observation {
        pose: RobotPose::new(Point3::origin(), 0.0),
        sensor: Sensor::Cloud(CloudObservation {
            origin: Point3::new(0.0, 0.0, 0.88),
            points,
        }),
    }
}

fn lp(x: f64, y: f64, z: f64, label: LabelId) -> LabeledPoint {
    LabeledPoint::new(x as f32, y as f32, z as f32, label)
}

/// The first command after one observation of `scene(depth)`, and whether
/// a decision so far looked down through the floor's edge.
fn first_command(config: AgentConfig, depth: f64) -> (AgentCommand, bool) {
    let mut agent = Agent::new(config).unwrap();
    agent.set_target("tv_monitor").unwrap();
    agent.observe(&scene(depth)).unwrap();
    let command = agent.step(Duration::from_secs(1)).unwrap();
    let looked = agent
        .decisions()
        .iter()
        .any(|d| d.reason.contains("looking down through the floor's edge"));
    (command, looked)
}

#[test]
fn a_deep_hole_next_to_the_robot_is_looked_into_first() {
    let (command, looked) = first_command(AgentConfig::default(), 2.5);
    assert!(looked, "{command:?}");
    let AgentCommand::Dispatch { mission, .. } = command else {
        panic!("a look is dispatched: {command:?}");
    };
    // It looks from the floor's end, back toward where the sensor saw the
    // edge from, down into the hole.
    let look = mission.look_at.expect("a point to look at");
    assert!(look.z < -1.0, "looks down: {look}");
    assert!(
        (0.8..=1.4).contains(&look.x) && look.y.abs() < 0.3,
        "at the floor's end: {look}"
    );
    assert!(mission.waypoint.x < look.x, "from the near side");
    assert!(mission.arrival_radius_m.is_some_and(|r| r <= 0.3));
}

#[test]
fn a_shallow_drop_or_a_robot_that_cannot_climb_does_not_look() {
    let (command, looked) = first_command(AgentConfig::default(), 0.5);
    assert!(!looked, "a 0.5 m drop is no stairwell: {command:?}");
    let mut wheeled = AgentConfig::default();
    wheeled.frontier.levels.allow_stairs = false;
    let (command, looked) = first_command(wheeled, 2.5);
    assert!(!looked, "a robot that cannot climb: {command:?}");
}
