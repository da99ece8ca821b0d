//! A robot that cannot climb stairs (`robot.can_climb_stairs = false`, the
//! Scout Mini) in a two-floor procedural house, searching for a category
//! that is only on the other floor: it explores its own floor, then holds
//! in the `floor_exhausted` state, naming the stairs that lead to the other
//! floor, within 1.5 m of the true stairwell.
//!
//! The robot node's logic ([`Bridge`]) is driven by `sornav-simbot`'s
//! simulated robot (the same `World`: NavMesh path following, panoramic
//! depth + semantic scans) on a simulated clock, without DDS: the DDS
//! transport is covered by `robot_simbot.rs` and platform-scout's loopback
//! tests, and a simulated clock makes the outcome independent of the
//! machine's load (the wall-clock time is only the rendering's).

#[allow(dead_code)]
#[path = "../src/bin/simbot/world.rs"]
mod world;

use std::time::{Duration, Instant};

use nalgebra::Point3;
use sornav::AgentConfig;
use sornav_platform_scout::bridge::{Bridge, NodeState, Outgoing, Status};
use sornav_platform_scout::config::ScoutConfig;
use sornav_platform_scout::msg::{
    Header, Odometry, Point, Pose, PoseWithCovariance, Quaternion, Time, TwistWithCovariance,
};
use sornav_platform_scout::pointcloud::{encode_xyzi, encode_xyzl};
use sornav_platform_sim::{InstanceKind, ProceduralConfig, Scene};

use world::World;

/// LiDAR height above the floor (the example configuration's).
const SENSOR_HEIGHT: f64 = 0.55;
/// Simulated seconds the robot may take.
const SIM_BUDGET_S: f64 = 200.0;

fn house() -> ProceduralConfig {
    ProceduralConfig {
        floors: Some(2),
        max_rooms_per_floor: 2,
        ..ProceduralConfig::default()
    }
}

fn header() -> Header {
    Header::new(Time::now(), "map")
}

fn odometry(world: &World) -> Odometry {
    let p = world.position;
    Odometry {
        header: header(),
        child_frame_id: "sensor".into(),
        pose: PoseWithCovariance {
            pose: Pose {
                position: Point::new(p.x, p.y, p.z + world.sensor_height()),
                orientation: Quaternion::from_yaw(world.yaw),
            },
            covariance: [0.0; 36],
        },
        twist: TwistWithCovariance::default(),
    }
}

