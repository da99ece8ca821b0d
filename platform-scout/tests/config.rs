//! The Scout Mini configuration and the topic contract.

use sornav_platform_scout::config::{ConfigError, OdometryFrame, ScoutConfig};
use sornav_platform_scout::contract::{Direction, Qos, Topics, is_ros_name};

#[test]
fn committed_example_parses_validates_and_round_trips() {
    let c = ScoutConfig::from_toml(ScoutConfig::EXAMPLE).unwrap();
    assert_eq!(c.robot.name, "scout_mini");
    assert_eq!(c.sensors.odometry_frame, OdometryFrame::Lidar);
    assert_eq!(c.sensors.lidar.z, 0.55);
    assert_eq!(c.rates.control_hz, 1.0);
    assert_eq!(c.topics, Topics::default());
    assert_eq!(c.agent.frontier.grid.max_range, 8.0);
    assert_eq!(c.agent.semantic_map.max_range, 8.0);
    assert_eq!(c.agent.gate.n_obs, 3, "the paper's defaults are kept");
    let again = ScoutConfig::from_toml(&c.to_toml().unwrap()).unwrap();
    assert_eq!(again, c);
    // Everything is optional.
    assert_eq!(ScoutConfig::from_toml("").unwrap(), ScoutConfig::default());
}

#[test]
fn footprint_radii_and_agent_overrides() {
    let c = ScoutConfig::default();
    assert!((c.robot.inscribed_radius() - 0.29).abs() < 1e-12);
    assert!((c.robot.circumscribed_radius() - 0.306f64.hypot(0.29)).abs() < 1e-12);
    let a = c.agent_config(-0.2).unwrap();
    assert_eq!(a.frontier.grid.floor_z, -0.2);
    assert_eq!(a.frontier.grid.robot_radius, c.robot.inflation_radius());
    assert_eq!(a.frontier.grid.robot_height, 0.75);
    assert_eq!(a.executor.explore.arrival.radius_m, 1.0);
    assert_eq!(a.executor.nav_to_object.arrival.radius_m, 0.6);
    assert_eq!(a.executor.nav_to_object.arrival.heading_tolerance_rad, None);
    let unl = a.labels.iter().find(|e| e.id == 0).unwrap();
    assert!(unl.ignored && unl.name == "unlabelled");
}

#[test]
fn can_climb_stairs_drives_the_agent_levels() {
    // The Scout Mini cannot climb: never plans over stairs, still finds them.
    let c = ScoutConfig::from_toml(ScoutConfig::EXAMPLE).unwrap();
    assert!(!c.robot.can_climb_stairs);
    assert!(!ScoutConfig::default().robot.can_climb_stairs);
    let a = c.agent_config(0.0).unwrap();
    assert!(!a.frontier.levels.allow_stairs);
    assert!(a.frontier.levels.detect_stairs);
    // Whatever the [agent] section says, the robot's capability decides.
    let c = ScoutConfig::from_toml(
        "[robot]\ncan_climb_stairs = true\n[agent.frontier.levels]\nallow_stairs = false\ndetect_stairs = false\n",
    )
    .unwrap();
    let a = c.agent_config(0.0).unwrap();
    assert!(a.frontier.levels.allow_stairs && a.frontier.levels.detect_stairs);
    assert_eq!(invalid("[robot]\ncan_climb_stairs = 1\n"), "toml");
}

fn invalid(text: &str) -> String {
    match ScoutConfig::from_toml(text) {
        Err(ConfigError::Invalid { field, .. }) => field.to_owned(),
        Err(ConfigError::Toml(_)) => "toml".to_owned(),
        Err(e) => format!("other: {e}"),
        Ok(_) => panic!("accepted: {text}"),
    }
}

