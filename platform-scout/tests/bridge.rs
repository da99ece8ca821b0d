//! The robot node's logic without DDS: decoded messages in, messages to
//! publish out.

use std::time::Duration;

use nalgebra::Point2;
use proptest::prelude::*;
use sornav_platform_scout::bridge::{
    Bridge, BridgeError, NodeState, Outgoing, Status, clamp_twist,
};
use sornav_platform_scout::config::ScoutConfig;
use sornav_platform_scout::markers::NAMESPACES;
use sornav_platform_scout::msg::*;
use sornav_platform_scout::pointcloud::{encode_xyzi, encode_xyzl};
use sornav_platform_scout::streams::SampleSource;

mod common;
use common::room;

fn ms(t: u64) -> Duration {
    Duration::from_millis(t)
}

fn semantic(pts: &[[f64; 4]]) -> PointCloud2 {
    encode_xyzl(Header::new(Time::default(), "map"), pts).unwrap()
}

fn xyzi(pts: &[[f64; 4]], frame: &str) -> PointCloud2 {
    encode_xyzi(Header::new(Time::default(), frame), pts).unwrap()
}

/// Odometry stamped with the wall clock (the bridge rejects stale stamps).
fn odom(x: f64, y: f64, yaw: f64) -> Odometry {
    common::odometry(Header::new(Time::now(), "map"), x, y, yaw)
}

/// Odometry stamped `stamp`.
fn odom_at(stamp: Time) -> Odometry {
    common::odometry(Header::new(stamp, "map"), 0.0, 0.0, 0.0)
}

/// A wall-clock reading `s` seconds after an arbitrary fixed time.
fn wall(s: f64) -> Time {
    Time::from_duration(Duration::from_secs(1_800_000_000) + Duration::from_secs_f64(s))
}

fn config() -> ScoutConfig {
    let mut c = ScoutConfig::default();
    c.rates.control_hz = 1.0;
    c.rates.observe_hz = 1.0;
    c
}

fn status_of(out: &[Outgoing]) -> Option<Status> {
    out.iter().rev().find_map(|o| match o {
        Outgoing::Status(s) => Some(serde_json::from_str(&s.data).unwrap()),
        _ => None,
    })
}

fn waypoints(out: &[Outgoing]) -> Vec<Point> {
    out.iter()
        .filter_map(|o| match o {
            Outgoing::WayPoint(w) => Some(w.point),
            _ => None,
        })
        .collect()
}

#[test]
fn start_enables_autonomy_and_shutdown_stops() {
    let mut b = Bridge::new(config()).unwrap();
    let out = b.start(ms(0));
    let Outgoing::Joy(joy) = &out[0] else {
        panic!("{out:?}")
    };
    assert_eq!(joy.axes.len(), 8);
    assert_eq!((joy.axes[2], joy.axes[4], joy.axes[5]), (-1.0, 1.0, 1.0));
    assert_eq!(joy.buttons.len(), 11);
    assert!(matches!(out[1], Outgoing::Stop(Int8 { data: 0 })));
    assert_eq!(
        status_of(&out).unwrap().state,
        NodeState::WaitingForOdometry
    );

    b.on_odometry(&odom(1.0, 2.0, 0.0), ms(0)).unwrap();
    let out = b.shutdown(ms(10));
    assert_eq!(
        waypoints(&out),
        vec![Point::new(1.0, 2.0, 0.0)],
        "hold at the base position"
    );
    assert!(
        out.iter()
            .any(|o| matches!(o, Outgoing::Stop(Int8 { data: 2 })))
    );
    assert_eq!(status_of(&out).unwrap().state, NodeState::Stopped);
    assert!(b.tick(ms(2000)).is_empty(), "nothing after shutdown");
}

#[test]
fn odometry_of_the_lidar_frame_gives_the_base_pose() {
    let mut c = config();
    c.sensors.lidar.x = 0.2; // LiDAR 0.2 m ahead of the base centre
    let mut b = Bridge::new(c).unwrap();
    let yaw = std::f64::consts::FRAC_PI_2;
    b.on_odometry(&odom(1.0, 1.0, yaw), ms(0)).unwrap();
    let p = b.status(ms(0)).pose.unwrap();
    assert!(
        (p[0] - 1.0).abs() < 1e-9 && (p[1] - 0.8).abs() < 1e-9 && p[2].abs() < 1e-9,
        "{p:?}"
    );
    assert!((p[3] - yaw).abs() < 1e-9);
    // The floor is the base height of the first message.
    assert_eq!(b.agent().unwrap().config().frontier.grid.floor_z, 0.0);
    let mut bad = odom(0.0, 0.0, 0.0);
    bad.pose.pose.orientation = Quaternion {
        x: 0.0,
        y: 0.0,
        z: 0.0,
        w: 0.0,
    };
    assert!(matches!(
        b.on_odometry(&bad, ms(1)),
        Err(BridgeError::BadOdometry)
    ));
    bad = odom(f64::NAN, 0.0, 0.0);
    assert!(matches!(
        b.on_odometry(&bad, ms(1)),
        Err(BridgeError::BadOdometry)
    ));
    assert_eq!(b.stats().rejected_messages, 2);
}

