//! The robot's configuration: an AgileX Scout Mini with a LiDAR, a
//! panoramic camera and the CMU autonomy stack, in one TOML document
//! (`config/scout_mini.toml` is the committed example).
//!
//! Every section has defaults and rejects unknown fields; [`ScoutConfig`]
//! validates ranges and cross-checks, and [`ScoutConfig::agent_config`]
//! derives the agent's configuration (floor height, inflation radius, robot
//! height, arrival radii, the "unlabelled" label) from the robot's.

use std::path::Path;

use nalgebra::{Isometry3, Point2, Translation3, UnitQuaternion};
use serde::{Deserialize, Serialize};
use sornav::{AgentConfig, LabelEntry};

use crate::contract::Topics;

/// Errors of loading and validating a [`ScoutConfig`].
#[derive(Debug, thiserror::Error)]
pub enum ConfigError {
    /// Reading, parsing (malformed TOML, unknown field) or writing the
    /// TOML document failed (`sornav`'s shared TOML loader).
    #[error("scout configuration: {0}")]
    Toml(#[from] sornav::TomlError),
    /// A value is out of range.
    #[error("invalid `{field}`: {message}")]
    Invalid {
        /// Dotted field path.
        field: &'static str,
        /// What is wrong.
        message: String,
    },
    /// The embedded agent configuration is invalid.
    #[error("invalid [agent] configuration: {0}")]
    Agent(#[from] sornav::ConfigError),
}

fn invalid(field: &'static str, message: impl Into<String>) -> ConfigError {
    ConfigError::Invalid {
        field,
        message: message.into(),
    }
}

fn positive(field: &'static str, v: f64) -> Result<(), ConfigError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(invalid(
            field,
            format!("must be positive and finite, got {v}"),
        ))
    }
}

/// A rigid mount of a sensor on the base (`base_link`): translation (m) and
/// roll/pitch/yaw (degrees, applied yaw-pitch-roll about the base axes).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Extrinsic {
    /// Forward (m).
    pub x: f64,
    /// Left (m).
    pub y: f64,
    /// Up from the floor (m).
    pub z: f64,
    /// Roll (deg).
    pub roll_deg: f64,
    /// Pitch (deg).
    pub pitch_deg: f64,
    /// Yaw (deg).
    pub yaw_deg: f64,
}

impl Default for Extrinsic {
    fn default() -> Self {
        Self {
            x: 0.0,
            y: 0.0,
            z: 0.5,
            roll_deg: 0.0,
            pitch_deg: 0.0,
            yaw_deg: 0.0,
        }
    }
}

impl Extrinsic {
    /// The transform base -> sensor.
    pub fn isometry(&self) -> Isometry3<f64> {
        Isometry3::from_parts(
            Translation3::new(self.x, self.y, self.z),
            UnitQuaternion::from_euler_angles(
                self.roll_deg.to_radians(),
                self.pitch_deg.to_radians(),
                self.yaw_deg.to_radians(),
            ),
        )
    }

    fn validate(&self, field: &'static str) -> Result<(), ConfigError> {
        let v = [
            self.x,
            self.y,
            self.z,
            self.roll_deg,
            self.pitch_deg,
            self.yaw_deg,
        ];
        if v.iter().all(|c| c.is_finite()) && self.z >= 0.0 && self.z <= 5.0 {
            Ok(())
        } else {
            Err(invalid(field, "must be finite with z in [0, 5] m"))
        }
    }
}

