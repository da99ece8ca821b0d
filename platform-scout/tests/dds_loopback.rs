//! The robot node over real DDS on loopback, inside a private network
//! namespace, on a private domain id: the test plays the CMU stack and the
//! sensors (odometry, semantic scan, registered scan, terrain map) of a
//! room with a television, requests "find the television", and checks that
//! `/joy`, `/way_point`, `/sornav/status` and, after the robot "arrives",
//! the confirmation and the shutdown stop arrive with the expected content.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::thread;
use std::time::{Duration, Instant};

use sornav_platform_scout::bridge::{NodeState, Status};
use sornav_platform_scout::config::ScoutConfig;
use sornav_platform_scout::contract::Qos;
use sornav_platform_scout::msg::*;
use sornav_platform_scout::node::{self, RobotNode};
use sornav_platform_scout::pointcloud::{encode_xyzi, encode_xyzl};
use sornav_test_support::netns;

mod common;
use common::room;

/// A private domain id (ROS 2 allows 0-232; 0 is the default to avoid).
const DOMAIN: u16 = 171;

/// What the test has received from the node so far.
#[derive(Default)]
struct Received {
    statuses: Vec<Status>,
    waypoints: Vec<PointStamped>,
    joys: Vec<Joy>,
    stops: Vec<Int8>,
    markers: usize,
}

fn header() -> Header {
    Header::new(Time::now(), "map")
}

fn wait_for<T>(timeout: Duration, mut f: impl FnMut() -> Option<T>) -> Option<T> {
    let t0 = Instant::now();
    while t0.elapsed() < timeout {
        if let Some(v) = f() {
            return Some(v);
        }
        thread::sleep(Duration::from_millis(20));
    }
    None
}

