//! The CMU autonomy-stack contract: which topics the robot node reads and
//! writes, with which message types and QoS.
//!
//! | role | default topic | type | direction | QoS |
//! |---|---|---|---|---|
//! | odometry | `/state_estimation` | `nav_msgs/Odometry` (map frame) | in | best effort |
//! | occupancy | `/registered_scan` | `sensor_msgs/PointCloud2` (map frame) | in | best effort |
//! | traversability | `/terrain_map` | `sensor_msgs/PointCloud2` (intensity = height above ground) | in | best effort |
//! | semantics | `/semantic_scan` | `sensor_msgs/PointCloud2` with `x y z label` | in | best effort |
//! | target request | `/sornav/target` | `std_msgs/String` | in | reliable |
//! | mission waypoint | `/way_point` | `geometry_msgs/PointStamped` (map frame) | out | reliable |
//! | autonomy mode | `/joy` | `sensor_msgs/Joy` | out | reliable |
//! | safety stop | `/stop` | `std_msgs/Int8` | out | reliable |
//! | status | `/sornav/status` | `std_msgs/String` (JSON) | out | reliable |
//! | RViz markers | `/sornav/markers` | `visualization_msgs/MarkerArray` | out | reliable |
//! | mission path | `/sornav/path` | `nav_msgs/Path` | out | reliable |
//! | relay in (optional) | `/cmd_vel` | `geometry_msgs/TwistStamped` | in | best effort |
//! | relay out (optional) | `/scout_mini/cmd_vel` | `geometry_msgs/Twist` | out | reliable |
//!
//! Sensor streams are read best effort (a best-effort reader matches both
//! reliable and best-effort writers, and a late cloud is worth less than the
//! next one); everything the node commands or reports is written reliable so
//! that reliable subscribers (the CMU planner, RViz, `ros2 topic echo`)
//! match it. [`Qos`] pins the profile of each side explicitly: ros2-client's
//! defaults differ between publishers and subscriptions.

use serde::{Deserialize, Serialize};

use crate::msg::RosMessage;

/// Reliability and history of one endpoint.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(tag = "reliability", rename_all = "snake_case")]
pub enum Qos {
    /// Reliable, volatile, keep last `depth`.
    Reliable {
        /// History depth.
        depth: usize,
    },
    /// Best effort, volatile, keep last `depth`.
    BestEffort {
        /// History depth.
        depth: usize,
    },
}

impl Qos {
    /// Commands and reports: reliable, depth 10.
    pub const COMMAND: Qos = Qos::Reliable { depth: 10 };
    /// Sensor streams: best effort, depth 5.
    pub const SENSOR: Qos = Qos::BestEffort { depth: 5 };

    /// Whether a writer with QoS `self` is matched by a reader with QoS
    /// `reader` (DDS request/offered rule: a reliable reader needs a
    /// reliable writer).
    pub fn writer_matches_reader(self, reader: Qos) -> bool {
        !matches!(
            (self, reader),
            (Qos::BestEffort { .. }, Qos::Reliable { .. })
        )
    }
}

/// Whether the node reads or writes a topic.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Direction {
    /// The node subscribes.
    In,
    /// The node publishes.
    Out,
}

/// Topic names (configurable; defaults are the CMU stack's and sornav's).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Topics {
    /// Vehicle odometry in the map frame.
    pub state_estimation: String,
    /// Registered LiDAR scan in the map frame.
    pub registered_scan: String,
    /// Terrain map (intensity = height above ground).
    pub terrain_map: String,
    /// Labelled semantic cloud (`x y z label`, map frame).
    pub semantic_scan: String,
    /// Natural-language target requests.
    pub target: String,
    /// Waypoint for the local planner.
    pub way_point: String,
    /// Joystick message switching the planner to autonomy mode.
    pub joy: String,
    /// The path follower's safety stop.
    pub stop: String,
    /// JSON status.
    pub status: String,
    /// RViz markers.
    pub markers: String,
    /// The active mission's planned path (RViz).
    pub path: String,
    /// Relay input: the path follower's `TwistStamped`.
    pub cmd_vel_in: String,
    /// Relay output: the Scout Mini driver's `Twist`.
    pub cmd_vel_out: String,
}