/// The robot body.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RobotConfig {
    /// Model name (status and markers only).
    pub name: String,
    /// Footprint polygon in the base frame (m, x forward, y left),
    /// counter-clockwise. Scout Mini: 0.612 m x 0.580 m.
    pub footprint: Vec<[f64; 2]>,
    /// Height of the robot with its sensor mast (m): returns up to this
    /// height are obstacles.
    pub height_m: f64,
    /// Obstacle inflation radius of the occupancy grid (m); `None`: the
    /// footprint's inscribed radius (a circumscribed radius would close
    /// doors for a 0.6 m robot on a 0.05 m grid).
    pub inflation_radius_m: Option<f64>,
    /// Largest forward speed (m/s) the relay lets through; set the CMU path
    /// follower's `maxSpeed` / `autonomySpeed` to at most this.
    pub max_speed_mps: f64,
    /// Largest yaw rate (deg/s) the relay lets through.
    pub max_yaw_rate_dps: f64,
    /// Whether the robot can climb stairs (default `false`: the Scout Mini
    /// cannot). `false`: the agent never plans over stairs
    /// (`frontier.levels.allow_stairs = false`) but still detects them
    /// (`detect_stairs = true`), so that when its floor is exhausted while
    /// seen stairs lead to another floor the node reports `floor_exhausted`
    /// ("not found on this floor; stairs at ... lead to an unexplored
    /// floor") instead of `exhausted`. `true`: the agent explores and
    /// searches over stairs (only for a base and a local planner that
    /// really climb them).
    pub can_climb_stairs: bool,
}

impl Default for RobotConfig {
    fn default() -> Self {
        Self {
            name: "scout_mini".into(),
            footprint: vec![
                [0.306, 0.29],
                [-0.306, 0.29],
                [-0.306, -0.29],
                [0.306, -0.29],
            ],
            height_m: 0.75,
            inflation_radius_m: None,
            max_speed_mps: 0.8,
            max_yaw_rate_dps: 90.0,
            can_climb_stairs: false,
        }
    }
}

impl RobotConfig {
    /// The footprint as points.
    pub fn footprint_points(&self) -> Vec<Point2<f64>> {
        self.footprint
            .iter()
            .map(|p| Point2::new(p[0], p[1]))
            .collect()
    }

    /// Distance from the base origin to the nearest footprint edge (m).
    pub fn inscribed_radius(&self) -> f64 {
        let pts = self.footprint_points();
        (0..pts.len())
            .map(|i| segment_distance(&Point2::origin(), &pts[i], &pts[(i + 1) % pts.len()]))
            .fold(f64::INFINITY, f64::min)
    }

    /// Distance from the base origin to the farthest footprint vertex (m).
    pub fn circumscribed_radius(&self) -> f64 {
        self.footprint_points()
            .iter()
            .map(|p| p.coords.norm())
            .fold(0.0, f64::max)
    }

    /// The inflation radius in use.
    pub fn inflation_radius(&self) -> f64 {
        self.inflation_radius_m
            .unwrap_or_else(|| self.inscribed_radius())
    }

    fn validate(&self) -> Result<(), ConfigError> {
        if self.footprint.len() < 3 {
            return Err(invalid("robot.footprint", "needs at least 3 vertices"));
        }
        if !self.footprint.iter().flatten().all(|c| c.is_finite()) {
            return Err(invalid("robot.footprint", "vertices must be finite"));
        }
        let pts = self.footprint_points();
        let area2: f64 = (0..pts.len())
            .map(|i| {
                let (a, b) = (pts[i], pts[(i + 1) % pts.len()]);
                a.x * b.y - b.x * a.y
            })
            .sum();
        if area2 <= 0.0 {
            return Err(invalid(
                "robot.footprint",
                "must be counter-clockwise with positive area",
            ));
        }
        if !point_in_polygon(&Point2::origin(), &pts) {
            return Err(invalid("robot.footprint", "must contain the base origin"));
        }
        positive("robot.height_m", self.height_m)?;
        if let Some(r) = self.inflation_radius_m {
            positive("robot.inflation_radius_m", r)?;
            if r > 2.0 {
                return Err(invalid("robot.inflation_radius_m", "must be at most 2 m"));
            }
        }
        positive("robot.max_speed_mps", self.max_speed_mps)?;
        positive("robot.max_yaw_rate_dps", self.max_yaw_rate_dps)?;
        Ok(())
    }
}

fn segment_distance(p: &Point2<f64>, a: &Point2<f64>, b: &Point2<f64>) -> f64 {
    let ab = b - a;
    let t = if ab.norm_squared() > 0.0 {
        ((p - a).dot(&ab) / ab.norm_squared()).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p - (a + ab * t)).norm()
}

