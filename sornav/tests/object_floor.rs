//! A target seen up a stairwell, on a floor the map does not hold yet: the
//! agent does not send the robot to a "view point" on its own floor under
//! the object (it would stand 2.6 m below a bed it cannot see from there,
//! as a robot did in a Sweet Home 3D home before); an object on the
//! robot's floor is approached as before.

mod common;

use std::time::Duration;

use common::{Robot, World, object, wall};
use nalgebra::Point3;
use sornav::executor::MissionKind;
use sornav::{Agent, AgentCommand, AgentConfig};

const BED: u16 = 12;

/// The `NAV_TO_OBJECT` waypoints of 60 actions in a closed 6 m x 4 m room
/// with a bed whose lowest point is `bottom` m above the robot's floor,
/// seen up to 4 m high (as through an open stairwell).
fn approaches(bottom: f64) -> Vec<Point3<f64>> {
    let world = World {
        blocks: vec![
            wall(-0.1, -0.1, 6.1, 0.0),
            wall(-0.1, 4.0, 6.1, 4.1),
            wall(-0.1, -0.1, 0.0, 4.1),
            wall(6.0, -0.1, 6.1, 4.1),
            object(BED, 4.0, 1.5, 5.5, 2.5, bottom, bottom + 0.6),
        ],
    };
    let mut agent = Agent::new(AgentConfig::default()).unwrap();
    agent.set_target("bed").unwrap();
    let mut robot = Robot::new(1.0, 2.0);
    let mut out = Vec::new();
    for action in 0..60u64 {
        agent
            .observe(&world.observation_to(robot.pose, 4.0))
            .unwrap();
        let command = agent.step(Duration::from_millis(500 * action)).unwrap();
        if let AgentCommand::Dispatch { mission, .. } = &command
            && matches!(mission.kind, MissionKind::NavToObject { .. })
        {
            out.push(mission.waypoint);
        }
        if !robot.obey(&command) {
            break;
        }
        robot.act();
    }
    out
}

#[test]
fn a_bed_on_the_robots_floor_is_approached() {
    assert!(
        !approaches(0.0).is_empty(),
        "the scripted room leads to an approach"
    );
}

#[test]
fn a_bed_a_floor_up_is_not_approached_from_below() {
    for bottom in [2.0, 2.62, 3.0] {
        let under: Vec<_> = approaches(bottom)
            .into_iter()
            .filter(|w| bottom - w.z >= 1.8)
            .collect();
        assert!(
            under.is_empty(),
            "bed at {bottom} m: approached from the floor below at {under:?}"
        );
    }
}
