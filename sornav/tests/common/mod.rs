//! A tiny scripted world for the agent's integration tests: axis-aligned
//! labelled blocks, a 360-degree labelled range scan (occlusion by the
//! nearest block along each ray), and a point robot that follows mission
//! paths. Only observations reach the agent; the world is never shown to it.

#![allow(dead_code)]

use std::time::Duration;

use nalgebra::{Point2, Point3};
use sornav::executor::{Mission, RobotPose};
use sornav::semantic_map::{LabelId, LabeledPoint};
use sornav::{Agent, AgentCommand, CloudObservation, Observation, Sensor};

/// Sensor height above the floor (m).
pub const SENSOR_Z: f64 = 0.88;
/// Sensor range (m), as the simulator's depth camera.
pub const RANGE: f64 = 5.0;

/// An axis-aligned labelled box.
#[derive(Debug, Clone, Copy)]
pub struct Block {
    pub lo: (f64, f64),
    pub hi: (f64, f64),
    pub z: (f64, f64),
    pub label: u16,
}

pub const WALL: u16 = 1;
pub const OUTSIDE: u16 = 3;

pub fn wall(x0: f64, y0: f64, x1: f64, y1: f64) -> Block {
    Block {
        lo: (x0, y0),
        hi: (x1, y1),
        z: (0.0, 2.5),
        label: WALL,
    }
}

pub fn object(label: u16, x0: f64, y0: f64, x1: f64, y1: f64, z0: f64, z1: f64) -> Block {
    Block {
        lo: (x0, y0),
        hi: (x1, y1),
        z: (z0, z1),
        label,
    }
}

/// Ray parameter of the first intersection of `o + t d` with `b`, if any.
fn hit(b: &Block, o: (f64, f64), d: (f64, f64)) -> Option<f64> {
    let (mut t0, mut t1) = (0.0f64, f64::INFINITY);
    for (oo, dd, lo, hi) in [(o.0, d.0, b.lo.0, b.hi.0), (o.1, d.1, b.lo.1, b.hi.1)] {
        if dd.abs() < 1e-12 {
            if oo < lo || oo > hi {
                return None;
            }
        } else {
            let (a, c) = ((lo - oo) / dd, (hi - oo) / dd);
            t0 = t0.max(a.min(c));
            t1 = t1.min(a.max(c));
        }
    }
    (t0 <= t1 && t1 > 0.0).then_some(t0)
}

pub struct World {
    pub blocks: Vec<Block>,
}

impl World {
    /// A 720-ray labelled scan from `pos`: each ray returns a vertical
    /// column of points on the first block it meets within range; rays
    /// that meet nothing return one unlabelled point beyond the range
    /// (free space up to the range).
    pub fn scan(&self, pos: Point2<f64>) -> Vec<LabeledPoint> {
        self.scan_to(pos, 2.0)
    }

    /// [`scan`](Self::scan) with the columns' points up to `max_z` m
    /// (2 m there: a camera's view of a room).
    pub fn scan_to(&self, pos: Point2<f64>, max_z: f64) -> Vec<LabeledPoint> {
        let mut points = Vec::new();
        for k in 0..720 {
            let a = f64::from(k) * std::f64::consts::PI / 360.0;
            let d = (a.cos(), a.sin());
            let first = self
                .blocks
                .iter()
                .filter_map(|b| hit(b, (pos.x, pos.y), d).map(|t| (t, b)))
                .min_by(|x, y| x.0.total_cmp(&y.0));
            match first {
                Some((t, b)) if t <= RANGE => {
                    // Nudge into the block so the voxel belongs to it.
                    let (x, y) = (pos.x + d.0 * (t + 0.01), pos.y + d.1 * (t + 0.01));
                    let step = if b.label == WALL { 0.1 } else { 0.05 };
                    let mut z = b.z.0 + 0.01;
                    while z < b.z.1.min(max_z) {
                        points.push(LabeledPoint::new(
                            x as f32,
                            y as f32,
                            z as f32,
                            LabelId(b.label),
                        ));
                        z += step;
                    }
                }
                _ => {
                    let t = RANGE + 1.0;
                    points.push(LabeledPoint::new(
                        (pos.x + d.0 * t) as f32,
                        (pos.y + d.1 * t) as f32,
                        0.5,
                        LabelId(OUTSIDE),
                    ));
                }
            }
        }
        points
    }