fn point_in_polygon(p: &Point2<f64>, poly: &[Point2<f64>]) -> bool {
    let mut inside = false;
    let n = poly.len();
    for i in 0..n {
        let (a, b) = (poly[i], poly[(i + n - 1) % n]);
        if (a.y > p.y) != (b.y > p.y) && p.x < (b.x - a.x) * (p.y - a.y) / (b.y - a.y) + a.x {
            inside = !inside;
        }
    }
    inside
}

/// Which frame `/state_estimation` reports.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum OdometryFrame {
    /// The LiDAR (the CMU stack's `sensor` / vehicle frame; its default).
    #[default]
    Lidar,
    /// The base on the floor.
    Base,
}

/// Sensor mounts.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SensorsConfig {
    /// LiDAR (Livox MID-360) on the base.
    pub lidar: Extrinsic,
    /// Panoramic camera on the base (documentation for the segmentation
    /// node; the semantic cloud arrives already in the map frame).
    pub camera: Extrinsic,
    /// The frame `/state_estimation` reports.
    pub odometry_frame: OdometryFrame,
}

impl Default for SensorsConfig {
    fn default() -> Self {
        Self {
            lidar: Extrinsic {
                z: 0.55,
                ..Extrinsic::default()
            },
            camera: Extrinsic {
                z: 0.7,
                ..Extrinsic::default()
            },
            odometry_frame: OdometryFrame::Lidar,
        }
    }
}

/// Arrival radii of the executor (arrival is computed from odometry: the
/// CMU stack has no "reached" signal).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ArrivalConfig {
    /// EXPLORE waypoints (m).
    pub explore_radius_m: f64,
    /// RELOCATE waypoints (m).
    pub relocate_radius_m: f64,
    /// NAV_TO_OBJECT waypoints (m).
    pub object_radius_m: f64,
    /// Heading tolerance toward the object at NAV_TO_OBJECT arrival (deg);
    /// `None` for a panoramic camera, which sees the object whatever the
    /// heading (the CMU planner cannot turn in place on request).
    pub object_heading_tolerance_deg: Option<f64>,
    /// Vertical tolerance (m).
    pub vertical_tolerance_m: f64,
}

impl Default for ArrivalConfig {
    fn default() -> Self {
        Self {
            explore_radius_m: 1.0,
            relocate_radius_m: 1.5,
            object_radius_m: 0.6,
            object_heading_tolerance_deg: None,
            vertical_tolerance_m: 1.0,
        }
    }
}

/// Largest `rates.odometry_max_age_s` and `rates.odometry_max_future_s`
/// (s): one hour.
pub const MAX_ODOMETRY_STAMP_TOLERANCE_S: f64 = 3600.0;

/// Rates of the node.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RatesConfig {
    /// Agent steps per second (the paper's supervisor runs at 1 Hz).
    pub control_hz: f64,
    /// Observations per second: the clouds received since the last one are
    /// merged into one observation.
    pub observe_hz: f64,
    /// Re-publish the active waypoint this often (s): the planner may start
    /// after the node, and early samples are lost before discovery.
    pub waypoint_republish_s: f64,
    /// Publish markers this often (s).
    pub markers_period_s: f64,
    /// Consider odometry stale after this long (s): the node holds.
    pub odometry_timeout_s: f64,
    /// Reject an odometry message whose header stamp is older than this
    /// when it is received (s, against the node's wall clock): a delayed,
    /// replayed or zero-stamped pose is counted (`stale_odometry`), not
    /// used. At most one hour.
    pub odometry_max_age_s: f64,
    /// Reject an odometry message stamped further than this ahead of the
    /// node's wall clock (s; clock skew between computers): counted
    /// (`future_odometry`), not used. At most one hour.
    pub odometry_max_future_s: f64,
    /// Whether odometry stamps are checked against the wall clock at all
    /// (`odometry_max_age_s`, `odometry_max_future_s`). Turn it off when
    /// the stamps are in simulated time (`use_sim_time`: a bag replayed, a
    /// simulator's clock), which the wall clock would reject every time.
    pub check_odometry_stamps: bool,
}