/// Runs the robot in house `seed` searching for `request`; returns the last
/// status (after `floor_exhausted` held for 2 s, or at the budget).
fn run(seed: u64, request: &str) -> (Status, World) {
    let scene = Scene::procedural(seed, &house()).unwrap();
    let mut world = World::new(
        scene,
        &AgentConfig::default().labels,
        SENSOR_HEIGHT,
        96,
        72,
        8.0,
        None,
    )
    .unwrap();
    world.speed = 1.5;
    let mut config = ScoutConfig::from_toml(ScoutConfig::EXAMPLE).unwrap();
    assert!(
        !config.robot.can_climb_stairs,
        "the Scout Mini cannot climb"
    );
    config.rates.control_hz = 2.0;
    config.initial_target = Some(request.into());
    let mut bridge = Bridge::new(config).unwrap();

    let dt = Duration::from_millis(50);
    let mut now = Duration::ZERO;
    let (mut autonomy, mut stopped) = (false, 0i8);
    let mut scans = 0u64;
    let mut last_scan: Option<Duration> = None;
    let mut held_since: Option<Duration> = None;
    let mut last: Option<Status> = None;
    let handle = |out: Vec<Outgoing>,
                  world: &mut World,
                  autonomy: &mut bool,
                  stopped: &mut i8,
                  last: &mut Option<Status>| {
        for o in out {
            match o {
                Outgoing::WayPoint(w) => {
                    world.set_goal([w.point.x, w.point.y, w.point.z]);
                }
                Outgoing::Joy(j) => *autonomy = j.axes.get(2).is_some_and(|a| *a < -0.1),
                Outgoing::Stop(s) => *stopped = s.data,
                Outgoing::Status(s) => *last = Some(serde_json::from_str(&s.data).unwrap()),
                _ => {}
            }
        }
    };
    let out = bridge.start(now);
    handle(out, &mut world, &mut autonomy, &mut stopped, &mut last);
    while now.as_secs_f64() < SIM_BUDGET_S {
        if autonomy && stopped < 1 {
            world.advance(dt.as_secs_f64());
        }
        bridge.on_odometry(&odometry(&world), now).unwrap();
        if last_scan.is_none_or(|t| (now - t).as_secs_f64() >= 0.25 - 1e-9) {
            last_scan = Some(now);
            let returns = world.scan(scans);
            let sem: Vec<[f64; 4]> = returns
                .iter()
                .map(|r| [r.p[0], r.p[1], r.p[2], f64::from(r.label)])
                .collect();
            bridge
                .on_semantic_scan(&encode_xyzl(header(), &sem).unwrap(), now)
                .unwrap();
            if scans.is_multiple_of(2) {
                let reg: Vec<[f64; 4]> = returns
                    .iter()
                    .map(|r| [r.p[0], r.p[1], r.p[2], 0.0])
                    .collect();
                bridge
                    .on_registered_scan(&encode_xyzi(header(), &reg).unwrap(), now)
                    .unwrap();
            }
            scans += 1;
        }
        let out = bridge.tick(now);
        handle(out, &mut world, &mut autonomy, &mut stopped, &mut last);
        if bridge.state() == NodeState::FloorExhausted {
            let since = *held_since.get_or_insert(now);
            if (now - since).as_secs_f64() >= 2.0 {
                break;
            }
        } else {
            held_since = None;
        }
        now += dt;
    }
    if let Some(agent) = bridge.agent() {
        let map = agent.frontier_map();
        eprintln!("levels {:?}", map.levels().collect::<Vec<_>>());
        for s in map.stairs() {
            eprintln!(
                "  map stair {:?} -> {:?} ({:.1} m)",
                s.lower, s.upper, s.length
            );
        }
    }
    (last.expect("a status"), world)
}

/// The house and the request: seed 7 (two rooms per floor; the robot
/// starts on the ground floor, every toilet is upstairs).
const SEED: u64 = 7;
const REQUEST: &str = "find the toilet";
const CATEGORY: &str = "toilet";

#[test]
fn robot_that_cannot_climb_reports_the_stairs_to_the_other_floor() {
    let wall = Instant::now();
    let (status, world) = run(SEED, REQUEST);
    let scene = world.scene();
    eprintln!(
        "house {SEED}: {:?} after {:.0} s simulated, {:.1} s wall, {:.1} m travelled; {:?}",
        status.state,
        status.time_s,
        wall.elapsed().as_secs_f64(),
        world.odometer,
        status.note,
    );
    // The premise: the category is only on the other floor.
    let start_level = scene.level_at(status.pose.unwrap()[2]);
    assert!(scene.objects_of(CATEGORY).count() > 0);
    assert!(
        scene
            .objects_of(CATEGORY)
            .all(|o| scene.level_at(o.bounds.min.z + 0.05) != start_level),
        "a {CATEGORY} on the start floor"
    );
    let stairwells: Vec<_> = scene
        .instances()
        .iter()
        .filter(|i| i.kind == InstanceKind::Stairs)
        .map(|i| i.bounds)
        .collect();
    assert!(!stairwells.is_empty());

    assert_eq!(
        status.state,
        NodeState::FloorExhausted,
        "last decision {:?}",
        status.last_decision
    );
    assert!(status.confirmed.is_empty());
    assert!(!status.stairs.is_empty());
    let note = status.note.as_deref().unwrap();
    assert!(
        note.starts_with("not found on this floor; stairs at (")
            && note.ends_with(") lead to an unexplored floor"),
        "{note}"
    );
    let s = status.stairs[0];
    assert!(note.contains(&format!("({:.2}, {:.2}, {:.2})", s[0], s[1], s[2])));
    // At least one reported stair is at the true stairwell, on the robot's
    // floor.
    let near = status.stairs.iter().any(|s| {
        let p = Point3::new(s[0], s[1], s[2]);
        (s[2] - world.position.z).abs() < 0.3 && stairwells.iter().any(|b| b.distance_xy(&p) <= 1.5)
    });
    assert!(
        near,
        "stairs {:?}, true stairwells {stairwells:?}",
        status.stairs
    );
}