    pub fn observation(&self, pose: RobotPose) -> Observation {
        self.observation_to(pose, 2.0)
    }

    /// [`observation`](Self::observation) of [`scan_to`](Self::scan_to).
    pub fn observation_to(&self, pose: RobotPose, max_z: f64) -> Observation {
        let xy = Point2::new(pose.position.x, pose.position.y);
        Observation {
            pose,
            sensor: Sensor::Cloud(CloudObservation {
                origin: Point3::new(xy.x, xy.y, SENSOR_Z),
                points: self.scan_to(xy, max_z),
            }),
        }
    }
}

/// A point robot: 0.25 m per action along the active mission's path,
/// turning in place toward a look-at point at the end of the path.
pub struct Robot {
    pub pose: RobotPose,
    path: Vec<Point3<f64>>,
    look_at: Option<Point3<f64>>,
}

impl Robot {
    pub fn new(x: f64, y: f64) -> Self {
        Self {
            pose: RobotPose::new(Point3::new(x, y, 0.0), 0.0),
            path: Vec::new(),
            look_at: None,
        }
    }

    pub fn follow(&mut self, mission: &Mission) {
        self.path = mission
            .path
            .clone()
            .unwrap_or_else(|| vec![mission.waypoint]);
        if self.path.last() != Some(&mission.waypoint) {
            self.path.push(mission.waypoint);
        }
        self.look_at = mission.look_at;
    }

    pub fn face(&mut self, p: &Point3<f64>) {
        let d = p - self.pose.position;
        self.pose.yaw = d.y.atan2(d.x);
    }

    pub fn hold(&mut self) {
        self.path.clear();
        self.look_at = None;
    }

    /// Follows one agent command; `false` when the episode ends (STOP or
    /// nothing left to explore).
    pub fn obey(&mut self, command: &AgentCommand) -> bool {
        match command {
            AgentCommand::Dispatch { mission, .. } => self.follow(mission),
            AgentCommand::Continue { mission: None } => self.hold(),
            AgentCommand::Continue { .. } => {}
            AgentCommand::Verify { look_at, .. } => {
                self.hold();
                self.face(look_at);
            }
            AgentCommand::Stop { .. }
            | AgentCommand::Exhausted
            | AgentCommand::FloorExhausted { .. } => return false,
        }
        true
    }

    /// One action.
    pub fn act(&mut self) {
        let mut budget = 0.25;
        while budget > 1e-9 {
            let Some(next) = self.path.first().copied() else {
                break;
            };
            let d = Point3::new(next.x, next.y, 0.0) - self.pose.position;
            let dist = d.norm();
            if dist <= budget {
                self.pose.position = Point3::new(next.x, next.y, 0.0);
                budget -= dist;
                self.path.remove(0);
            } else {
                self.pose.position += d * (budget / dist);
                self.pose.yaw = d.y.atan2(d.x);
                budget = 0.0;
            }
        }
        if self.path.is_empty()
            && let Some(p) = self.look_at
        {
            self.face(&p);
        }
    }
}

/// The result of [`run`].
pub struct Episode {
    pub commands: Vec<AgentCommand>,
    pub stop: Option<(u64, Point3<f64>)>,
    pub actions: usize,
}

/// Runs observe -> step -> act until STOP, exhaustion or `max_actions`.
/// Half a second of clock per action.
pub fn run(agent: &mut Agent, world: &World, robot: &mut Robot, max_actions: usize) -> Episode {
    let mut commands = Vec::new();
    let start = agent
        .last_step()
        .map_or(Duration::ZERO, |t| t + Duration::from_millis(500));
    for action in 0..max_actions {
        agent
            .observe(&world.observation(robot.pose))
            .expect("valid observation");
        let now = start + Duration::from_millis(500 * action as u64);
        let command = agent.step(now).expect("step");
        commands.push(command.clone());
        if !robot.obey(&command) {
            let stop = match command {
                AgentCommand::Stop { object, centre } => Some((object.0, centre)),
                _ => None,
            };
            return Episode {
                commands,
                stop,
                actions: action,
            };
        }
        robot.act();
    }
    Episode {
        commands,
        stop: None,
        actions: max_actions,
    }
}