impl Default for RatesConfig {
    fn default() -> Self {
        Self {
            control_hz: 1.0,
            observe_hz: 2.0,
            waypoint_republish_s: 1.0,
            markers_period_s: 2.0,
            odometry_timeout_s: 1.0,
            odometry_max_age_s: 1.0,
            odometry_max_future_s: 0.5,
            check_odometry_stamps: true,
        }
    }
}

/// How clouds become observations.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct InputsConfig {
    /// Label channel of the semantic cloud.
    pub label_field: String,
    /// Height-above-ground channel of the terrain map.
    pub terrain_height_field: String,
    /// Feed `/registered_scan` returns to the occupancy grid (as
    /// occupancy-only observations).
    pub use_registered_scan: bool,
    /// Feed `/terrain_map` to the occupancy grid (re-projected to the floor
    /// height plus its height above ground, so slopes stay traversable).
    pub use_terrain_map: bool,
    /// Label the upstream segmentation gives semantic-cloud points it could
    /// not classify; it must be an ignored (structure) label of the agent,
    /// and is added as `unlabelled` when the agent's label list lacks it, so
    /// such points never form object clusters. (Registered-scan and
    /// terrain-map returns carry no label at all: they reach the agent as
    /// occupancy-only observations.)
    pub unlabelled_label: u16,
    /// Cap on the points of one observation (newest clouds kept).
    pub max_points_per_observation: usize,
    /// World z of the floor in the map frame; `None`: the base height at the
    /// first odometry message.
    pub floor_z: Option<f64>,
}

impl Default for InputsConfig {
    fn default() -> Self {
        Self {
            label_field: "label".into(),
            terrain_height_field: "intensity".into(),
            use_registered_scan: true,
            use_terrain_map: true,
            unlabelled_label: 0,
            max_points_per_observation: 400_000,
            floor_z: None,
        }
    }
}

/// Largest ROS 2 domain id (RTPS port arithmetic on the default ports).
pub const MAX_DOMAIN_ID: u16 = 232;

/// ROS 2 participant settings.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RosConfig {
    /// `ROS_DOMAIN_ID` (0-232).
    pub domain_id: u16,
    /// Node name.
    pub node_name: String,
    /// Node namespace.
    pub namespace: String,
    /// Map frame of waypoints and markers.
    pub map_frame: String,
    /// IPv4 addresses of the interfaces DDS may use (discovery and data).
    /// Default loopback only: the CMU stack runs on the same computer. Add
    /// the robot's LAN address to reach a second computer.
    pub only_networks: Vec<std::net::Ipv4Addr>,
}

impl Default for RosConfig {
    fn default() -> Self {
        Self {
            domain_id: 0,
            node_name: "sornav".into(),
            namespace: "/".into(),
            map_frame: "map".into(),
            only_networks: vec![std::net::Ipv4Addr::LOCALHOST],
        }
    }
}

/// The optional `/cmd_vel` relay (TwistStamped -> Twist).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RelayConfig {
    /// Run the relay.
    pub enabled: bool,
    /// Publish one zero Twist when no command arrived for this long (s).
    pub watchdog_s: f64,
}

impl Default for RelayConfig {
    fn default() -> Self {
        Self {
            enabled: false,
            watchdog_s: 0.5,
        }
    }
}

/// The whole robot configuration.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ScoutConfig {
    /// Body, footprint and speed limits.
    pub robot: RobotConfig,
    /// Sensor mounts.
    pub sensors: SensorsConfig,
    /// Arrival radii.
    pub arrival: ArrivalConfig,
    /// Rates.
    pub rates: RatesConfig,
    /// Cloud handling.
    pub inputs: InputsConfig,
    /// DDS participant.
    pub ros: RosConfig,
    /// Topic names.
    pub topics: Topics,
    /// cmd_vel relay.
    pub relay: RelayConfig,
    /// Target to search at start (otherwise wait for `/sornav/target`).
    pub initial_target: Option<String>,
    /// The agent (every paper parameter; defaults are the paper's).
    pub agent: AgentConfig,
}