/// Tolerances of 1 s (stale) and 0.5 s (future), the defaults, stated.
fn stamp_config() -> ScoutConfig {
    let mut c = config();
    c.rates.odometry_max_age_s = 1.0;
    c.rates.odometry_max_future_s = 0.5;
    c
}

#[test]
fn stale_odometry_is_rejected_and_counted() {
    let mut b = Bridge::new(stamp_config()).unwrap();
    // 1.5 s old on receipt: rejected, not used (no agent, no pose).
    let e = b.on_odometry_at(&odom_at(wall(0.0)), ms(0), wall(1.5));
    assert!(
        matches!(e, Err(BridgeError::StaleOdometry { age_s, max_s })
            if (age_s - 1.5).abs() < 1e-9 && max_s == 1.0),
        "{e:?}"
    );
    // A zero stamp (never set) is stale.
    assert!(matches!(
        b.on_odometry_at(&odom_at(Time::default()), ms(10), wall(0.0)),
        Err(BridgeError::StaleOdometry { .. })
    ));
    // So is an hour-old one through the wall-clock entry point.
    let hour_ago = Time::from_system_time(std::time::SystemTime::now() - Duration::from_secs(3600));
    assert!(matches!(
        b.on_odometry(&odom_at(hour_ago), ms(20)),
        Err(BridgeError::StaleOdometry { .. })
    ));
    let s = b.status(ms(20));
    assert_eq!(s.state, NodeState::WaitingForOdometry);
    assert!(s.pose.is_none() && b.agent().is_none());
    assert_eq!(s.bridge.odometry, 0);
    assert_eq!(s.bridge.rejected_messages, 3);
    assert_eq!(s.rejections.get("stale_odometry"), Some(&3));
    assert!(s.last_error.unwrap().contains("rates.odometry_max_age_s"));
}

#[test]
fn future_odometry_is_rejected_and_counted() {
    let mut b = Bridge::new(stamp_config()).unwrap();
    let e = b.on_odometry_at(&odom_at(wall(10.75)), ms(0), wall(10.0));
    assert!(
        matches!(e, Err(BridgeError::FutureOdometry { ahead_s, max_s })
            if (ahead_s - 0.75).abs() < 1e-9 && max_s == 0.5),
        "{e:?}"
    );
    assert_eq!(e.unwrap_err().cause(), "future_odometry");
    let s = b.status(ms(0));
    assert!(s.pose.is_none() && b.agent().is_none());
    assert_eq!(s.rejections.get("future_odometry"), Some(&1));
    assert_eq!(s.bridge.rejected_messages, 1);
}

#[test]
fn odometry_within_the_stamp_tolerances_is_used() {
    let mut b = Bridge::new(stamp_config()).unwrap();
    // 0.9 s old, 0.4 s ahead, then exactly 1 s old and exactly 0.5 s
    // ahead (on the limits): all used.
    for (i, (stamp, received)) in [(0.0, 0.9), (10.4, 10.0), (20.0, 21.0), (30.5, 30.0)]
        .into_iter()
        .enumerate()
    {
        b.on_odometry_at(&odom_at(wall(stamp)), ms(i as u64 * 100), wall(received))
            .unwrap();
    }
    let s = b.status(ms(300));
    assert_eq!(s.bridge.odometry, 4);
    assert_eq!(s.bridge.rejected_messages, 0);
    assert!(s.rejections.is_empty());
    assert_eq!(s.state, NodeState::Idle);
    // A stale message between fresh ones keeps the last good pose.
    assert!(
        b.on_odometry_at(&odom_at(wall(0.0)), ms(400), wall(40.0))
            .is_err()
    );
    assert_eq!(b.status(ms(400)).bridge.odometry, 4);
    assert_eq!(b.state(), NodeState::Idle);
}

/// Stamps in simulated time (`use_sim_time`: a bag replay) are an hour or
/// years away from the wall clock: with `rates.check_odometry_stamps =
/// false` they are used, not rejected.
#[test]
fn odometry_stamps_in_simulated_time_are_used_when_the_check_is_off() {
    let mut c = stamp_config();
    c.rates.check_odometry_stamps = false;
    let mut b = Bridge::new(c).unwrap();
    let hour_ago = Time {
        sec: wall(0.0).sec - 3600,
        nanosec: 0,
    };
    for (i, stamp) in [Time::default(), hour_ago, wall(7200.0)]
        .into_iter()
        .enumerate()
    {
        b.on_odometry_at(&odom_at(stamp), ms(i as u64 * 100), wall(0.0))
            .unwrap();
    }
    assert_eq!(b.stats().odometry, 3);
    assert_eq!(b.stats().rejected_messages, 0);
    // on by default
    assert!(ScoutConfig::default().rates.check_odometry_stamps);
}