impl Default for Topics {
    fn default() -> Self {
        Self {
            state_estimation: "/state_estimation".into(),
            registered_scan: "/registered_scan".into(),
            terrain_map: "/terrain_map".into(),
            semantic_scan: "/semantic_scan".into(),
            target: "/sornav/target".into(),
            way_point: "/way_point".into(),
            joy: "/joy".into(),
            stop: "/stop".into(),
            status: "/sornav/status".into(),
            markers: "/sornav/markers".into(),
            path: "/sornav/path".into(),
            cmd_vel_in: "/cmd_vel".into(),
            cmd_vel_out: "/scout_mini/cmd_vel".into(),
        }
    }
}

/// One row of the contract.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct TopicSpec {
    /// What the topic is for (`odometry`, `way_point`, ...).
    pub role: &'static str,
    /// Topic name.
    pub name: String,
    /// ROS type (`nav_msgs/msg/Odometry`).
    pub ros_type: String,
    /// Direction seen from the robot node.
    pub direction: Direction,
    /// QoS of the node's endpoint.
    pub qos: Qos,
    /// Only when the cmd_vel relay is enabled.
    pub optional: bool,
}

fn spec<M: RosMessage>(
    role: &'static str,
    name: &str,
    direction: Direction,
    qos: Qos,
    optional: bool,
) -> TopicSpec {
    TopicSpec {
        role,
        name: name.to_owned(),
        ros_type: M::ros_type(),
        direction,
        qos,
        optional,
    }
}

impl Topics {
    /// Every topic of the contract with its type, direction and QoS.
    pub fn specs(&self) -> Vec<TopicSpec> {
        use crate::msg::*;
        use Direction::{In, Out};
        vec![
            spec::<Odometry>("odometry", &self.state_estimation, In, Qos::SENSOR, false),
            spec::<PointCloud2>("occupancy", &self.registered_scan, In, Qos::SENSOR, false),
            spec::<PointCloud2>("traversability", &self.terrain_map, In, Qos::SENSOR, false),
            spec::<PointCloud2>("semantics", &self.semantic_scan, In, Qos::SENSOR, false),
            spec::<RosString>("target", &self.target, In, Qos::COMMAND, false),
            spec::<PointStamped>("way_point", &self.way_point, Out, Qos::COMMAND, false),
            spec::<Joy>("joy", &self.joy, Out, Qos::COMMAND, false),
            spec::<Int8>("stop", &self.stop, Out, Qos::COMMAND, false),
            spec::<RosString>("status", &self.status, Out, Qos::COMMAND, false),
            spec::<MarkerArray>("markers", &self.markers, Out, Qos::COMMAND, false),
            spec::<Path>("path", &self.path, Out, Qos::COMMAND, false),
            spec::<TwistStamped>("cmd_vel_in", &self.cmd_vel_in, In, Qos::SENSOR, true),
            spec::<Twist>("cmd_vel_out", &self.cmd_vel_out, Out, Qos::COMMAND, true),
        ]
    }

    /// The QoS of the node's endpoint for `role` (a [`TopicSpec::role`] of
    /// [`specs`](Self::specs), e.g. `"odometry"`), `None` for a role the
    /// contract does not have.
    pub fn qos(&self, role: &str) -> Option<Qos> {
        self.specs()
            .into_iter()
            .find(|s| s.role == role)
            .map(|s| s.qos)
    }

    /// Checks that every name is an absolute ROS name (`/a/b_c`) and that no
    /// name is used twice (two roles on one topic would need one type).
    ///
    /// # Errors
    /// A message naming the offending topic.
    pub fn validate(&self) -> Result<(), String> {
        let specs = self.specs();
        for s in &specs {
            if !is_ros_name(&s.name) {
                return Err(format!(
                    "topic `{}` ({}) is not an absolute ROS name",
                    s.name, s.role
                ));
            }
        }
        for (i, a) in specs.iter().enumerate() {
            if let Some(b) = specs[i + 1..].iter().find(|b| b.name == a.name) {
                return Err(format!(
                    "topic `{}` is used for both {} and {}",
                    a.name, a.role, b.role
                ));
            }
        }
        Ok(())
    }
}

/// An absolute ROS 2 topic name: `/` then tokens of `[A-Za-z0-9_]` separated
/// by single `/`, no token starting with a digit, no `__`.
pub fn is_ros_name(name: &str) -> bool {
    let Some(rest) = name.strip_prefix('/') else {
        return false;
    };
    !rest.is_empty()
        && !rest.contains("__")
        && rest.split('/').all(|t| {
            !t.is_empty()
                && !t.starts_with(|c: char| c.is_ascii_digit())
                && t.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
        })
}