#[test]
fn invalid_configurations_name_the_field() {
    assert_eq!(
        invalid("[rates]\nodometry_max_age_s = 0.0"),
        "rates.odometry_max_age_s"
    );
    assert_eq!(
        invalid("[rates]\nodometry_max_age_s = nan"),
        "rates.odometry_max_age_s"
    );
    assert_eq!(
        invalid("[rates]\nodometry_max_age_s = 3601.0"),
        "rates.odometry_max_age_s"
    );
    assert_eq!(
        invalid("[rates]\nodometry_max_future_s = -1.0"),
        "rates.odometry_max_future_s"
    );
    assert_eq!(
        invalid("[rates]\nodometry_max_future_s = inf"),
        "rates.odometry_max_future_s"
    );
    assert_eq!(
        invalid("[robot]\nfootprint = [[0.3, 0.3], [-0.3, 0.3]]"),
        "robot.footprint"
    );
    assert_eq!(
        invalid("[robot]\nfootprint = [[0.3, -0.3], [-0.3, -0.3], [-0.3, 0.3], [0.3, 0.3]]"),
        "robot.footprint"
    ); // clockwise
    assert_eq!(
        invalid("[robot]\nfootprint = [[1.3, 0.3], [0.5, 0.3], [0.5, -0.3], [1.3, -0.3]]"),
        "robot.footprint"
    ); // origin outside
    assert_eq!(
        invalid("[robot]\nmax_speed_mps = 0.0"),
        "robot.max_speed_mps"
    );
    assert_eq!(invalid("[robot]\nheight_m = -1.0"), "robot.height_m");
    assert_eq!(invalid("[sensors.lidar]\nz = nan"), "sensors.lidar");
    assert_eq!(
        invalid("[arrival]\nobject_radius_m = 0.0"),
        "arrival.object_radius_m"
    );
    assert_eq!(
        invalid("[arrival]\nobject_heading_tolerance_deg = 270.0"),
        "arrival.object_heading_tolerance_deg"
    );
    assert_eq!(invalid("[rates]\ncontrol_hz = 0.0"), "rates.control_hz");
    assert_eq!(invalid("[rates]\nobserve_hz = 100.0"), "rates");
    assert_eq!(invalid("[ros]\ndomain_id = 300"), "ros.domain_id");
    assert_eq!(invalid("[ros]\nonly_networks = []"), "ros.only_networks");
    assert_eq!(invalid("[ros]\nnode_name = \"bad name\""), "ros.node_name");
    assert_eq!(invalid("[topics]\nway_point = \"way_point\""), "topics");
    assert_eq!(invalid("[topics]\nstatus = \"/joy\""), "topics");
    assert_eq!(
        invalid("[inputs]\nunlabelled_label = 10"),
        "inputs.unlabelled_label"
    ); // chair is not ignored
    assert_eq!(invalid("initial_target = \"  \""), "initial_target");
    assert_eq!(invalid("[robot]\nwheels = 4"), "toml");
    assert_eq!(invalid("speed = 1"), "toml");
    assert!(matches!(
        ScoutConfig::from_toml("[agent.gate]\nn_obs = 0"),
        Err(ConfigError::Agent(_))
    ));
}

