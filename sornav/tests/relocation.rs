//! A scripted context: target toilet, the robot in a bedroom-like region, a
//! bathroom-like region elsewhere. SOR-Nav relocates to the bathroom
//! cluster; the no-gate ablation explores locally.

mod common;

use std::time::Duration;

use common::{Robot, World, object, wall};
use sornav::{Agent, AgentCommand, AgentConfig, DecisionStep, LabelEntry, PolicyConfig, Variant};

const BED: u16 = 12;
const NIGHTSTAND: u16 = 20;
const WARDROBE: u16 = 21;
const SINK: u16 = 22;
const BATHTUB: u16 = 23;
const PILLOW: u16 = 24;

/// A bedroom (x 0-5) with an opening to the west, a 28 m corridor, and a
/// bathroom (x 33-37) with an opening to the east. No toilet in sight.
fn house() -> World {
    World {
        blocks: vec![
            // Bedroom.
            wall(-0.1, -0.1, 5.1, 0.1),
            wall(-0.1, 3.9, 5.1, 4.1),
            wall(-0.1, -0.1, 0.1, 1.5),
            wall(-0.1, 2.5, 0.1, 4.1),
            wall(4.9, -0.1, 5.1, 1.5),
            wall(4.9, 2.5, 5.1, 4.1),
            object(BED, 0.5, 2.6, 2.5, 3.8, 0.0, 0.6),
            object(NIGHTSTAND, 2.7, 3.4, 3.1, 3.8, 0.0, 0.5),
            object(WARDROBE, 3.5, 3.3, 4.8, 3.8, 0.0, 2.0),
            // A fourth bedroom object: the calibrated prior leaves
            // P(toilet | bed, nightstand, wardrobe) = 0.06, above the 0.05
            // conflict threshold.
            object(PILLOW, 1.0, 0.2, 1.8, 0.8, 0.0, 0.5),
            // Corridor.
            wall(5.0, 1.4, 33.0, 1.5),
            wall(5.0, 2.5, 33.0, 2.6),
            // Bathroom.
            wall(32.9, -0.1, 37.1, 0.1),
            wall(32.9, 3.9, 37.1, 4.1),
            wall(32.9, -0.1, 33.1, 1.5),
            wall(32.9, 2.5, 33.1, 4.1),
            wall(36.9, -0.1, 37.1, 1.5),
            wall(36.9, 2.5, 37.1, 4.1),
            object(SINK, 33.3, 3.3, 33.9, 3.8, 0.6, 0.9),
            object(BATHTUB, 34.5, 0.2, 36.5, 1.0, 0.0, 0.5),
        ],
    }
}

fn config(variant: Variant) -> AgentConfig {
    let mut c = AgentConfig::for_variant(variant).unwrap();
    for (id, name) in [
        (NIGHTSTAND, "nightstand"),
        (WARDROBE, "wardrobe"),
        (SINK, "sink"),
        (BATHTUB, "bathtub"),
        (PILLOW, "pillow"),
    ] {
        c.labels.push(LabelEntry {
            id,
            name: name.into(),
            ignored: false,
        });
    }
    c
}

/// Walks the robot from the bathroom through the corridor into the
/// bedroom, observing every metre, and returns it in the bedroom.
fn scripted_walk(agent: &mut Agent, world: &World) -> Robot {
    let mut robot = Robot::new(35.0, 2.0);
    let mut x = 35.0;
    while x > 2.5 {
        robot.pose.position.x = x;
        agent.observe(&world.observation(robot.pose)).unwrap();
        x -= 1.0;
    }
    robot.pose.position.x = 2.5;
    robot.pose.position.y = 1.8;
    for _ in 0..3 {
        agent.observe(&world.observation(robot.pose)).unwrap();
    }
    robot
}

#[test]
fn bedroom_context_relocates_to_the_bathroom_cluster() {
    let world = house();
    let mut agent = Agent::new(config(Variant::Sornav)).unwrap();
    agent.set_target("toilet").unwrap();
    scripted_walk(&mut agent, &world);
    let command = agent.step(Duration::ZERO).unwrap();
    // Two frontier clusters: the bedroom's west opening (near) and the
    // bathroom's east opening (far, behind a 30 m corridor).
    let clusters = agent.snapshot().clusters.expect("G_C built");
    assert_eq!(clusters.len(), 2);
    let AgentCommand::Dispatch { id, mission } = &command else {
        panic!("expected a dispatch, got {command:?}");
    };
    assert_eq!(mission.kind.name(), "relocate", "{:#?}", agent.decisions());
    assert!(
        mission.waypoint.x > 32.0,
        "relocation waypoint {}",
        mission.waypoint
    );
    let path = mission.path.as_ref().expect("executable path");
    assert!(path.len() >= 2);
    let decision = agent.snapshot().last_decision.unwrap();
    assert_eq!(decision.step, DecisionStep::PolicyEvaluated);
    assert_eq!(decision.action, "relocate");
    assert!(!decision.reason.is_empty());
    let relocation = agent.snapshot().relocation.expect("relocation recorded");
    assert_eq!(relocation.mission, *id);

    // Algorithm 1, line 2: the relocation is kept, and exploration does not
    // interrupt it.
    let next = agent.step(Duration::from_secs(5)).unwrap();
    assert_eq!(next, AgentCommand::Continue { mission: Some(*id) });
    assert_eq!(
        agent.decisions().last().unwrap().step,
        DecisionStep::RelocationActive
    );
}

#[test]
fn without_the_gate_the_robot_explores_locally() {
    let world = house();
    let mut agent = Agent::new(config(Variant::NoGate)).unwrap();
    assert_eq!(agent.config().policy, PolicyConfig::NeverRelocate);
    agent.set_target("toilet").unwrap();
    scripted_walk(&mut agent, &world);
    let command = agent.step(Duration::ZERO).unwrap();
    let AgentCommand::Dispatch { mission, .. } = &command else {
        panic!("expected a dispatch, got {command:?}");
    };
    assert_eq!(mission.kind.name(), "explore");
    assert!(
        mission.waypoint.x < 5.0,
        "local frontier {}",
        mission.waypoint
    );
}