#[test]
fn bad_inputs_are_rejected_and_counted() {
    let mut b = Bridge::new(config()).unwrap();
    let pts = room();
    assert!(matches!(
        b.on_semantic_scan(&semantic(&pts), ms(0)),
        Err(BridgeError::NoOdometry(_))
    ));
    b.on_odometry(&odom(0.0, 0.0, 0.0), ms(0)).unwrap();
    assert!(matches!(
        b.on_registered_scan(&xyzi(&pts, "base_link"), ms(0)),
        Err(BridgeError::Frame { .. })
    ));
    let mut broken = semantic(&pts);
    broken.data.truncate(100);
    assert!(matches!(
        b.on_semantic_scan(&broken, ms(0)),
        Err(BridgeError::Cloud { .. })
    ));
    // A semantic cloud without a label channel.
    assert!(matches!(
        b.on_semantic_scan(&xyzi(&pts, "map"), ms(0)),
        Err(BridgeError::Cloud { .. })
    ));
    assert!(matches!(
        b.on_target(&RosString { data: " ".into() }, ms(0)),
        Err(BridgeError::BlankTarget)
    ));
    assert!(matches!(
        b.on_target(
            &RosString {
                data: "find the spaceship".into()
            },
            ms(0)
        ),
        Err(BridgeError::Agent(_))
    ));
    let s = b.status(ms(0));
    // The cloud before the first odometry is a start-up race, counted
    // apart.
    assert_eq!(s.bridge.clouds_before_odometry, 1);
    assert_eq!(s.bridge.rejected_messages, 5);
    assert_eq!(s.state, NodeState::Idle);
    assert!(s.last_error.unwrap().contains("spaceship"));
    // "/map" is accepted as "map".
    assert!(b.on_terrain_map(&xyzi(&pts, "/map"), ms(0)).is_ok());
}

/// Issue 21: rejections were logged only at debug level and only the
/// latest showed (`last_error`), and undecodable samples were never
/// reported. Each is now counted by cause in the status and logged at warn,
/// at most once per cause and `REJECTION_WARN_INTERVAL`.
#[test]
fn rejections_are_counted_by_cause_and_logged_at_a_limited_rate() {
    use tracing_subscriber::Layer as _;
    use tracing_subscriber::layer::SubscriberExt;
    let sink = sornav_test_support::log_capture::LogSink::default();
    let writer = sink.clone();
    let subscriber = tracing_subscriber::registry().with(
        tracing_subscriber::fmt::layer()
            .with_ansi(false)
            .with_writer(move || writer.clone())
            .with_filter(tracing_subscriber::filter::LevelFilter::WARN),
    );
    let mut b = Bridge::new(config()).unwrap();
    tracing::subscriber::with_default(subscriber, || {
        b.on_odometry(&odom(0.0, 0.0, 0.0), ms(0)).unwrap();
        let mut wrong = odom(0.0, 0.0, 0.0);
        wrong.header.frame_id = "base_link".into();
        // a burst of 50 in 4.9 s, then one after the interval
        for t in 0..50 {
            assert!(b.on_odometry(&wrong, ms(t * 100)).is_err());
        }
        assert!(b.on_odometry(&wrong, ms(5_000)).is_err());
        b.on_undecodable("odometry", "buffer too short", ms(100));
        b.on_undecodable("odometry", "buffer too short", ms(200));
        // stale and future stamps: a cause each, one warning per burst
        for t in 0..3 {
            let stale = b.on_odometry_at(&odom_at(wall(0.0)), ms(1_000 + t * 100), wall(2.0));
            assert!(stale.is_err());
        }
        assert!(
            b.on_odometry_at(&odom_at(wall(3.0)), ms(1_500), wall(2.0))
                .is_err()
        );
        assert!(
            b.on_target(&RosString { data: " ".into() }, ms(300))
                .is_err()
        );
    });
    let s = b.status(ms(5_000));
    let expect: std::collections::BTreeMap<String, u64> = [
        ("frame:odometry", 51),
        ("undecodable:odometry", 2),
        ("blank_target", 1),
        ("stale_odometry", 3),
        ("future_odometry", 1),
    ]
    .into_iter()
    .map(|(k, v)| (k.to_owned(), v))
    .collect();
    assert_eq!(s.rejections, expect);
    assert_eq!(s.bridge.rejected_messages, 56);
    assert_eq!(s.bridge.undecodable_samples, 2);
    let log = sink.text();
    let lines = |needle: &str| log.lines().filter(|l| l.contains(needle)).count();
    // one warning at the burst's start, one after the interval (saying how
    // many were not logged), one per other cause
    assert_eq!(lines("odometry is in frame `base_link`"), 2, "{log}");
    assert!(log.contains("not_logged=49"), "{log}");
    assert_eq!(lines("failed to decode"), 1, "{log}");
    assert_eq!(lines("blank target"), 1, "{log}");
    assert_eq!(lines("more than rates.odometry_max_age_s"), 1, "{log}");
    assert_eq!(lines("more than rates.odometry_max_future_s"), 1, "{log}");
    assert!(log.lines().all(|l| l.contains("WARN")), "{log}");
}