impl ScoutConfig {
    /// The committed example (`config/scout_mini.toml`).
    pub const EXAMPLE: &'static str = include_str!("../config/scout_mini.toml");

    /// Parses and validates a TOML document.
    ///
    /// # Errors
    /// [`ConfigError::Toml`] and those of [`validate`](Self::validate).
    pub fn from_toml(text: &str) -> Result<Self, ConfigError> {
        let config: Self = sornav::toml_file::from_str(text)?;
        config.validate()?;
        Ok(config)
    }

    /// Applies the `ROS_DOMAIN_ID` environment variable, given as `value`
    /// (`std::env::var("ROS_DOMAIN_ID").ok()`): when set and not blank it
    /// replaces `ros.domain_id`, as in ROS 2.
    ///
    /// # Errors
    /// [`ConfigError::Invalid`] naming `ROS_DOMAIN_ID` when the value is
    /// not an integer in `0..=232`.
    pub fn apply_ros_domain_id_env(&mut self, value: Option<&str>) -> Result<(), ConfigError> {
        let Some(v) = value.map(str::trim).filter(|v| !v.is_empty()) else {
            return Ok(());
        };
        match v.parse::<u16>() {
            Ok(d) if d <= MAX_DOMAIN_ID => {
                self.ros.domain_id = d;
                Ok(())
            }
            _ => Err(invalid(
                "ROS_DOMAIN_ID",
                format!("`{v}` is not a domain id in 0..={MAX_DOMAIN_ID}"),
            )),
        }
    }

    /// Reads, parses and validates a TOML file.
    ///
    /// # Errors
    /// [`ConfigError::Toml`] when the file cannot be read or parsed (the
    /// error names the file and line), and every error of
    /// [`validate`](Self::validate).
    pub fn from_toml_file(path: &Path) -> Result<Self, ConfigError> {
        let config: Self = sornav::toml_file::from_file(path)?;
        config.validate()?;
        Ok(config)
    }

    /// The configuration as TOML (every field).
    ///
    /// # Errors
    /// [`ConfigError::Toml`].
    pub fn to_toml(&self) -> Result<String, ConfigError> {
        Ok(sornav::toml_file::to_string(self)?)
    }