#[test]
fn waypoint_and_status_over_loopback() {
    if !netns::isolate("waypoint_and_status_over_loopback") {
        return;
    }
    let mut config = ScoutConfig::default();
    config.ros.domain_id = DOMAIN;
    config.rates.control_hz = 4.0;
    config.rates.observe_hz = 4.0;
    config.rates.markers_period_s = 0.5;
    config.validate().unwrap();

    let stop = Arc::new(AtomicBool::new(false));
    let node_thread = {
        let stop = Arc::clone(&stop);
        let config = config.clone();
        thread::spawn(move || {
            let mut robot = RobotNode::new(config).expect("robot node");
            robot.run(&stop, Duration::from_millis(10), Duration::from_millis(500));
            robot.bridge().confirmed().to_vec()
        })
    };

    // The test plays the CMU stack, the sensors and the operator.
    let ctx = node::loopback_context(DOMAIN).unwrap();
    let mut n = node::ros_node(&ctx, "/", "cmu_stack_stub").unwrap();
    let t = &config.topics;
    let odom_pub = node::publisher::<Odometry>(&mut n, &t.state_estimation, Qos::SENSOR).unwrap();
    let sem_pub = node::publisher::<PointCloud2>(&mut n, &t.semantic_scan, Qos::SENSOR).unwrap();
    let reg_pub = node::publisher::<PointCloud2>(&mut n, &t.registered_scan, Qos::SENSOR).unwrap();
    let ter_pub = node::publisher::<PointCloud2>(&mut n, &t.terrain_map, Qos::SENSOR).unwrap();
    let target_pub = node::publisher::<RosString>(&mut n, &t.target, Qos::COMMAND).unwrap();
    let way_sub = node::subscription::<PointStamped>(&mut n, &t.way_point, Qos::COMMAND).unwrap();
    let status_sub = node::subscription::<RosString>(&mut n, &t.status, Qos::COMMAND).unwrap();
    let joy_sub = node::subscription::<Joy>(&mut n, &t.joy, Qos::COMMAND).unwrap();
    let stop_sub = node::subscription::<Int8>(&mut n, &t.stop, Qos::COMMAND).unwrap();
    let markers_sub = node::subscription::<MarkerArray>(&mut n, &t.markers, Qos::COMMAND).unwrap();

    let pts = room();
    let semantic = encode_xyzl(header(), &pts).unwrap();
    // Registered scan: the same returns, intensity unused (PCL's padded XYZI).
    let reg_rows: Vec<[f64; 4]> = pts.iter().map(|p| [p[0], p[1], p[2], 0.0]).collect();
    let registered = encode_xyzi(header(), &reg_rows).unwrap();
    // Terrain map: intensity = height above the ground (the floor is z = 0).
    let ter_rows: Vec<[f64; 4]> = pts.iter().map(|p| [p[0], p[1], p[2], p[2]]).collect();
    let terrain = encode_xyzi(header(), &ter_rows).unwrap();

    let mut robot_xy = (0.0, 0.0, 0.0);
    let mut rx = Received::default();
    let mut last_cloud = Instant::now() - Duration::from_secs(1);
    let mut target_sent: Option<Instant> = None;
    let mut arrived = false;
    let t0 = Instant::now();
    let mut pump = |(x, y, yaw): (f64, f64, f64), rx: &mut Received| {
        odom_pub
            .publish(common::odometry(header(), x, y, yaw))
            .unwrap();
        if last_cloud.elapsed() > Duration::from_millis(200) {
            last_cloud = Instant::now();
            sem_pub.publish(semantic.clone()).unwrap();
            reg_pub.publish(registered.clone()).unwrap();
            ter_pub.publish(terrain.clone()).unwrap();
        }
        rx.statuses.extend(
            node::drain(&status_sub, 100)
                .0
                .iter()
                .map(|s| serde_json::from_str::<Status>(&s.data).expect("status is Status JSON")),
        );
        rx.waypoints.extend(node::drain(&way_sub, 100).0);
        rx.joys.extend(node::drain(&joy_sub, 100).0);
        rx.stops.extend(node::drain(&stop_sub, 100).0);
        rx.markers += node::drain(&markers_sub, 100).0.len();
        thread::sleep(Duration::from_millis(50));
    };

    // Phase 1: request the target once the node's reader is discovered, and
    // wait for a NAV_TO_OBJECT way point toward the television.
    let nav = loop {
        assert!(
            t0.elapsed() < Duration::from_secs(60),
            "no NAV_TO_OBJECT way point; statuses: {:?}",
            rx.statuses.last()
        );
        pump(robot_xy, &mut rx);
        let requested = rx
            .statuses
            .last()
            .is_some_and(|s| s.target.as_deref() == Some("tv_monitor"));
        if !requested
            && n.subscription_count(&t.target) > 0
            && target_sent.is_none_or(|t| t.elapsed() > Duration::from_secs(2))
        {
            target_pub
                .publish(RosString {
                    data: "find the television".into(),
                })
                .unwrap();
            target_sent = Some(Instant::now());
        }
        if let Some(s) = rx.statuses.last()
            && let Some(m) = &s.active_mission
            && m.kind == "nav_to_object"
            && let Some(w) = rx.waypoints.iter().rev().find(|w| {
                (w.point.x - m.waypoint[0]).abs() < 1e-9 && (w.point.y - m.waypoint[1]).abs() < 1e-9
            })
        {
            break w.clone();
        }
    };
    assert_eq!(nav.header.frame_id, "map");
    // Within the standoff (0.45 m) plus a cell of the TV's bounds, inside the room.
    let (tx, ty) = (nav.point.x.clamp(-1.2, -0.7), 1.875);
    assert!(
        (nav.point.x - tx).hypot(nav.point.y - ty) < 0.6,
        "way point {:?} is not next to the TV",
        nav.point
    );
    assert!(nav.point.x.abs() < 3.0 && nav.point.y.abs() < 2.0);
    let joy = rx.joys.first().expect("autonomy-mode /joy received");
    assert_eq!(
        joy.axes[2], -1.0,
        "axes[2] = -1 switches the CMU planner to autonomy"
    );
    assert_eq!(joy.axes[4], 1.0);
    assert!(rx.stops.iter().all(|s| s.data == 0), "start releases /stop");
    let s = rx.statuses.last().unwrap();
    assert_eq!(s.state, NodeState::Searching);
    assert_eq!(s.request.as_deref(), Some("find the television"));
    assert!(s.objects >= 1);
    assert_eq!(s.last_decision.as_ref().unwrap().action, "nav_to_object");

    // Phase 2: the "planner" drives the robot to the way point; the node
    // computes arrival from odometry, verifies with a fresh scan and
    // confirms the television.
    let confirmed = loop {
        assert!(
            t0.elapsed() < Duration::from_secs(90),
            "target not confirmed; last status {:?}",
            rx.statuses.last()
        );
        if !arrived {
            robot_xy = (
                nav.point.x,
                nav.point.y,
                (ty - nav.point.y).atan2(tx - nav.point.x),
            );
            arrived = true;
        }
        pump(robot_xy, &mut rx);
        if let Some(c) = rx
            .statuses
            .last()
            .and_then(|s| s.confirmed.first().cloned())
        {
            break c;
        }
    };
    assert_eq!(confirmed.category, "tv_monitor");
    assert!(
        (confirmed.centre[0] + 0.95).abs() < 0.1 && (confirmed.centre[1] - 1.875).abs() < 0.1,
        "{confirmed:?}"
    );
    let s = rx.statuses.last().unwrap();
    assert_eq!(s.state, NodeState::Confirmed);
    assert!(
        s.bridge.observations >= 3 && s.bridge.rejected_messages == 0,
        "{:?}",
        s.bridge
    );
    assert!(s.bridge.registered_scans > 0 && s.bridge.terrain_maps > 0);
    assert!(rx.markers > 0, "markers published");

    // Shutdown publishes a hold way point and /stop = 2 (read while the
    // node lingers: a volatile reader's samples go with their writer).
    stop.store(true, Ordering::SeqCst);
    let got_stop = wait_for(Duration::from_secs(5), || {
        rx.stops.extend(node::drain(&stop_sub, 100).0);
        rx.stops.iter().any(|s| s.data == 2).then_some(())
    });
    let confirmed_in_node = node_thread.join().unwrap();
    assert_eq!(confirmed_in_node.len(), 1);
    assert!(
        got_stop.is_some(),
        "shutdown publishes /stop = 2; got {:?}",
        rx.stops
    );
}