#[test]
fn unlabelled_returns_feed_occupancy_only() {
    let mut b = Bridge::new(config()).unwrap();
    b.on_odometry(&odom(0.0, 0.0, 0.0), ms(0)).unwrap();
    let labelled = [[1.025, 0.025, 0.425, 15.0]];
    // One unlabelled return in the labelled point's voxel, one elsewhere.
    let unlabelled = [[1.03, 0.03, 0.43, 0.0], [2.025, 1.025, 0.425, 0.0]];
    b.on_semantic_scan(&semantic(&labelled), ms(0)).unwrap();
    b.on_registered_scan(&xyzi(&unlabelled, "map"), ms(0))
        .unwrap();
    // Terrain: intensity is the height above ground; re-projected to it.
    b.on_terrain_map(&xyzi(&[[3.025, 0.025, 5.0, 0.425]], "map"), ms(0))
        .unwrap();
    b.tick(ms(0));
    let s = b.status(ms(0));
    // A labelled cloud and an occupancy-only frame from the same pose.
    assert_eq!(s.bridge.observations, 2);
    let stats = s.agent.unwrap();
    assert_eq!((stats.observations, stats.occupancy_observations), (2, 1));
    let a = b.agent().unwrap();
    // The semantic map holds the labelled point only, with one hit: the
    // unlabelled return in its voxel did not dilute it.
    let m = a.semantic_map();
    assert_eq!(m.integrations(), 1);
    assert_eq!(m.voxel_count(), 1);
    let (_, evidence) = m.voxels().next().unwrap();
    assert_eq!(evidence.hits(), 1);
    // Every return reached the occupancy grid, the terrain cell at its
    // height above the floor (in the obstacle band).
    let grid = a
        .frontier_map()
        .level_map(sornav::frontier_graph::LevelId(0))
        .unwrap()
        .grid();
    for (x, y) in [(1.025, 0.025), (2.025, 1.025), (3.025, 0.025)] {
        let cell = grid.cell_of(&Point2::new(x, y)).unwrap();
        assert!(
            grid.log_odds(cell) > 0.0,
            "({x}, {y}) has no obstacle evidence"
        );
    }
    // Disabled inputs are ignored.
    let mut c = config();
    c.inputs.use_registered_scan = false;
    c.inputs.use_terrain_map = false;
    let mut b = Bridge::new(c).unwrap();
    b.on_odometry(&odom(0.0, 0.0, 0.0), ms(0)).unwrap();
    assert_eq!(
        b.on_registered_scan(&xyzi(&unlabelled, "map"), ms(0))
            .unwrap(),
        0
    );
    assert_eq!(
        b.on_terrain_map(&xyzi(&unlabelled, "map"), ms(0)).unwrap(),
        0
    );
}

#[test]
fn point_cap_drops_the_oldest_clouds() {
    let mut c = config();
    c.inputs.max_points_per_observation = 10;
    let mut b = Bridge::new(c).unwrap();
    b.on_odometry(&odom(0.0, 0.0, 0.0), ms(0)).unwrap();
    let cloud: Vec<[f64; 4]> = (0..6)
        .map(|i| [1.0 + f64::from(i) * 0.1, 0.0, 0.3, 1.0])
        .collect();
    b.on_semantic_scan(&semantic(&cloud), ms(0)).unwrap();
    b.on_semantic_scan(&semantic(&cloud), ms(0)).unwrap();
    assert_eq!(b.stats().dropped_points, 6);

    // A cloud whose points were all skipped sits at the front of the
    // buffer: it must not stop the trimming.
    let mut c = config();
    c.inputs.max_points_per_observation = 10;
    let mut b = Bridge::new(c).unwrap();
    b.on_odometry(&odom(0.0, 0.0, 0.0), ms(0)).unwrap();
    let all_nan = [[f64::NAN, 0.0, 0.3, 1.0]];
    assert_eq!(b.on_semantic_scan(&semantic(&all_nan), ms(0)).unwrap(), 0);
    b.on_semantic_scan(&semantic(&cloud), ms(0)).unwrap();
    b.on_semantic_scan(&semantic(&cloud), ms(0)).unwrap();
    assert_eq!(b.stats().dropped_points, 6);
    b.tick(ms(0));
    assert_eq!(b.agent().unwrap().semantic_map().integrations(), 1);
    assert_eq!(b.agent().unwrap().stats().observations, 1);
}