#[test]
fn contract_defaults_types_and_qos() {
    let t = Topics::default();
    assert!(t.validate().is_ok());
    let specs = t.specs();
    let get = |role: &str| specs.iter().find(|s| s.role == role).unwrap().clone();
    let odom = get("odometry");
    assert_eq!(
        (odom.name.as_str(), odom.ros_type.as_str()),
        ("/state_estimation", "nav_msgs/msg/Odometry")
    );
    assert_eq!((odom.direction, odom.qos), (Direction::In, Qos::SENSOR));
    for role in ["occupancy", "traversability", "semantics"] {
        let s = get(role);
        assert_eq!(
            (s.ros_type.as_str(), s.qos),
            ("sensor_msgs/msg/PointCloud2", Qos::SENSOR)
        );
    }
    assert_eq!(get("semantics").name, "/semantic_scan");
    assert_eq!(get("traversability").name, "/terrain_map");
    let w = get("way_point");
    assert_eq!(
        (w.name.as_str(), w.ros_type.as_str(), w.direction, w.qos),
        (
            "/way_point",
            "geometry_msgs/msg/PointStamped",
            Direction::Out,
            Qos::COMMAND
        )
    );
    assert_eq!(get("target").qos, Qos::COMMAND);
    assert_eq!(get("status").name, "/sornav/status");
    assert_eq!(
        get("markers").ros_type,
        "visualization_msgs/msg/MarkerArray"
    );
    assert_eq!(get("cmd_vel_in").ros_type, "geometry_msgs/msg/TwistStamped");
    assert_eq!(get("cmd_vel_out").ros_type, "geometry_msgs/msg/Twist");
    assert!(get("cmd_vel_out").optional);
    // Every output is reliable: reliable readers (CMU planner, RViz) match it.
    for s in specs.iter().filter(|s| s.direction == Direction::Out) {
        assert!(
            s.qos.writer_matches_reader(Qos::Reliable { depth: 1 }),
            "{}",
            s.role
        );
    }
    // Sensor inputs are best effort: they match reliable and best-effort writers.
    assert!(Qos::Reliable { depth: 5 }.writer_matches_reader(Qos::SENSOR));
    assert!(Qos::BestEffort { depth: 5 }.writer_matches_reader(Qos::SENSOR));
    assert!(!Qos::BestEffort { depth: 5 }.writer_matches_reader(Qos::COMMAND));
}

#[test]
fn contract_qos_lookup_of_every_node_endpoint() {
    // RobotNode takes each endpoint's QoS from this lookup.
    let t = Topics::default();
    for role in [
        "odometry",
        "occupancy",
        "traversability",
        "semantics",
        "cmd_vel_in",
    ] {
        assert_eq!(t.qos(role), Some(Qos::SENSOR), "{role}");
    }
    for role in [
        "target",
        "way_point",
        "joy",
        "stop",
        "status",
        "markers",
        "path",
        "cmd_vel_out",
    ] {
        assert_eq!(t.qos(role), Some(Qos::COMMAND), "{role}");
    }
    assert_eq!(t.qos("no_such_role"), None);
}

#[test]
fn ros_names() {
    for ok in ["/way_point", "/sornav/status", "/a1/b_2"] {
        assert!(is_ros_name(ok), "{ok}");
    }
    for bad in [
        "way_point",
        "/",
        "//a",
        "/a//b",
        "/1a",
        "/a b",
        "/a__b",
        "/a/",
    ] {
        assert!(!is_ros_name(bad), "{bad}");
    }
}

/// Issue 21: `ROS_DOMAIN_ID` was ignored although docs/ROBOT.md says it is
/// used. Set and not blank, it replaces `ros.domain_id`; a bad value names
/// the variable.
#[test]
fn ros_domain_id_from_the_environment() {
    let mut config = ScoutConfig::from_toml("[ros]\ndomain_id = 7\n").unwrap();
    config.apply_ros_domain_id_env(None).unwrap();
    assert_eq!(config.ros.domain_id, 7);
    config.apply_ros_domain_id_env(Some("  ")).unwrap();
    assert_eq!(config.ros.domain_id, 7);
    config.apply_ros_domain_id_env(Some("42")).unwrap();
    assert_eq!(config.ros.domain_id, 42);
    for bad in ["233", "-1", "forty", "1e3"] {
        match config.apply_ros_domain_id_env(Some(bad)) {
            Err(ConfigError::Invalid { field, .. }) => assert_eq!(field, "ROS_DOMAIN_ID"),
            other => panic!("{bad}: expected an invalid ROS_DOMAIN_ID, got {other:?}"),
        }
        assert_eq!(config.ros.domain_id, 42, "unchanged by {bad}");
    }
}