/// Issue 21: every clean Ctrl-C logged 11 ERROR lines from RustDDS, as the
/// node's endpoints were dropped after their participant. Dropping a
/// started node now logs no DDS error.
#[test]
fn dropping_the_node_logs_no_dds_errors() {
    if !netns::isolate("dropping_the_node_logs_no_dds_errors") {
        return;
    }
    let sink = sornav_test_support::log_capture::LogSink::default();
    let writer = sink.clone();
    // This process (the isolated child) runs only this test: the global
    // subscriber also receives RustDDS's `log` records.
    tracing_subscriber::fmt()
        .with_ansi(false)
        .with_max_level(tracing::Level::WARN)
        .with_writer(move || writer.clone())
        .init();
    let mut config = ScoutConfig::default();
    config.ros.domain_id = DOMAIN + 1;
    let stop = AtomicBool::new(false);
    let mut robot = RobotNode::new(config).expect("robot node");
    thread::scope(|s| {
        s.spawn(|| {
            thread::sleep(Duration::from_millis(300));
            stop.store(true, Ordering::SeqCst);
        });
        robot.run(&stop, Duration::from_millis(10), Duration::from_millis(100));
    });
    drop(robot);
    thread::sleep(Duration::from_millis(300));
    let log = sink.text();
    // Leaving the multicast group fails in a namespace where joining it
    // failed (only `lo`, no multicast route): that is the test's network,
    // not the drop order.
    let errors: Vec<&str> = log
        .lines()
        .filter(|l| l.contains("ERROR") && !l.contains("leave_multicast_group"))
        .collect();
    assert!(errors.is_empty(), "{}", errors.join("\n"));
}

/// Issue 21, lost samples over real DDS: a sensor reader (best effort,
/// keep last 5) that is not drained while a writer sends 300 samples keeps
/// only some of them (the newest); the samples it lost never reach the
/// node, and DDS says nothing. Their writer's sequence numbers, carried with every
/// sample, show the gap: the stream monitor counts exactly the samples
/// that were sent and not taken.
#[test]
fn samples_lost_before_decoding_are_counted_from_sequence_numbers() {
    use sornav_platform_scout::streams::StreamMonitor;
    if !netns::isolate("samples_lost_before_decoding_are_counted_from_sequence_numbers") {
        return;
    }
    // Writer and reader in two participants, as two processes would be.
    let ctx = node::loopback_context(DOMAIN + 2).unwrap();
    let mut n = node::ros_node(&ctx, "/", "loss_writer").unwrap();
    let publisher = node::publisher::<RosString>(&mut n, "/loss_test", Qos::SENSOR).unwrap();
    let reader_ctx = node::loopback_context(DOMAIN + 2).unwrap();
    let mut reader_node = node::ros_node(&reader_ctx, "/", "loss_reader").unwrap();
    let reader =
        node::subscription::<RosString>(&mut reader_node, "/loss_test", Qos::SENSOR).unwrap();
    assert!(
        wait_for(Duration::from_secs(10), || {
            (n.subscription_count("/loss_test") > 0).then_some(())
        })
        .is_some(),
        "the reader was not matched"
    );
    let send = |count: usize| {
        for i in 0..count {
            publisher
                .publish(RosString {
                    data: format!("sample {i}"),
                })
                .unwrap();
        }
        thread::sleep(Duration::from_millis(300));
    };
    let mut monitor = StreamMonitor::new();
    let mut taken = Vec::new();
    let take = |monitor: &mut StreamMonitor, taken: &mut Vec<i64>| {
        let (samples, errors) = node::drain_with_source(&reader, 100);
        assert!(errors.is_empty(), "{errors:?}");
        for (_, source) in samples {
            taken.push(source.sequence);
            monitor.on_sample(Some(source), Duration::from_millis(taken.len() as u64));
        }
    };
    // Three samples, taken as they come.
    for _ in 0..3 {
        send(1);
        take(&mut monitor, &mut taken);
    }
    assert!(!taken.is_empty(), "nothing arrived over loopback");
    // Many more without taking: the reader's history (5) cannot keep them.
    send(300);
    take(&mut monitor, &mut taken);
    assert!(
        taken.windows(2).all(|w| w[0] < w[1]),
        "sequence numbers must increase: {taken:?}"
    );
    let status = monitor.status(Duration::from_secs(1));
    let first = taken[0];
    let last = *taken.last().unwrap();
    assert_eq!(
        status.lost,
        (last - first + 1) as u64 - taken.len() as u64,
        "{taken:?}"
    );
    // How many survive depends on when RustDDS moves samples into the
    // reader's history of 5; most of the 300 cannot.
    assert!(status.lost > 0, "nothing lost: {taken:?}");
    eprintln!("taken {taken:?}: {} lost", status.lost);
}