/// Issue 21: one cloud above `max_points_per_observation` was dropped
/// whole; it is now thinned to the cap, its kept points spread over the
/// whole cloud.
#[test]
fn one_cloud_above_the_cap_is_thinned_not_dropped() {
    let mut c = config();
    c.inputs.max_points_per_observation = 100;
    let mut b = Bridge::new(c.clone()).unwrap();
    b.on_odometry(&odom(0.0, 0.0, 0.0), ms(0)).unwrap();
    // 1000 points 1 cm apart along 10 m (200 voxels of 5 cm)
    let line: Vec<[f64; 4]> = (0..1000)
        .map(|i| [1.0 + f64::from(i) * 0.01, 0.0, 0.3, 1.0])
        .collect();
    b.on_semantic_scan(&semantic(&line), ms(0)).unwrap();
    assert_eq!(
        (b.stats().dropped_points, b.stats().thinned_points),
        (0, 900)
    );
    b.tick(ms(0));
    let a = b.agent().unwrap();
    assert_eq!(a.stats().observations, 1);
    // the 100 kept points lie 10 cm apart over the whole line: 100 voxels
    // (the first 100 points would fill 20)
    assert_eq!(a.semantic_map().voxel_count(), 100);

    // both buffers with one cloud each, above the cap together: both
    // thinned, to exactly the cap
    let mut b = Bridge::new(c).unwrap();
    b.on_odometry(&odom(0.0, 0.0, 0.0), ms(0)).unwrap();
    b.on_semantic_scan(&semantic(&line[..80]), ms(0)).unwrap();
    b.on_registered_scan(&xyzi(&line[..80], "map"), ms(0))
        .unwrap();
    assert_eq!(
        (b.stats().dropped_points, b.stats().thinned_points),
        (0, 60)
    );
}

/// Issue 21: samples lost before decoding (a best-effort reader drops a
/// cloud whose fragments it cannot reassemble, and RustDDS reports nothing)
/// are visible in the status: gaps in a writer's sequence numbers are
/// counted as lost samples, whatever the timing, and a stream that stops
/// is reported silent once, then back when it resumes.
#[test]
fn lost_and_silent_streams_are_reported_in_the_status() {
    let mut b = Bridge::new(config()).unwrap();
    let cloud = semantic(&[[1.0, 0.0, 0.3, 1.0]]);
    let writer = |w: u8, sequence: i64| {
        Some(SampleSource {
            writer: [w; 16],
            sequence,
        })
    };
    let mut t_ms = 0;
    // Clouds at irregular times; numbers 13, 14 and 21 never arrive.
    for i in 1..=30i64 {
        t_ms += if i % 3 == 0 { 250 } else { 60 };
        b.on_delivery("odometry", writer(1, i), ms(t_ms));
        b.on_odometry(&odom(0.0, 0.0, 0.0), ms(t_ms)).unwrap();
        if ![13, 14, 21].contains(&i) {
            b.on_delivery("semantic_scan", writer(2, i), ms(t_ms));
            b.on_semantic_scan(&cloud, ms(t_ms)).unwrap();
        }
        b.tick(ms(t_ms));
    }
    let s = b.status(ms(t_ms));
    let scan = s.streams["semantic_scan"];
    assert_eq!((scan.received, scan.gaps, scan.lost), (27, 2, 3));
    assert!(!scan.silent);
    assert_eq!(s.streams["odometry"].lost, 0, "irregular timing is no loss");

    // The clouds stop (every one too large to reassemble); odometry goes on.
    for k in 1..=80i64 {
        t_ms += 100;
        b.on_delivery("odometry", writer(1, 30 + k), ms(t_ms));
        b.on_odometry(&odom(0.0, 0.0, 0.0), ms(t_ms)).unwrap();
        b.tick(ms(t_ms));
    }
    let s = b.status(ms(t_ms));
    let scan = s.streams["semantic_scan"];
    assert!(scan.silent);
    assert_eq!(scan.silences, 1, "one silence, counted once");
    assert!(scan.last_age_s.unwrap() > 7.9);
    assert!(!s.streams["odometry"].silent);

    // ... and come back, 80 numbers later.
    t_ms += 100;
    b.on_delivery("semantic_scan", writer(2, 111), ms(t_ms));
    let scan = b.status(ms(t_ms)).streams["semantic_scan"];
    assert!(!scan.silent);
    assert_eq!((scan.silences, scan.lost), (1, 3 + 80));
    // The JSON status carries it.
    let json = serde_json::to_value(b.status(ms(t_ms))).unwrap();
    assert_eq!(json["streams"]["semantic_scan"]["lost"], 83);
}