    /// Checks every section and the agent configuration derived from it.
    ///
    /// # Errors
    /// The first [`ConfigError`] found.
    pub fn validate(&self) -> Result<(), ConfigError> {
        self.robot.validate()?;
        self.sensors.lidar.validate("sensors.lidar")?;
        self.sensors.camera.validate("sensors.camera")?;
        let a = &self.arrival;
        positive("arrival.explore_radius_m", a.explore_radius_m)?;
        positive("arrival.relocate_radius_m", a.relocate_radius_m)?;
        positive("arrival.object_radius_m", a.object_radius_m)?;
        positive("arrival.vertical_tolerance_m", a.vertical_tolerance_m)?;
        if let Some(h) = a.object_heading_tolerance_deg
            && !(h.is_finite() && h > 0.0 && h <= 180.0)
        {
            return Err(invalid(
                "arrival.object_heading_tolerance_deg",
                "must be in (0, 180]",
            ));
        }
        let r = &self.rates;
        positive("rates.control_hz", r.control_hz)?;
        positive("rates.observe_hz", r.observe_hz)?;
        positive("rates.waypoint_republish_s", r.waypoint_republish_s)?;
        positive("rates.markers_period_s", r.markers_period_s)?;
        positive("rates.odometry_timeout_s", r.odometry_timeout_s)?;
        for (field, v) in [
            ("rates.odometry_max_age_s", r.odometry_max_age_s),
            ("rates.odometry_max_future_s", r.odometry_max_future_s),
        ] {
            positive(field, v)?;
            if v > MAX_ODOMETRY_STAMP_TOLERANCE_S {
                return Err(invalid(
                    field,
                    format!("must be at most {MAX_ODOMETRY_STAMP_TOLERANCE_S} s, got {v}"),
                ));
            }
        }
        if r.control_hz > 50.0 || r.observe_hz > 50.0 {
            return Err(invalid(
                "rates",
                "control_hz and observe_hz must be at most 50",
            ));
        }
        let i = &self.inputs;
        if i.label_field.is_empty() || i.terrain_height_field.is_empty() {
            return Err(invalid("inputs", "field names must not be empty"));
        }
        if i.max_points_per_observation == 0 {
            return Err(invalid(
                "inputs.max_points_per_observation",
                "must be positive",
            ));
        }
        if i.floor_z.is_some_and(|z| !z.is_finite()) {
            return Err(invalid("inputs.floor_z", "must be finite"));
        }
        if self.ros.domain_id > MAX_DOMAIN_ID {
            return Err(invalid("ros.domain_id", "must be in 0..=232"));
        }
        if self.ros.node_name.is_empty()
            || !self
                .ros
                .node_name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '_')
        {
            return Err(invalid("ros.node_name", "must be [A-Za-z0-9_]+"));
        }
        if self.ros.namespace != "/" && !crate::contract::is_ros_name(&self.ros.namespace) {
            return Err(invalid(
                "ros.namespace",
                "must be `/` or an absolute ROS name",
            ));
        }
        if self.ros.map_frame.is_empty() {
            return Err(invalid("ros.map_frame", "must not be empty"));
        }
        if self.ros.only_networks.is_empty() {
            return Err(invalid(
                "ros.only_networks",
                "list at least one interface address (127.0.0.1 for one computer)",
            ));
        }
        self.topics.validate().map_err(|m| invalid("topics", m))?;
        positive("relay.watchdog_s", self.relay.watchdog_s)?;
        if let Some(t) = &self.initial_target
            && t.trim().is_empty()
        {
            return Err(invalid("initial_target", "must not be blank"));
        }
        if let Some(e) = self
            .agent
            .labels
            .iter()
            .find(|e| e.id == self.inputs.unlabelled_label && !e.ignored)
        {
            return Err(invalid(
                "inputs.unlabelled_label",
                format!(
                    "label {} (`{}`) is not an ignored label of [agent]",
                    e.id, e.name
                ),
            ));
        }
        self.agent_config(0.0)?;
        Ok(())
    }

    /// The agent's configuration for a floor at world height `floor_z`: the
    /// `[agent]` section with the grid's floor, robot height and inflation
    /// radius, stair climbing (`frontier.levels.allow_stairs =
    /// robot.can_climb_stairs`, stairs always detected), the executor's
    /// arrival radii, and the unlabelled label, taken from the robot's
    /// sections.
    ///
    /// # Errors
    /// [`ConfigError::Agent`] when the result does not validate.
    pub fn agent_config(&self, floor_z: f64) -> Result<AgentConfig, ConfigError> {
        let mut c = self.agent.clone();
        c.frontier.grid.floor_z = floor_z;
        c.frontier.grid.robot_height = self.robot.height_m;
        c.frontier.grid.robot_radius = self.robot.inflation_radius();
        // A robot that cannot climb never plans over stairs, but still finds
        // them: they are what it reports when its floor is exhausted.
        c.frontier.levels.allow_stairs = self.robot.can_climb_stairs;
        c.frontier.levels.detect_stairs = true;
        let a = &self.arrival;
        for (kind, radius) in [
            (&mut c.executor.explore, a.explore_radius_m),
            (&mut c.executor.relocate, a.relocate_radius_m),
            (&mut c.executor.nav_to_object, a.object_radius_m),
        ] {
            kind.arrival.radius_m = radius;
            kind.arrival.vertical_tolerance_m = a.vertical_tolerance_m;
        }
        c.executor.nav_to_object.arrival.heading_tolerance_rad =
            a.object_heading_tolerance_deg.map(f64::to_radians);
        if !c
            .labels
            .iter()
            .any(|e| e.id == self.inputs.unlabelled_label)
        {
            c.labels.push(LabelEntry {
                id: self.inputs.unlabelled_label,
                name: "unlabelled".into(),
                ignored: true,
            });
        }
        c.validate()?;
        Ok(c)
    }
}