/// Drives the bridge in the room: returns the outputs of every tick.
fn run(b: &mut Bridge, from: u64, to: u64, pose: (f64, f64, f64)) -> Vec<Outgoing> {
    run_in(b, &room(), from, to, pose)
}

/// [`run`] in another scene.
fn run_in(
    b: &mut Bridge,
    pts: &[[f64; 4]],
    from: u64,
    to: u64,
    pose: (f64, f64, f64),
) -> Vec<Outgoing> {
    let cloud = semantic(pts);
    let mut out = Vec::new();
    for t in (from..to).step_by(250) {
        b.on_odometry(&odom(pose.0, pose.1, pose.2), ms(t)).unwrap();
        if t % 500 == 0 {
            b.on_semantic_scan(&cloud, ms(t)).unwrap();
        }
        out.extend(b.tick(ms(t)));
    }
    out
}

#[test]
fn finds_the_tv_then_switches_target_keeping_the_maps() {
    let mut b = Bridge::new(config()).unwrap();
    b.on_odometry(&odom(0.0, 0.0, 0.0), ms(0)).unwrap();
    let out = b
        .on_target(
            &RosString {
                data: "find the television".into(),
            },
            ms(0),
        )
        .unwrap();
    assert!(
        matches!(out[0], Outgoing::Joy(_)),
        "a new target re-enables autonomy"
    );
    assert_eq!(
        status_of(&out).unwrap().target.as_deref(),
        Some("tv_monitor")
    );

    // N_obs = 3 observations, then NAV_TO_OBJECT toward the TV.
    let out = run(&mut b, 0, 5000, (0.0, 0.0, 0.0));
    let s = status_of(&out).unwrap();
    let m = s.active_mission.clone().expect("a mission");
    assert_eq!(m.kind, "nav_to_object");
    let wps = waypoints(&out);
    let nav = *wps.last().unwrap();
    let d = (nav.x - m.waypoint[0]).hypot(nav.y - m.waypoint[1]);
    assert!(
        d < 1e-6,
        "the mission's way point is published: {nav:?} vs {:?}",
        m.waypoint
    );
    assert!(
        out.iter()
            .any(|o| matches!(o, Outgoing::Path(p) if !p.poses.is_empty()))
    );
    let dist = (nav.x - nav.x.clamp(-1.2, -0.7)).hypot(nav.y - 1.875);
    assert!(dist < 0.6, "{nav:?}");
    // Re-published while the mission lasts (1 s period, ticks every 250 ms).
    assert!(
        wps.iter()
            .filter(|w| (w.x - nav.x).hypot(w.y - nav.y) < 1e-6)
            .count()
            >= 2,
        "{wps:?}"
    );
    let markers = out.iter().rev().find_map(|o| match o {
        Outgoing::Markers(m) => Some(m.clone()),
        _ => None,
    });
    let markers = markers.expect("markers");
    assert_eq!(markers.markers[0].action, Marker::DELETEALL);
    assert!(
        markers.markers[1..]
            .iter()
            .all(|m| NAMESPACES.contains(&m.ns.as_str()))
    );
    assert!(
        markers
            .markers
            .iter()
            .any(|m| m.ns == "object_labels" && m.text.starts_with("tv"))
    );
    assert!(markers.markers.iter().any(|m| m.ns == "mission"));
    assert!(
        markers
            .markers
            .iter()
            .any(|m| m.ns == "footprint" && m.points.len() == 5)
    );

    // The planner drives there: arrival from odometry, verification, STOP.
    let yaw = (1.875 - nav.y).atan2(-0.95 - nav.x);
    let lidar_x = nav.x;
    let out = run(&mut b, 5000, 12_000, (lidar_x, nav.y, yaw));
    let s = status_of(&out).unwrap();
    assert_eq!(s.state, NodeState::Confirmed, "{:?}", s.last_decision);
    assert_eq!(s.confirmed.len(), 1);
    assert_eq!(s.confirmed[0].category, "tv_monitor");
    assert!((s.confirmed[0].centre[0] + 0.95).abs() < 0.1);
    // The status reports the confirming decision while the agent's log is
    // drained at every step (it would otherwise grow for as long as the
    // node runs).
    assert_eq!(s.last_decision.as_ref().unwrap().action, "stop");
    assert!(b.agent().unwrap().decisions().is_empty());
    assert!(
        waypoints(&out).contains(&Point::new(nav.x, nav.y, 0.0)),
        "hold at the target"
    );
    let observations = s.agent.unwrap().observations;
    let objects = s.objects;

    // Next request: the maps are kept.
    let out = b
        .on_target(
            &RosString {
                data: "toilet".into(),
            },
            ms(12_000),
        )
        .unwrap();
    let s = status_of(&out).unwrap();
    assert_eq!(
        (s.state, s.target.as_deref()),
        (NodeState::Searching, Some("toilet"))
    );
    assert_eq!(s.agent.unwrap().observations, observations);
    assert_eq!(s.objects, objects);
    let out = run(&mut b, 12_000, 14_000, (lidar_x, nav.y, yaw));
    let s = status_of(&out).unwrap();
    assert!(s.agent.unwrap().observations > observations);
    assert_eq!(s.confirmed.len(), 1, "the first confirmation is kept");
}

#[test]
fn a_repeated_request_does_not_restart_the_search() {
    let mut b = Bridge::new(config()).unwrap();
    let tv = |data: &str| RosString { data: data.into() };
    b.on_target(&tv("find the television"), ms(0)).unwrap();
    let out = run(&mut b, 0, 5000, (0.0, 0.0, 0.0));
    let m = status_of(&out).unwrap().active_mission.expect("a mission");
    assert_eq!(m.kind, "nav_to_object");
    // The same category again (other words): autonomy re-enabled, the
    // mission and the gate's evidence kept.
    let out = b.on_target(&tv("tv"), ms(5000)).unwrap();
    assert!(matches!(out[0], Outgoing::Joy(_)));
    let s = status_of(&out).unwrap();
    assert_eq!(s.active_mission, Some(m.clone()));
    assert_eq!(s.request.as_deref(), Some("find the television"));
    // Another category restarts.
    let s = status_of(&b.on_target(&tv("toilet"), ms(5000)).unwrap()).unwrap();
    assert_eq!(s.active_mission, None);
    assert_eq!(s.target.as_deref(), Some("toilet"));
}

#[test]
fn a_confirmed_target_stays_confirmed_across_stale_odometry() {
    let mut b = Bridge::new(config()).unwrap();
    b.on_target(&RosString { data: "tv".into() }, ms(0))
        .unwrap();
    let out = run(&mut b, 0, 5000, (0.0, 0.0, 0.0));
    let nav = *waypoints(&out).last().unwrap();
    let yaw = (1.875 - nav.y).atan2(-0.95 - nav.x);
    let _ = run(&mut b, 5000, 12_000, (nav.x, nav.y, yaw));
    assert_eq!(b.state(), NodeState::Confirmed);
    let _ = b.tick(ms(15_000)); // odometry last at 11.75 s
    assert_eq!(b.state(), NodeState::WaitingForOdometry);
    let out = run(&mut b, 15_000, 20_000, (nav.x, nav.y, yaw));
    let s = status_of(&out).unwrap();
    assert_eq!(s.state, NodeState::Confirmed, "not searching again");
    assert_eq!(s.confirmed.len(), 1, "no second confirmation");
}

/// The room with its doorway walled up: nothing to explore.
fn closed_room() -> Vec<[f64; 4]> {
    let mut pts = room();
    for j in -12..=12 {
        for h in 0..18 {
            pts.push([3.0, f64::from(j) * 0.05, f64::from(h) * 0.05, 1.0]);
        }
    }
    pts
}

#[test]
fn an_exhausted_search_resumes_when_a_candidate_appears() {
    let c = config();
    let toilet = c
        .agent
        .labels
        .iter()
        .find(|e| e.name == "toilet")
        .expect("toilet in the vocabulary")
        .id;
    let mut b = Bridge::new(c).unwrap();
    b.on_target(
        &RosString {
            data: "find the toilet".into(),
        },
        ms(0),
    )
    .unwrap();
    let room = closed_room();
    let out = run_in(&mut b, &room, 0, 4000, (0.0, 0.0, 0.0));
    let s = status_of(&out).unwrap();
    assert_eq!(s.state, NodeState::Exhausted, "{:?}", s.last_decision);
    assert_eq!(s.frontiers, 0);
    assert_eq!(
        waypoints(&out).last(),
        Some(&Point::new(0.0, 0.0, 0.0)),
        "holding"
    );
    let steps = s.bridge.steps;

    // Still stepped while exhausted: a toilet comes into view (someone
    // opened the bathroom door), gathers N_obs observations, and the
    // search resumes with NAV_TO_OBJECT.
    let mut with_toilet = room;
    for a in 0..8 {
        for h in 0..8 {
            let (x, z) = (1.025 + f64::from(a) * 0.05, 0.025 + f64::from(h) * 0.05);
            with_toilet.push([x, -1.825, z, f64::from(toilet)]);
        }
    }
    let out = run_in(&mut b, &with_toilet, 4000, 9000, (0.0, 0.0, 0.0));
    let s = status_of(&out).unwrap();
    assert!(s.bridge.steps > steps);
    assert_eq!(s.state, NodeState::Searching, "{:?}", s.last_decision);
    let m = s.active_mission.expect("a mission");
    assert_eq!(m.kind, "nav_to_object");
    assert!(m.waypoint[0] > 0.5 && m.waypoint[1] < -0.5, "{m:?}");
}

#[test]
fn stale_odometry_holds_the_robot() {
    let mut b = Bridge::new(config()).unwrap();
    b.on_target(&RosString { data: "tv".into() }, ms(0))
        .unwrap();
    let _ = run(&mut b, 0, 3000, (0.5, 0.0, 0.0));
    assert_eq!(b.state(), NodeState::Searching);
    let out = b.tick(ms(6000)); // odometry last at 2.75 s, timeout 1 s
    assert_eq!(waypoints(&out), vec![Point::new(0.5, 0.0, 0.0)]);
    assert_eq!(b.state(), NodeState::WaitingForOdometry);
    let _ = run(&mut b, 6000, 7000, (0.5, 0.0, 0.0));
    assert_eq!(b.state(), NodeState::Searching);
}

#[test]
fn pending_target_applies_at_the_first_odometry() {
    let mut c = config();
    c.initial_target = Some("find the television".into());
    let mut b = Bridge::new(c).unwrap();
    assert_eq!(
        b.status(ms(0)).target.as_deref(),
        Some("find the television")
    );
    b.on_odometry(&odom(0.0, 0.0, 0.0), ms(0)).unwrap();
    let s = b.status(ms(0));
    assert_eq!(
        (s.state, s.target.as_deref()),
        (NodeState::Searching, Some("tv_monitor"))
    );
}

#[test]
fn relay_clamps_and_watchdog_zeroes() {
    let cmd = TwistStamped {
        header: Header::default(),
        twist: Twist {
            linear: Vector3::new(3.0, 0.0, 1.0),
            angular: Vector3::new(0.5, 0.0, 5.0),
        },
    };
    let mut b = Bridge::new(config()).unwrap();
    assert!(
        b.on_cmd_vel(&cmd, ms(0)).is_none(),
        "relay disabled by default"
    );
    let mut c = config();
    c.relay.enabled = true;
    let mut b = Bridge::new(c).unwrap();
    let Some(Outgoing::CmdVel(t)) = b.on_cmd_vel(&cmd, ms(0)) else {
        panic!()
    };
    assert_eq!(t.linear, Vector3::new(0.8, 0.0, 0.0));
    assert_eq!(t.angular, Vector3::new(0.0, 0.0, 90f64.to_radians()));
    assert!(
        b.tick(ms(400))
            .iter()
            .all(|o| !matches!(o, Outgoing::CmdVel(_)))
    );
    let out = b.tick(ms(600));
    assert_eq!(
        out.iter()
            .filter(|o| matches!(o, Outgoing::CmdVel(t) if *t == Twist::default()))
            .count(),
        1
    );
    assert!(
        b.tick(ms(900))
            .iter()
            .all(|o| !matches!(o, Outgoing::CmdVel(_))),
        "watchdog fires once"
    );
    assert!(
        b.shutdown(ms(1000))
            .iter()
            .any(|o| matches!(o, Outgoing::CmdVel(t) if *t == Twist::default()))
    );
}

proptest! {
    #[test]
    fn clamped_twists_respect_the_limits(
        vx in -10f64..10.0, vy in -10f64..10.0, vz in -10f64..10.0, wz in -10f64..10.0,
        max_v in 0.1f64..3.0, max_w in 0.1f64..3.0,
    ) {
        let t = Twist { linear: Vector3::new(vx, vy, vz), angular: Vector3::new(1.0, 1.0, wz) };
        let c = clamp_twist(&t, max_v, max_w);
        let speed = c.linear.x.hypot(c.linear.y);
        prop_assert!(speed <= max_v + 1e-9);
        prop_assert!(c.angular.z.abs() <= max_w + 1e-12);
        prop_assert_eq!((c.linear.z, c.angular.x, c.angular.y), (0.0, 0.0, 0.0));
        // Direction kept; unchanged when within the limits.
        prop_assert!((c.linear.x * vy - c.linear.y * vx).abs() < 1e-9);
        if vx.hypot(vy) <= max_v {
            prop_assert_eq!((c.linear.x, c.linear.y), (vx, vy));
        }
    }
}

#[test]
fn clamp_handles_non_finite() {
    let t = Twist {
        linear: Vector3::new(f64::NAN, 1.0, 0.0),
        angular: Vector3::new(0.0, 0.0, f64::INFINITY),
    };
    let c = clamp_twist(&t, 0.5, 1.0);
    assert_eq!((c.linear.x, c.linear.y, c.angular.z), (0.0, 0.5, 0.0));
}
